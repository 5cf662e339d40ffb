"""The chaos floor: measured engine errors, the analytic model's self-agreement, the verdict sentence."""

from __future__ import annotations

import json

import numpy as np
import pytest

from housner.engines import get_engine
from housner.scenarios.catalogue.scenario import load_scenario
from housner.scenarios.motions.build import build_motions
from housner.scenarios.runs import chaos
from housner.scenarios.runs.chaos import (
    ChaosFloor,
    EngineErrors,
    chaos_floor,
    errors_from_dict,
    floor_verdict,
    measure_engine_errors,
    run_engine_errors,
)

SCENARIO = load_scenario("elcentro-strong")
SPEC = SCENARIO.specimen


@pytest.fixture(scope="module")
def motions():
    return build_motions(SCENARIO, 30)[0]


def test_measurement_recovers_a_known_r_error():
    """The analytic model run with r 0.4 % below Housner's measures as -0.4 % (to 0.02 %) and p exact.

    The measurement reads peaks from samples 3.16 ms apart (parabolic refinement), so it carries
    an error of its own; 0.02 % of r is a tenth of the tuned engines' errors.
    """
    eng = get_engine("housner", r=SPEC.r_housner * (1 - 0.004))
    err = measure_engine_errors(eng, SPEC, dt=0.0031622776601683794)
    assert np.allclose(err.r_rel_errors, -0.004, atol=2e-4)
    assert err.eps_r == pytest.approx(0.004, abs=2e-4)
    # the time to the first impact does not involve r: p within 0.05 % (the sampled crossing)
    assert err.eps_p < 5e-4


def test_floor_falls_as_the_perturbation_grows(motions):
    """Rocking is chaotic: a 1 % r error breaks record-by-record agreement far more than 0.01 %.

    No perturbation at all is a floor of 100 % (the model is deterministic).
    """
    zero = EngineErrors("none", (0.5,), (0.0,), (0.0,), 0.003)
    assert chaos_floor(SPEC, motions, zero, rtol=0.03, atol=0.0).share == 1.0
    tiny = chaos_floor(SPEC, motions, EngineErrors("x", (0.5,), (1e-4,), (1e-4,), 0.003), rtol=0.03, atol=0.0)
    big = chaos_floor(SPEC, motions, EngineErrors("x", (0.5,), (1e-2,), (1e-2,), 0.003), rtol=0.03, atol=0.0)
    assert set(big.shares) == {"r+", "r-", "p+", "p-"} and big.n == len(motions)
    assert big.share < tiny.share <= 1.0
    assert big.share_min <= big.share <= big.share_max


def test_run_errors_for_every_engine_but_the_reference(motions):
    out = run_engine_errors(SPEC, {"housner": {}, "mujoco": {}}, motions[:2])
    assert set(out) == {"mujoco"}
    d = out["mujoco"]
    # MuJoCo's tuned contact: r within 0.5 % at every release amplitude (the tuner's tolerance)
    assert max(abs(x) for x in d.r_rel_errors) < 5e-3 and d.r_reference == pytest.approx(SPEC.r_housner)
    # run.json's entry: the errors with their RMS, read back as they were
    stored = json.loads(json.dumps(d.to_json()))
    assert stored["eps_r"] == pytest.approx(d.eps_r) and errors_from_dict(stored) == d
    # no floor without the analytic model as the reference
    assert run_engine_errors(SPEC, {"mujoco": {}, "pybullet": {}}, motions[:2], reference="mujoco") == {}


def test_errors_are_cached_and_measured_meanwhile(motions, tmp_path, monkeypatch):
    """The cache gives back the very numbers measured; a changed setting is measured again; the
    background variant returns what the direct call does, and raises what the measurement raised."""
    engines = {"housner": {}, "mujoco": {}}
    first = run_engine_errors(SPEC, engines, motions[:2], cache_dir=tmp_path)
    (entry,) = (tmp_path / "engine-errors").glob("*.json")
    calls = []
    real = chaos.measure_engine_errors
    monkeypatch.setattr(chaos, "measure_engine_errors", lambda *a, **k: calls.append(1) or real(*a, **k))
    assert chaos.run_engine_errors_meanwhile(SPEC, engines, motions[:2], cache_dir=tmp_path)() == first
    assert calls == []  # read back, not measured
    changed = run_engine_errors(SPEC, {"housner": {}, "mujoco": {"timestep": 1e-4}}, motions[:2], cache_dir=tmp_path)
    assert calls == [1] and changed["mujoco"].r_rel_errors != first["mujoco"].r_rel_errors
    entry.write_text("{not json")  # a damaged entry: measured again, and written whole
    assert run_engine_errors(SPEC, engines, motions[:2], cache_dir=tmp_path) == first and calls == [1, 1]
    assert json.loads(entry.read_text()) == first["mujoco"].to_json()
    monkeypatch.setattr(chaos, "measure_engine_errors", lambda *a, **k: 1 / 0)  # a record error: named
    assert "ZeroDivisionError" in chaos.run_engine_errors_meanwhile(SPEC, engines, motions[:2])()["mujoco"].error
    monkeypatch.setattr(chaos, "measure_engine_errors", lambda *a, **k: {}[0])  # a bug: raised where it waits
    with pytest.raises(KeyError):
        chaos.run_engine_errors_meanwhile(SPEC, engines, motions[:2])()


def test_verdict_names_the_figures_and_the_side():
    fl = ChaosFloor(
        {"r+": 0.7, "r-": 0.8}, {"r+": 1.0, "r-": 1.0}, 0.75, 0.7, 0.8, 100, engine="e", eps_r=1e-3, eps_p=5e-4
    )
    at = floor_verdict(72, 100, fl)
    # the floor is the lowest perturbed share (70 %): the one the verdict is decided against
    assert "72% [" in at and "chaos floor of 70%" in at and "70%-80%" in at and "at the floor" in at
    below = floor_verdict(40, 100, fl)  # Wilson upper bound of 40/100 is about 50 % < 70 %
    assert "below the floor" in below
    assert floor_verdict(0, 0, fl) == "no paired records"
