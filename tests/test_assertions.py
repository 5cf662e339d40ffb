"""Tolerance assertions (housner.reports.assertions) and the pytest plugin (housner.reports.pytest_plugin)."""

from __future__ import annotations

import json
import subprocess
import sys
from importlib.metadata import entry_points

import numpy as np
import pandas as pd
import pytest

from housner.errors import DataFileError
from housner.reports.assertions import (
    AgreementReport,
    CDFAgreementError,
    RecordAgreementError,
    assert_cdf_agreement,
    assert_record_agreement,
    load_results,
)
from housner.statistics import ensemble_stats as stats
from housner.statistics import proportions

pytest_plugins = ["pytester"]

INF = np.inf
N = 100


def table(engines: dict[str, np.ndarray], failed: dict[str, list[int]] | None = None) -> pd.DataFrame:
    """A runner-like results table from theta_max/alpha per engine (+inf = overturned)."""
    rows = []
    for engine, vals in engines.items():
        for i, v in enumerate(vals):
            bad = i in (failed or {}).get(engine, [])
            rows.append(
                {
                    "engine": engine,
                    "motion_id": i,
                    "motion_name": f"gm{i:03d}",
                    "theta_max_over_alpha": np.nan if bad else float(v),
                    "overturned": False if bad else bool(np.isinf(v)),
                    "n_impacts": 4,
                    "wall_s": 0.02,
                    "status": "failed" if bad else "ok",
                    "error": "EngineError: contact diverged" if bad else "",
                }
            )
    return pd.DataFrame(rows)


@pytest.fixture
def base():
    """The reference ensemble: lognormal amplitudes (median 0.6 alpha), 20 % overturned."""
    rng = np.random.default_rng(2017)
    v = 0.6 * np.exp(0.5 * rng.standard_normal(N))
    v[rng.choice(N, size=20, replace=False)] = INF
    return v


def agreeing(base, seed=1):
    """An engine that reproduces the reference up to 3 % per record (same overturn verdicts)."""
    rng = np.random.default_rng(seed)
    return np.where(np.isinf(base), INF, base * np.exp(0.03 * rng.standard_normal(base.size)))


def test_agreeing_engines_pass_and_the_result_lists_every_criterion(base):
    df = table({"housner": base, "mujoco": agreeing(base)})
    res = assert_cdf_agreement(df, "mujoco", "housner", percentiles={25: 0.05, 50: 0.05}, wasserstein_max=0.05)
    assert isinstance(res, AgreementReport) and res.passed
    names = [c.name for c in res.criteria]
    assert names == [
        "usable records",
        "failed runs",
        "KS distance",
        "P[overturn]",
        "25th percentile of theta_max/alpha",
        "50th percentile of theta_max/alpha",
        "Wasserstein W1 (non-overturned)",
    ]
    ks = next(c for c in res.criteria if c.name == "KS distance")
    assert ks.value == stats.ks_2samp(agreeing(base), base).distance <= 0.15
    assert "passed" in str(res)


def test_shifted_distribution_fails_on_ks_with_both_sides_figures(base):
    shifted = np.where(np.isinf(base), INF, base * 1.5)
    df = table({"housner": base, "mujoco": shifted})
    with pytest.raises(CDFAgreementError) as info:
        assert_cdf_agreement(df, "mujoco", "housner", ks_max=0.15, overturn_tol=0.08)
    msg = str(info.value)
    d = stats.ks_2samp(shifted, base).distance
    assert d > 0.15
    assert "CDF agreement of 'mujoco' with 'housner': FAILED 1 of 4 criteria" in msg
    assert f"[FAIL] KS distance: D = {d:.3f}" in msg
    assert f"limit ks_max = 0.15; exceeded by {d - 0.15:.3g}" in msg
    assert "F_mujoco = " in msg and "F_housner = " in msg
    # Passed criteria are listed too, with their figures.
    assert "[PASS] P[overturn]: mujoco 0.200 (20/100" in msg and "housner 0.200 (20/100" in msg
    assert "[PASS] usable records: mujoco 100, housner 100; need >= 20 each" in msg
    assert "[PASS] failed runs: mujoco 0, housner 0; allowed <= 0 each" in msg
    assert isinstance(info.value, AssertionError)
    assert [c.name for c in info.value.result.failed] == ["KS distance"]


