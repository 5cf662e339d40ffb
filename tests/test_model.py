"""The analytic Housner solver against closed forms and independent computations.

Energies are normalised by the moment of inertia about the pivot and by p^2:
E = theta'^2 / (2 p^2) + cos(alpha - |theta|) - cos(alpha) [-], zero at rest;
at theta = 0 only the kinetic part remains.
"""

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp
from shared import reference_solve_ivp

from housner import G, GroundMotion, Specimen
from housner.model import default_substeps, simulate, simulate_many, theta_max_many
from housner.rocking_params import RockingParams

DATA = Path(__file__).resolve().parents[1] / "scenarios" / "catalogue" / "data"
SPEC = Specimen.bachmann2017()
ALPHA = SPEC.alpha
P = SPEC.p
R = SPEC.r_housner


# ----------------------------------------------------------------------
# independent references
def quarter_period(theta_pk, alpha=ALPHA, p=P):
    """Time [s] from theta = 0 to the free-rocking peak theta_pk, by quadrature of the energy integral.

    theta'^2 = 2 p^2 (cos(alpha - theta) - cos(alpha - theta_pk)) = 4 p^2 sin(alpha - (theta + theta_pk)/2)
    sin((theta_pk - theta)/2); the inverse square root singularity at theta_pk is taken by quad's
    algebraic weight, the rest of the integrand is smooth.
    """

    def smooth(th):
        x = 0.5 * (theta_pk - th)
        ratio = 1.0 if x == 0.0 else x / math.sin(x)
        return math.sqrt(ratio / (2.0 * p * p * math.sin(alpha - 0.5 * (th + theta_pk))))

    val, _ = quad(smooth, 0.0, theta_pk, weight="alg", wvar=(0.0, -0.5), epsabs=0.0, epsrel=1e-13)
    return val


def fall_time(theta0, alpha=ALPHA, p=P):
    """Time [s] for a block released at rest from theta0 > alpha to reach pi/2 (energy integral)."""

    def smooth(th):
        x = 0.5 * (th - theta0)
        ratio = 1.0 if x == 0.0 else x / math.sin(x)
        return math.sqrt(ratio / (2.0 * p * p * math.sin(0.5 * (th + theta0) - alpha)))

    val, _ = quad(smooth, theta0, math.pi / 2, weight="alg", wvar=(-0.5, 0.0), epsabs=0.0, epsrel=1e-13)
    return val


def peak_from_energy(e, alpha=ALPHA):
    """Free-rocking peak [rad] of a block with normalised energy e [-]."""
    return alpha - math.acos(math.cos(alpha) + e)


def energy(res, alpha=ALPHA, p=P):
    return res.theta_dot**2 / (2.0 * p * p) + np.cos(alpha - np.abs(res.theta)) - math.cos(alpha)


def noise_record(seed, n, dt, pga_g, f_lo=1.0, f_hi=8.0):
    """Band-limited Gaussian noise with a sine-squared envelope, scaled to pga_g [g]."""
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    spec = np.fft.rfft(rng.standard_normal(n))
    f = np.fft.rfftfreq(n, dt)
    spec[(f < f_lo) | (f > f_hi)] = 0.0
    a = np.fft.irfft(spec, n) * np.sin(np.pi * np.arange(n) / (n - 1)) ** 2
    return a * (pga_g * G / np.max(np.abs(a)))


def sine_pulse(amp_g, freq, dt=0.002, duration=4.0, cycles=1.0, delay=0.1):
    """One-sine acceleration pulse ug'' = -amp sin(2 pi f (t - delay)) [m/s^2], zero elsewhere."""
    t = np.arange(0.0, duration + 0.5 * dt, dt)
    tt = t - delay
    on = (tt >= 0) & (tt <= cycles / freq)
    return GroundMotion(np.where(on, -amp_g * G * np.sin(2 * np.pi * freq * tt), 0.0), dt, name="pulse")


@pytest.fixture(scope="module")
def elcentro():
    return GroundMotion.from_at2(DATA / "elcentro_1940_ns_I-ELC180_peer1999.AT2").to_model_scale(10)


