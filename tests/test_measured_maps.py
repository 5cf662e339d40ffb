"""The effect ``measured_maps``: an engine's measured impact and flight tables in Housner's kernel.

Checked against the library's own effects where the tables are constant (``restitution`` for the impact
table, ``rotational_damping`` for the flight table), against an interpolation written here in numpy for a
table that depends on the impact speed (each impact of a free vibration, its ratio read off the energy
integral of the half-cycles), for the sign of the flight loss on both sides, for the errors of bad tables,
and for the keys that tell two tables apart (the results cache, the kernel's term structure).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from housner import G, GroundMotion, Specimen
from housner.effects import available_effects, make_effect, simulate_with_effects
from housner.effects.measured import MeasuredMaps, table_q
from housner.engines.analytic import HousnerEngine
from housner.scenarios.execution.cache import cache_keys
from housner.scenarios.execution.rundir import effect_data

SPEC = Specimen.bachmann2017()
ALPHA, P, R_H = SPEC.alpha, SPEC.frequency_parameter, SPEC.r_housner
ENGINE = HousnerEngine()
FINE = 1e-4  # [s]: RK4 at p h = 5e-4 keeps the flight energy to ~1e-13 relative


def ground_motion(seed: int = 3) -> GroundMotion:
    """4 s of seeded band-limited noise at 200 Hz, peak 1.5 g tan(alpha): the block rocks to 0.66 alpha, 34 impacts,
    and stays up (checked where used)."""
    rng = np.random.default_rng(seed)
    a = np.convolve(rng.standard_normal(800), np.ones(15) / 15, mode="same")
    return GroundMotion(a / np.max(np.abs(a)) * 1.5 * G * math.tan(ALPHA), 0.005, name=f"noise-{seed}")


def half_cycle_energy(res) -> tuple[np.ndarray, list, list]:
    """Per half-cycle (release to impact, impact to impact): its mean energy per unit I0 [1/s^2], the samples'
    energies and the side (+1, -1) it rocked on. E = theta'^2/2 + p^2 (cos(alpha - |theta|) - cos alpha)."""
    k_after = np.searchsorted(res.t, res.impact_times)
    bounds = np.concatenate([[0], k_after])
    means, segs, sides = [], [], []
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        th, thd = res.theta[a:b], res.theta_dot[a:b]
        e = 0.5 * thd**2 + P * P * (np.cos(ALPHA - np.abs(th)) - math.cos(ALPHA))
        means.append(e.mean())
        segs.append(e)
        sides.append(1 if res.theta[a + 1] > 0 else -1)
    return np.array(means), segs, sides


def interp_log_numpy(x, xs, ys):
    """The table at x, linear in log x, held at the end values (written apart from the kernel's law)."""
    return np.interp(np.log(x), np.log(xs), ys)


# ----------------------------------------------------------------------------
# constant tables: the library's effects
@pytest.mark.parametrize("xs", [[1.0], [0.05, 0.3, 1.0, 3.0]])
@pytest.mark.parametrize("motion", ["free", "ground"])
def test_constant_impact_table_is_restitution(xs, motion):
    """A constant impact table k is ``restitution`` with r = k r_H: the same theta history to 1e-10 rad.

    (The two routes compute r k r_H and with_r(k r_H): equal to rounding, so the histories agree to far
    below 1e-10; a table of several equal points takes the interpolation's path and gives k exactly.)"""
    k = 0.97
    mo = GroundMotion.free_vibration(0.6 * ALPHA, 3.0, dt=0.001) if motion == "free" else ground_motion()
    maps = MeasuredMaps.from_tables(xs, [k] * len(xs))
    a = ENGINE.simulate(SPEC, mo, [maps])
    b = ENGINE.simulate(SPEC, mo, [make_effect("restitution", r=k * R_H)])
    assert a.impact_times.size >= 3 and not a.overturned and a.theta_max > 0.3 * ALPHA  # it rocks, with impacts
    np.testing.assert_allclose(a.theta, b.theta, rtol=0, atol=1e-10)
    np.testing.assert_allclose(a.impact_times, b.impact_times, rtol=0, atol=1e-10)


