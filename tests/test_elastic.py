"""Elastic response spectra: closed forms, an independent state-space integration, pyrotd and published figures."""

from __future__ import annotations

import math

import numpy as np
import pyrotd
import pytest
from scipy import signal

from housner import GroundMotion
from housner.scenarios.motions.elastic import (
    ensemble_spectra,
    linear_step_coefficients,
    response_spectrum,
    sdof_history,
)
from housner.scenarios.motions.records import elcentro
from housner.units import G


@pytest.fixture(scope="module")
def record():
    return elcentro()


def test_step_response_peak_is_the_closed_form():
    # Ground acceleration a0 from t = 0 on an oscillator at rest: u = -(a0 / w^2)
    # (1 - e^{-z w t} (cos wd t + z / sqrt(1 - z^2) sin wd t)), first peak at
    # t = pi / wd: |u| = (a0 / w^2) (1 + exp(-z pi / sqrt(1 - z^2))).
    # 2000 steps per period sample the peak within (pi / 2000)^2 / 2 = 1.2e-6.
    a0, dt = 1.7, 0.01
    m = GroundMotion(np.full(301, a0), dt)
    T = np.array([0.13, 0.5, 1.0, 2.9])
    w = 2 * np.pi / T
    for z in (0.0, 0.05, 0.2):
        psa, sd = response_spectrum(m, T, z, points_per_period=2000)
        expected = a0 / w**2 * (1 + np.exp(-z * np.pi / np.sqrt(1 - z * z)))
        np.testing.assert_allclose(sd, expected, rtol=2e-6)
        np.testing.assert_allclose(psa, w**2 * sd, rtol=1e-14)


def test_undamped_step_peak_on_the_grid_is_exact():
    # T = 0.5 s, dt = 0.01 s: the peak 2 a0 / w^2 falls on sample 25, so the
    # recurrence (exact for a piecewise-linear excitation) gets it to round-off.
    m = GroundMotion(np.full(60, 1.0), 0.01)
    _, sd = response_spectrum(m, [0.5], 0.0, points_per_period=1)
    assert sd[0] == pytest.approx(2.0 / (4 * np.pi) ** 2, rel=1e-12)


@pytest.mark.parametrize("zeta", [0.0, 0.02, 0.05, 0.3])
def test_recurrence_matches_scipy_lsim(record, zeta):
    # Independent integration: scipy.signal.lsim (matrix exponential of the
    # state-space model with a first-order hold, i.e. input linear between
    # samples) on the record sampled at the same sub-steps. Both are exact for
    # the same input, so only round-off separates them (rtol 1e-8).
    T = np.array([0.07, 0.3, 1.0, 3.0])
    psa, sd = response_spectrum(record, T, zeta)
    n_sub = np.maximum(1, np.ceil(20 * record.dt / T)).astype(int)
    for j, Tj in enumerate(T):
        w = 2 * np.pi / Tj
        t = np.arange((record.n - 1) * n_sub[j] + 1) * (record.dt / n_sub[j])
        a = np.interp(t, record.t, record.acc)
        sys = signal.StateSpace([[0, 1], [-w * w, -2 * zeta * w]], [[0], [1]], [[1, 0]], [[0]])
        _, y, _ = signal.lsim(sys, -a, t)
        assert sd[j] == pytest.approx(np.max(np.abs(y)), rel=1e-8)
        assert psa[j] == pytest.approx(w * w * np.max(np.abs(y)), rel=1e-8)


def test_critically_damped_history_matches_lsim(record):
    # The high-pass filter of the stochastic model runs sdof_history with zeta = 1.
    w = 2 * np.pi * 0.2
    u, v = sdof_history(record.acc, record.dt, w, 1.0)
    sys = signal.StateSpace([[0, 1], [-w * w, -2 * w]], [[0], [1]], np.eye(2), [[0], [0]])
    _, y, _ = signal.lsim(sys, record.acc, record.t)
    scale = np.max(np.abs(y), axis=0)
    np.testing.assert_allclose(u, y[:, 0], rtol=0, atol=1e-9 * scale[0])
    np.testing.assert_allclose(v, y[:, 1], rtol=0, atol=1e-9 * scale[1])
    u2, v2 = sdof_history(np.column_stack([record.acc, -2 * record.acc]), record.dt, w, 1.0)
    np.testing.assert_allclose(u2[:, 1], -2 * u, rtol=1e-12, atol=1e-15)