# ----------------------------------------------------------------------
# 1. free rocking periods
def test_free_rocking_half_cycles_match_energy_quadrature():
    theta0 = 0.5 * ALPHA
    res = simulate(SPEC, GroundMotion.free_vibration(theta0, 6.0))
    imp = res.impact_times
    assert imp.size >= 10
    # energy after impact k is r^k E0 (kinetic only at theta = 0), so each half-cycle peak is known
    e0 = math.cos(ALPHA - theta0) - math.cos(ALPHA)
    peaks = [peak_from_energy(e0 * R**k) for k in range(imp.size)]
    predicted = np.array([quarter_period(peaks[0])] + [2.0 * quarter_period(x) for x in peaks[1:]])
    measured = np.diff(np.concatenate([[0.0], imp]))
    # RK4 at p h <= 0.01 times impacts to ~1e-10 relative (measured 7e-11); 1e-6 is the brief's bound
    np.testing.assert_allclose(measured, predicted, rtol=1e-6, atol=0)


@pytest.mark.parametrize("q", [0.05, 0.1, 0.25, 0.35, 0.5])
def test_housner_cosh_formula(q):
    """Seed eq. 7, cosh(p T/4) = 1/(1 - theta0/alpha), is a small-alpha linearisation.

    As theta0 -> 0 its quarter period is short by the factor sqrt(sin(alpha)/alpha) ~ 1 - alpha^2/12
    (0.185 % for this specimen); the error shrinks with amplitude and is below 0.1 % for
    theta0 >= 0.35 alpha (0.065 % at 0.5 alpha). Checked against the solver, which matches the
    exact quadrature above.
    """
    res = simulate(SPEC, GroundMotion.free_vibration(q * ALPHA, 1.0))
    t4 = res.impact_times[0]
    t4_cosh = math.acosh(1.0 / (1.0 - q)) / P
    err = abs(t4_cosh - t4) / t4
    assert err <= ALPHA**2 / 12 * 1.001  # the small-amplitude limit bounds the error
    if q >= 0.35:
        assert err < 1e-3


# ----------------------------------------------------------------------
# 2-3. energy
def test_energy_ratio_per_impact_is_r_and_energy_is_conserved_between_impacts():
    res = simulate(SPEC, GroundMotion.free_vibration(0.6 * ALPHA, 5.0))
    e = energy(res)
    k_after = np.searchsorted(res.t, res.impact_times)  # first sample after each impact
    assert k_after.size >= 8 and np.all(np.diff(k_after) > 2)
    # between impacts RK4 drifts in energy by ~(p h)^4 per half-cycle; measured 5e-12 relative
    for a, b in zip(np.concatenate([[0], k_after]), np.concatenate([k_after, [res.t.size]]), strict=True):
        seg = e[a:b]
        assert np.max(np.abs(seg - seg[0])) <= 1e-10 * seg[0]
    # at the impact itself the kinetic energy drops by r exactly (ratio of neighbouring samples,
    # each conserved to 1e-11): 1e-9
    ratios = e[k_after[:-1]] / e[k_after[:-1] - 1]
    np.testing.assert_allclose(ratios, R, rtol=1e-9)


# ----------------------------------------------------------------------
# 4. mirror symmetry
def test_mirror_symmetry_is_exact_on_noise():
    acc = noise_record(11, 3000, 0.002, 0.4)
    a = simulate(SPEC, GroundMotion(acc, 0.002))
    b = simulate(SPEC, GroundMotion(-acc, 0.002))
    assert a.n_impacts > 3
    assert np.array_equal(a.theta, -b.theta) and np.array_equal(a.theta_dot, -b.theta_dot)
    assert np.array_equal(a.impact_times, b.impact_times) and a.theta_max == b.theta_max


