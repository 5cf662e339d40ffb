"""Physical effects of the analytic engine: each against a closed form or an independent computation."""

from __future__ import annotations

import dataclasses
import math
import sys
import textwrap
from dataclasses import dataclass

import numpy as np
import pytest
from scipy.optimize import brentq

from housner import GroundMotion, Specimen
from housner.effects import (
    EFFECTS,
    Effect,
    FlexibleFoundation,
    FrequencyParameter,
    ParamSpec,
    apply_effects,
    asymmetric_impact_ratios,
    available_effects,
    discover_effects,
    make_effect,
    make_effects,
    param,
    register_effect,
    simulate_flexible,
    simulate_with_effects,
)
from housner.engines.analytic import HousnerEngine
from housner.model import simulate
from housner.rocking_params import RockingParams
from housner.units import G

SPEC = Specimen.bachmann2017()
ALPHA, P, R_H = SPEC.alpha, SPEC.frequency_parameter, SPEC.r_housner
ENGINE = HousnerEngine()
BUILTIN = (
    "restitution",
    "amplitude_dependent_restitution",
    "rotational_damping",
    "asymmetric_pivots",
    "flexible_foundation",
    "sliding",
    "frequency_parameter",
    "sensor_offset",
    "time_lag",
)


def noise_record(seed: int, n: int, dt: float, pga_g: float) -> np.ndarray:
    """Seeded band-limited noise [m/s^2] with peak pga_g * g (a moving average of white noise)."""
    rng = np.random.default_rng(seed)
    a = np.convolve(rng.standard_normal(n), np.ones(15) / 15, mode="same")
    return a / np.max(np.abs(a)) * pga_g * G


def half_cycle_peaks(res) -> np.ndarray:
    """Largest |theta| [rad] of each complete half-cycle (release to impact, impact to impact), from samples."""
    edges = np.concatenate([[-1.0], res.impact_times])
    out = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        sel = (res.t > a) & (res.t < b)
        if sel.sum() > 3:
            out.append(np.max(np.abs(res.theta[sel])))
    return np.array(out)


def eq8_ratios(peaks: np.ndarray, alpha: float = ALPHA) -> np.ndarray:
    """Seed eq. 8: energy ratio of successive half-cycles from their peaks [-]."""
    e = np.cos(alpha - peaks) - math.cos(alpha)
    return e[1:] / e[:-1]


# ----------------------------------------------------------------------
# registry, validation, composition
def test_builtin_registry_and_metadata():
    assert set(BUILTIN) <= set(available_effects())
    for name in BUILTIN:
        cls = EFFECTS[name]
        assert cls.name == name and cls.__doc__ and "References" in cls.__doc__
        assert list(cls.param_specs) == list(cls.__dataclass_fields__)
        for key, spec in cls.param_specs.items():
            assert isinstance(spec, ParamSpec) and spec.unit and spec.doc
            lo, hi = spec.bounds_for(SPEC)
            assert lo < hi
            default = cls.__dataclass_fields__[key].default
            assert spec.default == (None if default is dataclasses.MISSING else default)
    assert EFFECTS["restitution"].param_specs["r"].neutral_for(SPEC) == R_H
    assert EFFECTS["asymmetric_pivots"].param_specs["e"].bounds_for(SPEC) == (-0.5 * SPEC.B, 0.5 * SPEC.B)


def test_unknown_name_lists_choices_and_suggests_closest():
    with pytest.raises(ValueError, match=r"unknown effect 'restitutoin'; did you mean 'restitution'\?") as e:
        make_effect("restitutoin", r=0.9)
    for name in BUILTIN:
        assert name in str(e.value)
    with pytest.raises(ValueError, match=r"did you mean 'mu'"):
        make_effect("sliding", muu=0.3)


@pytest.mark.parametrize(
    ("name", "kwargs", "param"),
    [
        ("restitution", {"r": 1.5}, "r"),
        ("rotational_damping", {"c": -0.1}, "c"),
        ("sliding", {"mu": -1.0}, "mu"),
        ("flexible_foundation", {"frequency": 0.5}, "frequency"),
        ("flexible_foundation", {"frequency": 50.0, "damping_ratio": 3.0}, "damping_ratio"),
        ("time_lag", {"tau": 1.0}, "tau"),
        ("sensor_offset", {"offset": float("nan")}, "offset"),
        ("frequency_parameter", {"factor": "x"}, "factor"),
    ],
)
def test_out_of_bounds_parameter_is_named(name, kwargs, param):
    with pytest.raises(ValueError, match=f"`{param}`"):
        make_effect(name, **kwargs)


def test_specimen_dependent_bounds_and_required_parameters():
    with pytest.raises(ValueError, match="`e`"):
        make_effect("asymmetric_pivots", specimen=SPEC, e=1.0 * SPEC.B)
    effect = make_effect("asymmetric_pivots", e=1.0 * SPEC.B)  # no specimen: checked when applied
    with pytest.raises(ValueError, match="`e`"):
        ENGINE.simulate(SPEC, GroundMotion.free_vibration(0.1, 0.1), [effect])
    with pytest.raises(ValueError, match="needs `r`"):
        make_effect("restitution")


