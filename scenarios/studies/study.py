"""Studies: one ensemble at intensity stripes and structure sizes, on every engine, to fragility curves.

A scenario with a ``[study]`` table is a study: each (size, stripe, motion) is one record, run on every
engine through the shared runner (:func:`housner.scenarios.execution.runner.run_engines`: its cache, process
pool or Dask cluster, fault tolerance), one size after another so that memory stays flat; the sizes stretch
the motions in time by sqrt(S0 / S), and a stripe scales them by an amplitude factor or to a dimensionless
intensity measure (``pga``, ``pgv``, ``sa``). The analysis (lognormal fragility by maximum likelihood,
Baker 2015, with bootstrap intervals) is :mod:`housner.scenarios.studies.fragility`'s. This module owns the
study directory: ``results.parquet`` (every record), ``fragility.parquet``, ``exceedance.parquet``,
``fragility.json``, ``study.json`` (and ``report.html``, written by :mod:`housner.reports.study.page`). The
table is in ``docs/reference/scenario-file.md`` ("[study]"); how the sizes and stripes scale, and how to run
and read a study, in ``docs/how-to/studies.md``.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa

from housner._values import JsonValue
from housner.errors import DataFileError
from housner.motion import GroundMotion
from housner.scenarios.catalogue.scenario import Scenario, load_scenario
from housner.scenarios.catalogue.study_table import Study
from housner.scenarios.execution.options import RunOptions
from housner.scenarios.execution.outputs import check_output_dir
from housner.scenarios.execution.run_meta import EngineFacts, Provenance, ScenarioCopy, SpecimenFacts
from housner.scenarios.execution.rundir import OUTCOME_COLUMNS, jsonable
from housner.scenarios.execution.runner import run_engines
from housner.scenarios.execution.workers import Progress
from housner.scenarios.motions.build import MotionFacts, build_motions
from housner.scenarios.motions.elastic import response_spectrum
from housner.scenarios.studies.fragility import (
    bootstrap_fit,
    compare_fits,
    exceedance,
    proportion_intervals,
    stripe_counts,
)
from housner.scenarios.studies.study_fits import StudyComparison, StudyFit, StudyFits
from housner.units import G

__all__ = [
    "STUDY_FILES",
    "StudyMeta",
    "StudyResult",
    "StudySettings",
    "intensity_measure",
    "load_study",
    "compare_ci",
    "run_study",
    "study_motions",
]

#: The files of a study directory, owned by this module (the report is written by housner.reports.study.page).
STUDY_FILES = (
    "results.parquet",
    "fragility.parquet",
    "exceedance.parquet",
    "fragility.json",
    "study.json",
    "report.html",
)
RESULTS_FILE, FRAGILITY_FILE, EXCEEDANCE_FILE, FITS_FILE, STUDY_FILE, REPORT_FILE = STUDY_FILES

#: Columns of results.parquet.
RESULT_COLUMNS = [
    "engine",
    "size",
    "S",
    "stripe",
    "intensity",
    "motion_id",
    "motion_name",
    "amplitude_factor",
    *OUTCOME_COLUMNS,
]


# --------------------------------------------------------------------------
def intensity_measure(motion: GroundMotion, kind: str, specimen, period: float | None = None) -> float:
    """A model-scale motion's dimensionless intensity [-] (see the module notes).

    Parameters
    ----------
    motion : GroundMotion
        At model scale.
    kind : {"pga", "pgv", "sa"}
    specimen : Specimen
        alpha [rad] and p [1/s].
    period : float, optional
        T [s] at model scale for "sa".
    """
    a = np.asarray(motion.acc, dtype=float)
    g_tan = G * math.tan(specimen.alpha)
    if kind == "pga":
        return float(np.max(np.abs(a))) / g_tan
    if kind == "pgv":
        v = np.concatenate(([0.0], np.cumsum(0.5 * (a[1:] + a[:-1]) * motion.dt)))  # exact for linear ug''
        return float(np.max(np.abs(v))) * specimen.frequency_parameter / g_tan
    if kind == "sa":
        psa, _ = response_spectrum(motion, [period], 0.05)
        return float(psa[0]) / g_tan
    raise ValueError(f"`kind` must be one of pga, pgv, sa, got {kind!r}")


def study_motions(study: Study, base: list[GroundMotion], S0: float, size: int, specimen) -> tuple[list, np.ndarray]:
    """The records of one size: every stripe of every motion, stripe-major.

    Parameters
    ----------
    study : Study
    base : list of GroundMotion
        The scenario's motions at model scale for its own size ratio ``S0``.
    S0 : float
        The size ratio [-] ``base`` was built for.
    size : int
        Index into ``study.S``.
    specimen : Specimen

    Returns
    -------
    motions : list of GroundMotion
        Record ``j * len(base) + i`` is motion i at stripe j.
    factors : ndarray
        (stripes, motions) amplitude factors applied [-].
    """
    S = study.S[size]
    stretch = math.sqrt(S0 / S)
    at_size = [m.scaled(time=stretch) if stretch != 1.0 else m for m in base]
    levels = np.asarray(study.levels)
    if study.intensity == "amplitude":
        factors = np.repeat(levels[:, None], len(base), axis=1)
    else:
        period = study.period / math.sqrt(S) if study.period is not None else None
        im = np.array([intensity_measure(m, study.intensity, specimen, period) for m in at_size])
        if not np.all(im > 0):
            bad = int(np.flatnonzero(~(im > 0))[0])
            raise ValueError(f"motion {base[bad].name!r} has no {study.intensity} (zero): it cannot be scaled")
        factors = levels[:, None] / im[None, :]
    out = []
    for j in range(len(levels)):
        for i, m in enumerate(at_size):
            f = float(factors[j, i])
            out.append(m.scaled(amplitude=f, name=f"{base[i].name} S={S:g} x{f:.4g}"))
    return out, factors


# --------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class StudySettings(JsonValue):
    """The [study] table as run (``Study.describe()``), with the motions, the reference and the comparisons' level.

    Attributes
    ----------
    intensity : str or None
        ``amplitude``, ``pga``, ``pgv`` or ``sa``.
    intensity_label : str or None
        The intensity measure in words, with its unit.
    levels : tuple of float
        The stripes' intensities.
    S, prototype_heights : tuple of float
        The sizes: scale factors [-] and prototype heights [m].
    thresholds : tuple of float
        theta_max / alpha levels of the exceedance curves [-].
    period : float or None
        T of ``sa`` at prototype scale [s] (None for another measure).
    n_boot : int or None
        Bootstrap resamples.
    seed : int or None
        Seed of the bootstrap.
    histories : bool or None
        Whether theta histories were kept.
    ci : float or None
        Level of the fits' intervals [-].
    n_motions : int or None
        Ground motions per stripe.
    reference : str or None
        The engine the others are compared with.
    compare_ci : float or None
        Level of each of the two intervals of an engine comparison [-] (:func:`compare_ci`).
    """

    intensity: str | None = None
    intensity_label: str | None = None
    levels: tuple[float, ...] = ()
    S: tuple[float, ...] = ()
    prototype_heights: tuple[float, ...] = ()
    thresholds: tuple[float, ...] = ()
    period: float | None = None
    n_boot: int | None = None
    seed: int | None = None
    histories: bool | None = None
    ci: float | None = None
    n_motions: int | None = None
    reference: str | None = None
    compare_ci: float | None = None
    extra: dict = field(default_factory=dict)

    _ALWAYS = ("period",)


@dataclass(frozen=True, eq=False)
class StudyMeta(JsonValue):
    """A study's metadata: what study.json holds, one field per key.

    :func:`write_study` writes it (:meth:`to_json`, the keys in the order of the fields) and
    :func:`load_study` reads it back (:meth:`from_json`, that of an earlier version too: a key it
    lacks takes its field's default, a key this version does not know is kept in ``extra``).

    Attributes
    ----------
    scenario : ScenarioCopy
        The scenario as run (``Scenario.describe()``).
    specimen : SpecimenFacts
        The specimen's geometry and derived figures (``Specimen.describe()``).
    motions : MotionFacts
        Facts of the scenario's ground motions (``build_motions``), at its own size ratio.
    study : StudySettings
        The [study] table as run (``Study.describe()``) with ``n_motions``, ``reference`` and
        ``compare_ci`` (the level of each interval of an engine comparison).
    engines : dict of EngineFacts
        Engine -> ``settings``, ``version``, ``wall_s`` [s] summed over the sizes, ``cached``,
        ``worker_deaths``.
    n_records : int or None
        Records run (None: not stated).
    n_failed : int or None
        Records failed (None: not stated).
    wall_s : float or None
        Wall time of the study [s] (None: not stated).
    provenance : Provenance
        Versions, git commit, platform, CPUs and the creation time.
    extra : dict
        Keys of study.json this version does not know, as read.
    """

    scenario: ScenarioCopy = field(default_factory=ScenarioCopy)
    specimen: SpecimenFacts = field(default_factory=SpecimenFacts)
    motions: MotionFacts = field(default_factory=MotionFacts)
    study: StudySettings = field(default_factory=StudySettings)
    engines: dict[str, EngineFacts] = field(default_factory=dict)
    n_records: int | None = None
    n_failed: int | None = None
    wall_s: float | None = None
    provenance: Provenance = field(default_factory=Provenance)
    extra: dict = field(default_factory=dict)

    @property
    def reference(self) -> str | None:
        """The engine the study compares the others with (None when study.json does not say)."""
        return self.study.reference


@dataclass
class StudyResult:
    """What :func:`run_study` returns (and :func:`load_study` reads back).

    Attributes
    ----------
    results : DataFrame
        One row per (engine, size, stripe, motion): :data:`RESULT_COLUMNS`.
    fragility : DataFrame
        Per (engine, size, stripe): engine, size [m], S, stripe, intensity, n, n_overturned, p, p_low, p_high.
    exceedance : DataFrame
        Per (engine, size, stripe, threshold): ..., threshold, n, k, p, p_low, p_high.
    fits : list of StudyFit
        Per (engine, size): median, beta and their intervals, status, message.
    comparisons : list of StudyComparison
        Per (engine, size) against the reference: median ratio, beta difference, intervals, disagree.
    meta : StudyMeta
        study.json.
    out : Path or None
        The study directory.
    """

    results: pd.DataFrame
    fragility: pd.DataFrame
    exceedance: pd.DataFrame
    fits: list[StudyFit]
    comparisons: list[StudyComparison]
    meta: StudyMeta
    out: Path | None = None
    histories: dict = field(default_factory=dict, repr=False)

    def fit(self, engine: str, size: float | None = None) -> StudyFit:
        """The fit of ``engine`` at prototype height ``size`` [m] (the only size when omitted)."""
        return _pick(self.fits, engine, size, "fit")

    def comparison(self, engine: str, size: float | None = None) -> StudyComparison:
        """The comparison of ``engine`` with the reference at prototype height ``size`` [m]."""
        return _pick(self.comparisons, engine, size, "comparison")


def _pick(rows: list, engine: str, size: float | None, what: str):
    mine = [r for r in rows if r.engine == engine]
    if not mine:
        have = sorted({r.engine for r in rows})
        raise ValueError(f"no {what} for engine {engine!r} (engines: {', '.join(have) or 'none'})")
    sizes = sorted({r.size for r in mine})
    if size is None:
        if len(sizes) > 1:
            raise ValueError(f"`size` is needed: the study has prototype heights {sizes} m")
        return mine[0]
    hit = [r for r in mine if math.isclose(r.size, float(size), rel_tol=1e-9)]
    if not hit:
        raise ValueError(f"no {what} for engine {engine!r} at size {size!r} m (sizes: {sizes})")
    return hit[0]


def run_study(
    scenario,
    *,
    engines: list[str] | None = None,
    n_motions: int | None = None,
    seed: int | None = None,
    out: str | Path | None = None,
    options: RunOptions | None = None,
    **execution: Any,
) -> StudyResult:
    """Run a scenario's ``[study]``: every (engine, size, stripe, motion), then the fragility analysis.

    Parameters
    ----------
    scenario : Scenario or str or Path
        A loaded scenario with a ``[study]`` table, a catalogue name or a TOML file.
    engines, n_motions, seed, out, options, **execution
        As :func:`housner.scenarios.runs.run.run_scenario`; ``out`` defaults to ``runs/<scenario>``. The
        sizes run one after another under one progress bar, on the same worker processes.

    Returns
    -------
    StudyResult
        Also written to ``out`` (see the module notes).
    """
    opts = RunOptions.merged(options, execution, "run_study")
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(scenario)
    study = scenario.study
    if study is None:
        raise ValueError(f"scenario {scenario.name!r} has no [study] table")
    names = list(engines) if engines else list(scenario.engines)
    scenario.check_engines(names)
    out = Path(out) if out else Path("runs") / scenario.name
    check_output_dir(out, "study directory", files=STUDY_FILES)
    t0 = time.perf_counter()
    base, mmeta = build_motions(scenario, n_motions, seed=seed)
    n = len(base)
    eng_settings = {e: dict(scenario.engine_settings.get(e, {})) for e in names}
    results, info, hist = _run_sizes(scenario, base, eng_settings, opts)
    reference = str(scenario.analysis.get("reference", "housner"))
    analysis = analyse(results, study, names, reference)
    meta = StudyMeta(
        scenario=ScenarioCopy(scenario.describe()),
        specimen=SpecimenFacts.from_json(scenario.specimen.describe()),
        motions=MotionFacts.from_json(mmeta),
        study=StudySettings.from_json(
            {**study.describe(), "n_motions": n, "reference": reference, "compare_ci": compare_ci(study.ci)}
        ),
        engines={e: EngineFacts.from_json(v) for e, v in info.items()},
        n_records=int(len(results)),
        n_failed=int((results["status"] != "ok").sum()),
        wall_s=time.perf_counter() - t0,
        provenance=Provenance.current(),
    )
    result = StudyResult(
        results,
        analysis["fragility"],
        analysis["exceedance"],
        analysis["fits"],
        analysis["comparisons"],
        meta,
        out,
        hist,
    )
    write_study(out, result)
    return result


def _run_sizes(scenario: Scenario, base: list[GroundMotion], eng_settings: dict, opts: RunOptions) -> tuple:
    """Every record of a study, one size after another under one progress bar.

    Returns
    -------
    results : DataFrame
        One row per (engine, size, stripe, motion): :data:`RESULT_COLUMNS`.
    info : dict
        Engine -> settings, version, and wall time [s], cached records and worker deaths summed over the sizes.
    histories : dict
        (engine, size index, record) -> theta [rad], when the study keeps histories.
    """
    study, n = scenario.study, len(base)
    total = len(eng_settings) * n * len(study.levels) * len(study.S)
    where = "in this process" if opts.jobs == 1 else "worker processes"
    how = "on the Dask cluster" if opts.scheduler is not None else where
    bar = Progress(total, opts.progress, f"{len(study.S)} sizes x {len(study.levels)} stripes x {n} motions, {how}")
    parts, info, hist = [], {}, {}
    try:
        for k, S in enumerate(study.S):
            motions, factors = study_motions(study, base, scenario.S, k, scenario.specimen)
            res, h, inf = run_engines(
                scenario.specimen,
                motions,
                eng_settings,
                opts.replace(progress=bar),
                effects=scenario.effects,
                histories=study.histories,
            )
            idx = res["motion_id"].to_numpy()
            stripe, motion_id = idx // n, idx % n
            parts.append(
                res.assign(
                    size=study.prototype_heights[k],
                    S=S,
                    stripe=stripe,
                    intensity=np.asarray(study.levels)[stripe],
                    motion_id=motion_id,
                    motion_name=[base[i].name for i in motion_id],
                    amplitude_factor=factors[stripe, motion_id],
                )[RESULT_COLUMNS]
            )
            _add_engine_info(info, inf)
            if study.histories:
                hist.update({(e, k, i): th for (e, i), th in h.items()})
            del motions, res, h
    finally:
        bar.close()
    return pd.concat(parts, ignore_index=True), info, hist


def _add_engine_info(info: dict, size_info: dict) -> None:
    """Add one size's engine facts (the runner's) to the study's: settings and version, times and counts summed."""
    for e, v in size_info.items():
        tot = info.setdefault(
            e, {"settings": v["settings"], "version": v["version"], "wall_s": 0.0, "cached": 0, "worker_deaths": 0}
        )
        tot["wall_s"] += v["wall_s"]
        tot["cached"] += v["cached"]
        tot["worker_deaths"] += v.get("worker_deaths", 0)