def test_mirror_symmetry_is_exact_on_el_centro(elcentro):
    m = elcentro.scaled(1.0)  # model scale (S = 10), PGA 0.31 g: rocks to ~0.47 alpha, does not overturn
    a = simulate(SPEC, m)
    b = simulate(SPEC, m.scaled(-1.0))
    assert not a.overturned and a.n_impacts > 10 and a.theta_max_over_alpha > 0.2
    assert np.array_equal(a.theta, -b.theta) and np.array_equal(a.theta_dot, -b.theta_dot)
    assert np.array_equal(a.impact_times, b.impact_times) and a.uplift_time == b.uplift_time


def test_mirror_symmetry_is_exact_with_overturn():
    m = sine_pulse(0.45, 1.5, duration=3.0)
    a, b = simulate(SPEC, m), simulate(SPEC, m.scaled(-1.0))
    assert a.overturned and b.overturned and a.overturn_time == b.overturn_time
    assert np.array_equal(a.theta, -b.theta)


# ----------------------------------------------------------------------
# 5. convergence and peaks between samples
@pytest.mark.parametrize("amp_g, freq", [(0.3, 4.0), (0.2, 3.0)])
def test_theta_max_converged_when_step_halved(amp_g, freq):
    m = sine_pulse(amp_g, freq)
    m0 = default_substeps(P, m.dt)
    a = simulate(SPEC, m)
    b = simulate(SPEC, m, substeps=2 * m0)
    assert a.info["substeps"] == m0 and not a.overturned and a.n_impacts >= 2 and a.theta_max_over_alpha > 0.1
    assert abs(a.theta_max - b.theta_max) < 1e-6 * ALPHA


def test_peak_between_samples_is_located():
    # launched from theta = 0 with speed v on a coarse 10 ms grid: the peak comes from the energy
    # integral, the sampled maximum is off by ~(p dt)^2 while the located peak is exact to ~1e-10
    v = 0.3
    res = simulate(SPEC, GroundMotion(np.zeros(101), 0.01), theta_dot0=v)
    exact = peak_from_energy(v * v / (2 * P * P))
    assert abs(res.theta_max - exact) < 1e-9 * exact
    assert np.max(np.abs(res.theta)) < res.theta_max


# ----------------------------------------------------------------------
# 6. uplift
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_uplift_threshold(sign):
    n, dt = 501, 0.002
    below = simulate(SPEC, GroundMotion(np.full(n, -sign * (1 - 1e-9) * G * math.tan(ALPHA)), dt))
    assert not below.rocked and np.all(below.theta == 0.0) and np.isnan(below.uplift_time)
    above = simulate(SPEC, GroundMotion(np.full(n, -sign * (1 + 1e-9) * G * math.tan(ALPHA)), dt))
    # ug'' below -g tan(alpha) tilts the block toward +x (theta > 0), and vice versa
    assert above.uplift_time == 0.0 and sign * above.theta[-1] > 0.0 and np.all(sign * above.theta >= 0.0)


def test_uplift_time_is_root_of_interpolant():
    dt, k = 0.002, 3.0  # ramp ug'' = -k t [m/s^2] reaches -g tan(alpha) at t = g tan(alpha) / k
    res = simulate(SPEC, GroundMotion(-k * np.arange(501) * dt, dt))
    assert res.uplift_time == pytest.approx(G * math.tan(ALPHA) / k, rel=1e-13)
    assert np.all(res.theta[res.t < res.uplift_time] == 0.0) and res.theta[-1] > 0.0


# ----------------------------------------------------------------------
# 7. overturning
def test_strong_long_pulse_overturns():
    m = GroundMotion(np.where(np.arange(1501) * 0.002 < 1.0, -0.5 * G, 0.0), 0.002)
    res = simulate(SPEC, m)
    assert res.overturned and res.theta_max_over_alpha == math.inf and res.theta_max == math.pi / 2
    k = np.searchsorted(res.t, res.overturn_time)
    assert np.all(res.theta[k:] == math.pi / 2) and np.all(res.theta_dot[k:] == 0.0)
    assert np.all(np.abs(res.theta[:k]) < math.pi / 2)


