"""Where a model fails: the localisation quantities of the measurement and of a model, with standard errors.

The same quantities are computed from the measured histories and from a
model's (observed through the same sensor, see :func:`housner.scenarios.diagnosis.comparison.record_comparison.compare`)
by :func:`features`, and :meth:`Features.metrics` gives each
(:data:`METRICS`) with its standard error, so that a difference between the two
is a difference of the physics (see :mod:`housner.scenarios.diagnosis.comparison.record_comparison`, "Where the model
fails").
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from housner.free_vibration.calibration import FreeVibrationCalibration, calibrate_free_vibration
from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.campaigns.campaign_records import MeasuredRecord
from housner.scenarios.diagnosis.comparison.history_error import FV_FLOOR_SIGMAS, measured_impacts
from housner.units import G

__all__ = ["METRICS", "Features", "Metric", "features", "line_fit", "mean_se", "measured_features"]

#: Free-vibration half-cycles below this many noise sigmas are left out of the localisation (their
#: peaks and slopes are known to worse than ~5 %).
FV_MIN_SIGMAS = 20.0
#: Energy kept between impacts: the speeds at the two impacts of a half-cycle are fitted on the
#: samples within this fraction of its amplitude, for half-cycles above FLIGHT_MIN_SIGMAS noise
#: sigmas (at 0.8 mrad the squared speed ratio then scatters by ~0.13 per half-cycle).
FLIGHT_BAND = 0.6
FLIGHT_MIN_SIGMAS = 40.0
#: Fewest records for a pooled regression's standard error to be clustered by record [-].
MIN_CLUSTERS = 10
#: Uplift detection: theta, averaged over this many samples, leaves rest by 5 of its sigmas.
UPLIFT_SMOOTH = 9
UPLIFT_SIGMAS = 5.0
#: Samples closer than this to the detected uplift do not count as "before uplift" [s].
UPLIFT_MARGIN = 0.05
#: Free-vibration analyses a campaign keeps (:func:`features`), the oldest dropped beyond this many [-].
FV_CACHE_SIZE = 256


class Metric(NamedTuple):
    """A localisation quantity: value and standard error (NaN when there is nothing to measure)."""

    value: float
    se: float
    n: int


#: The localisation metrics: key -> (label, unit, which Housner value it should have).
METRICS: dict[str, tuple[str, str]] = {
    "energy_ratio": ("energy ratio per impact (free vibration, seed eq. 8)", "-"),
    "energy_ratio_trend": ("slope of the energy ratio against amplitude/alpha", "-"),
    "energy_ratio_scatter": ("scatter of the energy ratio about its trend, impact to impact (standard deviation)", "-"),
    "flight_ratio": ("energy kept between impacts, (speed before / after the half-cycle)^2", "-"),
    "flight_ratio_trend": ("slope of the energy kept between impacts against amplitude/alpha", "-"),
    "p": ("frequency parameter from the half-cycle durations (exact seed eq. 7)", "1/s"),
    "alternation": ("ln c of impacts ending theta > 0 minus ending theta < 0 (free vibration)", "-"),
    "onset_pos": ("uplift onset toward +theta, ground acceleration / g tan(alpha)", "-"),
    "onset_neg": ("uplift onset toward -theta, ground acceleration / g tan(alpha)", "-"),
    "withstood_pos": ("largest ground acceleration toward +theta stood at rest / g tan(alpha)", "-"),
    "withstood_neg": ("largest ground acceleration toward -theta stood at rest / g tan(alpha)", "-"),
    "first_uplift_pos": ("share of records whose first uplift is toward +theta", "-"),
    "share_pos": ("share of excursions toward +theta", "-"),
    "tilt_offset": ("rotation before uplift at zero ground acceleration", "alpha"),
    "tilt_slope": ("rotation before uplift per ground acceleration over g tan(alpha)", "alpha"),
    "overturn_fraction": ("overturn fraction of the ground-motion records", "-"),
    "theta_max_median": ("median theta_max/alpha of the ground-motion records", "-"),
    "onset_scatter": ("scatter of the uplift onset from record to record, both directions (standard deviation)", "-"),
}


@dataclass(frozen=True, eq=False)
class Features:
    """The localisation quantities of one source (the measurement or a model).

    Attributes (arrays pool the records; amplitudes are over alpha)
    ----------------------------------------------------------------
    energy_amplitude, energy_ratio, energy_sign : ndarray
        Free vibration, per impact: amplitude before it [alpha], energy ratio
        c (seed eq. 8) [-], sign of theta in the half-cycle it ends.
    energy_record : ndarray
        Free vibration, per impact: position of its record in the campaign (the recording order) [-].
    half_cycle_amplitude, half_cycle_duration : ndarray
        Free vibration, per complete half-cycle: amplitude [alpha], duration [s].
    flight_amplitude, flight_ratio : ndarray
        Free vibration, per half-cycle: amplitude [alpha] and the squared
        ratio of the speeds at its closing and opening impacts [-] (1 when no
        energy is lost between impacts).
    onset_sign, onset_ratio : ndarray
        Ground motion, per record: direction of the first uplift (+1, -1, 0
        if it never rocked) and the largest ground acceleration toward that
        direction before the block is seen to move, over g tan(alpha) [-]
        (an upper estimate of the uplift threshold; identical for model and
        measurement).
    withstood_pos, withstood_neg : ndarray
        Ground motion, per record: the largest ground acceleration toward
        +theta (ug'' < 0) and toward -theta (ug'' > 0) that the block stood
        at rest, up to 50 ms before it is seen to move, over g tan(alpha) [-]
        (a lower estimate of each direction's threshold; NaN if it never rested).
    excursions : (int, int)
        Ground motion: number of excursions toward +theta and -theta.
    tilt_theta, tilt_acc : ndarray
        Ground motion, pooled samples before uplift while |ug''| < g tan(alpha):
        theta [alpha] and ug''/(g tan alpha) [-] (thinned to every 5th sample); ``tilt_record`` the
        record each came from (their standard errors are clustered by record: a sensor's noise is
        correlated within a record, not between records).
    theta_max_over_alpha : ndarray
        Ground motion, per record [-] (+inf overturned).
    calibrations : dict
        Free-vibration record id -> FreeVibrationCalibration (or the error message).
    """

    energy_amplitude: np.ndarray
    energy_ratio: np.ndarray
    energy_sign: np.ndarray
    energy_record: np.ndarray
    half_cycle_amplitude: np.ndarray
    half_cycle_duration: np.ndarray
    flight_amplitude: np.ndarray
    flight_ratio: np.ndarray
    onset_sign: np.ndarray
    onset_ratio: np.ndarray
    withstood_pos: np.ndarray
    withstood_neg: np.ndarray
    excursions: tuple[int, int]
    tilt_theta: np.ndarray
    tilt_acc: np.ndarray
    theta_max_over_alpha: np.ndarray
    calibrations: dict = field(default_factory=dict)
    tilt_record: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))

    def tilt_line(self) -> tuple[Metric, Metric]:
        """The rotation before uplift against the ground acceleration, as a line: its offset [alpha] and its slope
        [alpha per g tan(alpha)], with standard errors clustered by record."""
        return line_fit(self.tilt_acc, self.tilt_theta, self.tilt_record)

    def metrics(self) -> dict[str, Metric]:
        """Every metric of :data:`METRICS` with its standard error."""
        out: dict[str, Metric] = {}
        c, amp = self.energy_ratio, self.energy_amplitude
        out["energy_ratio"] = mean_se(c)
        out["energy_ratio_trend"] = _slope_se(amp, c)
        out["energy_ratio_scatter"] = _scatter_se(amp, c)
        # a ratio of two noisy speeds: averaged in logarithms (no bias toward > 1), reported as a ratio
        lf = mean_se(np.log(self.flight_ratio[self.flight_ratio > 0]))
        out["flight_ratio"] = Metric(math.exp(lf.value), math.exp(lf.value) * lf.se, lf.n) if lf.n else lf
        out["flight_ratio_trend"] = _slope_se(self.flight_amplitude, self.flight_ratio)
        out["p"] = _pooled_p(self.calibrations)
        out["alternation"] = _alternation(c, self.energy_sign)
        for key, s in (("onset_pos", 1), ("onset_neg", -1)):
            v = self.onset_ratio[(self.onset_sign == s) & np.isfinite(self.onset_ratio)]
            out[key] = _median_se(v)
        out["withstood_pos"] = mean_se(self.withstood_pos)
        out["withstood_neg"] = mean_se(self.withstood_neg)
        out["first_uplift_pos"] = _share(
            int(np.count_nonzero(self.onset_sign > 0)), int(np.count_nonzero(self.onset_sign))
        )
        out["share_pos"] = _share(self.excursions[0], sum(self.excursions))
        out["tilt_offset"], out["tilt_slope"] = self.tilt_line()
        out["overturn_fraction"], out["theta_max_median"] = _theta_max_metrics(self.theta_max_over_alpha)
        out["onset_scatter"] = _spread_se(self.onset_ratio)
        return out


def _pooled_p(calibrations: Mapping[str, Any]) -> Metric:
    """Frequency parameter p [1/s] of the free-vibration calibrations, weighted by their inverse variances."""
    ps, pv = [], []
    for cal in calibrations.values():
        if isinstance(cal, FreeVibrationCalibration) and math.isfinite(cal.p_std) and cal.p_std > 0:
            ps.append(cal.p)
            pv.append(cal.p_std**2)
    if not ps:
        return Metric(math.nan, math.nan, 0)
    w = 1.0 / np.asarray(pv)
    return Metric(float(np.sum(w * ps) / np.sum(w)), float(math.sqrt(1.0 / np.sum(w))), len(ps))


def _alternation(c: np.ndarray, sign: np.ndarray) -> Metric:
    """ln c of the impacts ending theta > 0 minus those ending theta < 0 [-] (c the energy ratios)."""
    lc = np.log(np.clip(c, 1e-6, None))
    a, b = lc[sign > 0], lc[sign < 0]
    if a.size < 2 or b.size < 2:
        return Metric(math.nan, math.nan, 0)
    return Metric(
        float(a.mean() - b.mean()),
        float(math.sqrt(a.var(ddof=1) / a.size + b.var(ddof=1) / b.size)),
        int(a.size + b.size),
    )


def _theta_max_metrics(tm: np.ndarray) -> tuple[Metric, Metric]:
    """Overturn fraction [-] and median theta_max/alpha [-] of the ground-motion records (+inf overturned)."""
    if not tm.size:
        return Metric(math.nan, math.nan, 0), Metric(math.nan, math.nan, 0)
    frac = _share(int(np.count_nonzero(np.isinf(tm))), tm.size)
    med = float(np.median(np.where(np.isinf(tm), 1e9, tm)))
    # standard error of a median from the order statistics around it (binomial, ~1 sigma)
    srt = np.sort(np.where(np.isinf(tm), 1e9, tm))
    j = max(1, int(round(math.sqrt(tm.size) / 2)))
    m = tm.size // 2
    lo, hi = srt[max(m - j, 0)], srt[min(m + j, tm.size - 1)]
    se = 0.5 * (hi - lo) if hi < 1e9 else math.inf
    return frac, Metric(math.inf if med >= 1e9 else med, se, tm.size)


def mean_se(v: np.ndarray) -> Metric:
    """Mean of the finite values of ``v`` with its standard error (NaN when there are fewer than two)."""
    v = np.asarray(v, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return Metric(math.nan, math.nan, 0)
    if v.size == 1:
        return Metric(float(v[0]), math.nan, 1)
    return Metric(float(v.mean()), float(v.std(ddof=1) / math.sqrt(v.size)), int(v.size))


def _spread_se(v: np.ndarray) -> Metric:
    """Robust standard deviation of the finite values of ``v`` (1.4826 x the median absolute deviation),
    with the large-sample standard error of that estimator, 1.1664 s / sqrt(n) (Rousseeuw & Croux 1993:
    37 % efficiency at the normal); robust, because a record or two whose first uplift is misread would
    otherwise decide it."""
    v = np.asarray(v, dtype=float)
    v = v[np.isfinite(v)]
    if v.size < 5:
        return Metric(math.nan, math.nan, int(v.size))
    s = 1.4826 * float(np.median(np.abs(v - np.median(v))))
    return Metric(s, 1.1664 * s / math.sqrt(v.size), int(v.size))


def _share(k: int, n: int) -> Metric:
    """A share k/n with its binomial standard error (never 0: at least that of one count in n)."""
    if n == 0:
        return Metric(math.nan, math.nan, 0)
    pr = k / n
    return Metric(pr, math.sqrt(max(pr * (1.0 - pr), 1.0 / n) / n), n)


def _median_se(v: np.ndarray) -> Metric:
    v = np.asarray(v, dtype=float)
    if v.size == 0:
        return Metric(math.nan, math.nan, 0)
    if v.size == 1:
        return Metric(float(v[0]), math.nan, 1)
    # large-sample standard error of a median, 1.2533 s / sqrt(n) for a near-normal spread
    return Metric(float(np.median(v)), float(1.2533 * v.std(ddof=1) / math.sqrt(v.size)), int(v.size))


def _slope_se(x: np.ndarray, y: np.ndarray) -> Metric:
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = np.asarray(x)[ok], np.asarray(y)[ok]
    if x.size < 4 or np.ptp(x) == 0:
        return Metric(math.nan, math.nan, int(x.size))
    A = np.column_stack((np.ones_like(x), x))
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    res = y - A @ coef
    s2 = float(res @ res) / (x.size - 2)
    cov = s2 * np.linalg.inv(A.T @ A)
    return Metric(float(coef[1]), float(math.sqrt(max(cov[1, 1], 0.0))), int(x.size))


def _scatter_se(x: np.ndarray, y: np.ndarray) -> Metric:
    """Standard deviation of y about its straight-line fit on x, with the standard error of a normal sample's s.

    Model and measurement are observed through the same sensor noise (see
    :func:`housner.scenarios.diagnosis.comparison.record_comparison.compare`), so the noise's share of the scatter is
    the same on both
    sides and a difference is impact-to-impact physics.
    """
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = np.asarray(x)[ok], np.asarray(y)[ok]
    if x.size < 5:
        return Metric(math.nan, math.nan, int(x.size))
    A = np.column_stack((np.ones_like(x), x))
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    res = y - A @ coef
    s = math.sqrt(float(res @ res) / (x.size - 2))
    return Metric(s, s / math.sqrt(2.0 * (x.size - 2)), int(x.size))


def line_fit(x: np.ndarray, y: np.ndarray, groups: np.ndarray | None = None) -> tuple[Metric, Metric]:
    """Least-squares line y = a + b x: (a, b) with standard errors; clustered by ``groups`` (the record of each
    sample) when there are enough of them: the sandwich (A'A)^-1 (sum_g A_g' r_g r_g' A_g) (A'A)^-1 with the
    small-sample factor G / (G - 1), which holds whatever the correlation within a record (a sensor's noise
    that wanders, a hum) and reduces to the plain one for independent samples."""
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = np.asarray(x)[ok], np.asarray(y)[ok]
    g = None if groups is None or np.size(groups) != ok.size else np.asarray(groups)[ok]
    if x.size < 4:
        nan = Metric(math.nan, math.nan, int(x.size))
        return nan, nan
    A = np.column_stack((np.ones_like(x), x))
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    res = y - A @ coef
    try:
        inv = np.linalg.inv(A.T @ A)
        labels = np.unique(g) if g is not None else np.zeros(0)
        if labels.size >= MIN_CLUSTERS:
            meat = np.zeros((2, 2))
            for lab in labels:
                u = A[g == lab].T @ res[g == lab]
                meat += np.outer(u, u)
            cov = labels.size / (labels.size - 1) * inv @ meat @ inv
        else:
            # the pooled samples are thinned to every 5th, which leaves white noise close to independent
            cov = float(res @ res) / max(x.size - 2, 1) * inv
    except np.linalg.LinAlgError:
        cov = np.full((2, 2), np.nan)
    return (
        Metric(float(coef[0]), float(math.sqrt(max(cov[0, 0], 0.0))), int(x.size)),
        Metric(float(coef[1]), float(math.sqrt(max(cov[1, 1], 0.0))), int(x.size)),
    )


def _crossing_speed(t, theta, tc: float, side: int, amp: float, sign: int) -> float:
    """|theta'| at an impact at time tc [rad/s] from a quadratic through (tc, 0) fitted on one side.

    ``side`` +1 uses the samples after tc (the opening of a half-cycle), -1 those before it (the
    closing), as long as sign*theta stays between 0 and :data:`FLIGHT_BAND` of the amplitude.
    The cubic term of the trajectory biases the slope by ~p^2 tau^2 / 6, the same at both ends of
    a conservative half-cycle (time-reversal symmetry), so the ratio of the two is unbiased.
    """
    j = int(np.searchsorted(t, tc)) - (1 if side < 0 else 0)
    idx = []
    while 0 <= j < t.size and 0.0 < sign * theta[j] < FLIGHT_BAND * amp:
        idx.append(j)
        j += side
    if len(idx) < 4:
        return math.nan
    idx = np.asarray(idx)
    tau = t[idx] - tc
    A = np.column_stack((tau, tau * tau))
    coef, *_ = np.linalg.lstsq(A, theta[idx], rcond=None)
    return abs(float(coef[0]))


def _fv_features(t, theta, alpha: float, noise: float):
    """Calibration and per-impact / per-half-cycle quantities of one free-vibration history."""
    cal = calibrate_free_vibration(t, theta, alpha, noise=noise, min_amplitude=FV_FLOOR_SIGMAS * noise)
    pk = cal.peaks
    amp = pk.amplitude
    keep = amp[:-1] > FV_MIN_SIGMAS * noise
    e_amp = amp[:-1][keep] / alpha
    e_c = cal.c[keep]
    e_s = pk.sign[:-1][keep]
    hk = cal.half_cycle_amplitude > FV_MIN_SIGMAS * noise
    h_amp = cal.half_cycle_amplitude[hk] / alpha
    h_dur = cal.half_cycle_duration[hk]
    f_amp, f_ratio = [], []
    for i in range(len(pk)):
        if not (math.isfinite(pk.t_start[i]) and math.isfinite(pk.t_end[i])) or amp[i] < FLIGHT_MIN_SIGMAS * noise:
            continue
        s = int(pk.sign[i])
        v0 = _crossing_speed(t, theta, pk.t_start[i], +1, amp[i], s)
        v1 = _crossing_speed(t, theta, pk.t_end[i], -1, amp[i], s)
        if math.isfinite(v0) and math.isfinite(v1) and v0 > 0 and v1 > 0:
            f_amp.append(amp[i] / alpha)
            f_ratio.append((v1 / v0) ** 2)
    return cal, (e_amp, e_c, e_s), (h_amp, h_dur), (np.asarray(f_amp), np.asarray(f_ratio))


def _smooth(x: np.ndarray, k: int) -> np.ndarray:
    """Centred moving average over k samples; the k // 2 samples at each end (no full window) are 0."""
    out = np.zeros_like(x)
    if x.size < k:
        return out
    c = np.concatenate(([0.0], np.cumsum(x)))
    h = k // 2
    out[h : x.size - h] = (c[k:] - c[:-k]) / k
    return out


def _gm_features(theta, acc, smooth_sd: float, alpha: float, tan_alpha: float, margin: int):
    """First uplift of one record: detection sample, direction, onset ratio [-] and the rest baseline [rad].

    The baseline is the median theta before |ug''| first exceeds half the uplift threshold (the block
    is surely at rest then); the block is seen to move where theta, averaged over 9 samples, leaves
    it by 5 of the average's noise sigmas (plus 1e-3 alpha for a noise-free model). ``smooth_sd`` is that
    average's noise sigma [rad]: sigma / 3 for white noise, up to sigma for noise that wanders slowly
    (:meth:`housner.scenarios.campaigns.sensor_noise.SensorNoise.mean_sd`).
    """
    gta = G * tan_alpha
    n = theta.size
    quiet = np.flatnonzero(np.abs(acc) > 0.5 * gta)
    k_quiet = int(quiet[0]) if quiet.size else n
    base = float(np.median(theta[:k_quiet])) if k_quiet >= 10 else 0.0
    sm = _smooth(theta - base, UPLIFT_SMOOTH)
    h = UPLIFT_SIGMAS * smooth_sd + 1e-3 * alpha
    moved = np.flatnonzero(np.abs(sm) > h)
    if moved.size:
        kd = int(moved[0])
        s = 1 if sm[kd] > 0 else -1
        onset = float(np.max(-s * acc[: kd + 1])) / gta
    else:
        kd, s, onset = n, 0, math.nan
    k_rest = kd - margin if kd < n else n
    if k_rest > 0:
        stood = (float(np.max(-acc[:k_rest])) / gta, float(np.max(acc[:k_rest])) / gta)
    else:
        stood = (math.nan, math.nan)
    return kd, s, onset, base, stood


def features(
    campaign: Campaign,
    histories: Mapping[str, np.ndarray] | None = None,
    overturned: Mapping[str, bool] | None = None,
    theta_max: Mapping[str, float] | None = None,
) -> Features:
    """Localisation quantities of the measurement (no ``histories``) or of a model.

    Parameters
    ----------
    campaign : Campaign
    histories : mapping, optional
        Record id -> model theta on the record's samples [rad]; records not
        in it are left out. None: the measured theta of every record.
    overturned, theta_max : mapping, optional
        Record id -> the model's overturn verdict and theta_max [rad]
        (default: from the histories).

    Notes
    -----
    Every quantity is computed the same way for the measurement and the
    model, with the measurement's noise level for the thresholds, so that a
    difference between the two is a difference of the physics.

    The analysis of a free-vibration history (its calibration, energy ratios, half-cycles) is derived
    once per campaign: a history analysed before (the measurement, or a model's that another
    comparison or the diagnosis' free-vibration check observed the same way) is taken from the
    campaign's cache, keyed by its samples.
    """
    pool = _Pool(campaign.specimen.alpha, campaign.specimen.tan_alpha, _fv_cache(campaign))
    for position, rec in enumerate(campaign.records):
        if histories is None:
            th = rec.theta
        elif rec.id in histories:
            th = np.asarray(histories[rec.id], dtype=float)
        else:
            continue
        if rec.kind == "free_vibration":
            pool.add_free_vibration(rec, th, position)
            continue
        if histories is None:
            over = rec.overturned
            tmax = rec.theta_max
        else:
            over = bool(overturned[rec.id]) if overturned is not None else bool(np.max(np.abs(th)) >= 0.99 * np.pi / 2)
            tmax = float(theta_max[rec.id]) if theta_max is not None else float(np.max(np.abs(th)))
        pool.add_ground_motion(rec, th, over, tmax)
    return pool.features()


def _fv_cache(campaign: Campaign) -> dict | None:
    """The campaign's free-vibration analyses, (record id, noise, alpha, digest of the history) -> the result of
    :func:`_fv_features` or its error message (None for an object without a cache)."""
    cache = getattr(campaign, "_cache", None)
    return None if cache is None else cache.setdefault("fv_analyses", {})


def measured_features(campaign: Campaign) -> Features:
    """:func:`features` of the measurement, computed once per campaign (kept in its cache)."""
    key = "measured_features"
    if key not in campaign._cache:
        campaign._cache[key] = features(campaign)
    return campaign._cache[key]


class _Pool:
    """The quantities of :func:`features`, pooled record by record (alpha [rad], tan(alpha) [-])."""

    def __init__(self, alpha: float, tan_alpha: float, fv_cache: dict | None = None):
        self.alpha, self.tan_alpha = alpha, tan_alpha
        self.fv_cache = fv_cache
        self.e_amp, self.e_c, self.e_s, self.h_amp, self.h_dur, self.f_amp, self.f_rat = ([] for _ in range(7))
        self.e_rec: list[np.ndarray] = []
        self.cals: dict[str, Any] = {}
        self.on_s, self.on_r, self.tm, self.st_p, self.st_n = [], [], [], [], []
        self.npos = self.nneg = 0
        self.tilt_th, self.tilt_acc, self.tilt_rec = [], [], []

    def add_free_vibration(self, rec: MeasuredRecord, th: np.ndarray, position: int = 0) -> None:
        """Calibration, energy ratios, half-cycles and energy kept between impacts of one free vibration."""
        got = self._fv_analysis(rec, th)
        if isinstance(got, str):
            self.cals[rec.id] = got
            return
        cal, (a1, c1, s1), (ha, hd), (fa, fr) = got
        self.cals[rec.id] = cal
        self.e_amp.append(a1)
        self.e_c.append(c1)
        self.e_s.append(s1)
        self.e_rec.append(np.full(np.size(c1), position))
        self.h_amp.append(ha)
        self.h_dur.append(hd)
        self.f_amp.append(fa)
        self.f_rat.append(fr)

    def _fv_analysis(self, rec: MeasuredRecord, th: np.ndarray):
        """:func:`_fv_features` of one free-vibration history, or its error message; from the cache when it holds
        the same history of the same record."""
        if self.fv_cache is None:
            key = None
        else:
            digest = hashlib.blake2b(np.ascontiguousarray(th, dtype=float).tobytes(), digest_size=16).digest()
            key = (rec.id, float(rec.noise), float(self.alpha), th.size, digest)
            if key in self.fv_cache:
                return self.fv_cache[key]
        try:
            got = _fv_features(rec.t, th, self.alpha, rec.noise)
        except ValueError as e:
            got = str(e)
        if key is not None:
            self.fv_cache[key] = got
            while len(self.fv_cache) > FV_CACHE_SIZE:
                del self.fv_cache[next(iter(self.fv_cache))]
        return got

    def add_ground_motion(self, rec: MeasuredRecord, th: np.ndarray, over: bool, tmax: float) -> None:
        """Uplift, tilt before it, excursions and peak of one ground motion (``tmax`` [rad])."""
        alpha = self.alpha
        gta = G * self.tan_alpha
        acc = rec.motion.acc
        margin = int(round(UPLIFT_MARGIN / rec.dt))
        smooth_sd = rec.noise_model.mean_sd(rec.noise, UPLIFT_SMOOTH)
        kd, s, onset, base, stood = _gm_features(th, acc, smooth_sd, alpha, self.tan_alpha, margin)
        self.on_s.append(s)
        self.on_r.append(onset)
        self.st_p.append(stood[0])
        self.st_n.append(stood[1])
        k_pre = kd - margin if kd < th.size else th.size
        if k_pre > 0:
            sel = np.flatnonzero(np.abs(acc[:k_pre]) < gta)[::5]
            self.tilt_th.append(th[sel] / alpha)
            self.tilt_acc.append(acc[sel] / gta)
            self.tilt_rec.append(np.full(sel.size, len(self.tilt_rec)))
        imp = measured_impacts(th - base, rec.noise)
        if kd < th.size:
            # excursions: the one that starts at uplift and one after each impact
            first = 1 if s > 0 else -1
            signs = first * (-1) ** np.arange(imp.size + 1)
            self.npos += int(np.count_nonzero(signs > 0))
            self.nneg += int(np.count_nonzero(signs < 0))
        self.tm.append(math.inf if over else tmax / alpha)

    def features(self) -> Features:
        def cat(parts, dtype=float):
            return np.concatenate(parts).astype(dtype) if parts else np.empty(0, dtype=dtype)

        return Features(
            energy_amplitude=cat(self.e_amp),
            energy_ratio=cat(self.e_c),
            energy_sign=cat(self.e_s, int),
            energy_record=cat(self.e_rec, int),
            half_cycle_amplitude=cat(self.h_amp),
            half_cycle_duration=cat(self.h_dur),
            flight_amplitude=cat(self.f_amp),
            flight_ratio=cat(self.f_rat),
            onset_sign=np.asarray(self.on_s, dtype=int),
            onset_ratio=np.asarray(self.on_r, dtype=float),
            withstood_pos=np.asarray(self.st_p, dtype=float),
            withstood_neg=np.asarray(self.st_n, dtype=float),
            excursions=(self.npos, self.nneg),
            tilt_theta=cat(self.tilt_th),
            tilt_acc=cat(self.tilt_acc),
            theta_max_over_alpha=np.asarray(self.tm, dtype=float),
            calibrations=self.cals,
            tilt_record=np.concatenate(self.tilt_rec).astype(int) if self.tilt_rec else np.zeros(0, dtype=int),
        )