@pytest.mark.parametrize("motion", ["free", "ground"])
def test_constant_flight_table_is_rotational_damping(motion):
    """A constant flight table c is ``rotational_damping`` c (its moment -c I0 theta', i.e. phi'' += -c w).

    Against both its routes (the parameter vector's damping and its own moment term): the same sum in
    another order, so equal to 1e-12 rad (measured: bit for bit or a few ulps)."""
    c = 0.8
    mo = GroundMotion.free_vibration(0.6 * ALPHA, 3.0, dt=0.001) if motion == "free" else ground_motion()
    maps = MeasuredMaps.from_tables([1.0], [1.0], flight_x=[0.1, 1.0], flight_c=[c, c])
    a = ENGINE.simulate(SPEC, mo, [maps])
    assert a.impact_times.size >= 2 and not a.overturned and a.theta_max > 0.2 * ALPHA  # damped: 0.29 alpha
    for prefer_terms in (False, True):
        b = simulate_with_effects(SPEC, mo, [make_effect("rotational_damping", c=c)], prefer_terms=prefer_terms)
        np.testing.assert_allclose(a.theta, b.theta, rtol=0, atol=1e-12)
    # and it is a loss: a smaller second peak than without it
    assert np.max(np.abs(a.theta)) <= np.max(np.abs(ENGINE.simulate(SPEC, mo).theta)) + 1e-15


# ----------------------------------------------------------------------------
# a table that depends on the speed
def test_each_impact_has_the_tables_ratio_at_its_speed():
    """Every impact of a free vibration has the energy ratio r_H k(x) at its own pre-impact speed x, to 1e-9.

    Each half-cycle's energy E (per unit I0) is constant in flight (measured 2e-12 relative, checked to 1e-10,
    while x > 0.05; RK4 at p h = 5e-4; below, cos(alpha - |theta|) - cos(alpha) loses digits to cancellation);
    the impact speed is sqrt(2 E) and the impact's ratio E_after / E_before (15 impacts, measured within 2e-13
    of the table, asserted 1e-9: the drift of E above, with margin). The
    table's value at x is interpolated here in numpy, apart from the kernel's law. The impacts fall in every
    interval of the table, below its first point and above its last (the clamps)."""
    xs, ks = [0.3, 0.5, 0.7, 0.9], [0.6, 0.75, 0.85, 0.9]
    res = ENGINE.simulate(SPEC, GroundMotion.free_vibration(0.8 * ALPHA, 4.0, dt=FINE), [MeasuredMaps(xs, ks)])
    e, segs, sides = half_cycle_energy(res)
    keep = int(np.sum(np.sqrt(2.0 * e) / (P * ALPHA) > 0.05))  # the half-cycles above x = 0.05
    e, segs, sides = e[:keep], segs[:keep], sides[:keep]
    for seg in segs:
        assert np.max(np.abs(seg - seg[0])) <= 1e-10 * seg[0]
    x = np.sqrt(2.0 * e[:-1]) / (P * ALPHA)  # speed before each impact [-]
    measured = e[1:] / e[:-1]
    expected = np.clip(R_H * interp_log_numpy(x, xs, ks), 0.0, 1.0)
    assert x.size >= 10
    for lo, hi in zip([0.0, *xs], [*xs, math.inf], strict=True):
        assert np.any((x > lo) & (x < hi))  # every interval met, and both clamps (below x_1, above x_n)
    np.testing.assert_allclose(measured, expected, rtol=1e-9)
    # the table matters: the ratios run from 0.6 to 0.9 of r_H (a constant table would give one value)
    assert np.ptp(measured / R_H) > 0.2
    assert sides == [1 if i % 2 == 0 else -1 for i in range(len(sides))]


def test_flight_loss_removes_energy_on_both_sides():
    """With c > 0 (a table that depends on x_E) the energy falls at every sample of every flight, on either side;
    with the flight table alone (impact ratio k = 1/r_H, lossless impacts) all the loss is in flight."""
    maps = MeasuredMaps.from_tables([1.0], [1.0 / R_H], flight_x=[0.1, 0.5, 1.0], flight_c=[0.6, 0.3, 0.1])
    res = ENGINE.simulate(SPEC, GroundMotion.free_vibration(-0.7 * ALPHA, 4.0, dt=0.001), [maps])
    e, segs, sides = half_cycle_energy(res)
    assert {1, -1} <= set(sides) and len(segs) >= 6
    for seg in segs:
        if seg.size > 3:
            assert np.all(np.diff(seg) < 0.0)
    # the impacts lose nothing: each half-cycle starts with the energy the last one ended with (to 2.5e-3 of E:
    # a sample on either side of the impact, dE/E = 2 c dt <= 1.2e-3 at c <= 0.6 1/s, dt = 1 ms)
    for s0, s1 in zip(segs[:-1], segs[1:], strict=True):
        assert s1[0] == pytest.approx(s0[-1], rel=2.5e-3)
    assert np.all(np.diff(e) < 0.0)
    # the loss rate is -c(x_E) theta'^2 with x_E = sqrt(2 E) / (p alpha): central differences of E at 1 ms
    # (error ~ dt^2/6 times the third derivative of E, measured 2e-5 of the largest rate; asserted 1e-4),
    # away from the impacts
    th, w = res.theta, res.theta_dot
    en = 0.5 * w**2 + P * P * (np.cos(ALPHA - np.abs(th)) - math.cos(ALPHA))
    rate = (en[2:] - en[:-2]) / (2.0 * 0.001)
    want = -interp_log_numpy(np.sqrt(2.0 * en[1:-1]) / (P * ALPHA), [0.1, 0.5, 1.0], [0.6, 0.3, 0.1]) * w[1:-1] ** 2
    away = np.ones(rate.size, bool)
    for k in np.searchsorted(res.t, res.impact_times):
        away[max(0, k - 3) : k + 2] = False
    np.testing.assert_allclose(rate[away], want[away], rtol=0, atol=1e-4 * np.max(np.abs(want)))
    # the sign is the loss's: the same table with c < 0 gains energy in flight
    gain = MeasuredMaps.from_tables([1.0], [1.0], flight_x=[1.0], flight_c=[-0.05])
    _e, segs_g, _s = half_cycle_energy(ENGINE.simulate(SPEC, GroundMotion.free_vibration(0.3 * ALPHA, 1.5), [gain]))
    assert all(np.all(np.diff(s) > 0.0) for s in segs_g if s.size > 3)


