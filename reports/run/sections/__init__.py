"""The sections of the run report (:mod:`housner.reports.run.page`), one module per subject.

Each section takes a :class:`housner.reports.run.view.Run` and returns HTML.
"""