def test_overturn_fraction_difference_fails(base):
    more = agreeing(base)
    rocking = np.flatnonzero(np.isfinite(more))
    more[rocking[:15]] = INF  # 15 more records overturn: 35 % against 20 %
    df = table({"housner": base, "mujoco": more})
    with pytest.raises(CDFAgreementError) as info:
        assert_cdf_agreement(df, "mujoco", "housner", ks_max=None, overturn_tol=0.08)
    msg = str(info.value)
    assert "[FAIL] P[overturn]: mujoco 0.350 (35/100, 95% CI" in msg
    assert "housner 0.200 (20/100, 95% CI" in msg
    assert "|difference| 0.150; limit overturn_tol = 0.08; exceeded by 0.07" in msg
    assert "KS distance" not in msg  # ks_max=None: not checked, not listed
    # The same table passes a looser tolerance.
    assert assert_cdf_agreement(df, "mujoco", "housner", ks_max=None, overturn_tol=0.16).passed


def test_percentile_criterion_fails_with_both_values(base):
    up = np.where(np.isinf(base), INF, base + 0.12)
    df = table({"housner": base, "mujoco": up})
    p_ref = stats.percentiles(base, [50], n_boot=0).value[0]
    p_eng = stats.percentiles(up, [50], n_boot=0).value[0]
    assert p_eng - p_ref == pytest.approx(0.12)
    with pytest.raises(CDFAgreementError) as info:
        assert_cdf_agreement(df, "mujoco", "housner", ks_max=None, percentiles={50: 0.1, 75: 0.2})
    msg = str(info.value)
    assert f"[FAIL] 50th percentile of theta_max/alpha: mujoco {p_eng:.3f}, housner {p_ref:.3f}" in msg
    assert "|difference| 0.120; limit percentiles[50] = 0.1; exceeded by 0.02" in msg
    assert "[PASS] 75th percentile of theta_max/alpha" in msg
    assert "FAILED 1 of 5 criteria" in msg


def test_percentile_where_only_one_side_overturns_fails():
    ref = np.concatenate([np.linspace(0.2, 0.9, 80), np.full(20, INF)])
    eng = np.concatenate([np.linspace(0.2, 0.9, 70), np.full(30, INF)])
    df = table({"housner": ref, "pybullet": eng})
    with pytest.raises(CDFAgreementError) as info:
        assert_cdf_agreement(df, "pybullet", ks_max=None, overturn_tol=None, percentiles={75: 0.1, 90: 0.1})
    msg = str(info.value)
    assert "[FAIL] 75th percentile of theta_max/alpha: pybullet overturn, housner 0." in msg
    assert "only one side overturns" in msg
    assert "[PASS] 90th percentile of theta_max/alpha: pybullet overturn, housner overturn; both overturn" in msg


def test_failed_runs_are_counted_named_and_excluded(base):
    df = table({"housner": base, "mujoco": agreeing(base)}, failed={"mujoco": [3, 17, 40, 41]})
    with pytest.raises(CDFAgreementError) as info:
        assert_cdf_agreement(df, "mujoco", "housner")
    msg = str(info.value)
    assert "[FAIL] failed runs: mujoco 4 (gm003: EngineError: contact diverged; gm017: EngineError" in msg
    assert "and 1 more), housner 0; allowed <= 0 each; 4 too many" in msg
    assert "[PASS] usable records: mujoco 96, housner 100" in msg
    assert "failed runs are excluded from every statistic above (mujoco: 4, housner: 0)" in msg
    # Allowing them, the statistics are those of the 96 usable records.
    res = assert_cdf_agreement(df, "mujoco", "housner", max_failed=None)
    keep = np.setdiff1d(np.arange(N), [3, 17, 40, 41])
    ks = next(c for c in res.criteria if c.name == "KS distance")
    assert ks.value == stats.ks_2samp(agreeing(base)[keep], base).distance


def test_too_few_records_fails(base):
    df = table({"housner": base[:12], "mujoco": agreeing(base)[:12]})
    with pytest.raises(CDFAgreementError, match=r"\[FAIL\] usable records: mujoco 12, housner 12; need >= 20 each; "):
        assert_cdf_agreement(df)
    # With 12 records the KS distance moves in steps of 1/12: 3 % noise already reorders two records.
    assert assert_cdf_agreement(df, min_records=10, ks_max=0.25).passed


def test_engine_with_only_failures_is_not_evaluated(base):
    df = table({"housner": base, "mujoco": base}, failed={"mujoco": list(range(N))})
    with pytest.raises(CDFAgreementError) as info:
        assert_cdf_agreement(df, max_failed=None, min_records=None)
    assert "[FAIL] KS distance: not evaluated: no usable records (mujoco 0, housner 100)" in str(info.value)


