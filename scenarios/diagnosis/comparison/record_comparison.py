"""Model against measurement: record by record, as distributions, and where the model fails.

:func:`compare` runs an engine (with physical effects, on the analytic engine) on every record of a
:class:`housner.scenarios.campaigns.campaign.Campaign`, driven by the measured ground acceleration (a
free-vibration record is released at its measured initial angle), sees the model through the record's
sensor, and gathers per record the time-history error over a window fixed by the measurement, the
divergence time, the peaks and outcomes, the distributions (:mod:`housner.statistics.ensemble_stats`) and the
localisation
quantities (:class:`Features`, :data:`METRICS`). The error is
:mod:`housner.scenarios.diagnosis.comparison.history_error`'s and the localisation quantities
:mod:`housner.scenarios.diagnosis.comparison.localise`'s (their names are importable from here too); the
definitions, and why each is taken so, are in ``docs/explanation/diagnosis.md`` ("A record's error").
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from housner.effects import make_effects
from housner.engines.base import Engine, get_engine
from housner.response import Response
from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.campaigns.campaign_records import OVERTURN_ANGLE, MeasuredRecord
from housner.scenarios.diagnosis.comparison.history_error import (
    RELEASE_DTHETA0_SIGMAS,
    divergence_time,
    error_window,
    scored_error,
)
from housner.scenarios.diagnosis.comparison.localise import (
    METRICS,
    Features,
    Metric,
    features,
    mean_se,
    measured_features,
)
from housner.statistics import ensemble_stats as stats
from housner.statistics import proportions

__all__ = [
    "OBSERVATION_SEED",
    "Comparison",
    "DistributionComparison",
    "RecordComparison",
    "compare",
    "observe",
    "on_grid",
    "release_sensitivities",
    "resolve_effects",
    "sees_overturn",
    "sensor_reading",
    "simulate_records",
]


# ----------------------------------------------------------------------------
# effects and simulation
def resolve_effects(effects: Iterable[Any], specimen=None) -> tuple:
    """Effects from Effect instances, registry names or ``{"name": ..., param: value}`` dicts."""
    out = make_effects(list(effects or ()))
    if specimen is not None:
        for e in out:
            e.check(specimen)
    return out


def simulate_records(
    specimen,
    records: Sequence[MeasuredRecord],
    engine: Any = "housner",
    effects: Sequence[Any] = (),
    engine_settings: Mapping[str, Any] | None = None,
) -> list[Response | str]:
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


def release_sensitivities(
    specimen,
    records: Sequence[MeasuredRecord],
    responses: Sequence[Response | str],
    engine: Any = "housner",
    effects: Sequence[Any] = (),
    engine_settings: Mapping[str, Any] | None = None,
) -> list[np.ndarray | None]:
    """d theta / d theta0 on each free-vibration record's grid (finite difference; None elsewhere).

    One more run of each free-vibration record, released RELEASE_DTHETA0_SIGMAS / 2 noise sigmas
    further from rest.
    """
    out: list[np.ndarray | None] = [None] * len(records)
    fv = [i for i, rec in enumerate(records) if rec.kind == "free_vibration" and isinstance(responses[i], Response)]
    if not fv:
        return out
    eps = [
        math.copysign(0.5 * RELEASE_DTHETA0_SIGMAS * max(records[i].noise, 1e-9), records[i].motion.theta0) for i in fv
    ]
    bumped = [
        replace(records[i], motion=replace(records[i].motion, theta0=records[i].motion.theta0 + e))
        for i, e in zip(fv, eps, strict=True)
    ]
    res = simulate_records(specimen, bumped, engine, effects, engine_settings)
    for i, e, r, rec in zip(fv, eps, res, bumped, strict=True):
        if isinstance(r, Response):
            out[i] = (on_grid(r, rec) - on_grid(responses[i], records[i])) / e
    return out


# ----------------------------------------------------------------------------
# the comparison
@dataclass(frozen=True, eq=False)
class RecordComparison:
    """Model against measurement on one record.

    Attributes
    ----------
    id, kind : str
    error : float
        Time-history error over the window [alpha] (``docs/explanation/diagnosis.md``, "A record's error"); NaN if
        the engine failed.
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
    ks : housner.statistics.ensemble_stats.KSResult
    wasserstein : float
        [alpha], rocking records only.
    overturn_measured, overturn_model : housner.statistics.proportions.ProportionCI
        Wilson 95 % intervals.
    percentiles_measured, percentiles_model : housner.statistics.ensemble_stats.PercentileEstimate
        25/50/75 % with 90 % bootstrap intervals.
    agreement : housner.statistics.ensemble_stats.RecordAgreement
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
        overturn_measured=proportions.overturn_probability(np.isinf(measured)),
        overturn_model=proportions.overturn_probability(np.isinf(model)),
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
        return mean_se(self.errors(kind, ids))

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
        raise TypeError(f"`campaign` must be a housner.scenarios.campaigns.Campaign, got {type(campaign).__name__}")
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
    rows = [
        _record_comparison(rec, res, i, alpha, window_impacts, sens[i])
        for i, (rec, res) in enumerate(zip(campaign.records, responses, strict=True))
    ]
    gm_ok = [r for r in rows if r.kind == "ground_motion" and r.response is not None]
    dist = _distribution(
        np.array([r.theta_max_over_alpha_measured for r in gm_ok]),
        np.array([r.theta_max_over_alpha_observed for r in gm_ok]),
    )
    measured = model = None
    if localise:
        measured = measured_features(campaign)
        observed = {
            rec.id: observe(on_grid(r.response, rec), rec, i)
            for i, (rec, r) in enumerate(zip(campaign.records, rows, strict=True))
            if r.response is not None
        }
        seen = {rec.id: rec for rec in campaign.records}
        model = features(
            campaign,
            observed,
            {r.id: sees_overturn(seen[r.id], r.overturned_model) for r in rows if r.response is not None},
        )
    floor = float(np.mean([rec.noise for rec in campaign.records])) / alpha
    return Comparison(campaign, name, eff, rows, dist, measured, model, floor)


