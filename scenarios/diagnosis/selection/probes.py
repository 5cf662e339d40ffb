"""Localisation probes: physics outside the effect library, tried to say where a misfit lies.

When no effect of the library explains a campaign, the localisation quantities
(:mod:`housner.scenarios.diagnosis.comparison.localise`) say where the model departs from the
measurement. Some physics leaves no mark on them that a campaign resolves: a
vertical table acceleration that the CSV does not carry changes the
effective gravity, and so the restoring moment and the uplift threshold,
from instant to instant with the table's motion; its effect is in the time
histories only. A *probe* is an effect of a physical class, with a generic
parameterisation, that the diagnosis fits on top of its final model and
judges like a candidate (held out, the same test). A probe that lowers the
error significantly names its class first, with its fitted parameters and the
error's fall; it is never offered as an explanation: the verdict stays
``partly_explained`` or ``unexplained``, since the library holds no effect
for what the campaign did not measure.

Probes (registered with ``probe = True``, so no search takes them as candidates):

``vertical_coupling``
    A vertical table acceleration proportional to the horizontal one, delayed:
    a_v(t) = k ug''(t - d) (a table whose vertical actuators or guides couple
    to its horizontal motion). The block feels g + a_v: the reduced equation
    gains -p^2 (a_v / g) sin(alpha - phi), the uplift threshold becomes
    tan(alpha) (1 + a_v / g).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numba import njit

from housner.effects import Effect, MomentTerm, ParamSpec, register_effect
from housner.motion import VERTICAL

__all__ = ["PROBES", "ProbeFinding", "VerticalCoupling"]


@dataclass(frozen=True)
class ProbeFinding:
    """A probe that lowered the final model's held-out error significantly (:func:`housner.scenarios.diagnosis.
    diagnose.probe`).

    Attributes
    ----------
    probe : str
        The probe's registered name.
    class_name : str
        The physical class it stands for (:data:`PROBES`).
    params : dict
        Its fitted parameters.
    error, error_with : float
        The final model's mean held-out error without and with it [alpha].
    improvement, se, z, p : float
        The mean paired fall [alpha], its standard error, their ratio [-] and the one-sided p-value [-].
    """

    probe: str
    class_name: str
    params: dict
    error: float
    error_with: float
    improvement: float
    se: float
    z: float
    p: float


@njit(cache=True)
def _vertical_moment(phi, w, t, a, v, s, alpha, p2, q):
    # g -> g + a_v in the restoring moment, v = a_v / g [-]  ->  extra phi'' [rad/s^2]
    return -p2 * v * math.sin(alpha - phi)


@register_effect
@dataclass(frozen=True)
class VerticalCoupling(Effect):
    """Probe: a vertical table acceleration k ug''(t - d) that the campaign did not record.

    Parameters
    ----------
    k : float
        Vertical over horizontal acceleration [-], in [-1, 1]; neutral 0.
    delay : float
        Delay of the vertical behind the horizontal acceleration [s], in [0, 0.1].
    """

    name = "vertical_coupling"
    probe = True
    probe_summary = "a vertical table acceleration k ug''(t - d) that the campaign did not record"
    makes_channels = (VERTICAL,)
    params = {
        "k": ParamSpec("-", (-1.0, 1.0), 0.0, 0.0, "vertical over horizontal table acceleration"),
        "delay": ParamSpec("s", (0.0, 0.1), 0.0, 0.0, "delay of the vertical behind the horizontal acceleration"),
    }
    k: float = 0.0
    delay: float = 0.0

    def transform_input(self, motion):
        t = motion.t
        a_v = self.k * np.interp(t - self.delay, t, motion.acc, left=0.0)
        return replace(motion, channels={**motion.channels, VERTICAL: a_v})

    def terms(self, params, specimen):
        return (MomentTerm(_vertical_moment, ()),) if self.k else ()


#: Probe name -> the physical class of housner.scenarios.diagnosis.comparison.pointers.CLASSES it stands for.
PROBES: dict[str, str] = {"vertical_coupling": "vertical_input"}