def test_release_beyond_alpha_falls_within_returns():
    out = simulate(SPEC, GroundMotion.free_vibration(1.05 * ALPHA, 3.0))
    assert out.overturned and out.n_impacts == 0
    # fall time from the energy integral; RK4 and the Newton event location agree to ~1e-10
    assert out.overturn_time == pytest.approx(fall_time(1.05 * ALPHA), rel=1e-8)
    back = simulate(SPEC, GroundMotion.free_vibration(0.98 * ALPHA, 3.0))
    assert not back.overturned and back.n_impacts >= 1 and back.theta_max == 0.98 * ALPHA
    neg = simulate(SPEC, GroundMotion.free_vibration(-1.05 * ALPHA, 3.0))
    assert neg.overturned and neg.theta[-1] == -math.pi / 2


# ----------------------------------------------------------------------
# 8. against scipy's solve_ivp
@pytest.mark.parametrize(
    "motion",
    [
        pytest.param(lambda: sine_pulse(0.3, 4.0, duration=2.0), id="sine-pulse"),
        pytest.param(lambda: GroundMotion(noise_record(3, 1001, 0.002, 0.35), 0.002), id="noise-a"),
        pytest.param(lambda: GroundMotion(noise_record(5, 1001, 0.002, 0.35), 0.002), id="noise-b"),
        pytest.param(lambda: sine_pulse(0.4, 2.0, duration=2.0), id="overturn"),
    ],
)
def test_against_solve_ivp(motion):
    m = motion()
    res = simulate(SPEC, m)
    ref_max, ref_over, ref_imp = reference_solve_ivp(m.acc, m.dt, ALPHA, P, R)
    assert res.rocked and res.overturned == ref_over
    # both are converged to ~1e-8 alpha (measured 3e-8 at most on such records); 1e-6 alpha is the brief's bound
    assert abs(res.theta_max - ref_max) < 1e-6 * ALPHA
    assert res.n_impacts == ref_imp.size
    # impact times: RK4's error (p h)^4 is amplified by 1/theta' at slow, grazing impacts in chatter
    # sequences; measured 5e-8 s at most (noise-b, impact 39 of 42, converging as h^4 with substeps)
    np.testing.assert_allclose(res.impact_times, ref_imp, rtol=0, atol=5e-7)


# ----------------------------------------------------------------------
# 9. rest, re-uplift, Zeno
def test_free_vibration_comes_to_rest_after_the_predicted_impact():
    theta0, tol = 0.5 * ALPHA, 1e-6
    res = simulate(SPEC, GroundMotion.free_vibration(theta0, 25.0), rest_tol=tol)
    # the energy after impact k is r^k E0; rest at the first impact whose peak is below tol*alpha.
    # (the prediction is 2.6 % away from the threshold on either side: no rounding can tip it)
    e0 = math.cos(ALPHA - theta0) - math.cos(ALPHA)
    e_rest = math.cos(ALPHA - tol * ALPHA) - math.cos(ALPHA)
    k_pred = next(k for k in range(1, 10_000) if e0 * R**k < e_rest)
    assert res.n_impacts == k_pred
    k = np.searchsorted(res.t, res.impact_times[-1])
    assert np.all(res.theta[k:] == 0.0) and np.all(res.theta_dot[k:] == 0.0)
    assert res.theta[-1] == 0.0
    # the same on a 1 s sample grid (489 substeps per sample): the 234 impacts overflow the solver's
    # first impact buffer (64 for 26 samples), which is then refilled; the times agree to RK4's error
    coarse = simulate(SPEC, GroundMotion.free_vibration(theta0, 25.0, dt=1.0), rest_tol=tol)
    assert coarse.n_impacts == k_pred
    np.testing.assert_allclose(coarse.impact_times, res.impact_times, rtol=0, atol=1e-8)


