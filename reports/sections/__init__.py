"""The sections of the run report (:mod:`reports.html`), one module per subject.

Each section takes a :class:`reports.run_view.Run` and returns HTML.
"""
