"""OpenSees engine: Housner's r, pulses against the analytic model, conformance and the protocol's promises."""

from __future__ import annotations

import pickle
import sys

import pytest
from shared import assert_overturns_and_holds, assert_pulses_follow_the_analytic_model

pytest.importorskip("openseespy.opensees", reason="the OpenSees engine needs openseespy: pip install -e '.[opensees]'")

from housner import GroundMotion, Specimen  # noqa: E402
from housner.effects import make_effect  # noqa: E402
from housner.engines.measures import first_impact_ratio  # noqa: E402
from housner.engines.opensees_engine import OpenSeesEngine  # noqa: E402

SEED = Specimen.bachmann2017()


@pytest.fixture(scope="module")
def engine() -> OpenSeesEngine:
    return OpenSeesEngine()


# The six conformance checks run over the registry in test_conformance.py (measured here: rest
# 1.0e-4 alpha, mirror 7e-5 of theta_max, period +0.006 %).


@pytest.mark.parametrize(
    ("algorithm", "contact_element"),
    [("KrylovNewton", "zeroLengthContact2D"), ("Newton", "zeroLengthContact2D"), ("KrylovNewton", "flatSliderBearing")],
)
@pytest.mark.parametrize("a", [0.2, 0.5, 0.8])
def test_first_impact_keeps_housners_energy_ratio(a, algorithm, contact_element):
    """Tuned damped penalty contact: r within 0.3 % of Housner's (measured at 0.2 / 0.5 / 0.8 alpha:
    zeroLengthContact2D, the default, with Krylov-Newton +0.095 / -0.024 / +0.005 %, with Newton
    +0.094 / -0.025 / +0.004 %; flatSliderBearing with Krylov-Newton +0.058 / +0.199 / +0.001 %).

    0.3 % is the tolerance the tuned MuJoCo and PyBullet meet over 0.2-0.9 alpha; the worst r error
    over 0.2-0.9 alpha in the tuner is 0.44-0.45 % for these settings, at other amplitudes.
    """
    engine = OpenSeesEngine(algorithm=algorithm, contact_element=contact_element)
    res = engine.simulate(SEED, GroundMotion.free_vibration(a * SEED.alpha, 1.2, dt=1e-3))
    assert first_impact_ratio(res, SEED.alpha) == pytest.approx(SEED.r_housner, rel=3e-3)
    assert res.engine == "opensees" and res.info["step"] == pytest.approx(2e-4)


def test_contact_elements_agree(engine):
    """The node-to-node contact (the default) and the friction bearing it replaced rock alike: the same
    impacts, theta within 0.02 alpha over 2 s of free rocking from 0.5 alpha (measured 0.0104 alpha; the
    two elements' stick laws differ, and a 0.1 % change of one impact's r shifts the later peaks by about
    that much)."""
    m = GroundMotion.free_vibration(0.5 * SEED.alpha, 2.0, dt=1e-3)
    new, old = engine.simulate(SEED, m), OpenSeesEngine(contact_element="flatSliderBearing").simulate(SEED, m)
    assert len(new.impact_times) == len(old.impact_times) == 4
    assert abs(new.theta - old.theta).max() < 0.02 * SEED.alpha


def test_a_corner_that_touches_down_after_a_nanometre_lift_is_finished_at_a_looser_tolerance(engine):
    """``elcentro`` motion 39 at 0.023 s: a corner lifted by 26 nm comes down again, the contact's stick force
    jumps by 0.01-0.1 N and no shorter step converges to 1 mN; the last retry finishes that one sample interval
    at 0.1 N and counts it. The record then runs to its end (before the retry it failed there), and free rocking
    never needs it."""
    from housner.scenarios.catalogue.scenario import load_scenario
    from housner.scenarios.motions.build import build_motions

    sc = load_scenario("elcentro")
    motion = build_motions(sc, 40)[0][39]
    res = engine.simulate(sc.specimen, motion)
    assert res.info["loose_samples"] == 1 and res.info["retried_samples"] >= 1
    assert not res.overturned and len(res.t) == motion.n  # the whole record, no overturn (bearing: the same)
    free = engine.simulate(SEED, GroundMotion.free_vibration(0.5 * SEED.alpha, 1.0))
    assert free.info["loose_samples"] == 0


