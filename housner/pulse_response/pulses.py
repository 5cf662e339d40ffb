"""Analytical pulse ground motions: Ricker wavelets, one-sine pulses, Mavroeidis-Papageorgiou near-fault pulses,
free-vibration releases.

Pulses are the excitations of rocking spectra (seed Figure 2): a block's theta_max / alpha depends only on
alpha, omega_p / p and a_p / (g tan alpha) (seed eq. 6). Every function returns a
:class:`housner.GroundMotion` in m/s^2 on a uniform grid, with its parameters in ``name`` and
``provenance``. ``a_p`` [m/s^2] is the pulse's peak ground acceleration, max |ug''| = |a_p| (a negative
``a_p`` mirrors the pulse); ``omega_p`` [rad/s] is its frequency: for both Ricker wavelets the frequency at
which the Fourier amplitude spectrum peaks, for the one-sine pulse the sine's own (period
T_p = 2 pi / omega_p). A positive ground acceleration tilts the block toward -x (theta < 0).

References
----------
Housner, G. W. (1963). The behavior of inverted pendulum structures during
earthquakes. BSSA 53(2), 403-417 (rectangular and sine pulses).
Zhang, J., Makris, N. (2001). Rocking response of free-standing blocks under
cycloidal pulses. J. Eng. Mech. 127(5), 473-483 (one-sine pulse, phase 0:
see :func:`one_sine`).
Vassiliou, M. F., Makris, N. (2011). Estimating time scales and length scales
in pulselike earthquake acceleration records with wavelet analysis. BSSA
101(2), 596-618 (symmetric and antisymmetric Ricker wavelets).
Mavroeidis, G. P., Papageorgiou, A. S. (2003). A mathematical representation
of near-fault ground motions. BSSA 93(3), 1099-1131 (eq. 4: the velocity pulse).
Dimitrakopoulos, E. G., DeJong, M. J. (2012). Revisiting the rocking block:
closed-form solutions and similarity laws. Proc. R. Soc. A 468, 2294-2318.
"""

from __future__ import annotations

import math

import numpy as np

from housner._validate import finite as _finite
from housner._validate import positive as _positive
from housner.motion import GroundMotion

__all__ = [
    "RICKER_KINDS",
    "RICKER_TAIL",
    "free_vibration",
    "mavroeidis_papageorgiou",
    "mp_velocity",
    "one_sine",
    "ricker",
    "ricker_half_width",
    "ricker_shape",
]

RICKER_KINDS = ("symmetric", "antisymmetric")

#: The Ricker window is cut where the wavelet's envelope falls below this
#: fraction of a_p for good; at 1e-6 the cut is far below any uplift threshold
#: (a_p / (g tan alpha) would have to exceed 1e6) and the velocity left at the
#: ends is ~1e-6 a_p / omega_p.
RICKER_TAIL = 1e-6

#: Peak of |(u^3 - 3u) exp(-u^2/2)|, at u^2 = 3 - sqrt(6): normalises the
#: antisymmetric wavelet to peak a_p (the beta = 1.3801 of Vassiliou & Makris 2011).
_BETA_ANTI = abs((lambda u: (u**3 - 3 * u) * math.exp(-0.5 * u * u))(math.sqrt(3.0 - math.sqrt(6.0))))

#: Free rocking after the pulse, in units of 1/p, when the block's p is given:
#: a free half-cycle of amplitude theta_i lasts 2 F(theta_i)/p with
#: F ~ arccosh(1/(1 - theta_i/alpha)); 30/p covers the time to the next peak
#: from any excursion below 0.9999 alpha (2 arccosh(1e4) = 19.8).
_FREE_ROCKING_P = 30.0

#: Free time after the pulse when p is not given [s]: 10 pulse periods, and at
#: least this much (covers 30/p for blocks with p >= 3 1/s, i.e. R <~ 0.8 m).
_FREE_ROCKING_MIN = 10.0


