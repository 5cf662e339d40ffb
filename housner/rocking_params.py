"""The rocking parameters of the analytic model: the two pivots' alpha and p, the restitution law, damping.

:class:`RockingParams` is what the compiled kernel (:mod:`housner._kernel`) reads, as one float64
vector (:meth:`RockingParams.as_array`); :mod:`housner.model` builds it from a specimen and effects
change it (``Effect.modify_params``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from housner._kernel_parts import (
    I_ALPHA_NEG,
    I_ALPHA_POS,
    I_DAMPING,
    I_P_NEG,
    I_P_POS,
    I_R,
    I_R_EXP,
    I_R_NEG,
    I_R_POS,
    N_PARAMS,
)
from housner._validate import finite as _finite
from housner.specimen import Specimen
from housner.units import G

__all__ = ["RockingParams", "pivot_impact_ratios"]


@dataclass(frozen=True)
class RockingParams:
    """Parameters of the rocking equation, per pivot.

    Parameters
    ----------
    alpha_pos, alpha_neg : float
        Slenderness [rad] when rocking on the +x corner (theta > 0) and on the
        -x corner (theta < 0); equal for a symmetric block.
    p_pos, p_neg : float
        Frequency parameter [1/s] when rocking on each corner.
    r : float
        Kinetic-energy ratio at impact [-], in [0, 1]: theta'_after =
        sqrt(r_eff) theta'_before. Used for the impacts of a side whose own
        ratio (``r_pos``, ``r_neg``) is None.
    r_amp_exponent : float
        Exponent n of an amplitude-dependent restitution [-]:
        r_eff = clip(r_s' (|theta'_before| / (p_s alpha_s))^n, 0, 1), where
        r_s' is the ratio of the impact (``r_pos``, ``r_neg`` or ``r``), p_s
        and alpha_s belong to the corner the block rocked on before the
        impact; p_s alpha_s is the impact speed of a block released from
        theta = alpha in the linearised model, so r_eff = r at that reference
        speed. n = 0 (default) is Housner's constant r; n > 0 makes small
        impacts more dissipative.
    damping : float
        Rotational viscous damping rate c [1/s]: the equation of motion gains
        the term -c theta'. Equivalent to a viscous moment -c I0 theta' about
        the pivot; the rocking energy E = theta'^2/2 + p^2 (cos(alpha - |theta|)
        - cos(alpha)) then decays as dE/dt = -c theta'^2. 0 (default) is
        Housner's model.
    r_pos, r_neg : float or None
        Restitution [-], in [0, 1], of the impact that lands on the +x corner
        (it ends a half-cycle on the -x corner, theta < 0, and starts one on
        the +x corner, theta > 0), and of the impact that lands on the -x
        corner: theta'_after = sqrt(r_pos) theta'_before, and likewise. None
        (default) means ``r``. Like ``r`` this is the ratio of the squared
        angular velocities, which is the kinetic-energy ratio when both
        corners have the same inertia; with inertias I+ and I- about the
        corners the kinetic energy changes by r_pos I+ / I- (and r_neg I- / I+).
        A block whose centre of mass is off-centre has r_pos != r_neg (see
        :class:`housner.effects.AsymmetricPivots`).

    Notes
    -----
    With alpha_pos == alpha_neg, p_pos == p_neg, r_pos and r_neg None (or
    equal to r), r_amp_exponent == 0 and damping == 0 the model is exactly
    Housner's (seed eq. 2 with eq. 4).

    ``dataclasses.replace(params, r=x)`` changes only the impacts of sides
    without their own ratio; :meth:`with_r` rescales the per-side ratios too.
    """

    alpha_pos: float
    alpha_neg: float
    p_pos: float
    p_neg: float
    r: float
    r_amp_exponent: float = 0.0
    damping: float = 0.0
    r_pos: float | None = None
    r_neg: float | None = None

    def __post_init__(self) -> None:
        for key in ("alpha_pos", "alpha_neg"):
            v = _finite(key, getattr(self, key))
            if not 0.0 < v < math.pi / 2:
                raise ValueError(f"`{key}` must lie in (0, pi/2) rad, got {v!r}")
            object.__setattr__(self, key, v)
        for key in ("p_pos", "p_neg"):
            v = _finite(key, getattr(self, key))
            if v <= 0.0:
                raise ValueError(f"`{key}` must be positive [1/s], got {v!r}")
            object.__setattr__(self, key, v)
        r = _finite("r", self.r)
        if not 0.0 <= r <= 1.0:
            raise ValueError(f"`r` must lie in [0, 1], got {r!r}")
        object.__setattr__(self, "r", r)
        for key in ("r_pos", "r_neg"):
            v = getattr(self, key)
            if v is None:
                continue
            v = _finite(key, v)
            if not 0.0 <= v <= 1.0:
                raise ValueError(f"`{key}` must lie in [0, 1] or be None, got {v!r}")
            object.__setattr__(self, key, v)
        object.__setattr__(self, "r_amp_exponent", _finite("r_amp_exponent", self.r_amp_exponent))
        c = _finite("damping", self.damping)
        if c < 0.0:
            raise ValueError(f"`damping` must be >= 0 [1/s], got {c!r}")
        object.__setattr__(self, "damping", c)

    @classmethod
    def from_specimen(cls, specimen: Specimen, r: float | None = None) -> RockingParams:
        """Housner's symmetric parameters of ``specimen``; ``r`` [-] defaults to ``specimen.r_housner``."""
        if not isinstance(specimen, Specimen):
            raise TypeError(f"`specimen` must be a housner.Specimen, got {type(specimen).__name__}")
        alpha = specimen.alpha
        p = specimen.frequency_parameter
        return cls(alpha, alpha, p, p, specimen.r_housner if r is None else r)

    @classmethod
    def from_pivots(cls, b_pos: float, b_neg: float, h: float, centroidal_inertia: float, mass: float):
        """A rigid block on two pivots under Housner's impact law, per side.

        Parameters
        ----------
        b_pos, b_neg : float
            Horizontal distance from the centre of mass to the +x and the -x pivot [m].
        h : float
            Height of the centre of mass above the pivots [m].
        centroidal_inertia : float
            I_c about the rocking axis through the centre of mass [kg m^2].
        mass : float
            [kg]

        Returns
        -------
        RockingParams
            alpha_s = atan(b_s / h), p_s = sqrt(m g R_s / (I_c + m R_s^2)) with R_s = hypot(b_s, h), and the
            restitution of each impact from angular momentum about the landing pivot
            (:func:`pivot_impact_ratios`): r_neg = rho+-^2, r_pos = rho-+^2 (each at most 1) and r their
            geometric mean. With b_pos = b_neg this is Housner's symmetric block.
        """
        side = {}
        for name, b in (("pos", b_pos), ("neg", b_neg)):
            rr = math.hypot(b, h)
            side[name] = (math.atan2(b, h), math.sqrt(mass * G * rr / (centroidal_inertia + mass * rr * rr)))
        rho_pn, rho_np = pivot_impact_ratios(b_pos, b_neg, h, centroidal_inertia, mass)
        return cls(
            side["pos"][0],
            side["neg"][0],
            side["pos"][1],
            side["neg"][1],
            min(1.0, abs(rho_pn * rho_np)),
            r_pos=min(1.0, rho_np * rho_np),
            r_neg=min(1.0, rho_pn * rho_pn),
        )

    @property
    def is_housner(self) -> bool:
        """True for the plain symmetric Housner model (no asymmetry, constant r, no damping)."""
        return (
            self.alpha_pos == self.alpha_neg
            and self.p_pos == self.p_neg
            and self.r_impact_pos == self.r
            and self.r_impact_neg == self.r
            and self.r_amp_exponent == 0.0
            and self.damping == 0.0
        )

    @property
    def r_impact_pos(self) -> float:
        """Kinetic-energy ratio [-] of an impact that lands on the +x corner (``r_pos``, else ``r``)."""
        return self.r if self.r_pos is None else self.r_pos

    @property
    def r_impact_neg(self) -> float:
        """Kinetic-energy ratio [-] of an impact that lands on the -x corner (``r_neg``, else ``r``)."""
        return self.r if self.r_neg is None else self.r_neg

    def with_r(self, r: float) -> RockingParams:
        """These parameters with restitution ``r`` [-], keeping the split between the sides.

        ``r`` replaces the common ratio; each per-side ratio that is set is
        scaled by r / self.r (clipped to 1), so that a block with r_pos !=
        r_neg keeps the ratio r_pos / r_neg of its two impacts. When r is the
        geometric mean of r_pos and r_neg (as :class:`housner.effects.
        AsymmetricPivots` sets it) it stays so, up to the clip. With
        self.r == 0 the set per-side ratios become ``r``.
        """
        r = _finite("r", r)
        if not 0.0 <= r <= 1.0:
            raise ValueError(f"`r` must lie in [0, 1], got {r!r}")

        def scaled(v):
            if v is None:
                return None
            return r if self.r == 0.0 else min(1.0, v * (r / self.r))

        return replace(self, r=r, r_pos=scaled(self.r_pos), r_neg=scaled(self.r_neg))

    def mirrored(self) -> RockingParams:
        """The same block seen in a mirror (x -> -x): the +x and -x sides swapped.

        Simulating the mirrored parameters under the negated ground motion
        gives exactly (bit for bit) the negated rotation history.
        """
        return replace(
            self,
            alpha_pos=self.alpha_neg,
            alpha_neg=self.alpha_pos,
            p_pos=self.p_neg,
            p_neg=self.p_pos,
            r_pos=self.r_neg,
            r_neg=self.r_pos,
        )

    @property
    def p_max(self) -> float:
        """The larger frequency parameter of the two corners [1/s]."""
        return max(self.p_pos, self.p_neg)

    def as_array(self) -> np.ndarray:
        """The kernel's parameter vector (float64, layout of ``housner._kernel_parts``)."""
        v = np.empty(N_PARAMS)
        v[I_ALPHA_POS] = self.alpha_pos
        v[I_ALPHA_NEG] = self.alpha_neg
        v[I_P_POS] = self.p_pos
        v[I_P_NEG] = self.p_neg
        v[I_R] = self.r
        v[I_R_POS] = self.r_impact_pos
        v[I_R_NEG] = self.r_impact_neg
        v[I_R_EXP] = self.r_amp_exponent
        v[I_DAMPING] = self.damping
        return v


def pivot_impact_ratios(b_pos: float, b_neg: float, h: float, centroidal_inertia: float, mass: float):
    """Angular-velocity ratios [-] of the two impacts of a rigid block on two pivots (Housner's assumptions).

    The centre of mass is h [m] above the pivots and b_pos, b_neg [m] from each horizontally. Angular
    momentum about the pivot that lands is conserved: with I+- = I_c + m (h^2 + b+-^2) the inertia about each
    pivot, theta'_after / theta'_before = (I_c + m (h^2 - b+ b-)) / I_landing.

    Returns
    -------
    (rho_pos_to_neg, rho_neg_to_pos) : tuple of float
        For an impact that ends rocking on the +x pivot and lands on the -x one, and for the reverse. For a
        symmetric block both are 1 - 2 m b^2 / I0 = sqrt(r_housner).
    """
    common = centroidal_inertia + mass * (h * h - b_pos * b_neg)
    return (
        common / (centroidal_inertia + mass * (h * h + b_neg * b_neg)),
        common / (centroidal_inertia + mass * (h * h + b_pos * b_pos)),
    )