def test_make_effects_from_plain_data():
    effects = make_effects(["sensor_offset", {"name": "restitution", "r": 0.9}, EFFECTS["time_lag"](tau=0.01)])
    assert [e.name for e in effects] == ["sensor_offset", "restitution", "time_lag"]
    assert effects[1].describe() == {"name": "restitution", "r": 0.9}
    with pytest.raises(ValueError, match="'name'"):
        make_effects([{"r": 0.9}])


def test_mechanics_effects_do_not_combine():
    mo = GroundMotion.free_vibration(0.3 * ALPHA, 0.2)
    flex, slide = make_effect("flexible_foundation", frequency=100.0), make_effect("sliding", mu=0.5)
    with pytest.raises(ValueError, match="'flexible_foundation' and 'sliding'.*cannot be combined"):
        apply_effects(SPEC, mo, [flex, slide])
    with pytest.raises(ValueError, match="cannot be combined with 'restitution'"):
        apply_effects(SPEC, mo, [flex, make_effect("restitution", r=0.9)])
    with pytest.raises(ValueError, match="given twice"):
        apply_effects(SPEC, mo, [make_effect("restitution", r=0.9), make_effect("restitution", r=0.8)])
    with pytest.raises(TypeError, match=r"`effects\[0\]`"):
        apply_effects(SPEC, mo, ["restitution"])


def test_composition_order_is_by_stage():
    """Geometry, then p, then dissipation: the built-in parameter effects commute."""
    mo = GroundMotion.free_vibration(0.3 * ALPHA, 0.2)
    fx = [
        make_effect("restitution", r=0.9),
        make_effect("frequency_parameter", factor=1.2),
        make_effect("asymmetric_pivots", e=0.005),
    ]
    a, b = apply_effects(SPEC, mo, fx), apply_effects(SPEC, mo, fx[::-1])
    assert a.params == b.params
    assert [e.name for e in a.effects] == ["asymmetric_pivots", "frequency_parameter", "restitution"]
    assert a.params.r == 0.9  # restitution, applied after the geometry, wins
    plain = apply_effects(SPEC, mo, fx[2:]).params
    assert a.params.p_pos == pytest.approx(1.2 * plain.p_pos, rel=1e-15)


# ----------------------------------------------------------------------
# neutral values: exactly the plain model
@pytest.mark.parametrize("name", BUILTIN)
def test_neutral_effect_reproduces_plain_model_exactly(name):
    mo = GroundMotion(noise_record(5, 1500, 0.002, 0.3), 0.002)
    plain = simulate(SPEC, mo)
    assert plain.rocked and plain.n_impacts > 3
    res = ENGINE.simulate(SPEC, mo, [EFFECTS[name].neutral(SPEC)])
    assert np.array_equal(res.theta, plain.theta) and np.array_equal(res.theta_dot, plain.theta_dot)
    assert np.array_equal(res.impact_times, plain.impact_times)
    assert res.theta_max == plain.theta_max and res.uplift_time == plain.uplift_time


def test_all_neutral_together_reproduce_plain_model_exactly():
    mo = GroundMotion(noise_record(6, 1500, 0.002, 0.3), 0.002)
    plain = simulate(SPEC, mo)
    effects = [EFFECTS[n].neutral(SPEC) for n in BUILTIN if n != "sliding"]
    res = ENGINE.simulate(SPEC, mo, effects)
    assert np.array_equal(res.theta, plain.theta) and res.theta_max == plain.theta_max
    assert [e["name"] for e in res.info["effects"]] == sorted([e.name for e in effects], key=lambda n: EFFECTS[n].stage)


# ----------------------------------------------------------------------
# parameter effects
# Peaks are read from samples 0.1 ms apart: the sampling error of a peak is at
# most theta'' dt^2 / 8 ~ p^2 alpha dt^2 / 8 ~ 5e-9 rad, i.e. ~1e-7 relative
# on eq. 8, hence the 1e-6 tolerances.
FINE = 1e-4


def test_restitution_energy_ratio_per_impact_is_r():
    r = 0.8
    res = ENGINE.simulate(
        SPEC, GroundMotion.free_vibration(0.6 * ALPHA, 2.4, dt=FINE), [make_effect("restitution", r=r)]
    )
    ratios = eq8_ratios(half_cycle_peaks(res))
    assert ratios.size >= 4
    np.testing.assert_allclose(ratios[:4], r, rtol=1e-6)


def test_amplitude_dependent_restitution_follows_the_law():
    n_exp, r = 0.4, 0.9
    fx = [make_effect("restitution", r=r), make_effect("amplitude_dependent_restitution", exponent=n_exp)]
    res = ENGINE.simulate(SPEC, GroundMotion.free_vibration(0.8 * ALPHA, 3.0, dt=FINE), fx)
    peaks = half_cycle_peaks(res)
    v = np.sqrt(2 * P**2 * (np.cos(ALPHA - peaks) - math.cos(ALPHA)))  # impact speed from the energy integral
    expected = np.clip(r * (v / (P * ALPHA)) ** n_exp, 0, 1)[:-1]
    ratios = eq8_ratios(peaks)
    assert ratios.size >= 4 and np.ptp(expected[:4]) > 0.01  # the ratio really changes with amplitude
    np.testing.assert_allclose(ratios[:4], expected[:4], rtol=1e-6)


