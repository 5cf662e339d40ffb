"""The HTML report of a scenario run: one self-contained page, figures embedded.

:func:`write_report` reads a run directory written by
:func:`housner.scenarios.execution.rundir.write_run` (``results.parquet``, ``histories.parquet``,
``motions.npz``, ``run.json``) and writes ``report.html`` next to it. The page
needs no network: figures are base64 PNGs, the style sheet is inline, and there
is no script.

What it answers, top first: how far each engine is from the reference (the
analytic Housner model) and how sure we are; then the specimen and engine
settings, the ground motions, the distribution of theta_max/alpha (seed Fig. 10
and Table 2), record-by-record agreement, rocking spectra for pulse scenarios,
free rocking for release scenarios, failed records and provenance.

All statistics come from :mod:`housner.statistics.ensemble_stats`; theta_max/alpha is +inf for an
overturned block and failed records are left out of every statistic (and
listed).

References
----------
Bachmann, J. A., Strand, M., Vassiliou, M. F., Broccardo, M., Stojadinovic, B.
(2017). Probabilistic validation of the Housner rocking model. COMPDYN 2017.
"""

from __future__ import annotations

from pathlib import Path

from housner.reports._scenario_page import scenario_page
from housner.reports.glossary import glossary_html
from housner.reports.page import Section, guarded, render_directory, write_directory_report
from housner.reports.run.sections.agreement import agreement_section, free_vibration_section, spectra_section
from housner.reports.run.sections.distribution import distribution_section
from housner.reports.run.sections.engines_explained import engines_explained, has_engine_measurements
from housner.reports.run.sections.ensemble import ensemble_section
from housner.reports.run.sections.headline import headline_section, specimen_section
from housner.reports.run.sections.outcomes import outcomes_section
from housner.reports.run.sections.run_info import failures_section, provenance_section
from housner.scenarios.execution.rundir import REPORT_FILE
from housner.scenarios.runs.view import Run

__all__ = [
    "render_report",
    "write_report",
]


# ----------------------------------------------------------------------------
# public API
def render_report(run_dir: str | Path, *, view: Run | None = None) -> str:
    """The HTML report of a run directory, as a string.

    Parameters
    ----------
    run_dir : str or pathlib.Path
        Directory written by :func:`housner.scenarios.execution.rundir.write_run`; it must hold
        ``results.parquet``; ``run.json``, ``motions.npz`` and
        ``histories.parquet`` add sections when present.
    view : Run, optional
        That directory already loaded (:meth:`Run.load`), for a caller that reads it too.

    Returns
    -------
    str
        A complete HTML5 document with every figure embedded.

    Raises
    ------
    housner.errors.DataFileError
        When the directory or its results table is missing or unreadable.
    """
    return render_directory(run_dir, Run.load if view is None else (lambda _: view), _build_sections, _page)


def write_report(run_dir: str | Path, out: str | Path | None = None, *, view: Run | None = None) -> Path:
    """Write the HTML report of a run directory.

    Parameters
    ----------
    run_dir : str or pathlib.Path
        A run directory (see :func:`render_report`).
    out : str or pathlib.Path, optional
        File to write; default ``run_dir/report.html``.
    view : Run, optional
        That directory already loaded (see :func:`render_report`).

    Returns
    -------
    pathlib.Path
        The file written.
    """
    return write_directory_report(run_dir, out, lambda d: render_report(d, view=view), REPORT_FILE)


# ----------------------------------------------------------------------------
# sections
def _build_sections(run: Run) -> list[Section]:
    if run.meta.is_campaign:
        return _campaign_sections(run)
    out = [
        Section("verdict", "How far is each engine from the reference?", headline_section(run)),
        Section("specimen", "Specimen and engines", specimen_section(run)),
        Section("ensemble", "Ground motions", ensemble_section(run)),
        Section("distribution", "Distribution of the peak rotation", distribution_section(run)),
        Section("agreement", "Cross-engine agreement", agreement_section(run)),
    ]
    if has_engine_measurements(run):
        out.append(
            Section(
                "engines-explained",
                "What each engine's departure is made of, and what it costs",
                guarded("The engines' decomposition and frontiers", lambda: engines_explained(run)),
            )
        )
    if run.source == "pulses":
        out.append(
            Section("rocking-spectra", "Rocking spectra", guarded("The rocking spectra", lambda: spectra_section(run)))
        )
    if run.source == "free_vibration":
        out.append(
            Section("free-vibration", "Free rocking", guarded("Free rocking", lambda: free_vibration_section(run)))
        )
    out.append(Section("failures", "Failed records", failures_section(run)))
    out.append(Section("provenance", "Provenance", provenance_section(run)))
    out.append(Section("glossary", "Glossary", glossary_html()))
    return out


def _campaign_sections(run: Run) -> list[Section]:
    """A measured campaign's run: the outcomes first; the distribution against the analytic model where it makes
    sense (the chaos floor, the record against its ensemble and the paper's Table 2 do not apply and are left out)."""
    out = [
        Section(
            "outcomes",
            "How well does each engine predict the measured outcomes?",
            guarded("The outcome scores", lambda: outcomes_section(run)),
        )
    ]
    if run.others:  # one engine alone has no distribution to be judged against
        out.append(Section("verdict", "How far is each engine from the analytic model?", headline_section(run)))
    return out + [
        Section("specimen", "Specimen and engines", specimen_section(run)),
        Section("ensemble", "Ground motions", ensemble_section(run)),
        Section("distribution", "Distribution of the peak rotation", distribution_section(run)),
        Section("agreement", "Cross-engine agreement", agreement_section(run)),
        Section("failures", "Failed records", failures_section(run)),
        Section("provenance", "Provenance", provenance_section(run)),
        Section("glossary", "Glossary", glossary_html()),
    ]


# ----------------------------------------------------------------------------
# the page


def _page(run: Run, sections: list[Section], seconds: float) -> str:
    n_motions = run.meta.n_motions if run.meta.n_motions is not None else run.results["motion_id"].nunique()
    return scenario_page(
        run,
        sections,
        seconds,
        title="housner report",
        heading="Campaign" if run.meta.is_campaign else "Scenario",
        writer="housner.reports.run.write_report",
        specimen=run.specimen.name or "",
        n_motions=n_motions,
    )