def test_message_points_to_the_report_next_to_the_results(tmp_path, base):
    df = table({"housner": base, "mujoco": np.where(np.isinf(base), INF, base * 2)})
    run = tmp_path / "run1"
    run.mkdir()
    df.to_parquet(run / "results.parquet")
    with pytest.raises(CDFAgreementError) as info:
        assert_cdf_agreement(run)
    assert f"(results: {(run / 'results.parquet').resolve()})" in str(info.value)
    assert f"No report.html next to the results; `housner report {run.resolve()}` renders" in str(info.value)
    assert info.value.report is None
    (run / "report.html").write_text("<html></html>")
    with pytest.raises(CDFAgreementError) as info:
        assert_cdf_agreement(run / "results.parquet")
    assert str(info.value).endswith(f"Report: {(run / 'report.html').resolve()}")
    with pytest.raises(CDFAgreementError, match="Report: elsewhere.html"):
        assert_cdf_agreement(load_results(run), report="elsewhere.html")


def test_accepts_the_runners_run_result(tmp_path, base):
    from housner.scenarios.runs.run import RunResult

    df = table({"housner": base, "mujoco": np.where(np.isinf(base), INF, base * 2)})
    (tmp_path / "report.html").write_text("<html></html>")
    run = RunResult(results=df, histories={}, motions=[], out=tmp_path)
    with pytest.raises(CDFAgreementError) as info:
        assert_cdf_agreement(run)
    assert f"(results: {tmp_path.resolve() / 'results.parquet'})" in str(info.value)
    assert info.value.report == tmp_path.resolve() / "report.html"


def test_load_results(tmp_path, base):
    df = table({"housner": base, "mujoco": agreeing(base)})
    run = tmp_path / "run"
    run.mkdir()
    df.to_parquet(run / "results.parquet")
    (run / "run.json").write_text(json.dumps({"scenario": "elcentro", "seed": 3}))
    got = load_results(run)
    pd.testing.assert_frame_equal(got, df)
    assert got.attrs["run"] == {"scenario": "elcentro", "seed": 3}
    assert np.isinf(got.theta_max_over_alpha).sum() == 2 * np.isinf(base).sum()  # +inf survives parquet
    df.to_csv(tmp_path / "r.csv", index=False)
    assert np.isinf(load_results(tmp_path / "r.csv").theta_max_over_alpha).sum() == 2 * np.isinf(base).sum()

    with pytest.raises(DataFileError, match="no such file"):
        load_results(tmp_path / "nope.parquet")
    with pytest.raises(DataFileError, match="no results.parquet in this directory"):
        load_results(tmp_path)
    df.drop(columns="status").to_parquet(tmp_path / "bad.parquet")
    with pytest.raises(DataFileError, match="missing column `status`") as info:
        load_results(tmp_path / "bad.parquet")
    assert info.value.column == "status"
    (tmp_path / "junk.parquet").write_text("not parquet")
    with pytest.raises(DataFileError, match="cannot read as parquet"):
        load_results(tmp_path / "junk.parquet")
    (run / "run.json").write_text('{"seed": 3,\n "x": }')
    with pytest.raises(DataFileError, match=r"run.json line 2: invalid JSON") as info:
        load_results(run)
    assert info.value.line == 2


def test_argument_errors(base):
    df = table({"housner": base, "mujoco": base})
    with pytest.raises(ValueError, match="unknown engine 'mujoc'; did you mean 'mujoco'"):
        assert_cdf_agreement(df, "mujoc")
    with pytest.raises(ValueError, match="`ks_max` must be a finite number >= 0"):
        assert_cdf_agreement(df, ks_max=-0.1)
    with pytest.raises(ValueError, match="`percentiles` must map"):
        assert_cdf_agreement(df, percentiles=[50])
    with pytest.raises(ValueError, match="both 'housner'"):
        assert_cdf_agreement(df, "housner", "housner")
    with pytest.raises(ValueError, match="more than one row for engine 'mujoco' and motion_id 0"):
        assert_cdf_agreement(pd.concat([df, df.iloc[[N]]]))


def test_record_agreement(base):
    good = agreeing(base)
    df = table({"housner": base, "mujoco": good})
    res = assert_record_agreement(df, "mujoco", rtol=0.1, atol=0.05, min_share=1.0, min_verdict_share=1.0)
    assert res.passed and res.criteria[0].name == "paired records"
    bad = good.copy()
    finite = np.flatnonzero(np.isfinite(bad))
    bad[finite[:30]] *= 1.5  # 30 records off by 50 %
    bad[finite[30]] = INF  # and one overturns that should not
    df = table({"housner": base, "mujoco": bad})
    with pytest.raises(RecordAgreementError) as info:
        assert_record_agreement(df, "mujoco", min_share=0.8, min_verdict_share=0.95)
    msg = str(info.value)
    assert (
        "[FAIL] records within atol=0.05 + rtol=0.1: 69 of 100 (69.0%); limit minimum share = 0.8; short by 0.11" in msg
    )
    assert "[PASS] same overturn verdict: 99 of 100 (99.0%)" in msg
    # The worst record first: the one with a different verdict.
    assert f"gm{finite[30]:03d} (motion {finite[30]}): overturn vs {base[finite[30]]:.3f}" in msg
    assert isinstance(info.value, CDFAgreementError)


