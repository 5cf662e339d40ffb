"""Checks of the independent campaign generator (tests/independent_campaigns.py) against closed forms.

The generator is checked against Housner's closed forms and the energy integral, not against the library
(only the slow cross-check at the end compares it with :func:`housner.model.simulate`). Each case's campaign
must be readable by :func:`housner.scenarios.campaigns.campaign.load_campaign` without a skipped record.
"""

from __future__ import annotations

import math
from dataclasses import replace

import independent_campaigns as ic
import numpy as np
import pytest
from scipy.integrate import quad

from housner.model import simulate
from housner.motion import GroundMotion
from housner.scenarios.campaigns.campaign import load_campaign
from housner.specimen import Specimen

ALPHA, P = ic.ALPHA, ic.P_STATED
G_TAN = ic.G * math.tan(ALPHA)  # uplift acceleration of the stated specimen [m/s^2]


@pytest.fixture(scope="module")
def housner():
    return ic.truth_for("none")


def fall_time(theta0: float, alpha: float = ALPHA, p: float = P) -> float:
    """Exact time [s] from a release at rest at theta0 to theta = 0 (energy integral of the nonlinear equation).

    theta'^2 / 2 = p^2 (cos(alpha - theta0) - cos(alpha - theta)); with theta = theta0 - v^2 the integrand
    is regular at the release.
    """
    a0 = alpha - theta0

    def f(v):
        u = v * v
        # cos(a0) - cos(a0 + u) written without cancellation
        return 2.0 * v / math.sqrt(4.0 * p * p * math.sin(a0 + 0.5 * u) * math.sin(0.5 * u))

    t, _err = quad(f, 0.0, math.sqrt(theta0), epsabs=1e-14, epsrel=1e-13, limit=200)
    return t


def impact_speed(theta0: float, alpha: float = ALPHA, p: float = P) -> float:
    """|theta'| [rad/s] at theta = 0 after a release at rest at theta0 (energy conservation)."""
    return math.sqrt(2.0 * p * p * (math.cos(alpha - theta0) - math.cos(alpha)))


# ----------------------------------------------------------------------------
# free rocking against closed forms
@pytest.mark.parametrize("x", [0.3, 0.75, -0.55])
def test_quarter_period(housner, x):
    """Release to first impact: Housner's linearised closed form cosh(p T/4) = 1/(1 - theta0/alpha), and the
    exact energy integral."""
    theta0 = x * ALPHA
    _th, _over, imp = ic.simulate_details(housner, np.zeros(1000), ic.DT, theta0=theta0)
    t1 = imp[0, 0]
    # the dense-output root and the 1e-9 tolerance of the integrator put the event within ~1e-11 s of the
    # exact time; 1e-9 s leaves two orders of margin
    assert t1 == pytest.approx(fall_time(abs(theta0)), abs=1e-9)
    # Housner's formula linearises sin(alpha - theta) ~ alpha - theta: the time is off by O(alpha^2)
    # relative (alpha^2 = 0.022; measured 3e-4 at 0.75 alpha), so 2e-3 relative
    linear = math.acosh(1.0 / (1.0 - abs(x))) / P
    assert t1 == pytest.approx(linear, rel=2e-3)


def test_half_period_after_impact(housner):
    """Between two impacts the block rises to the amplitude its speed allows and falls back: 2 x fall time."""
    _th, _over, imp = ic.simulate_details(housner, np.zeros(2000), ic.DT, theta0=0.6 * ALPHA)
    w = abs(imp[0, 2])  # speed just after the first impact
    # amplitude from energy: w^2 / 2 = p^2 (cos(alpha - theta1) - cos(alpha))
    theta1 = ALPHA - math.acos(math.cos(ALPHA) + w * w / (2 * P * P))
    assert imp[1, 0] - imp[0, 0] == pytest.approx(2.0 * fall_time(theta1), abs=2e-9)


def test_energy_ratio_per_impact(housner):
    """theta' after / before = sqrt(r) at every impact, the first impact at the energy-conservation speed, and
    the sampled peaks obey seed eq. 8 with r."""
    theta0 = 0.75 * ALPHA
    dt = 1e-4  # fine sampling: a sampled peak is within p^2 alpha dt^2 / 8 ~ 4e-9 rad of the true one
    th, _over, imp = ic.simulate_details(housner, np.zeros(40000), dt, theta0=theta0)
    assert imp.shape[0] >= 6  # 4 s of free rocking
    np.testing.assert_allclose(imp[:, 2] / imp[:, 1], math.sqrt(ic.R_HOUSNER), rtol=1e-13)
    assert abs(imp[0, 1]) == pytest.approx(impact_speed(theta0), rel=1e-9)
    # peaks of |theta| between impacts, and c_i = (cos(alpha - th_i+1) - cos a) / (cos(alpha - th_i) - cos a)
    peaks = [theta0]
    for t0, t1 in zip(imp[:-1, 0], imp[1:, 0], strict=False):
        k0, k1 = int(t0 / dt) + 1, int(t1 / dt) + 1
        peaks.append(float(np.max(np.abs(th[k0:k1]))))
    e = np.cos(ALPHA - np.array(peaks[:6])) - math.cos(ALPHA)
    # the peak error (4e-9 rad) times d c / d theta (< 30 for these amplitudes): ~1e-7
    np.testing.assert_allclose(e[1:] / e[:-1], ic.R_HOUSNER, rtol=1e-6)