def _matrices(results: pd.DataFrame, engine: str, size: float, n_stripes: int) -> tuple[np.ndarray, np.ndarray]:
    """(motions, stripes) theta_max / alpha (inf: overturned, NaN: failed) and the valid mask of one engine and size."""
    d = results[(results["engine"] == engine) & (results["size"] == size)]
    n = int(d["motion_id"].max()) + 1 if len(d) else 0
    th = np.full((n, n_stripes), np.nan)
    ok = (d["status"] == "ok").to_numpy()
    v = np.where(d["overturned"].to_numpy(bool), np.inf, d["theta_max_over_alpha"].to_numpy(float))
    th[d["motion_id"].to_numpy()[ok], d["stripe"].to_numpy()[ok]] = v[ok]
    return th, ~np.isnan(th)


#: The numbers of a fit (NaN when there is none).
_FIT_NUMBERS = ("median", "median_low", "median_high", "beta", "beta_low", "beta_high")


def _caveat(fit, im: np.ndarray) -> str:
    """What a reader must know of an ok fit: a median outside the stripes is an extrapolation ("" if none)."""
    if fit.status != "ok" or not math.isfinite(fit.median):
        return ""
    if fit.median > im.max() or fit.median < im.min():
        side = "above the highest" if fit.median > im.max() else "below the lowest"
        return (
            f"the median {fit.median:.3g} lies {side} stripe ({im.min():g}-{im.max():g}): it is extrapolated "
            "by the lognormal shape, not bracketed by data; add stripes there"
        )
    return ""


