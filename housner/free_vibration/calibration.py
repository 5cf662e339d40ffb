"""Free-vibration calibration of the frequency parameter p and the energy ratio r.

A block released from rest at theta0 rocks freely; between impacts its energy
is conserved, at each impact a fraction 1 - r of it is lost. A record theta(t)
of such a test (e.g. 500 Hz, 0.8 mrad noise, as in the seed paper) is split
into half-cycles at the impacts (zero crossings of theta); each half-cycle
gives an amplitude theta_i and a duration T_i.

* r follows from successive amplitudes through the potential energy at the
  peaks (seed eq. 8), fitted over all impacts as one energy-decay line.
* p follows from duration and amplitude. Housner's linearised relation
  cosh(p T/4) = 1/(1 - theta0/alpha) (seed eq. 7) is biased by the
  linearisation sin(x) ~ x; the exact duration of a free half-cycle of the
  nonlinear equation is T_i = 2 F(theta_i, alpha) / p with the energy integral
  F (see :func:`half_cycle_integral`), so p = 2 F / T_i needs no empirical
  amplitude correction.

Angles in rad, times in s, p in 1/s, r dimensionless.

References
----------
Those of :mod:`housner.free_vibration.closed_forms` (Housner 1963; Bachmann et al. 2017,
section 3.2, eqs. 7 and 8), whose closed forms the fits invert.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from housner.free_vibration.closed_forms import (
    check_alpha,
    energy_ratios,
    half_cycle_integral,
    p_from_half_cycle,
    potential,
)
from housner.free_vibration.impacts import HYSTERESIS_SIGMAS, MIN_SAMPLES, fit_crossing, fit_peak, hysteresis_crossings

__all__ = [
    "FreeVibrationCalibration",
    "FreeVibrationPeaks",
    "calibrate_free_vibration",
    "estimate_noise",
    "free_vibration_peaks",
    "half_cycle_durations",
]

#: Default noise floor: half-cycles whose amplitude falls below this many noise
#: standard deviations end the analysis (their peak would be known to worse than ~5 %).
_FLOOR_SIGMAS = 10.0
#: Central fraction of a half-cycle used for the quartic fit of its peak. The
#: bias of the fit (sextic term of the trajectory) stays below 1e-5 of the peak
#: over the whole amplitude range (noise-free tests).
_PEAK_WINDOW = 0.5
#: Half-width of the band |theta| < band around an impact that is used to locate
#: it, as a fraction of the smaller neighbouring amplitude.
_CROSSING_BAND = 0.65


# ----------------------------------------------------------------------------
# signal processing
# ----------------------------------------------------------------------------
def estimate_noise(theta) -> float:
    """Robust standard deviation of white measurement noise on a smooth record [rad].

    Uses the median absolute deviation of the third differences: for white
    noise of standard deviation sigma they have standard deviation sqrt(20) sigma,
    while a smooth rocking record contributes ~theta''' dt^3 (negligible at
    hundreds of Hz) and the impacts only a few outliers each.

    Parameters
    ----------
    theta : array_like
        Uniformly sampled rotation [rad].

    Returns
    -------
    float
        sigma [rad].
    """
    th = np.asarray(theta, dtype=float)
    if th.ndim != 1 or th.size < 8:
        raise ValueError("`theta` must be one-dimensional with at least 8 samples")
    d3 = np.diff(th, 3)
    moving = d3 != 0.0  # samples of an exactly resting block say nothing about the noise
    if not np.any(moving):
        return 0.0
    d3 = d3[moving]
    mad = np.median(np.abs(d3 - np.median(d3)))
    return float(1.4826 * mad / math.sqrt(20.0))


@dataclass(frozen=True, eq=False)
class FreeVibrationPeaks:
    """Half-cycles of a free-vibration record, one entry per half-cycle.

    Attributes
    ----------
    t : ndarray
        Time of each peak [s].
    amplitude : ndarray
        |theta| at the peak [rad].
    amplitude_std : ndarray
        Standard error of the amplitude from the local fit [rad].
    sign : ndarray
        +1 where theta > 0 in the half-cycle, -1 where theta < 0.
    t_start, t_end : ndarray
        Impacts (zero crossings) that open and close the half-cycle [s]; NaN
        for the release segment (start) and a segment cut by the record's end.
    t_start_std, t_end_std : ndarray
        Approximate standard errors of those times [s].
    noise : float
        Noise standard deviation used [rad] (estimated or given).
    """

    t: np.ndarray
    amplitude: np.ndarray
    amplitude_std: np.ndarray
    sign: np.ndarray
    t_start: np.ndarray
    t_end: np.ndarray
    t_start_std: np.ndarray
    t_end_std: np.ndarray
    noise: float

    def __len__(self) -> int:
        return int(self.amplitude.size)

    @property
    def complete(self) -> np.ndarray:
        """Mask of half-cycles bounded by two located impacts."""
        return np.isfinite(self.t_start) & np.isfinite(self.t_end)

    @property
    def durations(self) -> np.ndarray:
        """t_end - t_start [s] (NaN for incomplete half-cycles)."""
        return self.t_end - self.t_start


def _check_record(t, theta) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(t, dtype=float)
    theta = np.asarray(theta, dtype=float)
    if t.ndim != 1 or theta.ndim != 1 or t.size != theta.size:
        raise ValueError(f"`t` and `theta` must be one-dimensional of equal length, got {t.shape} and {theta.shape}")
    if t.size < 16:
        raise ValueError(f"`theta` needs at least 16 samples, got {t.size}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(theta))):
        raise ValueError("`t` and `theta` must be finite")
    dt = np.diff(t)
    if not np.all(dt > 0) or np.ptp(dt) > 1e-6 * float(np.mean(dt)):
        raise ValueError("`t` must be uniformly increasing")
    return t, theta


def free_vibration_peaks(
    t, theta, alpha: float | None = None, *, noise: float | None = None, min_amplitude: float | None = None
) -> FreeVibrationPeaks:
    """Peaks of |theta| per half-cycle of a free-vibration record, robust to noise.

    Parameters
    ----------
    t : array_like
        Uniform sample times [s].
    theta : array_like
        Measured or simulated rotation [rad].
    alpha : float, optional
        Slenderness [rad]; only checked against the amplitudes when given.
    noise : float, optional
        Standard deviation of the measurement noise [rad]; estimated from the
        record (:func:`estimate_noise`) when omitted.
    min_amplitude : float, optional
        Noise floor [rad]: the analysis stops at the first half-cycle whose
        amplitude is below it. Default 10 noise standard deviations.

    Returns
    -------
    FreeVibrationPeaks

    Notes
    -----
    1. Impacts are the zero crossings of theta, detected with hysteresis:
       theta must pass from beyond +h to beyond -h (h = 4 sigma), so noise
       chattering around zero makes no spurious impact.
    2. Each impact time is refined with a kinked least-squares fit (one
       quadratic each side through the common zero, slopes free) over the
       samples with |theta| below 65 % of the smaller neighbouring amplitude.
    3. Each peak is the vertex of a least-squares quartic over the central
       half of its half-cycle, not the raw maximum of noisy samples (which is
       biased upward by about sigma times the expected maximum of the noise).
    4. A record that starts at the release (theta at rest, as simulated
       free-vibration responses do) gives the release angle as the first peak,
       from an even quartic with its vertex at the first sample. Otherwise the
       segment before the first impact is kept only when its peak is interior
       (e.g. a hold at the release angle before letting go).
    """
    t, theta = _check_record(t, theta)
    if alpha is not None:
        alpha = check_alpha(alpha)
    sigma, sigma_eff, floor = _noise_floor(theta, noise, min_amplitude)
    h = HYSTERESIS_SIGMAS * sigma_eff
    kx, first_sign = hysteresis_crossings(theta, h)
    if first_sign == 0:
        raise ValueError("`theta` never leaves the noise band: no rocking to analyse")
    # segments between detected crossings: [b_j, b_{j+1})
    bounds = np.concatenate(([0], kx, [theta.size]))
    signs = first_sign * (-1) ** np.arange(bounds.size - 1)
    rough = np.array([np.max(signs[j] * theta[bounds[j] : bounds[j + 1]]) for j in range(bounds.size - 1)])
    tc, tc_std = _impact_times(t, theta, kx, rough, floor, h, sigma_eff)
    rows = _half_cycle_rows(t, theta, bounds, signs, rough, tc, tc_std, floor, sigma_eff)
    if not rows:
        raise ValueError("no half-cycle above the noise floor could be analysed")
    arr = np.array(rows, dtype=float)
    if alpha is not None and np.any(arr[:, 1] >= alpha):
        raise ValueError(f"peak amplitude {arr[:, 1].max():.6g} rad reaches `alpha` = {alpha:.6g} rad")
    return FreeVibrationPeaks(
        t=arr[:, 0],
        amplitude=arr[:, 1],
        amplitude_std=arr[:, 2],
        sign=arr[:, 3].astype(int),
        t_start=arr[:, 4],
        t_end=arr[:, 5],
        t_start_std=arr[:, 6],
        t_end_std=arr[:, 7],
        noise=sigma,
    )


def _noise_floor(theta: np.ndarray, noise: float | None, min_amplitude: float | None) -> tuple[float, float, float]:
    """The noise of a record and the floor of the analysis: (sigma, sigma_eff, floor) [rad].

    ``sigma`` is ``noise`` when given, else estimated (:func:`estimate_noise`); ``sigma_eff`` is at least
    1e-9 of the record's peak, so that a noise-free record still gets a non-zero band; ``floor`` is
    ``min_amplitude``, by default :data:`_FLOOR_SIGMAS` times ``sigma_eff``.
    """
    if noise is None:
        sigma = estimate_noise(theta)
    else:
        if not (math.isfinite(noise) and noise >= 0):
            raise ValueError(f"`noise` must be non-negative and finite, got {noise!r}")
        sigma = float(noise)
    scale = float(np.max(np.abs(theta)))
    if scale == 0.0:
        raise ValueError("`theta` is identically zero: the block never rocked")
    sigma_eff = max(sigma, 1e-9 * scale)  # a noise-free record still needs a non-zero band
    floor = _FLOOR_SIGMAS * sigma_eff if min_amplitude is None else float(min_amplitude)
    if not (math.isfinite(floor) and floor >= 0):
        raise ValueError(f"`min_amplitude` must be non-negative and finite, got {min_amplitude!r}")
    return sigma, sigma_eff, floor


def _impact_times(
    t: np.ndarray, theta: np.ndarray, kx: np.ndarray, rough: np.ndarray, floor: float, h: float, sigma: float
) -> tuple[np.ndarray, np.ndarray]:
    """Impact times refined between samples and their standard errors [s], one per detected crossing.

    Crossing j (sample ``kx[j]``) is fitted over the samples around it with |theta| below
    :data:`_CROSSING_BAND` of the smaller neighbouring rough amplitude (``rough``); the refinement stops,
    leaving NaN, at the first crossing next to a segment below ``floor`` or with too few samples in its band.
    """
    n = theta.size
    tc = np.full(kx.size, np.nan)
    tc_std = np.full(kx.size, np.nan)
    for j, k in enumerate(kx):
        if min(rough[j], rough[j + 1]) < floor:
            break
        band = max(_CROSSING_BAND * min(rough[j], rough[j + 1]), 2.0 * h)
        lo = k - 1
        while lo > 0 and abs(theta[lo - 1]) < band:
            lo -= 1
        hi = k + 1
        while hi < n and abs(theta[hi]) < band:
            hi += 1
        if (k - lo) < MIN_SAMPLES // 2 + 1 or (hi - k) < MIN_SAMPLES // 2 + 1:
            break
        tc[j], tc_std[j] = fit_crossing(t, theta, lo, hi, k, h, sigma)
    return tc, tc_std


def _half_cycle_rows(t, theta, bounds, signs, rough, tc, tc_std, floor: float, sigma: float) -> list[tuple]:
    """One row (t_peak, amplitude, amplitude_std, sign, t_start, t_end, t_start_std, t_end_std) per half-cycle.

    Segment j runs between samples ``bounds[j]`` and ``bounds[j + 1]`` with sign ``signs[j]``, between impacts
    ``tc[j - 1]`` and ``tc[j]``. The rows stop at the first half-cycle below ``floor``, after an impact that
    could not be located, or at a peak that cannot be fitted (a release segment without one is skipped).
    """
    rows = []
    for j in range(bounds.size - 1):
        s = signs[j]
        if rough[j] < floor:
            break
        y = s * theta
        t0 = tc[j - 1] if j >= 1 else math.nan
        t1 = tc[j] if j < tc.size else math.nan
        if j >= 1 and not math.isfinite(t0):
            break  # the impact before this half-cycle could not be located: past the floor
        peak = _segment_peak(t, y, bounds[j], bounds[j + 1], t0, t1, j == 0, sigma)
        if peak is None:
            break
        tp, amp, std = peak
        if not math.isfinite(amp):
            if j == 0:
                continue  # no usable release peak; the first full half-cycle follows
            break
        if amp < floor:
            break
        s0 = tc_std[j - 1] if j >= 1 else math.nan
        s1 = tc_std[j] if j < tc.size else math.nan
        rows.append((tp, amp, std, s, t0, t1, s0, s1))
    return rows


def _segment_peak(
    t: np.ndarray, y: np.ndarray, b0: int, b1: int, t0: float, t1: float, first: bool, sigma: float
) -> tuple[float, float, float] | None:
    """Peak (time [s], amplitude [rad], its standard error [rad]) of the segment of samples ``b0:b1`` of
    ``y`` = sign x theta, between the impacts at ``t0`` and ``t1`` (NaN where not located).

    A half-cycle between two impacts: quartic over the central :data:`_PEAK_WINDOW` of it. The ``first``
    segment, before the first impact: :func:`_fit_release`. A segment cut by the end of the record: a
    quartic around its maximum, or None (no peak) when the maximum is not well inside it.
    """
    if math.isfinite(t0) and math.isfinite(t1):
        w = 0.5 * _PEAK_WINDOW * (t1 - t0)
        mid = 0.5 * (t0 + t1)
        return fit_peak(t, y, mid - w, mid + w, sigma)
    if first and math.isfinite(t1):
        return _fit_release(t, y, t1, sigma)
    # segment cut by the end of the record: use it only if its peak is well inside
    kk = b0 + int(np.argmax(y[b0:b1]))
    half = max(MIN_SAMPLES, (b1 - b0) // 8)
    if kk - half < b0 or kk + half >= b1:
        return None
    return fit_peak(t, y, t[kk - half], t[kk + half], sigma)


def _fit_release(t: np.ndarray, y: np.ndarray, t1: float, sigma: float) -> tuple[float, float, float]:
    """Peak of the segment before the first impact (at t1).

    If the record starts at the release (at rest), the trajectory is the falling half of a
    symmetric peak with its vertex at t[0]: fit a + c tau^2 + e tau^4 over the first quarter of
    the time to the impact. Otherwise (a hold before the release, a late start) fit a free quartic
    around the maximum if it is interior. NaN when neither applies.
    """
    k_max = int(np.argmax(y[t < t1]))
    n_first = int(np.count_nonzero(t < t1))
    if k_max > max(2, n_first // 20):
        # the record does not start at the release (hold before it, or a late start)
        half = max(MIN_SAMPLES, n_first // 8)
        if k_max - half < 0 or k_max + half >= n_first:
            return math.nan, math.nan, math.nan
        return fit_peak(t, y, t[k_max - half], t[k_max + half], sigma)
    m = t <= t[0] + 0.5 * _PEAK_WINDOW * (t1 - t[0])
    if np.count_nonzero(m) < MIN_SAMPLES + 2:
        return math.nan, math.nan, math.nan
    x = (t[m] - t[0]) / (t1 - t[0])
    A = np.column_stack((np.ones_like(x), x * x, x**4))  # even: symmetric about the release
    coef, *_ = np.linalg.lstsq(A, y[m], rcond=None)
    resid = y[m] - A @ coef
    s = max(sigma, math.sqrt(float(resid @ resid) / max(x.size - 3, 1)))
    std = s * math.sqrt(float(np.linalg.inv(A.T @ A)[0, 0]))
    return float(t[0]), float(coef[0]), std


def half_cycle_durations(t, theta=None, *, noise: float | None = None, min_amplitude: float | None = None):
    """Durations between successive impacts, each with the amplitude of its half-cycle.

    Parameters
    ----------
    t : array_like or FreeVibrationPeaks
        Sample times [s], or the result of :func:`free_vibration_peaks`.
    theta : array_like, optional
        Rotation [rad] (required when ``t`` is an array).
    noise, min_amplitude : float, optional
        Passed to :func:`free_vibration_peaks`.

    Returns
    -------
    durations : ndarray
        Time between the two impacts that bound each complete half-cycle [s];
        impact times are zero crossings located by a local fit between samples.
    amplitudes : ndarray
        Peak |theta| of the same half-cycles [rad].
    """
    if isinstance(t, FreeVibrationPeaks):
        pk = t
    else:
        if theta is None:
            raise ValueError("`theta` is required when `t` is an array of times")
        pk = free_vibration_peaks(t, theta, noise=noise, min_amplitude=min_amplitude)
    m = pk.complete
    return pk.durations[m], pk.amplitude[m]


@dataclass(frozen=True, eq=False)
class FreeVibrationCalibration:
    """Calibrated p and r of a rocking specimen from one free-vibration record.

    Attributes
    ----------
    p : float
        Frequency parameter [1/s] from the exact half-cycle durations
        (inverse-variance weighted mean over the first ``n_p`` complete half-cycles).
    p_std : float
        Its standard error [1/s] (from the scatter of the per-half-cycle values).
    p_linearised : float
        The same average of Housner's linearised eq. 7 values [1/s], for comparison.
    r : float
        Kinetic-energy ratio at impact [-]: exp of the slope of the weighted
        least-squares line through ln(cos(alpha - theta_i) - cos(alpha)) against
        the half-cycle index i, over all impacts above the noise floor.
    r_std : float
        Its standard error [-].
    n_half_cycles : int
        Number of half-cycles analysed (peaks found).
    n_p : int
        Number of complete half-cycles averaged for p.
    alpha : float
        Slenderness used [rad].
    noise : float
        Noise standard deviation [rad] (estimated or given).
    peaks : FreeVibrationPeaks
        The per-half-cycle analysis (peak times, amplitudes, impact times).
    p_half_cycle : ndarray
        Exact-method p of each complete half-cycle [1/s].
    p_half_cycle_linearised : ndarray
        Eq. 7 p of each complete half-cycle [1/s].
    half_cycle_amplitude : ndarray
        Amplitude of each complete half-cycle [rad].
    half_cycle_duration : ndarray
        Duration of each complete half-cycle [s].
    c : ndarray
        Energy ratio of each impact (seed eq. 8) [-].
    c_amplitude : ndarray
        Amplitude before each impact [rad] (for plots of r against amplitude).
    """

    p: float
    p_std: float
    p_linearised: float
    r: float
    r_std: float
    n_half_cycles: int
    n_p: int
    alpha: float
    noise: float
    peaks: FreeVibrationPeaks
    p_half_cycle: np.ndarray
    p_half_cycle_linearised: np.ndarray
    half_cycle_amplitude: np.ndarray
    half_cycle_duration: np.ndarray
    c: np.ndarray
    c_amplitude: np.ndarray

    def summary(self) -> dict:
        """Plain dict of the scalar results."""
        return {
            "p_1_s": self.p,
            "p_std_1_s": self.p_std,
            "p_linearised_1_s": self.p_linearised,
            "r": self.r,
            "r_std": self.r_std,
            "n_half_cycles": self.n_half_cycles,
            "n_p": self.n_p,
            "noise_rad": self.noise,
        }


def _weighted_mean(x: np.ndarray, var: np.ndarray) -> tuple[float, float]:
    """Inverse-variance weighted mean and its standard error (scaled by the observed scatter)."""
    w = 1.0 / var
    mean = float(np.sum(w * x) / np.sum(w))
    if x.size < 2:
        return mean, float(math.sqrt(1.0 / np.sum(w)))
    chi2 = float(np.sum(w * (x - mean) ** 2)) / (x.size - 1)
    return mean, float(math.sqrt(max(chi2, 1.0) / np.sum(w)))


def calibrate_free_vibration(
    t,
    theta,
    alpha: float,
    noise: float | None = None,
    *,
    n_p: int = 15,
    min_amplitude: float | None = None,
) -> FreeVibrationCalibration:
    """Calibrate p and r from a free-vibration record (seed section 3.2).

    Parameters
    ----------
    t : array_like
        Uniform sample times [s].
    theta : array_like
        Rotation [rad], released from rest at the start or after a hold.
    alpha : float
        Slenderness of the specimen [rad] (geometry: atan(B/H) of the pivots).
    noise : float, optional
        Measurement noise standard deviation [rad]; estimated when omitted.
    n_p : int
        Number of complete half-cycles, from the first, whose p values are
        averaged (the seed used 15).
    min_amplitude : float, optional
        Noise floor [rad]; see :func:`free_vibration_peaks`.

    Returns
    -------
    FreeVibrationCalibration

    Notes
    -----
    * p: each complete half-cycle i gives p_i = 2 F(theta_i, alpha) / T_i
      (exact; :func:`p_from_half_cycle` with ``method="exact"``). Its variance
      is propagated from the amplitude and impact-time errors,
      var(ln p_i) = (d ln F / d ln theta_i)^2 (s_theta/theta_i)^2 + (s_T/T_i)^2,
      and the first ``n_p`` values are averaged with inverse-variance weights.
    * r: with E_i = cos(alpha - theta_i) - cos(alpha) the potential energy at
      peak i (over m g R), an ideal Housner block has E_{i+1} = r E_i, i.e.
      ln E_i = ln E_0 + i ln r. The line is fitted by weighted least squares
      with var(ln E_i) = (sin(alpha - theta_i) s_theta_i / E_i)^2, which uses
      every impact but lets the noisy small ones count little. The per-impact
      c_i (seed eq. 8) are returned too: a trend of c_i with amplitude shows an
      impact that is not Housner's.

    References
    ----------
    Housner (1963); Bachmann et al. (2017), section 3.2, eqs. 7 and 8.
    """
    alpha = check_alpha(alpha)
    if not (isinstance(n_p, (int, np.integer)) and n_p >= 1):
        raise ValueError(f"`n_p` must be a positive integer, got {n_p!r}")
    pk = free_vibration_peaks(t, theta, alpha, noise=noise, min_amplitude=min_amplitude)
    if len(pk) < 2:
        raise ValueError("fewer than two half-cycles above the noise floor: cannot calibrate r")
    amp = pk.amplitude
    s_amp = np.maximum(pk.amplitude_std, 1e-12 * amp)
    r, r_std = _energy_decay_r(amp, s_amp, alpha)
    T, a_c, p_exact, p_lin, var_lnp = _half_cycle_p(pk, s_amp, alpha)
    k = min(n_p, p_exact.size)
    p, p_std = _weighted_mean(p_exact[:k], var_lnp[:k] * p_exact[:k] ** 2)
    p_l, _ = _weighted_mean(p_lin[:k], var_lnp[:k] * p_lin[:k] ** 2)
    return FreeVibrationCalibration(
        p=p,
        p_std=p_std,
        p_linearised=p_l,
        r=r,
        r_std=r_std,
        n_half_cycles=len(pk),
        n_p=k,
        alpha=alpha,
        noise=pk.noise,
        peaks=pk,
        p_half_cycle=p_exact,
        p_half_cycle_linearised=p_lin,
        half_cycle_amplitude=a_c,
        half_cycle_duration=T,
        c=energy_ratios(amp, alpha),
        c_amplitude=amp[:-1],
    )


def _energy_decay_r(amp: np.ndarray, s_amp: np.ndarray, alpha: float) -> tuple[float, float]:
    """r and its standard error [-]: the weighted energy-decay line through the peak amplitudes ``amp`` [rad]
    with standard errors ``s_amp`` [rad] (see :func:`calibrate_free_vibration`, Notes)."""
    E = potential(amp, alpha)
    var_lnE = (np.sin(alpha - amp) * s_amp / E) ** 2
    i = np.arange(amp.size, dtype=float)
    w = 1.0 / var_lnE
    A = np.column_stack((np.ones_like(i), i))
    Aw = A * w[:, None]
    cov = np.linalg.inv(A.T @ Aw)
    coef = cov @ (Aw.T @ np.log(E))
    resid = np.log(E) - A @ coef
    dof = amp.size - 2
    chi2 = float(np.sum(w * resid**2)) / dof if dof > 0 else 1.0
    slope_std = math.sqrt(cov[1, 1] * max(chi2, 1.0))
    r = math.exp(coef[1])
    return r, r * slope_std


def _half_cycle_p(pk: FreeVibrationPeaks, s_amp: np.ndarray, alpha: float):
    """Durations [s], amplitudes [rad], exact and linearised p [1/s] and var(ln p) [-] of the complete
    half-cycles (see :func:`calibrate_free_vibration`, Notes); the largest positive variance stands in
    where one is not a positive finite number."""
    m = pk.complete
    T = pk.durations[m]
    a_c = pk.amplitude[m]
    sa_c = s_amp[m]
    sT = np.hypot(pk.t_start_std[m], pk.t_end_std[m])
    if a_c.size == 0:
        raise ValueError("no complete half-cycle (two located impacts) above the noise floor: cannot calibrate p")
    p_exact = np.atleast_1d(p_from_half_cycle(T, a_c, alpha, method="exact"))
    p_lin = np.atleast_1d(p_from_half_cycle(T, a_c, alpha, method="linearised"))
    # logarithmic sensitivity of F to the amplitude, by a forward difference
    eps = 1e-4
    F = np.atleast_1d(half_cycle_integral(a_c, alpha))
    Fp = np.atleast_1d(half_cycle_integral(np.minimum(a_c * (1 + eps), 0.5 * (a_c + alpha)), alpha))
    dlnF = np.log(Fp / F) / np.log1p(eps)
    var_lnp = (dlnF * sa_c / a_c) ** 2 + (sT / T) ** 2
    var_lnp = np.where(np.isfinite(var_lnp) & (var_lnp > 0), var_lnp, np.nanmax(var_lnp[var_lnp > 0], initial=1e-12))
    return T, a_c, p_exact, p_lin, var_lnp
