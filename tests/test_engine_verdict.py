"""An engine's verdict against the reference: PASS/FAIL on enough records, inconclusive on tiny sets,
with the record-by-record verdict against the chaos floor beside it; `housner run` prints it.

The rule (housner.scenarios.runs.verdicts.MIN_RECORDS): one record moves the KS distance by 1/n, so a distribution
verdict against the 0.15 tolerance needs n >= 3 / 0.15 = 20 records; a failed record fails at any size.
"""

from __future__ import annotations

import subprocess
import sys

import pandas as pd
import pytest

from housner.scenarios.runs.chaos import ChaosFloor
from housner.scenarios.runs.verdicts import MIN_RECORDS, engine_verdict
from housner.stats import KS_MAX


def _row(ks, dp, n_ok, n_failed=0, share=0.5, n_paired=None):
    return pd.Series({"ks_distance": ks, "overturn_diff": dp, "n_ok": n_ok, "n_failed": n_failed,
                      "agreement_share": share, "n_paired": n_ok if n_paired is None else n_paired})  # fmt: skip


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
        assert "needs 20" in v.line()


def test_record_by_record_verdict_sits_beside_the_distribution_one():
    shares = {"r+": 0.6, "r-": 0.66, "p+": 0.7, "p-": 0.68}
    floor = ChaosFloor(shares, shares, 0.66, 0.6, 0.7, 100, engine="mujoco", eps_r=0.002, eps_p=0.001)
    below = engine_verdict(_row(0.05, 0.0, 100, share=0.28), floor)  # MuJoCo on elcentro: PASS, 28 % vs 66 %
    assert below.status == "PASS" and below.below_floor is True and "below the floor" in below.line()
    at = engine_verdict(_row(0.05, 0.0, 100, share=0.64), floor)
    assert at.below_floor is False and "at the floor" in at.line()


def test_run_prints_each_engines_verdict_and_check_passes_an_inconclusive_one(tmp_path):
    cmd = [sys.executable, "-m", "housner.cli", "run", "elcentro", "--engines", "housner,mujoco", "--n-motions", "3",
           "--out", str(tmp_path / "run"), "--no-report", "--check", "-q", "--jobs", "1"]  # fmt: skip
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    line = next(x for x in res.stdout.splitlines() if x.strip().startswith("mujoco") and ":" in x)
    assert "inconclusive: only 3 records" in line and "record by record" in line
