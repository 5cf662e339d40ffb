"""Contact tuning: the closed forms it relies on, and the tuner's choice on tiny candidate lists."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from engines.tuning import (
    DEFAULT_AMPLITUDES,
    first_impact_ratio,
    first_peak,
    free_rocking_quarter_period,
    free_vibration_motions,
    pulse_motions,
    tune,
    tuning_report_figure,
)
from housner import GroundMotion, Specimen
from housner.calibration import half_cycle_time
from housner.model import simulate as housner_simulate

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


def test_default_amplitudes():
    assert DEFAULT_AMPLITUDES[0] == 0.2 and DEFAULT_AMPLITUDES[-1] == 0.9 and len(DEFAULT_AMPLITUDES) == 15


def test_tuner_picks_the_candidate_that_meets_the_target():
    # Two candidates of the analytic engine: r = 0.90 (5 % off) and Housner's r (exact); two amplitudes.
    res = tune("housner", SEED, amplitudes=(0.3, 0.7), candidates=[{"r": 0.90}, {"r": SEED.r_housner}], progress=False)
    assert res.met
    assert res.settings["r"] == SEED.r_housner
    assert res.worst_rel_error < 1e-5
    assert list(res.candidates["met"]) == [False, True]
    assert res.candidates["worst_rel_error"].iloc[0] == pytest.approx(1 - 0.90 / SEED.r_housner, rel=1e-4)
    assert list(res.table["amplitude"]) == [0.3, 0.7]
    assert np.all(res.pulse_table["rel_error"].abs() < 1e-9)  # the analytic engine against itself
    assert "MET" in res.summary() and "NOT MET" not in res.summary()
    json.dumps(res.to_dict(), default=float)  # plain data


def test_tuner_says_so_when_no_candidate_meets_the_target():
    res = tune(
        "housner", SEED, target_r=0.9532, amplitudes=(0.3, 0.7), candidates=[{"r": 0.80}, {"r": 0.94}], progress=False
    )
    assert not res.met
    assert res.settings["r"] == 0.94  # the closer one
    assert res.worst_rel_error == pytest.approx(1 - 0.94 / 0.9532, rel=1e-4)
    assert "NOT MET" in res.summary()
    fig = tuning_report_figure(res)
    ax = fig.axes[0]
    assert len(fig.axes) == 1 and "NOT met" in ax.get_title()
    assert ax.lines[-1].get_ydata() == pytest.approx(res.table["r_engine"].to_numpy())


def test_tuner_on_mujoco_prefers_the_tuned_contact_to_mujocos_defaults():
    # MuJoCo's own defaults (2 ms step, solref 0.02, elliptic cone, impratio 1) lose several percent per impact;
    # the tuned defaults are within 0.5 %. Two candidates, two amplitudes.
    stock = {"timestep": 2e-3, "solref": (0.02, 1.0), "solimp": (0.9, 0.95, 0.001, 0.5, 2.0), "cone": "elliptic"}
    stock["impratio"] = 1.0
    res = tune("mujoco", SEED, amplitudes=(0.3, 0.7), candidates=[stock, {}], progress=False)
    assert res.met
    assert res.settings["timestep"] == 1.25e-4
    worst_stock = res.candidates["worst_rel_error"].iloc[0]
    assert worst_stock > 0.02
    assert res.cost_per_sim_second > 0


def test_tuner_validates_its_arguments():
    with pytest.raises(ValueError, match="`target_r`"):
        tune("housner", SEED, target_r=1.2, candidates=[{}])
    with pytest.raises(ValueError, match="`amplitudes`"):
        tune("housner", SEED, amplitudes=(0.5, 1.5), candidates=[{}])
    with pytest.raises(ValueError, match="unknown engine"):
        tune("mujocco", SEED, candidates=[{}])