def _default_free_time(omega_p: float, p: float | None) -> float:
    if p is not None:
        return _FREE_ROCKING_P / _positive("p", p)
    return max(10.0 * 2.0 * math.pi / omega_p, _FREE_ROCKING_MIN)


def _grid(total: float, dt: float) -> np.ndarray:
    n = int(math.floor(total / dt + 1e-9)) + 1
    return np.arange(n) * dt


def ricker(
    a_p: float,
    omega_p: float,
    *,
    kind: str = "symmetric",
    dt: float,
    duration: float | None = None,
    t0: float | None = None,
    p: float | None = None,
) -> GroundMotion:
    """Ricker-wavelet acceleration pulse (Vassiliou & Makris 2011).

    ug''(t) = a_p psi(omega_p (t - t0)), with psi from :func:`ricker_shape`:

    * symmetric: psi(x) = (1 - x^2/2) exp(-x^2/4), so ug''(t0) = a_p is the peak;
    * antisymmetric: psi(x) = (u^3 - 3u) exp(-u^2/2) / beta, u = x/sqrt(3),
      beta = 1.3801, so the two main lobes peak at -+a_p either side of t0.

    Parameters
    ----------
    a_p : float
        Peak ground acceleration of the pulse [m/s^2]; its sign sets the polarity.
    omega_p : float
        Frequency where the wavelet's Fourier amplitude peaks [rad/s].
    kind : {"symmetric", "antisymmetric"}
        Wavelet.
    dt : float
        Sample step [s]; resolve the pulse with about 50 or more samples per
        2 pi / omega_p (the motion is linear between samples).
    duration : float, optional
        Total duration [s]. Default: the pulse window 2 t0 plus the free
        rocking after it, 30/p when ``p`` is given, else the larger of ten
        pulse periods and 10 s.
    t0 : float, optional
        Centre of the wavelet [s]. Default: the half-width beyond which
        |psi| < 1e-6 for good (8.33/omega_p symmetric, 10.64/omega_p
        antisymmetric), so the motion starts from ~zero.
    p : float, optional
        Frequency parameter of the block that will be shaken [1/s]; only used
        for the default duration.

    Returns
    -------
    GroundMotion
        Accelerations [m/s^2] at t = k dt.

    References
    ----------
    Vassiliou & Makris (2011); Dimitrakopoulos & DeJong (2012).
    """
    a_p = _finite("a_p", a_p)
    omega_p = _positive("omega_p", omega_p)
    dt = _positive("dt", dt)
    if kind not in RICKER_KINDS:
        raise ValueError(f"`kind` must be one of {RICKER_KINDS}, got {kind!r}")
    t0 = ricker_half_width(kind) / omega_p if t0 is None else _finite("t0", t0)
    total = 2.0 * max(t0, 0.0) + _default_free_time(omega_p, p) if duration is None else _positive("duration", duration)
    t = _grid(total, dt)
    acc = a_p * ricker_shape(omega_p * (t - t0), kind)
    return GroundMotion(
        acc=acc,
        dt=dt,
        name=f"{kind} Ricker a_p={a_p:.4g} m/s^2 omega_p={omega_p:.4g} rad/s",
        provenance=(
            f"housner.pulse_response.pulses.ricker(a_p={a_p!r}, omega_p={omega_p!r}, kind={kind!r}, dt={dt!r}, "
            f"duration={total!r}, t0={t0!r}); Vassiliou & Makris (2011) wavelet, peak |ug''| = |a_p|"
        ),
    )


