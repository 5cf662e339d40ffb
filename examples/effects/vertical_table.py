"""A vertical table acceleration a_v, read from the motion's ``ground_acc_vertical`` channel [m/s^2].

The block feels gravity g + a_v (a_v positive up): the restoring moment m (g + a_v) R sin(alpha - |theta|)
adds -p^2 v sin(alpha - phi) to the reduced equation (v = a_v / g), and so the uplift threshold becomes
tan(alpha) (1 + v), for a_v > -g. ``gain`` is the share of the recorded channel the block feels (1: all
of it). A motion without the channel is refused by name. Load with
``housner.effects.load_plugin("examples/effects/vertical_table.py")``.
"""

import math
from dataclasses import dataclass

from numba import njit

from housner.effects import Effect, MomentTerm, param, register_effect


@njit(cache=True)
def vertical_moment(phi, w, t, a, v, s, alpha, p2, q):
    return -q[0] * p2 * v * math.sin(alpha - phi)  # [rad/s^2]


@register_effect
@dataclass(frozen=True)
class VerticalTable(Effect):
    name = "vertical_table"
    channels = ("ground_acc_vertical",)
    gain: float = param(
        "-", (0.0, 2.0), neutral=0.0, default=1.0, doc="share of the recorded vertical acceleration felt"
    )

    def terms(self, params, specimen):
        return (MomentTerm(vertical_moment, (self.gain,)),) if self.gain else ()
