"""The HTML report of a fragility study: one self-contained page, figures embedded.

A study directory, written by :func:`housner.scenarios.studies.study.run_study`, holds:

- ``study.json``: scenario, specimen, the study's settings (intensity measure,
  stripe levels, prototype heights and scale factors S, response thresholds,
  motions, bootstrap replicates, seed, confidence level, reference engine),
  engines with settings, versions and wall times, record counts, provenance;
- ``fragility.parquet``: overturns per (engine, size, stripe) with Wilson intervals;
- ``exceedance.parquet``: P[theta_max/alpha >= threshold] per (engine, size, stripe, threshold);
- ``fragility.json``: the lognormal fits per (engine, size) with bootstrap
  intervals and status, and each engine's comparison with the reference
  (ratio of medians, difference of betas, paired-bootstrap intervals);
- ``results.parquet``: one row per record (engine, size, stripe, motion).

:func:`write_study_report` writes ``report.html`` next to them, having read
them through :func:`housner.scenarios.studies.study.load_study`, the one reader
of the format and of its errors (:mod:`~housner.reports.study.view`). What the
page answers, top first: what was run and, per engine and size, whether its
fragility function agrees with the reference's within the intervals (the
study's verdict: only when the interval of the ratio of medians contains 1 and
that of the difference of betas contains 0), and by how much it differs
otherwise (:mod:`~housner.reports.study.verdict`); then the fits per size, the
fragility curves, the median against size, the exceedance of response
thresholds, the stripe counts, the failed records and provenance
(:mod:`~housner.reports.study.sections`). A fit whose status is not "ok" (no
overturn, all overturned, separated data ...) is not a maximum-likelihood fit:
the page gives its message and no number as its median or beta.

References
----------
Baker, J. W. (2015). Efficient analytical fragility function fitting using
dynamic structural analysis. Earthquake Spectra 31(1), 579-599.
Efron, B., Tibshirani, R. (1993). An Introduction to the Bootstrap, ch. 13.
"""

from __future__ import annotations

from pathlib import Path

from housner.reports._scenario_page import scenario_page
from housner.reports.page import Section, guarded, render_directory, write_directory_report
from housner.reports.study.sections import (
    exceedance_figures,
    failures,
    fragility_figures,
    provenance,
    size_figure,
    stripes,
)
from housner.reports.study.verdict import fit_tables, headline
from housner.reports.study.view import StudyView
from housner.scenarios.studies.study import REPORT_FILE

__all__ = ["render_study_report", "write_study_report"]


# ----------------------------------------------------------------------------
# public API
def render_study_report(study_dir: str | Path) -> str:
    """The HTML report of a study directory, as a string.

    Parameters
    ----------
    study_dir : str or pathlib.Path
        Directory written by :func:`housner.scenarios.studies.study.run_study`: ``study.json``,
        ``fragility.parquet``, ``exceedance.parquet``, ``fragility.json`` and ``results.parquet``.

    Returns
    -------
    str
        A complete HTML5 document with every figure embedded.

    Raises
    ------
    ValueError
        From :func:`housner.scenarios.studies.study.load_study`: naming the directory and the file it lacks.
    """
    return render_directory(study_dir, StudyView.load, _build_sections, _page)


def write_study_report(study_dir: str | Path, out: str | Path | None = None) -> Path:
    """Write the HTML report of a study directory.

    Parameters
    ----------
    study_dir : str or pathlib.Path
        A study directory (see :func:`render_study_report`).
    out : str or pathlib.Path, optional
        File to write; default ``study_dir/report.html``.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    return write_directory_report(study_dir, out, render_study_report, REPORT_FILE)


# ----------------------------------------------------------------------------
# the page
def _build_sections(study: StudyView) -> list[Section]:
    return [
        Section(
            "verdict",
            "Does each engine's fragility agree with the reference?",
            guarded("The verdict", lambda: headline(study)),
        ),
        Section("fits", "Fits per size", guarded("The fit tables", lambda: fit_tables(study))),
        Section("fragility", "Fragility curves", fragility_figures(study)),
        Section("size-effect", "Median capacity against size", size_figure(study)),
        Section("exceedance", "Exceedance of response thresholds", exceedance_figures(study)),
        Section("stripes", "Stripe counts", guarded("The stripe tables", lambda: stripes(study))),
        Section("failures", "Failed records", guarded("The failed records", lambda: failures(study))),
        Section("provenance", "Provenance", guarded("The provenance", lambda: provenance(study))),
    ]


def _page(study: StudyView, sections: list[Section], seconds: float) -> str:
    return scenario_page(
        study,
        sections,
        seconds,
        title="fragility study",
        heading="Fragility study",
        writer="housner.reports.study.page.write_study_report",
        specimen=study.meta.specimen.name or "",
    )