def test_rotational_damping_energy_balance():
    """Between impacts E = theta'^2/2 + p^2 (cos(alpha - |theta|) - cos alpha) obeys dE/dt = -c theta'^2 exactly."""
    c = 0.6
    res = ENGINE.simulate(
        SPEC, GroundMotion.free_vibration(0.6 * ALPHA, 0.8, dt=FINE), [make_effect("rotational_damping", c=c)]
    )
    th, thd, t = res.theta, res.theta_dot, res.t
    e = 0.5 * thd**2 + P**2 * (np.cos(ALPHA - np.abs(th)) - math.cos(ALPHA))
    i0, i1 = 10, int(np.searchsorted(t, res.impact_times[0])) - 10  # inside the first half-cycle
    i1 -= (i1 - i0) % 2  # Simpson needs an even number of intervals
    f = c * thd[i0 : i1 + 1] ** 2
    integral = FINE / 3 * (f[0] + f[-1] + 4 * f[1:-1:2].sum() + 2 * f[2:-1:2].sum())
    loss = e[i0] - e[i1]
    assert loss > 0.05 * e[i0]  # a real decay, not rounding
    # Simpson's error ~ dt^4 f''''/180 over the interval, RK4's ~ (p h)^4: both far below 1e-7
    assert loss == pytest.approx(integral, rel=1e-7)


def test_asymmetric_pivots_uplift_thresholds_differ():
    e = 0.4 * SPEC.B
    fx = [make_effect("asymmetric_pivots", e=e)]
    a_pos = math.atan((SPEC.B - e) / SPEC.H)  # the centre of mass is closer to the +x corner
    a_neg = math.atan((SPEC.B + e) / SPEC.H)

    def push(acc):
        return ENGINE.simulate(SPEC, GroundMotion(np.full(200, acc), 0.002), fx)

    assert push(-1.01 * G * math.tan(a_pos)).theta[-1] > 0  # lifts onto the +x corner
    assert not push(-0.99 * G * math.tan(a_pos)).rocked
    assert not push(1.01 * G * math.tan(a_pos)).rocked  # the same push the other way is below g tan(alpha-)
    assert not push(0.99 * G * math.tan(a_neg)).rocked
    assert push(1.01 * G * math.tan(a_neg)).theta[-1] < 0


def test_asymmetric_pivots_impact_law_and_alternating_peaks():
    e = 0.3 * SPEC.B
    m, hh, ic = SPEC.mass, SPEC.H, SPEC.centroidal_inertia
    rho_pn, rho_np = asymmetric_impact_ratios(SPEC, e)
    assert rho_pn * rho_np == pytest.approx(R_H, rel=2e-3) and rho_pn != rho_np
    assert asymmetric_impact_ratios(SPEC, 0.0)[0] == pytest.approx(math.sqrt(R_H), rel=1e-14)
    prm = apply_effects(SPEC, GroundMotion.free_vibration(0.1, 0.1), [make_effect("asymmetric_pivots", e=e)]).params
    assert prm.r == pytest.approx(rho_pn * rho_np, rel=1e-14)
    # per impact: landing on the -x corner scales theta' by rho_pn, landing on the +x corner by rho_np
    assert prm.r_neg == pytest.approx(rho_pn**2, rel=1e-14) and prm.r_pos == pytest.approx(rho_np**2, rel=1e-14)
    # independent per-side quantities
    side = {}
    for key, b in (("pos", SPEC.B - e), ("neg", SPEC.B + e)):
        rr = math.hypot(b, hh)
        side[key] = (math.atan(b / hh), math.sqrt(m * G * rr / (ic + m * rr * rr)))
    assert (prm.alpha_pos, prm.p_pos) == pytest.approx(side["pos"], rel=1e-14)
    assert (prm.alpha_neg, prm.p_neg) == pytest.approx(side["neg"], rel=1e-14)
    # free vibration: peaks from the energy integral of each side, sqrt(r) on the speed at each impact
    theta0 = 0.7 * side["pos"][0]
    res = ENGINE.simulate(
        SPEC, GroundMotion.free_vibration(theta0, 2.4, dt=FINE), [make_effect("asymmetric_pivots", e=e)]
    )
    expected, peak, s = [theta0], theta0, "pos"
    for _ in range(4):
        a, p = side[s]
        s = "neg" if s == "pos" else "pos"
        rho = rho_pn if s == "neg" else rho_np  # the ratio of the impact that lands on corner s
        v2 = 2 * p * p * (math.cos(a - peak) - math.cos(a)) * rho * rho
        a, p = side[s]
        peak = a - math.acos(math.cos(a) + v2 / (2 * p * p))
        expected.append(peak)
    peaks = half_cycle_peaks(res)[:5]
    np.testing.assert_allclose(peaks, expected, rtol=1e-6)
    # sizes alternate: the -x half-cycles (larger alpha, slower p) lose relatively more of their angle
    ratio = peaks[1:] / peaks[:-1]
    assert ratio[0] < ratio[1] > ratio[2] < ratio[3]


def angular_momentum_ratio(e: float, s_old: int) -> float:
    """theta'_after / theta'_before [-] of the impact that leaves corner s_old (+1: +x), by 2-D vectors.

    Independent of housner.effects: angular momentum about the landing corner, L = I_c W + m (G - O) x v_G,
    with v_G = W z x (G - O_old), is kept through the impact; after it the block turns about O with
    I_O = I_c + m |G - O|^2.
    """
    m, ic = SPEC.mass, SPEC.centroidal_inertia
    com = np.array([e, SPEC.H])
    corner = {1: np.array([SPEC.B, 0.0]), -1: np.array([-SPEC.B, 0.0])}
    d_old, d_new = com - corner[s_old], com - corner[-s_old]
    v_g = np.array([-d_old[1], d_old[0]])  # W = 1 rad/s
    ang = ic + m * (d_new[0] * v_g[1] - d_new[1] * v_g[0])
    return ang / (ic + m * float(d_new @ d_new))