def test_rest_then_reuplift_on_second_pulse():
    dt = 0.002
    first = sine_pulse(0.25, 4.0, dt=dt, duration=12.0, delay=0.1).acc
    second = np.roll(sine_pulse(0.25, 4.0, dt=dt, duration=12.0, delay=0.1).acc, int(8.0 / dt))
    # r = 0.5 makes the block settle (by the rest rule) within ~1.3 s of the first pulse
    res = simulate(SPEC, GroundMotion(first + second, dt), r=0.5)
    alone = simulate(SPEC, GroundMotion(first, dt), r=0.5)
    quiet = (res.t > alone.impact_times[-1] + 0.01) & (res.t < 8.1)
    assert alone.impact_times[-1] < 7.5 and np.all(res.theta[quiet] == 0.0)  # at rest before the second pulse
    late = res.impact_times[res.impact_times > 8.0]
    assert late.size >= 2 and np.max(np.abs(res.theta[res.t > 8.1])) > 0.1 * ALPHA
    # the block is at rest when the second pulse comes, so it answers it exactly as to the first
    np.testing.assert_allclose(late - 8.0, alone.impact_times, rtol=0, atol=1e-9)


def test_rest_and_reuplift_within_the_same_sample():
    # r = 0: the block stops dead at its first impact; the ground acceleration is then still beyond
    # +g tan(alpha), so it lifts at once onto the other corner (theta < 0) in the same sample
    dt = 0.002
    t = np.arange(0, 2.0 + dt / 2, dt)
    acc = np.where(t < 0.1, -0.3 * G, np.where(t < 1.5, 0.3 * G, 0.0))
    res = simulate(SPEC, GroundMotion(acc, dt), r=0.0)
    assert res.n_impacts == 1 and res.overturned and res.theta[-1] == -math.pi / 2  # 0.3 g held: it falls
    t_imp = res.impact_times[0]
    assert 0.1 < t_imp < res.overturn_time < 1.5
    k = np.searchsorted(res.t, t_imp)
    assert res.theta[k] < 0.0 and res.theta_dot[k] < 0.0
    # with a zero-speed restart the first samples follow theta'' = -p^2 (sin(-alpha-theta) + a cos(...)),
    # i.e. theta ~ -p^2 (a cos(alpha) - sin(alpha)) (t - t_imp)^2 / 2 for small t - t_imp
    tau = res.t[k] - t_imp
    approx = -0.5 * P * P * (0.3 * math.cos(ALPHA) - math.sin(ALPHA)) * tau * tau
    assert res.theta[k] == pytest.approx(approx, rel=1e-2)


def test_elastic_impacts_keep_rocking():
    res = simulate(SPEC, GroundMotion.free_vibration(0.3 * ALPHA, 10.0), r=1.0)
    half = np.diff(res.impact_times)
    assert half.size > 10
    np.testing.assert_allclose(half, 2 * quarter_period(0.3 * ALPHA), rtol=1e-8)


# ----------------------------------------------------------------------
# model parameters ("physical effects")
def test_params_from_specimen_are_plain_housner():
    prm = RockingParams.from_specimen(SPEC)
    assert prm.is_housner and prm.r == R and prm.alpha_pos == ALPHA and prm.p_neg == P
    m = GroundMotion(noise_record(7, 2000, 0.002, 0.4), 0.002)
    a, b = simulate(SPEC, m), simulate(SPEC, m, params=prm)
    assert np.array_equal(a.theta, b.theta) and np.array_equal(a.impact_times, b.impact_times)
    c = simulate(SPEC, m, params=RockingParams.from_specimen(SPEC, r=0.5))
    assert c.info["params"]["r"] == 0.5 and not np.array_equal(a.theta, c.theta)


def test_asymmetric_slenderness_sets_each_uplift_threshold():
    prm = RockingParams(alpha_pos=0.15, alpha_neg=0.10, p_pos=P, p_neg=P, r=R)
    acc = G * math.tan(0.12)  # between the two thresholds
    push_neg = simulate(SPEC, GroundMotion(np.full(300, acc), 0.002), params=prm)
    assert push_neg.theta[-1] < 0.0  # beyond g tan(alpha_neg): lifts onto the -x corner
    push_pos = simulate(SPEC, GroundMotion(np.full(300, -acc), 0.002), params=prm)
    assert not push_pos.rocked  # below g tan(alpha_pos): stays


