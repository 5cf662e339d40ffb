"""Free-rocking measures of a simulated response: peaks, first-impact energy ratio, exact quarter period and decay.

What the contact tuning (:mod:`housner.engines.tuning`) and the conformance check
(:mod:`housner.engines.conformance`) measure on an engine's noise-free response, and
the exact values of Housner's equation they are compared with. Peaks are
refined by a parabola through the samples around the largest one.

Angles in rad, times in s.

References
----------
Housner, G. W. (1963). The behavior of inverted pendulum structures during
earthquakes. BSSA 53(2), 403-417.
Bachmann, J. A. et al. (2017). Probabilistic validation of the Housner rocking
model. COMPDYN 2017, eqs. 4, 7 and 8.
"""

from __future__ import annotations

import math

import numpy as np

from housner.free_vibration.closed_forms import energy_ratios, half_cycle_integral
from housner.response import Response
from housner.rocking_params import RockingParams
from housner.specimen import Specimen

__all__ = [
    "decay_peaks",
    "first_impact_ratio",
    "first_peak",
    "first_impact_velocity_ratio",
    "free_rocking_quarter_period",
    "half_cycle_peaks",
    "parabolic_peak",
    "rocking_energy",
]


def free_rocking_quarter_period(specimen: Specimen, theta0: float, params: RockingParams | None = None) -> float:
    """Time [s] from a release at rest at ``theta0`` [rad] to the first impact, exact for Housner's equation.

    With no ground motion, rocking on the +x pivot obeys
    theta'' = -p^2 sin(alpha - theta), whose energy integral from a release at
    rest at theta0 is theta'^2 / 2 = p^2 (cos(alpha - theta0) - cos(alpha - theta)).
    The time to fall to theta = 0 is

        T/4 = int_0^theta0 dtheta / sqrt(2 p^2 (cos(alpha - theta0) - cos(alpha - theta))).

    That integral is F(theta0, alpha) / p with F from
    :func:`housner.free_vibration.closed_forms.half_cycle_integral`; a free half-cycle (impact
    to impact) lasts twice as long, since its rise and fall are symmetric.

    Parameters
    ----------
    specimen : Specimen
        Provides p [1/s] and alpha [rad].
    theta0 : float
        Release angle [rad], 0 < |theta0| < alpha.
    params : RockingParams, optional
        alpha and p of each pivot (a block with ``asymmetric_pivots``): those of the pivot on
        theta0's side are used. None (default): the specimen's.

    References
    ----------
    Housner (1963), eq. for the free-rocking period; Bachmann et al. (2017), eq. 7.
    """
    th0 = abs(float(theta0))
    alpha, p = specimen.alpha, specimen.p
    if params is not None:
        alpha, p = (params.alpha_pos, params.p_pos) if theta0 > 0.0 else (params.alpha_neg, params.p_neg)
    if not 0.0 < th0 < alpha:
        raise ValueError(f"`theta0` must satisfy 0 < |theta0| < alpha = {alpha:.6g} rad, got {theta0!r}")
    return float(half_cycle_integral(th0, alpha)) / p


def parabolic_peak(y: np.ndarray, i: int) -> float:
    """Vertex of the parabola through y[i-1], y[i], y[i+1] (y[i] at the ends)."""
    if i <= 0 or i >= y.size - 1:
        return float(y[i])
    a, b, c = y[i - 1], y[i], y[i + 1]
    den = a - 2.0 * b + c
    if den >= 0.0:
        return float(b)
    return float(b - 0.125 * (a - c) ** 2 / den)