@pytest.mark.parametrize("e_over_b", [0.3, -0.45])
def test_asymmetric_pivots_each_impact_keeps_angular_momentum(e_over_b):
    """Every single impact of a free vibration has the restitution of its own direction, to 1e-9.

    theta'^2 at theta = 0 just before and after each impact comes from the energy integral of each
    half-cycle on its own corner, eps = theta'^2 / 2 + p_s^2 (cos(alpha_s - |theta|) - cos(alpha_s))
    [1/s^2], averaged over the samples of the half-cycle (RK4 at p h <= 0.01 keeps it to ~1e-11
    relative, checked below to 1e-10; measured 5e-14); their ratio is the kernel's squared speed ratio
    at that impact (measured within 3e-14 of the derived ratio, asserted to 1e-9).
    """
    e = e_over_b * SPEC.B
    fx = [make_effect("asymmetric_pivots", e=e)]
    prm = apply_effects(SPEC, GroundMotion.free_vibration(0.1, 0.1), fx).params
    rho = {-1: angular_momentum_ratio(e, 1), 1: angular_momentum_ratio(e, -1)}  # keyed by the landing corner
    assert (prm.r_neg, prm.r_pos) == pytest.approx((rho[-1] ** 2, rho[1] ** 2), rel=1e-13)
    # the two directions really differ, by (I+/I-)^2: more than a per mil here
    assert abs(prm.r_pos / prm.r_neg - 1.0) > 1e-3
    # released on the more slender side: the other, stockier side then rocks well below its alpha
    theta0 = 0.6 * prm.alpha_pos if prm.alpha_pos < prm.alpha_neg else -0.6 * prm.alpha_neg
    res = ENGINE.simulate(SPEC, GroundMotion.free_vibration(theta0, 2.5, dt=FINE), fx)
    k_after = np.searchsorted(res.t, res.impact_times)
    assert k_after.size >= 6 and np.all(np.diff(k_after) > 10)
    eps, sides = [], []
    bounds = np.concatenate([[0], k_after])
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        side = 1 if res.theta[a + 1] > 0 else -1
        al, p = (prm.alpha_pos, prm.p_pos) if side > 0 else (prm.alpha_neg, prm.p_neg)
        th, thd = res.theta[a:b], res.theta_dot[a:b]
        seg = 0.5 * thd**2 + p * p * (np.cos(al - np.abs(th)) - math.cos(al))
        assert np.max(np.abs(seg - seg[0])) <= 1e-10 * seg[0]
        eps.append(seg.mean())
        sides.append(side)
    assert sides[0] == np.sign(theta0) and all(a == -b for a, b in zip(sides[:-1], sides[1:], strict=True))
    measured = np.array(eps[1:]) / np.array(eps[:-1])
    expected = np.array([rho[s] ** 2 for s in sides[1:]])
    np.testing.assert_allclose(measured, expected, rtol=1e-9)
    # the single common r of the old model would be off by (I+/I-) per impact, alternately
    assert np.all(np.abs(measured / prm.r - 1.0) > 5e-4)


def test_asymmetric_pivots_with_restitution_keeps_the_split():
    e = 0.3 * SPEC.B
    base = apply_effects(SPEC, GroundMotion.free_vibration(0.1, 0.1), [make_effect("asymmetric_pivots", e=e)]).params
    fx = [make_effect("restitution", r=0.8), make_effect("asymmetric_pivots", e=e)]  # applied by stage: geometry first
    prm = apply_effects(SPEC, GroundMotion.free_vibration(0.1, 0.1), fx).params
    assert prm.r == 0.8
    assert prm.r_pos / prm.r_neg == pytest.approx(base.r_pos / base.r_neg, rel=1e-14)
    assert math.sqrt(prm.r_pos * prm.r_neg) == pytest.approx(0.8, rel=1e-14)  # r is their geometric mean
    # a ratio already in force before the geometry is scaled as Housner's is: r_in_force rho^2 / r_housner
    pre = RockingParams.from_specimen(SPEC, r=0.8)
    prm2 = apply_effects(SPEC, GroundMotion.free_vibration(0.1, 0.1), fx[1:], params=pre).params
    rho_pn, rho_np = asymmetric_impact_ratios(SPEC, e)
    assert (prm2.r_pos, prm2.r_neg) == pytest.approx((0.8 * rho_np**2 / R_H, 0.8 * rho_pn**2 / R_H), rel=1e-14)


def test_frequency_parameter_scales_half_cycles():
    k = 1.3
    mo = GroundMotion.free_vibration(0.5 * ALPHA, 2.0, dt=FINE)
    plain = simulate(SPEC, mo, r=1.0)
    fx = [make_effect("restitution", r=1.0), make_effect("frequency_parameter", factor=k)]
    res = ENGINE.simulate(SPEC, mo, fx)
    n = min(res.n_impacts, plain.n_impacts)
    assert n >= 3
    # theta'' = -p^2 sin(alpha - theta) has time scale 1/p: durations scale exactly (integrator error ~1e-10)
    np.testing.assert_allclose(res.impact_times[:n] * k, plain.impact_times[:n], rtol=1e-8)
    eff = FrequencyParameter.from_p(SPEC, 5.5)
    assert eff.factor * P == pytest.approx(5.5, rel=1e-15)


