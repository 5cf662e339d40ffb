"""The HTML report of a fragility study: one self-contained page, figures embedded.

:func:`write_study_report` writes ``report.html`` next to the files of a study directory (written by
:func:`housner.scenarios.studies.study.run_study`), having read them through
:func:`housner.scenarios.studies.study.load_study`, the one reader of the format and of its errors
(:mod:`~housner.reports.study.view`). The page answers, top first, what was run and whether each engine's
fragility function agrees with the reference's (:mod:`~housner.reports.study.verdict`), then shows the fits,
curves, medians against size, exceedances, stripe counts, failures and provenance
(:mod:`~housner.reports.study.sections`); a fit whose status is not "ok" gives its message, never a number.
The files and what the page shows are in ``docs/reference/run-directory.md`` ("A study directory").
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
