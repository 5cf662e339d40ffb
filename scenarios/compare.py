"""Model against measurement: record by record, as distributions, and where the model fails.

:func:`compare` runs an engine (with physical effects, on the analytic
engine) on every record of a :class:`scenarios.campaign.Campaign`, driven by
the measured ground acceleration (a free-vibration record is released at its
measured initial angle), and compares the simulated rotation with the
measured one.

Per record
----------
*Time-history error.* Rocking is chaotic: after a few impacts two histories
that start together part ways for reasons that no model parameter explains,
so the error is taken over the part of the record before that happens, fixed
by the measurement alone (the same window for every model, so that errors of
two models are paired and comparable)::

    e = sqrt( mean_{t_k <= t_end} min(|theta_model(t_k) - theta_meas(t_k)| / alpha, 1)^2 )   [-]

where t_end is, for a ground-motion record, the earliest of the
``window_impacts``-th measured impact (6 by default), the moment the
measured block passes alpha on its way to overturning, and the end of the
record; for a free-vibration record the ``window_impacts_fv``-th impact
(20) or the impact after which the measured amplitude falls below 10 noise
sigmas. Impacts are zero crossings of the measured theta detected with a
hysteresis of 4 noise sigmas (noise never makes a spurious one). The clip at
1 (alpha) keeps one record where model and measurement overturn differently
from drowning the others. A perfect model scores the noise alone,
sigma/alpha (0.0054 for 0.8 mrad on the seed specimen): :attr:`Comparison.noise_floor`.

*Divergence time.* The first time |theta_model - theta_meas| exceeds
5 sigma + 0.05 alpha for 50 ms in a row (NaN if never): how long the model
follows the measurement.

*Peak and verdict.* theta_max/alpha of model and measurement (+inf when
overturned; the measured block has overturned when |theta| reached
:data:`scenarios.campaign.OVERTURN_ANGLE` or the campaign says so).

*The model seen through the sensor.* A measured peak carries the noise (the
largest of many noisy samples lies ~2-3 sigma above the true peak, which
matters for records that barely rock), and noisy free-vibration peaks bias
the energy ratios a little. So that such biases cancel, the model's history
is observed through the same sensor before peaks, distributions and
localisation quantities are taken from it: Gaussian noise of the record's
sigma is added (seeded, :data:`OBSERVATION_SEED`). The time-history error
uses the model's own history.

As distributions (ground-motion records)
----------------------------------------
The statistics of :mod:`housner.stats`: Kolmogorov-Smirnov distance and
p-value, Wasserstein distance, overturn probability with a Wilson interval
for each side, percentiles with bootstrap intervals, record-by-record
agreement.

Where the model fails (localisation)
------------------------------------
The same quantities are computed from the measurement and from the model
(:class:`Features`), each with its standard error, so that the report shows
them side by side (:data:`METRICS`): energy ratio per impact against
amplitude (seed eq. 8) and its trend; half-cycle duration against amplitude
(p of seed eq. 7, exact form); energy kept between impacts; alternation of
the free-vibration energy ratios (asymmetry); uplift onset per direction;
share of excursions toward +theta; rotation before uplift; overturn fraction;
theta_max distribution.

References
----------
Housner, G. W. (1963). The behavior of inverted pendulum structures during
earthquakes. BSSA 53(2), 403-417.
Bachmann, J. A., Strand, M., Vassiliou, M. F., Broccardo, M., Stojadinovic, B.
(2017). Probabilistic validation of the Housner rocking model. COMPDYN 2017,
eqs. 2, 7, 8; Figs. 9-10; Table 2.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from housner import stats
from housner.calibration import FreeVibrationCalibration, calibrate_free_vibration
from housner.impacts import HYSTERESIS_SIGMAS, noise_crossings
from housner.response import Response
from housner.units import G
from scenarios.campaign import Campaign, MeasuredRecord

__all__ = [
    "DIVERGENCE_SUSTAIN",
    "METRICS",
    "WINDOW_IMPACTS",
    "WINDOW_IMPACTS_FV",
    "Comparison",
    "DistributionComparison",
    "Features",
    "Metric",
    "RecordComparison",
    "compare",
    "divergence_time",
    "error_window",
    "features",
    "measured_impacts",
    "record_error",
    "resolve_effects",
    "simulate_records",
]

#: Measured impacts in the error window of a ground-motion record [-]. Six impacts are about
#: three rocking cycles: long enough for every effect of the library to show (uplift thresholds,
#: impact losses, timing), short enough that a model with fitted (not exact) parameters has
#: mostly not yet parted from the measurement by chaos. (The exact model and an independent
#: integrator of the same physics stay within ~0.006 alpha over whole 6 s records.)
WINDOW_IMPACTS = 6
#: Free vibration is not chaotic; its window runs over up to this many impacts [-] (from 0.8 alpha
#: with r = 0.95 that is down to ~0.3 alpha: p and r are pinned long before).
WINDOW_IMPACTS_FV = 20
#: Per-sample error clip [alpha].
ERROR_CLIP = 1.0
#: Divergence: |delta theta| > DIVERGENCE_SIGMAS sigma + DIVERGENCE_ALPHA alpha for DIVERGENCE_SUSTAIN s.
DIVERGENCE_SIGMAS = 5.0
DIVERGENCE_ALPHA = 0.05
DIVERGENCE_SUSTAIN = 0.05
#: Free-vibration half-cycles below this many noise sigmas are left out of the localisation (their
#: peaks and slopes are known to worse than ~5 %).
FV_MIN_SIGMAS = 20.0
#: Free-vibration analyses stop at this many noise sigmas (the calibration's floor).
FV_FLOOR_SIGMAS = 10.0
#: Energy kept between impacts: the speeds at the two impacts of a half-cycle are fitted on the
#: samples within this fraction of its amplitude, for half-cycles above FLIGHT_MIN_SIGMAS noise
#: sigmas (at 0.8 mrad the squared speed ratio then scatters by ~0.13 per half-cycle).
FLIGHT_BAND = 0.6
FLIGHT_MIN_SIGMAS = 40.0
#: Uplift detection: theta, averaged over this many samples, leaves rest by 5 of its sigmas.
UPLIFT_SMOOTH = 9
UPLIFT_SIGMAS = 5.0
#: Samples closer than this to the detected uplift do not count as "before uplift" [s].
UPLIFT_MARGIN = 0.05


# ----------------------------------------------------------------------------
# effects and simulation
def resolve_effects(effects: Iterable[Any], specimen=None) -> tuple:
    """Effects from Effect instances, registry names or ``{"name": ..., param: value}`` dicts."""
    from housner.effects import make_effects

    out = make_effects(list(effects or ()))
    if specimen is not None:
        for e in out:
            e.check(specimen)
    return out


def simulate_records(
    specimen, records: Sequence[MeasuredRecord], engine: Any = "housner", effects: Sequence[Any] = (),
    engine_settings: Mapping[str, Any] | None = None,
) -> list[Response | str]:  # fmt: skip
    """Run an engine on the measured records (whole record in, whole response out).

    Parameters
    ----------
    specimen : Specimen
    records : sequence of MeasuredRecord
        Each is driven by its measured ground acceleration and released from
        its ``motion.theta0`` [rad].
    engine : str or Engine
        Registry name (``housner``, ``mujoco``, ``pybullet``, ...) or an engine.
    effects : sequence
        Effects (instances, names or dicts); only the analytic engine realises them.
    engine_settings : mapping, optional
        Settings when ``engine`` is a name.

    Returns
    -------
    list
        One :class:`housner.Response` per record, or the error message of a
        record the engine failed on.

    Raises
    ------
    ValueError
        An effect the engine does not realise (named), or an unknown effect.

    Notes
    -----
    The engine's ``simulate_many`` runs them (the analytic engine batches the
    records whose effects keep Housner's equation of motion, with the same
    responses as one call per record); free-vibration records and the others
    go in two calls, the former without the effects a free vibration cannot show.
    """
    from engines.base import Engine, get_engine

    eng = engine if isinstance(engine, Engine) else get_engine(engine, **dict(engine_settings or {}))
    effects = resolve_effects(effects, specimen)
    refused = [e.name for e in effects if e.name not in eng.effects_supported]
    if refused:
        supported = ", ".join(sorted(eng.effects_supported)) or "none"
        raise ValueError(
            f"engine {eng.name!r} cannot realise effect(s) {', '.join(map(repr, refused))} (it realises: "
            f"{supported}); compare effects on the analytic engine, 'housner'"
        )
    # an effect a free vibration cannot show (its time axis starts at its own release) is left out there
    fv_effects = tuple(e for e in effects if type(e).seen_in_free_vibration)
    out: list[Response | str] = [""] * len(records)
    for kind_effects, idx in (
        (fv_effects, [i for i, r in enumerate(records) if r.kind == "free_vibration"]),
        (effects, [i for i, r in enumerate(records) if r.kind != "free_vibration"]),
    ):
        if not idx:
            continue
        res = eng.simulate_many(specimen, [records[i].motion for i in idx], kind_effects, errors="return")
        for i, r in zip(idx, res, strict=True):
            out[i] = r if isinstance(r, Response) else f"{type(r).__name__}: {r}"
    return out


# ----------------------------------------------------------------------------
# time-history error
def measured_impacts(theta, noise: float) -> np.ndarray:
    """Indices of the measured impacts: zero crossings of theta with a hysteresis of 4 noise sigmas.

    :func:`housner.impacts.noise_crossings`, the detector the free-vibration
    calibration uses too.

    Parameters
    ----------
    theta : array_like
        Rotation [rad].
    noise : float
        Noise standard deviation [rad].

    Returns
    -------
    ndarray of int
        For each crossing, the first sample beyond the band on the new side.
    """
    return noise_crossings(theta, noise)


def error_window(record: MeasuredRecord, alpha: float, window_impacts: int | None = None) -> int:
    """Number of samples (from the start) over which the time-history error of ``record`` is taken.

    See the module docstring: up to the ``window_impacts``-th measured
    impact, the measured block passing alpha, or the end (ground motion); up
    to the ``window_impacts``-th impact or the last one above 10 noise sigmas
    (free vibration).
    """
    th = record.theta
    n = th.size
    imp = measured_impacts(th, record.noise)
    if record.kind == "free_vibration":
        k_imp = WINDOW_IMPACTS_FV if window_impacts is None else window_impacts
        floor = FV_FLOOR_SIGMAS * record.noise
        bounds = np.concatenate(([0], imp, [n]))
        end = n
        for j in range(imp.size):
            nxt = np.max(np.abs(th[bounds[j + 1] : bounds[j + 2]]))
            if j + 1 >= k_imp or nxt < floor:
                end = int(imp[j]) + 1
                break
        return max(end, 2)
    k_imp = WINDOW_IMPACTS if window_impacts is None else window_impacts
    end = n
    if imp.size >= k_imp:
        end = int(imp[k_imp - 1]) + 1
    past = np.flatnonzero(np.abs(th) > alpha + HYSTERESIS_SIGMAS * record.noise)
    if past.size:
        end = min(end, int(past[0]) + 1)
    return max(end, 2)


def record_error(
    theta_model, theta_measured, end: int, alpha: float, *, align: int = 0, sensitivity=None, max_dtheta0: float = 0.0
) -> float:
    """RMS of min(|theta_model - theta_measured| / alpha, 1) over the first ``end`` samples [-].

    ``align`` > 0 (a free vibration): the release instant and angle are nuisance parameters,
    :func:`release_error`.
    """
    if align > 0:
        return release_error(theta_model, theta_measured, end, alpha, align, sensitivity, max_dtheta0)
    d = np.abs(np.asarray(theta_model[:end]) - np.asarray(theta_measured[:end])) / alpha
    np.minimum(d, ERROR_CLIP, out=d)
    return float(math.sqrt(float(np.mean(d * d))))


def release_error(theta_model, theta_measured, end: int, alpha: float, max_shift: int, sensitivity=None,
                  max_dtheta0: float = 0.0) -> float:  # fmt: skip
    """:func:`record_error` of a free vibration, minimised over its release instant and angle [-].

    A free-vibration record's time axis starts at the release its own theta channel shows and its
    initial angle is fitted there (:func:`scenarios.campaign.estimate_release`). Near the release
    theta falls only as c (t - t_r)^2, so with 0.8 mrad noise the instant is known to about +-20 ms,
    and a hold too short to be told from the fall (measured on the seed specimen: 10 samples, half of
    the time) biases the angle by 0.3-0.45 noise sigmas; either alone costs 2-5 noise sigmas of error
    over the window. Both are nuisance parameters of the measurement, not physics: the model is
    shifted by s samples, |s| <= ``max_shift`` (every whole sample, then the vertex of the parabola
    through the best and its neighbours), its release angle changed by d, |d| <= ``max_dtheta0`` [rad],
    to first order through ``sensitivity`` = d theta / d theta0 on the model's grid (least squares for
    d at each shift), and the smallest error counts.
    """
    m = np.asarray(theta_model, dtype=float)
    g = None if sensitivity is None or max_dtheta0 <= 0 else np.asarray(sensitivity, dtype=float)
    y = np.asarray(theta_measured[:end], dtype=float)
    n, k = y.size, int(max_shift)

    def pad(a: np.ndarray) -> np.ndarray:
        # a[j - s] for every shift s in [-k, k]: held at its first value before it starts and at its
        # last beyond its end
        tail = max(0, n + k - a.size)
        return np.concatenate((np.full(k, a[0]), a[: n + k], np.full(tail, a[-1])))

    def errors(rows_m: np.ndarray, rows_g: np.ndarray | None) -> np.ndarray:
        r = y - rows_m
        if rows_g is not None:
            gg = np.einsum("ij,ij->i", rows_g, rows_g)
            d = np.where(gg > 0, np.einsum("ij,ij->i", r, rows_g) / np.where(gg > 0, gg, 1.0), 0.0)
            r = r - np.clip(d, -max_dtheta0, max_dtheta0)[:, None] * rows_g
        e = np.minimum(np.abs(r) / alpha, ERROR_CLIP)
        return np.sqrt(np.mean(e * e, axis=1))

    # whole-sample shifts at once: row i is the model delayed by s = k - i samples
    win_m = np.lib.stride_tricks.sliding_window_view(pad(m), n)
    win_g = None if g is None else np.lib.stride_tricks.sliding_window_view(pad(g), n)
    vals = errors(win_m, win_g)
    b = int(np.argmin(vals))
    best = float(vals[b])
    if 0 < b < vals.size - 1:
        # a fraction of a sample: the vertex of the parabola through the best shift and its neighbours
        den = vals[b - 1] - 2 * vals[b] + vals[b + 1]
        if den > 0:
            frac = 0.5 * (vals[b - 1] - vals[b + 1]) / den  # in rows, |frac| <= 1/2
            shift = (k - b) - frac
            idx = np.arange(n, dtype=float) - shift
            grid = np.arange(m.size, dtype=float)
            rm = np.interp(idx, grid, m)[None, :]
            rg = None if g is None else np.interp(idx, grid, g)[None, :]
            best = min(best, float(errors(rm, rg)[0]))
    return best


#: Largest shift of the release instant of a free vibration tried by the error [s] (release_error):
#: twice the +-20 ms to which the instant is known.
RELEASE_SHIFT = 0.05
#: Largest change of a free vibration's release angle tried by the error [noise sigmas]: about twice
#: the bias an undetected short hold leaves (0.3-0.45 sigma), five times the fit's standard error.
RELEASE_DTHETA0_SIGMAS = 1.0


def release_shift_samples(rec: MeasuredRecord) -> int:
    """Samples a free-vibration record's model may be shifted by (0 for a ground motion)."""
    if rec.kind != "free_vibration":
        return 0
    return max(1, int(round(RELEASE_SHIFT / rec.dt)))