def test_momentum_ratio_symmetric():
    """Housner's closed form 1 - 2 m B^2 / I0 from the corner vectors, and r = 0.9465 for the seed specimen."""
    tr = ic.truth_for("none")
    rho_pn, rho_np = ic.momentum_ratio(tr.b_pos, tr.b_neg, tr.height, tr.i_c, tr.mass)
    assert rho_pn == pytest.approx(1 - 2 * ic.MASS * ic.B_HALF**2 / ic.I0_STATED, rel=1e-14)
    assert rho_np == pytest.approx(rho_pn, rel=1e-14)
    assert ic.R_HOUSNER == pytest.approx(0.9465, abs=5e-5)  # seed Table 1


# ----------------------------------------------------------------------------
# ground motions
def sine(amplitude: float, freq: float = 2.0, duration: float = 3.0, dt: float = ic.DT, cycles: float = 2.0):
    t = np.arange(int(round(duration / dt))) * dt
    return np.where(t < cycles / freq, -amplitude * G_TAN * np.sin(2 * math.pi * freq * t), 0.0)


@pytest.mark.parametrize("convention", ["linear", "held"])
def test_no_uplift_below_threshold(housner, convention):
    th, over = ic.simulate(housner, sine(0.9), ic.DT, convention=convention)
    assert not over
    assert np.all(th == 0.0)  # the block never leaves rest: theta is exactly zero


def test_uplift_above_threshold(housner):
    acc = sine(1.1, freq=4.0)
    th, over = ic.simulate(housner, acc, ic.DT)
    assert not over
    moved = np.flatnonzero(th != 0.0)
    assert moved.size > 0 and np.max(np.abs(th)) > 1e-3 * ALPHA
    # the first half-cycle is negative: the block lifts onto its +x corner, after ug'' passed -g tan(alpha)
    assert th[moved[0]] > 0.0
    assert np.min(acc[: moved[0] + 1]) < -G_TAN


def test_mirror_symmetry(housner):
    """ug -> -ug gives theta -> -theta: the equations are odd in (ug'', theta) and so is every floating-point
    operation of the kernel (sin is odd, the thresholds and the impact law are mirrored), so the mirrored
    run is bit-identical; 1e-12 rad only allows for a libm whose sin is not exactly odd."""
    for i in range(4):
        acc = ic.ground_motion(np.random.default_rng(100 + i))
        a, oa = ic.simulate(housner, acc, ic.DT)
        b, ob = ic.simulate(housner, -acc, ic.DT)
        assert oa == ob
        np.testing.assert_allclose(a, -b, rtol=0, atol=1e-12)


def test_overturn_holds(housner):
    th, over = ic.simulate(housner, sine(3.0, freq=1.0, cycles=1.0), ic.DT)
    assert over
    k = int(np.argmax(np.abs(th) >= 0.5 * math.pi))
    assert k > 0 and np.all(np.abs(th[:k]) < 0.5 * math.pi)
    assert np.all(th[k:] == th[k]) and abs(th[k]) == 0.5 * math.pi


def test_held_converges_to_linear(housner):
    """The hold lags the linear input by about dt/2, so held and linear responses differ by O(dt): halving
    the sampling step of the same continuous motion must roughly halve their difference (a non-overturning
    one-cycle sine pulse, 1.5 g tan(alpha) at 4 Hz; peak 0.26 alpha)."""
    diffs = []
    for m in (1, 2, 4, 8):
        dt = ic.DT / m
        acc = sine(1.5, freq=4.0, dt=dt, cycles=1.0)
        a, _ = ic.simulate(housner, acc, dt)
        b, _ = ic.simulate(housner, acc, dt, convention="held")
        diffs.append(np.max(np.abs(a - b)) / ALPHA)
    diffs = np.array(diffs)
    assert np.all(diffs[1:] < 0.7 * diffs[:-1])  # first order: ratio 2 expected, measured 2.0-3.1
    assert diffs[-1] < 1e-3


# ----------------------------------------------------------------------------
# the effects the library does not have, and the foundation
def test_pivot_friction_work(housner):
    """With a Coulomb moment M_f at the pivot the first impact speed follows from the work-energy balance
    I0 w^2 / 2 = m g R (cos(alpha - theta0) - cos alpha) - M_f theta0; a release where the restoring moment
    m g R sin(alpha - theta0) is below M_f stays put."""
    tr = ic.truth_for("pivot_friction")
    mf = tr.pivot_moment
    _al, rr, i0, _p = tr.side(1)
    theta0 = 0.6 * ALPHA
    _th, _over, imp = ic.simulate_details(tr, np.zeros(1000), ic.DT, theta0=theta0)
    work = ic.MASS * ic.G * rr * (math.cos(ALPHA - theta0) - math.cos(ALPHA)) - mf * theta0
    assert abs(imp[0, 1]) == pytest.approx(math.sqrt(2 * work / i0), rel=1e-9)
    stuck = ALPHA - 0.5 * math.asin(mf / (ic.MASS * ic.G * rr))  # restoring moment M_f / 2 there
    th, _over = ic.simulate(tr, np.zeros(500), ic.DT, theta0=stuck)
    assert np.all(th == stuck)


