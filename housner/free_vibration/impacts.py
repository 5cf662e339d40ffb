"""Impacts and peaks of a sampled rotation theta(t): one detector for measured and simulated histories.

An impact of a rocking block is a zero crossing of theta. In a sampled,
possibly noisy record it is found in one of two ways, both here:

* :func:`hysteresis_crossings`: theta has crossed to the other side beyond a
  band +-h (h a few noise standard deviations), so noise near zero is not
  counted twice; for measured records (calibration, comparison with a
  campaign). :func:`fit_crossing` then locates the crossing between samples
  and :func:`fit_peak` the peak of a half-cycle.
* :func:`impact_times`: theta changes sign after |theta| exceeded a tolerance
  since the previous impact; for the noise-free histories of the engines,
  whose compliant contacts chatter by far less than the tolerance;
  :func:`uplift_time` finds when such a history first left the rest position.

Angles in rad, times in s.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize

__all__ = [
    "HYSTERESIS_SIGMAS",
    "IMPACT_RESOLUTION",
    "MIN_SAMPLES",
    "fit_crossing",
    "fit_peak",
    "hysteresis_crossings",
    "impact_times",
    "noise_crossings",
    "resolved_impact_count",
    "uplift_time",
]

#: Hysteresis of the zero-crossing detector, in noise standard deviations: a
#: crossing counts only once theta has gone beyond this band on the other side.
#: At 4 sigma a spurious crossing from Gaussian noise has probability ~3e-5 per sample.
HYSTERESIS_SIGMAS = 4.0
#: Resolution of impact counts compared across engines [-]: an impact counts when the half-cycle
#: before it reached this fraction of alpha. The analytic model's rest rule lets a record end in a
#: tail of ever smaller impacts that a compliant or rigid-LCP contact damps out; this leaves both out.
IMPACT_RESOLUTION = 0.01
#: Fewest samples on each side of an impact, and in a peak window, for a fit.
MIN_SAMPLES = 4


def hysteresis_crossings(theta: np.ndarray, h: float) -> tuple[np.ndarray, int]:
    """Indices k where theta has crossed to the other side beyond the band +-h.

    Returns the indices of the first sample beyond the band after each crossing,
    and the sign of the first side (0 if theta never leaves the band).
    """
    above = theta > h
    below = theta < -h
    state = np.zeros(theta.size, dtype=np.int8)
    state[above] = 1
    state[below] = -1
    k = np.flatnonzero(state)
    if k.size == 0:
        return np.empty(0, dtype=int), 0
    s = state[k]
    flips = np.flatnonzero(s[1:] != s[:-1]) + 1
    return k[flips], int(s[0])


def fit_crossing(
    t: np.ndarray, theta: np.ndarray, lo: int, hi: int, kc: int, h: float, sigma: float
) -> tuple[float, float]:
    """Impact time from a kinked fit through samples lo..hi-1 (|theta| within the band).

    Each side of the impact is a quadratic through (t_c, 0) with its own slope
    and curvature (the angular velocity drops at the impact); t_c minimises the
    total squared residual. Returns t_c and an approximate standard error.
    """
    ts = t[lo:hi]
    ys = theta[lo:hi]

    yy = ys * ys

    def sse(tc: float) -> float:
        # two least-squares fits through the origin, y ~ b tau + c tau^2, by their 2 x 2 normal equations
        tau = ts - tc
        total = 0.0
        for side in (tau < 0.0, tau >= 0.0):
            if np.count_nonzero(side) < 3:
                return math.inf
            u = tau[side]
            y = ys[side]
            u2 = u * u
            s11, s12, s22 = u2.sum(), (u2 * u).sum(), (u2 * u2).sum()
            r1, r2 = (u * y).sum(), (u2 * y).sum()
            det = s11 * s22 - s12 * s12
            if not det > 0:
                return math.inf
            b = (s22 * r1 - s12 * r2) / det
            c = (s11 * r2 - s12 * r1) / det
            total += float(yy[side].sum() - b * r1 - c * r2)
        return total

    # theta goes from beyond the band on the old side (last such sample before kc) to beyond it on the new
    # side (kc): the zero crossing lies in between. Scan that bracket finely, then polish with Brent.
    dt = t[1] - t[0]
    s_new = math.copysign(1.0, theta[kc])
    k_old = kc - 1
    while k_old > lo and not (s_new * theta[k_old] < -h):
        k_old -= 1
    a, b = max(t[k_old], ts[0] + 0.5 * dt), min(t[kc], ts[-1] - 0.5 * dt)
    if not b > a:
        a, b = ts[0], ts[-1]
    grid = np.linspace(a, b, max(3, int(round((b - a) / dt * 4)) + 1))
    vals = [sse(x) for x in grid]
    j = int(np.argmin(vals))
    lo_b, hi_b = grid[max(j - 1, 0)], grid[min(j + 1, grid.size - 1)]
    res = optimize.minimize_scalar(sse, bounds=(lo_b, hi_b), method="bounded", options={"xatol": 1e-7 * dt})
    tc = float(res.x)
    # profile-likelihood standard error: var(t_c) = 2 sigma^2 / SSE''(t_c), the other parameters re-fitted
    hstep = 0.05 * dt
    curv = (sse(tc + hstep) - 2.0 * res.fun + sse(tc - hstep)) / hstep**2
    std = math.sqrt(2.0 * sigma * sigma / curv) if curv > 0 and math.isfinite(curv) else math.nan
    return tc, std


def fit_peak(t: np.ndarray, y: np.ndarray, t_lo: float, t_hi: float, sigma: float) -> tuple[float, float, float]:
    """Vertex of a least-squares quartic through |theta| samples with t_lo <= t <= t_hi.

    A parabola is not enough: over the central half of a large half-cycle the
    trajectory's quartic term (theta ~ alpha - (alpha - theta_i) cosh(p tau)
    near the peak) biases a parabola's vertex by ~1e-3 of the amplitude, while
    the quartic costs only ~25 % more noise on the vertex than the parabola.
    """
    m = (t >= t_lo) & (t <= t_hi)
    if np.count_nonzero(m) < MIN_SAMPLES + 3:
        return math.nan, math.nan, math.nan
    ts = t[m]
    ys = y[m]
    tc = 0.5 * (t_lo + t_hi)
    half = 0.5 * (t_hi - t_lo)
    x = (ts - tc) / half  # scaled to [-1, 1] for conditioning
    A = np.vander(x, 5, increasing=True)
    coef, *_ = np.linalg.lstsq(A, ys, rcond=None)
    # vertex: Newton on the derivative from x = 0 (the peak is near the middle of a half-cycle)
    xv = 0.0
    for _ in range(20):
        d1 = coef[1] + 2 * coef[2] * xv + 3 * coef[3] * xv**2 + 4 * coef[4] * xv**3
        d2 = 2 * coef[2] + 6 * coef[3] * xv + 12 * coef[4] * xv**2
        if not d2 < 0:
            return math.nan, math.nan, math.nan
        step = d1 / d2
        xv -= step
        if abs(step) < 1e-14:
            break
    if not (-1.0 <= xv <= 1.0):
        return math.nan, math.nan, math.nan
    g = xv ** np.arange(5)
    amp = float(g @ coef)
    # standard error of the fitted curve at the vertex (the vertex position's own error is second order)
    resid = ys - A @ coef
    dof = max(ys.size - 5, 1)
    s = max(sigma, math.sqrt(float(resid @ resid) / dof))
    cov = s * s * np.linalg.inv(A.T @ A)
    std = math.sqrt(max(float(g @ cov @ g), 0.0))
    return tc + xv * half, amp, std


def noise_crossings(theta, noise: float) -> np.ndarray:
    """Indices of the impacts of a measured record: crossings beyond +-``HYSTERESIS_SIGMAS`` noise sigmas.

    Parameters
    ----------
    theta : array_like
        Rotation [rad], uniformly sampled.
    noise : float
        Noise standard deviation [rad] (a floor of 1e-12 rad keeps the band open).

    Returns
    -------
    ndarray of int
        For each crossing, the first sample beyond the band on the new side.
    """
    th = np.asarray(theta, dtype=float)
    return hysteresis_crossings(th, HYSTERESIS_SIGMAS * max(float(noise), 1e-12))[0]


def impact_times(t: np.ndarray, theta: np.ndarray, tol: float) -> np.ndarray:
    """Times [s] at which theta changes sign after |theta| exceeded ``tol`` [rad] since the previous one.

    Samples exactly at zero belong to neither side. The crossing time is
    interpolated linearly between the two samples around it.

    Parameters
    ----------
    t : ndarray
        Sample times [s].
    theta : ndarray
        Rotation [rad] at ``t``.
    tol : float
        Smallest swing [rad] that makes a sign change an impact: the block resting
        on both pivots, or a compliant contact's chatter, tilts by far less.

    Returns
    -------
    ndarray
        Impact times [s], increasing.
    """
    t = np.asarray(t, dtype=float)
    th = np.asarray(theta, dtype=float)
    sgn = np.sign(th)
    nz = np.flatnonzero(sgn != 0)
    if nz.size < 2:
        return np.empty(0)
    s = sgn[nz]
    change = np.flatnonzero(s[1:] != s[:-1])  # between nz[c] and nz[c + 1]
    if change.size == 0:
        return np.empty(0)
    # |theta| max of the stretch ending at each change: a stretch above tol makes its change an impact
    # (a stretch below it cannot follow an uncounted one above it, so "since the previous impact" is the same)
    starts = np.concatenate(([nz[0]], nz[change + 1]))
    seg_max = np.maximum.reduceat(np.abs(th), starts)[:-1]
    keep = change[seg_max > tol]
    i0, i1 = nz[keep], nz[keep + 1]
    a, b = th[i0], th[i1]
    return t[i0] + (t[i1] - t[i0]) * a / (a - b)


def uplift_time(t: np.ndarray, theta: np.ndarray, tol: float, released: bool, quiet: float = 2e-3) -> float:
    """When the block left its rest position [s], from a sampled theta; NaN when it never rocked.

    The block rocks once |theta| passes ``tol`` [rad] (as in :func:`impact_times`). A
    release from a tilted or moving state (``released``) lifts off at the first
    sample. Otherwise the climb of |theta| that first passed ``tol`` is followed back
    while |theta| falls and stays above ``quiet * tol``; just after uplift theta grows
    like (t - t_u)^3 (the ground acceleration crosses g tan(alpha) with a finite
    slope), so the times t1 and t2 at which the climb passes q = quiet tol and 8 q
    (linear interpolation between samples) give t_u = 2 t1 - t2. Against the analytic
    model's exact uplift instants this is within about 1 ms on one-sine pulses, where
    the first sample above q alone is 3-6 ms late.
    """
    t = np.asarray(t, dtype=float)
    abs_theta = np.abs(np.asarray(theta, dtype=float))
    big = abs_theta > tol
    if not big.any():
        return math.nan
    if released:
        return float(t[0])
    first = int(np.argmax(big))
    q = tol * quiet
    j = first
    while j > 0 and q < abs_theta[j - 1] < abs_theta[j]:
        j -= 1
    if j == 0 or abs_theta[j] <= q:
        return float(t[j])

    def crossing(level: float) -> float:
        k = j + int(np.argmax(abs_theta[j : first + 1] > level))
        a, b = abs_theta[k - 1], abs_theta[k]
        return float(t[k - 1] + (level - a) / (b - a) * (t[k] - t[k - 1])) if b > a else float(t[k])

    t1, t2 = crossing(q), crossing(8.0 * q)
    return max(float(t[j - 1]) - (t2 - t1), min(t1, 2.0 * t1 - t2), float(t[0]))


def resolved_impact_count(response, resolution: float = IMPACT_RESOLUTION) -> int:
    """Impacts of a response's sampled theta after a half-cycle peak of at least ``resolution`` alpha.

    The same count for every engine (the analytic one included): :func:`impact_times` on the
    response's samples, with the tolerance ``resolution * alpha`` [rad].
    """
    tol = resolution * response.alpha
    return int(impact_times(response.t, response.theta, tol).size)
