"""The diagnosis page: its sections (:mod:`housner.reports.diagnosis.sections`) in one self-contained HTML page."""

from __future__ import annotations

import time
from pathlib import Path

from housner.reports.diagnosis.sections import (
    candidates_section,
    ladder_section,
    localisation_section,
    records_section,
    sensor_section,
    settings_section,
    summary_section,
)
from housner.reports.page import Section, document, esc, write_page

__all__ = ["render_diagnosis", "write_diagnosis_report"]


def render_diagnosis(diag) -> str:
    """The diagnosis report as one HTML string (self-contained: inline CSS, base64 PNG figures).

    Parameters
    ----------
    diag : housner.scenarios.diagnosis.results.Diagnosis
        From :func:`housner.scenarios.diagnosis.diagnose.diagnose` with ``compare_steps=True``
        (every step carries its comparison with the campaign).
    """
    if any(s.comparison is None for s in diag.steps):
        raise ValueError("the diagnosis has no comparisons per step; run diagnose(..., compare_steps=True)")
    t0 = time.perf_counter()
    sections = [
        ("summary", "Verdict", summary_section(diag)),
        ("ladder", "Error ladder", ladder_section(diag)),
        ("candidates", "Candidate effects", candidates_section(diag)),
        ("where", "Where the model fails, step by step", localisation_section(diag)),
        ("sensor", "The sensor", sensor_section(diag)),
        ("records", "Records", records_section(diag)),
        ("settings", "Settings", settings_section(diag)),
    ]
    took = time.perf_counter() - t0
    return document(
        f"{diag.campaign.name}: diagnosis",
        f"Diagnosis: <code>{esc(diag.campaign.name)}</code>",
        '<p class="sub">Which physical effect the Housner model misses, judged on held-out records.</p>',
        [Section(i, t, b) for i, t, b in sections],
        f"Page built in {took:.1f} s.",
    )


def write_diagnosis_report(diag, path: str | Path) -> Path:
    """Write :func:`render_diagnosis` to ``path`` (parents created) and return the path."""
    return write_page(path, render_diagnosis(diag))