# ----------------------------------------------------------------------------
# the pytest plugin
def _plugin_args() -> list[str]:
    """`-p housner.reports.pytest_plugin` unless the entry point already loads it (twice would clash)."""
    installed = any(ep.value == "housner.reports.pytest_plugin" for ep in entry_points(group="pytest11"))
    return [] if installed else ["-p", "housner.reports.pytest_plugin"]


@pytest.fixture(scope="session", autouse=True)
def _heavy_modules_imported(tmp_path_factory):
    """Import, before any `pytester` fixture is set up, what the in-process user sessions import.

    `pytester` removes at teardown every module imported during its test, and some extension
    modules (pandas' pyarrow extension types, scipy.stats) cannot be imported a second time.
    """
    path = tmp_path_factory.mktemp("warm") / "results.parquet"
    df = table({"housner": np.linspace(0.1, 1.0, 30), "mujoco": np.linspace(0.1, 1.0, 30)})
    df.to_parquet(path)
    assert_cdf_agreement(load_results(path), percentiles={50: 0.1})  # imports scipy.stats on the way
    proportions.overturn_probability([True, False], method="clopper-pearson")


def write_run(directory, df):
    """Write DIRECTORY/results.parquet."""
    directory.mkdir(parents=True, exist_ok=True)
    df.to_parquet(directory / "results.parquet")


USER_TESTS = """
from housner.reports.assertions.runs import assert_cdf_agreement

def test_engines_agree(housner_results):
    assert len(housner_results) == 200
    assert_cdf_agreement(housner_results, "mujoco", "housner", percentiles={50: 0.1})

def test_factory(housner_results_factory, housner_results):
    again = housner_results_factory()
    again.loc[:, "engine"] = "changed"  # a copy: does not touch other tests' tables
    assert set(housner_results.engine) == {"housner", "mujoco"}
"""


def test_plugin_loads_results_given_on_the_command_line(pytester, tmp_path, base):
    write_run(tmp_path, table({"housner": base, "mujoco": agreeing(base)}))
    pytester.makepyfile(USER_TESTS)
    # A fresh interpreter, as a user's CI would run it.
    result = pytester.runpytest_subprocess(*_plugin_args(), f"--housner-results={tmp_path}")
    result.assert_outcomes(passed=2)
    result.stdout.fnmatch_lines([f"housner results: {tmp_path}"])


def test_plugin_reads_the_environment_and_reports_failures(pytester, tmp_path, base, monkeypatch):
    write_run(tmp_path, table({"housner": base, "mujoco": np.where(np.isinf(base), INF, base * 1.5)}))
    monkeypatch.setenv("HOUSNER_RESULTS", str(tmp_path / "results.parquet"))
    pytester.makepyfile(USER_TESTS)
    result = pytester.runpytest(*_plugin_args())
    result.assert_outcomes(passed=1, failed=1)
    result.stdout.fnmatch_lines(["*CDFAgreementError: CDF agreement of 'mujoco' with 'housner': FAILED*"])
    result.stdout.fnmatch_lines(["*[[]FAIL[]] KS distance: D = *"])


def test_plugin_reads_the_ini_option_relative_to_the_rootdir(pytester, base, monkeypatch):
    monkeypatch.delenv("HOUSNER_RESULTS", raising=False)
    write_run(pytester.path / "runs" / "a", table({"housner": base, "mujoco": agreeing(base)}))
    pytester.makeini("[pytest]\nhousner_results = runs/a\n")
    pytester.makepyfile(USER_TESTS)
    result = pytester.runpytest(*_plugin_args())
    result.assert_outcomes(passed=2)


def test_plugin_skips_without_a_path_and_errors_on_a_bad_one(pytester, monkeypatch):
    monkeypatch.delenv("HOUSNER_RESULTS", raising=False)
    pytester.makepyfile(USER_TESTS)
    result = pytester.runpytest(*_plugin_args(), "-rs")
    result.assert_outcomes(skipped=2)
    result.stdout.fnmatch_lines(["*no housner results given: pass --housner-results PATH*HOUSNER_RESULTS=PATH*"])
    result = pytester.runpytest(*_plugin_args(), "--housner-results=missing-run")
    result.assert_outcomes(errors=2)
    result.stdout.fnmatch_lines(["*DataFileError*missing-run: no such file or directory*"])


def test_plugin_imports_nothing_heavy():
    code = (
        "import sys, housner.reports.pytest_plugin\n"
        "print([m for m in ('numpy', 'pandas', 'scipy', 'pyarrow', 'housner.motion') if m in sys.modules])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