def test_asymmetric_frequency_parameter_per_side():
    p_pos, p_neg = 4.0, 6.0
    prm = RockingParams(alpha_pos=ALPHA, alpha_neg=ALPHA, p_pos=p_pos, p_neg=p_neg, r=0.9)
    theta0 = 0.5 * ALPHA
    res = simulate(SPEC, GroundMotion.free_vibration(theta0, 1.5), params=prm)
    t1, t2 = res.impact_times[:2]
    assert t1 == pytest.approx(quarter_period(theta0, p=p_pos), rel=1e-8)
    # impact speed from the + side's energy integral, then the - side's peak from its own p
    v2 = 0.9 * 2 * p_pos**2 * (math.cos(ALPHA - theta0) - math.cos(ALPHA))
    peak_neg = peak_from_energy(v2 / (2 * p_neg**2))
    assert t2 - t1 == pytest.approx(2 * quarter_period(peak_neg, p=p_neg), rel=1e-8)


def test_amplitude_dependent_restitution():
    n_exp, theta0 = 0.5, 0.7 * ALPHA
    prm = RockingParams(ALPHA, ALPHA, P, P, r=R, r_amp_exponent=n_exp)
    res = simulate(SPEC, GroundMotion.free_vibration(theta0, 1.0), params=prm)
    e = energy(res)
    k = np.searchsorted(res.t, res.impact_times[0])
    v = math.sqrt(2 * P * P * (math.cos(ALPHA - theta0) - math.cos(ALPHA)))  # impact speed [rad/s]
    r_eff = R * (v / (P * ALPHA)) ** n_exp
    assert e[k] / e[k - 1] == pytest.approx(r_eff, rel=1e-9)  # as the energy test above


def test_per_side_restitution_applies_to_the_landing_corner():
    """r_pos is the impact that lands on the +x corner, r_neg the one that lands on the -x corner.

    Released on the +x corner the first impact lands on -x: theta'^2 drops by r_neg, the next by r_pos,
    alternately; with an amplitude exponent the law of r_amp_exponent is applied on top of each side's
    ratio, with the speed reference of the corner left. Energies as in the energy test above (1e-9).
    """
    r_pos, r_neg, theta0 = 0.7, 0.95, 0.6 * ALPHA
    prm = RockingParams(ALPHA, ALPHA, P, P, R, r_pos=r_pos, r_neg=r_neg)
    res = simulate(SPEC, GroundMotion.free_vibration(theta0, 3.0), params=prm)
    e = energy(res)
    k = np.searchsorted(res.t, res.impact_times)
    assert k.size >= 6
    ratios = e[k[:6]] / e[k[:6] - 1]
    np.testing.assert_allclose(ratios, [r_neg, r_pos] * 3, rtol=1e-9)
    # amplitude-dependent on top: r_eff = r_side (v / (p alpha))^n
    n_exp = 0.5
    prm = RockingParams(ALPHA, ALPHA, P, P, R, r_amp_exponent=n_exp, r_pos=r_pos, r_neg=r_neg)
    res = simulate(SPEC, GroundMotion.free_vibration(theta0, 1.5), params=prm)
    e = energy(res)
    k = np.searchsorted(res.t, res.impact_times)
    v = math.sqrt(2 * P * P * (math.cos(ALPHA - theta0) - math.cos(ALPHA)))  # first impact speed [rad/s]
    r1 = r_neg * (v / (P * ALPHA)) ** n_exp
    v2 = math.sqrt(r1) * v  # after the first impact; the half-cycle returns with the same speed (no damping)
    r2 = r_pos * (v2 / (P * ALPHA)) ** n_exp
    np.testing.assert_allclose(e[k[:2]] / e[k[:2] - 1], [r1, r2], rtol=1e-9)


