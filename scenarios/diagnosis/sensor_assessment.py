"""The theta sensor of a campaign, assessed before any physics is fitted: its noise, and its faults.

A diagnosis compares a model with what a sensor recorded. Before physics is asked to explain a misfit,
:func:`assess_sensor` asks the records what the sensor did and returns the campaign with what it found, in
:class:`SensorReport`: the faults that touch samples (saturation, spikes, dropouts: named, masked in
``MeasuredRecord.valid``, spikes and dropouts bridged), the noise as measured on the samples where the block
is surely still (:mod:`housner.scenarios.campaigns.sensor_noise`), and the faults along the recording order
(a drifting offset or gain, tested as a linear trend and corrected relative to the first record). What each
test looks for, and its thresholds (:data:`SPIKE_SIGMAS`, :data:`DROPOUT_RUN`, :data:`REST_MARGIN`,
:data:`QUIET_ACC`, :data:`T_TREND`, :data:`GAIN_MIN_SIGMAS`), are in ``docs/explanation/diagnosis.md``
("The sensor, first").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from housner.free_vibration.calibration import estimate_noise
from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.campaigns.campaign_records import MeasuredRecord
from housner.scenarios.campaigns.sensor_noise import WHITE, SensorNoise, estimate_sensor_noise
from housner.scenarios.diagnosis.comparison.localise import line_fit
from housner.scenarios.diagnosis.comparison.record_comparison import on_grid, simulate_records

__all__ = [
    "DROPOUT_RUN",
    "QUIET_ACC",
    "REST_MARGIN",
    "SPIKE_SIGMAS",
    "T_TREND",
    "SensorFault",
    "SensorReport",
    "assess_sensor",
]

G = 9.80665
#: A spike: a sample off the mean of its two neighbours by more than this many robust standard deviations of
#: that difference (a record's own, from its median absolute deviation) [-]. An impact's kink at 200 Hz and
#: 0.5 rad/s moves it by ~3.
SPIKE_SIGMAS = 10.0
#: A dropout: at least this many identical consecutive samples (noise of one sensor sigma over its
#: quantisation step makes even two rare) [-].
DROPOUT_RUN = 4
#: Fewest samples at one extreme level for a record to be flat-topped there [-].
SATURATION_RUN = 3
#: Time after the plain model's last motion before a rest counts as quiet [s] (a true block with more
#: energy left than the model may still rock for a few small half-cycles).
REST_MARGIN = 1.0
#: The table is quiet below this share of the uplift acceleration g tan(alpha) [-].
QUIET_ACC = 0.05
#: Shortest quiet segment measured [s].
MIN_QUIET = 0.25
#: A rest level further than this share of alpha from the campaign's typical one is no rest [-] (a block
#: that rocks on, or toppled, where the plain model rests; a still sensor's offset is a few mrad).
REST_LEVEL_ALPHA = 0.05
#: A ground motion's rest is measured only when its standard deviation is within this factor of the
#: typical rest's [-].
QUIET_SD_RATIO = 1.25
#: |t| of a linear trend along the recording order that names a drift [-] (two-sided p ~ 6e-5; two trends tested).
T_TREND = 4.0
#: Fewest records with a usable first excursion or rest level for a trend [-].
MIN_TREND_RECORDS = 8
#: Every excursion before the one used for the gain stays below this share of its amplitude [-] (their impacts
#: carried at most 4 % of its energy).
GAIN_PRIOR_SHARE = 0.2
#: The excursion used for the gain is the first beyond this many noise sigmas [-].
GAIN_MIN_SIGMAS = 10.0


@dataclass(frozen=True)
class SensorFault:
    """One sensor fault: ``kind`` (saturation, spikes, dropouts, offset_drift, gain_drift), the records it
    touched, the samples masked and the figures that named it (in words: :mod:`housner.reports.diagnosis.sensor_text`).

    ``figures`` by kind: saturation ``low``, ``high`` (the sensor's range [rad]) and ``alpha`` [rad]; spikes
    ``sigmas`` [-]; dropouts ``run`` [-]; offset drift ``slope_per_record`` [rad], ``change`` [rad], ``t`` [-] and
    ``n`` (rest levels used); gain drift ``gain_first`` [-], ``slope_per_record`` [-], ``relative_change`` [-],
    ``t`` [-] and ``n`` (ground motions used).
    """

    kind: str
    records: tuple[str, ...]
    samples: int
    figures: dict

    def to_dict(self) -> dict:
        return {
            "kind": self.kind,
            "records": list(self.records),
            "samples": self.samples,
            "figures": dict(self.figures),
        }


@dataclass(frozen=True)
class SensorReport:
    """What :func:`assess_sensor` found: the noise, the faults (what was masked or corrected), the free vibrations
    left out because their release was beyond the sensor's range, and whether the records' sample rates differ
    (the noise is then taken as white)."""

    noise: SensorNoise = WHITE
    faults: tuple[SensorFault, ...] = ()
    sigma_before: float = math.nan
    sigma_after: float = math.nan
    unseen_releases: tuple[str, ...] = ()
    mixed_rates: bool = False

    @property
    def fault_kinds(self) -> list[str]:
        return [f.kind for f in self.faults]

    def to_dict(self) -> dict:
        return {
            "noise": self.noise.to_dict(),
            "faults": [f.to_dict() for f in self.faults],
            "sigma_before": self.sigma_before,
            "sigma_after": self.sigma_after,
            "unseen_releases": list(self.unseen_releases),
            "mixed_rates": self.mixed_rates,
        }


# ----------------------------------------------------------------------------
# faults on samples
def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of each run of True."""
    m = np.concatenate(([False], mask, [False])).astype(np.int8)
    d = np.diff(m)
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist(), strict=True))


