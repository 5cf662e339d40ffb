"""The impact law through which every planar adapter realises an energy ratio below its contact's own.

:class:`ImpactLaw` detects an impact from theta's sign change after a swing above :data:`IMPACT_LAW_TOL`
alpha and, :data:`IMPACT_LAW_DELAY` later, scales the block's velocities so that it keeps a given fraction
of the energy its contact leaves it (docs/explanation/impact-law.md). Which fraction a record asks for,
from its ``restitution`` effect and the adapter's ``impact_energy_factor`` setting, is the adapters'
business (:func:`housner.engines._planar.law_factor`).
"""

from __future__ import annotations

import math

import numpy as np

from housner.rocking_params import RockingParams

__all__ = ["IMPACT_LAW_DELAY", "IMPACT_LAW_TOL", "ImpactLaw"]

#: |theta| / alpha [-] a swing must exceed for the impact law to count its next sign change as an
#: impact (why 1e-3: docs/results.md#defaults-planar).
IMPACT_LAW_TOL = 1e-3

#: Time [s] from an impact's sign change to the impact law's scaling: the contacts the adapters
#: ship finish an impact well within it (MuJoCo's time constant is 0.4 ms, the OpenSees springs'
#: contact half-period about 1 ms, DART and PyBullet are rigid). The law's energy bookkeeping makes the
#: delay exact in free rocking; under a ground motion the ground's work in these 2 ms is scaled too.
IMPACT_LAW_DELAY = 2e-3


class ImpactLaw:
    """The adapters' impact law: the block keeps ``factor`` of the energy its contact leaves it at each impact.

    Housner's r follows from a plastic impact at the new pivot, and a rigid or
    stiff contact reproduces exactly that loss; no engine's contact has a knob
    that takes uniformly more (docs/results.md#defaults-planar).
    A specimen that loses more at impact (a measured r below Housner's) is
    modelled by this law, the same in every adapter. The engine still does
    everything else: the flight, the uplift, the impact itself and the overturn.

    1. An impact is detected as :func:`housner.free_vibration.impacts.impact_times` counts
       one: theta changes sign after |theta| exceeded :data:`IMPACT_LAW_TOL`
       alpha since the previous sign change.
    2. :data:`IMPACT_LAW_DELAY` later, when the contact has finished the
       impact, every velocity of the block (relative to the ground) is
       multiplied by one factor c, chosen so that the block's energy above the
       upright position, per unit of I0,

           e = theta'^2 / 2 + p^2 (cos(alpha - |theta|) - cos alpha),

       becomes ``factor`` times what it was. In free rocking e is constant
       between impacts, so the energy ratio of the impact (the seed's eq. 8,
       which compares exactly these energies at the peaks) is ``factor``
       times the contact's, whatever the delay. Scaling at the sign change
       itself, in the middle of a compliant contact's impact, scatters each
       impact's ratio (docs/results.md#defaults-planar).

    Parameters
    ----------
    factor : float
        Energy kept at each impact, as a fraction of what the contact leaves [-], in (0, 1];
        1 leaves the contact alone.
    specimen : Specimen
        The block: alpha [rad] and p [1/s].
    step : float
        The engine step [s] at which :meth:`after_step` is called.
    theta0 : float
        The record's initial rotation [rad].
    params : RockingParams, optional
        alpha and p of each pivot (``alpha_pos``, ``p_pos`` for theta > 0, ``alpha_neg``, ``p_neg`` for
        theta < 0) of a block whose pivots are not symmetric (``asymmetric_pivots``): the energy above
        is then that per unit of the inertia about the pivot the block rocks on, with that pivot's alpha
        and p, and the threshold of step 1 is IMPACT_LAW_TOL times the smaller alpha. None (default):
        the specimen's alpha and p on both sides.
    """

    __slots__ = ("factor", "tol", "_alpha", "_cos_a", "_p2", "_sides", "_wait", "_side", "_peak", "_countdown")

    def __init__(self, factor: float, specimen, step: float, theta0: float = 0.0, params: RockingParams | None = None):
        self.factor = float(factor)
        self._alpha = specimen.alpha
        self._cos_a = math.cos(self._alpha)
        self._p2 = specimen.frequency_parameter**2
        self.tol = IMPACT_LAW_TOL * self._alpha
        self._sides = None  # ((alpha, cos alpha, p^2) of the + pivot, of the - pivot), or None: symmetric
        if params is not None:
            self._sides = tuple(
                (a, math.cos(a), p * p) for a, p in ((params.alpha_pos, params.p_pos), (params.alpha_neg, params.p_neg))
            )
            self.tol = IMPACT_LAW_TOL * min(params.alpha_pos, params.alpha_neg)
        self._wait = max(1, math.ceil(IMPACT_LAW_DELAY / step * (1.0 - 1e-9)))
        self._side = 0.0 if theta0 == 0.0 else math.copysign(1.0, theta0)
        self._peak = abs(theta0)
        self._countdown = 0  # steps until the pending impact's energy is scaled; 0: none pending

    @property
    def active(self) -> bool:
        """Whether the law changes anything (``factor`` below 1)."""
        return self.factor != 1.0

    @property
    def step_hook(self):
        """:meth:`after_step`, or None where the law changes nothing: a step loop asks it after a step only when it
        is not None (an attribute test per step, not a property call)."""
        return self.after_step if self.active else None

    def after_step(self, theta: float, omega: float) -> float | None:
        """The factor to multiply every velocity of the block by after a step that reached (theta, omega), or None.

        ``theta`` [rad] and ``omega`` [rad/s] are the block's rotation and rate after the step.
        """
        scale = None
        if theta != 0.0:
            side = 1.0 if theta > 0.0 else -1.0
            if self._side != 0.0 and side != self._side:
                impact = self._peak > self.tol
                self._side, self._peak = side, abs(theta)
                if impact:
                    if self._countdown:  # the previous impact is still pending: it is scaled now
                        scale = self._scale(theta, omega)
                    self._countdown = self._wait
                return scale
            self._side = side
            self._peak = max(self._peak, abs(theta))
        if self._countdown:
            self._countdown -= 1
            if not self._countdown:
                scale = self._scale(theta, omega)
        return scale

    def _scale(self, theta: float, omega: float) -> float:
        """c with c^2 theta'^2 / 2 + u = factor (theta'^2 / 2 + u), u the potential energy per I0 (0 if unreachable)."""
        k = 0.5 * omega * omega
        if k <= 0.0:
            return 1.0
        if self._sides is not None:  # the pivot the block rocks on now, that of theta's side
            alpha, cos_a, p2 = self._sides[0 if theta >= 0.0 else 1]
            u = p2 * (math.cos(alpha - abs(theta)) - cos_a)
            return math.sqrt(max(self.factor * (k + u) - u, 0.0) / k)
        u = self._p2 * (math.cos(self._alpha - abs(theta)) - self._cos_a)
        return math.sqrt(max(self.factor * (k + u) - u, 0.0) / k)

    def first_scale(self, theta: np.ndarray, omega: np.ndarray) -> tuple[int, float] | None:
        """The first step of consecutive steps (``theta`` [rad], ``omega`` [rad/s]) after which to scale, else None.

        Returns (index, factor); the law's state advances up to and including that step, so the next
        call continues after it.
        """
        pairs = zip(np.asarray(theta, float).tolist(), np.asarray(omega, float).tolist(), strict=True)
        for i, (th, w) in enumerate(pairs):
            c = self.after_step(th, w)
            if c is not None:
                return i, c
        return None
