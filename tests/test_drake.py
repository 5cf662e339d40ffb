"""Drake engine: conformance, Housner's r, pulses against the analytic model, the protocol's promises, speed."""

from __future__ import annotations

import math
import pickle
import sys
import time

import numpy as np
import pytest
from shared import assert_overturns_and_holds, assert_pulses_follow_the_analytic_model

pytest.importorskip("pydrake", reason="the Drake engine needs drake: pip install -e '.[drake]'")

from housner import GroundMotion, Specimen  # noqa: E402
from housner.effects import make_effect  # noqa: E402
from housner.engines.base import engine_class  # noqa: E402
from housner.engines.conformance import check_engine  # noqa: E402
from housner.engines.drake_engine import DrakeEngine, _drake  # noqa: E402
from housner.engines.measures import first_impact_ratio  # noqa: E402
from housner.engines.tuning import pulse_motions, tune  # noqa: E402
from housner.errors import EngineUnavailable  # noqa: E402

SEED = Specimen.bachmann2017()


@pytest.fixture(scope="module")
def engine() -> DrakeEngine:
    return DrakeEngine()


def test_passes_the_conformance_check(engine):
    """All six checks (measured: at rest 6e-6 alpha, mirror 0, period -0.045 % / -0.003 %)."""
    report = check_engine(engine)
    assert report.ok, str(report)
    assert len(report.checks) == 6


SAP = dict(contact_approximation="sap", timestep=2.5e-4, stiffness=5e8)  # the defaults until 2026-11-26


@pytest.mark.parametrize("settings", [{}, SAP], ids=["tamsi", "sap"])
@pytest.mark.parametrize("a", [0.2, 0.5, 0.8])
def test_first_impact_keeps_housners_energy_ratio(a, settings):
    """Stiff point contact, TAMSI at 1/8 ms on 2.5e9 N/m (the defaults) and SAP at 1/4 ms on 5e8 N/m: r within
    0.3 % of Housner's (measured +0.07 / +0.10 / -0.11 % and +0.07 / -0.18 / -0.12 %).

    0.3 % is the tolerance the tuned MuJoCo and PyBullet meet over 0.2-0.9 alpha. The error is
    each impact's scatter with where it falls within the step (SAP: +-0.31 % over 0.2-0.9 alpha
    on a 0.05 grid), not a bias (SAP: mean +0.05 % over 0.05-0.9 alpha).
    """
    engine = DrakeEngine(**settings)
    res = engine.simulate(SEED, GroundMotion.free_vibration(a * SEED.alpha, 1.2, dt=1e-3))
    assert first_impact_ratio(res, SEED.alpha) == pytest.approx(SEED.r_housner, rel=3e-3)
    step = {**DrakeEngine.DEFAULTS, **settings}["timestep"]
    assert res.engine == "drake" and res.info["step"] == pytest.approx(step)


def test_tamsi_dissipation_default_is_drakes_own():
    """The ``dissipation`` default is the value Drake gives a point contact that names none (the module
    docstring's claim): the same trajectory to the last bit when the material leaves it unset."""
    import pydrake.geometry as geometry

    released = GroundMotion.free_vibration(0.3 * SEED.alpha, 1.5, dt=1e-3)
    ours = DrakeEngine().simulate(SEED, released).theta
    real = geometry.AddContactMaterial
    try:
        geometry.AddContactMaterial = lambda _d, k, f, props: real(None, k, f, props)
        drakes = DrakeEngine().simulate(SEED, released).theta
    finally:
        geometry.AddContactMaterial = real
    assert np.array_equal(ours, drakes)


def test_pulses_match_the_analytic_model(engine):
    """theta_max of the tuner's one-sine pulses within 1 % of the analytic model (measured +0.10 to +0.37 %).

    The issue allows 3 %; 1 % leaves a margin of 2.7 over the worst measured, which is one
    impact's scatter (the first peaks, before any impact, are within 0.1 %).
    """
    assert_pulses_follow_the_analytic_model(engine, SEED, rel=0.01, same_impacts=False)


def test_overturns_and_holds(engine):
    """A -3 g tan(alpha) push overturns the block to +pi/2 and the response holds there."""
    assert_overturns_and_holds(engine, SEED)