def test_restitution_drift():
    n_rec = 63
    tr = ic.truth_for("restitution_drift", n_records=n_rec)
    for k, r in ((0, 0.947), (31, 0.947 + (0.852 - 0.947) * 31 / 62), (62, 0.852)):
        _th, _over, imp = ic.simulate_details(tr, np.zeros(1500), ic.DT, theta0=0.5 * ALPHA, record_index=k)
        np.testing.assert_allclose(imp[:, 2] / imp[:, 1], math.sqrt(r), rtol=1e-13)


def test_vertical_input():
    """a_v = 0.25 x (the input low-passed at 8 Hz), 30 ms (15 samples) late: zero before, 0.25 x a step after
    the filter has settled (DC gain 1)."""
    tr = ic.truth_for("vertical_table")
    acc = np.full(1000, -1.0)
    av = ic.vertical_input(tr, acc, ic.DT)
    assert np.all(av[:15] == 0.0) and av[16] != 0.0
    assert av[-1] == pytest.approx(-0.25, rel=1e-6)


def test_vertical_table_lowers_uplift():
    """A table falling with the block (a_v < 0 when ug'' < 0, through the filter) lowers the effective gravity
    and so the uplift threshold: a slow ramp to 0.99 g tan(alpha) leaves the plain block at rest but lifts
    the one on the vertical table (threshold g tan(alpha) / (1 + 0.25 tan(alpha)) = 0.964 g tan(alpha))."""
    t = np.arange(2000) * ic.DT
    acc = -0.99 * G_TAN * np.minimum(t / 2.0, 1.0)
    th0, _ = ic.simulate(ic.truth_for("none"), acc, ic.DT)
    th1, _ = ic.simulate(ic.truth_for("vertical_table"), acc, ic.DT)
    assert np.all(th0 == 0.0)
    assert np.max(th1) > 0.0


def test_sliding_never_rocks_from_rest(housner):
    tr = ic.truth_for("sliding")
    acc = ic.ground_motion(np.random.default_rng(3))
    th, over = ic.simulate(tr, acc, ic.DT)
    assert not over and np.all(th == 0.0)
    # the free vibration's pivot holds (friction demand below mu): it rocks as Housner's block
    a, _ = ic.simulate(housner, np.zeros(3000), ic.DT, theta0=0.75 * ALPHA)
    b, _ = ic.simulate(tr, np.zeros(3000), ic.DT, theta0=0.75 * ALPHA)
    np.testing.assert_array_equal(a, b)


def test_foundation_rigid_limit(housner):
    """A stiff (1000 Hz), half-critically damped foundation rocks as Housner's block: the library's docstring
    says it loses Housner's r to 4 digits; over 2 s of free rocking theta stays within 1e-3 alpha and the
    zero crossings within one sample of the rigid impacts."""
    stiff = replace(housner, foundation_freq=1000.0, foundation_zeta=0.5)
    a, _, imp = ic.simulate_details(housner, np.zeros(1000), ic.DT, theta0=0.5 * ALPHA)
    b, _ = ic.simulate(stiff, np.zeros(1000), ic.DT, theta0=0.5 * ALPHA)
    assert np.max(np.abs(a - b)) < 1e-3 * ALPHA
    crossings = (np.flatnonzero(np.diff(np.sign(b)) != 0) + 1) * ic.DT
    n = min(4, crossings.size)
    np.testing.assert_allclose(crossings[:n], imp[:n, 0], atol=ic.DT)


# ----------------------------------------------------------------------------
# campaigns
def test_deterministic_and_stable_in_n(tmp_path):
    """Same seed, same bytes; and a record does not change when the campaign grows (the i-th child seed)."""
    a = ic.write_campaign(tmp_path / "a", "none", n_ground=3, seed=7)
    b = ic.write_campaign(tmp_path / "b", "none", n_ground=3, seed=7)
    c = ic.write_campaign(tmp_path / "c", "none", n_ground=5, seed=7)
    for f in sorted((a["root"] / "records").iterdir()):
        assert f.read_bytes() == (b["root"] / "records" / f.name).read_bytes()
        if f.name.startswith("gm"):
            assert f.read_bytes() == (c["root"] / "records" / f.name).read_bytes()
    assert (a["root"] / "campaign.toml").read_bytes() == (b["root"] / "campaign.toml").read_bytes()
    d = ic.write_campaign(tmp_path / "d", "none", n_ground=3, seed=8)
    assert (d["root"] / "records" / "gm001.csv").read_bytes() != (a["root"] / "records" / "gm001.csv").read_bytes()