def compare_ci(ci: float) -> float:
    """Confidence level of each of the two intervals (median ratio, beta difference) of an engine comparison."""
    return 1.0 - 0.5 * (1.0 - ci)


def analyse(results: pd.DataFrame, study: Study, engines: list[str], reference: str) -> dict:
    """The fragility analysis of a study's records (see the module notes).

    Returns
    -------
    dict
        ``fragility`` and ``exceedance`` (DataFrames), ``fits`` (list of :class:`StudyFit`) and ``comparisons``
        (list of :class:`StudyComparison`).
    """
    im = np.asarray(study.levels, dtype=float)
    frag, exc, fits, comps = [], [], [], []
    for size, S in zip(study.prototype_heights, study.S, strict=True):
        mats = {e: _matrices(results, e, size, len(im)) for e in engines}
        for e in engines:
            th, valid = mats[e]
            over = np.isinf(th)
            n, k = stripe_counts(over, valid)
            p, lo, hi = proportion_intervals(k, n, study.ci)
            frag.append(
                pd.DataFrame(
                    {
                        "engine": e,
                        "size": size,
                        "S": S,
                        "stripe": np.arange(len(im)),
                        "intensity": im,
                        "n": n,
                        "n_overturned": k,
                        "p": p,
                        "p_low": lo,
                        "p_high": hi,
                    }
                )
            )
            ex = exceedance(th, study.thresholds, valid, study.ci)
            exc.append(ex.assign(engine=e, size=size, S=S, intensity=im[ex["stripe"].to_numpy()]))
            if not valid.any():  # every record of this engine and size failed: nothing to fit
                fits.append(
                    StudyFit(
                        engine=e,
                        size=size,
                        S=S,
                        **dict.fromkeys(_FIT_NUMBERS, math.nan),
                        status="no_data",
                        message="no valid record at any stripe (every record failed)",
                        n_boot=0,
                        n_failed=0,
                    )
                )
                continue
            b = bootstrap_fit(im, over, valid, n_boot=study.n_boot, seed=study.seed, ci=study.ci)
            fits.append(
                StudyFit(
                    engine=e,
                    size=size,
                    S=S,
                    median=b.fit.median,
                    median_low=b.median_low,
                    median_high=b.median_high,
                    beta=b.fit.beta,
                    beta_low=b.beta_low,
                    beta_high=b.beta_high,
                    status=b.fit.status,
                    message=b.fit.message,
                    n_boot=b.n_boot,
                    n_failed=b.n_failed,
                    caveat=_caveat(b.fit, im),
                )
            )
        if reference in mats:
            th_r, valid_r = mats[reference]
            for e in engines:
                if e == reference:
                    continue
                th, valid = mats[e]
                if th.shape != th_r.shape or not valid.any() or not valid_r.any():
                    continue  # no records on one side (or not the same motions): no paired comparison
                # two intervals decide "disagree": each at 1 - (1 - ci) / 2 (Bonferroni), so that agreeing
                # engines are called different at most 1 - ci of the time (at ci each: 14 % measured, not 5 %)
                c = compare_fits(
                    im,
                    np.isinf(th),
                    np.isinf(th_r),
                    valid,
                    valid_r,
                    n_boot=study.n_boot,
                    seed=study.seed,
                    ci=compare_ci(study.ci),
                )
                comps.append(StudyComparison.of(c, e, reference, size, S))
    ex_cols = ["engine", "size", "S", "stripe", "intensity", "threshold", "n", "k", "p", "p_low", "p_high"]
    return {
        "fragility": pd.concat(frag, ignore_index=True),
        "exceedance": pd.concat(exc, ignore_index=True)[ex_cols],
        "fits": fits,
        "comparisons": comps,
    }