# ----------------------------------------------------------------------
# sensor effects
def test_sensor_offset_is_an_exact_shift():
    mo = GroundMotion(noise_record(8, 1500, 0.002, 0.3), 0.002)
    plain = simulate(SPEC, mo)
    off = 0.004
    res = ENGINE.simulate(SPEC, mo, [make_effect("sensor_offset", offset=off)])
    assert np.array_equal(res.theta, plain.theta + off) and np.array_equal(res.theta_dot, plain.theta_dot)
    assert np.array_equal(res.impact_times, plain.impact_times)
    sampled = np.max(np.abs(plain.theta + off))
    # the block's own peak (between samples) on its side, shifted; at least the sampled observation
    assert sampled <= res.theta_max <= plain.theta_max + off + 1e-15
    assert res.info["sensor_offset"] == off


def test_time_lag_is_an_exact_shift():
    dt = 0.002
    mo = GroundMotion(noise_record(9, 1500, dt, 0.3), dt)
    plain = simulate(SPEC, mo)
    k = 7
    res = ENGINE.simulate(SPEC, mo, [make_effect("time_lag", tau=k * dt)])
    assert np.array_equal(res.theta[k:], plain.theta[:-k]) and np.all(res.theta[:k] == plain.theta[0])
    np.testing.assert_allclose(res.impact_times, plain.impact_times + k * dt, rtol=0, atol=1e-15)
    assert res.theta_max == plain.theta_max
    # a fraction of a sample: linear interpolation between the two neighbours
    f = 0.3
    res = ENGINE.simulate(SPEC, mo, [make_effect("time_lag", tau=(k + f) * dt)])
    n = plain.theta.size
    expect = (1 - f) * plain.theta[1 : n - k] + f * plain.theta[: n - k - 1]
    np.testing.assert_allclose(res.theta[k + 1 :], expect, rtol=0, atol=1e-15)
    # negative lag: theta leads
    res = ENGINE.simulate(SPEC, mo, [make_effect("time_lag", tau=-k * dt)])
    assert np.array_equal(res.theta[:-k], plain.theta[k:]) and np.all(res.theta[-k:] == plain.theta[-1])
    # a peak outside the observed window is not observed: released at theta0, leading by 5 samples
    fv = GroundMotion.free_vibration(0.5 * ALPHA, 0.3, dt=dt)
    res = ENGINE.simulate(SPEC, fv, [make_effect("time_lag", tau=-5 * dt)])
    assert res.theta_max == np.max(np.abs(res.theta)) < 0.5 * ALPHA


# ----------------------------------------------------------------------
# flexible foundation
def flex_energy(res) -> np.ndarray:
    """Total energy per unit mass [m^2/s^2] (kinetic + gravity + springs), with no ground motion."""
    prm = res.info["params"]
    hh = SPEC.H
    bp, bn = hh * math.tan(prm["alpha_pos"]), hh * math.tan(prm["alpha_neg"])
    rr = math.hypot(bp, hh)
    ic = G * rr / prm["p_pos"] ** 2 - rr * rr
    kap = res.info["k"] / SPEC.mass
    th, thd, w, wd = res.theta, res.theta_dot, res.info["w"], res.info["w_dot"]
    a = np.where(th > 0, bp, -bn) * np.sin(th) + hh * np.cos(th)  # x_G' / theta'
    zd = wd - hh * np.sin(th) * thd
    dp = np.maximum(bp * np.sin(th) - w, 0.0)
    dn = np.maximum(-w - bn * np.sin(th), 0.0)
    return 0.5 * ((a * thd) ** 2 + zd**2 + ic * thd**2) + G * (w + hh * np.cos(th)) + 0.5 * kap * (dp**2 + dn**2)


def test_flexible_foundation_static_tilt_matches_springs():
    """A constant lateral acceleration below uplift tilts the block on its springs.

    Equilibrium (both corners pushing, F+ + F- = m g, F+ - F- = 2 k B sin theta),
    moments about the pivot: -ug'' (B sin th + H cos th) + g H sin th - (2 k B^2/m) sin th cos th = 0;
    small angles: theta = m a H / (2 k B^2 - m g H).
    """
    f, a = 25.0, 0.6 * G * SPEC.tan_alpha
    kap = 0.5 * (2 * math.pi * f) ** 2  # k/m per corner
    dt, n = 0.002, 3001
    acc = -a * np.clip(np.arange(n) * dt / 1.0, 0.0, 1.0)  # ramp to -a in 1 s, then hold 5 s
    res = ENGINE.simulate(
        SPEC, GroundMotion(acc, dt), [make_effect("flexible_foundation", frequency=f, damping_ratio=1.0)]
    )
    hh, b = SPEC.H, SPEC.B

    def moment(th):
        return (
            a * (b * math.sin(th) + hh * math.cos(th))
            + G * hh * math.sin(th)
            - 2 * kap * b * b * math.sin(th) * math.cos(th)
        )

    exact = brentq(moment, 1e-9, 0.05)
    linear = a * hh / (2 * kap * b * b - G * hh)
    assert exact == pytest.approx(linear, rel=5e-3)  # the small-angle form, good to O(theta)
    # after 5 s the rocking-on-springs mode (~3 Hz, heavily damped) has settled to ~1e-6
    np.testing.assert_allclose(res.theta[-100:], exact, rtol=2e-5)
    assert math.isnan(res.uplift_time) and res.n_impacts == 0
    # the rigid model does not move at all under the same acceleration
    assert not simulate(SPEC, GroundMotion(acc, dt)).rocked