@pytest.mark.parametrize("case", list(ic.CASES))
def test_case_loads(tmp_path, case):
    info = ic.write_campaign(tmp_path / "c", case, n_ground=4, seed=1)
    camp = load_campaign(info["root"])
    assert camp.skipped == []
    assert [r.id for r in camp.records] == [rid for rid, _k, _i in ic.recording_order(4)]
    truth = info["truth"]
    releases = ic.case_parameters(case).get("fv_releases", ic.FV_RELEASES)
    # the release is fitted to the noisy samples (standard error 0.1-0.2 mrad under white noise,
    # campaign.estimate_release); an Ornstein-Uhlenbeck part that hardly changes over the fit's window (the
    # first ~0.3-0.6 s) shifts the fitted angle by its value there, sd noise_ou: 4 of those
    tol = max(1e-3, 4.0 * ic.noise_truth(case)["ou"])
    for rec, x in zip(camp.free_vibration, releases, strict=True):
        assert not rec.overturned
        assert rec.motion.theta0 == pytest.approx(x * ALPHA + truth.offset, abs=tol)
    for rec, over in zip(camp.ground_motion, info["overturned"], strict=True):
        assert rec.overturned == bool(over)
        assert rec.dt == pytest.approx(ic.sample_interval(case), rel=1e-9)


def test_cached_campaign(tmp_path):
    a = ic.cached_campaign(tmp_path, "sensor_offset", n_ground=2)
    stamp = (a["root"] / "records" / "gm001.csv").stat().st_mtime_ns
    b = ic.cached_campaign(tmp_path, "sensor_offset", n_ground=2)
    assert b["root"] == a["root"] and b["truth"] == a["truth"]
    assert (b["root"] / "records" / "gm001.csv").stat().st_mtime_ns == stamp


def test_library_parameters():
    assert ic.library_parameters("none") == {}
    assert ic.library_parameters("frequency_parameter") == {"frequency_parameter": {"factor": pytest.approx(1.06)}}
    assert set(ic.library_parameters("time_lag+restitution")) == {"time_lag", "restitution"}
    for case, (_kw, expected) in ic.CASES.items():
        if isinstance(expected, tuple):
            assert set(ic.library_parameters(case)) == set(expected)


# ----------------------------------------------------------------------------
# sample rates, scaled specimens, sensors and their faults
SCALED = [c for c in ic.CASES if "scale" in ic.case_parameters(c)]
COLORED = [c for c in ic.CASES if any(k in ic.case_parameters(c) for k in ("noise_white", "noise_ou", "hum_amp"))]


def read_record(path):
    """(t [s], ground_acc [m/s^2], theta [rad]) of a written record."""
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    return data[:, 0], data[:, 1], data[:, 2]


def test_new_case_lists():
    assert SCALED == ["colored_hum60_big_200hz", "white_big_1000hz", "colored_small_1000hz"]
    assert len(COLORED) == 6 and all(ic.expected_diagnosis(c) == () for c in COLORED)
    assert ic.expected_faults("none") == () and ic.expected_faults("colored_hum50") == ()
    assert ic.expected_faults("spikes_dropouts") == ("spikes", "dropouts")
    assert ic.expected_diagnosis("saturation_colored_restitution") == ("restitution",)
    assert ic.library_parameters("saturation_colored_restitution") == {"restitution": {"r": 0.90}}
    assert ic.truth_for("saturation_colored_restitution").rho_pn == pytest.approx(math.sqrt(0.90), rel=1e-15)
    for case in ic.FAULT_CASES:
        assert ic.library_parameters(case).keys() == set(ic.expected_diagnosis(case))
    with pytest.raises(KeyError):
        ic.expected_faults("no such case")


def test_noise_truth_closed_form():
    assert ic.noise_truth("none")["sd"] == ic.NOISE and ic.noise_truth("none")["lag1"] == 0.0
    nt = ic.noise_truth("colored_hum50")
    # sqrt(0.4^2 + 0.6^2 + 0.6^2 / 2 (1 + 1/9)) mrad = sqrt(0.72) mrad
    assert nt["sd"] == pytest.approx(math.sqrt(0.72) * 1e-3, rel=1e-12)
    w = 2 * math.pi * 50.0 * 0.002
    lag1 = (0.36 * math.exp(-0.002 / 0.1) + 0.18 * (math.cos(w) + math.cos(2 * w) / 9)) / 0.72
    assert nt["lag1"] == pytest.approx(lag1, rel=1e-12)
    assert ic.noise_truth("colored_hum60_big_200hz")["dt"] == 0.005


@pytest.mark.parametrize("case", ["none", "colored_hum60_big_200hz", "white_big_1000hz", "colored_small_1000hz"])
def test_free_rocking_at_other_rates_and_scales(case):
    """The integrator's impacts at 200 and 1000 Hz (steps never cross a sample) and on a scaled block: the first
    impact at the exact fall time with p = P / sqrt(scale), the second a double fall time later (within 2e-9 s, as
    at 500 Hz), r and alpha those of the seed block."""
    truth = ic.truth_for(case)
    scale = ic.case_parameters(case).get("scale", 1.0)
    dt = ic.sample_interval(case)
    al, _rr, _i0, p = truth.side(1)
    assert p == pytest.approx(P / math.sqrt(scale), rel=1e-13)
    assert al == pytest.approx(ALPHA, rel=1e-13) and truth.rho_pn == pytest.approx(math.sqrt(ic.R_HOUSNER), rel=1e-13)
    for dt_run in {dt, 0.005, 0.001}:
        _th, _over, imp = ic.simulate_details(truth, np.zeros(int(round(3.0 / dt_run))), dt_run, theta0=0.6 * ALPHA)
        assert imp[0, 0] == pytest.approx(fall_time(0.6 * ALPHA, p=p), abs=1e-9)
        w = abs(imp[0, 2])
        theta1 = ALPHA - math.acos(math.cos(ALPHA) + w * w / (2 * p * p))
        assert imp[1, 0] - imp[0, 0] == pytest.approx(2.0 * fall_time(theta1, p=p), abs=2e-9)


