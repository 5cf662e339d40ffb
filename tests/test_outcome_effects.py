"""The effect library on outcome records: which effects the records can feel, their grids, their tables, and
a library effect found behind outcomes it caused."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from test_outcomes import DT, SPEC, _campaign, _pulses

from housner.effects import EFFECTS, Effect, apply_effects, make_effect, param, register_effect
from housner.effects.registry import STAGE_DISSIPATION
from housner.model import simulate_many, theta_max_many
from housner.scenarios.diagnosis.outcomes.outcome_diagnosis import diagnose_outcomes
from housner.scenarios.diagnosis.outcomes.outcome_effects import GRID_SHARES, effect_table, outcome_effects
from housner.scenarios.diagnosis.outcomes.outcome_models import Geometry


def test_the_records_search_every_effect_they_can_feel():
    found, left = outcome_effects(SPEC)
    names = {e.name for e in found}
    assert {"restitution", "rotational_damping", "amplitude_dependent_restitution", "frequency_parameter"} <= names
    why = {e.name: e.why for e in left}
    # a sensor's offset or lag changes what is read, never whether the block falls
    assert why["sensor_offset"] == why["time_lag"] == "sensor"
    assert not names & set(why)


def test_a_grid_holds_the_shares_of_the_way_to_each_bound_and_leaves_the_neutral_value_out():
    found, _ = outcome_effects(SPEC, ["rotational_damping", "frequency_parameter", "sliding"])
    grids = {e.name: e for e in found}
    c = grids["rotational_damping"]  # bounds 0 .. 5 1/s, neutral 0: one side only
    assert c.values == pytest.approx([5.0 * s for s in GRID_SHARES])
    f = grids["frequency_parameter"]  # bounds 0.5 .. 2, neutral 1: both sides
    assert len(f.values) == 2 * len(GRID_SHARES) and 1.0 not in f.values
    assert min(f.values) == pytest.approx(0.5) and max(f.values) == pytest.approx(2.0)
    mu = grids["sliding"]  # neutral inf, outside its bounds: spaced over them, logarithmically
    assert mu.values[0] == pytest.approx(0.01) and mu.values[-1] == pytest.approx(2.0)
    assert np.allclose(np.diff(np.log(mu.values)), np.log(mu.values[1] / mu.values[0]))


def test_a_users_effect_is_a_candidate_on_outcome_records():
    @dataclass(frozen=True)
    class ExtraLoss(Effect):
        """A test effect: r scaled by a factor."""

        name = "test_extra_loss"
        stage = STAGE_DISSIPATION
        k: float = param("-", (0.5, 1.0), neutral=1.0, default=1.0, doc="factor on r")

        def modify_params(self, params, specimen):
            return params.with_r(params.r * self.k)

    register_effect(ExtraLoss)
    try:
        found, _ = outcome_effects(SPEC)
        assert "test_extra_loss" in {e.name for e in found}
    finally:
        EFFECTS.pop("test_extra_loss", None)


def test_the_peaks_with_kernel_terms_equal_the_histories():
    """theta_max_many with an effect's kernel terms gives the peaks and the overturns of simulate_many."""
    accs = _pulses(30, seed=4)
    motions = [_campaign(accs, [False] * 30).outcomes[i].motion for i in range(30)]
    for name, value in (("rotational_damping", {"c": 0.8}), ("amplitude_dependent_restitution", {"exponent": 0.4})):
        plan = apply_effects(SPEC, motions[0], [make_effect(name, SPEC, **value)], prefer_terms=True)
        assert plan.terms is not None
        peak, ov, _ = theta_max_many(SPEC, accs, DT, params=plan.params, terms=plan.terms)
        res = simulate_many(SPEC, motions, params=plan.params, terms=plan.terms)
        assert np.array_equal(ov, [r.overturned for r in res])
        standing = ~ov
        # one kernel, one arithmetic: equal to the last bit
        assert np.array_equal(peak[standing], np.array([r.theta_max for r in res])[standing] / SPEC.alpha)


def test_an_effect_table_is_the_records_run_with_the_effect():
    accs = _pulses(20, seed=6)
    camp = _campaign(accs, [False] * 20)
    geo = Geometry.of(camp)
    found, _ = outcome_effects(SPEC, ["rotational_damping"])
    motions = [r.motion for r in camp.outcomes]
    table = effect_table(found[0], motions, SPEC, [geo.params()])
    for j, c in enumerate(found[0].values):
        plan = apply_effects(SPEC, motions[0], [make_effect("rotational_damping", SPEC, c=c)], params=geo.params())
        expected = [r.overturned for r in simulate_many(SPEC, motions, params=plan.params, terms=plan.terms)]
        assert np.array_equal(table.overturned[:, 0, j], expected)


@pytest.fixture(scope="module")
def damped():
    """Outcomes of the block with rotational damping c = 1.5 1/s (a value of its grid)."""
    accs = _pulses(200, seed=21)
    camp = _campaign(accs, [False] * len(accs))
    plan = apply_effects(SPEC, camp.outcomes[0].motion, [make_effect("rotational_damping", SPEC, c=1.5)])
    _, ov, _ = theta_max_many(SPEC, accs, DT, params=plan.params, terms=plan.terms)
    _, ov_plain, _ = theta_max_many(SPEC, accs, DT)
    assert 20 < ov.sum() < 180 and np.sum(ov != ov_plain) >= 15  # the damping decides enough outcomes
    return diagnose_outcomes(_campaign(accs, ov), folds=4, seed=0, repeats=2)


def test_the_library_effect_behind_the_outcomes_is_found(damped):
    assert damped.effects == ["rotational_damping"]
    assert damped.final.params["c"] == pytest.approx(1.5)
    assert damped.status == "explained"
    assert {e.name for e in damped.searched} >= {"rotational_damping", "restitution"}
    assert "sensor_offset" in {e.name for e in damped.left_out}


def test_a_frozen_library_effect_transfers_to_new_records(damped, tmp_path):
    """The damped model, written and read back, predicts other records of the same damped block with nothing
    refitted: its effect is tabulated at its fitted value only."""
    from housner.reports.diagnosis.outcome_text import write_outcome_json
    from housner.scenarios.diagnosis.outcomes.outcome_transfer import read_frozen_model

    path = tmp_path / "damped.json"
    write_outcome_json(damped, path)
    frozen = read_frozen_model(path)
    assert frozen.name == "rotational_damping" and frozen.params["c"] == pytest.approx(1.5)
    accs = _pulses(120, seed=22)
    camp = _campaign(accs, [False] * len(accs))
    plan = apply_effects(SPEC, camp.outcomes[0].motion, [make_effect("rotational_damping", SPEC, c=1.5)])
    ov = theta_max_many(SPEC, accs, DT, params=plan.params, terms=plan.terms)[1]
    d = diagnose_outcomes(_campaign(accs, ov), folds=4, seed=0, repeats=1, effects=[], model=frozen)
    t = d.transfer
    assert t.model == "rotational_damping"
    # the same physics on new records: it decides every outcome but the lapse's share
    assert t.scores.accuracy == 1.0
    assert all(c.advantage > 0 for c in t.against.values())
