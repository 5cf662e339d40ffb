"""The run report: one HTML page of a run directory (headline, distributions, agreement, ensemble, tuning)."""

from housner.reports.run.page import render_report, write_report

__all__ = ["render_report", "write_report"]