def first_impact_ratio(response: Response, alpha: float | None = None) -> float:
    """Kinetic-energy ratio of the first impact of a free-vibration response (seed eq. 8) [-].

    The peaks are |theta| at release (the largest |theta| before the first
    sign change) and the largest |theta| of the next half-cycle, refined by a
    parabola through the samples around it. NaN when the record ends before
    that half-cycle's peak, when the block never crossed zero, or when a peak
    reached alpha.

    Parameters
    ----------
    response : Response
        A free-vibration response (noise-free engine output).
    alpha : float, optional
        Slenderness [rad]; defaults to ``response.alpha``.

    References
    ----------
    Bachmann et al. (2017), eq. 8.
    """
    alpha = response.alpha if alpha is None else float(alpha)
    th = np.asarray(response.theta, dtype=float)
    s0 = np.sign(th[0]) if th[0] != 0 else np.sign(th[np.argmax(np.abs(th))])
    crossed = np.flatnonzero(th * s0 < 0)
    if crossed.size == 0:
        return math.nan
    k1 = int(crossed[0])
    i0 = int(np.argmax(np.abs(th[:k1])))
    peak0 = parabolic_peak(np.abs(th), i0)
    back = np.flatnonzero(th[k1:] * s0 > 0)
    k2 = k1 + int(back[0]) if back.size else th.size
    seg = np.abs(th[k1:k2])
    i1 = int(np.argmax(seg))
    if i1 >= seg.size - 1:  # still rising when the record (or half-cycle) ends
        return math.nan
    peak1 = parabolic_peak(np.abs(th), k1 + i1)
    if not (peak0 < alpha and peak1 < alpha):  # rocked past alpha: no free-vibration half-cycle to compare
        return math.nan
    return float(energy_ratios([peak0, peak1], alpha)[0])


#: |theta| / alpha below which a response counts as still at rest in :func:`first_peak` [-]: above the
#: 2.4e-8 alpha jitter of DART's rigid contact at rest, five orders below the smallest first peak the
#: tuner measures (0.018 alpha).
FIRST_PEAK_JITTER = 1e-6


def first_peak(response: Response) -> float:
    """Largest |theta| [rad] before the first impact of a response that starts at rest.

    The peak is refined by a parabola through the samples around it. NaN if
    the block never left rest, or if |theta| is still growing when the record
    ends before any impact.
    """
    th = np.asarray(response.theta, dtype=float)
    # A rigid contact's solver leaves the block at rest jittering by a few 1e-8 alpha of either sign
    # (DART's boxed LCP); that is not rocking, and a sign change of it is no impact.
    tol = FIRST_PEAK_JITTER * response.alpha
    moving = np.flatnonzero(np.abs(th) > tol)
    if moving.size == 0:
        return math.nan
    k0 = int(moving[0])
    s0 = np.sign(th[k0])
    back = np.flatnonzero(th[k0:] * s0 < -tol)
    end = k0 + int(back[0]) if back.size else th.size
    seg = np.abs(th[:end])
    i = int(np.argmax(seg))
    if i >= seg.size - 1 and not back.size:
        return math.nan
    return parabolic_peak(np.abs(th), i)


def half_cycle_peaks(response: Response | np.ndarray) -> np.ndarray:
    """|theta| peak [rad] of each half-cycle of a response (or of sampled theta [rad]), up to the last complete one.

    Half-cycles are the stretches between sign changes of the sampled theta;
    each peak is refined by a parabola through the samples around the largest
    one. Index 0 is the stretch that starts the record (the release, for a
    free vibration), index k the one after the k-th impact. A final stretch
    still rising when the record ends is left out.
    """
    th = np.asarray(response.theta if isinstance(response, Response) else response, dtype=float)
    a = np.abs(th)
    sgn = np.sign(th)
    nz = np.flatnonzero(sgn != 0)
    if nz.size == 0:
        return np.empty(0)
    change = nz[1:][sgn[nz[1:]] != sgn[nz[:-1]]]  # first sample of each new half-cycle
    bounds = np.concatenate(([0], change, [th.size]))
    out = []
    for i0, i1 in zip(bounds[:-1], bounds[1:], strict=True):
        i = i0 + int(np.argmax(a[i0:i1]))
        if i == th.size - 1 and i > 0:  # still rising at the end of the record
            break
        out.append(parabolic_peak(a, i))
    return np.asarray(out)