def test_per_side_restitution_equal_to_r_is_the_plain_model_bit_for_bit():
    m = GroundMotion(noise_record(7, 2000, 0.002, 0.4), 0.002)
    plain = simulate(SPEC, m)
    same = simulate(SPEC, m, params=RockingParams(ALPHA, ALPHA, P, P, R, r_pos=R, r_neg=R))
    assert plain.n_impacts > 5
    assert np.array_equal(plain.theta, same.theta) and np.array_equal(plain.theta_dot, same.theta_dot)
    assert np.array_equal(plain.impact_times, same.impact_times) and plain.theta_max == same.theta_max
    # also on an asymmetric, damped block with amplitude-dependent restitution
    kw = {"r_amp_exponent": 0.3, "damping": 0.2}
    a = simulate(SPEC, m, params=RockingParams(0.16, 0.14, 4.7, 5.1, 0.9, **kw))
    b = simulate(SPEC, m, params=RockingParams(0.16, 0.14, 4.7, 5.1, 0.9, r_pos=0.9, r_neg=0.9, **kw))
    assert a.n_impacts > 5 and np.array_equal(a.theta, b.theta) and np.array_equal(a.impact_times, b.impact_times)
    assert RockingParams(ALPHA, ALPHA, P, P, R, r_pos=R, r_neg=R).is_housner
    assert not RockingParams(ALPHA, ALPHA, P, P, R, r_pos=0.9).is_housner


def test_mirror_with_sides_swapped_is_exact():
    """Mirroring ug and swapping every per-side parameter mirrors the response bit for bit."""
    prm = RockingParams(0.16, 0.13, 4.6, 5.2, 0.9, r_amp_exponent=0.3, damping=0.1, r_pos=0.86, r_neg=0.93)
    mir = prm.mirrored()
    assert (mir.alpha_pos, mir.p_pos, mir.r_pos) == (prm.alpha_neg, prm.p_neg, prm.r_neg)
    assert (mir.alpha_neg, mir.p_neg, mir.r_neg) == (prm.alpha_pos, prm.p_pos, prm.r_pos) and mir.mirrored() == prm
    acc = noise_record(11, 3000, 0.002, 0.45)
    a = simulate(SPEC, GroundMotion(acc, 0.002), params=prm)
    b = simulate(SPEC, GroundMotion(-acc, 0.002), params=mir)
    assert a.n_impacts > 5
    assert np.array_equal(a.theta, -b.theta) and np.array_equal(a.theta_dot, -b.theta_dot)
    assert np.array_equal(a.impact_times, b.impact_times) and a.theta_max == b.theta_max
    # without the swap the response is another one: the sides really matter
    c = simulate(SPEC, GroundMotion(-acc, 0.002), params=prm)
    assert not np.array_equal(a.theta, -c.theta)
    # a free vibration released on either side
    d = simulate(SPEC, GroundMotion.free_vibration(0.1, 2.0), params=prm)
    f = simulate(SPEC, GroundMotion.free_vibration(-0.1, 2.0), params=mir)
    assert d.n_impacts >= 4 and np.array_equal(d.theta, -f.theta) and np.array_equal(d.impact_times, f.impact_times)


def test_with_r_rescales_the_per_side_ratios():
    prm = RockingParams(ALPHA, ALPHA, P, P, 0.9, r_pos=0.85, r_neg=0.95)
    q = prm.with_r(0.45)
    assert (q.r, q.r_pos, q.r_neg) == pytest.approx((0.45, 0.425, 0.475), rel=1e-15)
    assert prm.with_r(1.0).r_neg == 1.0  # clipped: 0.95 / 0.9 > 1
    assert RockingParams.from_specimen(SPEC).with_r(0.5) == RockingParams.from_specimen(SPEC, r=0.5)
    # simulate(..., r=) with params goes through with_r
    m = GroundMotion.free_vibration(0.5 * ALPHA, 1.0)
    assert np.array_equal(simulate(SPEC, m, params=prm, r=0.45).theta, simulate(SPEC, m, params=q).theta)


def test_viscous_damping_against_solve_ivp():
    c, theta0 = 0.4, 0.5 * ALPHA
    prm = RockingParams(ALPHA, ALPHA, P, P, r=R, damping=c)
    res = simulate(SPEC, GroundMotion.free_vibration(theta0, 0.5), params=prm)

    def rhs(t, y):
        return [y[1], -P * P * math.sin(ALPHA - y[0]) - c * y[1]]

    def hit(t, y):
        return y[0]

    hit.terminal = True
    sol = solve_ivp(rhs, (0, 1.0), [theta0, 0.0], method="DOP853", rtol=1e-12, atol=1e-15, events=hit)
    assert res.impact_times[0] == pytest.approx(sol.t_events[0][0], rel=1e-9)
    # damping slows the fall: later than the undamped quarter period
    assert res.impact_times[0] > quarter_period(theta0)