def test_flexible_foundation_lifts_off_below_g_tan_alpha():
    """Uplift when the trailing corner unloads: sin th_u = m g / (2 k B), i.e. below the rigid g tan(alpha)."""
    f = 25.0
    kap = 0.5 * (2 * math.pi * f) ** 2
    hh, b = SPEC.H, SPEC.B
    th_u = math.asin(G / (2 * kap * b))
    a_u = (2 * kap * b * b * math.cos(th_u) - G * hh) * math.sin(th_u) / (b * math.sin(th_u) + hh * math.cos(th_u))
    assert 0.9 < a_u / (G * SPEC.tan_alpha) < 0.95  # 93 % of the rigid threshold for this block
    dt, n = 0.002, 4001
    ramp = np.clip(np.arange(n) * dt / 4.0, 0.0, 1.0)  # quasi-static: 4 s ramp, ~3 Hz mode
    eff = [make_effect("flexible_foundation", frequency=f, damping_ratio=1.0)]
    below = ENGINE.simulate(SPEC, GroundMotion(-0.98 * a_u * ramp, dt), eff)
    above = ENGINE.simulate(SPEC, GroundMotion(-1.02 * a_u * ramp, dt), eff)
    assert math.isnan(below.uplift_time) and not math.isnan(above.uplift_time)


def test_flexible_foundation_energy():
    """Undamped springs conserve the total energy; dashpots only dissipate it."""
    mo = GroundMotion.free_vibration(0.5 * ALPHA, 2.0, dt=0.002)
    res = simulate_flexible(SPEC, mo, frequency=200.0, damping_ratio=0.0)
    e = flex_energy(res)
    kap = res.info["k"] / SPEC.mass
    rest = G * (SPEC.H - G / (2 * kap)) + kap * (G / (2 * kap)) ** 2  # at rest on both springs [m^2/s^2]
    rocking = e[0] - rest
    assert res.n_impacts >= 3 and rocking > 0.01
    # RK4 with 0.05 rad per step of the fastest contact mode: measured ~3e-8 of the rocking energy
    assert np.max(np.abs(e - e[0])) < 1e-6 * rocking
    res = simulate_flexible(SPEC, mo, frequency=200.0, damping_ratio=0.3)
    e = flex_energy(res)
    assert np.all(np.diff(e) <= 1e-12 * rocking) and e[-1] < e[0] - 0.1 * rocking


def test_flexible_foundation_impacts_take_time_and_approach_housner():
    mo = GroundMotion.free_vibration(0.6 * ALPHA, 2.5, dt=0.001)
    rigid = simulate(SPEC, mo)
    durations = {}
    for f in (50.0, 200.0, 1000.0):
        res = ENGINE.simulate(SPEC, mo, [FlexibleFoundation(frequency=f, damping_ratio=0.5)])
        d = res.info["impact_durations"][:3]
        assert np.all(d > 0)
        durations[f] = d.mean()
    # stiffer springs, shorter impacts (0.4 ms at 200 Hz, 0.02 ms at 1000 Hz)
    assert durations[50.0] > durations[200.0] > durations[1000.0] > 0
    # stiff and damped: Housner's energy ratio per impact and half-cycle durations to ~1e-4
    ratios = eq8_ratios(half_cycle_peaks(res))[:4]
    np.testing.assert_allclose(ratios, R_H, rtol=1e-3)
    np.testing.assert_allclose(np.diff(res.impact_times[:4]), np.diff(rigid.impact_times[:4]), rtol=1e-3)
    assert res.info["k"] == pytest.approx(0.5 * SPEC.mass * (2 * math.pi * 1000.0) ** 2)
    ff = FlexibleFoundation.from_stiffness(SPEC, k=res.info["k"], c=res.info["c"])
    assert (ff.frequency, ff.damping_ratio) == pytest.approx((1000.0, 0.5), rel=1e-12)


# ----------------------------------------------------------------------
# sliding
def step(acc: float, duration: float = 1.0, dt: float = 0.002) -> GroundMotion:
    return GroundMotion(np.full(int(round(duration / dt)) + 1, acc), dt)


@pytest.mark.parametrize("a_g", [-0.12, -0.3, 0.3])
def test_sliding_with_low_mu_slides_and_never_rocks(a_g):
    """mu < tan(alpha): friction caps the base force at mu m g < m g tan(alpha), so the block cannot tip.

    It slides once |ug''| > mu g with x'' = |ug''| - mu g away from the ground's push: x = (|a| - mu g) t^2 / 2.
    """
    mu = 0.1
    assert mu < SPEC.tan_alpha
    res = ENGINE.simulate(SPEC, step(a_g * G), [make_effect("sliding", mu=mu)])
    assert np.all(res.theta == 0.0) and not res.rocked
    expect = -np.sign(a_g) * 0.5 * (abs(a_g) - mu) * G * res.t**2
    np.testing.assert_allclose(res.info["slip"], expect, rtol=0, atol=1e-12)  # RK4 is exact on t^2
    assert set(np.unique(res.info["regime"])) == {0, 1} or set(np.unique(res.info["regime"])) == {1}


