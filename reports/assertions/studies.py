"""Tolerance assertion on a study's fragility curves, for users' pytest suites and CI.

Typical use::

    from housner.reports.assertions import assert_fragility_agreement

    def test_mujoco_fragility_matches_housner():
        assert_fragility_agreement("runs/fragility-elcentro", engine="mujoco", reference="housner",
                                   median_rtol=0.1, beta_atol=0.1)

Per size of the study it checks the engine's fitted median against the
reference's (their ratio, within ``median_rtol`` of 1) and its beta (the
difference, within ``beta_atol``), each printed with its paired bootstrap
interval (:func:`housner.scenarios.studies.fragility.compare_fits`); a degenerate fit (no
overturn, every record overturned, a step) fails, with its reason: there is no
curve to agree with. With ``require_interval=True`` a criterion passes only if
its whole interval lies inside the tolerance, i.e. the data confirm the
agreement at the study's confidence level, not just its point estimate.
"""

from __future__ import annotations

import math
from pathlib import Path

from housner.reports.assertions.criteria import AgreementReport, CDFAgreementError, Criterion, check_count, check_tol
from housner.scenarios.studies.study import StudyResult, load_study
from housner.scenarios.studies.study_fits import StudyFit

__all__ = ["FragilityAgreementError", "assert_fragility_agreement"]


class FragilityAgreementError(CDFAgreementError):
    """An engine's fragility curve does not agree with the reference's within the tolerances."""


def _study(results):
    if isinstance(results, StudyResult):
        return results
    if isinstance(results, (str, Path)):
        return load_study(results)
    raise TypeError(f"`results` must be a study directory or a StudyResult, got {type(results)}")


def _fit_words(fit: StudyFit) -> str:
    if not fit.ok:
        return f"no fit ({fit.message})"
    return (
        f"median {fit.median:.4g} [{fit.median_low:.4g}, {fit.median_high:.4g}], "
        f"beta {fit.beta:.3f} [{fit.beta_low:.3f}, {fit.beta_high:.3f}]"
    )


def _criterion(
    name: str, value: float, low: float, high: float, centre: float, tol: float, strict: bool, level: str
) -> Criterion:
    """|value - centre| <= tol (and, when strict, the whole interval [low, high] within centre +- tol)."""
    off = abs(value - centre)
    reach = max(abs(low - centre), abs(high - centre))
    interval = f"{level} interval [{low:.4g}, {high:.4g}]"
    if not math.isfinite(off):
        return Criterion(name, False, f"cannot be evaluated ({value!r})", value, tol, math.inf)
    excess = (reach if strict else off) - tol
    what = "the interval's far end" if strict else "the estimate"
    words = f"limit {tol:g} on {what}; " + (f"exceeded by {excess:.3g}" if excess > 0 else f"margin {-excess:.3g}")
    detail = f"{value:.4g}, {interval}; |off| {off:.3g}; {words}"
    if not strict and excess <= 0 and reach > tol:
        detail += f"; not confirmed: the interval reaches {reach:.3g} from {centre:g}"
    return Criterion(name, excess <= 0, detail, off, tol, excess)


def _size_criteria(
    st: StudyResult,
    engine: str,
    reference: str,
    h: float,
    tols: tuple[float, float],
    require_interval: bool,
    level: str,
) -> list[Criterion]:
    """The criteria at prototype height ``h`` [m]: both fits there, or the median ratio and the beta difference
    within ``tols`` (median_rtol, beta_atol)."""
    fe, fr = st.fit(engine, h), st.fit(reference, h)
    tag = f"H = {h:g} m"
    if not fe.ok or not fr.ok:
        detail = f"{engine}: {_fit_words(fe)}; {reference}: {_fit_words(fr)}"
        return [Criterion(f"fragility fits at {tag}", False, detail, math.nan, math.nan, math.inf)]
    c = st.comparison(engine, h)
    median_rtol, beta_atol = tols
    return [
        _criterion(
            f"median ratio at {tag} ({engine} {fe.median:.4g} / {reference} {fr.median:.4g})",
            c.median_ratio,
            c.ratio_low,
            c.ratio_high,
            1.0,
            median_rtol,
            require_interval,
            level,
        ),
        _criterion(
            f"beta difference at {tag} ({engine} {fe.beta:.3f} - {reference} {fr.beta:.3f})",
            c.beta_diff,
            c.diff_low,
            c.diff_high,
            0.0,
            beta_atol,
            require_interval,
            level,
        ),
    ]


