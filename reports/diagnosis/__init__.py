"""The diagnosis report: which effect the Housner model misses, and the error falling as it is added.

:func:`render_diagnosis` turns a :class:`housner.scenarios.diagnosis.results.Diagnosis` into
one self-contained HTML page (figures are base64 PNGs, the style sheet is
inline, no script, no network); :func:`write_diagnosis_report` writes it.
The page is :mod:`housner.reports.diagnosis.page`'s, its sections
:mod:`housner.reports.diagnosis.sections`' and its figures
:mod:`housner.reports.diagnosis.figures`'.

What it shows, top first: the verdict, stated once (what fails, which effect
explains it), the held-out error before (plain Housner model) and after (final
model) with their standard errors, and the effects' parameters with their
units; the measured rotation against both models for the worst and the median
ground-motion record and a free vibration; the residual against the
correct-model floor; the error
ladder (baseline, then each added effect, held-out error with its standard
error, against the noise floor); the candidates of every greedy round; the
theta_max/alpha CDFs of the measurement and of the model at every step; the
localisation figures, each with the measurement and the model at every step
side by side (energy ratio per impact and half-cycle duration against
amplitude, energy kept between impacts, uplift onset per direction,
direction bias, rotation before uplift, overturn fraction); the table of the
localisation quantities; a per-record table.

References
----------
Bachmann, J. A., Strand, M., Vassiliou, M. F., Broccardo, M., Stojadinovic, B.
(2017). Probabilistic validation of the Housner rocking model. COMPDYN 2017,
eqs. 7-8, Figs. 5 and 10.
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
