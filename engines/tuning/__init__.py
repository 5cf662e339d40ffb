"""Contact tuning: find engine settings that reproduce a target energy ratio r at impact.

An engine's contact model decides how much kinetic energy the block keeps at each impact.
:func:`tune` releases the block from rest at a set of amplitudes, measures each first impact's
energy ratio, compares it with the target (Housner's r by default) and runs the pulse and
free-decay checks, for each of the engine's candidate settings, and picks the cheapest that
passes them all (``housner tune ENGINE [--r R] [--figure FILE]`` from the shell).

* :mod:`~housner.engines.tuning.checks`: the four checks, their records, tolerances and analytic
  references, and a candidate's score;
* :mod:`~housner.engines.tuning.measuring`: an engine run through the check records;
* :mod:`~housner.engines.tuning.search`: :func:`tune`, the candidates and the choice;
* :mod:`~housner.engines.tuning.result`: :class:`TuningResult`, its tables and summary.

References
----------
Housner, G. W. (1963). The behavior of inverted pendulum structures during
earthquakes. BSSA 53(2), 403-417.
Bachmann, J. A. et al. (2017). Probabilistic validation of the Housner rocking
model. COMPDYN 2017, eqs. 7-8, Table 1 and Fig. 5.
"""

from __future__ import annotations

from housner.engines.measures import (
    decay_peaks,
    first_impact_ratio,
    first_peak,
    free_rocking_quarter_period,
    half_cycle_peaks,
)
from housner.engines.tuning.checks import (
    DECAY_FLOOR,
    DECAY_IMPACTS,
    DECAY_RTOL,
    DECAY_START,
    DEFAULT_AMPLITUDES,
    PULSES,
    RTOL,
    SAMPLE_STEPS,
    SMALL_AMPLITUDES,
    SMALL_WORST_FACTOR,
    THRESHOLD_PULSES,
    decay_motion,
    free_vibration_motions,
    pulse_motions,
)
from housner.engines.tuning.checks import (
    check_suite as check_suite,  # re-exported for tests/test_impact_law.py
)
from housner.engines.tuning.result import TuningResult
from housner.engines.tuning.search import COST_TIE, impact_law_candidates, tune
from housner.engines.tuning.search import _best as _best  # re-exported for tests/test_impact_law.py

__all__ = [
    "COST_TIE",
    "DECAY_FLOOR",
    "DECAY_IMPACTS",
    "DECAY_RTOL",
    "DECAY_START",
    "DEFAULT_AMPLITUDES",
    "PULSES",
    "RTOL",
    "SAMPLE_STEPS",
    "SMALL_AMPLITUDES",
    "SMALL_WORST_FACTOR",
    "THRESHOLD_PULSES",
    "TuningResult",
    "decay_motion",
    "impact_law_candidates",
    "decay_peaks",
    "first_impact_ratio",
    "first_peak",
    "free_vibration_motions",
    "free_rocking_quarter_period",
    "half_cycle_peaks",
    "pulse_motions",
    "tune",
]