def release_sensitivities(specimen, records: Sequence[MeasuredRecord], responses: Sequence[Response | str],
                          engine: Any = "housner", effects: Sequence[Any] = (),
                          engine_settings: Mapping[str, Any] | None = None) -> list[np.ndarray | None]:  # fmt: skip
    """d theta / d theta0 on each free-vibration record's grid (finite difference; None elsewhere).

    One more run of each free-vibration record, released RELEASE_DTHETA0_SIGMAS / 2 noise sigmas
    further from rest.
    """
    from dataclasses import replace

    out: list[np.ndarray | None] = [None] * len(records)
    fv = [i for i, rec in enumerate(records) if rec.kind == "free_vibration" and isinstance(responses[i], Response)]
    if not fv:
        return out
    eps = [math.copysign(0.5 * RELEASE_DTHETA0_SIGMAS * max(records[i].noise, 1e-9), records[i].motion.theta0)
           for i in fv]  # fmt: skip
    bumped = [replace(records[i], motion=replace(records[i].motion, theta0=records[i].motion.theta0 + e))
              for i, e in zip(fv, eps, strict=True)]  # fmt: skip
    res = simulate_records(specimen, bumped, engine, effects, engine_settings)
    for i, e, r, rec in zip(fv, eps, res, bumped, strict=True):
        if isinstance(r, Response):
            out[i] = (_on_grid(r, rec) - _on_grid(responses[i], records[i])) / e
    return out