@pytest.mark.parametrize("scale", [2.0, 1.6, 0.7])
def test_scaled_block_is_similar(housner, scale):
    """Geometric similarity: the block enlarged by ``scale`` under ug''(t / sqrt(scale)) rocks as the seed block
    under ug''(t), slowed by sqrt(scale): the same samples at dt sqrt(scale) give the same theta (to the
    integrators' tolerance; a motion that rocks without overturning, 0.3-0.4 alpha)."""
    big = ic.truth_for("none", options={"scale": scale})
    acc = ic.ground_motion(np.random.default_rng(7))
    a, over_a = ic.simulate(housner, acc, ic.DT)
    b, over_b = ic.simulate(big, acc, ic.DT * math.sqrt(scale))
    assert not over_a and not over_b and np.max(np.abs(a)) > 0.2 * ALPHA
    assert np.max(np.abs(a - b)) < 1e-6 * ALPHA


def test_scaled_ground_motions(tmp_path):
    """A campaign of the block enlarged 2 x has its ground motions' frequencies 1 / sqrt(2) of the seed's: the
    same seeds draw the same numbers, and the median frequency of the shaking's power (the normalised periodograms
    of 12 records pooled) drops by 0.707 within 10 % (the periodogram's resolution, 1 / 6.5 s = 0.15 Hz, is 5 % of
    the ~3.4 Hz median, and the unscaled envelope and pulse timing add a little; measured 0.68-0.74 for three sets
    of seeds, an unscaled motion gives 1); the peak stays in 1.0-2.5 g tan(alpha)."""
    a = ic.write_campaign(tmp_path / "a", "none", n_ground=12, seed=6)
    b = ic.write_campaign(tmp_path / "b", "none", n_ground=12, seed=6, options={"scale": 2.0})
    medians = []
    for info in (a, b):
        pooled = 0.0
        for rid in info["gm_ids"]:
            _t, acc, _th = read_record(info["root"] / "records" / f"{rid}.csv")
            assert 1.0 - 1e-9 <= np.max(np.abs(acc)) / G_TAN <= 2.5 + 1e-9
            shake = acc[: int(round((ic.GM_DURATION - ic.QUIET) / ic.DT))]
            power = np.abs(np.fft.rfft(shake)) ** 2
            pooled = pooled + power / power.sum()
        freq = np.fft.rfftfreq(shake.size, ic.DT)
        cum = np.cumsum(pooled)
        medians.append(freq[np.searchsorted(cum, 0.5 * cum[-1])])
    assert medians[1] / medians[0] == pytest.approx(1 / math.sqrt(2.0), rel=0.1)


@pytest.mark.parametrize("case", SCALED)
def test_scaled_campaign_written_as_stated(tmp_path, case):
    """The [specimen] table, the time column at the case's rate, and the free rocking of the written fv01
    (released at 0.75 alpha): its first zero crossing at Housner's quarter period arccosh(1/(1 - 0.75)) / p,
    p = P / sqrt(scale). Tolerance 1 %: the linearisation is 3e-4 off (see test_quarter_period), the noise
    (<= 1 mrad) over the crossing speed (~0.5 rad/s) moves the crossing by ~2 ms (0.3 %); a block of the seed's
    p would be 16-41 % off."""
    try:
        import tomllib
    except ImportError:  # Python 3.10
        import tomli as tomllib

    scale = ic.case_parameters(case)["scale"]
    dt = ic.sample_interval(case)
    info = ic.write_campaign(tmp_path / "c", case, n_ground=1, seed=2)
    spec = tomllib.loads((info["root"] / "campaign.toml").read_text())["specimen"]
    expected = {
        "height": ic.HEIGHT * scale,
        "width": ic.WIDTH * scale,
        "depth": ic.DEPTH * scale,
        "mass": ic.MASS * scale**3,
        "p": P / math.sqrt(scale),
    }
    assert spec.keys() == expected.keys()
    for k, v in expected.items():
        assert spec[k] == pytest.approx(v, rel=1e-11), k
    for rid, duration in (("gm001", ic.GM_DURATION), ("fv01", ic.FV_DURATION)):
        t, _acc, _th = read_record(info["root"] / "records" / f"{rid}.csv")
        assert t.size == round(duration / dt)
        np.testing.assert_allclose(np.diff(t), dt, atol=1.01e-6)  # %.6f
    t, _acc, th = read_record(info["root"] / "records" / "fv01.csv")
    k = int(np.flatnonzero(th < 0.0)[0])
    t_cross = t[k - 1] + dt * th[k - 1] / (th[k - 1] - th[k])
    assert t_cross == pytest.approx(math.acosh(1.0 / (1.0 - 0.75)) / (P / math.sqrt(scale)), rel=1e-2)