def one_sine(
    a_p: float,
    omega_p: float,
    *,
    dt: float,
    duration: float | None = None,
    phase: float = 0.0,
    p: float | None = None,
) -> GroundMotion:
    """One full cycle of sine acceleration, then rest (Housner 1963; Zhang & Makris 2001).

    ug''(t) = a_p sin(omega_p t + phase) for 0 <= t <= T_p = 2 pi / omega_p, 0 after.
    With the default phase 0 this is the one-sine pulse of Zhang & Makris
    (2001), the block waiting at rest until |ug''| reaches g tan(alpha)
    (see ``phase``).

    Parameters
    ----------
    a_p : float
        Amplitude [m/s^2] (the peak of |ug''|).
    omega_p : float
        Circular frequency of the sine [rad/s].
    dt : float
        Sample step [s]. The grid is not adjusted: choose dt = T_p / N for a
        pulse that ends on a sample.
    duration : float, optional
        Total duration [s]; default T_p plus the free rocking after it (30/p
        when ``p`` is given, else the larger of ten pulse periods and 10 s).
    phase : float
        Phase of the sine at t = 0 [rad]. It shifts the sine *inside* a window
        that is always one full period, 0 <= t <= T_p: the pulse runs from
        phase ``phase`` to ``phase + 2 pi``, so a non-zero phase gives a
        different pulse, not the same pulse started later. With any phase the
        ground velocity returns to zero at T_p; the displacement ends at
        2 pi a_p cos(phase) / omega_p^2 (2 pi a_p / omega_p^2 with phase 0).

        **Zhang & Makris (2001) use phase 0** (their one-sine, "type-A" pulse,
        whose displacement is a cycloid): the ground moves from t = 0, the
        block stays at rest until a_p sin(omega_p t) first reaches
        g tan(alpha), at t_u = asin(g tan(alpha) / a_p) / omega_p, and the
        pulse ends at T_p. Their angle psi = asin(g tan(alpha) / a_p) is the
        phase of the pulse *at uplift*, with which they write the solution in
        a time counted from the uplift; it is not a phase to pass here.
        ``phase = psi`` would run a whole extra period from the uplift phase
        (the pulse then ends at psi + 2 pi), a stronger pulse: at
        omega_p / p = 5 and r = 0.81 its first overturning acceleration is
        3.34 g tan(alpha) instead of their 3.02, 11 % off.
        ``tests/test_published.py`` reproduces their overturning boundaries
        with phase 0.
    p : float, optional
        Frequency parameter of the block [1/s]; only used for the default duration.

    Returns
    -------
    GroundMotion
        Accelerations [m/s^2] at t = k dt: the sine up to T_p, then zeros.

    References
    ----------
    Housner (1963); Zhang & Makris (2001).
    """
    a_p = _finite("a_p", a_p)
    omega_p = _positive("omega_p", omega_p)
    dt = _positive("dt", dt)
    phase = _finite("phase", phase)
    Tp = 2.0 * math.pi / omega_p
    total = Tp + _default_free_time(omega_p, p) if duration is None else _positive("duration", duration)
    t = _grid(total, dt)
    acc = np.where(t <= Tp * (1.0 + 1e-12), a_p * np.sin(omega_p * t + phase), 0.0)
    return GroundMotion(
        acc=acc,
        dt=dt,
        name=f"one-sine a_p={a_p:.4g} m/s^2 omega_p={omega_p:.4g} rad/s",
        provenance=(
            f"housner.pulse_response.pulses.one_sine(a_p={a_p!r}, omega_p={omega_p!r}, dt={dt!r}, duration={total!r}, "
            f"phase={phase!r}); one cycle of a_p sin(omega_p t + phase), then zero"
        ),
    )


def mp_velocity(t, f_p: float, gamma: float, nu: float, t0: float) -> np.ndarray:
    """The Mavroeidis-Papageorgiou velocity pulse of unit amplitude [-] at times ``t`` [s] (their eq. 4).

    v(t) = 1/2 (1 + cos(2 pi f_p (t - t0) / gamma)) cos(2 pi f_p (t - t0) + nu) for
    |t - t0| <= gamma / (2 f_p), 0 outside: a harmonic of frequency ``f_p`` [Hz] and phase ``nu`` [rad] under a
    raised-cosine envelope ``gamma`` [-] of its cycles wide, centred at ``t0`` [s].
    """
    t = np.asarray(t, dtype=float)
    u = 2.0 * math.pi * f_p * (t - t0)
    inside = np.abs(t - t0) <= gamma / (2.0 * f_p)
    return np.where(inside, 0.5 * (1.0 + np.cos(u / gamma)) * np.cos(u + nu), 0.0)


