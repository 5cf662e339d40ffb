"""Scenario-level analyses beyond one run: the spread of Table 2 over independent ensembles, and the
record against its own simulated ensemble (why Table 2 of the seed paper is not reproduced)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from housner._values import JsonValue
from housner.engines.base import get_engine
from housner.scenarios.catalogue.scenario import Scenario
from housner.scenarios.execution.options import RunOptions
from housner.scenarios.execution.runner import run_engines
from housner.scenarios.motions.build import build_motions
from housner.scenarios.motions.elastic import ensemble_spectra, response_spectrum
from housner.scenarios.motions.records import arias_intensity

__all__ = [
    "RECORD_BAND_S",
    "AmplitudeFactor",
    "EquivalentAmplitudes",
    "RecordGap",
    "Table2Spread",
    "ensemble_seeds",
    "equivalent_amplitude",
    "record_against_ensemble",
    "seed_spread",
]

#: Prototype periods [s] where the rocking of the seed's 5 m prototype (p = 1.55 1/s) is decided:
#: omega_p/p of about 3-8 (seed Fig. 2), i.e. T = 2 pi / (omega_p) = 0.5-1.25 s.
RECORD_BAND_S = (0.5, 1.25)


@dataclass(frozen=True, eq=False)
class Table2Spread(JsonValue):
    """Table 2 over independent ensembles (:func:`seed_spread`; run.json's ``table2_spread``).

    Attributes
    ----------
    k : int or None
        Ensembles.
    seeds : tuple of int
        Their seeds.
    percentiles : dict
        Percentile [%] -> theta_max/alpha of each ensemble [-] (inf: overturn).
    overturn_fraction : tuple of float
        Each ensemble's share of overturns [-].
    overturn_fraction_range : tuple of float
        (min, median, max) of ``overturn_fraction``.
    summary : dict
        Percentile [%] -> (min, median, max) over the ensembles [-].
    inf_means : str or None
        What an infinite value means ("overturn").
    nan_free : bool or None
        Whether every ensemble had a usable record.
    n_failed : int or None
        Records left out, over all ensembles.
    """

    k: int | None = None
    seeds: tuple[int, ...] = ()
    percentiles: dict[int, tuple[float, ...]] = field(default_factory=dict)
    overturn_fraction: tuple[float, ...] = ()
    overturn_fraction_range: tuple[float, ...] = ()
    summary: dict[int, tuple[float, ...]] = field(default_factory=dict)
    inf_means: str | None = None
    nan_free: bool | None = None
    n_failed: int | None = None
    extra: dict = field(default_factory=dict)

    @property
    def n_ensembles(self) -> int:
        """Ensembles of the spread: ``k``, else as many as seeds."""
        return self.k if self.k is not None else len(self.seeds)


@dataclass(frozen=True, eq=False)
class RecordGap(JsonValue):
    """The record an ensemble was fitted to, measured as one more member of it (:func:`record_against_ensemble`).

    Attributes
    ----------
    engine : str
        The engine that gave the record's response.
    amplitude : float
        Factor on the record, as on the ensemble [-].
    record : str
        The record's name.
    record_theta_max_over_alpha : float
        The record's response [-] (inf: overturned).
    record_percentile : float
        Per cent of the ensemble strictly below the record, ties counted half [%].
    n_ensemble : int
        The ensemble's usable records.
    damping : float
        Damping ratio of the spectra [-].
    band_s : tuple of float
        The prototype period range where rocking is decided [s].
    band_periods_s, band_psa_ratio : tuple of float
        Periods of the band [s] and the ensemble's mean PSa over the record's at each [-].
    band_ratio_min, band_ratio_max, band_ratio_mean : float
        Of ``band_psa_ratio`` [-].
    short_s : tuple of float
        The short period range [s].
    short_ratio_max, short_ratio_max_period_s : float
        The largest ratio there [-] and its period [s].
    p_prototype_1_s : float
        The prototype's frequency parameter [1/s].
    omega_ratio_band : tuple of float
        omega_p/p of the prototype at the band's ends [-].
    arias_record_m_s, arias_ensemble_mean_m_s : float
        Arias intensities at prototype scale [m/s].
    arias_ensemble_5_95_m_s : tuple of float
        The ensemble's 5th and 95th percentiles of it [m/s].
    """

    engine: str
    amplitude: float
    record: str
    record_theta_max_over_alpha: float
    record_percentile: float
    n_ensemble: int
    damping: float
    band_s: tuple[float, ...]
    band_periods_s: tuple[float, ...]
    band_psa_ratio: tuple[float, ...]
    band_ratio_min: float
    band_ratio_max: float
    band_ratio_mean: float
    short_s: tuple[float, ...]
    short_ratio_max: float
    short_ratio_max_period_s: float
    p_prototype_1_s: float
    omega_ratio_band: tuple[float, ...]
    arias_record_m_s: float
    arias_ensemble_mean_m_s: float
    arias_ensemble_5_95_m_s: tuple[float, ...]


@dataclass(frozen=True, eq=False)
class AmplitudeFactor(JsonValue):
    """The factor on an ensemble at which one of its percentiles reaches a target, and its bootstrap interval.

    ``factor``, ``low`` and ``high`` [-] are NaN where the target is not reached within the search range;
    ``target`` is the percentile's target [-] (inf: overturn).
    """

    factor: float
    low: float
    high: float
    target: float


@dataclass(frozen=True, eq=False)
class EquivalentAmplitudes(JsonValue):
    """What :func:`equivalent_amplitude` found.

    Attributes
    ----------
    factors : dict of AmplitudeFactor
        Percentile [%] -> its factor.
    grid : tuple of float
        The factors simulated [-].
    evaluations : int
        Factors simulated.
    step, ci : float
        The grid's relative spacing [-] and the intervals' level [-].
    engine : str
    n : int
        Records.
    """

    factors: dict[float, AmplitudeFactor]
    grid: tuple[float, ...]
    evaluations: int
    step: float
    ci: float
    engine: str
    n: int


def ensemble_seeds(seed: int, k: int) -> list[int]:
    """``k`` independent ensemble seeds derived from ``seed`` (SeedSequence spawning)."""
    return [int(s.generate_state(1, dtype=np.uint32)[0]) for s in np.random.SeedSequence(seed).spawn(k)]


def seed_spread(
    scenario: Scenario,
    k: int = 10,
    *,
    n: int | None = None,
    q=(25, 50, 75),
    engine: str = "housner",
    options: RunOptions | None = None,
    **execution,
) -> Table2Spread:
    """Percentiles of theta_max/alpha and the overturn fraction over ``k`` independent ensembles.

    Each ensemble has the scenario's size (or ``n``) and its own seed from
    :func:`ensemble_seeds`; ``engine`` (the analytic model by default, with the
    scenario's settings) runs them through :func:`housner.scenarios.execution.runner.run_engines`,
    so the records are cached like any run's and a failed record is left out
    and counted, not lost. The spread shows how much Table 2 of the seed paper
    would move with another draw of 100 motions.

    Parameters
    ----------
    scenario : Scenario
    k : int
        Number of ensembles.
    n : int, optional
        Motions per ensemble (default: the scenario's).
    q : sequence of float
        Percentiles [%].
    engine : str
        Engine that runs the ensembles.
    options : RunOptions, optional
        How the ensembles' records execute (:class:`~housner.scenarios.execution.options.RunOptions`:
        ``jobs``, ``cache_dir``, ``use_cache``...), as for
        :func:`housner.scenarios.execution.runner.run_engines`, without a progress bar; ``jobs``
        None (the default) means one process here: the analytic model is faster than starting workers.
    **execution
        :class:`RunOptions` fields as keywords (``jobs=2``, ``cache_dir=...``), over ``options``.

    Returns
    -------
    Table2Spread
        ``seeds``; ``percentiles`` {q: k values, inf = overturn};
        ``overturn_fraction`` (k values); ``summary`` {q: (min, median, max)};
        ``n_failed`` (records left out, over all ensembles).
    """
    opts = RunOptions.merged(options, execution, "seed_spread")
    opts = dataclasses.replace(opts, jobs=opts.jobs or 1, progress=False)
    settings = {engine: dict(scenario.engine_settings.get(engine, {}))}
    seeds = ensemble_seeds(int(scenario.seed or 0), k)
    pct: dict[int, list[float]] = {int(x): [] for x in q}
    fr = []
    n_failed = 0
    for s in seeds:
        motions, _ = build_motions(scenario, n, seed=s)
        res, _, _ = run_engines(scenario.specimen, motions, settings, opts)
        ok = res[res["status"] == "ok"]
        n_failed += len(res) - len(ok)
        v = ok["theta_max_over_alpha"].to_numpy(float)
        fr.append(float(np.mean(np.isinf(v))) if v.size else math.nan)
        for x in pct:
            pct[x].append(float(np.percentile(v, x, method="inverted_cdf")) if v.size else math.nan)
    summary = {}
    for x, vals in pct.items():
        a = np.sort(np.asarray(vals))
        summary[x] = (float(a[0]), float(np.median(a)), float(a[-1]))
    return Table2Spread(
        k=k,
        seeds=tuple(seeds),
        percentiles={x: tuple(v) for x, v in pct.items()},
        overturn_fraction=tuple(fr),
        overturn_fraction_range=(min(fr), float(np.median(fr)), max(fr)),
        summary=summary,
        inf_means="overturn",
        nan_free=all(math.isfinite(f) for f in fr),
        n_failed=n_failed,
    )


def record_against_ensemble(
    specimen,
    record,
    motions,
    S: float,
    *,
    amplitude: float = 1.0,
    engine: str = "housner",
    settings: dict | None = None,
    ensemble_values=None,
    band: tuple[float, float] = RECORD_BAND_S,
    short: tuple[float, float] = (0.1, 0.5),
    damping: float = 0.05,
    n_periods: int = 16,
) -> RecordGap:
    """The record an ensemble was fitted to, measured as one more member of it.

    The record (times ``amplitude``, as the ensemble) is compressed by sqrt(S)
    and run through ``engine`` on ``specimen``, exactly as the ensemble was;
    its theta_max/alpha is ranked among the ensemble's. The ensemble's mean
    ``damping``-damped pseudo-acceleration spectrum is compared with the
    record's at prototype scale in ``band`` (where rocking is decided) and at
    ``short`` periods. The Arias intensities (prototype scale) show whether the
    record's energy is reproduced at all.

    Parameters
    ----------
    specimen : housner.Specimen
        The block of the run (model scale).
    record : housner.GroundMotion
        The recorded motion at prototype scale, as fitted [m/s^2].
    motions : sequence of GroundMotion
        The ensemble at model scale (time compressed by sqrt(S)), amplitude included.
    S : float
        Size ratio prototype / model [-] (seed eq. 9).
    amplitude : float
        Factor applied to the ensemble's motions; the record gets the same.
    engine, settings
        Engine that gives the record's theta_max/alpha (the analytic model by default).
    ensemble_values : array_like, optional
        theta_max/alpha of the ensemble (+inf = overturn) from the run; simulated
        with ``engine`` when not given.
    band, short : (float, float)
        Prototype period ranges [s].
    damping : float
        Damping ratio of the spectra [-].
    n_periods : int
        Log-spaced periods per range.

    Returns
    -------
    RecordGap
        ``record_theta_max_over_alpha``; ``record_percentile`` (per cent of the
        ensemble strictly below the record, ties counted half); ``n_ensemble``;
        ``band_s``, ``band_periods_s``, ``band_psa_ratio`` (ensemble mean PSa /
        record PSa per period), ``band_ratio_min``/``_max``/``_mean``;
        ``short_s``, ``short_ratio_max`` and ``short_ratio_max_period_s``;
        ``omega_ratio_band`` (omega_p/p of the prototype at the band's ends);
        ``p_prototype_1_s``; ``arias_record_m_s``, ``arias_ensemble_mean_m_s``,
        ``arias_ensemble_5_95_m_s``.
    """
    motions = list(motions)
    if not motions:
        raise ValueError("`motions` is empty")
    if not (math.isfinite(S) and S > 0):
        raise ValueError(f"`S` must be positive, got {S!r}")
    rec = record.scaled(amplitude=amplitude) if amplitude != 1.0 else record
    x, v, pct = _record_rank(get_engine(engine, **(settings or {})), specimen, rec, motions, S, ensemble_values)
    return RecordGap(
        engine=engine,
        amplitude=amplitude,
        record=rec.name,
        record_theta_max_over_alpha=x,
        record_percentile=float(pct),
        n_ensemble=int(v.size),
        **_record_spectra(specimen, rec, motions, S, band, short, damping, n_periods),
    )


def _record_rank(eng, specimen, rec, motions: list, S: float, ensemble_values) -> tuple[float, np.ndarray, float]:
    """The record's theta_max/alpha (compressed by sqrt(S), through ``eng``), the ensemble's values that are
    not NaN (simulated with ``eng`` when ``ensemble_values`` is None), and the record's percentile among them
    [%] (ties counted half)."""
    x = float(eng.simulate(specimen, rec.to_model_scale(S)).theta_max_over_alpha)
    if ensemble_values is None:
        resp = eng.simulate_many(specimen, motions)
        ensemble_values = [r.theta_max_over_alpha for r in resp]
    v = np.asarray(ensemble_values, dtype=float)
    v = v[~np.isnan(v)]
    pct = 100.0 * (np.sum(v < x) + 0.5 * np.sum(v == x)) / v.size if v.size else math.nan
    return x, v, pct


def _record_spectra(
    specimen,
    rec,
    motions: list,
    S: float,
    band: tuple[float, float],
    short: tuple[float, float],
    damping: float,
    n_periods: int,
) -> dict:
    """The spectral and energy part of :func:`record_against_ensemble` (its keys from ``damping`` on): the
    ensemble's mean PSa over the record's at prototype scale in ``band`` and at ``short`` periods, the
    prototype's omega_p/p at the band's ends, and the Arias intensities [m/s]."""
    proto = [m.scaled(time=math.sqrt(S)) for m in motions]
    T_band = np.geomspace(band[0], band[1], n_periods)
    T_short = np.geomspace(short[0], short[1], n_periods)
    T = np.concatenate([T_band, T_short])
    psa, _ = ensemble_spectra(proto, T, damping)
    rec_psa, _ = response_spectrum(rec, T, damping)
    ratio = psa.mean(axis=0) / rec_psa
    rb, rs = ratio[:n_periods], ratio[n_periods:]
    k = int(np.argmax(rs))
    p_proto = specimen.p / math.sqrt(S)
    ia = np.array([arias_intensity(m) for m in proto])
    return {
        "damping": damping,
        "band_s": (float(band[0]), float(band[1])),
        "band_periods_s": tuple(T_band.tolist()),
        "band_psa_ratio": tuple(rb.tolist()),
        "band_ratio_min": float(rb.min()),
        "band_ratio_max": float(rb.max()),
        "band_ratio_mean": float(rb.mean()),
        "short_s": (float(short[0]), float(short[1])),
        "short_ratio_max": float(rs[k]),
        "short_ratio_max_period_s": float(T_short[k]),
        "p_prototype_1_s": p_proto,
        "omega_ratio_band": (2 * math.pi / (band[1] * p_proto), 2 * math.pi / (band[0] * p_proto)),
        "arias_record_m_s": float(arias_intensity(rec)),
        "arias_ensemble_mean_m_s": float(ia.mean()),
        "arias_ensemble_5_95_m_s": (float(np.percentile(ia, 5)), float(np.percentile(ia, 95))),
    }


def equivalent_amplitude(
    specimen,
    motions,
    targets: dict,
    *,
    engine: str = "housner",
    settings: dict | None = None,
    step: float = 0.02,
    max_factor: float = 8.0,
    ci: float = 0.90,
    n_boot: int = 1000,
    seed: int = 0,
) -> EquivalentAmplitudes:
    """Factors on an ensemble's accelerations at which its percentiles reach another study's values.

    How much stronger, in effect, another study's motions were than these, one
    percentile at a time. The ensemble (as run) is multiplied by factors ``a``
    on a geometric grid of ratio 1 + ``step`` and simulated with ``engine``;
    for each target percentile q the factor is the first grid point where the
    q-th percentile of theta_max/alpha reaches the target (+inf: the percentile
    overturns). The grid spans the factors needed, found first by steps of 1.25
    from 1, and one step of 1.1 beyond them. A percentile of an ensemble is
    nearly, not strictly, monotone in the amplitude (single records are not),
    so the first crossing is counted from the grid's lower end. Bootstrapping
    the records (same grid, resampled columns) gives each factor's interval:
    if one factor moved the whole distribution onto the study's, the
    intervals of the percentiles would overlap.

    Parameters
    ----------
    specimen : housner.Specimen
    motions : sequence of GroundMotion
        The ensemble as run (model scale, its amplitude included).
    targets : dict
        Percentile [%] -> theta_max/alpha to reach [-] (``inf`` for "overturn").
    engine, settings
        The engine (the analytic model by default).
    step : float
        Relative spacing of the grid of factors [-] (the factors' resolution).
    max_factor : float
        Search range [1/max_factor, max_factor]; a target out of it gets nan.
    ci : float
        Level of the bootstrap intervals.
    n_boot : int
        Bootstrap resamples of the records.
    seed : int
        Seed of the bootstrap.

    Returns
    -------
    EquivalentAmplitudes
        ``factors`` {q: AmplitudeFactor (``factor``, ``low``, ``high``, ``target``)} (nan where not reached),
        ``grid`` (the factors simulated), ``evaluations``, ``step``, ``ci``,
        ``engine``, ``n`` (records).
    """
    motions = list(motions)
    if not motions:
        raise ValueError("`motions` is empty")
    tg = _checked_targets(targets)
    values = _AmplitudeSweep(get_engine(engine, **(settings or {})), specimen, motions)
    grid = _factor_grid(tg, values, step, max_factor)
    V = np.stack([values(float(a)) for a in grid])  # (grid, records)
    V = V[:, ~np.isnan(V).any(axis=0)]  # a record that failed at any factor leaves every factor
    n = V.shape[1]
    if n == 0:
        raise ValueError("no record of `motions` gives a theta_max/alpha at every factor")
    return EquivalentAmplitudes(
        factors=_crossings(V, grid, tg, ci, n_boot, seed),
        grid=tuple(grid.tolist()),
        evaluations=len(values.cache),
        step=step,
        ci=ci,
        engine=engine,
        n=int(n),
    )


class _AmplitudeSweep:
    """theta_max/alpha of every record of an ensemble at a factor ``a`` on its accelerations, called as
    ``sweep(a)``; each factor is simulated once (``cache``: factor -> values)."""

    def __init__(self, eng, specimen, motions: list):
        self.eng, self.specimen, self.motions = eng, specimen, motions
        self.cache: dict[float, np.ndarray] = {}

    def __call__(self, a: float) -> np.ndarray:
        if a not in self.cache:
            ms = [m.scaled(amplitude=a) for m in self.motions]
            resp = self.eng.simulate_many(self.specimen, ms)
            self.cache[a] = np.array([r.theta_max_over_alpha for r in resp], dtype=float)
        return self.cache[a]


def _checked_targets(targets: dict) -> dict[float, float]:
    """``targets`` as {percentile [%]: theta_max/alpha [-]} floats, each checked (ValueError naming the bad one)."""
    tg = {}
    for q, v in targets.items():
        q, v = float(q), float(v)
        if not (0 < q < 100):
            raise ValueError(f"`targets`: percentile must lie in (0, 100), got {q!r}")
        if math.isnan(v) or v <= 0:
            raise ValueError(f"`targets`: theta_max/alpha must be positive or inf, got {v!r} at q={q:g}")
        tg[q] = v
    if not tg:
        raise ValueError("`targets` is empty")
    return tg


def _valid_percentile(v: np.ndarray, q: float) -> float:
    """The ``q``-th percentile (inverted CDF) of the values of ``v`` that are not NaN; NaN if none is."""
    v = v[~np.isnan(v)]
    return float(np.percentile(v, q, method="inverted_cdf")) if v.size else math.nan


def _factor_grid(tg: dict[float, float], values, step: float, max_factor: float) -> np.ndarray:
    """The factors to simulate: powers of 1 + ``step`` over the bracket of every target (found by steps of
    1.25 from 1 with ``values(a)``, the records' theta_max/alpha at factor a), widened by one step of 1.1."""
    lo_all, hi_all = 1.0, 1.0
    for q, t in tg.items():
        a = 1.0
        if _valid_percentile(values(a), q) >= t:
            while a > 1.0 / max_factor and _valid_percentile(values(a), q) >= t:
                a /= 1.25
            lo_all = min(lo_all, a)
        else:
            while a < max_factor and not _valid_percentile(values(a), q) >= t:
                a *= 1.25
            hi_all = max(hi_all, a)
    # one step of 1.1 beyond the bracket, so that the bootstrap's crossings are rarely cut off by the grid
    lo_all, hi_all = max(lo_all / 1.1, 1.0 / max_factor), min(hi_all * 1.1, max_factor)
    k0 = math.floor(math.log(lo_all) / math.log1p(step))
    k1 = math.ceil(math.log(hi_all) / math.log1p(step))
    return np.array([(1.0 + step) ** k for k in range(k0, k1 + 1)])


def _crossings(
    V: np.ndarray, grid: np.ndarray, tg: dict[float, float], ci: float, n_boot: int, seed: int
) -> dict[float, AmplitudeFactor]:
    """Per target percentile q: the first factor of ``grid`` where the q-th percentile of ``V`` (grid, records)
    reaches the target, and its bootstrap interval over resampled records (nan where not reached)."""

    def first_crossing(P: np.ndarray, t: float) -> np.ndarray:
        hit = P >= t
        idx = np.argmax(hit, axis=-1)
        return np.where(hit.any(axis=-1), grid[idx], np.nan)

    n = V.shape[1]
    Vb = V[:, np.random.default_rng(seed).integers(0, n, size=(n_boot, n))]  # (grid, boot, records)
    out = {}
    for q, t in tg.items():
        f = float(first_crossing(np.percentile(V, q, axis=1, method="inverted_cdf"), t))
        fb = first_crossing(np.percentile(Vb, q, axis=2, method="inverted_cdf").T, t)
        fb = np.where(np.isnan(fb), np.inf, fb)  # not reached on the grid: above it
        fb = np.sort(fb)  # order statistics: the interval's ends are bootstrap values, never interpolated
        lo, hi = fb[int((1 - ci) / 2 * fb.size)], fb[min(math.ceil((1 + ci) / 2 * fb.size) - 1, fb.size - 1)]
        lo, hi = (float(x) if math.isfinite(x) else math.nan for x in (lo, hi))
        out[q] = AmplitudeFactor(factor=f, low=float(lo), high=float(hi), target=t)
    return out
