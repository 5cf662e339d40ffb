"""An engine's one verdict against the reference: the distribution test (PASS/FAIL on enough records, inconclusive on
tiny sets) and the record-by-record agreement against the chaos floor, combined by one rule into AGREES, ENSEMBLE ONLY,
FAILS, INCONCLUSIVE or NO DATA; `housner run` prints it and `assert_verdict` asserts it.

The rule (housner.scenarios.runs.verdicts.MIN_RECORDS): one record moves the KS distance by 1/n, so a distribution
verdict against the 0.15 tolerance needs n >= 3 / 0.15 = 20 records; a failed record fails at any size.
"""

from __future__ import annotations

import subprocess

import pytest
from shared import run_command

from housner.scenarios.execution.tables import EngineSummary, Estimate
from housner.scenarios.runs.chaos import ChaosFloor
from housner.scenarios.runs.verdicts import MIN_RECORDS, engine_verdict
from housner.statistics.ensemble_stats import KS_MAX


def _row(ks, dp, n_ok, n_failed=0, share=0.5, n_paired=None):
    """An engine's summary with the figures the verdict reads (the rest NaN)."""
    nan = float("nan")
    return EngineSummary(
        n=n_ok + n_failed,
        n_failed=n_failed,
        n_ok=n_ok,
        percentiles={},
        p_overturn=Estimate(nan, nan, nan),
        ks_distance=ks,
        ks_pvalue=nan,
        wasserstein=nan,
        overturn_diff=dp,
        n_paired=float(n_ok if n_paired is None else n_paired),
        agreement_share=share,
        verdict_share=nan,
    )


def test_min_records_follows_from_the_tolerance():
    assert MIN_RECORDS == 20 and MIN_RECORDS * KS_MAX >= 3


@pytest.mark.parametrize(
    ("row", "status"),
    [
        (_row(0.05, 0.0, 100), "PASS"),
        (_row(0.18, 0.0, 100), "FAIL"),  # PyBullet on elcentro: KS 0.18 > 0.15
        (_row(0.05, 0.1, 100), "FAIL"),
        (_row(0.05, 0.0, 100, n_failed=1), "FAIL"),
        (_row(1.0, 0.0, 1), "inconclusive"),  # one record: KS is 0 or 1 whatever the engines do
        (_row(0.4, 0.2, 19), "inconclusive"),
        (_row(0.0, 0.0, 5, n_failed=1), "FAIL"),  # a failed record fails at any size
        (_row(float("nan"), 0.0, 0), "no data"),
    ],
)
def test_status(row, status):
    v = engine_verdict(row)
    assert v.status == status
    assert v.ok is {"PASS": True, "FAIL": False}.get(status)
    if status == "inconclusive":
        assert "needs 20" in v.line() and v.badge == "INCONCLUSIVE"


def _floor():
    shares = {"r+": 0.6, "r-": 0.66, "p+": 0.7, "p-": 0.68}
    return ChaosFloor(shares, shares, 0.66, 0.6, 0.7, 100, engine="mujoco", eps_r=0.002, eps_p=0.001)


def test_one_verdict_from_the_distribution_and_the_records():
    floor = _floor()  # the floor is the lowest perturbed share, 60 %
    below = engine_verdict(_row(0.05, 0.0, 100, share=0.28), floor)  # MuJoCo on elcentro: PASS, 28 % vs 60 %
    assert below.status == "PASS" and below.below_floor is True
    assert below.kind == "ensemble" and below.badge == "ENSEMBLE ONLY"
    assert "28% [20%, 37%] of records agree, chaos floor 60%" in below.line()  # the figure that decided it
    assert "not for one record's response" in below.line() and "below the floor" in below.figures()
    # 52/100: Wilson upper end 61.6 % reaches the 60 % floor: at the floor
    at = engine_verdict(_row(0.05, 0.0, 100, share=0.52), floor)
    assert at.below_floor is False and at.kind == "agrees" and at.badge == "AGREES"
    assert "good for ensembles and for single records" in at.line() and "at the floor" in at.figures()
    # a failed distribution test fails whatever the records say, and names the criterion that failed
    fails = engine_verdict(_row(0.18, 0.0, 100, share=0.9), floor)
    assert fails.kind == "fails" and "(KS 0.180 > 0.15)" in fails.line() and "good for neither" in fails.line()
    failed = engine_verdict(_row(0.05, 0.0, 100, n_failed=2, share=0.9), floor)
    assert failed.kind == "fails" and "records failed to run (2 failed records)" in failed.line()
    # no floor (the reference is not the analytic model): the distribution only, and it says records were not judged
    alone = engine_verdict(_row(0.05, 0.0, 100))
    assert alone.kind == "ensemble" and "not judged" in alone.line() and "(KS 0.050 <= 0.15)" in alone.line()
    assert engine_verdict(_row(float("nan"), 0.0, 0)).badge == "NO DATA"


def test_run_prints_each_engines_verdict_and_check_passes_an_inconclusive_one(tmp_path):
    cmd = run_command(tmp_path / "run", "housner,mujoco", 3, "--no-report", "--check", "-q", "--jobs", "1")
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    i = next(i for i, x in enumerate(lines) if x.strip().startswith("mujoco") and ":" in x)
    assert "INCONCLUSIVE: too few records for a verdict (only 3 records" in lines[i]
    assert "distribution test inconclusive" in lines[i + 1] and "record by record" in lines[i + 1]
    assert sum(x.startswith("verdict against") for x in lines) == 1


def test_a_run_with_one_engine_prints_no_verdict_heading(tmp_path):
    cmd = run_command(tmp_path / "run", "housner", 2, "--no-report", "-q", "--jobs", "1")
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    assert "verdict" not in res.stdout
