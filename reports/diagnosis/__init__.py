"""The diagnosis report: which effect the Housner model misses, and the error falling as it is added.

:func:`render_diagnosis` turns a :class:`housner.scenarios.diagnosis.results.Diagnosis` into one
self-contained HTML page (figures are base64 PNGs, the style sheet is inline, no script, no network);
:func:`write_diagnosis_report` writes it. The page is :mod:`housner.reports.diagnosis.page`'s, its sections
:mod:`housner.reports.diagnosis.sections`' and its figures :mod:`housner.reports.diagnosis.figures`'. What it
shows, top first (the verdict, the error before and after, the records against both models, the residual
against the floor, the ladder, the candidates, the CDFs, the localisation figures after the seed paper's
eqs. 7-8 and Figs. 5 and 10, a per-record table), is in ``docs/how-to/diagnose-campaign.md`` ("Read the
report").
"""

from housner.reports.diagnosis.figures import history_records
from housner.reports.diagnosis.outcomes import render_outcome_report, write_outcome_report
from housner.reports.diagnosis.page import render_diagnosis, write_diagnosis_report

__all__ = [
    "history_records",
    "render_diagnosis",
    "render_outcome_report",
    "write_diagnosis_report",
    "write_outcome_report",
]