def _saturation(theta: np.ndarray) -> tuple[np.ndarray, list[float]]:
    """Samples at a flat top (the record's maximum or minimum repeated in a run) and those levels."""
    bad = np.zeros(theta.size, dtype=bool)
    levels = []
    for v in (float(theta.max()), float(theta.min())):
        at = theta == v
        if int(at.sum()) >= SATURATION_RUN and any(b - a >= 2 for a, b in _runs(at)):
            bad |= at
            levels.append(v)
    return bad, levels


def _spikes(theta: np.ndarray, skip: np.ndarray | None = None, alpha: float = math.inf) -> np.ndarray:
    """Single samples off both neighbours by more than :data:`SPIKE_SIGMAS` robust standard deviations, outside
    ``skip`` (a flat top, whose repeated samples say nothing of the noise) and within alpha of rest (beyond, a
    toppling block stops against the table)."""
    out = np.zeros(theta.size, dtype=bool)
    if theta.size < 5:
        return out
    d = theta[1:-1] - 0.5 * (theta[:-2] + theta[2:])
    use = np.ones(d.size, dtype=bool) if skip is None else ~(skip[:-2] | skip[1:-1] | skip[2:])
    if use.sum() < 5:
        return out
    s = 1.4826 * float(np.median(np.abs(d[use] - np.median(d[use]))))
    if not s > 0:
        return out
    big = np.abs(d) > SPIKE_SIGMAS * s
    # a spike at i leaves its neighbours' differences at about -d_i / 2: opposite signs
    left = np.concatenate(([0.0], d[:-1]))
    right = np.concatenate((d[1:], [0.0]))
    spike = (
        big
        & use
        & (np.sign(left) == -np.sign(d))
        & (np.sign(right) == -np.sign(d))
        & (np.abs(d) >= np.abs(left))
        & (np.abs(d) >= np.abs(right))
        & (np.abs(theta[1:-1]) < alpha)
    )
    out[1:-1] = spike
    return out


def _dropouts(theta: np.ndarray, skip: np.ndarray) -> np.ndarray:
    """Samples of runs of identical values (all but the first of each run), outside ``skip``."""
    out = np.zeros(theta.size, dtype=bool)
    same = np.concatenate(([False], np.diff(theta) == 0.0))
    for a, b in _runs(same & ~skip):
        if b - a + 1 >= DROPOUT_RUN:
            out[a:b] = True
    return out


def _bridge(theta: np.ndarray, bad: np.ndarray) -> np.ndarray:
    """``theta`` with the ``bad`` samples replaced by the straight line between their good neighbours."""
    if not bad.any() or bad.all():
        return theta
    k = np.arange(theta.size)
    return np.where(bad, np.interp(k, k[~bad], theta[~bad]), theta)