def test_sliding_with_high_mu_rocks_and_onset_criterion():
    """mu > tan(alpha): a step just beyond g tan(alpha) rocks without slip.

    At the onset (theta = theta' = 0) the friction demand is F/m = ug'' + H theta'' and the normal force
    N/m = g + B theta'', theta'' = -p^2 (sin(alpha) + ug''/g cos(alpha)); the base slips at once iff |F| > mu N.
    """
    mu = 0.2
    res = ENGINE.simulate(SPEC, step(-1.05 * G * SPEC.tan_alpha, 0.3), [make_effect("sliding", mu=mu)])
    plain = simulate(SPEC, step(-1.05 * G * SPEC.tan_alpha, 0.3))
    assert np.all(res.info["slip"] == 0.0) and res.rocked
    np.testing.assert_allclose(res.theta, plain.theta, rtol=0, atol=1e-12 * ALPHA)

    def excess(a):  # |F| - mu N at the onset, for a step ug'' = -a [m/s^2]
        thdd = P * P * (a / G * math.cos(ALPHA) - math.sin(ALPHA))
        return abs(-a + SPEC.H * thdd) - mu * (G + SPEC.B * thdd)

    a_star = brentq(excess, 1.001 * G * SPEC.tan_alpha, 2 * G)
    slow = ENGINE.simulate(SPEC, step(-0.99 * a_star, 0.01), [make_effect("sliding", mu=mu)])
    fast = ENGINE.simulate(SPEC, step(-1.01 * a_star, 0.01), [make_effect("sliding", mu=mu)])
    assert slow.info["regime"][1] == 2 and fast.info["regime"][1] == 3  # rock vs slide-rock
    assert fast.info["slide_time"] == 0.0 and slow.info["slip"][1] == 0.0 < fast.info["slip"][1]


def test_sliding_obeys_coulomb_on_the_centre_of_mass_path():
    """Newton on the centre of mass, from the output alone: F = m (ug'' + x_G''), N = m (g + z_G'').

    The centre of mass of a block on pivot s = sgn(theta) that has slipped x is at
    x_G = x + s B (1 - cos theta) + H sin theta, z_G = s B sin theta + H cos theta (ground frame).
    Slipping (slide-rock): |F| = mu N, F opposing the slip; sticking (rock): |F| <= mu N.
    """
    mu, dt = 0.25, 1e-4
    t = np.arange(15001) * dt
    acc = np.where(t < 0.1, -0.45 * G * np.sin(np.pi * t / 0.1), 0.0)
    res = ENGINE.simulate(SPEC, GroundMotion(acc, dt), [make_effect("sliding", mu=mu)])
    reg = res.info["regime"]
    assert {2, 3} <= set(np.unique(reg)) and res.n_impacts >= 2 and not res.overturned
    th, x = res.theta, res.info["slip"]
    s = np.where(th >= 0, 1.0, -1.0)
    xg = x + s * SPEC.B * (1 - np.cos(th)) + SPEC.H * np.sin(th)
    zg = s * SPEC.B * np.sin(th) + SPEC.H * np.cos(th)

    def d2(y):
        return (y[2:] - 2 * y[1:-1] + y[:-2]) / dt**2

    f, n = acc[1:-1] + d2(xg), G + d2(zg)
    slip_rate = (x[2:] - x[:-2]) / (2 * dt)
    # central differences need three samples in one regime on one pivot, away from impacts
    ok = (reg[2:] == reg[1:-1]) & (reg[:-2] == reg[1:-1]) & (s[2:] == s[1:-1]) & (s[:-2] == s[1:-1])
    for k in np.searchsorted(t, res.impact_times):
        ok[max(k - 3, 0) : k + 2] = False
    slip, stick = ok & (reg[1:-1] == 3), ok & (reg[1:-1] == 2)
    assert slip.sum() > 100 and stick.sum() > 1000
    # finite-difference error ~ dt^2 x''''/12: measured ~1e-6 relative
    np.testing.assert_allclose(np.abs(f[slip]) / n[slip], mu, rtol=1e-5)
    assert np.all(np.sign(f[slip]) == -np.sign(slip_rate[slip]))
    assert np.all(np.abs(f[stick]) <= mu * n[stick] * (1 + 1e-5)) and np.all(slip_rate[stick] == 0)


def test_sliding_with_very_high_mu_is_the_plain_model():
    mo = GroundMotion(noise_record(3, 2000, 0.002, 0.25), 0.002)
    plain = simulate(SPEC, mo)
    res = ENGINE.simulate(SPEC, mo, [make_effect("sliding", mu=2.0)])
    assert plain.n_impacts > 10 and not plain.overturned
    assert np.all(res.info["slip"] == 0.0) and res.n_impacts == plain.n_impacts
    # an independent kernel (other root finder, same RK4 grid): agreement to rounding, amplified
    # over 4 s of chaotic rocking to ~1e-10 alpha
    np.testing.assert_allclose(res.theta, plain.theta, rtol=0, atol=1e-8 * ALPHA)
    assert res.theta_max == pytest.approx(plain.theta_max, rel=1e-8)