def _mp_acc(t, f_p: float, gamma: float, nu: float, t0: float) -> np.ndarray:
    """The exact time derivative of :func:`mp_velocity` [1/s] (per unit velocity amplitude)."""
    t = np.asarray(t, dtype=float)
    u = 2.0 * math.pi * f_p * (t - t0)
    inside = np.abs(t - t0) <= gamma / (2.0 * f_p)
    a = -math.pi * f_p * (np.sin(u / gamma) * np.cos(u + nu) / gamma + (1.0 + np.cos(u / gamma)) * np.sin(u + nu))
    return np.where(inside, a, 0.0)


def mavroeidis_papageorgiou(
    a_p: float,
    omega_p: float,
    *,
    dt: float,
    gamma: float = 2.0,
    nu: float = 0.0,
    duration: float | None = None,
    p: float | None = None,
) -> GroundMotion:
    """A near-fault velocity pulse (Mavroeidis & Papageorgiou 2003), as the ground acceleration it implies.

    The velocity is :func:`mp_velocity` with f_p = omega_p / (2 pi), scaled so that the acceleration, its exact
    derivative, peaks at |a_p|; the pulse starts at t = 0 (t0 = gamma / (2 f_p)) and the ground is at rest
    after it (velocity back to zero: the envelope vanishes at both ends).

    Parameters
    ----------
    a_p : float
        Peak ground acceleration [m/s^2] (a negative value mirrors the pulse).
    omega_p : float
        The pulse's circular frequency 2 pi f_p [rad/s].
    dt : float
        Sample step [s].
    gamma : float
        Oscillatory character [-], > 1: the envelope spans gamma cycles (near-fault records: 1.5-3).
    nu : float
        Phase of the harmonic [rad] (0: a symmetric velocity pulse; pi/2: an antisymmetric one).
    duration : float, optional
        Total duration [s]; default the pulse plus the free rocking after it (as :func:`one_sine`).
    p : float, optional
        Frequency parameter of the block [1/s]; only used for the default duration.

    Returns
    -------
    GroundMotion
        Accelerations [m/s^2] at t = k dt.

    References
    ----------
    Mavroeidis & Papageorgiou (2003), eq. 4.
    """
    a_p = _finite("a_p", a_p)
    omega_p = _positive("omega_p", omega_p)
    dt = _positive("dt", dt)
    gamma = _finite("gamma", gamma)
    if not gamma > 1.0:
        raise ValueError(f"`gamma` must exceed 1 (the envelope spans gamma cycles), got {gamma!r}")
    nu = _finite("nu", nu)
    f_p = omega_p / (2.0 * math.pi)
    width = gamma / f_p
    t0 = 0.5 * width
    # the peak of the unit pulse's acceleration, on a grid of 2e5 points over its width (relative error ~1e-9)
    peak = float(np.max(np.abs(_mp_acc(np.linspace(0.0, width, 200_001), f_p, gamma, nu, t0))))
    total = width + _default_free_time(omega_p, p) if duration is None else _positive("duration", duration)
    t = _grid(total, dt)
    acc = a_p / peak * _mp_acc(t, f_p, gamma, nu, t0)
    return GroundMotion(
        acc=acc,
        dt=dt,
        name=f"Mavroeidis-Papageorgiou a_p={a_p:.4g} m/s^2 omega_p={omega_p:.4g} rad/s gamma={gamma:.3g} nu={nu:.3g}",
        provenance=(
            f"housner.pulse_response.pulses.mavroeidis_papageorgiou(a_p={a_p!r}, omega_p={omega_p!r}, dt={dt!r}, "
            f"gamma={gamma!r}, nu={nu!r}, duration={total!r}); the derivative of the velocity pulse of "
            "Mavroeidis & Papageorgiou (2003, eq. 4), peak acceleration a_p"
        ),
    )