def assert_fragility_agreement(
    results,
    engine: str = "mujoco",
    reference: str = "housner",
    *,
    median_rtol: float = 0.1,
    beta_atol: float = 0.1,
    size: float | None = None,
    require_interval: bool = False,
    max_failed: int | None = 0,
) -> AgreementReport:
    """Assert that an engine's lognormal fragility agrees with the reference's at every size of a study.

    Parameters
    ----------
    results : str, pathlib.Path or housner.scenarios.studies.study.StudyResult
        A study directory (``housner run`` on a scenario with ``[study]``) or what
        :func:`housner.scenarios.studies.study.run_study` returned.
    engine, reference : str
        Engine under test, and the one it must match (the study's reference: the
        comparisons are computed against it).
    median_rtol : float
        Largest allowed |median_engine / median_reference - 1| [-].
    beta_atol : float
        Largest allowed |beta_engine - beta_reference| [-].
    size : float, optional
        Check this prototype height [m] only (default: every size of the study).
    require_interval : bool
        Pass a criterion only if its whole bootstrap interval lies within the
        tolerance (the data confirm the agreement), not just its estimate.
    max_failed : int or None
        Most failed records allowed for each of the two engines (they are left
        out of the fits, so ignoring them would flatter an engine); None: any.

    Returns
    -------
    AgreementReport
        Every criterion with its figures, when all pass.

    Raises
    ------
    FragilityAgreementError
        (an ``AssertionError``) when a criterion fails; the message lists every criterion.
    ValueError
        Unknown engine or size, a bad tolerance, or a directory that is not a study.
    """
    __tracebackhide__ = True
    check_tol("median_rtol", median_rtol, allow_none=False)
    check_tol("beta_atol", beta_atol, allow_none=False)
    check_count("max_failed", max_failed)
    st = _study(results)
    meta_ref = st.meta.reference
    if meta_ref is not None and reference != meta_ref:
        raise ValueError(f"the study's comparisons are against {meta_ref!r}, not {reference!r}")
    sizes = sorted({f.size for f in st.fits if f.engine == engine})
    if not sizes:
        have = sorted({f.engine for f in st.fits})
        raise ValueError(f"engine {engine!r} is not in the study (engines: {', '.join(have)})")
    if size is not None:
        sizes = [st.fit(engine, size).size]
    settings = st.meta.study
    each = next((x for x in (settings.compare_ci, settings.ci) if x is not None), 0.95)
    level = f"{each:.1%}"
    criteria = []
    if max_failed is not None:
        for name in (engine, reference):
            bad = int(((st.results["engine"] == name) & (st.results["status"] != "ok")).sum())
            criteria.append(
                Criterion(
                    f"failed records of {name}",
                    bad <= max_failed,
                    f"{bad} (limit {max_failed})",
                    bad,
                    max_failed,
                    bad - max_failed,
                )
            )
    for h in sizes:
        criteria += _size_criteria(st, engine, reference, h, (median_rtol, beta_atol), require_interval, level)
    report = st.out / "report.html" if st.out is not None and (st.out / "report.html").exists() else None
    source = str(st.out / "fragility.json") if st.out is not None else None
    result = AgreementReport(f"fragility agreement of {engine!r} with {reference!r}", tuple(criteria), source, report)
    if not result.passed:
        raise FragilityAgreementError(result)
    return result
