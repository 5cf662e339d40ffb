"""The study report: fragility curves, size effect and exceedance of a study directory."""

from housner.reports.study.page import render_study_report, write_study_report

__all__ = ["render_study_report", "write_study_report"]