# ----------------------------------------------------------------------------
# bad tables, and what tells two tables apart
@pytest.mark.parametrize(
    ("kwargs", "named"),
    [
        ({"impact_x": [], "impact_ratio": []}, "impact_x"),
        ({"impact_x": [0.1, 1.0], "impact_ratio": [1.0]}, "impact_ratio"),
        ({"impact_x": [0.5, 0.2], "impact_ratio": [1.0, 1.0]}, "impact_x"),
        ({"impact_x": [0.0, 1.0], "impact_ratio": [1.0, 1.0]}, "impact_x"),
        ({"impact_x": [0.1, 1.0], "impact_ratio": [1.0, -0.1]}, "impact_ratio"),
        ({"impact_x": [0.1, 1.0], "impact_ratio": [1.0, math.nan]}, "impact_ratio"),
        ({"impact_x": [[0.1, 1.0]], "impact_ratio": [[1.0, 1.0]]}, "impact_x"),
        ({"impact_x": ["a"], "impact_ratio": [1.0]}, "impact_x"),
        ({"impact_x": [1.0], "impact_ratio": [1.0], "flight_x": [1.0, 0.5], "flight_c": [0.1, 0.1]}, "flight_x"),
        ({"impact_x": [1.0], "impact_ratio": [1.0], "flight_x": [1.0], "flight_c": [math.inf]}, "flight_c"),
        ({"impact_x": [1.0], "impact_ratio": [1.0], "flight_x": [1.0], "flight_c": []}, "flight_c"),
    ],
)
def test_bad_tables_are_refused_by_name(kwargs, named):
    with pytest.raises(ValueError, match=f"`{named}`") as err:
        MeasuredMaps.from_tables(**kwargs)
    assert "\n" not in str(err.value)


def test_by_name_it_is_built_from_tables_only():
    """The registry knows it (the analytic engine realises it) but no search takes it; a digest given by hand is
    refused, naming it."""
    assert "measured_maps" in ENGINE.effects_supported and "measured_maps" not in available_effects()
    assert make_effect("measured_maps").terms(None, SPEC) == ()  # the neutral effect adds nothing
    with pytest.raises(ValueError, match="`digest`.*from_tables"):
        make_effect("measured_maps", digest=5.0)


def test_two_tables_have_two_keys_and_two_results():
    """Different tables: different cache keys, descriptions and histories; the same table: the same key; tables
    of different lengths (up to the padded capacity) share one compiled kernel structure."""
    a = MeasuredMaps.from_tables([0.2, 1.0], [0.95, 1.0], [0.5], [0.2])
    b = MeasuredMaps.from_tables([0.2, 1.0], [0.95, 1.01], [0.5], [0.2])
    a2 = MeasuredMaps.from_tables(np.array([0.2, 1.0]), (0.95, 1.0), [0.5], [0.2])
    mo = [GroundMotion.free_vibration(0.5 * ALPHA, 2.0)]
    keys = [cache_keys(SPEC, mo, "housner", {}, "v", (m,))[0] for m in (a, b, a2)]
    assert keys[0] != keys[1] and keys[0] == keys[2]
    assert effect_data(a) != effect_data(b) and a != b and a == a2 and hash(a) == hash(a2)
    assert a.describe()["impact_ratio"] == [0.95, 1.0] and a.describe() != b.describe()
    ta, tb = (ENGINE.simulate(SPEC, mo[0], [m]).theta for m in (a, b))
    assert np.max(np.abs(ta - tb)) > 1e-4  # a 1 % larger ratio above x = 0.2: a visibly different decay
    from housner.effects import apply_effects

    five = MeasuredMaps.from_tables([0.1, 0.2, 0.4, 0.8, 1.6], [1.0] * 5, [0.5], [0.2])
    sa, s5 = (apply_effects(SPEC, mo[0], [m]).terms.structure for m in (a, five))
    assert sa == s5 and len(table_q(range(1, 10), range(9))) == 1 + 2 * 16


