"""Where a model's history parts from an engine's (scenarios/runs/departure.py), on histories of known shape."""

import math

import numpy as np

from housner.reports.explain_text import departures_text
from housner.scenarios.runs.departure import DEPART_TOL, SMALL_ROCKING, departure, summarise

ALPHA = 0.15
DT = 1e-3


def _rocking(amplitudes, half_period=0.2, lead=0.1):
    """Half-sines of the given amplitudes [alpha], alternating in sign, after ``lead`` s at rest: each sign
    change between them is an impact."""
    n_half = int(round(half_period / DT))
    parts = [np.zeros(int(round(lead / DT)))]
    for k, a in enumerate(amplitudes):
        s = 1.0 if k % 2 == 0 else -1.0
        parts.append(s * a * ALPHA * np.sin(np.pi * np.arange(1, n_half + 1) / (n_half + 1)))
    return np.concatenate(parts)


def test_identical_histories_never_part():
    th = _rocking([0.5, 0.4, 0.3])
    d = departure(3, th, th.copy(), DT, ALPHA)
    assert d.phase == "never" and math.isnan(d.time) and d.record == 3


def test_parting_in_the_first_half_cycle_is_uplift():
    eng = _rocking([0.5, 0.4])
    mod = _rocking([0.7, 0.4])  # larger first half-cycle: parts before any sign change
    d = departure(0, eng, mod, DT, ALPHA)
    assert d.phase == "uplift" and d.impacts_before == 0
    # the first sample where |difference| > DEPART_TOL alpha: 0.2 alpha * sin(x) > 0.05 alpha
    n0 = 100  # lead samples
    x = np.pi * np.arange(1, 201) / 201
    k = n0 + int(np.flatnonzero(0.2 * np.sin(x) > DEPART_TOL)[0])
    assert d.time == k * DT


def test_parting_after_impacts_counts_them_and_names_small_or_large_rocking():
    eng = _rocking([0.5, 0.4, 0.3, 0.05, 0.04])
    mod_large = _rocking([0.5, 0.4, 0.5, 0.05, 0.04])  # parts in the third half-cycle (after 2 impacts), large
    d = departure(1, eng, mod_large, DT, ALPHA)
    assert (d.phase, d.impacts_before) == ("rocking", 2)
    # small rocking: the model keeps rocking where the engine has all but stopped
    mod_small = _rocking([0.5, 0.4, 0.3, 0.05, 0.12])
    d = departure(2, eng, mod_small, DT, ALPHA)
    assert d.phase == "small rocking" and d.impacts_before == 4 and d.amplitude < SMALL_ROCKING


def test_nan_in_a_history_counts_as_parted_and_unequal_lengths_are_compared_over_the_common_part():
    eng = _rocking([0.5, 0.4])
    mod = eng.copy()
    mod[150] = np.nan
    assert departure(0, eng, mod, DT, ALPHA).time == 150 * DT
    assert departure(0, eng, eng[:200], DT, ALPHA).phase == "never"


def test_summary_counts_phases_and_names_records():
    eng = _rocking([0.5, 0.4, 0.3])
    deps = [
        departure(0, eng, _rocking([0.7, 0.4, 0.3]), DT, ALPHA),
        departure(1, eng, _rocking([0.5, 0.4, 0.6]), DT, ALPHA),
        departure(2, eng, eng, DT, ALPHA),
    ]
    s = summarise(deps)
    assert s.n == 3
    assert s.by_phase == {"uplift": 1, "small rocking": 0, "rocking": 1, "never": 1}
    assert s.records["uplift"] == (0,) and s.records["rocking"] == (1,)
    assert s.impacts_before.median == 2
    # its words, rendered from those figures in reports (the summary holds no sentence)
    text = departures_text(s)
    assert "Of the 3 records" in text and "1 parts before the first impact" in text
    assert "after a median 2 impacts" in text
    assert departures_text(summarise([])) == ""


def test_disagreeing_applies_the_per_record_rule_and_agrees_with_record_agreement():
    import pandas as pd

    from housner.scenarios.runs.departure import disagreeing, record_agreement

    eng = pd.Series([np.inf, 0.50, 0.50, np.inf, 0.30], index=[0, 1, 2, 3, 4])
    mod = pd.Series([np.inf, 0.51, 0.60, 0.40, np.inf], index=[0, 1, 2, 3, 4])
    # both overturned; within 3 % of the engine's (0.51 vs 0.50: 2 %); 20 % off; one overturned, the other not
    assert disagreeing(eng, mod) == [2, 3, 4]
    share, n = record_agreement(eng, mod)
    assert n == 5 and share == 1.0 - len(disagreeing(eng, mod)) / n
