"""The parameters of the Rezaeian & Der Kiureghian ground-motion model (:mod:`housner.scenarios.motions.rdk`).

Ia, D5-95 and t_mid set the time-modulating function q(t); omega_mid, omega' and
zeta_f the filter; omega_c the high-pass corner (units in :class:`RDKParams`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import numpy as np

from housner.scenarios.motions.rdk_envelope import solve_envelope

__all__ = ["DEFAULT_OMEGA_C", "RDKParams", "settle_time"]

#: Default corner frequency of the high-pass filter, 2 pi x 0.2 rad/s [rad/s]: the
#: high-pass corner with which PEER processed the El Centro record (its header
#: reads HP = 0.2 Hz), so simulated and recorded motions lack the same
#: long-period content. The papers keep omega_c fixed for all motions.
DEFAULT_OMEGA_C = 2.0 * math.pi * 0.2

#: The critically damped filter's free response (1 + omega_c t) exp(-omega_c t)
#: falls below 1e-3 at omega_c t = 9.2335 [-]; see :func:`settle_time`.
_SETTLE_OMEGA_T = 9.2335


def settle_time(omega_c: float) -> float:
    """Time for the critically damped high-pass filter to come to rest, 9.23 / omega_c [s].

    Its free response (1 + omega_c t) exp(-omega_c t) is then below 1e-3 of its
    start; 7.3 s for omega_c = 2 pi x 0.2 rad/s.
    """
    if not (math.isfinite(omega_c) and omega_c > 0):
        raise ValueError(f"`omega_c` must be positive and finite, got {omega_c!r}")
    return _SETTLE_OMEGA_T / omega_c


_UNITS = {
    "Ia": "Ia_m_s",
    "D5_95": "D5_95_s",
    "t_mid": "t_mid_s",
    "omega_mid": "omega_mid_rad_s",
    "omega_prime": "omega_prime_rad_s2",
    "zeta_f": "zeta_f",
    "omega_c": "omega_c_rad_s",
    "dt": "dt_s",
    "duration": "duration_s",
    "T0": "T0_s",
    "tail": "tail_s",
}


@dataclass(frozen=True)
class RDKParams:
    """Parameters of the Rezaeian & Der Kiureghian model and of the simulation grid.

    Parameters
    ----------
    Ia : float
        Arias intensity of the modulating function, pi / (2 g) int q^2 dt over
        the simulated window [m/s]: the expected Arias intensity of x before the
        high-pass filter (which removes a few per cent).
    D5_95 : float
        Significant duration of the modulating function's Husid curve, 5 % to 95 % [s].
    t_mid : float
        Time at 45 % of the modulating function's Arias intensity [s], counted
        from the first sample.
    omega_mid : float
        Filter frequency at t_mid [rad/s].
    omega_prime : float
        Rate of change of the filter frequency [rad/s^2]; the filter frequency is
        omega_f(t) = omega_mid + omega_prime (t - t_mid), floored at ``omega_c``
        (content below the high-pass corner is removed anyway).
    zeta_f : float
        Filter damping ratio [-], in (0, 1).
    omega_c : float
        Corner frequency of the critically damped high-pass filter [rad/s].
    dt : float
        Sample step [s].
    duration : float
        End of the modulated noise [s]; the Husid parameters refer to [max(T0, 0), duration].
    T0 : float
        Start of the modulating function [s]: q = 0 for t <= T0. The default 0
        starts it at the first sample, as the record starts; a negative value is
        an envelope already under way at t = 0.
    tail : float, optional
        Time the high-pass filter is followed after ``duration`` with no further
        input [s], so that velocity and displacement return to zero; by default
        :func:`settle_time` (omega_c), resolved at construction (pass
        ``tail=None`` again when replacing ``omega_c``). Simulated motions have
        round((duration + tail) / dt) + 1 samples.

    Notes
    -----
    alpha1, alpha2 and alpha3 of q are solved at construction so that the Husid
    curve of q^2 over [max(T0, 0), duration] has the given D5-95 and t_mid and
    its integral gives Ia. Shapes down to alpha2 = 0.55 are accepted: with
    alpha2 < 1 q is unbounded at T0 but q^2 is integrable, which a strongly
    front-loaded record such as El Centro needs (alpha2 = 0.97 with T0 = 0).

    References
    ----------
    Rezaeian, S. & Der Kiureghian, A. (2010). Earthquake Engng Struct. Dyn. 39,
    1155-1180.
    """

    Ia: float
    D5_95: float
    t_mid: float
    omega_mid: float
    omega_prime: float
    zeta_f: float
    omega_c: float = DEFAULT_OMEGA_C
    dt: float = 0.01
    duration: float = 40.0
    T0: float = 0.0
    tail: float | None = None
    _alphas: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.tail is None:
            try:
                object.__setattr__(self, "tail", settle_time(float(self.omega_c)))
            except (TypeError, ValueError):
                object.__setattr__(self, "tail", 0.0)  # omega_c is reported below
        for key in _UNITS:
            value = getattr(self, key)
            try:
                v = float(value)
            except (TypeError, ValueError):
                raise ValueError(f"`{key}` must be a number, got {value!r}") from None
            if not math.isfinite(v):
                raise ValueError(f"`{key}` must be finite, got {value!r}")
            object.__setattr__(self, key, v)
        for key in ("Ia", "D5_95", "omega_mid", "omega_c", "dt", "duration"):
            if getattr(self, key) <= 0.0:
                raise ValueError(f"`{key}` must be positive, got {getattr(self, key)!r}")
        if self.tail < 0.0:
            raise ValueError(f"`tail` must be non-negative, got {self.tail!r}")
        if not 0.0 < self.zeta_f < 1.0:
            raise ValueError(f"`zeta_f` must lie in (0, 1), got {self.zeta_f!r}")
        if self.duration < 10.0 * self.dt:
            raise ValueError(f"`duration` ({self.duration} s) must span at least 10 steps of `dt` ({self.dt} s)")
        if not max(self.T0, 0.0) < self.t_mid < self.duration:
            raise ValueError(
                f"`t_mid` ({self.t_mid} s) must lie between max(`T0`, 0) and `duration` ({self.duration} s)"
            )
        if self.omega_mid <= self.omega_c:
            raise ValueError(f"`omega_mid` ({self.omega_mid} rad/s) must exceed `omega_c` ({self.omega_c} rad/s)")
        if self.omega_mid * self.dt >= math.pi:
            raise ValueError(f"`omega_mid` ({self.omega_mid} rad/s) must be below the Nyquist frequency pi / `dt`")
        object.__setattr__(self, "_alphas", solve_envelope(self.Ia, self.D5_95, self.t_mid, self.T0, self.duration))

    # --- derived -------------------------------------------------------
    @property
    def alpha1(self) -> float:
        """Scale of q [m/s^2 s^(1 - alpha2)]."""
        return self._alphas[0]

    @property
    def alpha2(self) -> float:
        """Shape of q [-] (> 0.5)."""
        return self._alphas[1]

    @property
    def alpha3(self) -> float:
        """Decay rate of q [1/s]."""
        return self._alphas[2]

    @property
    def n_noise(self) -> int:
        """Samples carrying modulated noise, t = 0 .. duration."""
        return int(round(self.duration / self.dt)) + 1

    @property
    def n_warm(self) -> int:
        """White-noise pulses before t = 0 [-], for the filter's impulse response to decay to 1e-3.

        The model's filtered noise integrates white noise from -infinity; starting
        the pulses at t = 0 instead would make the first samples a single
        normalised pulse, which under an envelope at its peak at t = 0 (alpha2 <= 1)
        gives isolated spikes.
        """
        decay = math.log(1e3) / self.zeta_f
        w = float(self.filter_frequency(0.0))
        w = float(self.filter_frequency(-decay / w))  # lower before t = 0 if omega' > 0
        return int(math.ceil(decay / (w * self.dt)))

    @property
    def n(self) -> int:
        """Samples of a simulated motion, t = 0 .. duration + tail."""
        return int(round((self.duration + self.tail) / self.dt)) + 1

    @property
    def t(self) -> np.ndarray:
        """Sample times of a simulated motion [s]."""
        return np.arange(self.n) * self.dt

    def modulating(self, t) -> np.ndarray:
        """Time-modulating function q(t) [m/s^2], the standard deviation of x(t); 0 for t <= T0 and t > duration."""
        t = np.asarray(t, dtype=float)
        s = np.atleast_1d(t - self.T0)
        out = np.zeros(s.shape)
        on = (s > 0.0) & (np.atleast_1d(t) <= self.duration + 0.5 * self.dt)
        out[on] = self.alpha1 * s[on] ** (self.alpha2 - 1.0) * np.exp(-self.alpha3 * s[on])
        return out.reshape(t.shape)

    def filter_frequency(self, t) -> np.ndarray:
        """Filter frequency omega_f(t) = omega_mid + omega' (t - t_mid), floored at omega_c [rad/s]."""
        t = np.asarray(t, dtype=float)
        return np.maximum(self.omega_mid + self.omega_prime * (t - self.t_mid), self.omega_c)

    def describe(self) -> dict:
        """Plain dict of the parameters (units in the keys) and derived values, for reports."""
        out: dict = {"model": "Rezaeian & Der Kiureghian (2010)"}
        out.update({_UNITS[f.name]: getattr(self, f.name) for f in fields(self) if f.name in _UNITS})
        out.update(
            {
                "f_mid_Hz": self.omega_mid / (2.0 * math.pi),
                "alpha1": self.alpha1,
                "alpha2": self.alpha2,
                "alpha3_1_s": self.alpha3,
            }
        )
        return out