def free_vibration(theta0: float, duration: float, dt: float = 0.002) -> GroundMotion:
    """No ground motion; the block is released from rest at ``theta0`` [rad].

    Parameters
    ----------
    theta0 : float
        Release angle [rad], |theta0| < alpha for a block that rocks back.
    duration : float
        Duration [s].
    dt : float
        Sample step [s] (500 Hz like the seed's optical measurements by default).

    Returns
    -------
    GroundMotion
        Zero accelerations with ``theta0`` set (:meth:`GroundMotion.free_vibration`).
    """
    return GroundMotion.free_vibration(_finite("theta0", theta0), _positive("duration", duration), _positive("dt", dt))


def ricker_shape(x, kind: str = "symmetric") -> np.ndarray:
    """Unit Ricker wavelet at dimensionless time x = omega_p (t - t0) [-].

    Parameters
    ----------
    x : array_like
        omega_p (t - t0) [-].
    kind : {"symmetric", "antisymmetric"}
        ``"symmetric"``: (1 - x^2/2) exp(-x^2/4), the second derivative of the
        Gaussian exp(-x^2/4) up to a factor; value 1 at x = 0.
        ``"antisymmetric"``: (u^3 - 3u) exp(-u^2/2) / beta with u = x / sqrt(3)
        (the third derivative of the Gaussian exp(-x^2/6) up to a factor),
        beta = 1.3801 its peak; -1 at u = sqrt(3 - sqrt(6)) (x = 1.285) and +1 at x = -1.285.

    Returns
    -------
    ndarray
        The wavelet [-], with max |value| = 1.

    Notes
    -----
    With these Gaussians the Fourier amplitude of either wavelet, |omega|^k
    exp(-omega^2 s^2 / 2) with k = 2, s^2 = 2/omega_p^2 and k = 3, s^2 = 3/omega_p^2,
    peaks at omega = omega_p, the convention of Vassiliou & Makris (2011).

    References
    ----------
    Vassiliou, M. F., Makris, N. (2011). Estimating time scales and length
    scales in pulselike earthquake acceleration records with wavelet analysis.
    BSSA 101(2), 596-618.
    """
    x = np.asarray(x, dtype=float)
    if kind == "symmetric":
        return (1.0 - 0.5 * x * x) * np.exp(-0.25 * x * x)
    if kind == "antisymmetric":
        u = x / math.sqrt(3.0)
        return (u**3 - 3.0 * u) * np.exp(-0.5 * u * u) / _BETA_ANTI
    raise ValueError(f"`kind` must be one of {RICKER_KINDS}, got {kind!r}")


def ricker_half_width(kind: str = "symmetric", tail: float = RICKER_TAIL) -> float:
    """Dimensionless half-width x = omega_p t beyond which |ricker_shape(x)| < ``tail`` for good [-].

    8.33 (symmetric) and 10.64 (antisymmetric) for the default tail 1e-6.
    """
    from scipy import optimize

    if kind not in RICKER_KINDS:
        raise ValueError(f"`kind` must be one of {RICKER_KINDS}, got {kind!r}")
    if not (0.0 < tail < 0.1):
        raise ValueError(f"`tail` must lie in (0, 0.1), got {tail!r}")
    # beyond the last side lobe (x^2 = 6 symmetric, u^2 = 3 + sqrt(6) antisymmetric) |psi| only falls
    x_lobe = math.sqrt(6.0) if kind == "symmetric" else math.sqrt(3.0 * (3.0 + math.sqrt(6.0)))
    return optimize.brentq(lambda x: abs(float(ricker_shape(x, kind))) - tail, x_lobe, 80.0, xtol=1e-12)