# ----------------------------------------------------------------------
# batch entry points and arguments
def test_batch_entry_points_agree_with_simulate():
    dt = 0.002
    motions = [GroundMotion(noise_record(s, 1500, dt, 0.25 + 0.05 * s), dt) for s in range(6)]
    motions.append(GroundMotion(noise_record(9, 900, 0.004, 0.4), 0.004))
    singles = [simulate(SPEC, m) for m in motions]
    for parallel in (False, True):
        many = simulate_many(SPEC, motions, parallel=parallel)
        for a, b in zip(singles, many, strict=True):
            assert np.array_equal(a.theta, b.theta) and np.array_equal(a.impact_times, b.impact_times)
        ratio, over, n_imp = theta_max_many(SPEC, [m.acc for m in motions], [m.dt for m in motions], parallel=parallel)
        assert np.array_equal(ratio, [s.theta_max_over_alpha for s in singles])
        assert np.array_equal(over, [s.overturned for s in singles])
        assert np.array_equal(n_imp, [s.n_impacts for s in singles])
    assert any(s.overturned for s in singles) and any(not s.overturned and s.rocked for s in singles)
    ratio2d, _, _ = theta_max_many(SPEC, np.array([m.acc for m in motions[:6]]), dt)
    assert np.array_equal(ratio2d, ratio[:6])


def test_duration_pads_with_free_rocking():
    m = sine_pulse(0.3, 4.0, duration=1.0)
    res = simulate(SPEC, m, duration=3.0)
    assert res.t.size == 1501 and res.t[-1] == pytest.approx(3.0)
    assert res.n_impacts > simulate(SPEC, m).n_impacts


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"r": 1.5}, "`r`"),
        ({"r": -0.1}, "`r`"),
        ({"theta0": 1.6}, "`theta0`"),
        ({"theta0": math.nan}, "`theta0`"),
        ({"theta_dot0": math.inf}, "`theta_dot0`"),
        ({"substeps": 0}, "`substeps`"),
        ({"substeps": 2.5}, "`substeps`"),
        ({"rest_tol": 0.0}, "`rest_tol`"),
        ({"duration": -1.0}, "`duration`"),
    ],
)
def test_arguments_are_validated(kwargs, match):
    with pytest.raises(ValueError, match=match):
        simulate(SPEC, GroundMotion.free_vibration(0.1, 1.0), **kwargs)


def test_params_are_validated():
    with pytest.raises(ValueError, match="`alpha_neg`"):
        RockingParams(0.1, 1.7, 1.0, 1.0, 0.9)
    with pytest.raises(ValueError, match="`p_pos`"):
        RockingParams(0.1, 0.1, 0.0, 1.0, 0.9)
    with pytest.raises(ValueError, match="`damping`"):
        RockingParams(0.1, 0.1, 1.0, 1.0, 0.9, damping=-1.0)
    with pytest.raises(ValueError, match="`r_pos`"):
        RockingParams(0.1, 0.1, 1.0, 1.0, 0.9, r_pos=1.2)
    with pytest.raises(ValueError, match="`r_neg`"):
        RockingParams(0.1, 0.1, 1.0, 1.0, 0.9, r_neg=math.nan)
    with pytest.raises(ValueError, match="`r`"):
        RockingParams(0.1, 0.1, 1.0, 1.0, 0.9).with_r(-0.5)
    with pytest.raises(TypeError, match="`params`"):
        simulate(SPEC, GroundMotion.free_vibration(0.1, 1.0), params={"r": 0.9})
    with pytest.raises(ValueError, match="`dt`"):
        theta_max_many(SPEC, np.zeros((2, 10)), -0.01)