def test_step_coefficients_reproduce_free_vibration():
    # With f = 0 the one-step matrix is exp(F h): check against the analytic
    # damped free vibration from (u, v) = (1, 0) after one step.
    w, z, h = 7.0, 0.1, 0.03
    A, B0, B1 = linear_step_coefficients(w, z, h)
    wd = w * math.sqrt(1 - z * z)
    u = math.exp(-z * w * h) * (math.cos(wd * h) + z * w / wd * math.sin(wd * h))
    v = -math.exp(-z * w * h) * w * w / wd * math.sin(wd * h)
    np.testing.assert_allclose(A[0] @ [1.0, 0.0], [u, v], rtol=1e-13)
    # a constant force f gives the static solution f / w^2 as the fixed point
    x = np.linalg.solve(np.eye(2) - A[0], (B0[0] + B1[0]) * 1.0)
    np.testing.assert_allclose(x, [1 / w**2, 0.0], atol=1e-14)


@pytest.mark.parametrize("variant", ["peer1999", "chopra"])
def test_agrees_with_pyrotd_within_the_interpolation_difference(variant):
    # pyrotd works in the frequency domain: the record is taken as band-limited
    # (ideal interpolation) and periodic. Padding with zeros removes the wrap-
    # around; what remains is the interpolation: a record linear between
    # samples has the band-limited spectrum times sinc^2(f dt), so at the
    # oscillator frequency the two inputs differ by 1 - sinc^2(dt / T). That,
    # plus 0.5 % for the peak picking, is the tolerance at each period.
    rec = elcentro(variant)
    T = np.logspace(-1, math.log10(3.0), 25)
    psa, _ = response_spectrum(rec, T)
    padded = np.concatenate([rec.acc / G, np.zeros(4 * rec.n)])
    ref = pyrotd.calc_spec_accels(rec.dt, padded, 1 / T, 0.05).spec_accel * G
    tol = 1 - np.sinc(rec.dt / T) ** 2 + 0.005
    assert np.all(np.abs(psa / ref - 1) <= tol), np.abs(psa / ref - 1) / tol


def test_peer1999_matches_the_published_figures(record):
    # shared/data/README.md: 5 % Sa [g] at T = 0.1 ... 2 s by eqsig (time domain,
    # like us) and by pyrotd on the unpadded record. eqsig's are printed to 3
    # digits: tolerance half a unit in the last digit plus 0.3 % for peak
    # sampling (eqsig follows the record's 0.01 s step, we sub-step). pyrotd's
    # differ by interpolation (3.3 % at 0.1 s, see above) and its wrap-around
    # (3.6 % at 2 s), so 4 %.
    T = [0.1, 0.2, 0.3, 0.5, 1.0, 2.0]
    eqsig = np.array([0.711, 0.634, 0.677, 0.713, 0.486, 0.187])
    pyrotd_unpadded = np.array([0.729, 0.639, 0.677, 0.713, 0.487, 0.194])
    psa, _ = response_spectrum(record, T)
    np.testing.assert_allclose(psa / G, eqsig, rtol=0.003, atol=0.0005)
    np.testing.assert_allclose(psa / G, pyrotd_unpadded, rtol=0.04)


def test_ensemble_equals_one_by_one_and_mixes_steps(record):
    chopra = elcentro("chopra")
    T = np.logspace(-1.5, 0.5, 12)
    psa, sd = ensemble_spectra([record, chopra, record.scaled(2.0)], T, 0.05)
    assert psa.shape == sd.shape == (3, 12)
    for row, m in zip(range(3), [record, chopra, record.scaled(2.0)], strict=True):
        p1, s1 = response_spectrum(m, T, 0.05)
        np.testing.assert_array_equal(psa[row], p1)
        np.testing.assert_array_equal(sd[row], s1)
    np.testing.assert_allclose(psa[2], 2 * psa[0], rtol=1e-12)  # linear in the amplitude


def test_time_scaling_moves_the_spectrum(record):
    # Compressing time by sqrt(S) (seed eq. 9) maps Sd(T) at prototype scale to
    # Sd(T / sqrt(S)) / S at model scale for the same record samples; the exact
    # recurrence keeps this to round-off when the sub-steps scale alike.
    S = 10.0
    T = np.array([0.2, 0.5, 1.0, 2.0])
    _, sd = response_spectrum(record, T, points_per_period=1)
    _, sd_m = response_spectrum(record.to_model_scale(S), T / math.sqrt(S), points_per_period=1)
    np.testing.assert_allclose(sd_m, sd / S, rtol=1e-10)


def test_arguments_are_checked(record):
    with pytest.raises(ValueError, match="`periods`"):
        response_spectrum(record, [0.5, -1.0])
    with pytest.raises(ValueError, match="`periods`"):
        response_spectrum(record, [])
    with pytest.raises(ValueError, match="`damping`"):
        response_spectrum(record, [0.5], damping=5.0)
    with pytest.raises(ValueError, match="`points_per_period`"):
        response_spectrum(record, [0.5], points_per_period=0)
    with pytest.raises(TypeError, match="`motion`"):
        response_spectrum(record.acc, [0.5])
    with pytest.raises(ValueError, match="`motions` is empty"):
        ensemble_spectra([], [0.5])
