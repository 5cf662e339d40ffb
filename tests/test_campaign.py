"""Measurement campaigns and model-against-measurement comparison (housner.scenarios.campaigns)."""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path

import campaign_generators as cg
import numpy as np
import pytest

from housner import GroundMotion, Specimen
from housner.cli import main
from housner.errors import DataFileError
from housner.free_vibration.closed_forms import half_cycle_integral
from housner.model import simulate
from housner.readers.measured_data import uniform_step
from housner.scenarios.campaigns.campaign import load_campaign
from housner.scenarios.campaigns.campaign_records import OVERTURN_ANGLE, estimate_release
from housner.scenarios.diagnosis.comparison.history_error import (
    ERROR_CLIP,
    divergence_time,
    error_window,
    measured_impacts,
    record_error,
)
from housner.scenarios.diagnosis.comparison.localise import features
from housner.scenarios.diagnosis.comparison.record_comparison import compare

SPEC = Specimen.bachmann2017()
ALPHA = SPEC.alpha
NOISE = cg.NOISE


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """A small campaign (3 free vibrations, 4 ground motions) to copy and break."""
    root = tmp_path_factory.mktemp("small")
    info = cg.write_campaign(root, "none", n_ground=4, seed=3, fv_duration=6.0)
    return info


@pytest.fixture(scope="module")
def full_none(tmp_path_factory):
    base = tmp_path_factory.getbasetemp() / "campaigns"
    return load_campaign(cg.cached_campaign(base, "none")["root"])


def _copy(small, tmp_path) -> Path:
    dst = tmp_path / "c"
    shutil.copytree(small["root"], dst)
    return dst


# ----------------------------------------------------------------------------
# loading
def test_load_reads_specimen_records_and_release_angles(small):
    c = load_campaign(small["root"])
    assert c.specimen.alpha == pytest.approx(ALPHA, rel=1e-12)
    assert c.specimen.p == pytest.approx(cg.P_SEED, rel=1e-12)
    assert [r.kind for r in c.records] == ["free_vibration"] * 3 + ["ground_motion"] * 4
    assert not c.skipped
    for r, x in zip(c.free_vibration, (0.8, -0.65, 0.5), strict=True):
        # theta0 from ~100 samples of 0.8 mrad noise fitted with 3 parameters: standard error
        # ~2 sigma/sqrt(n) = 0.16 mrad; 0.6 mrad is almost 4 of them.
        assert r.motion.theta0 == pytest.approx(x * ALPHA, abs=6e-4)
        assert r.motion.theta_dot0 == 0.0
        assert r.t_offset == 0.0  # the generator releases at the first sample: no hold may be invented
    for r in c.records:
        # the third-difference MAD estimator scatters by ~3 % on 3000 samples of pure noise
        # (0.78-0.84 mrad over 8 seeds); 12 % is 4 of its standard errors
        assert r.noise == pytest.approx(NOISE, rel=0.12)
        assert r.motion.dt == pytest.approx(cg.DT)
        assert r.theta.size == r.motion.n == r.t.size


def test_release_after_a_hold_is_found_and_trimmed(tmp_path, small):
    # a free-vibration record held at theta0 for 0.4 s before release
    truth = cg.truth_for("none")
    th, _ = cg.simulate_truth(truth, np.zeros(2000), theta0=0.7 * ALPHA)
    hold = 200
    rng = np.random.default_rng(5)
    theta = np.concatenate((np.full(hold, th[0]), th)) + rng.normal(0, NOISE, hold + th.size)
    t = np.arange(theta.size) * cg.DT
    k, th0 = estimate_release(t, theta, NOISE)
    # A fall from rest starts with zero speed: theta departs from the plateau by 1 sigma only after
    # sqrt(2 sigma / theta'') ~ 50 ms, so the release can only be placed to about that (25 samples).
    assert abs(k - hold) <= 30
    assert th0 == pytest.approx(0.7 * ALPHA, abs=6e-4)
    d = _copy(small, tmp_path)
    np.savetxt(
        d / "records" / "fv01.csv",
        np.column_stack((t, np.zeros_like(t), theta)),
        delimiter=",",
        header="time,ground_acc,theta",
        comments="",
    )
    r = load_campaign(d).record("fv01")
    assert r.t_offset == pytest.approx(k * cg.DT)
    assert r.theta.size == theta.size - k
    assert r.t[0] == 0.0