def test_settings_are_checked_and_travel(engine):
    for key, bad in (("timestep", 0.5), ("stiffness", -1.0), ("relaxation_time", 2.0), ("friction", "a lot")):
        with pytest.raises(ValueError, match=f"Drake setting `{key}`"):
            DrakeEngine(**{key: bad})
    with pytest.raises(ValueError, match="unknown Drake setting"):
        DrakeEngine(stepsize=1e-4)
    with pytest.raises(ValueError, match="`contact_approximation` 'tamsy'; did you mean 'tamsi'"):
        DrakeEngine(contact_approximation="tamsy")
    with pytest.raises(ValueError, match="`relaxation_time` is SAP's dissipation"):
        DrakeEngine(relaxation_time=1e-3)  # TAMSI would ignore it
    with pytest.raises(ValueError, match="`pivot_radius`"):
        DrakeEngine(pivot_radius=5e-3).simulate(SEED, GroundMotion.free_vibration(0.5 * SEED.alpha, 0.1))
    with pytest.raises(ValueError, match="cannot realise effect 'sliding'"):
        engine.simulate(SEED, GroundMotion.free_vibration(0.5 * SEED.alpha, 0.2), [make_effect("sliding", mu=0.3)])


def test_pickles_without_its_model_and_is_deterministic(engine):
    """The Drake diagram is built lazily in each process; a copy (fresh model) gives identical results."""
    m = pulse_motions(SEED)[0]
    first = engine.simulate(SEED, m)  # builds and caches the model
    copy = pickle.loads(pickle.dumps(engine))
    assert copy.settings() == engine.settings() and copy.version() == engine.version()
    again = copy.simulate(SEED, m)
    assert np.array_equal(first.theta, again.theta) and np.array_equal(first.theta_dot, again.theta_dot)


def test_missing_package_is_one_line_naming_the_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "pydrake", None)
    with pytest.raises(EngineUnavailable, match=r"pip install -e '\.\[drake\]'") as info:
        _drake()
    assert "\n" not in str(info.value)


def test_tuning_candidates_are_short_and_aimed():
    """Near Housner's r: the defaults first, steps dividing the tuner's 1 ms samples; away from it: softer
    pivots on SAP (whose dissipation time the lower targets need)."""
    near = DrakeEngine.tuning_candidates(SEED, SEED.r_housner)
    assert near and near[0] == {}
    steps = [{**DrakeEngine.DEFAULTS, **c}["timestep"] for c in near]
    assert all(abs(1e-3 / h - round(1e-3 / h)) < 1e-9 for h in steps)
    stiff = DrakeEngine.DEFAULTS["stiffness"]
    for target in (0.85, 0.90, 0.96):
        cands = DrakeEngine.tuning_candidates(SEED, target)
        assert 0 < len(cands) <= 12
        assert all(c["stiffness"] < stiff and c["contact_approximation"] == "sap" for c in cands)
        for c in cands:
            DrakeEngine(**c)  # every candidate is a valid setting
    below = DrakeEngine.tuning_candidates(SEED, 0.90)
    assert all(c["relaxation_time"] > 0 for c in below)


def test_a_softer_damped_contact_lowers_r():
    """The knob the lower-target candidates turn (measured r = 0.946 at 0.5 alpha, 0.6 % below Housner's)."""
    res = DrakeEngine(**{**SAP, "stiffness": 2e6}, relaxation_time=1e-3).simulate(
        SEED, GroundMotion.free_vibration(0.5 * SEED.alpha, 1.2, dt=1e-3)
    )
    assert first_impact_ratio(res, SEED.alpha) < SEED.r_housner * 0.998


def test_the_tuner_runs_it():
    """``tune`` drives the registered engine end to end (one candidate, one release, no pulses)."""
    assert engine_class("drake") is DrakeEngine
    res = tune(
        "drake",
        SEED,
        amplitudes=(0.5,),
        small_amplitudes=(),
        candidates=[{}],
        progress=False,
        check_pulses=False,
        check_decay=False,
        sample_steps=(1e-3,),
    )
    assert res.met and res.settings == DrakeEngine().settings()


def test_speed(engine):
    """CPU seconds per simulated second on a 10 s noise record at 3.16 ms: measured 0.25; bound 1.0.

    The bound is four times the measurement so that a loaded machine does not fail it; it still
    catches a lost optimisation (a Simulator per step, sampled output ports: 0.3-0.8).
    """
    dt = 0.01 / math.sqrt(10.0)
    n = int(10.0 / dt) + 1
    acc = np.random.default_rng(1).standard_normal(n)
    motion = GroundMotion(0.1 * 9.80665 * acc / acc.std(), dt, name="noise 0.1 g RMS")
    engine.simulate(SEED, GroundMotion.free_vibration(0.1, 0.05, dt=dt))  # model built outside the timing
    c0 = time.process_time()
    res = engine.simulate(SEED, motion)
    cpu = time.process_time() - c0
    assert not res.overturned
    assert cpu / motion.duration < 1.0
