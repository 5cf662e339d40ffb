"""Elastic response spectra of ground motions.

The single-degree-of-freedom oscillator

    u'' + 2 zeta omega u' + omega^2 u = -ug''(t)

is integrated with the exact recurrence for an excitation that is linear
between samples (Nigam & Jennings 1969): over a step h the state (u, u')
advances as ``x[k+1] = A x[k] + B0 f[k] + B1 f[k+1]`` with A, B0 and B1 exact
for the oscillator, so the only approximation is the linear interpolation of
the record itself. Peaks between samples are caught by sub-stepping: every
oscillator is advanced with at least ``points_per_period`` steps per natural
period (the interpolated input is unchanged by this, only sampled more finely).

The recurrence runs for all periods of a spectrum in one compiled loop.

References
----------
Nigam, N. C. & Jennings, P. C. (1969). Calculation of response spectra from
strong-motion earthquake records. BSSA 59(2), 909-922.
Chopra, A. K. (2012). Dynamics of Structures, 4th ed., sec. 5.2 (interpolation
of excitation) and ch. 6 (response spectra).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numba
import numpy as np
from scipy.linalg import expm

from housner.motion import GroundMotion

__all__ = ["ensemble_spectra", "linear_step_coefficients", "response_spectrum", "sdof_history"]

#: Default smallest number of integration steps per oscillator period [-]. With
#: 20 points a sinusoidal peak is sampled within 1 - cos(pi/20) = 1.2 % of its
#: true value even before the exact-recurrence interpolation is considered.
POINTS_PER_PERIOD = 20


def linear_step_coefficients(omega, zeta: float, h) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact one-step matrices of u'' + 2 zeta omega u' + omega^2 u = f(t) for f linear over the step.

    Parameters
    ----------
    omega : float or array_like
        Natural circular frequency [rad/s], shape (m,) or scalar.
    zeta : float
        Damping ratio [-]; any value >= 0 (1 is critical damping).
    h : float or array_like
        Step [s], scalar or broadcastable to ``omega``.

    Returns
    -------
    A : ndarray, shape (m, 2, 2)
    B0, B1 : ndarray, shape (m, 2)
        ``[u, u'][k+1] = A @ [u, u'][k] + B0 f[k] + B1 f[k+1]`` [m, m/s for f in m/s^2].

    Notes
    -----
    The matrices are the exponential of the oscillator augmented with the
    forcing and its (constant) slope as states, which is the closed-form
    Nigam & Jennings recurrence written for any damping.
    """
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    h = np.broadcast_to(np.asarray(h, dtype=float), omega.shape)
    m = np.zeros(omega.shape + (4, 4))
    m[:, 0, 1] = 1.0
    m[:, 1, 0] = -(omega**2)
    m[:, 1, 1] = -2.0 * zeta * omega
    m[:, 1, 2] = 1.0
    m[:, 2, 3] = 1.0
    e = expm(m * h[:, None, None])
    A = np.ascontiguousarray(e[:, :2, :2])
    slope = e[:, :2, 3] / h[:, None]
    B0 = np.ascontiguousarray(e[:, :2, 2] - slope)
    B1 = np.ascontiguousarray(slope)
    return A, B0, B1


@numba.njit(cache=True)
def _peak_displacements(acc, n_sub, A, B0, B1):  # pragma: no cover - compiled
    """Peak |u| of each oscillator j for the ground acceleration ``acc`` (forcing -acc)."""
    n = acc.size
    n_osc = n_sub.size
    out = np.zeros(n_osc)
    for j in range(n_osc):
        a00, a01, a10, a11 = A[j, 0, 0], A[j, 0, 1], A[j, 1, 0], A[j, 1, 1]
        b00, b01, b10, b11 = B0[j, 0], B0[j, 1], B1[j, 0], B1[j, 1]
        ns = n_sub[j]
        u = 0.0
        v = 0.0
        peak = 0.0
        for k in range(n - 1):
            f0 = -acc[k]
            df = (-acc[k + 1] - f0) / ns
            for s in range(ns):
                fa = f0 + s * df
                fb = fa + df
                un = a00 * u + a01 * v + b00 * fa + b10 * fb
                v = a10 * u + a11 * v + b01 * fa + b11 * fb
                u = un
                if abs(u) > peak:
                    peak = abs(u)
        out[j] = peak
    return out


@numba.njit(cache=True)
def _history(f, A, B0, B1):  # pragma: no cover - compiled
    """Displacement and velocity histories for forcing columns f[:, m] (one oscillator)."""
    n, m = f.shape
    u = np.zeros((n, m))
    v = np.zeros((n, m))
    a00, a01, a10, a11 = A[0, 0], A[0, 1], A[1, 0], A[1, 1]
    b00, b01, b10, b11 = B0[0], B0[1], B1[0], B1[1]
    for k in range(n - 1):
        for c in range(m):
            fa = f[k, c]
            fb = f[k + 1, c]
            u[k + 1, c] = a00 * u[k, c] + a01 * v[k, c] + b00 * fa + b10 * fb
            v[k + 1, c] = a10 * u[k, c] + a11 * v[k, c] + b01 * fa + b11 * fb
    return u, v