def test_release_estimate_does_not_invent_holds():
    truth = cg.truth_for("none")
    ks = []
    for seed in range(12):
        rng = np.random.default_rng(seed)
        x = rng.uniform(0.3, 0.9) * rng.choice([-1, 1]) * ALPHA
        th, _ = cg.simulate_truth(truth, np.zeros(1500), theta0=x)
        theta = th + rng.normal(0, NOISE, th.size)
        k, th0 = estimate_release(np.arange(th.size) * cg.DT, theta, NOISE)
        ks.append(k)
        assert th0 == pytest.approx(x, abs=6e-4)
    # the information criterion keeps a spurious hold rare; allow one in twelve
    assert sum(k != 0 for k in ks) <= 1


def test_bad_record_files_are_skipped_with_file_line_and_column(small, tmp_path):
    d = _copy(small, tmp_path)
    f = d / "records" / "gm002.csv"
    lines = f.read_text().splitlines()
    lines[10] = lines[10].split(",")[0] + ",abc," + lines[10].split(",")[2]
    f.write_text("\n".join(lines) + "\n")
    g = d / "records" / "gm003.csv"
    lines = g.read_text().splitlines()
    lines[20] = "0.0391," + ",".join(lines[20].split(",")[1:])  # time jumps back: non-uniform
    g.write_text("\n".join(lines) + "\n")
    (d / "records" / "gm004.csv").unlink()
    c = load_campaign(d)
    assert [r.id for r in c.records] == ["fv01", "fv02", "fv03", "gm001"]
    msgs = {rid: msg for rid, _f, msg in c.skipped}
    assert "gm002.csv line 11, column `ground_acc`" in msgs["gm002"] and "'abc'" in msgs["gm002"]
    assert "gm003.csv line 21, column `time`" in msgs["gm003"] and "non-uniform" in msgs["gm003"]
    assert "gm004.csv" in msgs["gm004"] and "cannot read" in msgs["gm004"]


def test_theta_in_degrees_and_fv_at_rest_are_refused(small, tmp_path):
    d = _copy(small, tmp_path)
    f = d / "records" / "gm001.csv"
    a = np.loadtxt(f, delimiter=",", skiprows=1)
    a[100, 2] = 45.0  # a value in degrees
    np.savetxt(f, a, delimiter=",", header="time,ground_acc,theta", comments="")
    g = d / "records" / "fv02.csv"
    b = np.loadtxt(g, delimiter=",", skiprows=1)
    b[:, 2] = np.random.default_rng(0).normal(0, NOISE, b.shape[0])  # never tilted
    np.savetxt(g, b, delimiter=",", header="time,ground_acc,theta", comments="")
    c = load_campaign(d)
    msgs = {rid: msg for rid, _f, msg in c.skipped}
    assert "line 102, column `theta`" in msgs["gm001"] and "beyond pi/2" in msgs["gm001"]
    assert "released tilt" in msgs["fv02"]


def _write_toml(d: Path, text: str) -> Path:
    (d / "campaign.toml").write_text(text)
    return d


_GOOD_HEAD = 'name = "t"\n[specimen]\nheight = 0.5\nwidth = 0.075\ndepth = 0.4\nmass = 3.94\np = 4.8883\n'
_REC = '[[record]]\nid = "{id}"\nkind = "{kind}"\nfile = "records/{id}.csv"\n'


