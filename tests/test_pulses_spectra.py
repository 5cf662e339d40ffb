"""Pulse ground motions (housner.pulse_response.pulses) and rocking spectra (housner.pulse_response.spectra)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from housner import G, GroundMotion, Specimen
from housner.model import simulate
from housner.pulse_response import pulses
from housner.pulse_response.pulses import ricker_half_width, ricker_shape
from housner.pulse_response.spectra import (
    PULSES,
    free_rocking_peak,
    pulse_motion,
    rocking_spectrum,
)

SPEC = Specimen.bachmann2017()


def _integrate(acc: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Velocity and displacement of a motion linear between samples (exact for velocity)."""
    v = np.concatenate(([0.0], np.cumsum(0.5 * (acc[1:] + acc[:-1]) * dt)))
    # displacement of a piecewise-linear acceleration: exact by Simpson-free closed form per interval
    d = np.concatenate(([0.0], np.cumsum(v[:-1] * dt + (acc[:-1] / 3.0 + acc[1:] / 6.0) * dt * dt)))
    return v, d


# ---------------------------------------------------------------------------
# pulses
def test_ricker_shapes_closed_forms():
    x = np.linspace(-30, 30, 60001)
    s = ricker_shape(x, "symmetric")
    assert s.max() == pytest.approx(1.0, abs=1e-12) and s[x.size // 2] == 1.0
    np.testing.assert_allclose(s, s[::-1], rtol=0, atol=1e-14)  # even (the grid itself is symmetric to ~1e-15)
    a = ricker_shape(x, "antisymmetric")
    np.testing.assert_allclose(a, -a[::-1], rtol=0, atol=1e-14)  # odd
    # main lobes at u^2 = 3 - sqrt(6), x = sqrt(3) u = 1.2851, of height exactly -/+1 (beta normalisation)
    xm = math.sqrt(3 * (3 - math.sqrt(6)))
    assert ricker_shape(xm, "antisymmetric") == pytest.approx(-1.0, abs=1e-14)
    assert np.abs(a).max() == pytest.approx(1.0, abs=1e-6)  # grid step 1e-3 misses the peak by < 1e-6
    # Fourier amplitude of both peaks at omega_p (x is omega_p t, so at frequency 1)
    xf = x[::10]  # dx = 0.01 resolves wavelets of unit frequency to spectral accuracy
    freqs = np.linspace(0.5, 1.5, 201)
    for kind in ("symmetric", "antisymmetric"):
        y = ricker_shape(xf, kind)
        amp = np.abs(np.exp(-1j * np.outer(freqs, xf)) @ y)
        assert freqs[int(np.argmax(amp))] == pytest.approx(1.0, abs=0.005)
    # the cut-off: beyond the half-width |psi| < 1e-6
    for kind in ("symmetric", "antisymmetric"):
        xw = ricker_half_width(kind)
        assert abs(ricker_shape(xw, kind)) == pytest.approx(1e-6, rel=1e-6)
        assert np.abs(ricker_shape(np.linspace(xw, 40, 1000), kind)).max() <= 1e-6 * (1 + 1e-9)


def test_ricker_motion_peak_velocity_and_displacement():
    a_p, w, dt = 2.0, 12.0, 1e-4
    g = pulses.ricker(a_p, w, kind="symmetric", dt=dt, p=SPEC.p)
    assert isinstance(g, GroundMotion) and g.dt == dt
    assert abs(g.acc[0]) <= 1e-6 * a_p  # starts from ~zero
    # peak a_p at t0; the grid misses t0 by < dt/2: 1 - psi ~ (3/4)(w dt/2)^2 = 2.7e-7
    assert g.pga == pytest.approx(a_p, rel=3e-7)
    v, d = _integrate(g.acc, dt)
    # the symmetric Ricker is -(2 a_p / w^2) g''(t) with the Gaussian g = exp(-w^2 (t - t0)^2 / 4): the
    # velocity returns to zero and the displacement -(2 a_p / w^2) g(t) reaches -2 a_p / w^2 and returns
    assert abs(v[-1]) < 1e-6 * a_p / w
    # (the window starts where the Gaussian is 3e-8 and its slope w^2 t0/2 g ~ 1e-6 of w: ~1e-6 relative)
    assert d.min() == pytest.approx(-2 * a_p / w**2, rel=1e-5)
    assert abs(d[-1]) < 1e-6 * a_p / w**2 * (g.duration * w)
    # the antisymmetric one (third derivative of a Gaussian) also returns to zero velocity and displacement
    g = pulses.ricker(-a_p, w, kind="antisymmetric", dt=dt)
    assert g.pga == pytest.approx(a_p, rel=1e-6)
    v, d = _integrate(g.acc, dt)
    assert abs(v[-1]) < 1e-6 * a_p / w and abs(d[-1]) < 1e-5 * a_p / w**2 * (g.duration * w)
    # default duration: window plus the free rocking; p sets 30/p, else >= 10 s
    t0 = ricker_half_width("antisymmetric") / w
    assert g.duration == pytest.approx(2 * t0 + max(10 * 2 * math.pi / w, 10.0), abs=dt)
    assert pulses.ricker(1.0, w, dt=0.01, p=2.0).duration == pytest.approx(2 * 8.3263 / w + 15.0, abs=0.01)


def test_one_sine_closed_forms():
    a_p, w = 3.0, 2 * math.pi  # T_p = 1 s
    dt = 1e-3
    g = pulses.one_sine(a_p, w, dt=dt, duration=3.0)
    t = g.t
    np.testing.assert_allclose(g.acc[t <= 1.0], a_p * np.sin(w * t[t <= 1.0]), atol=1e-12)
    assert np.all(g.acc[t > 1.0 + dt / 2] == 0.0)
    assert g.pga == pytest.approx(a_p, rel=1e-6)
    v, d = _integrate(g.acc, dt)
    # v = a_p (1 - cos w t) / w returns to 0 at T_p; d = a_p (t - sin(w t)/w) / w ends at 2 pi a_p / w^2
    # (linear interpolation of the sine: relative error ~ (w dt)^2 / 12 = 3e-6)
    assert abs(v[-1]) < 1e-9
    assert d[-1] == pytest.approx(2 * math.pi * a_p / w**2 + 0.0 * (t[-1] - 1.0), rel=1e-5)
    # phase: the sine starts at sin(phase). With phase = asin(g tan(alpha) / a_p) (the phase at which the block
    # uplifts under Zhang & Makris' pulse, which itself has phase 0) the first sample is the uplift acceleration.
    ph = math.asin(SPEC.uplift_acceleration / a_p)
    assert pulses.one_sine(a_p, w, dt=dt, phase=ph).acc[0] == pytest.approx(SPEC.uplift_acceleration)


def test_free_vibration_and_validation():
    g = pulses.free_vibration(0.1, 2.0)
    assert g.theta0 == 0.1 and g.pga == 0.0 and g.dt == 0.002
    with pytest.raises(ValueError, match="kind"):
        pulses.ricker(1.0, 1.0, kind="mexican", dt=0.01)
    with pytest.raises(ValueError, match="dt"):
        pulses.one_sine(1.0, 1.0, dt=0.0)
    with pytest.raises(ValueError, match="omega_p"):
        pulses.ricker(1.0, -1.0, dt=0.01)
    with pytest.raises(ValueError, match="did you mean 'one_sine'"):
        rocking_spectrum(SPEC, "one-sine", [1.0], [1.0])


# ---------------------------------------------------------------------------
# free rocking after the pulse
@pytest.mark.parametrize(
    "theta, theta_dot",
    [
        (0.02, 0.25),  # moving away: the peak of the current excursion
        (-0.01, -0.4),  # the same on the other pivot
        (0.015, -0.6),  # moving toward zero: the peak after the impact
        (-0.1, 0.05),  # near the top, moving back
    ],
)
def test_free_rocking_peak_against_simulation(theta, theta_dot):
    # The closed form (energy conservation, r at the impact) against the solver run long enough
    # (40/p covers the slowest excursion here); both are exact up to RK4's ~1e-9 alpha.
    r = SPEC.r_housner
    res = simulate(SPEC, GroundMotion.free_vibration(theta, 40 / SPEC.p), theta_dot0=theta_dot, r=r)
    peak, over = free_rocking_peak(theta, theta_dot, SPEC.alpha, SPEC.p, r)
    assert not over and not res.overturned
    assert res.theta_max == pytest.approx(max(float(peak), abs(theta)), abs=1e-8)


def test_free_rocking_peak_overturn_threshold():
    # Energy just above / below the top of the potential (theta = alpha) from theta = 0.
    a, p, r = SPEC.alpha, SPEC.p, SPEC.r_housner
    w_top = p * math.sqrt(2 * (1 - math.cos(a)))
    assert free_rocking_peak(0.0, 1.001 * w_top, a, p, r)[1]
    assert not free_rocking_peak(0.0, 0.999 * w_top, a, p, r)[1]
    # toward zero the impact takes 1 - r of it first
    assert not free_rocking_peak(-1e-9, 1.001 * w_top, a, p, r)[1]
    assert free_rocking_peak(-1e-9, 1.001 * w_top / math.sqrt(r), a, p, r)[1]
    res = simulate(SPEC, GroundMotion.free_vibration(0.0, 30 / p), theta_dot0=1.001 * w_top, r=r)
    assert res.overturned


# ---------------------------------------------------------------------------
# spectra
@pytest.mark.parametrize("pulse", list(PULSES))
def test_no_rocking_below_uplift(pulse):
    # |ug''| <= a_p < g tan(alpha) everywhere: the block never leaves its rest position (Housner 1963).
    s = rocking_spectrum(SPEC, pulse, [0.5, 2.0, 8.0], [0.2, 0.9, 0.999])
    assert np.all(s.theta_max_over_alpha == 0.0) and not s.overturned.any()
    # just above it, it rocks
    s = rocking_spectrum(SPEC, pulse, [2.0], [1.05])
    assert s.theta_max_over_alpha[0, 0] > 0


@pytest.mark.parametrize(
    "pulse, w, a",
    [
        ("symmetric_ricker", 3.0, 1.8),
        ("symmetric_ricker", 8.0, 6.0),
        ("antisymmetric_ricker", 4.0, 2.5),
        ("one_sine", 2.5, 1.2),
        ("one_sine", 7.0, 3.0),
    ],
)
def test_spectrum_point_against_direct_simulation(pulse, w, a):
    # Direct simulation of the same pulse from housner.pulse_response.pulses, padded with 40/p of free rocking,
    # against the spectrum (forcing window + closed-form free rocking). Same samples, same RK4:
    # they differ only by the closed form vs RK4 over the free part (~1e-8 alpha).
    s = rocking_spectrum(SPEC, pulse, [w], [a])
    p = SPEC.p
    dt = pulse_motion(pulse, 1.0, w * p, p).dt
    a_p = a * G * SPEC.tan_alpha
    if pulse == "one_sine":
        g = pulses.one_sine(a_p, w * p, dt=dt, p=p)
    else:
        g = pulses.ricker(a_p, w * p, kind=PULSES[pulse], dt=dt, duration=None, p=p)
    g = g.with_duration(g.duration + 10 / p)  # 40/p of free rocking in all
    res = simulate(SPEC, g)
    assert res.theta_max_over_alpha == pytest.approx(s.theta_max_over_alpha[0, 0], abs=1e-6)
    assert 0 < res.theta_max_over_alpha < 1


def test_symmetric_ricker_mirror_symmetry():
    # a_p -> -a_p mirrors theta -> -theta (the solver is mirror-exact bit for bit) so theta_max = max|theta|
    # is unchanged.
    W = [1.5, 3.0, 6.0]
    A = np.array([1.2, 2.0, 4.0])
    pos = rocking_spectrum(SPEC, "symmetric_ricker", W, A)
    neg = rocking_spectrum(SPEC, "symmetric_ricker", W, -A)
    np.testing.assert_array_equal(pos.theta_max_over_alpha, neg.theta_max_over_alpha)
    np.testing.assert_array_equal(pos.overturned, neg.overturned)


def test_spectrum_depends_only_on_the_ratios():
    # Seed eq. 6: theta/alpha = phi(alpha, omega_p/p, a_p/(g tan alpha)). A geometrically similar block ten
    # times larger (same alpha and r, p / sqrt(10)) has the same spectrum; the time grid scales with 1/p
    # too, so the discrete problems are the same up to rounding.
    W, A = [1.0, 4.0, 9.0], [1.3, 3.0, 7.0]
    small = rocking_spectrum(SPEC, "antisymmetric_ricker", W, A)
    big = rocking_spectrum(SPEC.scaled(10.0), "antisymmetric_ricker", W, A)
    assert big.p == pytest.approx(SPEC.p / math.sqrt(10))
    np.testing.assert_array_equal(small.overturned, big.overturned)
    fin = np.isfinite(small.theta_max_over_alpha)
    np.testing.assert_allclose(big.theta_max_over_alpha[fin], small.theta_max_over_alpha[fin], rtol=1e-9, atol=1e-12)


def test_overturn_acceleration_trends():
    # Seed section 2 (Figure 2): for long pulses (small omega_p/p) the acceleration that overturns the block
    # approaches the uplift acceleration g tan(alpha). Reason: once lifted, a block departs from equilibrium
    # exponentially at rate ~p (negative stiffness) for as long as |ug''| > g tan(alpha), i.e. for
    # (pi - 2 asin(1/a)) / omega_p under a one-sine pulse of a = a_p/(g tan alpha); at omega_p/p = 0.05 and
    # a = 1.02 that is 7.9/p, e^7.9 ~ 2700-fold growth, ample to pass alpha. For short pulses the pulse
    # reverses before the block has moved far, so overturning needs a much larger a (about 3.7 at
    # omega_p/p = 6 for this alpha).
    A = np.array([1.0, 1.02, 1.05, 1.1, 1.2, 1.5, 2.0, 3.0, 4.0])
    s = rocking_spectrum(SPEC, "one_sine", [0.05, 6.0], A)
    a_ov = s.min_overturn_accel()
    assert a_ov[0] <= 1.02
    assert not s.overturned[0, 0]  # a = 1.0: no uplift, no overturn
    assert a_ov[1] >= 3.0
    # and the minimum overturning acceleration of the symmetric Ricker grows with omega_p / p
    W = np.array([1.0, 2.0, 4.0, 6.0])
    A = np.linspace(1.0, 8.0, 36)
    a_ov = rocking_spectrum(SPEC, "symmetric_ricker", W, A).min_overturn_accel()
    assert np.all(np.diff(a_ov) > 0), a_ov


def test_response_grows_with_amplitude_below_overturn():
    # For a fixed symmetric Ricker pulse shape, a larger a_p (just above uplift, before any overturning)
    # lifts the block earlier and harder, so theta_max/alpha grows: monotone up to the first overturn.
    A = np.linspace(1.05, 3.0, 14)
    s = rocking_spectrum(SPEC, "symmetric_ricker", [3.0, 8.0], A)
    for j in range(2):
        col = s.theta_max_over_alpha[:, j]
        k = np.flatnonzero(~np.isfinite(col))
        col = col[: k[0]] if k.size else col
        assert col.size >= 3 and np.all(np.diff(col) > 0)


def test_plot(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    s = rocking_spectrum(SPEC, "symmetric_ricker", np.linspace(1, 8, 6), np.linspace(0.5, 6, 6))
    ax = s.plot()
    assert ax.get_xlabel() == r"$\omega_p / p$"
    ax.figure.savefig(tmp_path / "spectrum.png")
    assert (tmp_path / "spectrum.png").stat().st_size > 1000
    import matplotlib.pyplot as plt

    plt.close(ax.figure)


# ----------------------------------------------------------------------------
# Mavroeidis-Papageorgiou near-fault pulses (issue 51, item 7)
def test_the_mp_pulse_is_the_derivative_of_its_velocity_pulse():
    """The acceleration integrates back to Mavroeidis & Papageorgiou's velocity pulse (eq. 4) scaled to peak a_p;
    the ground is at rest after it (the envelope closes: v = 0 at both ends). Trapezoid on 1e5 samples per pulse
    width: error O(dt^2), below 1e-7 of the peak velocity."""
    import math

    from housner.pulse_response.pulses import mavroeidis_papageorgiou, mp_velocity

    a_p, omega_p, gamma, nu = 3.0, 2 * math.pi * 1.5, 2.3, 0.7
    width = gamma / 1.5
    dt = width / 100_000
    g = mavroeidis_papageorgiou(a_p, omega_p, dt=dt, gamma=gamma, nu=nu, duration=1.2 * width)
    t = np.arange(g.acc.size) * dt
    v = np.concatenate([[0.0], np.cumsum(0.5 * (g.acc[1:] + g.acc[:-1]) * dt)])
    unit = mp_velocity(t, 1.5, gamma, nu, width / 2)
    scale = v[np.argmax(np.abs(unit))] / unit[np.argmax(np.abs(unit))]
    assert np.max(np.abs(v - scale * unit)) < 1e-7 * np.max(np.abs(v))
    assert abs(v[-1]) < 1e-7 * np.max(np.abs(v))  # at rest after the pulse
    # the peak acceleration is a_p (the grid's peak within its sampling: 1e-9 relative)
    assert np.max(np.abs(g.acc)) == pytest.approx(a_p, rel=1e-6)
    with pytest.raises(ValueError, match="gamma"):
        mavroeidis_papageorgiou(a_p, omega_p, dt=0.002, gamma=1.0)


def test_the_near_fault_scenario_builds_its_grid_of_pulses(tmp_path):
    """The catalogue's near-fault scenario: one pulse per grid point, each peaking at its a_p/(g tan alpha);
    the shape keys are refused on another pulse."""
    from housner.scenarios.catalogue import ScenarioError
    from housner.scenarios.catalogue.scenario import load_scenario
    from housner.scenarios.motions.build import build_motions

    sc = load_scenario("near-fault-pulses")
    motions, meta = build_motions(sc)
    assert len(motions) == 64 and meta["pulse"] == "mavroeidis_papageorgiou" and meta["gamma"] == 2.0
    a_up = sc.specimen.uplift_acceleration
    peaks = np.array([np.max(np.abs(m.acc)) for m in motions]) / a_up
    # sampled at dt, a peak is missed by at most a_p (omega_p dt)^2 / 2 (a cosine's top; 3e-3 at the grid's fastest
    # pulse, omega_p = 8 p) and never exceeded
    target = np.array(meta["accel_ratio"])
    miss = 0.5 * (np.array(meta["omega_ratio"]) * sc.specimen.p * 0.002) ** 2
    assert np.all(peaks <= target * (1 + 1e-12)) and np.all(peaks >= target * (1 - miss))
    text = sc.path.read_text().replace('pulse = "mavroeidis_papageorgiou"', 'pulse = "one_sine"')
    bad = tmp_path / "x.toml"
    bad.write_text(text)
    with pytest.raises(ScenarioError, match="gamma"):
        load_scenario(bad)