def test_pulses_match_the_analytic_model(engine):
    """theta_max of the tuner's three one-sine pulses within 1 % of the analytic model (measured -0.28 to -0.78 %).

    The compliant contact tilts the block slightly before uplift and rocks it a little less far;
    1 % is a third of the issue's 3 %.
    """
    assert_pulses_follow_the_analytic_model(engine, SEED, rel=0.01, same_impacts=True)


def test_overturns_and_holds(engine):
    """A -3 g tan(alpha) push overturns the block to +pi/2 and the response holds there."""
    assert_overturns_and_holds(engine, SEED)


def test_settings_are_checked_and_travel(engine):
    with pytest.raises(ValueError, match="OpenSees setting `timestep`"):
        OpenSeesEngine(timestep=0.5)
    with pytest.raises(ValueError, match="OpenSees setting `contact_damping`"):
        OpenSeesEngine(contact_damping=-1.0)
    with pytest.raises(ValueError, match="OpenSees setting `friction` must be a number"):
        OpenSeesEngine(friction="high")
    with pytest.raises(ValueError, match="unknown OpenSees setting"):
        OpenSeesEngine(stepsize=1e-4)
    with pytest.raises(ValueError, match="`algorithm` 'Krylov'; did you mean 'KrylovNewton'"):
        OpenSeesEngine(algorithm="Krylov")
    with pytest.raises(ValueError, match="`contact_element` 'zeroLengthContact'; did you mean 'zeroLengthContact2D'"):
        OpenSeesEngine(contact_element="zeroLengthContact")
    copy = pickle.loads(pickle.dumps(OpenSeesEngine(timestep=1e-4)))
    assert copy.settings()["timestep"] == 1e-4 and copy.version() == engine.version()
    with pytest.raises(ValueError, match="cannot realise effect 'sliding'"):
        engine.simulate(SEED, GroundMotion.free_vibration(0.5 * SEED.alpha, 0.2), [make_effect("sliding", mu=0.3)])


def test_quiet(engine, capfd):
    """No OpenSees chatter on stdout/stderr per record."""
    engine.simulate(SEED, GroundMotion.free_vibration(0.5 * SEED.alpha, 0.3))
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_tuning_candidates():
    """Short lists; damping for lower targets, a softer contact for higher ones, defaults first at Housner's r."""
    at = OpenSeesEngine.tuning_candidates(SEED, SEED.r_housner)
    below = OpenSeesEngine.tuning_candidates(SEED, 0.90)
    above = OpenSeesEngine.tuning_candidates(SEED, 0.9532)
    assert at[0] == {} and all(len(c) <= 12 for c in (at, below, above))
    assert all(c["contact_damping"] > OpenSeesEngine.DEFAULTS["contact_damping"] for c in below)
    assert all(c["contact_stiffness"] < OpenSeesEngine.DEFAULTS["contact_stiffness"] for c in above)
    for c in at + below + above:
        OpenSeesEngine(**c)  # every candidate is a valid setting


@pytest.mark.parametrize(
    "raised, says",
    [
        (ImportError("No module named 'openseespy'"), "pip install -e '.[opensees]'"),
        (RuntimeError("Failed to import openseespy on Linux."), "apt-get install libblas3 liblapack3"),
    ],
)
def test_missing_package_or_library_is_one_line_naming_the_install(monkeypatch, raised, says):
    """No openseespy, or openseespy without Debian's BLAS/LAPACK: EngineUnavailable naming what to install."""
    import builtins

    from housner.errors import EngineUnavailable

    real_import = builtins.__import__

    def fake_import(name, *args, **kwargs):
        if name.startswith("openseespy"):
            raise raised
        return real_import(name, *args, **kwargs)

    monkeypatch.delitem(sys.modules, "openseespy.opensees", raising=False)
    monkeypatch.setattr(builtins, "__import__", fake_import)
    with pytest.raises(EngineUnavailable) as e:
        OpenSeesEngine()
    assert says in str(e.value) and "\n" not in str(e.value)
