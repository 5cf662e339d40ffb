"""The sections of the run report (:mod:`housner.reports.run.page`), one module per subject.

Each section takes a :class:`housner.scenarios.runs.view.Run` and returns HTML.
"""