def scored_error(theta_model, rec: MeasuredRecord, end: int, alpha: float, sensitivity=None) -> float:
    """The time-history error of one record as the comparison and the diagnosis score it [-]."""
    return record_error(theta_model, rec.theta, end, alpha, align=release_shift_samples(rec), sensitivity=sensitivity,
                        max_dtheta0=RELEASE_DTHETA0_SIGMAS * rec.noise)  # fmt: skip


def divergence_time(theta_model, theta_measured, t, noise: float, alpha: float) -> float:
    """First time [s] at which |theta_model - theta_measured| exceeds 5 sigma + 0.05 alpha for 50 ms; NaN if never."""
    d = np.abs(np.asarray(theta_model) - np.asarray(theta_measured))
    thr = DIVERGENCE_SIGMAS * noise + DIVERGENCE_ALPHA * alpha
    over = (d > thr).astype(np.int64)
    dt = float(t[1] - t[0]) if len(t) > 1 else 1.0
    w = max(1, int(round(DIVERGENCE_SUSTAIN / dt)))
    if over.size < w:
        return math.nan
    c = np.concatenate(([0], np.cumsum(over)))
    run = c[w:] - c[:-w]
    k = np.flatnonzero(run == w)
    return float(t[k[0]]) if k.size else math.nan