def test_default_options_change_nothing(tmp_path):
    """Options set to their defaults write the bytes of the plain campaign (white noise of NOISE drawn as before,
    500 Hz, the seed specimen)."""
    a = ic.write_campaign(tmp_path / "a", "none", n_ground=2, seed=4)
    b = ic.write_campaign(
        tmp_path / "b", "none", n_ground=2, seed=4, options={"noise_white": ic.NOISE, "dt": ic.DT, "scale": 1.0}
    )
    for f in sorted(a["root"].rglob("*.csv")):
        assert f.read_bytes() == (b["root"] / f.relative_to(a["root"])).read_bytes()
    assert (a["root"] / "campaign.toml").read_bytes() == (b["root"] / "campaign.toml").read_bytes()


def _noise_kwargs(case):
    nt = ic.noise_truth(case)
    return {
        "white": nt["white"],
        "ou": nt["ou"],
        "tau": nt["tau"],
        "hum_amp": nt["hum_amp"],
        "hum_freq": nt["hum_freq"],
    }


def _pooled(records):
    """Pooled mean square and lag-1 autocorrelation (sum of x_k x_k+1 over sum of x_k^2, over all records) of
    zero-mean records of one length, each with its standard error from the spread between the (independent)
    records (the ratio's by the delta method: the spread of c_i - r v_i over the mean v). A mean of per-record
    ratios would be biased by O(tau / duration) (-0.03 at tau = 0.5 s over 8 s); the pooled ratio's bias is
    O(1 / records) of that."""
    v = np.array([np.mean(x * x) for x in records])
    c = np.array([np.sum(x[:-1] * x[1:]) / x.size for x in records])
    m = len(records)
    r = c.sum() / v.sum()
    return v.mean(), v.std(ddof=1) / math.sqrt(m), r, (c - r * v).std(ddof=1) / math.sqrt(m) / v.mean()


@pytest.mark.parametrize("case", COLORED)
def test_noise_generator_statistics(case):
    """200 records of 8 s from :func:`ic.sensor_noise`: the mean square is noise_truth's sd^2 and the lag-1
    autocorrelation its lag1, each within 4 standard errors measured from the spread between the independent
    records (each starts from the stationary distribution, so the mean square is unbiased; the ratio's bias is
    O(1/200) of its standard error). The standard errors are small enough to see a missing part: under 3 % of the
    variance (the OU part is 37-82 % of it) and under 0.01 in lag1."""
    nt = ic.noise_truth(case)
    dt = nt["dt"]
    n = int(round(8.0 / dt))
    seeds = np.random.SeedSequence(11).spawn(200)
    recs = [ic.sensor_noise(np.random.default_rng(s), n, dt, **_noise_kwargs(case)) for s in seeds]
    v, se_v, r, se_r = _pooled(recs)
    assert se_v < 0.03 * nt["sd"] ** 2 and se_r < 0.01
    assert abs(v - nt["sd"] ** 2) < 4 * se_v
    assert abs(r - nt["lag1"]) < 4 * se_r


@pytest.mark.parametrize("dt, tau", [(0.002, 0.02), (0.005, 0.5), (0.001, 0.05)])
def test_ou_exact_and_stationary(dt, tau):
    """The OU part alone: its first and last samples over 10000 records have the stationary sd (standard error of
    a sample sd: sd / sqrt(2 N)), and the pooled lag-1 coefficient is exp(-dt / tau) (standard error
    sqrt((1 - a^2) / N) of an AR(1) estimate; the Euler 1 - dt / tau would be 8-9 of them off at dt / tau = 0.1,
    and a start at 0 would leave the first sample's sd at 0)."""
    m, n, ou = 10000, 50, 1.0
    seeds = np.random.SeedSequence(12).spawn(m)
    x = np.array([ic.sensor_noise(np.random.default_rng(s), n, dt, white=0.0, ou=ou, tau=tau) for s in seeds])
    for col in (x[:, 0], x[:, -1]):
        assert np.sqrt(np.mean(col**2)) == pytest.approx(ou, abs=4 * ou / math.sqrt(2 * m))
    a = math.exp(-dt / tau)
    a_hat = np.sum(x[:, :-1] * x[:, 1:]) / np.sum(x[:, :-1] ** 2)
    assert a_hat == pytest.approx(a, abs=4 * math.sqrt((1 - a * a) / (m * (n - 1))))


@pytest.mark.parametrize("case", ["colored_hum50", "colored_hum60_big_200hz"])
def test_hum_lines(case):
    """The hum alone: a line of hum_amp at hum_freq and of hum_amp / 3 at twice it (aliased at 200 Hz: 120 -> 80
    Hz), from projections over whole cycles (exact to rounding), with a phase that changes between records."""
    nt = ic.noise_truth(case)
    dt, f, amp = nt["dt"], nt["hum_freq"], nt["hum_amp"]
    t = np.arange(int(round(8.0 / dt))) * dt
    phases = []
    for seed in (1, 2):
        x = ic.sensor_noise(np.random.default_rng(seed), t.size, dt, white=0.0, hum_amp=amp, hum_freq=f)
        for mult, expect in ((1, amp), (2, amp / 3)):
            z = 2.0 * np.mean(x * np.exp(-2j * math.pi * mult * f * t))
            assert abs(z) == pytest.approx(expect, rel=1e-9)
        phases.append(np.angle(2.0 * np.mean(x * np.exp(-2j * math.pi * f * t))))
    assert abs(phases[0] - phases[1]) > 1e-3


