"""Coulomb friction at the pivot: a moment M_f against the rotation; the block sticks while the rest stay below it.

I0 theta'' = (Housner's moments) - M_f sgn(theta'), and at theta' = 0 the block holds while the other
moments stay within +-M_f (from rest it lifts once they exceed M_f: a higher uplift threshold). The kernel
takes the capacity M_f / I0_s [rad/s^2] of each pivot; I0_s = m g R_s / p_s^2 with R_s = H / cos(alpha_s),
from the final rocking parameters (so it composes with asymmetric pivots). Load with
``housner.effects.load_plugin("examples/effects/pivot_friction.py")``, then ``make_effect("pivot_friction",
moment=0.09)``.
"""

import math
from dataclasses import dataclass

from numba import njit

from housner.effects import CoulombTerm, Effect, param, register_effect
from housner.units import G


@njit(cache=True)
def capacity(phi, t, a, v, s, alpha, p2, q):
    return q[0] if s > 0.0 else q[1]  # M_f / I0 of the pivot [rad/s^2]


@register_effect
@dataclass(frozen=True)
class PivotFriction(Effect):
    name = "pivot_friction"
    moment: float = param("N m", (0.0, 0.5), neutral=0.0, default=0.0, doc="Coulomb moment M_f at the pivot")

    def terms(self, params, specimen):
        sides = ((params.alpha_pos, params.p_pos), (params.alpha_neg, params.p_neg))
        i0 = [specimen.mass * G * specimen.H / math.cos(al) / p**2 for al, p in sides]  # [kg m^2]
        return (CoulombTerm(capacity, (self.moment / i0[0], self.moment / i0[1])),) if self.moment else ()
