"""The Rezaeian & Der Kiureghian model: envelope, filtered process, seeds, fit and the El Centro ensemble."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest
from scipy import signal
from scipy.integrate import cumulative_trapezoid

from housner.scenarios.motions import rdk
from housner.scenarios.motions.elastic import ensemble_spectra, response_spectrum
from housner.scenarios.motions.rdk import fit, simulate
from housner.scenarios.motions.rdk_params import RDKParams, settle_time
from housner.scenarios.motions.records import (
    arias_intensity,
    elcentro,
    husid_time,
    pmnm_count,
    significant_duration,
    upcrossing_count,
)
from housner.units import G

# A mid-size, mid-frequency motion used where El Centro's own fit is not needed.
KNOWN = dict(Ia=1.2, D5_95=15.0, t_mid=7.0, omega_mid=2 * np.pi * 4.0, omega_prime=-0.25, zeta_f=0.3, duration=35.0)


@pytest.fixture(scope="module")
def record():
    return elcentro()


@pytest.fixture(scope="module")
def fitted(record):
    return fit(record)


@pytest.fixture(scope="module")
def ensemble(fitted):
    return simulate(fitted, 100, seed=2017)


# ----------------------------------------------------------------------
# The modulating function
# ----------------------------------------------------------------------
def test_exponential_envelope_closed_form():
    # With alpha2 = 1, q^2 = alpha1^2 exp(-2 alpha3 t) and its Husid curve is
    # 1 - exp(-2 alpha3 t): t_p = -ln(1 - p) / (2 alpha3). So t_mid = ln(1/0.55) D / ln 19
    # gives alpha2 = 1 and alpha3 = ln 19 / (2 D); int q^2 = alpha1^2 / (2 alpha3) = 2 g Ia / pi.
    # A 1000 s window leaves exp(-147) of the energy outside: exact to round-off.
    D, Ia = 10.0, 0.8
    p = RDKParams(Ia, D, math.log(1 / 0.55) * D / math.log(19), 20.0, 0.0, 0.3, duration=1000.0)
    assert p.alpha2 == pytest.approx(1.0, abs=1e-9)
    assert p.alpha3 == pytest.approx(math.log(19) / (2 * D), rel=1e-9)
    assert p.alpha1 == pytest.approx(math.sqrt(2 * G * Ia / math.pi * 2 * p.alpha3), rel=1e-9)


@pytest.mark.parametrize(
    "Ia, D, tmid, T0, duration",
    [
        (1.703, 24.1026, 4.9015, 0.0, 39.99),  # El Centro: alpha2 < 1, cut by the record's end
        (1.2, 15.0, 7.0, 0.0, 35.0),  # alpha2 ~ 2
        (0.5, 8.0, 6.0, 2.0, 30.0),  # envelope starting after the first sample
        (0.5, 8.0, 3.0, -1.5, 20.0),  # envelope already under way at t = 0
    ],
)
def test_envelope_reproduces_its_husid_parameters(Ia, D, tmid, T0, duration):
    # Independent check: integrate q^2 numerically on a fine grid over the
    # simulated window (geometric near T0, where q^2 ~ (t - T0)^(2 alpha2 - 2)
    # may be singular) and read D5-95, t_mid and Ia off its Husid curve.
    # Quadrature error with 400 001 points is < 1e-6 relative; times to 1e-4 s.
    p = RDKParams(Ia, D, tmid, 20.0, 0.0, 0.3, duration=duration, T0=T0)
    w0 = max(T0, 0.0)
    t = np.unique(np.concatenate([T0 + np.geomspace(1e-12, 1.0, 200_001), np.linspace(w0, duration, 200_001)]))
    t = t[(t >= w0) & (t <= duration)]
    q2 = p.modulating(t) ** 2
    if T0 >= 0:
        q2[0] = 0.0  # q may be infinite at T0 itself; the geometric grid carries the integrable peak
    c = cumulative_trapezoid(q2, t, initial=0.0)
    assert math.pi / (2 * G) * c[-1] == pytest.approx(Ia, rel=2e-4)
    t5, t45, t95 = np.interp([0.05, 0.45, 0.95], c / c[-1], t)
    assert t45 == pytest.approx(tmid, abs=1e-3)
    assert t95 - t5 == pytest.approx(D, abs=1e-3)


def test_envelope_rejects_what_a_gamma_shape_cannot_reach():
    with pytest.raises(ValueError, match="`D5_95`"):
        RDKParams(1.0, 30.0, 2.0, 20.0, 0.0, 0.3, duration=40.0)  # too long for so early a t_mid
    with pytest.raises(ValueError, match="`t_mid`"):
        RDKParams(1.0, 10.0, 50.0, 20.0, 0.0, 0.3, duration=40.0)
    with pytest.raises(ValueError, match="`zeta_f`"):
        RDKParams(1.0, 10.0, 5.0, 20.0, 0.0, 1.0)
    with pytest.raises(ValueError, match="`omega_mid`"):
        RDKParams(1.0, 10.0, 5.0, 1.0, 0.0, 0.3)
    with pytest.raises(ValueError, match="`Ia`"):
        RDKParams(-1.0, 10.0, 5.0, 20.0, 0.0, 0.3)


# ----------------------------------------------------------------------
# The filtered process
# ----------------------------------------------------------------------
@pytest.fixture(scope="module")
def raw_process():
    """400 motions before and after the high-pass filter, with their parameters."""
    p = RDKParams(**KNOWN)
    u = rdk.white_noise(rdk.seed_sequence(11).spawn(400), p.n_warm + p.n_noise)
    acc, x = rdk._simulate_array(p, u)
    return p, acc, x


def test_normalised_noise_has_variance_q_squared(raw_process):
    # E[x(t)^2] = q(t)^2 (sigma_h normalisation). With 400 motions the sample
    # variance / q^2 has standard deviation sqrt(2 / 400) = 0.07 per instant;
    # averaged over 1 s windows (about 8 independent instants for a
    # correlation time of ~1 / (zeta omega) = 0.13 s) 0.025: 5 sigma = 0.125.
    p, _, x = raw_process
    t = np.arange(p.n_noise) * p.dt
    ratio = (x[: p.n_noise] ** 2).mean(axis=1)[1:] / p.modulating(t[1:]) ** 2
    windows = ratio[: (ratio.size // 100) * 100].reshape(-1, 100).mean(axis=1)
    assert np.all(np.abs(windows - 1) < 0.125), windows
    assert abs(ratio.mean() - 1) < 0.02


def test_zero_crossing_rate_is_the_filter_frequency(raw_process):
    # The displacement of a linear oscillator driven by white noise crosses zero
    # upward at omega / (2 pi) on average, so the model's cumulative count is
    # int omega_f / (2 pi) dt. Per motion the count over 22 s has sd ~4 (of
    # ~82), the mean of 400 an sd of 0.2 %: tolerance 1 %. The high-pass filter
    # raises the rate a little (it removes slow content): 0-8 % more.
    p, acc, x = raw_process
    t = p.t
    j0, j1 = 300, 2500
    expected = np.trapezoid(p.filter_frequency(t[j0 : j1 + 1]) / (2 * np.pi), t[j0 : j1 + 1])
    counts_x = upcrossing_count(x)
    counts_acc = upcrossing_count(acc)
    assert (counts_x[j1] - counts_x[j0]).mean() == pytest.approx(expected, rel=0.01)
    assert 1.0 <= (counts_acc[j1] - counts_acc[j0]).mean() / expected <= 1.08


def test_counting_statistics_on_closed_forms():
    t = np.linspace(0, 10, 10_001)
    n = upcrossing_count(np.sin(2 * np.pi * 1.5 * t + 0.3))
    assert n[-1] == 15  # 1.5 Hz for 10 s
    a = np.array([1.0, 0.5, 0.8, 0.2, 0.6, -0.4, -0.9, -0.3, -0.6, 0.4])
    # positive minima at 0.5 and 0.2, negative maximum at -0.3
    np.testing.assert_array_equal(pmnm_count(a), [0, 1, 1, 2, 2, 2, 2, 3, 3, 3])
    two = pmnm_count(np.column_stack([a, -a]))
    np.testing.assert_array_equal(two[:, 0], two[:, 1])


# ----------------------------------------------------------------------
# Seeds and determinism
# ----------------------------------------------------------------------
def test_same_seed_same_motions_and_motion_i_independent_of_n(monkeypatch):
    p = RDKParams(**KNOWN)
    a = simulate(p, 3, seed=5)
    b = simulate(p, 3, seed=5)
    for m1, m2 in zip(a, b, strict=True):
        np.testing.assert_array_equal(m1.acc, m2.acc)
    more = simulate(p, 7, seed=5)
    for i in range(3):
        np.testing.assert_array_equal(more[i].acc, a[i].acc)
    # chunked generation (motions are simulated in blocks) changes nothing either
    monkeypatch.setattr(rdk, "_CHUNK", 2)
    chunked = simulate(p, 7, seed=5)
    for m1, m2 in zip(chunked, more, strict=True):
        np.testing.assert_array_equal(m1.acc, m2.acc)
    assert not np.array_equal(more[0].acc, more[1].acc)
    assert not np.array_equal(simulate(p, 1, seed=6)[0].acc, a[0].acc)


def test_motions_carry_names_grid_and_provenance():
    p = RDKParams(**KNOWN)
    ms = simulate(p, 2, seed=np.random.SeedSequence(99))
    assert [m.name for m in ms] == ["rdk-000", "rdk-001"]
    assert all(m.n == p.n and m.dt == p.dt for m in ms)
    assert p.n == round((p.duration + settle_time(p.omega_c)) / p.dt) + 1
    prov = ms[1].provenance
    assert "Rezaeian & Der Kiureghian" in prov and "entropy=99" in prov and "spawn(n)[1]" in prov
    assert "zeta_f=0.3" in prov


def test_seed_sequence_is_not_advanced_and_generators_are_refused():
    p = RDKParams(**KNOWN)
    ss = np.random.SeedSequence(42)
    first = simulate(p, 2, ss)
    again = simulate(p, 2, ss)
    as_int = simulate(p, 2, 42)
    for m1, m2, m3 in zip(first, again, as_int, strict=True):
        np.testing.assert_array_equal(m1.acc, m2.acc)
        np.testing.assert_array_equal(m1.acc, m3.acc)
    with pytest.raises(ValueError, match="`seed`"):
        simulate(p, 2, np.random.default_rng(1))
    with pytest.raises(ValueError, match="`seed`"):
        simulate(p, 2, -3)
    with pytest.raises(ValueError, match="`n`"):
        simulate(p, 2.5, 1)


# ----------------------------------------------------------------------
# Fit
# ----------------------------------------------------------------------
def test_fit_takes_husid_parameters_from_the_record(record, fitted):
    assert fitted.D5_95 == pytest.approx(significant_duration(record), rel=1e-12)
    assert fitted.t_mid == pytest.approx(husid_time(record, 0.45), rel=1e-12)
    assert fitted.dt == record.dt and fitted.duration == record.duration
    # Ia of the model is before the high-pass filter, which removes a few per cent
    assert 1.0 < fitted.Ia / arias_intensity(record) < 1.15
    d = fitted.describe()
    for key in ("Ia_m_s", "D5_95_s", "t_mid_s", "omega_mid_rad_s", "omega_prime_rad_s2", "zeta_f", "alpha2"):
        assert key in d
    assert d["f_mid_Hz"] == pytest.approx(fitted.omega_mid / (2 * np.pi))


def test_fit_matches_the_counting_statistics_it_was_fitted_to(record, fitted, ensemble):
    # The ensemble reproduces the record's cumulative counts over [t5, t95]:
    # zero-level up-crossings (107 in the record) within 8 % - the model's count
    # is int omega_f / (2 pi) before the high-pass filter, which adds 0-8 % (see
    # test_zero_crossing_rate_is_the_filter_frequency); positive minima and
    # negative maxima after the 15 Hz low-pass (55 in the record) within 10 %,
    # the granularity of the zeta_f search (0.01 in zeta_f moves the count ~1.5 %)
    # plus the 20-motion sampling error of the fit (sd ~3 %).
    t5, t95 = husid_time(record, [0.05, 0.95])
    j0, j1 = int(np.ceil(t5 / record.dt)), int(t95 / record.dt)
    acc = np.column_stack([m.acc for m in ensemble])
    up_rec = upcrossing_count(record.acc)
    up_sim = upcrossing_count(acc)
    assert (up_sim[j1] - up_sim[j0]).mean() == pytest.approx(up_rec[j1] - up_rec[j0], rel=0.08)
    sos = signal.butter(4, rdk.DEFAULT_COUNT_LOWPASS, fs=1 / record.dt, output="sos")
    pm_rec = pmnm_count(signal.sosfiltfilt(sos, record.acc))
    pm_sim = pmnm_count(signal.sosfiltfilt(sos, acc, axis=0))
    assert (pm_sim[j1] - pm_sim[j0]).mean() == pytest.approx(pm_rec[j1] - pm_rec[j0], rel=0.10)


def test_fit_recovers_known_parameters():
    # Six motions simulated from known parameters, each fitted on its own. The
    # mean of the six fitted values must lie within 3 standard errors of the
    # truth, with the per-motion scatter measured once over 30 motions:
    # Ia 9.4 %, D5-95 0.79 s, t_mid 0.56 s, omega_mid 2.0 rad/s, zeta_f 0.08
    # (3 sd / sqrt(6): 11.5 %, 0.97 s, 0.69 s, 2.4 rad/s, 0.10). omega' is
    # poorly determined by one motion (sd 0.43 rad/s^2); only its sign-free
    # bound is checked. The high-pass filter biases omega_mid up by ~3 %
    # (test_zero_crossing_rate_is_the_filter_frequency), inside the tolerance.
    true = RDKParams(**KNOWN)
    fits = [fit(m) for m in simulate(true, 6, seed=123)]
    mean = {k: np.mean([getattr(f, k) for f in fits]) for k in ("Ia", "D5_95", "t_mid", "omega_mid", "zeta_f")}
    assert mean["Ia"] == pytest.approx(true.Ia, rel=0.115)
    assert mean["D5_95"] == pytest.approx(true.D5_95, abs=0.97)
    assert mean["t_mid"] == pytest.approx(true.t_mid, abs=0.69)
    assert mean["omega_mid"] == pytest.approx(true.omega_mid, abs=2.4)
    assert mean["zeta_f"] == pytest.approx(true.zeta_f, abs=0.10)
    assert abs(np.mean([f.omega_prime for f in fits]) - true.omega_prime) < 3 * 0.43 / math.sqrt(6)


def test_fit_checks_its_arguments(record):
    with pytest.raises(ValueError, match="`count_lowpass`"):
        fit(record, count_lowpass=60.0)
    with pytest.raises(ValueError, match="`n_sim`"):
        fit(record, n_sim=0)
    with pytest.raises(TypeError, match="`record`"):
        fit(record.acc)


# ----------------------------------------------------------------------
# The El Centro ensemble (seed paper, sec. 4)
# ----------------------------------------------------------------------
def test_ensemble_husid_statistics_cover_the_record(record, ensemble):
    for measure in (arias_intensity, significant_duration, lambda m: husid_time(m, 0.45)):
        values = np.array([measure(m) for m in ensemble])
        lo, hi = np.percentile(values, [5, 95])
        assert lo <= measure(record) <= hi, (lo, measure(record), hi)


def test_ensemble_mean_arias_intensity_is_the_records(record, ensemble):
    # Per-motion Ia scatters by ~9 %, so the mean of 100 by ~1 %; the fit's
    # high-pass correction is estimated from 20 motions sharing their noise
    # before and after the filter (< 1 %): 5 %.
    mean = np.mean([arias_intensity(m) for m in ensemble])
    assert mean == pytest.approx(arias_intensity(record), rel=0.05)


def test_simulated_motions_end_at_rest(ensemble):
    # The high-pass filter is followed until (1 + w_c t) exp(-w_c t) < 1e-3, so
    # the end velocity and displacement are at most ~1e-3 of the filter state
    # when the noise stops, itself below the peaks.
    for m in ensemble:
        v = cumulative_trapezoid(m.acc, dx=m.dt, initial=0.0)
        d = cumulative_trapezoid(v, dx=m.dt, initial=0.0)
        assert abs(v[-1]) < 1e-3 * np.max(np.abs(v))
        assert abs(d[-1]) < 1e-3 * np.max(np.abs(d))


PERIODS = np.logspace(-1, math.log10(2.0), 20)


@pytest.fixture(scope="module")
def spectra(record, ensemble):
    psa, sd = ensemble_spectra(ensemble, PERIODS)
    rec_psa, rec_sd = response_spectrum(record, PERIODS)
    return psa, sd, rec_psa, rec_sd


def test_ensemble_mean_spectra_match_the_record_on_average(spectra):
    # Geometric mean over 0.1-2 s of (ensemble mean / record) for PSa and Sd
    # (Sd = PSa / w^2 motion by motion, so their ratios coincide) within 25 %.
    # Measured 0.85. Fitted with extrema counted raw (zeta_f = 0.13) it is 0.62 and fails.
    psa, sd, rec_psa, rec_sd = spectra
    for ens, rec in ((psa, rec_psa), (sd, rec_sd)):
        ratio = ens.mean(axis=0) / rec
        assert abs(np.mean(np.log(ratio))) < math.log(1.25), ratio


# ----------------------------------------------------------------------
# Figure 8
# ----------------------------------------------------------------------
def test_ensemble_figure_draws(record, ensemble):
    from matplotlib.figure import Figure

    from housner.reports.run.ground_figures import plot_ensemble_spectra, plot_record

    fig = plot_ensemble_spectra(record, ensemble[:10], S=10.0, periods=np.logspace(-2, 0.4, 15))
    assert isinstance(fig, Figure)
    axes = fig.get_axes()
    assert len(axes) == 7  # record trace, then PSa / mean PSa / mean Sd at both scales
    assert axes[0].get_ylabel() == "ground acceleration [g]"
    assert [ax.get_ylabel() for ax in axes[1:]] == ["PSa [g]", "PSa [g]", "Sd [mm]"] * 2
    assert all(ax.get_xscale() == "log" for ax in axes[1:])
    assert len(axes[1].lines) == 10 + 2  # members, mean, record
    assert "S = 10" in axes[4].get_title()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=50)
    assert buf.getvalue()[:4] == b"\x89PNG"

    fig2 = plot_ensemble_spectra(record, ensemble[:3], periods=[0.1, 0.5, 1.0])
    assert len(fig2.get_axes()) == 4
    ax = Figure().add_subplot()
    assert plot_record(record, ax) is ax and len(ax.lines) == 2
    with pytest.raises(ValueError, match="`S`"):
        plot_ensemble_spectra(record, ensemble[:3], S=-1.0)
    with pytest.raises(ValueError, match="`motions`"):
        plot_ensemble_spectra(record, [])
