"""housner.free_vibration.impacts: the one detector of impacts in a sampled theta, for measured and simulated
histories."""

from __future__ import annotations

import numpy as np
import pytest

from housner.free_vibration.impacts import HYSTERESIS_SIGMAS, hysteresis_crossings, impact_times, noise_crossings


def test_impact_times_of_a_sine_are_its_zeros():
    # theta = A sin(2 pi f t): zeros at k / (2 f). Linear interpolation between samples 1 ms apart
    # misses a zero of a sine by at most (pi f dt)^2 dt / 6 ~ 2e-9 s here: 1e-8 s.
    f, dt = 1.3, 1e-3
    t = np.arange(0.0, 3.0, dt)
    th = 0.01 * np.sin(2 * np.pi * f * t + 0.1)
    got = impact_times(t, th, tol=1e-3)
    want = (np.arange(1, 8) * np.pi - 0.1) / (2 * np.pi * f)
    np.testing.assert_allclose(got, want[want < t[-1]], atol=1e-8)


def test_chatter_below_the_tolerance_is_not_an_impact_and_zeros_belong_to_no_side():
    t = np.arange(12) * 0.1
    # a swing up, exact zeros, a chatter of 1e-6 across zero, a swing down, back across
    th = np.array([0.0, 0.02, 0.03, 0.0, 0.0, -1e-6, 1e-6, -1e-6, -0.02, -0.01, 0.01, 0.02])
    got = impact_times(t, th, tol=1e-3)
    # 1. +0.03 -> -1e-6 (the zeros skipped: interpolated between samples 2 and 5), counted: the swing before it
    #    exceeded the tolerance; 2. the chatter -1e-6 -> 1e-6 -> -1e-6: not counted; 3. -0.01 -> +0.01
    a = 0.03 / (0.03 + 1e-6)
    np.testing.assert_allclose(got, [0.2 + a * 0.3, 0.95], rtol=1e-12)
    assert impact_times(t, np.zeros(12), tol=1e-3).size == 0


def test_hysteresis_counts_each_crossing_of_a_noisy_sine_once():
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 4.0, 0.002)
    sigma = 8e-4  # rad: the seed's sensor noise
    th = 0.05 * np.sin(2 * np.pi * 1.0 * t) + rng.normal(0.0, sigma, t.size)
    k = noise_crossings(th, sigma)
    # 7 true zeros inside (0, 4) s; each detected at the first sample beyond 4 sigma on the new side,
    # i.e. within 4 sigma / slope = 4 * 8e-4 / (2 pi 0.05) ~ 0.01 s (plus noise) after the zero
    zeros = np.arange(1, 8) * 0.5
    assert k.size == 7
    assert np.all((t[k] > zeros) & (t[k] < zeros + 0.03)), t[k] - zeros
    # the band is HYSTERESIS_SIGMAS noise sigmas wide
    idx, first = hysteresis_crossings(th, HYSTERESIS_SIGMAS * sigma)
    np.testing.assert_array_equal(idx, k)
    assert first == 1


@pytest.mark.parametrize("theta", [np.zeros(10), np.full(10, 1e-9)])
def test_no_crossing_without_leaving_the_band(theta):
    idx, first = hysteresis_crossings(theta, 1e-6)
    assert idx.size == 0 and first in (0, 1)
    assert noise_crossings(theta, 1e-6).size == 0


def test_resolved_impact_count_leaves_out_the_small_tail():
    """Free rocking from 0.1 alpha: an impact counts when the half-cycle before it peaked at 0.01 alpha or more.

    The count must equal the number of half-cycle peaks at or above the resolution (an independent
    measure, housner.engines.measures.half_cycle_peaks): 42 of the analytic model's 209 impacts at 0.01 alpha,
    83 at 0.001 alpha; the rest is the rest rule's tail of ever smaller impacts.
    """
    from housner import GroundMotion, Specimen, simulate
    from housner.engines.measures import half_cycle_peaks
    from housner.free_vibration.impacts import IMPACT_RESOLUTION, resolved_impact_count

    spec = Specimen.bachmann2017()
    res = simulate(spec, GroundMotion.free_vibration(0.1 * spec.alpha, 8.0, dt=1e-3))
    peaks = half_cycle_peaks(res) / spec.alpha
    assert IMPACT_RESOLUTION == 0.01
    for resolution in (IMPACT_RESOLUTION, 1e-3):
        assert resolved_impact_count(res, resolution) == int(np.sum(peaks >= resolution))
    assert 0 < resolved_impact_count(res) < resolved_impact_count(res, 1e-3) < res.n_impacts
