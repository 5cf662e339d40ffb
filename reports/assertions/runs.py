"""Tolerance assertions on engine results, for users' pytest suites and CI.

Typical use, in a test file of the user's project::

    from housner.reports.assertions.runs import assert_cdf_agreement

    def test_mujoco_matches_housner(housner_results):  # fixture of housner.reports.pytest_plugin
        assert_cdf_agreement(housner_results, "mujoco", "housner", ks_max=0.15, percentiles={50: 0.1})

On failure the message lists every criterion that was checked, passed or not,
with both engines' figures, the threshold and the margin, and points to the
HTML report of the run when there is one next to the results.

Figures are theta_max/alpha [-] (+inf for an overturn), probabilities [-] and
distances in units of alpha; see :mod:`housner.statistics.ensemble_stats` for the definitions.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from housner.errors import unknown_choice
from housner.reports.assertions.criteria import (
    SHOW_FAILED,
    AgreementReport,
    CDFAgreementError,
    Criterion,
    RecordAgreementError,
    check_count,
    check_percentiles,
    check_tol,
    criterion_fields,
    fmt_value,
    limit_text,
    shorten,
)
from housner.scenarios.execution.rundir import REPORT_FILE, RESULTS_FILE, load_results
from housner.scenarios.execution.tables import split_failed
from housner.statistics import ensemble_stats as stats
from housner.statistics import proportions
from housner.statistics.ensemble_stats import KS_MAX, OVERTURN_TOL

__all__ = ["assert_cdf_agreement", "assert_record_agreement"]


# ----------------------------------------------------------------------------
# outcome of a check


# ----------------------------------------------------------------------------
# shared plumbing
@dataclass
class _Sides:
    engine: str
    reference: str
    ok: pd.DataFrame
    failed: pd.DataFrame
    a: np.ndarray  # theta_max/alpha of the engine, usable records
    b: np.ndarray  # of the reference
    source: str | None
    report: Path | None


def _prepare(results, engine: str, reference: str, report) -> _Sides:
    source = None
    if isinstance(results, (str, Path)):
        results = load_results(results)
    elif isinstance(getattr(results, "results", None), pd.DataFrame):  # the runner's RunResult
        out = getattr(results, "out", None)
        source = str(Path(out).resolve() / RESULTS_FILE) if out is not None else None
        results = results.results
    if not isinstance(results, pd.DataFrame):
        raise ValueError(
            "`results` must be a results DataFrame, a run directory, a results.parquet path or the runner's "
            f"RunResult, got {type(results)}"
        )
    source = results.attrs.get("source") or source
    for name, value in (("engine", engine), ("reference", reference)):
        if not isinstance(value, str) or not value:
            raise ValueError(f"`{name}` must be an engine name, got {value!r}")
    if engine == reference:
        raise ValueError(f"`engine` and `reference` are both {engine!r}; compare two different engines")
    ok, failed = split_failed(results)
    names = sorted(set(results["engine"].astype(str)))
    for kind, value in (("engine", engine), ("reference engine", reference)):
        if value not in names:
            raise unknown_choice(kind, value, names)
    mine = results["engine"].astype(str).isin([engine, reference])
    dup = results.loc[mine].duplicated(["engine", "motion_id"])
    if dup.any():
        row = results.loc[mine].loc[dup].iloc[0]
        raise ValueError(
            f"`results` has more than one row for engine {row['engine']!r} and motion_id {row['motion_id']}; "
            "select one scenario and one set of effects first (e.g. df[df['scenario'] == ...])"
        )
    if report is not None:
        report = Path(report)
    elif source:
        candidate = Path(source).parent / REPORT_FILE
        report = candidate if candidate.is_file() else None
    a = ok.loc[ok["engine"].astype(str) == engine, "theta_max_over_alpha"].to_numpy(np.float64)
    b = ok.loc[ok["engine"].astype(str) == reference, "theta_max_over_alpha"].to_numpy(np.float64)
    return _Sides(engine, reference, ok, failed, a, b, source, report)


def _record_criteria(s: _Sides, min_records: int | None, max_failed: int | None) -> list[Criterion]:
    out = []
    na, nb = s.a.size, s.b.size
    if min_records is not None:
        short = max(min_records - na, min_records - nb)
        out.append(
            Criterion(
                "usable records",
                short <= 0,
                f"{s.engine} {na}, {s.reference} {nb}; need >= {min_records} each"
                + (f"; short by {short}" if short > 0 else ""),
                float(min(na, nb)),
                float(min_records),
                float(short),
            )
        )
    if max_failed is not None:
        parts, worst = [], 0
        for name in (s.engine, s.reference):
            rows = s.failed[s.failed["engine"].astype(str) == name]
            worst = max(worst, len(rows))
            text = f"{name} {len(rows)}"
            if len(rows):
                label = rows["motion_name"] if "motion_name" in rows.columns else rows["motion_id"]
                errors = rows["error"] if "error" in rows.columns else [""] * len(rows)
                shown = [f"{m}{': ' + shorten(e) if str(e) else ''}" for m, e in zip(label, errors, strict=True)]
                shown = shown[:SHOW_FAILED]
                more = f", and {len(rows) - SHOW_FAILED} more" if len(rows) > SHOW_FAILED else ""
                text += f" ({'; '.join(shown)}{more})"
            parts.append(text)
        excess = worst - max_failed
        out.append(
            Criterion(
                "failed runs",
                excess <= 0,
                ", ".join(parts)
                + f"; allowed <= {max_failed} each"
                + (f"; {excess} too many (failed runs are left out of the statistics)" if excess > 0 else ""),
                float(worst),
                float(max_failed),
                float(excess),
            )
        )
    return out


def _not_evaluated(name: str, s: _Sides, threshold: float) -> Criterion:
    return Criterion(
        name,
        False,
        f"not evaluated: no usable records ({s.engine} {s.a.size}, {s.reference} {s.b.size})",
        math.nan,
        threshold,
        math.inf,
    )


# ----------------------------------------------------------------------------
# the assertions
def assert_cdf_agreement(
    results,
    engine: str = "mujoco",
    reference: str = "housner",
    *,
    ks_max: float | None = KS_MAX,
    overturn_tol: float | None = OVERTURN_TOL,
    percentiles: Mapping[float, float] | None = None,
    wasserstein_max: float | None = None,
    min_records: int | None = 20,
    max_failed: int | None = 0,
    report: str | Path | None = None,
) -> AgreementReport:
    """Assert that an engine's distribution of theta_max/alpha agrees with a reference's.

    Parameters
    ----------
    results : pandas.DataFrame, str, pathlib.Path or housner.scenarios.runs.run.RunResult
        The results table, a run directory / ``results.parquet`` to load
        with :func:`load_results`, or what the runner returned.
    engine, reference : str
        Engine under test and the engine (or experiment) it must match.
    ks_max : float or None
        Largest allowed Kolmogorov-Smirnov distance between the two CDFs of
        theta_max/alpha [-], overturns included as +inf (see
        :func:`housner.statistics.ensemble_stats.ks_2samp`). None skips the criterion.
    overturn_tol : float or None
        Largest allowed |P_engine[overturn] - P_reference[overturn]| [-].
    percentiles : mapping of float to float, optional
        Percentile level [%] -> absolute tolerance on theta_max/alpha [-] at
        that percentile, e.g. ``{50: 0.1}``. Both sides overturning at that
        level passes; only one side overturning fails.
    wasserstein_max : float or None
        Largest allowed W1 distance between the non-overturned parts [alpha]
        (see :func:`housner.statistics.ensemble_stats.wasserstein`).
    min_records : int or None
        Fewest usable (non-failed) records each side must have.
    max_failed : int or None
        Most failed runs allowed on each side (failed runs are left out of
        every statistic, so silently ignoring them would flatter an engine).
    report : str or pathlib.Path, optional
        HTML report to point to in the message; by default ``report.html``
        next to the results file when it exists.

    Returns
    -------
    AgreementReport
        Every criterion with its figures, when all pass.

    Raises
    ------
    CDFAgreementError
        (an ``AssertionError``) when any criterion fails; its message lists
        every criterion checked, passed or failed.
    ValueError
        For an unknown engine, a bad tolerance, or a table with several rows
        per engine and motion.

    Notes
    -----
    Sampling noise: for two independent samples of n records each from one
    distribution, D exceeds 1.36 sqrt(2/n) with probability 0.05 (0.19 for
    n = 100), so ``ks_max`` = 0.15 is demanding for 100 records unless the
    engines agree record by record. The KS p-value is printed to help judge.

    References
    ----------
    Bachmann et al. (2017), Sec. 6: models are judged by the statistics of
    the response to an ensemble, not record by record.
    """
    __tracebackhide__ = True
    levels = _check_cdf_arguments(ks_max, overturn_tol, wasserstein_max, min_records, max_failed, percentiles)
    s = _prepare(results, engine, reference, report)
    criteria = _record_criteria(s, min_records, max_failed)
    criteria += _distribution_criteria(s, ks_max, overturn_tol, levels, wasserstein_max)
    title = f"CDF agreement of {engine!r} with {reference!r}"
    result = AgreementReport(title, tuple(criteria), s.source, s.report, _notes(s))
    if not result.passed:
        raise CDFAgreementError(result)
    return result


def assert_record_agreement(
    results,
    engine: str = "mujoco",
    reference: str = "housner",
    *,
    rtol: float = 0.1,
    atol: float = 0.05,
    min_share: float | None = 0.8,
    min_verdict_share: float | None = None,
    min_records: int | None = 20,
    max_failed: int | None = 0,
    report: str | Path | None = None,
    show: int = 5,
) -> AgreementReport:
    """Assert that two engines agree record by record on the same motions.

    Parameters
    ----------
    results : pandas.DataFrame, str, pathlib.Path or housner.scenarios.runs.run.RunResult
        The results table or where to load it from.
    engine, reference : str
        The engines compared; records are paired by ``motion_id``.
    rtol, atol : float
        A record agrees when both overturned, or neither did and
        |a - b| <= atol + rtol |b| on theta_max/alpha (b: the reference) [-].
    min_share : float or None
        Smallest allowed share of records in agreement [-].
    min_verdict_share : float or None
        Smallest allowed share of records with the same overturn verdict [-].
    min_records, max_failed, report
        As in :func:`assert_cdf_agreement`; ``min_records`` counts paired records.
    show : int
        How many of the worst disagreeing records the message names.

    Returns
    -------
    AgreementReport

    Raises
    ------
    RecordAgreementError
        (an ``AssertionError``) when a criterion fails.

    Notes
    -----
    Rocking is sensitive to small perturbations (Bachmann et al. 2017,
    Fig. 9): even a well-calibrated model can miss single records, so keep
    this for engines expected to reproduce the reference closely (e.g. the
    same model integrated two ways).
    """
    __tracebackhide__ = True
    check_tol("rtol", rtol, allow_none=False)
    check_tol("atol", atol, allow_none=False)
    for name, v in (("min_share", min_share), ("min_verdict_share", min_verdict_share)):
        if v is not None and not (isinstance(v, (int, float, np.floating)) and 0.0 <= v <= 1.0):
            raise ValueError(f"`{name}` must be a share in [0, 1] or None, got {v!r}")
    check_count("min_records", min_records)
    check_count("max_failed", max_failed)
    check_count("show", show)
    s = _prepare(results, engine, reference, report)
    sub = s.ok[s.ok["engine"].astype(str).isin([engine, reference])]
    wide = sub.pivot(index="motion_id", columns="engine", values="theta_max_over_alpha")
    wide = wide.reindex(columns=[engine, reference]).dropna()
    a, b = wide[engine].to_numpy(np.float64), wide[reference].to_numpy(np.float64)
    # min_records here counts records both engines ran successfully.
    paired = _Sides(engine, reference, s.ok, s.failed, a, b, s.source, s.report)
    criteria = _record_criteria(paired, min_records, max_failed)
    if criteria and criteria[0].name == "usable records":
        criteria[0] = Criterion("paired records", *criterion_fields(criteria[0]))
    agreement = stats.per_record_agreement(a, b, rtol=rtol, atol=atol)
    criteria += _share_criteria(agreement, atol, rtol, min_share, min_verdict_share)
    notes = _worst_records(paired, wide, agreement, atol, rtol, show)
    result = AgreementReport(
        f"Record-by-record agreement of {engine!r} with {reference!r}", tuple(criteria), s.source, s.report, notes
    )
    if not result.passed:
        raise RecordAgreementError(result)
    return result


# ----------------------------------------------------------------------------
# criteria
def _check_cdf_arguments(ks_max, overturn_tol, wasserstein_max, min_records, max_failed, percentiles) -> list:
    """Refuse a bad tolerance or count of :func:`assert_cdf_agreement` (ValueError); the percentile levels checked."""
    for name, tol in (("ks_max", ks_max), ("overturn_tol", overturn_tol), ("wasserstein_max", wasserstein_max)):
        check_tol(name, tol)
    check_count("min_records", min_records)
    check_count("max_failed", max_failed)
    return check_percentiles(percentiles)


def _distribution_criteria(s: _Sides, ks_max, overturn_tol, levels, wasserstein_max) -> list[Criterion]:
    """The criteria of :func:`assert_cdf_agreement` on the two distributions (those given a tolerance), each
    "not evaluated" where a side has no usable record."""
    have = s.a.size > 0 and s.b.size > 0
    out = []
    if ks_max is not None:
        out.append(_ks_criterion(s, ks_max) if have else _not_evaluated("KS distance", s, ks_max))
    if overturn_tol is not None:
        out.append(_overturn_criterion(s, overturn_tol) if have else _not_evaluated("P[overturn]", s, overturn_tol))
    for q, tol in levels:
        name = f"{stats.percentile_label(q)} percentile of theta_max/alpha"
        out.append(_percentile_criterion(s, q, tol, name) if have else _not_evaluated(name, s, tol))
    if wasserstein_max is not None:
        name = "Wasserstein W1 (non-overturned)"
        out.append(
            _wasserstein_criterion(s, wasserstein_max, name) if have else _not_evaluated(name, s, wasserstein_max)
        )
    return out


def _share_criteria(agreement, atol: float, rtol: float, min_share, min_verdict_share) -> list[Criterion]:
    """The criteria of :func:`assert_record_agreement` on the shares of paired records (those given a limit)."""
    out = []
    for name, share, k, limit in (
        (f"records within atol={atol:g} + rtol={rtol:g}", agreement.share, agreement.n_agree, min_share),
        ("same overturn verdict", agreement.verdict_share, agreement.n_same_verdict, min_verdict_share),
    ):
        if limit is None:
            continue
        if agreement.n == 0:
            out.append(Criterion(name, False, "not evaluated: no paired records", math.nan, limit, math.inf))
            continue
        words, excess = limit_text("minimum share", share, limit, upper=False)
        out.append(Criterion(name, excess <= 0, f"{k} of {agreement.n} ({share:.1%}); {words}", share, limit, excess))
    return out


def _worst_records(s: _Sides, wide: pd.DataFrame, agreement, atol: float, rtol: float, show: int) -> tuple[str, ...]:
    """Lines naming the ``show`` worst disagreeing records of a record-by-record check, worst first: verdict
    differences, then by |difference| relative to the tolerance."""
    bad = np.flatnonzero(~agreement.agree)
    if not (bad.size and show):
        return ()
    a, b = s.a, s.b
    with np.errstate(invalid="ignore"):
        gap = np.where(agreement.same_verdict, np.abs(a - b) / (atol + rtol * np.abs(b)), np.inf)
    order = bad[np.argsort(-gap[bad], kind="stable")][:show]
    names = _motion_names(s.ok, wide.index.to_numpy())
    lines = [f"  Worst disagreeing records ({s.engine} vs {s.reference}, theta_max/alpha):"]
    lines += [f"    {names[i]}: {fmt_value(a[i])} vs {fmt_value(b[i])}" for i in order]
    return tuple(lines)


def _ks_criterion(s: _Sides, ks_max: float) -> Criterion:
    ks = stats.ks_2samp(s.a, s.b)
    fa, fb = stats.ecdf(s.a), stats.ecdf(s.b)
    grid = np.union1d(fa.x, fb.x)
    if grid.size:
        gap = np.abs(fa(grid) - fb(grid))
        k = int(np.argmax(gap))
        where = (
            f"largest gap at theta_max/alpha = {grid[k]:.3f}: F_{s.engine} = {fa(grid[k]):.3f}, "
            f"F_{s.reference} = {fb(grid[k]):.3f}"
        )
    else:
        where = "both sides overturned on every record"
    words, excess = limit_text("ks_max", ks.distance, ks_max)
    detail = f"D = {ks.distance:.3f} (p = {ks.pvalue:.3g}); {where}; {words}"
    return Criterion("KS distance", excess <= 0, detail, ks.distance, ks_max, excess)


def _overturn_criterion(s: _Sides, tol: float) -> Criterion:
    sides = []
    for name, v in ((s.engine, s.a), (s.reference, s.b)):
        p = proportions.overturn_probability(np.isposinf(v), ci=0.95)
        k = int(np.isposinf(v).sum())
        sides.append((p.estimate, f"{name} {p.estimate:.3f} ({k}/{v.size}, 95% CI {p.low:.3f}-{p.high:.3f})"))
    diff = abs(sides[0][0] - sides[1][0])
    words, excess = limit_text("overturn_tol", diff, tol)
    detail = f"{sides[0][1]}, {sides[1][1]}; |difference| {diff:.3f}; {words}"
    return Criterion("P[overturn]", excess <= 0, detail, diff, tol, excess)


def _percentile_criterion(s: _Sides, q: float, tol: float, name: str) -> Criterion:
    pa = stats.percentiles(s.a, [q], n_boot=0).value[0]
    pb = stats.percentiles(s.b, [q], n_boot=0).value[0]
    both = f"{s.engine} {fmt_value(pa)}, {s.reference} {fmt_value(pb)}"
    if np.isposinf(pa) and np.isposinf(pb):
        return Criterion(name, True, f"{both}; both overturn at this level; limit {tol:g}", 0.0, tol, -tol)
    if np.isposinf(pa) or np.isposinf(pb):
        return Criterion(
            name, False, f"{both}; only one side overturns at this level; limit {tol:g}", math.inf, tol, math.inf
        )
    diff = abs(pa - pb)
    words, excess = limit_text(f"percentiles[{q:g}]", diff, tol)
    return Criterion(name, excess <= 0, f"{both}; |difference| {diff:.3f}; {words}", diff, tol, excess)


def _wasserstein_criterion(s: _Sides, limit: float, name: str) -> Criterion:
    w = stats.wasserstein(s.a, s.b)
    sides = []
    for side, v in ((s.engine, s.a), (s.reference, s.b)):
        f = v[np.isfinite(v)]
        med = f"median {np.median(f):.3f}" if f.size else "none rocked without overturning"
        sides.append(f"{side} {med} over {f.size} records")
    words, excess = limit_text("wasserstein_max", w, limit)
    return Criterion(name, excess <= 0, f"W1 = {fmt_value(w)} alpha ({'; '.join(sides)}); {words}", w, limit, excess)


# ----------------------------------------------------------------------------
# small helpers


def _notes(s: _Sides) -> tuple[str, ...]:
    n_fail = {name: int((s.failed["engine"].astype(str) == name).sum()) for name in (s.engine, s.reference)}
    if any(n_fail.values()):
        return (
            "  Note: failed runs are excluded from every statistic above "
            f"({s.engine}: {n_fail[s.engine]}, {s.reference}: {n_fail[s.reference]}).",
        )
    return ()


def _motion_names(ok: pd.DataFrame, motion_ids: np.ndarray) -> list[str]:
    if "motion_name" not in ok.columns:
        return [f"motion {m}" for m in motion_ids]
    names = ok.drop_duplicates("motion_id").set_index("motion_id")["motion_name"]
    return [f"{names.get(m, '?')} (motion {m})" for m in motion_ids]