@pytest.mark.parametrize("case", COLORED)
def test_written_noise(tmp_path, case):
    """The noise of a written campaign: theta minus the block's theta simulated from the written ground_acc
    (rounded to 10 digits: the two agree to ~1e-9 rad) over 12 ground-motion records has noise_truth's total sd
    and lag-1 autocorrelation, within 4 standard errors from the spread between the records (11 degrees of
    freedom: a false alarm below 1 %; the standard error of the mean square is 1-12 % of it here, the larger for the
    slow tau = 0.5 s)."""
    info = ic.write_campaign(tmp_path / "c", case, n_ground=12, seed=3)
    nt = ic.noise_truth(case)
    dt = info["dt"]
    res = []
    for rid in info["gm_ids"]:
        _t, acc, th = read_record(info["root"] / "records" / f"{rid}.csv")
        true, _over = ic.simulate(info["truth"], acc, dt)
        res.append(th - true)
    assert max(np.max(np.abs(x)) for x in res) < 8 * nt["sd"]  # noise, and no trace of the block's motion
    v, se_v, r, se_r = _pooled(res)
    assert se_v < 0.15 * nt["sd"] ** 2
    assert abs(v - nt["sd"] ** 2) < 4 * se_v
    assert abs(r - nt["lag1"]) < 4 * se_r


def test_saturation(tmp_path):
    """The written theta never leaves +-saturation; where the block's theta is beyond it by 6 noise sigmas the
    record reads the limit exactly, where it is 6 sigmas inside the record is theta plus noise (never at the
    limit); fv01 (released at 0.75 alpha) starts clipped; the logged clipped counts are the samples at the limit."""
    sat = ic.FAULT_CASES["saturation"][0]["saturation"]
    info = ic.write_campaign(tmp_path / "c", "saturation", n_ground=4, seed=1)
    sigma = ic.noise_truth("saturation")["sd"]
    n_at_limit = 0
    for rid, kind, i in ic.recording_order(4):
        _t, acc, th = read_record(info["root"] / "records" / f"{rid}.csv")
        theta0 = 0.0 if kind == "ground_motion" else ic.FV_RELEASES[i] * ALPHA
        true, _over = ic.simulate(info["truth"], acc, ic.DT, theta0=theta0)
        assert np.max(np.abs(th)) <= sat * (1 + 1e-9)
        beyond = np.abs(true) > sat + 6 * sigma
        inside = np.abs(true) < sat - 6 * sigma
        np.testing.assert_allclose(th[beyond], np.sign(true[beyond]) * sat, rtol=1e-9)
        assert np.all(np.abs(th[inside] - true[inside]) < 6 * sigma)
        at_limit = np.abs(np.abs(th) - sat) < 1e-9 * sat
        assert not np.any(at_limit & inside)
        assert np.count_nonzero(at_limit) == info["sensor"][rid]["clipped"]
        n_at_limit += np.count_nonzero(at_limit)
        if rid == "fv01":
            assert th[0] == pytest.approx(sat, rel=1e-9)
    assert n_at_limit > 100


def test_gain_drift(tmp_path):
    """The last free vibration's release reads gain_end = 1.25 times its angle, the first's 1.0 times (the ratio
    of the two ratios is gain_end to 1.5 %: each release is fitted to 0.1-0.2 mrad, 0.2-0.4 % of these angles);
    and every record's theta regressed on the block's theta has the slope of the linear drift along the
    recording order (4 standard errors sigma / sqrt(sum theta^2))."""
    n_ground = 2
    info = ic.write_campaign(tmp_path / "c", "gain_drift", n_ground=n_ground, seed=1)
    camp = load_campaign(info["root"])
    fv = {rec.id: rec.motion.theta0 for rec in camp.free_vibration}
    first = fv["fv01"] / (ic.FV_RELEASES[0] * ALPHA)
    last = fv["fv03"] / (ic.FV_RELEASES[2] * ALPHA)
    assert first == pytest.approx(1.0, abs=0.01)
    assert last / first == pytest.approx(1.25, rel=0.015)
    order = ic.recording_order(n_ground)
    for k, (rid, kind, i) in enumerate(order):
        _t, acc, th = read_record(info["root"] / "records" / f"{rid}.csv")
        theta0 = 0.0 if kind == "ground_motion" else ic.FV_RELEASES[i] * ALPHA
        true, _over = ic.simulate(info["truth"], acc, ic.DT, theta0=theta0)
        slope = np.sum(th * true) / np.sum(true * true)
        gain = 1.0 + 0.25 * k / (len(order) - 1)
        assert info["sensor"][rid]["gain"] == pytest.approx(gain, rel=1e-12)
        assert slope == pytest.approx(gain, abs=4 * ic.NOISE / math.sqrt(np.sum(true * true)))