# ----------------------------------------------------------------------------
# localisation
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
}


@dataclass(frozen=True, eq=False)
class Features:
    """The localisation quantities of one source (the measurement or a model).

    Attributes (arrays pool the records; amplitudes are over alpha)
    ----------------------------------------------------------------
    energy_amplitude, energy_ratio, energy_sign : ndarray
        Free vibration, per impact: amplitude before it [alpha], energy ratio
        c (seed eq. 8) [-], sign of theta in the half-cycle it ends.
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
        theta [alpha] and ug''/(g tan alpha) [-] (thinned to every 5th sample).
    theta_max_over_alpha : ndarray
        Ground motion, per record [-] (+inf overturned).
    calibrations : dict
        Free-vibration record id -> FreeVibrationCalibration (or the error message).
    """

    energy_amplitude: np.ndarray
    energy_ratio: np.ndarray
    energy_sign: np.ndarray
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

    def metrics(self) -> dict[str, Metric]:
        """Every metric of :data:`METRICS` with its standard error."""
        out: dict[str, Metric] = {}
        c, amp = self.energy_ratio, self.energy_amplitude
        out["energy_ratio"] = _mean_se(c)
        out["energy_ratio_trend"] = _slope_se(amp, c)
        out["energy_ratio_scatter"] = _scatter_se(amp, c)
        # a ratio of two noisy speeds: averaged in logarithms (no bias toward > 1), reported as a ratio
        lf = _mean_se(np.log(self.flight_ratio[self.flight_ratio > 0]))
        out["flight_ratio"] = Metric(math.exp(lf.value), math.exp(lf.value) * lf.se, lf.n) if lf.n else lf
        out["flight_ratio_trend"] = _slope_se(self.flight_amplitude, self.flight_ratio)
        ps, pv = [], []
        for cal in self.calibrations.values():
            if isinstance(cal, FreeVibrationCalibration) and math.isfinite(cal.p_std) and cal.p_std > 0:
                ps.append(cal.p)
                pv.append(cal.p_std**2)
        if ps:
            w = 1.0 / np.asarray(pv)
            out["p"] = Metric(float(np.sum(w * ps) / np.sum(w)), float(math.sqrt(1.0 / np.sum(w))), len(ps))
        else:
            out["p"] = Metric(math.nan, math.nan, 0)
        lc = np.log(np.clip(c, 1e-6, None))
        a, b = lc[self.energy_sign > 0], lc[self.energy_sign < 0]
        if a.size >= 2 and b.size >= 2:
            out["alternation"] = Metric(
                float(a.mean() - b.mean()),
                float(math.sqrt(a.var(ddof=1) / a.size + b.var(ddof=1) / b.size)),
                int(a.size + b.size),
            )
        else:
            out["alternation"] = Metric(math.nan, math.nan, 0)
        for key, s in (("onset_pos", 1), ("onset_neg", -1)):
            v = self.onset_ratio[(self.onset_sign == s) & np.isfinite(self.onset_ratio)]
            out[key] = _median_se(v)
        out["withstood_pos"] = _mean_se(self.withstood_pos)
        out["withstood_neg"] = _mean_se(self.withstood_neg)
        out["first_uplift_pos"] = _share(
            int(np.count_nonzero(self.onset_sign > 0)), int(np.count_nonzero(self.onset_sign))
        )
        out["share_pos"] = _share(self.excursions[0], sum(self.excursions))
        off, slope = _regression(self.tilt_acc, self.tilt_theta)
        out["tilt_offset"], out["tilt_slope"] = off, slope
        tm = self.theta_max_over_alpha
        if tm.size:
            out["overturn_fraction"] = _share(int(np.count_nonzero(np.isinf(tm))), tm.size)
            med = float(np.median(np.where(np.isinf(tm), 1e9, tm)))
            # standard error of a median from the order statistics around it (binomial, ~1 sigma)
            srt = np.sort(np.where(np.isinf(tm), 1e9, tm))
            j = max(1, int(round(math.sqrt(tm.size) / 2)))
            m = tm.size // 2
            lo, hi = srt[max(m - j, 0)], srt[min(m + j, tm.size - 1)]
            se = 0.5 * (hi - lo) if hi < 1e9 else math.inf
            out["theta_max_median"] = Metric(math.inf if med >= 1e9 else med, se, tm.size)
        else:
            out["overturn_fraction"] = Metric(math.nan, math.nan, 0)
            out["theta_max_median"] = Metric(math.nan, math.nan, 0)
        return out