def decay_peaks(specimen: Specimen, theta0: float, n_impacts: int, r: float | None = None) -> np.ndarray:
    """Exact peaks [rad] of Housner's free rocking from rest at ``theta0``, before and after each of ``n_impacts``.

    Between impacts the energy integral holds, and each impact keeps the
    fraction r of the kinetic energy, which at theta = 0 is the whole energy
    above the upright position; so the peak after impact k satisfies

        cos(alpha - theta_k) - cos(alpha) = r^k (cos(alpha - theta_0) - cos(alpha)).

    Parameters
    ----------
    specimen : Specimen
        Provides alpha [rad] and Housner's r.
    theta0 : float
        Release angle [rad], 0 < |theta0| < alpha.
    n_impacts : int
        Number of impacts.
    r : float, optional
        Kinetic-energy ratio at impact [-]; ``specimen.r_housner`` by default.

    Returns
    -------
    numpy.ndarray
        n_impacts + 1 peaks |theta_k| [rad], k = 0 .. n_impacts.

    References
    ----------
    Housner (1963); Bachmann et al. (2017), eqs. 4 and 8.
    """
    alpha = specimen.alpha
    th0 = abs(float(theta0))
    if not 0.0 < th0 < alpha:
        raise ValueError(f"`theta0` must satisfy 0 < |theta0| < alpha = {alpha:.6g} rad, got {theta0!r}")
    r = specimen.r_housner if r is None else float(r)
    e0 = math.cos(alpha - th0) - math.cos(alpha)
    k = np.arange(int(n_impacts) + 1)
    return alpha - np.arccos(np.cos(alpha) + r**k * e0)


def rocking_energy(params: RockingParams, theta: float, theta_dot: float) -> float:
    """Rocking energy per unit of the inertia about the pivot rocked on [1/s^2]:
    theta'^2 / 2 + p_s^2 (cos(alpha_s - |theta|) - cos alpha_s), with alpha_s, p_s of the pivot of theta's
    side s (``params``: per pivot, as ``asymmetric_pivots`` sets them). Constant in free rocking between
    impacts; theta'^2 / 2 at theta = 0."""
    alpha, p = (params.alpha_pos, params.p_pos) if theta >= 0.0 else (params.alpha_neg, params.p_neg)
    return 0.5 * theta_dot * theta_dot + p * p * (math.cos(alpha - abs(theta)) - math.cos(alpha))


def first_impact_velocity_ratio(response: Response, params: RockingParams, window: float = 0.01) -> float:
    """|theta'| after / before the first impact of a free-rocking response [-], from its rocking energy.

    The energy (:func:`rocking_energy`, per unit of the inertia about the pivot rocked on) at the
    sample ``window`` [s] before the first impact and at the one ``window`` after it; in free rocking
    each is theta'^2 / 2 at theta = 0 on its side, so the ratio's square root is that of the angular
    velocities just before and just after the impact (sqrt(r_pos) or sqrt(r_neg) of
    :class:`housner.rocking_params.RockingParams` for the analytic model). Unlike
    :func:`first_impact_ratio` it needs no second peak, so it also measures a first impact after which
    the block falls. ``window`` leaves a compliant contact time to finish the impact (MuJoCo's time
    constant is 0.4 ms, the OpenSees springs' contact half-period about 1 ms).

    Raises
    ------
    ValueError
        The response has no impact, or not ``window`` of samples on either side of the first.
    """
    if response.impact_times.size == 0:
        raise ValueError("`response` has no impact")
    t, t1 = response.t, float(response.impact_times[0])
    if not (t[0] <= t1 - window and t1 + window <= t[-1]):
        raise ValueError(f"`response` needs {window:g} s of samples on either side of its first impact at {t1:g} s")
    ib = int(np.searchsorted(t, t1 - window, side="right")) - 1
    ia = int(np.searchsorted(t, t1 + window))
    before = rocking_energy(params, float(response.theta[ib]), float(response.theta_dot[ib]))
    after = rocking_energy(params, float(response.theta[ia]), float(response.theta_dot[ia]))
    return math.sqrt(after / before)