@pytest.mark.parametrize(
    ("text", "needles"),
    [
        (
            _GOOD_HEAD.replace("height", "heigth") + _REC.format(id="gm001", kind="ground_motion"),
            ["unknown key [specimen] 'heigth'", "did you mean 'height'", "line 3"],
        ),
        (
            _GOOD_HEAD.replace("mass = 3.94\n", "") + _REC.format(id="gm001", kind="ground_motion"),
            ["missing key [specimen] 'mass'", "line 2"],
        ),
        (
            _GOOD_HEAD + _REC.format(id="gm001", kind="ground_motoin"),
            ["'kind' must be one of", "did you mean 'ground_motion'", "line 10"],
        ),
        (_GOOD_HEAD + _REC.format(id="gm001", kind="ground_motion") * 2, ["'id' 'gm001' is already used", "line 13"]),
        (_GOOD_HEAD + "[[record]]\nid = 'gm001'\nkind = 'ground_motion'\n", ["missing key [[record]] #1 'file'"]),
        (_GOOD_HEAD.replace("p = 4.8883", "p = -1"), ["[specimen] 'p' must be a positive number", "line 7"]),
        (_GOOD_HEAD + "[[record]\nid = 1\n", ["not valid TOML", "line 8"]),
        (_GOOD_HEAD, ["no [[record]] tables"]),
    ],
)
def test_campaign_toml_errors_name_the_key_and_line(small, tmp_path, text, needles):
    d = _copy(small, tmp_path)
    _write_toml(d, text)
    with pytest.raises(DataFileError) as err:
        load_campaign(d)
    msg = str(err.value)
    assert "campaign.toml" in msg
    for n in needles:
        assert n in msg


# ----------------------------------------------------------------------------
# record groups: the records played under one ground motion (issue 48)
def _group_campaign(d: Path, groups: dict[str, str]) -> Path:
    """Three outcome records (o1..o3) and two theta records (m1, m2) at 100 Hz; ``groups`` maps an id to the
    text of its ``group = ...`` line."""
    t = np.arange(200) * 0.01
    acc = 0.5 * np.sin(2 * np.pi * t)
    (d / "records").mkdir(parents=True)
    recs = []
    for rid in ("o1", "o2", "o3", "m1", "m2"):
        theta = rid.startswith("m")
        cols = [t, acc, 1e-4 * np.sin(7 * t)] if theta else [t, acc]
        head = "time,ground_acc,theta" if theta else "time,ground_acc"
        rows = "".join(",".join(f"{v:.6g}" for v in row) + "\n" for row in zip(*cols, strict=True))
        (d / "records" / f"{rid}.csv").write_text(head + "\n" + rows)
        recs.append(_REC.format(id=rid, kind="ground_motion") + ("" if theta else "overturned = false\n"))
        recs[-1] += f"group = {groups[rid]}\n" if rid in groups else ""
    return _write_toml(d, _GOOD_HEAD + "".join(recs))


def test_record_groups_are_read_and_a_record_without_one_is_its_own(tmp_path):
    d = _group_campaign(tmp_path / "c", {"o1": '"RSN43_LYTLECREEK"', "o3": '"RSN43_LYTLECREEK"', "m2": "'fv set'"})
    c = load_campaign(d)
    assert not c.skipped
    assert [(o.id, o.group) for o in c.outcomes] == [
        ("o1", "RSN43_LYTLECREEK"),
        ("o2", None),
        ("o3", "RSN43_LYTLECREEK"),
    ]
    assert [(r.id, r.group) for r in c.records] == [("m1", None), ("m2", "fv set")]
    assert c.outcome_groups == ["RSN43_LYTLECREEK", "o2", "RSN43_LYTLECREEK"]
    assert c.record_groups == ["m1", "fv set"]


def test_a_campaign_without_groups_gives_each_record_its_id(tmp_path):
    c = load_campaign(_group_campaign(tmp_path / "c", {}))
    assert c.outcome_groups == ["o1", "o2", "o3"] and c.record_groups == ["m1", "m2"]


@pytest.mark.parametrize("value", ["3", '""', '"  "', "true", '["RSN43"]', "{ name = 'RSN43' }"])
def test_a_group_that_is_not_a_non_empty_string_refuses_the_campaign_naming_key_and_line(tmp_path, value):
    d = _group_campaign(tmp_path / "c", {"o2": value})
    line = (d / "campaign.toml").read_text().splitlines().index(f"group = {value}") + 1
    with pytest.raises(DataFileError) as err:
        load_campaign(d)
    msg = str(err.value)
    assert f"campaign.toml line {line}: [[record]] #2 'group' must be a non-empty string" in msg
    assert "\n" not in msg


