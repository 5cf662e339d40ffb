"""The model-form part of the diagnosis' floor (housner.scenarios.diagnosis.verdict.integrator_families) and the
verdict's new pointers.

Closed forms first: the input a correct integrator feels under each
convention, the acceleration channel's noise read off still records, the
rank test of a drift along the recording order at its level, the share of an
energy loss put between the impacts, and the pointer of thresholds that move
alike in both directions.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from housner import GroundMotion, Specimen
from housner.effects import SensorOffset
from housner.engines import get_engine
from housner.model import REST_TOL
from housner.scenarios.diagnosis.comparison.localise import Metric
from housner.scenarios.diagnosis.comparison.pointers import Z_DRIFT, _flight_share, order_drift, physical_classes
from housner.scenarios.diagnosis.selection.fitting import fit_effect, joint_refit
from housner.scenarios.diagnosis.verdict.integrator_families import (
    FAMILIES,
    SCALE_SD,
    SHIFT_SAMPLES,
    UPSAMPLE,
    ModelForm,
    acc_channel_noise,
)

DT = 0.002


def _ramp_motion(n=11):
    return GroundMotion(np.arange(n, dtype=float), DT, "ramp")


def test_linear_input_on_the_fine_grid_passes_through_the_samples():
    mo = _ramp_motion()
    felt = ModelForm("linear", 0.0).felt(mo)
    assert felt.dt == pytest.approx(DT / UPSAMPLE)
    # every UPSAMPLE-th fine sample is a record sample, exactly; in between the line between them
    np.testing.assert_array_equal(felt.acc[::UPSAMPLE], mo.acc)
    np.testing.assert_allclose(felt.acc, np.arange(felt.acc.size) / UPSAMPLE, atol=1e-12)


def test_a_shift_delays_the_input_and_held_holds_each_sample():
    mo = _ramp_motion()
    # a delay of half a sample: the ramp reads half a unit less (the first samples clip at the start)
    late = ModelForm("linear", 0.5).felt(mo)
    np.testing.assert_allclose(late.acc[4:], np.arange(4, late.acc.size) / UPSAMPLE - 0.5, atol=1e-12)
    held = ModelForm("held", 0.0).felt(mo)
    # zero-order hold: sample k over [k dt, (k+1) dt) (1e-9 samples of slack for the rounding of t / dt)
    np.testing.assert_array_equal(held.acc, np.floor(np.arange(held.acc.size) / UPSAMPLE))
    # scale multiplies, and the release state is carried over
    mo0 = GroundMotion(np.ones(5), DT, "one", theta0=0.01)
    sc = ModelForm("linear", 0.0, scale=1.001).felt(mo0)
    assert sc.theta0 == 0.01 and np.allclose(sc.acc, 1.001)


def test_families_are_nested_and_draws_are_seeded():
    rng = np.random.default_rng(0)
    exact = [ModelForm.draw(rng, 0.0, "exact") for _ in range(20)]
    assert all(f == ModelForm(noise_seed=f.noise_seed) for f in exact)  # the library's own integrator
    same = [ModelForm.draw(rng, 0.0, "solver") for _ in range(50)]
    assert all(f.convention == "linear" and f.shift == 0.0 and f.scale == 1.0 for f in same)
    assert len({f.rest_tol for f in same}) > 1 and {f.substep_factor for f in same} == {1, 2, 4}
    close = [ModelForm.draw(rng, 0.0, "input-0.1") for _ in range(200)]
    assert max(abs(f.shift) for f in close) <= FAMILIES["input-0.1"][0] * SHIFT_SAMPLES
    assert all(f.convention == "linear" for f in close)
    anyf = [ModelForm.draw(rng, 0.0, "any") for _ in range(200)]
    assert {f.convention for f in anyf} == {"linear", "held"}
    assert max(abs(f.shift) for f in anyf) > 0.4  # uniform over +-0.5 samples: 200 draws reach past 0.4
    assert np.std([f.scale for f in anyf]) == pytest.approx(SCALE_SD, rel=0.3)  # 200 draws: s within ~10 %
    a = ModelForm.draw(np.random.default_rng(7), 0.1, "any")
    b = ModelForm.draw(np.random.default_rng(7), 0.1, "any")
    assert a == b
    with pytest.raises(ValueError, match="family"):
        ModelForm.draw(rng, 0.0, "some")


class _Rec:
    def __init__(self, kind, acc):
        self.kind = kind
        self.motion = GroundMotion(np.asarray(acc, dtype=float), DT, kind)


class _Camp:
    def __init__(self, recs):
        self.free_vibration = [r for r in recs if r.kind == "free_vibration"]
        self.ground_motion = [r for r in recs if r.kind == "ground_motion"]


def test_acceleration_channel_noise_is_read_where_the_table_is_still():
    rng = np.random.default_rng(1)
    sigma = 0.02
    # free vibrations that recorded the channel: their RMS about the mean (5000 samples: within 2 %)
    fv = [_Rec("free_vibration", 0.3 + rng.normal(0, sigma, 5000))]
    assert acc_channel_noise(_Camp(fv)) == pytest.approx(sigma, rel=0.03)
    # free vibrations written as zeros: the quiet ends of the ground motions, not their shaking
    t = np.arange(4000) * DT
    shake = np.where((t > 1) & (t < 6), 2.0 * np.sin(2 * math.pi * 40 * t), 0.0)
    gms = [_Rec("ground_motion", shake + rng.normal(0, sigma, t.size)) for _ in range(9)]
    est = acc_channel_noise(_Camp([_Rec("free_vibration", np.zeros(100)), *gms]))
    assert est == pytest.approx(sigma, rel=0.1)  # 400-sample MAD estimates, median of 9: within ~10 %
    assert acc_channel_noise(_Camp([_Rec("ground_motion", shake)])) == 0.0


def test_the_analytic_engine_takes_the_rest_rule_and_keeps_its_default_settings():
    eng = get_engine("housner")
    assert eng.settings() == {"r": None, "substeps": None}  # unchanged: the cache keys of earlier runs hold
    assert eng.rest_tol == REST_TOL
    loose = get_engine("housner", rest_tol=0.05)
    assert loose.settings()["rest_tol"] == 0.05
    spec = Specimen.bachmann2017()
    mo = GroundMotion(np.zeros(15000), DT, "fv", theta0=0.3 * spec.alpha)
    a, b = eng.simulate(spec, mo), loose.simulate(spec, mo)
    # a free vibration chatters toward rest: the looser rule (next peak below 5 % of alpha) stops it
    # earlier, with fewer impacts
    assert b.n_impacts < a.n_impacts and b.info["rest_tol"] == 0.05


def test_a_drift_along_the_recording_order_is_found_and_exchangeable_errors_are_not():
    rng = np.random.default_rng(2)
    n = 63
    flat = np.abs(rng.standard_t(3, n)) * 0.01
    assert order_drift([flat]) is None
    trend = flat + np.linspace(0, 0.03, n)
    d = order_drift([flat, trend])
    assert d is not None and d.name == "drift" and d.evidence[0].z > Z_DRIFT
    assert "recording order" in d.meaning and "grows" in d.evidence[0].label
    # its level: on 400 campaigns of exchangeable heavy-tailed errors, two models each, at most 1 %
    # false alarms (nominal 2 x 4.7e-4; 1 % allows a binomial count of 4 where ~0.4 are expected)
    alarms = sum(
        order_drift([np.abs(rng.standard_cauchy(n)), np.abs(rng.standard_cauchy(n))]) is not None for _ in range(400)
    )
    assert alarms <= 4


class _Cmp:
    def __init__(self, loc):
        self._loc = loc

    def localisation(self):
        return self._loc

    def discrepancies(self, z=3.0):
        out = []
        for k, (m, x) in self._loc.items():
            se = math.hypot(m.se, x.se)
            zz = (x.value - m.value) / se
            if abs(zz) > z:
                out.append((k, zz, m, x))
        return sorted(out, key=lambda r: -abs(r[1]))


def _m(v, se):
    return Metric(v, se, 50)


def test_an_energy_loss_between_impacts_points_to_dissipation_and_one_at_the_impact_does_not():
    # measured energy ratio 0.90 against the model's 0.946; the flight ratio (energy kept between
    # impacts) falls by the same factor: all of the extra loss is between the impacts
    between = {
        "energy_ratio": (_m(0.9026, 0.0013), _m(0.9461, 0.001)),
        "flight_ratio": (_m(0.955, 0.029), _m(1.002, 0.02)),
    }
    s, se = _flight_share(between)
    assert s == pytest.approx(1.0, abs=0.05) and se > 0.3
    assert physical_classes(_Cmp(between))[0].name == "dissipation"
    at_impact = {
        "energy_ratio": (_m(0.9026, 0.0013), _m(0.9461, 0.001)),
        "flight_ratio": (_m(1.0, 0.029), _m(1.002, 0.02)),
    }
    assert _flight_share(at_impact)[0] == pytest.approx(0.04, abs=0.05)
    assert physical_classes(_Cmp(at_impact))[0].name == "impact"


def test_uplift_thresholds_that_move_alike_point_to_the_input_and_opposite_ones_to_asymmetry():
    alike = {"onset_pos": (_m(1.13, 0.02), _m(0.99, 0.02)), "onset_neg": (_m(1.124, 0.02), _m(0.97, 0.02))}
    assert physical_classes(_Cmp(alike))[0].name == "vertical_input"
    opposite = {"onset_pos": (_m(1.13, 0.02), _m(0.99, 0.02)), "onset_neg": (_m(0.85, 0.02), _m(0.97, 0.02))}
    assert physical_classes(_Cmp(opposite))[0].name == "asymmetry"


def test_a_sensor_offset_starts_from_the_rotation_measured_at_rest():
    class Spec:
        alpha = 0.1489

    assert SensorOffset.measured_params({"tilt_offset": Metric(0.02, 0.0001, 100)}, Spec) == {
        "offset": pytest.approx(0.02 * 0.1489)
    }
    # not resolved (within 3 standard errors), or not measured: no start
    assert SensorOffset.measured_params({"tilt_offset": Metric(0.002, 0.001, 100)}, Spec) is None
    assert SensorOffset.measured_params({}, Spec) is None


def test_a_restitution_that_wears_shows_in_the_free_vibrations_energy_ratio_along_the_order():
    rng = np.random.default_rng(3)
    # three free vibrations (first, middle, last of 63 records), 20 impacts each, amplitude falling;
    # the energy ratio falls with the amplitude too (an amplitude-dependent law), which is held out
    pos = np.repeat([0, 31, 62], 20)
    amp = np.tile(np.geomspace(0.8, 0.05, 20), 3)
    law = 0.94 - 0.02 * amp
    noise = rng.normal(0, 0.005, pos.size)
    assert order_drift([], (pos, amp, law + noise)) is None
    worn = law - 0.0015 * pos + noise  # 0.947 -> 0.852 over the campaign, as in the brief
    d = order_drift([], (pos, amp, worn))
    assert d is not None and d.evidence[0].metric == "energy_ratio_order"
    assert d.evidence[0].measured == pytest.approx(-0.0015, rel=0.1)  # 60 impacts of 0.005 scatter


def test_a_measured_parameter_is_kept_by_the_fits():
    spec = Specimen.bachmann2017()
    # an objective whose optimum is elsewhere: the pinned offset stays as measured
    params, _v, n = fit_effect(
        "sensor_offset", lambda e: (e.offset - 0.01) ** 2, spec, pinned={"sensor_offset": {"offset": 0.003}}
    )
    assert params == {"offset": 0.003} and n == 1

    class Scorer:
        def loss(self, effects):
            return sum(
                (getattr(e, "offset", 0.0) - 0.01) ** 2
                + (getattr(e, "c", 0.0) - 0.5) ** 2
                + (getattr(e, "factor", 1.0) - 1.05) ** 2
                for e in effects
            )

    model = [
        ("sensor_offset", {"offset": 0.003}),
        ("rotational_damping", {"c": 0.2}),
        ("frequency_parameter", {"factor": 1.0}),
    ]
    out, _f = joint_refit(model, Scorer(), spec, pinned={"sensor_offset": {"offset": 0.003}})
    assert dict(out)["sensor_offset"] == {"offset": 0.003}  # the others move toward their optimum
    assert dict(out)["rotational_damping"]["c"] > 0.2 and dict(out)["frequency_parameter"]["factor"] > 1.0
