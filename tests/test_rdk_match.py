"""Spectrally matched RDK ensembles: bands out of sample, seeds, rest at the end, the published model kept."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid

from housner.scenarios.motions import bands, rdk, rdk_match
from housner.scenarios.motions.bands import BAND_BOUNDS, band_centres, band_check, band_periods
from housner.scenarios.motions.elastic import ensemble_spectra, response_spectrum
from housner.scenarios.motions.rdk_match import MatchedRDK, fit_matched, simulate_matched
from housner.scenarios.motions.records import elcentro

VARIANTS = ("peer1999", "ngawest2")

#: Seed of the out-of-sample ensembles; the fit uses rdk.DEFAULT_FIT_SEED.
TEST_SEED = 2017


@pytest.fixture(scope="module")
def records():
    return {v: elcentro(v) for v in VARIANTS}


@pytest.fixture(scope="module")
def models(records):
    return {v: fit_matched(records[v]) for v in VARIANTS}


@pytest.fixture(scope="module")
def ensembles(models):
    return {v: simulate_matched(models[v], 100, TEST_SEED) for v in VARIANTS}


# ----------------------------------------------------------------------
# Bands
# ----------------------------------------------------------------------
def test_bands_are_third_octaves_that_cover_the_range():
    c = band_centres(0.05, 3.0)
    k = np.round(3 * np.log2(c))
    np.testing.assert_allclose(c, 2.0 ** (k / 3), rtol=1e-12)
    np.testing.assert_array_equal(k, np.arange(-13, 6))  # 0.0496 .. 3.17 s
    lo, hi = c * 2 ** (-1 / 6), c * 2 ** (1 / 6)
    np.testing.assert_allclose(lo[1:], hi[:-1], rtol=1e-12)  # the bands tile the axis
    assert lo[0] <= 0.05 < hi[0] and lo[-1] < 3.0 <= hi[-1]  # and every period of the range is in one
    np.testing.assert_array_equal(np.round(3 * np.log2(band_centres(0.5, 3.0))), np.arange(-3, 6))
    T = band_periods(c, 5).reshape(c.size, 5)
    assert np.all((T > lo[:, None]) & (T < hi[:, None]))
    np.testing.assert_allclose(np.exp(np.log(T).mean(axis=1)), c, rtol=1e-12)  # centred in log T


# ----------------------------------------------------------------------
# Acceptance: the ensemble mean spectrum band by band, out of sample
# ----------------------------------------------------------------------
@pytest.mark.parametrize("variant", VARIANTS)
def test_bands_pass_out_of_sample(variant, records, models, ensembles):
    # The fit matches the mean of 100 motions of rdk.DEFAULT_FIT_SEED to the
    # record (in sample within 7 %, except the PSa ~ PGA band of ngawest2 at
    # 1.17); these are 100 other motions. A band's mean has a sampling sd of
    # ~CV / sqrt(100) = 3-5 % (CV of PSa 0.3-0.5, largest at long periods), so
    # fit and test ensembles differ by ~5-7 % per band: measured worst 0.90
    # (peer1999, 2-2.5 s) and 1.16 (ngawest2, 0.05 s); over ten other seeds the
    # worst band of 100 motions lay in 0.87-1.18, its seed-to-seed sd <= 0.03
    # in log, so 2.5-3 sd inside the bounds [0.8, 1.25], which are the issue's
    # target, not loosened.
    assert TEST_SEED != rdk.DEFAULT_FIT_SEED
    model = models[variant]
    assert model.achieved.psa.passed
    check = band_check(ensembles[variant], records[variant])
    print(check)
    assert check.psa.bounds == check.sd.bounds == BAND_BOUNDS == (0.8, 1.25)
    assert check.psa.n_motions == 100 and len(check.psa.ratio) == 19 and len(check.sd.ratio) == 9
    assert check.psa.passed, str(check.psa)
    assert check.sd.passed, str(check.sd)
    assert check.passed
    # Sd = PSa / omega^2 motion by motion and for the record: same ratios where both are checked
    common = {c: r for c, r in zip(check.psa.centre, check.psa.ratio, strict=True)}
    for c, r in zip(check.sd.centre, check.sd.ratio, strict=True):
        assert r == pytest.approx(common[c], rel=1e-9)


def test_the_published_model_fails_the_same_check(records, models):
    # The check has teeth: the published model's ensemble (same noise) is at
    # 0.49 of the record at 1 s (seed paper's Figure 8 limitation).
    check = band_check(rdk.simulate(models["peer1999"].params, 100, TEST_SEED), records["peer1999"])
    assert not check.psa.passed
    assert check.psa.worst < 0.6


@pytest.mark.parametrize("variant", VARIANTS)
def test_matched_spectra_within_25_percent_at_every_period_where_the_published_miss(
    variant, records, models, ensembles
):
    """The per-period target the published model cannot reach (it was a strict xfail of tests/test_rdk.py).

    Ensemble mean 5 % PSa / record at 20 periods 0.1-2 s: the published model's single-mode
    filter leaves 0.5-1 s short (0.53 of the record there, docs/results.md), the matched model is
    within 25 % at every period (measured 0.84-1.18 on both variants).
    """
    periods = np.logspace(-1, np.log10(2.0), 20)
    rec, _ = response_spectrum(records[variant], periods)
    published = rdk.simulate(models[variant].params, 100, TEST_SEED)
    for ens, within in ((ensembles[variant], True), (published, False)):
        ratio = ensemble_spectra(ens, periods)[0].mean(axis=0) / rec
        assert bool(np.all(np.abs(ratio - 1) <= 0.25)) is within, np.round(ratio, 2)


@pytest.mark.parametrize("variant", VARIANTS)
def test_band_ratios_agree_with_pyrotd(variant, records, ensembles):
    """The band check recomputed with a second implementation: pyrotd (frequency domain, test extra).

    Each spectrum alone differs from pyrotd's by the interpolation between samples, 1 - sinc^2(dt/T),
    plus 0.5 % for the peak picking (tests/test_elastic.py). The interpolation factor depends on the
    oscillator period, not on the motion, so it cancels in a ratio of spectra of motions sampled
    alike; the two peak pickings remain: 1 % on every band's ratio.
    """
    import pyrotd

    g = 9.80665
    rec, ms = records[variant], ensembles[variant][:10]
    assert all(m.dt == rec.dt for m in ms)  # sampled alike: the cancellation holds
    check = band_check(ms, rec)

    def spectrum(m, T):  # zero padding removes pyrotd's wrap-around
        padded = np.concatenate([m.acc / g, np.zeros(4 * m.n)])
        return pyrotd.calc_spec_accels(m.dt, padded, 1 / T, 0.05).spec_accel * g

    for table in (check.psa, check.sd):
        T = band_periods(np.array(table.centre), bands.CHECK_PER_BAND)
        mean = np.mean([spectrum(m, T) for m in ms], axis=0)
        ref = spectrum(rec, T)  # Sd = PSa / omega^2 on both sides: the same ratio
        ratio = np.exp(np.log(mean / ref).reshape(len(table.centre), -1).mean(axis=1))
        np.testing.assert_allclose(table.ratio, ratio, rtol=0.01, err_msg=table.quantity)


def test_band_table_reports_verdict_interval_and_rows(records, ensembles):
    check = band_check(ensembles["peer1999"][:20], records["peer1999"], per_band=3, bounds=(0.95, 1.05))
    rows = check.rows()
    assert len(rows) == 19 + 9
    assert {"centre_s", "lo_s", "hi_s", "ratio", "ci95_lo", "ci95_hi", "verdict"} <= set(rows[0])
    for r in rows:
        assert r["ci95_lo"] < r["ratio"] < r["ci95_hi"]
        assert r["verdict"] == ("PASS" if 0.95 <= r["ratio"] <= 1.05 else "FAIL")
    text = str(check)
    assert "PSa" in text and "Sd" in text and "overall" in text and "20 motions" in text


# ----------------------------------------------------------------------
# The fit and the simulation
# ----------------------------------------------------------------------
def test_in_sample_table_is_the_fit_ensembles(records, models):
    # The fit ensemble is simulate_matched(model, n_fit, fit seed): its band
    # ratios, recomputed through ensemble_spectra, are the stored ones.
    model = models["peer1999"]
    fit_ens = simulate_matched(model, model.n_fit, rdk.DEFAULT_FIT_SEED)
    periods = band_periods(np.array(model.achieved.psa.centre), rdk_match.FIT_PER_BAND)
    check = band_check(fit_ens, records["peer1999"], per_band=rdk_match.FIT_PER_BAND)
    np.testing.assert_allclose(check.psa.ratio, model.achieved.psa.ratio, rtol=1e-10)
    # the fit's batched spectrum kernel is ensemble_spectra's recurrence
    psa, _ = ensemble_spectra(fit_ens[:4], periods)
    acc = np.column_stack([m.acc for m in fit_ens[:4]])
    batch = rdk_match._psa_batch(acc, rdk_match._psa_plan(model.dt, periods, 0.05))
    np.testing.assert_allclose(batch, psa, rtol=1e-12)


def test_gain_filter_is_causal_with_the_fitted_magnitude(models):
    # The minimum-phase FIR realises G within its truncation: rms log error
    # 0.4 % and at most 8 % (next to the kinks of the log-log interpolation)
    # over 0.25-25 Hz for a 10 s filter; a constant gain is a scaled impulse.
    model = models["ngawest2"]
    h = model.impulse_response()
    assert h.size == model.n_taps == 1000
    f = np.fft.rfftfreq(2**16, model.dt)
    sel = (f > 0.25) & (f < 25.0)
    err = np.log(np.abs(np.fft.rfft(h, 2**16))[sel] / model.gain_at(f[sel]))
    assert np.sqrt(np.mean(err**2)) < 0.01 and np.max(np.abs(err)) < 0.1
    e = np.cumsum(h**2) / np.sum(h**2)
    assert e[300] > 0.99  # energy up front (minimum phase): 99.9 % within 3.3 s
    flat = MatchedRDK(model.params, model.centres, [2.5] * len(model.centres))
    np.testing.assert_allclose(flat.impulse_response()[0], 2.5, rtol=1e-12)
    assert np.max(np.abs(flat.impulse_response()[1:])) < 1e-12


def test_unit_gain_gives_the_published_model(models):
    # G = 1 is a unit impulse: the published motions (to FFT round-off), then
    # fir_length more seconds of the high-pass filter at rest.
    p = models["peer1999"].params
    plain = rdk.simulate(p, 3, seed=9)
    unit = simulate_matched(MatchedRDK(p, (0.1, 1.0), (1.0, 1.0)), 3, seed=9)
    for a, b in zip(plain, unit, strict=True):
        assert b.n == a.n + 999
        peak = np.max(np.abs(a.acc))
        np.testing.assert_allclose(b.acc[: a.n], a.acc, rtol=0, atol=1e-12 * peak)
        assert np.max(np.abs(b.acc[a.n :])) < 1e-3 * peak


def test_same_seed_same_motions_and_motion_i_independent_of_n(models, monkeypatch):
    model = models["ngawest2"]
    a = simulate_matched(model, 3, seed=5)
    b = simulate_matched(model, 3, seed=5)
    more = simulate_matched(model, 7, seed=np.random.SeedSequence(5))
    for i in range(3):
        np.testing.assert_array_equal(a[i].acc, b[i].acc)
        np.testing.assert_array_equal(a[i].acc, more[i].acc)
    monkeypatch.setattr(rdk, "_CHUNK", 2)  # simulated in blocks of 2: nothing changes
    for m1, m2 in zip(simulate_matched(model, 7, seed=5), more, strict=True):
        np.testing.assert_array_equal(m1.acc, m2.acc)
    assert not np.array_equal(more[0].acc, more[1].acc)
    assert not np.array_equal(simulate_matched(model, 1, seed=6)[0].acc, a[0].acc)


def test_motions_carry_names_grid_and_provenance(models):
    model = models["peer1999"]
    ms = simulate_matched(model, 2, seed=99, name="elc")
    assert [m.name for m in ms] == ["elc-000", "elc-001"]
    assert all(m.n == model.n == model.params.n + model.n_taps - 1 and m.dt == model.dt for m in ms)
    prov = ms[1].provenance
    for text in ("Rezaeian & Der Kiureghian", "Gasparini & Vanmarcke", "elcentro-peer1999", "entropy=99", "[1]"):
        assert text in prov
    d = model.describe()
    assert d["record"] == "elcentro-peer1999" and len(d["gain"]) == len(d["gain_centres_s"]) == 19
    assert d["fir_length_s"] == 10.0 and d["iterations"] == model.iterations >= 1 and "SIMQKE" in d["model"]


@pytest.mark.parametrize("variant", VARIANTS)
def test_simulated_motions_end_at_rest(variant, ensembles):
    # The gain filter stops ringing fir_length after the noise does, and the
    # high-pass filter is then followed for settle_time(omega_c), until its
    # free response (1 + w_c t) exp(-w_c t) < 1e-3: the end velocity and
    # displacement are ~1e-3 of the filter state when its input stops, itself
    # far below the peaks (the envelope has decayed): the published model's
    # bound. Measured: below 1e-6 of the peaks.
    for m in ensembles[variant]:
        v = cumulative_trapezoid(m.acc, dx=m.dt, initial=0.0)
        d = cumulative_trapezoid(v, dx=m.dt, initial=0.0)
        assert abs(v[-1]) < 1e-3 * np.max(np.abs(v))
        assert abs(d[-1]) < 1e-3 * np.max(np.abs(d))


# ----------------------------------------------------------------------
# The published model is unchanged
# ----------------------------------------------------------------------
def test_published_fit_and_simulate_are_unchanged(records, models):
    # Values recorded from rdk.fit / rdk.simulate before housner.scenarios.motions.rdk gained
    # the modulated_noise / highpass hook (commit e88a637); they matched bit
    # for bit after it. rtol 1e-12 leaves room only for libm differences.
    p = rdk.fit(records["peer1999"])
    assert p == models["peer1999"].params  # fit_matched starts from the published fit
    recorded = dict(
        Ia=1.8087040903427747,
        D5_95=24.102629585764305,
        t_mid=4.901505077487918,
        omega_mid=32.24734068946931,
        omega_prime=-0.3977360577680784,
        zeta_f=0.454,
    )
    for key, value in recorded.items():
        assert getattr(p, key) == pytest.approx(value, rel=1e-12), key
    ms = rdk.simulate(p, 3, seed=2017)
    assert ms[0].n == 4735
    np.testing.assert_allclose(
        ms[0].acc[[1, 250, 1000, 3999]],
        [-1.6739957201255375, -0.08939598548911037, 1.1937251713737616, -0.19401050874570874],
        rtol=1e-10,
    )
    np.testing.assert_allclose(
        ms[2].acc[[1, 250, 1000, 3999]],
        [1.8596556207915957, -0.7436982814544809, 1.1580520192719652, 0.055448881610771966],
        rtol=1e-10,
    )
    assert np.max(np.abs(ms[0].acc)) == pytest.approx(2.3156272213828357, rel=1e-10)


# ----------------------------------------------------------------------
# Arguments
# ----------------------------------------------------------------------
@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(n_fit=0), "`n_fit`"),
        (dict(iterations=-1), "`iterations`"),
        (dict(beta=0.0), "`beta`"),
        (dict(beta=1.5), "`beta`"),
        (dict(tol=-0.1), "`tol`"),
        (dict(gain_bounds=(2.0, 3.0)), "`gain_bounds`"),
        (dict(gain_bounds=(3.0, 2.0)), "`gain_bounds`"),
        (dict(psa_range=(3.0, 0.05)), "`psa_range`"),
        (dict(per_band=0), "`per_band`"),
        (dict(damping=1.2), "`damping`"),
        (dict(fir_length=-1.0), "`fir_length`"),
        (dict(fir_length=0.05), "`fir_length`"),
        (dict(seed=-1), "`seed`"),
    ],
)
def test_fit_matched_rejects_bad_arguments(records, models, kwargs, name):
    with pytest.raises(ValueError, match=name):
        fit_matched(records["peer1999"], params=models["peer1999"].params, **kwargs)


def test_other_bad_input_names_the_argument(records, models, ensembles):
    model, rec = models["peer1999"], records["peer1999"]
    with pytest.raises(ValueError, match="`n`"):
        simulate_matched(model, -1, 0)
    with pytest.raises(ValueError, match="`seed`"):
        simulate_matched(model, 2, np.random.default_rng(0))
    with pytest.raises(ValueError, match="`motions`"):
        band_check([], rec)
    with pytest.raises(ValueError, match="`bounds`"):
        band_check(ensembles["peer1999"][:2], rec, bounds=(1.25, 0.8))
    with pytest.raises(ValueError, match="`psa_range`"):
        band_check(ensembles["peer1999"][:2], rec, psa_range=(-1.0, 3.0))
    with pytest.raises(ValueError, match="`gain`"):
        MatchedRDK(model.params, (0.1, 1.0), (1.0, -2.0))
    with pytest.raises(ValueError, match="`gain`"):
        MatchedRDK(model.params, (0.1, 1.0), (1.0,))
    with pytest.raises(ValueError, match="`centres`"):
        MatchedRDK(model.params, (1.0, 1.0), (1.0, 2.0))
    with pytest.raises(TypeError, match="`record`"):
        fit_matched(rec.acc)
    with pytest.raises(TypeError, match="`model`"):
        simulate_matched(model.params, 2, 0)