def sdof_history(f: np.ndarray, dt: float, omega: float, zeta: float) -> tuple[np.ndarray, np.ndarray]:
    """Response of u'' + 2 zeta omega u' + omega^2 u = f(t) from rest, f linear between samples.

    Parameters
    ----------
    f : ndarray, shape (n,) or (n, m)
        Forcing per unit mass at t_k = k dt [m/s^2]; columns are independent records.
    dt : float
        Sample step [s].
    omega : float
        Natural circular frequency [rad/s].
    zeta : float
        Damping ratio [-] (>= 0; 1 for a critically damped filter).

    Returns
    -------
    u, v : ndarray, same shape as ``f``
        Displacement [m] and velocity [m/s] at the samples.
    """
    f = np.asarray(f, dtype=float)
    squeeze = f.ndim == 1
    f2 = np.ascontiguousarray(f.reshape(f.shape[0], -1))
    A, B0, B1 = linear_step_coefficients(omega, zeta, dt)
    u, v = _history(f2, A[0], B0[0], B1[0])
    if squeeze:
        return u[:, 0], v[:, 0]
    return u, v


def _check_spectrum_args(periods, damping, points_per_period) -> tuple[np.ndarray, float, int]:
    """Periods [s], damping ratio [-] and integration points per period, checked (in that order)."""
    T, zeta = _check_periods(periods), check_damping(damping)
    if int(points_per_period) < 1:
        raise ValueError(f"`points_per_period` must be a positive integer, got {points_per_period!r}")
    return T, zeta, int(points_per_period)


def _check_periods(periods) -> np.ndarray:
    try:
        T = np.asarray(periods, dtype=float)
    except (TypeError, ValueError):
        raise ValueError("`periods` must be numeric [s]") from None
    if T.ndim > 1:
        raise ValueError(f"`periods` must be one-dimensional, got shape {T.shape}")
    T = np.atleast_1d(T)
    if T.size == 0:
        raise ValueError("`periods` is empty")
    if not np.all(np.isfinite(T)) or np.any(T <= 0):
        raise ValueError("`periods` must be positive and finite [s]")
    return T


def check_damping(damping: float) -> float:
    try:
        z = float(damping)
    except (TypeError, ValueError):
        raise ValueError(f"`damping` must be a number, got {damping!r}") from None
    if not (math.isfinite(z) and 0.0 <= z < 1.0):
        raise ValueError(f"`damping` must lie in [0, 1) (a ratio, 0.05 for 5 %), got {damping!r}")
    return z


def _spectrum_plan(dt: float, T: np.ndarray, damping: float, points_per_period: int):
    omega = 2.0 * np.pi / T
    n_sub = np.maximum(1, np.ceil(points_per_period * dt / T)).astype(np.int64)
    A, B0, B1 = linear_step_coefficients(omega, damping, dt / n_sub)
    return omega, n_sub, A, B0, B1


def response_spectrum(
    motion: GroundMotion, periods, damping: float = 0.05, *, points_per_period: int = POINTS_PER_PERIOD
) -> tuple[np.ndarray, np.ndarray]:
    """Pseudo-acceleration and displacement spectra of one ground motion.

    Parameters
    ----------
    motion : GroundMotion
        Ground acceleration [m/s^2], linear between samples, oscillators at rest at t = 0.
    periods : array_like
        Natural periods T [s], positive.
    damping : float
        Damping ratio zeta [-], in [0, 1); 0.05 is 5 % of critical.
    points_per_period : int
        Smallest number of integration steps per period [-]; the record step is
        subdivided (excitation still linear between the record's samples) where
        ``dt > T / points_per_period``, so short-period peaks are not missed.

    Returns
    -------
    psa : ndarray
        Pseudo-spectral acceleration omega^2 Sd [m/s^2], one per period.
    sd : ndarray
        Spectral displacement max |u| [m], one per period.

    Notes
    -----
    The response is followed over the record only (no free-vibration tail),
    as is usual for records that end quietly.

    References
    ----------
    Nigam, N. C. & Jennings, P. C. (1969). BSSA 59(2), 909-922.
    """
    if not isinstance(motion, GroundMotion):
        raise TypeError(f"`motion` must be a housner.GroundMotion, got {type(motion).__name__}")
    T, zeta, points_per_period = _check_spectrum_args(periods, damping, points_per_period)
    omega, n_sub, A, B0, B1 = _spectrum_plan(motion.dt, T, zeta, points_per_period)
    sd = _peak_displacements(np.ascontiguousarray(motion.acc), n_sub, A, B0, B1)
    return omega**2 * sd, sd


def ensemble_spectra(
    motions: Sequence[GroundMotion],
    periods,
    damping: float = 0.05,
    *,
    points_per_period: int = POINTS_PER_PERIOD,
) -> tuple[np.ndarray, np.ndarray]:
    """Spectra of many motions: ``psa`` [m/s^2] and ``sd`` [m], each of shape (len(motions), len(periods)).

    Parameters are those of :func:`response_spectrum`. Motions may differ in step
    and length; the integration plan is shared between motions of equal step.
    Take ``psa.mean(axis=0)`` for the ensemble mean spectrum.
    """
    motions = list(motions)
    if not motions:
        raise ValueError("`motions` is empty")
    for i, m in enumerate(motions):
        if not isinstance(m, GroundMotion):
            raise TypeError(f"`motions[{i}]` must be a housner.GroundMotion, got {type(m).__name__}")
    T, zeta, points_per_period = _check_spectrum_args(periods, damping, points_per_period)
    plans: dict[float, tuple] = {}
    sd = np.empty((len(motions), T.size))
    for i, m in enumerate(motions):
        plan = plans.get(m.dt)
        if plan is None:
            plan = plans[m.dt] = _spectrum_plan(m.dt, T, zeta, int(points_per_period))
        omega, n_sub, A, B0, B1 = plan
        sd[i] = _peak_displacements(np.ascontiguousarray(m.acc), n_sub, A, B0, B1)
    return (2.0 * np.pi / T) ** 2 * sd, sd