# --------------------------------------------------------------------------
def _plain(x: Any) -> Any:
    """JSON data with NaN / inf written as null / "inf" strings (JSON has neither)."""
    return jsonable(x, nonfinite="null")


def write_study(out: Path, result: StudyResult) -> None:
    """Write a study directory (results, fragility, exceedance, fits, meta) and its report."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    result.results.to_parquet(out / RESULTS_FILE, index=False)
    result.fragility.to_parquet(out / FRAGILITY_FILE, index=False)
    result.exceedance.to_parquet(out / EXCEEDANCE_FILE, index=False)
    fits = StudyFits(tuple(result.fits), tuple(result.comparisons))
    (out / FITS_FILE).write_text(json.dumps(_plain(fits.to_json()), indent=1))
    (out / STUDY_FILE).write_text(json.dumps(_plain(result.meta.to_json()), indent=1))


def load_study(path: str | Path) -> StudyResult:
    """Read a study directory written by :func:`run_study`.

    Raises
    ------
    ValueError
        Naming the directory and the file that is missing.
    DataFileError
        Naming a study file that cannot be read (corrupt JSON or parquet).
    """
    out = Path(path)
    for name in STUDY_FILES[:-1]:
        if not (out / name).is_file():
            raise ValueError(f"{out}: not a study directory (no {name}; run `housner run` on a scenario with [study])")

    def read(name: str, how):
        try:
            return how(out / name)
        except (OSError, ValueError, KeyError, pa.ArrowException) as e:  # JSONDecodeError is a ValueError
            first = (str(e).splitlines() or [type(e).__name__])[0]
            raise DataFileError(out / name, f"cannot read this study file ({first}); run the study again") from None

    data = read(FITS_FILE, lambda p: json.loads(p.read_text()))
    if not (isinstance(data, dict) and {"fits", "comparisons"} <= set(data)):
        raise DataFileError(out / FITS_FILE, "is not a study's fits (no 'fits' and 'comparisons'); run the study again")
    fits = StudyFits.from_json(data)
    return StudyResult(
        results=read(RESULTS_FILE, pd.read_parquet),
        fragility=read(FRAGILITY_FILE, pd.read_parquet),
        exceedance=read(EXCEEDANCE_FILE, pd.read_parquet),
        fits=list(fits.fits),
        comparisons=list(fits.comparisons),
        meta=StudyMeta.from_json(read(STUDY_FILE, lambda p: json.loads(p.read_text()))),
        out=out,
    )
