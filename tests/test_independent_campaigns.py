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
    for rec, x in zip(camp.free_vibration, releases, strict=True):
        assert not rec.overturned
        # the release is fitted to the noisy samples (standard error 0.1-0.2 mrad, campaign.estimate_release)
        assert rec.motion.theta0 == pytest.approx(x * ALPHA + truth.offset, abs=1e-3)
    for rec, over in zip(camp.ground_motion, info["overturned"], strict=True):
        assert rec.overturned == bool(over)
        assert rec.dt == pytest.approx(ic.DT)


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
