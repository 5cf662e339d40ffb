"""Contact tuning: the closed forms it relies on, and the tuner's choice on tiny candidate lists."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.integrate import solve_ivp
from shared import SoftGroundMujoco

from housner import GroundMotion, Specimen
from housner.engines.base import ENGINES
from housner.engines.mujoco_engine import MujocoEngine
from housner.engines.tuning import (
    DECAY_IMPACTS,
    DECAY_START,
    DEFAULT_AMPLITUDES,
    PULSES,
    SAMPLE_STEPS,
    SMALL_AMPLITUDES,
    THRESHOLD_PULSES,
    TuningResult,
    decay_motion,
    decay_peaks,
    first_impact_ratio,
    first_peak,
    free_rocking_quarter_period,
    free_vibration_motions,
    half_cycle_peaks,
    pulse_motions,
    tune,
)
from housner.engines.tuning.result import DecayCheck, PulseCheck, RatioCheck
from housner.free_vibration.closed_forms import half_cycle_time
from housner.model import simulate as housner_simulate
from housner.reports.tuning_figure import tuning_report_figure

SEED = Specimen.bachmann2017()


@pytest.mark.parametrize("fraction", [0.05, 0.5, 0.95])
def test_quarter_period_is_the_exact_time_to_impact(fraction):
    # Independent computation: integrate theta'' = -p^2 sin(alpha - theta) to the theta = 0 event at tight tolerance.
    a, p = SEED.alpha, SEED.p
    th0 = fraction * a
    ev = lambda t, y: y[0]  # noqa: E731
    ev.terminal = True
    sol = solve_ivp(
        lambda t, y: [y[1], -(p**2) * math.sin(a - y[0])], [0, 10], [th0, 0.0], events=ev, rtol=1e-12, atol=1e-15
    )
    assert free_rocking_quarter_period(SEED, th0) == pytest.approx(sol.t_events[0][0], rel=1e-9)
    # and the other helper's exact half-cycle (impact to impact) is two quarter periods
    assert 2 * free_rocking_quarter_period(SEED, th0) == pytest.approx(half_cycle_time(th0, a, p), rel=1e-8)


def test_quarter_period_tends_to_housners_linearised_formula_for_slender_blocks():
    # cosh(p T/4) = 1 / (1 - theta0/alpha) (seed eq. 7) is exact for the linearised equation; for alpha = 0.01 rad
    # the nonlinearity is O(alpha^2) = 1e-4.
    slender = Specimen(height=2.0, width=0.02, depth=1.0, mass=1.0)
    for f in (0.3, 0.8):
        exact = free_rocking_quarter_period(slender, f * slender.alpha)
        linear = math.acosh(1 / (1 - f)) / slender.p
        assert exact == pytest.approx(linear, rel=1e-4)


def test_quarter_period_rejects_bad_amplitudes():
    with pytest.raises(ValueError, match="`theta0`"):
        free_rocking_quarter_period(SEED, 1.2 * SEED.alpha)


@pytest.mark.parametrize("r", [0.8, 0.9465166])
def test_first_impact_ratio_recovers_r_of_the_analytic_model(r):
    # The analytic engine multiplies the kinetic energy by exactly r at each impact; peaks come from 1 ms samples
    # refined by a parabola, whose error is O(p^2 dt^2) relative to curvature, ~1e-7 here.
    for m in free_vibration_motions(SEED, (0.2, 0.7)):
        assert first_impact_ratio(housner_simulate(SEED, m, r=r)) == pytest.approx(r, rel=1e-5)


def test_first_impact_ratio_is_nan_when_the_record_is_too_short():
    th0 = 0.5 * SEED.alpha
    m = GroundMotion.free_vibration(th0, 1.1 * free_rocking_quarter_period(SEED, th0), dt=0.001)
    assert math.isnan(first_impact_ratio(housner_simulate(SEED, m)))


def test_pulses_first_peak_and_no_impact_before_it():
    for m in pulse_motions(SEED):
        resp = housner_simulate(SEED, m)
        pk = first_peak(resp)
        assert 0.1 * SEED.alpha < pk < 0.5 * SEED.alpha
        assert pk <= resp.theta_max + 1e-12
    # the near-threshold pulses lift the block to about 0.02 alpha only, then rock it further after one impact
    for m in pulse_motions(SEED, THRESHOLD_PULSES):
        resp = housner_simulate(SEED, m)
        assert 0.01 * SEED.alpha < first_peak(resp) < 0.03 * SEED.alpha < 0.1 * SEED.alpha < resp.theta_max
        assert resp.impact_times[0] < resp.t[np.argmax(np.abs(resp.theta))]


def test_default_amplitudes():
    assert DEFAULT_AMPLITUDES[0] == 0.2 and DEFAULT_AMPLITUDES[-1] == 0.9 and len(DEFAULT_AMPLITUDES) == 71
    assert np.allclose(np.diff(DEFAULT_AMPLITUDES), 0.01)
    assert SMALL_AMPLITUDES[0] == 0.02 and max(SMALL_AMPLITUDES) < DEFAULT_AMPLITUDES[0]
    assert len(PULSES) == 3 and len(THRESHOLD_PULSES) == 2
    assert SAMPLE_STEPS[1] == pytest.approx(0.01 / math.sqrt(10))  # El Centro (0.01 s) at model scale 1/10


def test_decay_peaks_follow_the_analytic_model_impact_by_impact():
    # Independent computation: the event-accurate analytic solver (impacts located, kinetic energy times r) sampled at
    # 1 ms, each half-cycle's peak refined by a parabola (error ~1e-7 relative, as for first_impact_ratio).
    m = decay_motion(SEED)
    exact = decay_peaks(SEED, DECAY_START * SEED.alpha, max(DECAY_IMPACTS))
    got = half_cycle_peaks(housner_simulate(SEED, m))
    assert got.size > max(DECAY_IMPACTS)  # the record holds the 40th impact's peak
    assert got[: exact.size] == pytest.approx(exact, rel=1e-5)
    # small amplitudes: the energy above upright is ~ sin(alpha) theta, so each impact multiplies the peak by ~r
    assert exact[1] / exact[0] == pytest.approx(SEED.r_housner, rel=0.05 * DECAY_START)
    with pytest.raises(ValueError, match="`theta0`"):
        decay_peaks(SEED, 1.5 * SEED.alpha, 3)


def test_half_cycle_peaks_skip_a_rising_end():
    t = np.arange(0, 1.0, 0.001)
    th = 0.01 * np.sin(2 * np.pi * 1.5 * t)  # three half-cycles, peaks 0.01 at 1/6, 1/2 and 5/6 s
    assert half_cycle_peaks(th) == pytest.approx([0.01, 0.01, 0.01], rel=1e-6)  # parabola through 1 ms samples
    assert half_cycle_peaks(th[:750]).size == 2  # the third half-cycle is still rising when the record ends


def test_tuner_picks_the_candidate_that_meets_the_target():
    # Two candidates of the analytic engine: r = 0.90 (5 % off) and Housner's r (exact); two amplitudes. Every check
    # compares the analytic engine with itself for the second candidate.
    res = tune("housner", SEED, amplitudes=(0.3, 0.7), candidates=[{"r": 0.90}, {"r": SEED.r_housner}], progress=False)
    assert res.met
    assert res.settings["r"] == SEED.r_housner
    assert res.worst_rel_error < 1e-5
    assert list(res.candidates["met"]) == [False, True]
    assert res.candidates["worst_rel_error"].iloc[0] == pytest.approx(1 - 0.90 / SEED.r_housner, rel=1e-4)
    assert list(res.table["amplitude"]) == [0.3, 0.7] * len(SAMPLE_STEPS)
    assert sorted(set(res.table["dt"])) == sorted(SAMPLE_STEPS)
    assert len(res.small_table) == len(SMALL_AMPLITUDES) * len(SAMPLE_STEPS)
    assert np.all(res.small_table["rel_error"].abs() < 1e-5)
    assert np.all(res.decay_table["rel_error"].abs() < 1e-5)
    assert len(res.pulse_table) == (len(PULSES) + len(THRESHOLD_PULSES)) * len(SAMPLE_STEPS)
    assert np.all(res.pulse_table[["rel_error", "theta_max_rel_error"]].abs() < 1e-9)
    # r = 0.90 keeps 5 % less energy per impact: the 40th decay peak is (0.90 / r_housner)^40 ~ 0.13 of Housner's
    assert res.candidates["decay_rel_error"].iloc[0] > 0.8
    assert res.candidates["score"].iloc[1] < 1e-3 < 1 < res.candidates["score"].iloc[0]
    assert "MET" in res.summary() and "NOT MET" not in res.summary()
    json.dumps(res.to_dict(), default=float)  # plain data


def test_tuner_says_so_when_no_candidate_meets_the_target():
    res = tune(
        "housner",
        SEED,
        target_r=0.9532,
        amplitudes=(0.3, 0.7),
        candidates=[{"r": 0.80}, {"r": 0.94}],
        progress=False,
        small_amplitudes=(0.05,),
        check_decay=False,
        sample_steps=(0.001,),
    )
    assert not res.met
    assert res.settings["r"] == 0.94  # the closer one
    assert res.worst_rel_error == pytest.approx(1 - 0.94 / 0.9532, rel=1e-4)
    assert np.isnan(res.candidates["decay_rel_error"]).all() and len(res.decay_table) == 0
    assert "NOT MET" in res.summary()
    # it says what it reaches instead: r = 0.94 at every amplitude, -1.38 % from the target
    assert res.reached_r == pytest.approx((0.94, 0.94, 0.94), rel=1e-5)
    assert "cannot reach r = 0.9532" in res.summary() and "r = 0.9400 on average" in res.summary()
    assert res.to_dict()["reached_r"] == pytest.approx([0.94] * 3, rel=1e-5)
    fig = tuning_report_figure(res)
    ax = fig.axes[0]
    assert len(fig.axes) == 1 and "NOT met" in ax.get_title()
    # the last line: r at the small amplitude and the two others, all 0.94 for this analytic candidate
    assert ax.lines[-1].get_xdata() == pytest.approx([0.05, 0.3, 0.7])
    assert ax.lines[-1].get_ydata() == pytest.approx([0.94] * 3, rel=1e-5)


def test_tuner_rejects_the_soft_contact_that_only_matched_r_above_0_2_alpha(monkeypatch):
    # The failure that checks 2-4 were added for: the first tuned contact (0.125 ms, solref (0.25 ms, 1), averaged
    # with the ground's default 20 ms) kept r within 0.5 % at 0.2-0.9 alpha but lost 3 % per impact at 0.02 alpha,
    # let the small rocking die out and rocked too far after near-threshold pulses. Here on today's sphere pivots
    # (measured: 2.0 % at 0.02 alpha, the block at rest before the 40th impact, pulses 4.2 % off).
    monkeypatch.setitem(ENGINES, "mujoco-soft-ground", SoftGroundMujoco)
    old = {"timestep": 1.25e-4, "solref": (2.5e-4, 1.0), "impratio": 100.0, "cone": "pyramidal"}
    res = tune(
        "mujoco-soft-ground",
        SEED,
        amplitudes=(0.2, 0.3, 0.5, 0.7, 0.9),
        candidates=[old],
        progress=False,
        small_amplitudes=(0.02, 0.05),
        sample_steps=(0.001,),
    )
    c = res.candidates.iloc[0]
    assert c["worst_rel_error"] <= 0.005  # check 1 alone let it through
    assert not res.met
    assert c["small_worst_rel_error"] > 0.015  # check 2
    assert c["decay_rel_error"] > 0.5  # check 3 (inf: no 40th impact at all)
    assert c["pulse_rel_error"] > 0.02  # check 4


def test_tuner_on_mujoco_prefers_the_tuned_contact_to_mujocos_defaults():
    # MuJoCo's own defaults (2 ms step, solref 0.02, elliptic cone, impratio 1) lose several percent per impact;
    # the tuned defaults are within 0.5 %. Two candidates, two amplitudes, one small amplitude, one sample step.
    stock = {"timestep": 2e-3, "solref": (0.02, 1.0), "solimp": (0.9, 0.95, 0.001, 0.5, 2.0), "cone": "elliptic"}
    stock["impratio"] = 1.0
    res = tune(
        "mujoco",
        SEED,
        amplitudes=(0.3, 0.7),
        candidates=[stock, {}],
        progress=False,
        small_amplitudes=(0.05,),
        sample_steps=(0.001,),
    )
    assert res.met
    assert res.settings == MujocoEngine().settings()
    worst_stock = res.candidates["worst_rel_error"].iloc[0]
    assert worst_stock > 0.02
    assert res.cost_per_sim_second > 0


def test_mujoco_defaults_pass_every_check_at_both_sample_steps():
    # The shipped defaults against the full criterion (checks 1-4 at 1 ms and 3.16 ms sample steps); measured score
    # 0.57 (largest error over its tolerance: the 0.85 % theta_max of the 3p-1.2gtan pulse at 3.16 ms, accepted 1.5 %).
    res = tune("mujoco", SEED, candidates=[{}], progress=False)
    assert res.met, res.summary()
    assert res.candidates["score"].iloc[0] < 0.8  # a margin, not a lucky pass


def test_tuner_validates_its_arguments():
    with pytest.raises(ValueError, match="`target_r`"):
        tune("housner", SEED, target_r=1.2, candidates=[{}])
    with pytest.raises(ValueError, match="`amplitudes`"):
        tune("housner", SEED, amplitudes=(0.5, 1.5), candidates=[{}])
    with pytest.raises(ValueError, match="`small_amplitudes`"):
        tune("housner", SEED, small_amplitudes=(0.0,), candidates=[{}])
    with pytest.raises(ValueError, match="`sample_steps`"):
        tune("housner", SEED, sample_steps=(), candidates=[{}])
    with pytest.raises(ValueError, match="unknown engine"):
        tune("mujocco", SEED, candidates=[{}])


def test_a_tuning_files_rows_read_as_checks():
    """Each table of a tuning file reads row by row into its typed check; a column an older file lacks is NaN."""
    root = Path(__file__).resolve().parents[1]
    data = json.loads((root / "engines" / "models" / "tuning-pybullet.json").read_text())
    t = TuningResult.from_json(data)
    r = RatioCheck.from_row(t.table.iloc[0])
    assert (r.dt, r.amplitude, r.rel_error) == tuple(data["table"][k][0] for k in ("dt", "amplitude", "rel_error"))
    d = DecayCheck.from_row(t.decay_table.iloc[-1])
    assert d.impacts == data["decay_table"]["impacts"][-1] and isinstance(d.impacts, int)
    assert d.peak_analytic == data["decay_table"]["peak_analytic"][-1]
    p = PulseCheck.from_row(t.pulse_table.iloc[1])
    assert p.pulse == data["pulse_table"]["pulse"][1] and p.theta_max_rtol == data["pulse_table"]["theta_max_rtol"][1]
    old = PulseCheck.from_row(pd.Series({"rel_error": 0.01, "theta_max_rel_error": -0.02, "theta_max_rtol": 0.05}))
    assert old.pulse == "" and math.isnan(old.dt) and math.isnan(old.peak_engine)
    assert math.isnan(RatioCheck.from_row(pd.Series({"amplitude": 0.5, "rel_error": 0.0})).r_engine)