def _to_degrees(d: Path, ids) -> int:
    """Rewrite the theta column of records ``ids`` in degrees (header unchanged); how many leave |theta| <= pi/2."""
    refused = 0
    for rid in ids:
        f = d / "records" / f"{rid}.csv"
        a = np.loadtxt(f, delimiter=",", skiprows=1)
        a[:, 2] = np.degrees(a[:, 2])
        np.savetxt(f, a, delimiter=",", header="time,ground_acc,theta", comments="")
        refused += bool(np.max(np.abs(a[:, 2])) > math.pi / 2 + 0.1)
    return refused


def test_a_campaign_mostly_unreadable_is_refused_in_one_line(small, tmp_path):
    d = _copy(small, tmp_path)
    ids = [f.stem for f in sorted((d / "records").glob("*.csv"))]
    refused = _to_degrees(d, ids)
    assert 2 * refused > len(ids) == 7  # the free vibrations and the ground motions that rock
    with pytest.raises(ValueError) as err:
        load_campaign(d)
    msg = str(err.value)
    assert "\n" not in msg
    assert "campaign 'synthetic campaign, hidden effect: none'" in msg and "campaign.toml" in msg
    assert f"{refused} of 7 records could not be read" in msg
    # the most common cause, with one example file
    assert f"most common cause ({refused} of them): |theta| = " in msg and "beyond pi/2" in msg
    assert "`theta [deg]`" in msg
    assert re.search(r"\(e\.g\. record '\w+', records/\w+\.csv line \d+, column `theta`\)$", msg), msg


def test_a_minority_of_unreadable_records_is_skipped_and_listed(small, tmp_path):
    d = _copy(small, tmp_path)
    assert _to_degrees(d, ["fv01", "fv02", "fv03"]) == 3  # 3 of 7: fewer than half
    c = load_campaign(d)
    assert [r.id for r in c.records] == ["gm001", "gm002", "gm003", "gm004"]
    assert [rid for rid, _f, _m in c.skipped] == ["fv01", "fv02", "fv03"]
    assert all("beyond pi/2" in m for _r, _f, m in c.skipped)


