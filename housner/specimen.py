"""The rocking specimen: geometry, mass and the derived Housner parameters.

Conventions (SI throughout): ``height`` is 2H, the distance from the pivot line
to the top [m]; ``width`` is 2B, the distance between the two rocking pivots
[m]; the centre of mass sits at (0, H) above the midpoint of the pivots.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace

from housner._validate import positive
from housner.units import G

__all__ = ["Specimen"]

#: Relative tolerance for ``p`` and ``I0`` given together: they must describe
#: the same block to this precision (both are usually typed in with 4-6 digits).
_P_I0_RTOL = 1e-4


def _positive(name: str, value: float | None, *, optional: bool = False) -> float | None:
    if value is None:
        if optional:
            return None
        raise ValueError(f"`{name}` is required")
    return positive(name, value)


@dataclass(frozen=True)
class Specimen:
    """A rigid rectangular block that rocks on two pivots.

    Parameters
    ----------
    height : float
        2H [m], pivot line to top; the centre of mass is at H.
    width : float
        2B [m], distance between the two pivots.
    depth : float
        Out-of-plane depth [m]; used by engines for their 3-D body only.
    mass : float
        Mass m [kg].
    p : float, optional
        Frequency parameter p = sqrt(m g R / I0) [1/s], usually measured.
    I0 : float, optional
        Moment of inertia about a pivot [kg m^2]. If neither ``p`` nor ``I0``
        is given the block is a solid rectangle: I0 = 4/3 m R^2. After
        construction both attributes hold the derived values.
    name : str
        Free text for reports.
    g : float
        The gravity where the block stands [m/s^2] (default standard gravity): p and I0 are related by
        p^2 = m g R / I0 at this g. A campaign states its own (``docs/reference/campaign-format.md``).

    Notes
    -----
    Derived quantities: ``alpha`` = atan(B/H) [rad], ``R`` = sqrt(B^2 + H^2)
    [m], ``p`` [1/s], ``I0`` [kg m^2], and Housner's kinetic-energy ratio at
    impact ``r_housner`` = (1 - 2 m R^2 / I0 sin^2 alpha)^2 [-].

    References
    ----------
    Housner, G. W. (1963). The behavior of inverted pendulum structures during
    earthquakes. BSSA 53(2), 403-417.
    Bachmann, J. A. et al. (2017). Probabilistic validation of the Housner
    rocking model. COMPDYN 2017, eqs. 1-4 and Table 1.
    """

    height: float
    width: float
    depth: float
    mass: float
    p: float | None = None
    I0: float | None = None
    name: str = "specimen"
    g: float = G
    _I0: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        h = _positive("height", self.height)
        w = _positive("width", self.width)
        d = _positive("depth", self.depth)
        m = _positive("mass", self.mass)
        p = _positive("p", self.p, optional=True)
        i0 = _positive("I0", self.I0, optional=True)
        g = _positive("g", self.g)
        object.__setattr__(self, "g", g)
        for key, value in (("height", h), ("width", w), ("depth", d), ("mass", m), ("p", p), ("I0", i0)):
            object.__setattr__(self, key, value)
        R = math.hypot(h / 2.0, w / 2.0)
        if w >= h:
            alpha = math.atan2(w, h)
            warnings.warn(
                f"`width` ({w} m) >= `height` ({h} m): alpha = {alpha:.4f} rad "
                f"({math.degrees(alpha):.1f} deg), a squat block that rocks only under very strong shaking",
                stacklevel=3,
            )
        if i0 is None:
            i0 = m * g * R / p**2 if p is not None else 4.0 / 3.0 * m * R**2
        elif p is not None:
            i0_from_p = m * g * R / p**2
            if abs(i0_from_p - i0) > _P_I0_RTOL * i0:
                raise ValueError(
                    f"`p` = {p} 1/s and `I0` = {i0} kg m^2 disagree: p implies I0 = {i0_from_p:.6g} kg m^2 "
                    f"(m g R / p^2 with R = {R:.6g} m); give only one of them"
                )
        if i0 < m * R**2:
            # Parallel-axis theorem: I0 = I_cm + m R^2 >= m R^2.
            raise ValueError(
                f"`{'p' if p is not None else 'I0'}` is impossible: I0 = {i0:.6g} kg m^2 is below "
                f"m R^2 = {m * R**2:.6g} kg m^2 (so p must be at most sqrt(g/R) = {math.sqrt(g / R):.6g} 1/s)"
            )
        object.__setattr__(self, "_I0", i0)
        # After validation, ``p`` and ``I0`` always hold the derived values.
        object.__setattr__(self, "I0", i0)
        object.__setattr__(self, "p", math.sqrt(m * g * R / i0))

    # --- geometry -------------------------------------------------------
    @property
    def H(self) -> float:
        """Half height [m]: pivot line to centre of mass."""
        return self.height / 2.0

    @property
    def B(self) -> float:
        """Half width [m]: centre line to either pivot."""
        return self.width / 2.0

    @property
    def R(self) -> float:
        """Semi-diagonal, pivot to centre of mass [m]."""
        return math.hypot(self.H, self.B)

    @property
    def alpha(self) -> float:
        """Slenderness angle atan(B/H) [rad]."""
        return math.atan2(self.B, self.H)

    @property
    def tan_alpha(self) -> float:
        """tan(alpha) = B/H [-]."""
        return self.B / self.H

    # --- dynamics -------------------------------------------------------
    @property
    def inertia(self) -> float:
        """Moment of inertia about a pivot I0 [kg m^2] (given, from p, or solid block)."""
        return self._I0

    @property
    def frequency_parameter(self) -> float:
        """Frequency parameter p = sqrt(m g R / I0) [1/s]."""
        return math.sqrt(self.mass * self.g * self.R / self._I0)

    @property
    def uplift_acceleration(self) -> float:
        """Ground acceleration magnitude that starts rocking, g tan(alpha) [m/s^2]."""
        return self.g * self.tan_alpha

    @property
    def r_housner(self) -> float:
        """Housner's kinetic-energy ratio at impact, (1 - 2 m R^2/I0 sin^2 alpha)^2 [-]."""
        m_r2 = self.mass * self.R**2 / self._I0
        return (1.0 - 2.0 * m_r2 * math.sin(self.alpha) ** 2) ** 2

    @property
    def centroidal_inertia(self) -> float:
        """Moment of inertia about the centre of mass, I0 - m R^2 [kg m^2]."""
        return self._I0 - self.mass * self.R**2

    def scaled(self, S: float) -> Specimen:
        """The geometrically similar block S times larger [-].

        Lengths scale by S, mass by S^3, and the inertia keeps its ratio to
        m R^2, so alpha and r are unchanged and p scales by 1/sqrt(S).
        """
        S = _positive("S", S)
        ratio = self._I0 / (self.mass * self.R**2)
        m = self.mass * S**3
        R = self.R * S
        return Specimen(
            height=self.height * S,
            width=self.width * S,
            depth=self.depth * S,
            mass=m,
            I0=ratio * m * R**2,
            name=f"{self.name} x{S:g}",
            g=self.g,
        )

    def with_p(self, p: float) -> Specimen:
        """The same block with another frequency parameter p [1/s].

        Use this (not ``dataclasses.replace``) to change p: after construction
        both ``p`` and ``I0`` are set, and replacing only one makes them disagree.
        """
        return replace(self, p=p, I0=None)

    @classmethod
    def bachmann2017(cls) -> Specimen:
        """The ETH specimen of the seed paper: 2H = 0.5 m, 2B = 0.075 m, 3.94 kg, p = 4.8883 1/s."""
        return cls(height=0.5, width=0.075, depth=0.4, mass=3.94, p=4.8883, name="ETH specimen (Bachmann 2017)")

    def describe(self) -> dict:
        """Plain dict of inputs and derived values, for reports and hashing."""
        return {
            "name": self.name,
            "height_m": self.height,
            "width_m": self.width,
            "depth_m": self.depth,
            "mass_kg": self.mass,
            "I0_kgm2": self.inertia,
            "alpha_rad": self.alpha,
            "R_m": self.R,
            "p_1_s": self.frequency_parameter,
            "r_housner": self.r_housner,
        }