def test_from_engine_maps_leaves_out_empty_bins():
    """From the measurement's tables (an object with ``impact_table()`` and ``flight_table()``, as EngineMaps):
    bins without data (NaN) are left out; the rest are the tables."""

    class Tables:
        def impact_table(self):
            return np.array([0.1, 0.2, 0.4]), np.array([1.0, math.nan, 0.98])

        def flight_table(self):
            return np.array([0.2, math.nan]), np.array([0.3, 0.1])

    maps = MeasuredMaps.from_engine_maps(Tables())
    assert maps == MeasuredMaps.from_tables([0.1, 0.4], [1.0, 0.98], [0.2], [0.3])
    with pytest.raises(ValueError, match="`maps`"):
        MeasuredMaps.from_engine_maps(object())


# ----------------------------------------------------------------------------
# the scatter: one realisation of an engine whose impacts scatter about its mean law
def test_scattered_impacts_are_standard_normal_about_the_table_and_repeatable():
    """With impact_spread sigma, each impact's ratio over r_H is k + sigma z; z, recovered from the energies of the
    half-cycles (exact to 1e-9, the test above), has mean 0 and standard deviation 1 within their sampling errors.

    A free vibration from 0.95 alpha with k = 1 and sigma = 0.004 keeps ~70 impacts above x = 0.05: the mean of
    n standard normals is within 3.5/sqrt(n) of 0 and their standard deviation within 1 +- 3.5/sqrt(2 n) (3.5
    sigmas: a seeded test must not fail by chance, and a wrong scale or a biased draw, e.g. u in [0, 1) fed to
    the log, shifts either by far more). The same seed gives the same history; another seed another one."""
    sigma = 0.004
    maps = [MeasuredMaps([0.05, 1.0], [1.0, 1.0], impact_spread=[sigma, sigma], seed=s) for s in (7, 7, 8)]
    motion = GroundMotion.free_vibration(0.95 * ALPHA, 40.0, dt=FINE)
    runs = [ENGINE.simulate(SPEC, motion, [m]) for m in maps]
    assert np.array_equal(runs[0].theta, runs[1].theta) and not np.array_equal(runs[0].theta, runs[2].theta)
    z = []
    for res in (runs[0], runs[2]):
        e, _segs, _sides = half_cycle_energy(res)
        keep = int(np.sum(np.sqrt(2.0 * e) / (P * ALPHA) > 0.05))
        z.append((e[1:keep] / e[: keep - 1] / R_H - 1.0) / sigma)
    z = np.concatenate(z)
    n = z.size
    assert n >= 100
    assert abs(z.mean()) < 3.5 / math.sqrt(n)
    assert abs(z.std() - 1.0) < 3.5 / math.sqrt(2 * n)


def test_scatter_is_part_of_the_key_and_refused_when_malformed():
    a = MeasuredMaps([0.1, 1.0], [1.0, 1.0])
    b = MeasuredMaps([0.1, 1.0], [1.0, 1.0], impact_spread=[0.01, 0.01], seed=1)
    c = MeasuredMaps([0.1, 1.0], [1.0, 1.0], impact_spread=[0.01, 0.01], seed=2)
    assert len({a.digest, b.digest, c.digest}) == 3 and b.describe()["seed"] == 1
    assert MeasuredMaps([0.1, 1.0], [1.0, 1.0], seed=5) == a  # no spread: the seed is not read
    for kwargs, named in (
        ({"impact_spread": [0.01]}, "impact_spread"),
        ({"impact_spread": [-0.01, 0.0]}, "impact_spread"),
        ({"impact_spread": [0.01, 0.01], "seed": -1}, "seed"),
        ({"impact_spread": [0.01, 0.01], "seed": 1.5}, "seed"),
    ):
        with pytest.raises(ValueError, match=f"`{named}`"):
            MeasuredMaps([0.1, 1.0], [1.0, 1.0], **kwargs)