def test_cli_refuses_a_mostly_unreadable_campaign_with_one_line(small, tmp_path, capsys):
    d = _copy(small, tmp_path)
    refused = _to_degrees(d, [f.stem for f in sorted((d / "records").glob("*.csv"))])
    assert main(["diagnose", str(d), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{refused} of 7 records could not be read" in err[0], err
    assert "skipped record" not in err[0]


def test_all_records_bad_raises_and_overturn_flag(small, tmp_path):
    d = _copy(small, tmp_path)
    _write_toml(d, _GOOD_HEAD + _REC.format(id="nope", kind="ground_motion"))
    with pytest.raises(DataFileError, match="no record could be read"):
        load_campaign(d)
    _write_toml(d, _GOOD_HEAD + _REC.format(id="gm001", kind="ground_motion") + "overturned = true\n")
    assert load_campaign(d).records[0].overturned


def test_measured_overturn_is_seen_from_theta(full_none):
    # the generator holds an overturned block at +-pi/2: every such record must be flagged, no other
    gm = full_none.ground_motion
    over = [bool(np.max(np.abs(r.theta)) >= OVERTURN_ANGLE) for r in gm]
    assert [r.overturned for r in gm] == over
    assert 5 <= sum(over) <= 30  # the ground motions are strong enough to overturn some, not most


# ----------------------------------------------------------------------------
# error, window, divergence: closed forms
def test_record_error_closed_forms():
    th = np.linspace(-0.1, 0.1, 500)
    # a constant offset c gives exactly c / alpha
    assert record_error(th + 0.003, th, th.size, ALPHA) == pytest.approx(0.003 / ALPHA, rel=1e-12)
    # differences beyond alpha are clipped to 1
    assert record_error(th + 3 * ALPHA, th, th.size, ALPHA) == pytest.approx(ERROR_CLIP, rel=1e-12)
    # only the window counts
    d = np.zeros(500)
    d[250:] = 0.01
    assert record_error(d, np.zeros(500), 250, ALPHA) == 0.0


def test_window_counts_measured_impacts_and_stops_at_overturn(full_none):
    c = full_none
    for r in c.ground_motion[:20]:
        end = error_window(r, ALPHA)
        imp = measured_impacts(r.theta, r.noise)
        if r.overturned:
            k_over = int(np.flatnonzero(np.abs(r.theta) > ALPHA + 4 * r.noise)[0])
            assert end <= k_over + 1
        elif imp.size >= 6:
            assert end == imp[5] + 1
        else:
            assert end == r.theta.size


def test_divergence_time_of_a_step():
    t = np.arange(1000) * cg.DT
    a = np.zeros(1000)
    b = np.where(t >= 1.0, 0.05, 0.0)  # apart by 0.05 rad from t = 1 s on
    assert divergence_time(a, b, t, NOISE, ALPHA) == pytest.approx(1.0)
    b2 = b.copy()
    b2[550:] = 0.0  # apart for 0.1 s... sustained 50 ms is enough
    assert divergence_time(a, b2, t, NOISE, ALPHA) == pytest.approx(1.0)
    b3 = np.where((t >= 1.0) & (t < 1.02), 0.05, 0.0)  # a 20 ms blip is not a divergence
    assert math.isnan(divergence_time(a, b3, t, NOISE, ALPHA))


# ----------------------------------------------------------------------------
# compare
def test_compare_plain_model_on_plain_data_is_at_the_noise_floor(full_none):
    cmp = compare(full_none)
    e = cmp.error()
    # An independent integrator of the same physics: the model's histories agree to ~1e-3 alpha
    # within the window, so the error is the noise alone, sigma/alpha (0.0054); 5 % covers the
    # noise estimate's scatter.
    assert e.value == pytest.approx(cmp.noise_floor, rel=0.05)
    assert cmp.error("free_vibration").value == pytest.approx(cmp.noise_floor, rel=0.1)
    d = cmp.distribution
    assert d.ks.distance <= 0.1 and d.ks.pvalue > 0.5
    assert d.overturn_measured.estimate == d.overturn_model.estimate
    assert cmp.discrepancies() == []
    assert not cmp.failures
    tab = cmp.table()
    assert len(tab) == len(full_none.records)
    assert tab["overturned_measured"].tolist() == tab["overturned_model"].tolist()


def test_localisation_of_housner_histories_matches_closed_forms(full_none):
    # features of noise-free Housner histories: the energy ratio of every impact is r (seed eq. 8),
    # every half-cycle lasts 2 F(theta_i, alpha) / p (exact eq. 7), no energy is lost in flight,
    # the block does not move before uplift.
    c = full_none
    hist = {r.id: simulate(c.specimen, r.motion).theta for r in c.records}
    f = features(c, hist)
    # peaks from local quartic fits: bias below 1e-4 of the peak -> c within 1e-3
    np.testing.assert_allclose(f.energy_ratio, SPEC.r_housner, atol=1e-3)
    T = 2 * np.asarray(half_cycle_integral(f.half_cycle_amplitude * ALPHA, ALPHA)) / SPEC.p
    # impact times from kinked fits: ~1e-5 s on ~0.3 s half-cycles
    np.testing.assert_allclose(f.half_cycle_duration, T, rtol=2e-3)
    # speeds from quadratic fits at both ends: the cubic bias is the same at both ends
    np.testing.assert_allclose(f.flight_ratio, 1.0, atol=0.02)
    m = f.metrics()
    # the block may already rock below the detection threshold (~0.01 alpha) in the 50 ms margin:
    # a few of the ~10^4 samples move, the mean stays within 5e-5 alpha (7 microrad)
    assert abs(m["tilt_offset"].value) < 5e-5
    assert m["p"].value == pytest.approx(SPEC.p, rel=1e-3)


def test_localisation_finds_a_sensor_offset_and_a_wrong_p(tmp_path_factory):
    base = tmp_path_factory.getbasetemp() / "campaigns"
    so = load_campaign(cg.cached_campaign(base, "sensor_offset")["root"])
    cmp = compare(so)
    offset = cg.HIDDEN["sensor_offset"][0]["offset"]
    # before uplift the measured block reads the offset; the regression over ~10^4 samples pins it
    m, x = cmp.localisation()["tilt_offset"]
    assert m.value * ALPHA == pytest.approx(offset, abs=4 * m.se * ALPHA + 1e-5)
    assert abs(x.value) < 4 * x.se + 1e-6
    # the baseline error is the offset and the noise in quadrature
    assert cmp.error().value == pytest.approx(math.hypot(offset, NOISE) / ALPHA, rel=0.05)
    assert cmp.discrepancies()[0][0] == "tilt_offset"

    pm = load_campaign(cg.cached_campaign(base, "p_misstated")["root"])
    cmp = compare(pm)
    m, x = cmp.localisation()["p"]
    # the free-vibration calibration recovers the true p to its standard error (~0.002 1/s)
    assert m.value == pytest.approx(cg.HIDDEN["p_misstated"][0]["p_true"], abs=4 * m.se)
    assert x.value == pytest.approx(cg.P_SEED, abs=4 * x.se)
    assert cmp.discrepancies()[0][0] == "p"


def test_compare_with_another_engine_and_refused_effects(small):
    c = load_campaign(small["root"])
    cmp = compare(c, engine="mujoco", localise=False)
    assert cmp.engine == "mujoco"
    assert not cmp.failures
    # MuJoCo's contact is soft and its restitution tuned only approximately: it follows the
    # measurement far less well than the analytic model, but it does follow it (error < 1 alpha)
    assert 0 < cmp.error(kind=None).value < 1.0
    # MuJoCo realises rotational_damping and restitution (below its contact's r) only
    with pytest.raises(ValueError, match="cannot realise effect.*'sliding'"):
        compare(c, engine="mujoco", effects=[{"name": "sliding", "mu": 0.3}])


def test_compare_accepts_effects_by_name_and_dict(small):
    c = load_campaign(small["root"])
    a = compare(c, effects=[{"name": "sensor_offset", "offset": 0.002}], localise=False)
    # a 2 mrad offset on plain data: error sqrt(offset^2 + sigma^2) / alpha for every ground-motion
    # record (free vibrations add the drift from their 0.1-0.3 mrad release-angle error)
    for r in a.records:
        if r.kind == "ground_motion":
            assert r.error == pytest.approx(math.hypot(0.002, r.noise) / ALPHA, rel=0.03)
    with pytest.raises(ValueError, match="unknown effect"):
        compare(c, effects=["sensor_ofset"])


def test_simulated_free_vibration_starts_at_the_measured_release(small):
    c = load_campaign(small["root"])
    r = c.free_vibration[0]
    res = simulate(c.specimen, r.motion)
    assert res.theta[0] == r.motion.theta0
    ref = simulate(c.specimen, GroundMotion.free_vibration(0.8 * ALPHA, r.motion.duration, cg.DT))
    # released 0.1-0.2 mrad off: the histories stay within 1 mrad over the first second
    assert np.max(np.abs(res.theta[:500] - ref.theta[:500])) < 1e-3


def test_time_stamps_rounded_to_nine_digits_are_read_as_uniform_and_an_irregular_column_is_not():
    import warnings
    from pathlib import Path

    # acquisition software writes a fixed number of significant digits: a sqrt(10) ms step to 9 digits
    # deviates from its grid by up to 5e-9 s, far within 1 % of the step (3e-5 s)
    dt = 0.00316227766
    t = np.array([float(f"{x:.9g}") for x in np.arange(3000) * dt])
    lines = np.arange(2, t.size + 2)
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        step = uniform_step(Path("gm01.csv"), t, lines)
    assert step == pytest.approx(dt, rel=1e-9)
    assert len(w) == 1 and "rounded" in str(w[0].message) and "gm01.csv" in str(w[0].message)
    # a sample 0.3 ms off a 2 ms grid written to 0.1 ms: beyond half a unit (0.05 ms) and 1 % of the step
    t2 = np.round(np.arange(3000) * 0.002, 4)
    t2[1500] += 0.0003
    with pytest.raises(DataFileError, match="line 1502.*non-uniform sampling"):
        uniform_step(Path("gm02.csv"), t2, lines)