def _mean_se(v: np.ndarray) -> Metric:
    v = np.asarray(v, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return Metric(math.nan, math.nan, 0)
    if v.size == 1:
        return Metric(float(v[0]), math.nan, 1)
    return Metric(float(v.mean()), float(v.std(ddof=1) / math.sqrt(v.size)), int(v.size))


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

    Model and measurement are observed through the same sensor noise (see :func:`compare`), so the
    noise's share of the scatter is the same on both sides and a difference is impact-to-impact physics.
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


def _regression(x: np.ndarray, y: np.ndarray) -> tuple[Metric, Metric]:
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = np.asarray(x)[ok], np.asarray(y)[ok]
    if x.size < 4:
        nan = Metric(math.nan, math.nan, int(x.size))
        return nan, nan
    A = np.column_stack((np.ones_like(x), x))
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    res = y - A @ coef
    s2 = float(res @ res) / max(x.size - 2, 1)
    try:
        cov = s2 * np.linalg.inv(A.T @ A)
    except np.linalg.LinAlgError:
        cov = np.full((2, 2), np.nan)
    # the pooled samples are thinned to every 5th, which leaves them close to independent
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


def _gm_features(theta, acc, noise: float, alpha: float, tan_alpha: float, margin: int):
    """First uplift of one record: detection sample, direction, onset ratio [-] and the rest baseline [rad].

    The baseline is the median theta before |ug''| first exceeds half the uplift threshold (the block
    is surely at rest then); the block is seen to move where theta, averaged over 9 samples, leaves
    it by 5 of the average's noise sigmas (plus 1e-3 alpha for a noise-free model).
    """
    gta = G * tan_alpha
    n = theta.size
    quiet = np.flatnonzero(np.abs(acc) > 0.5 * gta)
    k_quiet = int(quiet[0]) if quiet.size else n
    base = float(np.median(theta[:k_quiet])) if k_quiet >= 10 else 0.0
    sm = _smooth(theta - base, UPLIFT_SMOOTH)
    h = UPLIFT_SIGMAS * noise / math.sqrt(UPLIFT_SMOOTH) + 1e-3 * alpha
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
    """
    alpha = campaign.specimen.alpha
    tan_a = campaign.specimen.tan_alpha
    gta = G * tan_a
    e_amp, e_c, e_s, h_amp, h_dur, f_amp, f_rat = ([] for _ in range(7))
    cals: dict[str, Any] = {}
    on_s, on_r, tm, st_p, st_n = [], [], [], [], []
    npos = nneg = 0
    tilt_th, tilt_acc = [], []
    for rec in campaign.records:
        if histories is None:
            th = rec.theta
        elif rec.id in histories:
            th = np.asarray(histories[rec.id], dtype=float)
        else:
            continue
        if rec.kind == "free_vibration":
            try:
                cal, (a1, c1, s1), (ha, hd), (fa, fr) = _fv_features(rec.t, th, alpha, rec.noise)
            except ValueError as e:
                cals[rec.id] = str(e)
                continue
            cals[rec.id] = cal
            e_amp.append(a1)
            e_c.append(c1)
            e_s.append(s1)
            h_amp.append(ha)
            h_dur.append(hd)
            f_amp.append(fa)
            f_rat.append(fr)
            continue
        acc = rec.motion.acc
        margin = int(round(UPLIFT_MARGIN / rec.dt))
        kd, s, onset, base, stood = _gm_features(th, acc, rec.noise, alpha, tan_a, margin)
        on_s.append(s)
        on_r.append(onset)
        st_p.append(stood[0])
        st_n.append(stood[1])
        k_pre = kd - margin if kd < th.size else th.size
        if k_pre > 0:
            sel = np.flatnonzero(np.abs(acc[:k_pre]) < gta)[::5]
            tilt_th.append(th[sel] / alpha)
            tilt_acc.append(acc[sel] / gta)
        imp = measured_impacts(th - base, rec.noise)
        if kd < th.size:
            # excursions: the one that starts at uplift and one after each impact
            first = 1 if s > 0 else -1
            signs = first * (-1) ** np.arange(imp.size + 1)
            npos += int(np.count_nonzero(signs > 0))
            nneg += int(np.count_nonzero(signs < 0))
        if histories is None:
            over = rec.overturned
            tmax = rec.theta_max
        else:
            over = bool(overturned[rec.id]) if overturned is not None else bool(np.max(np.abs(th)) >= 0.99 * np.pi / 2)
            tmax = float(theta_max[rec.id]) if theta_max is not None else float(np.max(np.abs(th)))
        tm.append(math.inf if over else tmax / alpha)

    def cat(parts, dtype=float):
        return np.concatenate(parts).astype(dtype) if parts else np.empty(0, dtype=dtype)

    return Features(
        energy_amplitude=cat(e_amp),
        energy_ratio=cat(e_c),
        energy_sign=cat(e_s, int),
        half_cycle_amplitude=cat(h_amp),
        half_cycle_duration=cat(h_dur),
        flight_amplitude=cat(f_amp),
        flight_ratio=cat(f_rat),
        onset_sign=np.asarray(on_s, dtype=int),
        onset_ratio=np.asarray(on_r, dtype=float),
        withstood_pos=np.asarray(st_p, dtype=float),
        withstood_neg=np.asarray(st_n, dtype=float),
        excursions=(npos, nneg),
        tilt_theta=cat(tilt_th),
        tilt_acc=cat(tilt_acc),
        theta_max_over_alpha=np.asarray(tm, dtype=float),
        calibrations=cals,
    )


# ----------------------------------------------------------------------------
# the comparison
@dataclass(frozen=True, eq=False)
class RecordComparison:
    """Model against measurement on one record.

    Attributes
    ----------
    id, kind : str
    error : float
        Time-history error over the window [alpha] (see the module docstring); NaN if the engine failed.
    window_end : float
        End of the error window [s].
    divergence_time : float
        First time the model leaves the measurement [s]; NaN if it never does.
    theta_max_over_alpha_measured, theta_max_over_alpha_model : float
        [-], +inf when overturned; the model's is its own (between samples).
    theta_max_over_alpha_observed : float
        The model's peak as the sensor would see it [-]: the largest |theta|
        of its sampled history plus the record's noise (see :func:`compare`),
        the quantity the distributions compare with the measured peak (which
        carries the noise too).
    overturned_measured, overturned_model : bool
    noise : float
        The record's noise sigma [rad].
    response : Response or None
        The model's response (None if the engine failed).
    failure : str
        The engine's error message, "" when it ran.
    """

    id: str
    kind: str
    error: float
    window_end: float
    divergence_time: float
    theta_max_over_alpha_measured: float
    theta_max_over_alpha_model: float
    theta_max_over_alpha_observed: float
    overturned_measured: bool
    overturned_model: bool
    noise: float
    response: Response | None = None
    failure: str = ""

    @property
    def same_verdict(self) -> bool:
        return self.overturned_measured == self.overturned_model


@dataclass(frozen=True, eq=False)
class DistributionComparison:
    """Model and measurement as ensembles (ground-motion records that both ran).

    Attributes
    ----------
    measured, model : ndarray
        theta_max/alpha per record [-] (+inf overturned).
    ks : housner.stats.KSResult
    wasserstein : float
        [alpha], rocking records only.
    overturn_measured, overturn_model : housner.stats.ProportionCI
        Wilson 95 % intervals.
    percentiles_measured, percentiles_model : housner.stats.PercentileEstimate
        25/50/75 % with 90 % bootstrap intervals.
    agreement : housner.stats.RecordAgreement
        rtol 0.1, atol 0.05 alpha.
    """

    measured: np.ndarray
    model: np.ndarray
    ks: Any
    wasserstein: float
    overturn_measured: Any
    overturn_model: Any
    percentiles_measured: Any
    percentiles_model: Any
    agreement: Any

    def summary(self) -> dict:
        return {
            "n": int(self.measured.size),
            "ks_distance": self.ks.distance,
            "ks_pvalue": self.ks.pvalue,
            "wasserstein": self.wasserstein,
            "p_overturn_measured": list(self.overturn_measured),
            "p_overturn_model": list(self.overturn_model),
            "median_measured": float(self.percentiles_measured.value[1]),
            "median_model": float(self.percentiles_model.value[1]),
            "agreement_share": self.agreement.share,
        }


def _distribution(measured: np.ndarray, model: np.ndarray, seed: int = 0) -> DistributionComparison | None:
    if measured.size == 0:
        return None
    return DistributionComparison(
        measured=measured,
        model=model,
        ks=stats.ks_2samp(measured, model),
        wasserstein=stats.wasserstein(measured, model),
        overturn_measured=stats.overturn_probability(np.isinf(measured)),
        overturn_model=stats.overturn_probability(np.isinf(model)),
        percentiles_measured=stats.percentiles(measured, n_boot=500, seed=seed),
        percentiles_model=stats.percentiles(model, n_boot=500, seed=seed),
        agreement=stats.per_record_agreement(model, measured),
    )


@dataclass(eq=False)
class Comparison:
    """The result of :func:`compare`.

    Attributes
    ----------
    campaign : Campaign
    engine : str
    effects : tuple of Effect
    records : list of RecordComparison
        One per campaign record, in order.
    distribution : DistributionComparison or None
        Ground-motion records that ran.
    measured, model : Features or None
        Localisation quantities (None when not computed).
    noise_floor : float
        Mean sigma/alpha of the records [-]: the time-history error of a perfect model.
    """

    campaign: Campaign
    engine: str
    effects: tuple
    records: list[RecordComparison]
    distribution: DistributionComparison | None
    measured: Features | None
    model: Features | None
    noise_floor: float

    @property
    def failures(self) -> list[tuple[str, str]]:
        """(record id, message) of the records the engine failed on."""
        return [(r.id, r.failure) for r in self.records if r.failure]

    def errors(self, kind: str | None = "ground_motion", ids: Iterable[str] | None = None) -> np.ndarray:
        """Time-history errors [alpha] of the records of ``kind`` (None: all) or of ``ids``, failures left out."""
        want = set(ids) if ids is not None else None
        v = [
            r.error
            for r in self.records
            if (kind is None or r.kind == kind) and (want is None or r.id in want) and math.isfinite(r.error)
        ]
        return np.asarray(v, dtype=float)

    def error(self, kind: str | None = "ground_motion", ids: Iterable[str] | None = None) -> Metric:
        """Mean time-history error [alpha] with its standard error."""
        return _mean_se(self.errors(kind, ids))

    def localisation(self) -> dict[str, tuple[Metric, Metric]]:
        """Metric name -> (measured, model) for every metric of :data:`METRICS`."""
        if self.measured is None or self.model is None:
            return {}
        a, b = self.measured.metrics(), self.model.metrics()
        return {k: (a[k], b[k]) for k in METRICS}

    def discrepancies(self, z: float = 3.0) -> list[tuple[str, float, Metric, Metric]]:
        """Localisation metrics where model and measurement differ by more than ``z`` standard errors.

        Returns (name, z-score, measured, model), the largest |z| first. The
        standard error combines both sides' (the model's from the same records).
        """
        out = []
        for k, (m, x) in self.localisation().items():
            if not (math.isfinite(m.value) and math.isfinite(x.value)):
                continue  # e.g. a median in the overturn mass: the overturn fraction speaks for it
            se = math.hypot(m.se if math.isfinite(m.se) else 0.0, x.se if math.isfinite(x.se) else 0.0)
            if se <= 0:
                continue
            zz = (x.value - m.value) / se
            if abs(zz) > z:
                out.append((k, zz, m, x))
        return sorted(out, key=lambda r: -abs(r[1]))

    def table(self):
        """Per-record table (pandas DataFrame)."""
        import pandas as pd

        rows = []
        for r in self.records:
            rows.append(
                {
                    "id": r.id,
                    "kind": r.kind,
                    "error": r.error,
                    "window_end_s": r.window_end,
                    "divergence_time_s": r.divergence_time,
                    "theta_max_over_alpha_measured": r.theta_max_over_alpha_measured,
                    "theta_max_over_alpha_model": r.theta_max_over_alpha_model,
                    "overturned_measured": r.overturned_measured,
                    "overturned_model": r.overturned_model,
                    "failure": r.failure,
                }
            )
        return pd.DataFrame(rows)

    def summary(self) -> dict:
        """Plain data: errors, distribution statistics, localisation (measured and model)."""
        e = self.error()
        fv = self.error("free_vibration")
        out: dict[str, Any] = {
            "engine": self.engine,
            "effects": [x.describe() for x in self.effects],
            "error_ground_motion": e.value,
            "error_ground_motion_se": e.se,
            "error_free_vibration": fv.value,
            "noise_floor": self.noise_floor,
            "n_failed": len(self.failures),
        }
        if self.distribution is not None:
            out["distribution"] = self.distribution.summary()
        loc = self.localisation()
        if loc:
            out["localisation"] = {
                k: {"measured": [m.value, m.se], "model": [x.value, x.se]} for k, (m, x) in loc.items()
            }
        return out


def _measured_features(campaign: Campaign) -> Features:
    key = "measured_features"
    if key not in campaign._cache:
        campaign._cache[key] = features(campaign)
    return campaign._cache[key]


def compare(
    campaign: Campaign,
    engine: Any = "housner",
    effects: Sequence[Any] = (),
    engine_settings: Mapping[str, Any] | None = None,
    *,
    window_impacts: int | None = None,
    localise: bool = True,
    responses: Sequence[Response | str] | None = None,
) -> Comparison:
    """Compare a model with every record of a campaign.

    Parameters
    ----------
    campaign : Campaign
    engine : str or Engine
        ``"housner"`` (the analytic model, the only one that realises
        effects), ``"mujoco"``, ``"pybullet"``, or an engine instance.
    effects : sequence
        Physical effects (instances, registry names or dicts with ``name``).
    engine_settings : mapping, optional
        Engine settings when ``engine`` is a name.
    window_impacts : int, optional
        Measured impacts in the error window of a ground-motion record
        (default :data:`WINDOW_IMPACTS`).
    localise : bool
        Also compute the localisation quantities (calibrations of the
        free-vibration records, uplift, tilt, ...), for measurement and model.
    responses : sequence, optional
        Precomputed responses (one per record, as from :func:`simulate_records`).

    Returns
    -------
    Comparison
    """
    if not isinstance(campaign, Campaign):
        raise TypeError(f"`campaign` must be a scenarios.campaign.Campaign, got {type(campaign).__name__}")
    spec = campaign.specimen
    alpha = spec.alpha
    eff = resolve_effects(effects, spec)
    if responses is None:
        responses = simulate_records(spec, campaign.records, engine, eff, engine_settings)
    elif len(responses) != len(campaign.records):
        raise ValueError(
            f"`responses` must hold one response per record ({len(campaign.records)}), got {len(responses)}"
        )
    name = engine if isinstance(engine, str) else getattr(engine, "name", type(engine).__name__)
    sens = release_sensitivities(spec, campaign.records, responses, engine, eff, engine_settings)
    rows = []
    for rec, res in zip(campaign.records, responses, strict=True):
        meas_tm = math.inf if rec.overturned else rec.theta_max / alpha
        end = error_window(rec, alpha, None if rec.kind == "free_vibration" else window_impacts)
        if not isinstance(res, Response):
            rows.append(
                RecordComparison(rec.id, rec.kind, math.nan, float(rec.t[end - 1]), math.nan, meas_tm, math.nan,
                                 math.nan, rec.overturned, False, rec.noise, None, str(res) or "not simulated")
            )  # fmt: skip
            continue
        th = _on_grid(res, rec)
        obs_tm = math.inf if res.overturned else float(np.max(np.abs(_observe(th, rec, len(rows))))) / alpha
        rows.append(
            RecordComparison(
                id=rec.id,
                kind=rec.kind,
                error=scored_error(th, rec, end, alpha, sens[len(rows)]),
                window_end=float(rec.t[end - 1]),
                divergence_time=divergence_time(th, rec.theta, rec.t, rec.noise, alpha),
                theta_max_over_alpha_measured=meas_tm,
                theta_max_over_alpha_model=res.theta_max_over_alpha,
                theta_max_over_alpha_observed=obs_tm,
                overturned_measured=rec.overturned,
                overturned_model=bool(res.overturned),
                noise=rec.noise,
                response=res,
            )
        )
    gm_ok = [r for r in rows if r.kind == "ground_motion" and r.response is not None]
    dist = _distribution(
        np.array([r.theta_max_over_alpha_measured for r in gm_ok]),
        np.array([r.theta_max_over_alpha_observed for r in gm_ok]),
    )
    measured = model = None
    if localise:
        measured = _measured_features(campaign)
        observed = {rec.id: _observe(_on_grid(r.response, rec), rec, i) for i, (rec, r) in
                    enumerate(zip(campaign.records, rows, strict=True)) if r.response is not None}  # fmt: skip
        model = features(campaign, observed, {r.id: r.overturned_model for r in rows if r.response is not None})
    floor = float(np.mean([rec.noise for rec in campaign.records])) / alpha
    return Comparison(campaign, name, eff, rows, dist, measured, model, floor)


#: Seed of the sensor noise added to model histories for the localisation and the distributions.
OBSERVATION_SEED = 20170615


def _observe(theta: np.ndarray, rec: MeasuredRecord, index: int) -> np.ndarray:
    """The model's theta as the record's sensor would show it: plus Gaussian noise of the record's sigma.

    Seeded by the record's position in the campaign, so a comparison is reproducible and two models
    compared on the same campaign see the same noise.
    """
    rng = np.random.default_rng(np.random.SeedSequence([OBSERVATION_SEED, index]))
    return theta + rng.normal(0.0, rec.noise, theta.size)


def _on_grid(res: Response, rec: MeasuredRecord) -> np.ndarray:
    """The model's theta on the record's samples (engines answer on the motion's grid; others are interpolated)."""
    th = np.asarray(res.theta, dtype=float)
    if th.size == rec.theta.size:
        return th
    return np.interp(rec.t, np.asarray(res.t, dtype=float), th)
