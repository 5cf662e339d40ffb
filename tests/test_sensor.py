"""The theta sensor assessed before the physics: its noise as measured, its faults named and masked.

Unit checks on synthetic noise and samples; the campaigns of the second generator
(tests/independent_campaigns.py) check the whole assessment (test_sensor_campaigns).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from housner.reports.diagnosis.sensor_text import noise_text, sensor_text
from housner.scenarios.campaigns.sensor_noise import WHITE, estimate_sensor_noise
from housner.scenarios.diagnosis.comparison.history_error import record_error
from housner.scenarios.diagnosis.sensor_assessment import _dropouts, _saturation, _spikes, _trend
from housner.scenarios.diagnosis.verdict.status import STATUS_RULE, status_rule

DT = 0.002


def _ou(rng, n, tau, sd):
    a = math.exp(-DT / tau)
    e = rng.normal(0.0, sd * math.sqrt(1 - a * a), n)
    x = np.empty(n)
    x[0] = rng.normal(0.0, sd)
    for i in range(1, n):
        x[i] = a * x[i - 1] + e[i]
    return x


def _colored(rng, n, white=0.4e-3, ou=0.6e-3, tau=0.1, hum=0.6e-3, f=50.0):
    t = np.arange(n) * DT
    return rng.normal(0, white, n) + _ou(rng, n, tau, ou) + hum * np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))


def test_white_noise_is_called_white_and_keeps_the_independent_sample_formulas():
    rng = np.random.default_rng(0)
    sn = estimate_sensor_noise([("rest", rng.normal(0, 8e-4, 3000)) for _ in range(8)], DT)
    assert sn.white and sn.sigma == pytest.approx(8e-4, rel=0.02)  # 24000 samples: sd to ~0.5 %
    assert sn.mean_sd(1.0, 9) == pytest.approx(1 / 3)
    assert WHITE.white and WHITE.effective_samples(50) == pytest.approx(50)


def test_correlated_noise_is_measured_with_its_variance_and_its_correlation():
    rng = np.random.default_rng(1)
    segs = [("rest", _colored(rng, 3000)) for _ in range(20)]
    true_sd = math.sqrt(0.4e-3**2 + 0.6e-3**2 + 0.6e-3**2 / 2)
    sn = estimate_sensor_noise(segs, DT)
    assert not sn.white
    # 60000 samples, but correlated over ~50 samples (tau 0.1 s): ~1200 independent ones, sd to ~3 %
    assert sn.sigma == pytest.approx(true_sd, rel=0.06)
    # the difference-based estimate sees mostly the white part: about twice too small
    assert sn.diff_ratio > 1.6
    # the sd of a 9-sample mean: the measured model against the empirical one (not 1/3 of sigma)
    emp = np.std([x[i : i + 9].mean() for _s, x in segs for i in range(0, 2990, 37)]) / true_sd
    assert sn.mean_sd(1.0, 9) == pytest.approx(emp, rel=0.08)
    assert sn.mean_sd(1.0, 9) > 0.6
    # the measured autocorrelation against the truth's: white at lag 0 only, the OU part exp(-k dt / tau), the
    # hum's cos(2 pi f k dt) (it pulls lag 5, half its period, down); ~1200 independent samples: +-0.05
    d = [sn.draw(rng, 1.0, 3000) for _ in range(100)]
    for k in (1, 5, 10):
        truth = (0.6e-3**2 * math.exp(-k * DT / 0.1) + 0.6e-3**2 / 2 * math.cos(2 * np.pi * 50 * k * DT)) / true_sd**2
        assert sn.rho[k] == pytest.approx(truth, abs=0.05)
        # drawn noise has the measured correlation (100 draws of 3000: ~6000 independent samples, +-0.04)
        drawn = sum(float(np.dot(x[:-k], x[k:])) for x in d) / sum(float(np.dot(x, x)) for x in d)
        assert drawn == pytest.approx(sn.rho[k], abs=0.04)
    assert np.std(np.concatenate(d)) == pytest.approx(1.0, rel=0.05)


def test_too_few_quiet_samples_leave_the_noise_white_and_unmeasured():
    sn = estimate_sensor_noise([("rest", np.zeros(100))], DT)
    assert sn.white and sn.n_samples == 0 and "not measured" in noise_text(sn)


def test_flat_tops_spikes_and_dropouts_are_found_where_they_are():
    rng = np.random.default_rng(2)
    t = np.arange(2000) * DT
    th = 0.05 * np.sin(2 * np.pi * 1.0 * t) + rng.normal(0, 8e-4, t.size)
    clipped = np.clip(th, -0.03, 0.03)
    bad, levels = _saturation(clipped)
    assert sorted(levels) == [-0.03, 0.03]
    assert np.array_equal(bad, np.abs(clipped) == 0.03)
    assert not _saturation(th)[1]  # unclipped: no flat top
    spiky = th.copy()
    spiky[[300, 900, 1500]] += [0.025, -0.025, 0.025]
    assert list(np.flatnonzero(_spikes(spiky))) == [300, 900, 1500]
    assert not _spikes(th).any()  # a smooth swing and its noise make none
    held = th.copy()
    held[700:760] = held[699]
    got = np.flatnonzero(_dropouts(held, np.zeros(th.size, dtype=bool)))
    assert got[0] == 700 and got[-1] == 759 and got.size == 60
    assert not _dropouts(th, np.zeros(th.size, dtype=bool)).any()


def test_masked_samples_are_left_out_of_the_error():
    y = np.zeros(100)
    m = np.zeros(100)
    y[10:20] = 1.0  # a fault's samples, far off
    valid = np.ones(100, dtype=bool)
    valid[10:20] = False
    assert record_error(m, y, 100, 1.0) > 0.3
    assert record_error(m, y, 100, 1.0, valid=valid) == 0.0


def test_a_trend_along_the_order_is_told_from_scatter():
    rng = np.random.default_rng(3)
    x = np.arange(60.0)
    _a, _b, t0 = _trend(x, rng.normal(1.0, 0.02, 60))
    _a, b, t1 = _trend(x, 1.0 + 0.25 * x / 59 + rng.normal(0, 0.02, 60))
    assert abs(t0) < 4 and t1 > 4 and b * 59 == pytest.approx(0.25, abs=0.03)


def test_the_status_rule_is_one_table_that_covers_every_case():
    for combo in np.ndindex(2, 2, 2, 2, 2):
        status_rule(*map(bool, combo))  # no case without a row
    assert status_rule(True, False, False, False, True) == "no_misfit"
    assert status_rule(True, True, True, False, True) == "explained"
    assert status_rule(True, True, True, True, True) == "partly_explained"
    assert status_rule(True, False, True, True, True) == "unexplained"
    assert status_rule(False, False, False, False, True) == "inconclusive"
    assert {s for _row, s in STATUS_RULE} == {
        "no_misfit",
        "explained",
        "partly_explained",
        "unexplained",
        "inconclusive",
    }


# ----------------------------------------------------------------------------
# on campaigns the library did not write (tests/independent_campaigns.py)
@pytest.fixture(scope="module")
def indep(tmp_path_factory):
    import independent_campaigns as ic

    base = tmp_path_factory.getbasetemp() / "independent"
    from housner.scenarios.campaigns.campaign import load_campaign
    from housner.scenarios.diagnosis.sensor_assessment import assess_sensor

    def get(case):
        raw = load_campaign(ic.cached_campaign(base, case)["root"])
        return ic, raw, assess_sensor(raw)

    return get


@pytest.mark.parametrize("case", ["colored_tau0.2", "colored_hum60_big_200hz", "white_big_1000hz"])
def test_the_noise_is_measured_as_the_independent_generator_made_it(indep, case):
    ic, raw, c = indep(case)
    truth = ic.noise_truth(case)
    sn = c.sensor.noise
    assert sn.white == (truth["ou"] == 0 and truth["hum_amp"] == 0)
    # the quiet samples hold 15-100 s of noise; with a correlation time up to 0.5 s the sd of a variance estimate
    # is up to ~sqrt(2 tau / T) = 25 %, of sigma half that: 30 % allows two of those
    assert sn.sigma == pytest.approx(truth["sd"], rel=0.3)
    mean_noise = float(np.mean([r.noise for r in c.records]))
    assert mean_noise == pytest.approx(truth["sd"], rel=0.3)
    if not sn.white:
        # the difference-based estimate it replaces was at least 1.5x too small
        assert float(np.mean([r.noise for r in raw.records])) < mean_noise / 1.5


def test_the_block_is_seen_at_rest_under_noise_that_wanders(indep):
    from housner.scenarios.diagnosis.comparison.record_comparison import compare

    _ic, raw, c = indep("colored_tau0.2")
    # the largest acceleration the block stood at rest, over g tan(alpha): read off the measurement with white
    # noise's thresholds, slowly wandering noise made it move at once (0.05); with the measured noise it agrees
    # with the model's to the detection's resolution (a few per cent)
    before = compare(raw).measured.metrics()["withstood_pos"].value
    cm = compare(c)
    m, mo = cm.measured.metrics()["withstood_pos"].value, cm.model.metrics()["withstood_pos"].value
    assert before < 0.5 * mo
    assert m == pytest.approx(mo, rel=0.1)


@pytest.mark.parametrize("case", ["saturation", "gain_drift", "spikes_dropouts", "none", "restitution_drift"])
def test_sensor_faults_are_named_where_they_are_and_only_there(indep, case):
    ic, _raw, c = indep(case)
    assert set(c.sensor.fault_kinds) == set(ic.expected_faults(case)), sensor_text(c.sensor)
    if case == "gain_drift":
        f = c.sensor.faults[0].figures
        # the truth drifts by +25 % over the order; 21 first excursions pin it to ~1 %
        assert f["relative_change"] == pytest.approx(0.25, abs=0.03)
    if case == "saturation":
        f = c.sensor.faults[0].figures
        assert f["high"] == pytest.approx(0.45 * ic.ALPHA, rel=1e-6) and f["low"] == pytest.approx(
            -0.45 * ic.ALPHA, rel=1e-6
        )
        # free vibrations released beyond the range are left out, with the reason
        assert any("beyond the sensor's range" in s[2] for s in c.skipped)


def test_a_model_is_read_through_the_saturating_sensor_as_the_block_was(indep):
    from housner.scenarios.diagnosis.comparison.record_comparison import compare
    from housner.scenarios.diagnosis.verdict.decision import distribution_checks

    _ic, _raw, c = indep("saturation")
    cm = compare(c)
    # through a range of 0.45 alpha no overturn shows, the model's no more than the block's: the overturn
    # fractions and the theta_max distributions agree (a correct model; before, 0/60 against 19/60, z = 4.8)
    m, mo = cm.measured.metrics()["overturn_fraction"], cm.model.metrics()["overturn_fraction"]
    assert m.value == mo.value == 0.0
    assert distribution_checks(cm) == []


def test_the_report_shows_the_sensor(indep, tmp_path):
    from housner.reports.diagnosis import render_diagnosis
    from housner.scenarios.diagnosis.diagnose import diagnose

    _ic, _raw, c = indep("gain_drift")
    page = render_diagnosis(diagnose(c, compare_steps=True, effects=[]))
    i = page.index('id="sensor"')
    part = page[i : page.index("</section>", i)]
    assert "gain drift" in part and "white" in part and "<img" in part


def test_sensor_words_are_read_from_the_values_alone():
    # The assessment returns figures; the words (reports.diagnosis.sensor_text) are built from them alone.
    from housner.reports.diagnosis.sensor_text import fault_text, sensor_document, sensor_verdict_sentence
    from housner.scenarios.diagnosis.sensor_assessment import SensorFault, SensorReport

    sat = SensorFault("saturation", ("a", "b"), 12, {"low": -math.inf, "high": 0.12, "alpha": 0.15})
    assert fault_text(sat).startswith("saturation: 2 record(s) flat-topped at +0.12 rad (+0.80 alpha), the sensor's")
    gain = SensorFault("gain_drift", ("a",), 0, {"relative_change": 0.25, "t": 6.04, "n": 9})
    assert "reads +25.0 % more from the first record to the last (t = +6.0 over 9 ground motions" in fault_text(gain)
    report = SensorReport(faults=(sat, gain), unseen_releases=("fv1",), mixed_rates=True)
    sentence = sensor_verdict_sentence(report)
    assert sentence.startswith(" The sensor, not the physics: saturation, gain drift. Saturation: 2 record(s)")
    assert "1 free vibration(s) (fv1) start beyond the sensor's range" in sentence
    assert "different sample rates" in sentence
    doc = sensor_document(report)
    assert [f["text"] for f in doc["faults"]] == [fault_text(sat), fault_text(gain)] and len(doc["notes"]) == 2
    assert sensor_verdict_sentence(SensorReport()) == ""  # a white, faultless sensor adds nothing