# ----------------------------------------------------------------------------
# trends along the order
def _trend(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """Least-squares line y = a + b x (:func:`housner.scenarios.diagnosis.comparison.localise.line_fit`): (a, b, t of
    b);
    (mean of y, 0, 0) where no line can be fitted."""
    off, slope = line_fit(x, y)
    a, b, se = off.value, slope.value, slope.se
    if not (math.isfinite(a) and math.isfinite(b)):
        return float(np.mean(y)), 0.0, 0.0
    return a, b, (b / se if se > 0 else (math.inf if b != 0 else 0.0))


def _quiet_start(rec: MeasuredRecord, model: np.ndarray | None, alpha: float) -> int | None:
    """First sample of the record's final rest (docs/explanation/diagnosis.md), None when it has none long enough."""
    n = rec.theta.size
    if model is None or model.size < n or not np.all(np.isfinite(model[:n])):
        return None
    m = model[:n]
    if np.max(np.abs(m)) >= 0.5 * math.pi - 1e-9:
        return None  # the model overturned
    moving = np.flatnonzero(m != 0.0)
    k = (int(moving[-1]) + 1 if moving.size else 0) + int(round(REST_MARGIN / rec.dt))
    loud = np.flatnonzero(np.abs(rec.motion.acc[:n]) > QUIET_ACC * G * math.tan(alpha))
    if loud.size:
        k = max(k, int(loud[-1]) + 1)
    if rec.kind == "free_vibration" and not moving.size:
        return None
    # a motion that is still dying out (a foundation's vibration, the last small rocking) is no rest: the
    # tail's first half may not be louder than its second by more than QUIET_SD_RATIO, else it is dropped
    need = int(round(MIN_QUIET / rec.dt))
    while n - k >= 2 * need:
        mid = (k + n) // 2
        if float(np.std(rec.theta[k:mid])) <= QUIET_SD_RATIO * float(np.std(rec.theta[mid:])):
            break
        k = mid
    return k if n - k >= need else None


def _first_excursion(rec: MeasuredRecord, model: np.ndarray, least: float) -> slice | None:
    """The model's first excursion beyond ``least`` [rad] on a ground motion (from its uplift or the impact
    before it to the next impact, or an overturn), when every excursion before it stayed below
    :data:`GAIN_PRIOR_SHARE` of it: the impacts before carried too little energy for an impact law to matter."""
    m = model[: rec.theta.size]
    if rec.kind != "ground_motion" or not np.any(m != 0.0):
        return None
    sgn = np.sign(m)
    edges = np.flatnonzero(np.diff(sgn) != 0) + 1  # where the side (or rest) changes
    bounds = np.concatenate(([0], edges, [m.size]))
    prior = 0.0
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        amp = float(np.max(np.abs(m[a:b])))
        if amp > least:
            return slice(int(a), int(b)) if prior <= GAIN_PRIOR_SHARE * amp and b - a >= 10 else None
        prior = max(prior, amp)
    return None


def _corrected(rec: MeasuredRecord, fix, gain: float = 1.0) -> MeasuredRecord:
    """``rec`` with ``fix`` applied to every theta it carries: the samples, the hold and a free vibration's
    release angle (read off the uncorrected samples); its noise sigma divided by ``gain`` (the noise read
    through a gain corrected away)."""
    motion = rec.motion
    if rec.kind == "free_vibration":
        motion = replace(motion, theta0=float(fix(np.array([motion.theta0]))[0]))
    return replace(rec, theta=fix(rec.theta), hold=fix(rec.hold), motion=motion, noise=rec.noise / gain)


def assess_sensor(campaign: Campaign, engine_settings: dict | None = None) -> Campaign:
    """The campaign with its theta sensor assessed (``docs/explanation/diagnosis.md``); itself when already assessed.

    Returns a new :class:`Campaign` whose records carry the measured noise (``noise``, ``noise_model``), the
    masks of faulty samples (``valid``), the sensor's range (``clip``) and the corrections of drifts, and whose
    ``sensor`` is the :class:`SensorReport`.
    """
    if campaign.sensor is not None or not campaign.records:
        return campaign
    alpha = campaign.specimen.alpha
    # 1. faults on samples, and the free vibrations whose release the sensor did not see
    recs, faults = _sample_faults(list(campaign.records), alpha)
    recs, skipped, unseen = _unseen_releases(recs, list(campaign.skipped))
    # 2. the plain model: where the block is surely still, and each first excursion
    res = simulate_records(campaign.specimen, recs, "housner", (), engine_settings)
    models = [
        None if isinstance(r, str) else np.asarray(on_grid(r, rec), dtype=float)
        for r, rec in zip(res, recs, strict=True)
    ]
    # the recording order: each record's place among the [[record]] tables, those that could not be read counted
    order = np.array([r.position if r.position >= 0 else i for i, r in enumerate(recs)], dtype=float)
    tails, level_of = _rest_tails(recs, models, alpha)
    # 3. faults along the order, corrected relative to the first record
    for drift in (_offset_drift, _gain_drift):
        recs, level_of, fault = drift(recs, models, order, tails, level_of)
        if fault is not None:
            faults.append(fault)
    # 4. the noise, on the quiet samples
    before = float(np.mean([r.noise for r in recs]))
    recs, noise, mixed_rates = _measured_noise(recs, tails, level_of)
    after = float(np.mean([r.noise for r in recs]))
    report = SensorReport(noise, tuple(faults), before, after, unseen, mixed_rates)
    return replace(campaign, records=recs, sensor=report, skipped=skipped)


def _sample_faults(recs: list[MeasuredRecord], alpha: float) -> tuple[list[MeasuredRecord], list[SensorFault]]:
    """Saturation, spikes and dropouts of every record: the records masked (and bridged) and the faults named."""
    faults: list[SensorFault] = []
    sat_ids, sat_levels, sat_n = [], [], 0
    spk_ids, spk_n, drop_ids, drop_n = [], 0, [], 0
    masks: list[np.ndarray] = []
    thetas: list[np.ndarray] = []
    for rec in recs:
        th = np.asarray(rec.theta, dtype=float)
        sat, levels = _saturation(th)
        spk = _spikes(th, sat, alpha) & ~sat
        drp = _dropouts(th, sat)
        if levels:
            sat_ids.append(rec.id)
            sat_levels += levels
            sat_n += int(sat.sum())
        if spk.any():
            spk_ids.append(rec.id)
            spk_n += int(spk.sum())
        if drp.any():
            drop_ids.append(rec.id)
            drop_n += int(drp.sum())
        masks.append(~(sat | spk | drp))
        thetas.append(_bridge(th, spk | drp))
    clip = (-math.inf, math.inf)
    if sat_ids:
        hi = [v for v in sat_levels if v > 0]
        lo = [v for v in sat_levels if v < 0]
        clip = (max(lo) if lo else -math.inf, min(hi) if hi else math.inf)
        faults.append(
            SensorFault("saturation", tuple(sat_ids), sat_n, {"low": clip[0], "high": clip[1], "alpha": alpha})
        )
    if spk_ids:
        faults.append(SensorFault("spikes", tuple(spk_ids), spk_n, {"sigmas": SPIKE_SIGMAS}))
    if drop_ids:
        faults.append(SensorFault("dropouts", tuple(drop_ids), drop_n, {"run": DROPOUT_RUN}))
    recs = [
        replace(r, theta=th, valid=None if m.all() else m, clip=clip)
        for r, th, m in zip(recs, thetas, masks, strict=True)
    ]
    return recs, faults


def _unseen_releases(recs: list[MeasuredRecord], skipped: list) -> tuple[list[MeasuredRecord], list, tuple[str, ...]]:
    """A free vibration released beyond the sensor's range has no measured release angle: left out (the records,
    the skipped list with each, and their ids)."""
    lost = [r for r in recs if r.kind == "free_vibration" and r.valid is not None and not r.valid[:3].all()]
    for r in lost:
        skipped.append(
            (
                r.id,
                str(r.file),
                f"{r.file}: the free vibration starts beyond the sensor's range "
                f"(flat at {r.theta[0]:+.4g} rad): its release angle was not measured, so it cannot pin p "
                "or r; left out",
            )
        )
    return [r for r in recs if r not in lost], skipped, tuple(r.id for r in lost)


def _rest_tails(recs, models, alpha: float) -> tuple[list[tuple[int, int]], dict[int, float]]:
    """(record, first sample) of each final rest (:func:`_quiet_start`) with no masked sample, and its level."""
    tails: list[tuple[int, int]] = []
    for i, (rec, m) in enumerate(zip(recs, models, strict=True)):
        k = _quiet_start(rec, m, alpha)
        if k is not None and (rec.valid is None or rec.valid[k:].all()):
            tails.append((i, k))
    level_of = {i: float(np.median(recs[i].theta[k:])) for i, k in tails}
    if level_of:
        # a block that went on rocking, or toppled, where the plain model rests is no rest level
        mid = float(np.median(list(level_of.values())))
        tails = [(i, k) for i, k in tails if abs(level_of[i] - mid) <= REST_LEVEL_ALPHA * alpha]
        level_of = {i: level_of[i] for i, _k in tails}
    return tails, level_of


def _offset_drift(recs, models, order, tails, level_of):
    """The rest levels along the order: (records, levels, fault or None), corrected to the first record's offset."""
    if len(tails) < MIN_TREND_RECORDS:
        return recs, level_of, None
    xi = np.array([order[i] for i, _ in tails], dtype=float)
    yi = np.array([level_of[i] for i, _ in tails])
    _a, b, t = _trend(xi, yi)
    if not abs(t) > T_TREND:
        return recs, level_of, None
    change = b * (order[-1] - order[0])
    offsets = b * (order - order[0])  # relative to the first record
    figures = {"slope_per_record": b, "change": change, "t": t, "n": len(tails)}
    fault = SensorFault("offset_drift", tuple(r.id for r in recs), 0, figures)
    recs = [_corrected(r, lambda x, i=i: x - offsets[i]) for i, r in enumerate(recs)]
    return recs, {i: v - offsets[i] for i, v in level_of.items()}, fault


def _gain_drift(recs, models, order, tails, level_of):
    """Each ground motion's first large excursion against the plain model's, along the order: (records, levels,
    fault or None), corrected to the first record's gain."""
    gains, gx = [], []
    sig0 = float(np.median([r.noise for r in recs]))
    for i, (rec, m) in enumerate(zip(recs, models, strict=True)):
        sl = None if m is None else _first_excursion(rec, m, GAIN_MIN_SIGMAS * max(sig0, 1e-9))
        if sl is None:
            continue
        y = rec.theta[sl] - level_of.get(i, float(np.median(rec.theta[: max(sl.start, 1)])))
        ok = rec.valid[sl] if rec.valid is not None else np.ones(y.size, dtype=bool)
        mm = m[sl][ok]
        den = float(np.dot(mm, mm))
        if den > 0:
            gains.append(float(np.dot(mm, y[ok]) / den))
            gx.append(float(order[i]))
    if len(gains) < MIN_TREND_RECORDS:
        return recs, level_of, None
    a, b, t = _trend(np.array(gx), np.array(gains))
    g0 = a + b * order[0]
    if not (abs(t) > T_TREND and g0 > 0):
        return recs, level_of, None
    rel = (a + b * order) / g0  # the gain relative to the first record's
    change = float(rel[-1] - 1.0)
    figures = {"gain_first": g0, "slope_per_record": b, "relative_change": change, "t": t, "n": len(gains)}
    fault = SensorFault("gain_drift", tuple(r.id for r in recs), 0, figures)
    recs = [_corrected(r, lambda x, i=i: x / rel[i], rel[i]) for i, r in enumerate(recs)]
    return recs, {i: v / rel[i] for i, v in level_of.items()}, fault


def _measured_noise(recs, tails, level_of) -> tuple[list[MeasuredRecord], SensorNoise, bool]:
    """The noise on the quiet samples (:func:`estimate_sensor_noise`): the records with their sigma and its
    correlation where it is not white, the noise, and whether the sample rates differ (then it is white)."""
    dt = float(np.median([r.dt for r in recs]))
    segs, lev = [], []
    rest = float(np.median(list(level_of.values()))) if level_of else 0.0
    # only the rests as quiet as the typical one: a block that rocks on where the plain model rests is louder
    sd = {i: float(np.std(recs[i].theta[k:])) for i, k in tails}
    ref = float(np.median(list(sd.values()))) if sd else 0.0
    for i, k in tails:
        if sd[i] <= QUIET_SD_RATIO * ref:
            segs.append((f"rest after a {recs[i].kind.replace('_', ' ')}", recs[i].theta[k:]))
            lev.append(rest)
    for r in recs:
        if r.hold.size >= int(round(MIN_QUIET / r.dt)):
            segs.append(("hold before a release", r.hold))
            lev.append(float(np.mean(r.hold)))
    same_rate = all(abs(r.dt - dt) <= 1e-9 * dt for r in recs)
    noise = estimate_sensor_noise(segs, dt, lev) if same_rate else WHITE
    if not noise.white and math.isfinite(noise.diff_ratio) and noise.diff_ratio > 0:
        recs = [
            replace(
                r,
                noise=float(noise.diff_ratio * estimate_noise(r.theta)) if r.noise > 0 else r.noise,
                noise_model=noise,
            )
            for r in recs
        ]
    return recs, noise, not same_rate