def test_fault_generator_rates():
    """:func:`ic.sensor_faults` over 2000 s at 500 Hz: spikes and dropouts at their Poisson rates (4 standard
    errors sqrt(N) of the counts: 600 +- 98 spikes, 200 +- 57 dropouts), every spike isolated and of +-amp, every
    dropout a run of round(len / dt) repeats of the sample before it (but where cut by the end), the rest
    untouched."""
    dt, n = 0.002, 1_000_000
    x = np.random.default_rng(0).normal(0.0, 1e-3, n)
    y, log = ic.sensor_faults(
        x, dt, np.random.default_rng(1), spike_rate=0.3, spike_amp=25e-3, dropout_rate=0.1, dropout_len=0.1
    )
    duration = n * dt
    spikes, drops = np.array(log["spikes"]), log["dropouts"]
    assert abs(spikes.size - 0.3 * duration) < 4 * math.sqrt(0.3 * duration)
    assert abs(len(drops) - 0.1 * duration) < 4 * math.sqrt(0.1 * duration)
    assert np.all(np.diff(spikes) > 1)
    held = np.zeros(n, dtype=bool)
    for start, length in drops:
        assert length == 50 or start + length == n
        held[start : start + length] = True
    for start, length in drops:
        seg = y[start : start + length]
        assert np.all(seg == y[start - 1])
    free = ~held
    hit = np.zeros(n, dtype=bool)
    hit[spikes] = True
    d = y - x
    np.testing.assert_allclose(np.abs(d[free & hit]), 25e-3, rtol=1e-12)
    assert np.all(d[free & ~hit] == 0.0)


def test_spikes_and_dropouts_in_a_campaign(tmp_path):
    """Found in the written records without the log: a spike is a sample 0.75 spike_amp (19 mrad) off the mean of
    its neighbours (a spike's neighbours are 0.5 spike_amp off, the noise and the rocking's curvature add < 4
    mrad) while they agree to 0.5 spike_amp (the jump at a dropout's end is off its neighbours' mean by half
    its size, but they differ by all of it), a dropout a run of equal values (the noise
    makes equal neighbours impossible otherwise); their counts are the Poisson rates times the campaign's 116 s
    within 4 standard errors (35 +- 24 spikes, 12 +- 14 dropouts) and as logged (a spike next to or under a dropout
    can hide); a dropout holds 0.1 s = 50 samples."""
    n_ground = 10
    info = ic.write_campaign(tmp_path / "c", "spikes_dropouts", n_ground=n_ground, seed=5)
    duration = n_ground * ic.GM_DURATION + len(ic.FV_RELEASES) * ic.FV_DURATION
    n_spikes = n_runs = 0
    run_lengths = []
    for rid, _kind, _i in ic.recording_order(n_ground):
        _t, _acc, th = read_record(info["root"] / "records" / f"{rid}.csv")
        dev = np.abs(th[1:-1] - 0.5 * (th[:-2] + th[2:]))
        n_spikes += int(np.count_nonzero((dev > 0.75 * 25e-3) & (np.abs(th[2:] - th[:-2]) < 0.5 * 25e-3)))
        same = np.concatenate(([False], th[1:] == th[:-1], [False]))
        edges = np.flatnonzero(np.diff(same.astype(int)))
        starts, ends = edges[::2], edges[1::2]
        n_runs += starts.size
        run_lengths += list(ends - starts)
    logged_spikes = sum(len(v["spikes"]) for v in info["sensor"].values())
    logged_drops = sum(len(v["dropouts"]) for v in info["sensor"].values())
    assert abs(logged_spikes - 0.3 * duration) < 4 * math.sqrt(0.3 * duration)
    assert abs(logged_drops - 0.1 * duration) < 4 * math.sqrt(0.1 * duration)
    assert logged_spikes - 3 <= n_spikes <= logged_spikes
    assert logged_drops - 1 <= n_runs <= logged_drops and n_runs >= 1
    assert np.median(run_lengths) == 50  # the held samples after the last good one


@pytest.mark.parametrize("case", list(ic.FAULT_CASES))
def test_fault_case_loads(tmp_path, case):
    info = ic.write_campaign(tmp_path / "c", case, n_ground=4, seed=1)
    camp = load_campaign(info["root"])
    assert camp.skipped == []
    assert [r.id for r in camp.records] == [rid for rid, _k, _i in ic.recording_order(4)]


# ----------------------------------------------------------------------------
# cross-check with the library (the only place it is used)
@pytest.mark.slow
def test_free_vibrations_match_library(housner):
    """The ``none`` free vibrations agree with :func:`housner.model.simulate` to 1e-4 alpha over 10 s (free
    rocking is not chaotic: both integrators are accurate to ~1e-9 rad, the rest rules differ below 1e-8 rad)."""
    spec = Specimen.bachmann2017()
    n = int(round(10.0 / ic.DT)) + 1
    for x in ic.FV_RELEASES:
        acc = np.zeros(n)
        mine, _ = ic.simulate(housner, acc, ic.DT, theta0=x * ALPHA)
        lib = simulate(spec, GroundMotion(acc=acc, dt=ic.DT, name=f"fv {x}", theta0=x * ALPHA))
        assert np.max(np.abs(mine - lib.theta[:n])) < 1e-4 * ALPHA