def _record_comparison(
    rec: MeasuredRecord, res: Response | str, index: int, alpha: float, window_impacts: int | None, sensitivity
) -> RecordComparison:
    """Model against measurement on one record (``index`` its position in the campaign, ``alpha`` [rad])."""
    meas_tm = math.inf if rec.overturned else rec.theta_max / alpha
    end = error_window(rec, alpha, None if rec.kind == "free_vibration" else window_impacts)
    if not isinstance(res, Response):
        failure = str(res) or "not simulated"
        return RecordComparison(
            rec.id,
            rec.kind,
            math.nan,
            float(rec.t[end - 1]),
            math.nan,
            meas_tm,
            math.nan,
            math.nan,
            rec.overturned,
            False,
            rec.noise,
            None,
            failure,
        )
    th = on_grid(res, rec)
    over = sees_overturn(rec, bool(res.overturned))
    obs_tm = math.inf if over else float(np.max(np.abs(observe(th, rec, index)))) / alpha
    return RecordComparison(
        id=rec.id,
        kind=rec.kind,
        error=scored_error(th, rec, end, alpha, sensitivity),
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


def sees_overturn(rec: MeasuredRecord, overturned: bool) -> bool:
    """Whether the record's sensor would show a model's overturn: not through a range below the overturn
    angle (a saturating sensor reads a toppled block and one that stopped at its range alike)."""
    return overturned and min(-rec.clip[0], rec.clip[1]) >= OVERTURN_ANGLE


#: Seed of the sensor noise added to model histories for the localisation and the distributions.
OBSERVATION_SEED = 20170615


def observe(theta: np.ndarray, rec: MeasuredRecord, index: int) -> np.ndarray:
    """The model's theta as the record's sensor would show it: plus Gaussian noise of the record's sigma and
    correlation in time (``rec.noise_model``), within the sensor's range (``rec.clip``).

    Seeded by the record's position in the campaign, so a comparison is reproducible and two models
    compared on the same campaign see the same noise.
    """
    return sensor_reading(theta, rec, np.random.default_rng(np.random.SeedSequence([OBSERVATION_SEED, index])))


def sensor_reading(theta: np.ndarray, rec: MeasuredRecord, rng: np.random.Generator) -> np.ndarray:
    """``theta`` [rad] as the record's sensor reads it: plus a draw of its noise (``rec.noise`` and
    ``rec.noise_model``), within its range (``rec.clip``)."""
    seen = theta + rec.noise_model.draw(rng, rec.noise, theta.size)
    lo, hi = rec.clip
    return seen if (lo, hi) == (-math.inf, math.inf) else np.clip(seen, lo, hi)


def on_grid(res: Response, rec: MeasuredRecord) -> np.ndarray:
    """The model's theta on the record's samples (engines answer on the motion's grid; others are interpolated)."""
    th = np.asarray(res.theta, dtype=float)
    if th.size == rec.theta.size:
        return th