# ----------------------------------------------------------------------
# user-defined effects
def test_user_effect_registered_by_decorator_is_accepted_and_acts():
    @register_effect
    @dataclass(frozen=True)
    class TableGain(Effect):
        """Shake-table gain error (test effect)."""

        name = "test_table_gain"
        params = {"gain": ParamSpec("-", (0.5, 2.0), 1.0, 1.0, "gain of the table")}
        gain: float = 1.0

        def transform_input(self, motion):
            return motion.scaled(amplitude=self.gain)

    try:
        assert "test_table_gain" in HousnerEngine.effects_supported
        mo = GroundMotion(noise_record(4, 1000, 0.002, 0.2), 0.002)
        res = ENGINE.simulate(SPEC, mo, [make_effect("test_table_gain", gain=1.5)])
        ref = simulate(SPEC, mo.scaled(amplitude=1.5))
        assert ref.rocked and np.array_equal(res.theta, ref.theta)
        with pytest.raises(ValueError, match="`gain`"):
            make_effect("test_table_gain", gain=5.0)
        with pytest.raises(ValueError, match="already registered"):
            register_effect("restitution")(TableGain)
        assert TableGain.name == "test_table_gain"
    finally:
        EFFECTS.pop("test_table_gain", None)


def test_a_parameter_is_declared_once_on_its_field():
    """param() puts the spec on the field: the table is read off the fields; a second table is refused."""

    @dataclass(frozen=True)
    class Gain(Effect):
        name = "test_param_gain"
        lag: float = param("s", (0.0, 0.1), neutral=0.0, doc="lag")
        gain: float = param("-", (0.5, 2.0), neutral=1.0, default=1.0, doc="gain of the table")

    try:
        register_effect(Gain)
        assert list(Gain.param_specs) == ["lag", "gain"]
        assert Gain.param_specs["gain"] == ParamSpec("-", (0.5, 2.0), 1.0, 1.0, "gain of the table")
        assert Gain.param_specs["lag"].default is None
        with pytest.raises(ValueError, match="needs `lag`"):
            make_effect("test_param_gain", gain=1.5)
        assert make_effect("test_param_gain", lag=0.01).describe() == {
            "name": "test_param_gain",
            "lag": 0.01,
            "gain": 1.0,
        }
        with pytest.raises(ValueError, match="`gain`"):
            Gain(lag=0.0, gain=5.0)
    finally:
        EFFECTS.pop("test_param_gain", None)

    @dataclass(frozen=True)
    class Twice(Effect):
        name = "test_param_twice"
        params = {"gain": ParamSpec("-", (0.5, 2.0), 1.0, 1.0, "gain")}
        gain: float = param("-", (0.5, 2.0), neutral=1.0, default=1.0, doc="gain")

    with pytest.raises(ValueError, match="declared twice"):
        register_effect(Twice)

    @dataclass(frozen=True)
    class Bare(Effect):
        name = "test_param_bare"
        gain: float = 1.0

    with pytest.raises(ValueError, match="declare each field with param"):
        register_effect(Bare)


def test_user_effect_from_an_entry_point(tmp_path, monkeypatch):
    """A package declaring ``[housner.effects]`` in its metadata is found by importlib.metadata."""
    (tmp_path / "hx_plugin_mod.py").write_text(
        textwrap.dedent(
            '''
            from dataclasses import dataclass, replace
            from housner.effects import Effect, ParamSpec

            @dataclass(frozen=True)
            class ExtraLoss(Effect):
                """Halve r (test plugin)."""
                name = "test_plugin_extra_loss"
                params = {"factor": ParamSpec("-", (0.0, 1.0), 1.0, 1.0, "factor on r")}
                factor: float = 1.0

                def modify_params(self, params, specimen):
                    return replace(params, r=params.r * self.factor)
            '''
        )
    )
    dist = tmp_path / "hx_plugin-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: hx-plugin\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text("[housner.effects]\nextra = hx_plugin_mod:ExtraLoss\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        assert "test_plugin_extra_loss" in discover_effects(force=True)
        mo = GroundMotion.free_vibration(0.5 * ALPHA, 1.0)
        res = ENGINE.simulate(SPEC, mo, [make_effect("test_plugin_extra_loss", factor=0.5)])
        ref = simulate(SPEC, mo, r=0.5 * R_H)
        assert np.array_equal(res.theta, ref.theta)
    finally:
        EFFECTS.pop("test_plugin_extra_loss", None)
        sys.modules.pop("hx_plugin_mod", None)


def test_other_engines_refuse_effects_by_name():
    from housner.engines.base import Engine

    class Bare(Engine):
        name = "bare"

    with pytest.raises(ValueError, match="cannot realise effect 'sliding'"):
        Bare().simulate(SPEC, GroundMotion.free_vibration(0.1, 0.1), [make_effect("sliding", mu=0.3)])


def test_simulate_with_effects_matches_the_engine():
    mo = GroundMotion(noise_record(11, 1000, 0.002, 0.3), 0.002)
    fx = [make_effect("rotational_damping", c=0.3), make_effect("time_lag", tau=0.004)]
    a, b = simulate_with_effects(SPEC, mo, fx), ENGINE.simulate(SPEC, mo, fx)
    assert np.array_equal(a.theta, b.theta) and a.info["effects"] == b.info["effects"]
    assert HousnerEngine(r=0.5).simulate(SPEC, mo, fx[:1]).info["params"]["r"] == 0.5
    # the engine's r is the starting point of the effects
    assert RockingParams.from_specimen(SPEC, r=0.5).r == 0.5
