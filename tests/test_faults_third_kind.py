"""Faults of the third kind (issue 41, parts 3-5): non-finite models, a damaged kernel cache, a torn run directory.

Each case is tried as a careless or hostile colleague would: a plugin effect whose histories are all
NaN, added by hand and offered as a candidate; the generated kernel files truncated and numba's
cache files overwritten with garbage (then simulated again in a new process, as the next run would);
a run directory holding another run's results.parquet, or whose writing was killed half-way.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from housner import Specimen
from housner.cli import main
from housner.effects import EFFECTS, load_plugin, make_effect
from housner.reports.diagnosis.reason_text import reason_text
from housner.scenarios.campaigns.campaign import load_campaign
from housner.scenarios.diagnosis.diagnose import diagnose
from housner.scenarios.diagnosis.selection.reasons import Reason
from housner.scenarios.diagnosis.selection.record_scoring import NonFiniteHistory, NonFiniteScore, Scorer, check_finite
from housner.scenarios.execution.run_meta import RunMeta
from housner.scenarios.execution.rundir import (
    IncompleteRunError,
    UnverifiedRunWarning,
    load_results,
    provenance,
    write_run,
)
from housner.scenarios.execution.runner import run_engines
from housner.scenarios.motions import elcentro

ROOT = Path(__file__).resolve().parent.parent
CAMPAIGN = ROOT / "examples" / "campaigns" / "pivot-friction"

NAN_EFFECT = '''
"""An effect whose moment is NaN once the block rocks: every history it makes is NaN."""

from dataclasses import dataclass

from numba import njit

from housner.effects import Effect, MomentTerm, register_effect


@njit(cache=True)
def nan_moment(phi, w, t, a, v, s, alpha, p2, q):
    return q[0] * float("nan")


@register_effect
@dataclass(frozen=True)
class NanAlways(Effect):
    name = "nan_always"
    params = {}

    def terms(self, params, specimen):
        return (MomentTerm(nan_moment, (1.0,), at_rest=False),)
'''


@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory):
    """One cache for the module: the NaN effect's kernel is compiled once."""
    return tmp_path_factory.mktemp("cache")


@pytest.fixture
def nan_plugin(tmp_path_factory, cache_dir, monkeypatch):
    """The NaN effect's file, loaded (and unregistered after the test: other tests enumerate the registry)."""
    monkeypatch.setenv("HOUSNER_CACHE_DIR", str(cache_dir))
    monkeypatch.delenv("HOUSNER_KERNEL_DIR", raising=False)
    path = tmp_path_factory.getbasetemp() / "nan_effect.py"
    path.write_text(NAN_EFFECT)
    before = dict(EFFECTS)
    load_plugin(path)
    yield path
    EFFECTS.clear()
    EFFECTS.update(before)


# ----------------------------------------------------------------------------
# 3. no verdict from non-finite numbers
def test_scorer_refuses_a_model_with_non_finite_histories_by_name(nan_plugin):
    camp = load_campaign(CAMPAIGN)
    sc = Scorer(camp, [r.id for r in camp.records])
    with pytest.raises(NonFiniteHistory, match=r"nan_always\(\) gives a non-finite theta history on record 'fv01'"):
        sc.errors([make_effect("nan_always")])
    assert np.all(np.isfinite(sc.errors([])))  # the plain model still scores


def test_nan_effect_added_by_hand_stops_the_diagnosis_with_one_line(nan_plugin, capsys):
    # before: `verdict: explained ... nan_always explains it`, exit 0, from a floor of clipped errors
    argv = ["diagnose", str(CAMPAIGN), "--plugin", str(nan_plugin), "--add", "nan_always", "--effects", "none", "-q"]
    status = main(argv)
    out, err = capsys.readouterr()
    assert status == 2  # the model handed in is at fault: bad input, as a bad plugin is
    assert "verdict" not in out
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err
    assert "effect 'nan_always', added by hand, gives a non-finite theta history on record 'fv01'" in lines[0]


def test_nan_candidate_is_rejected_in_its_round(nan_plugin):
    lines: list[str] = []
    diag = diagnose(CAMPAIGN, effects=["nan_always"], compare_steps=False, n_replicas=2, progress=lines.append)
    (cand,) = diag.rounds[0]
    assert cand.effect == "nan_always" and not cand.significant and math.isnan(cand.heldout_error)
    assert cand.reason == Reason("rejected_not_finite", {"record": "fv01"})
    assert reason_text(cand.reason).startswith("rejected: its theta history is not finite on record 'fv01'")
    assert any("nan_always" in ln and "rejected" in ln for ln in lines)  # a line of the progress
    assert diag.selected == [] and diag.status != "explained"
    assert all(np.all(np.isfinite(f.mean)) for f in diag.floors)


def test_a_non_finite_score_or_floor_stops_with_one_line(monkeypatch):
    with pytest.raises(NonFiniteScore, match=r"the correct-model floor is not finite \(nan\) on record 'b'"):
        check_finite("the correct-model floor", [0.1, math.nan], ["a", "b"])
    check_finite("x", [0.0, 1.0])
    # a score that comes out NaN from finite histories: stopped, not judged
    import housner.scenarios.diagnosis.selection.record_scoring as scoring

    camp = load_campaign(CAMPAIGN)
    sc = Scorer(camp, [r.id for r in camp.records][:4])
    monkeypatch.setattr(scoring, "scored_error", lambda *a, **k: math.nan)
    with pytest.raises(NonFiniteScore, match="time-history error of the plain Housner model is not finite"):
        sc.errors([])


# ----------------------------------------------------------------------------
# 4. caches that heal
SIMULATE = textwrap.dedent(
    """
    import json, sys, hashlib
    from pathlib import Path
    from housner import GroundMotion, Specimen
    from housner.effects import apply_effects, make_effect, simulate_with_effects
    from housner.effects.codegen import kernel_cache_repairs, kernel_module

    spec = Specimen.bachmann2017()
    mo = GroundMotion.free_vibration(0.5 * spec.alpha, 2.0)
    fx = [make_effect("rotational_damping", c=0.4)]
    mod = kernel_module(apply_effects(spec, mo, fx, prefer_terms=True).terms.structure)
    if sys.argv[1:] == ["garble-after-load"]:  # damaged after this process checked it: numba fails at the call
        for p in Path(mod.__file__).parent.glob("__pycache__/*.nb?"):
            p.write_bytes(b"garbage" * 50)
    res = simulate_with_effects(spec, mo, fx, prefer_terms=True)
    print(json.dumps({"theta": hashlib.sha256(res.theta.tobytes()).hexdigest(), "repairs": kernel_cache_repairs(),
                      "kernel": mod.__file__}))
    """
)


def _simulate(cache: Path, *args: str) -> dict:
    """One simulation with a term kernel in a new process (as the next run would), with ``cache`` as its cache."""
    env = {k: v for k, v in os.environ.items() if k != "HOUSNER_KERNEL_DIR"}
    env["HOUSNER_CACHE_DIR"] = str(cache)
    res = subprocess.run([sys.executable, "-c", SIMULATE, *args], capture_output=True, text=True, env=env, timeout=300)
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def kernel_cache(tmp_path_factory):
    """A cache holding one term kernel, compiled once, and the first simulation's answer."""
    cache = tmp_path_factory.mktemp("kernel-cache")
    first = _simulate(cache)
    assert first["repairs"] == {"kernel_files": 0, "numba_caches": 0, "numba_retries": 0}
    return cache, first


def _fresh_copy(kernel_cache, tmp_path) -> tuple[Path, dict, Path]:
    cache, first = kernel_cache
    copy = tmp_path / "cache"
    shutil.copytree(cache, copy)
    return copy, first, copy / "kernels"


def test_truncated_kernel_file_is_rebuilt_and_counted(kernel_cache, tmp_path):
    cache, first, kdir = _fresh_copy(kernel_cache, tmp_path)
    files = sorted(kdir.glob("housner_terms_*.py"))
    assert len(files) == 2
    whole = {p: p.read_bytes() for p in files}
    for p in files:
        p.write_bytes(whole[p][:3000])  # before: a SyntaxError in the generated file on every later run
    again = _simulate(cache)
    assert again["theta"] == first["theta"]
    assert again["repairs"]["kernel_files"] == 2
    assert all(p.read_bytes() == whole[p] for p in files)
    assert _simulate(cache)["repairs"]["kernel_files"] == 0  # healed for good
    assert not list(kdir.glob("*.tmp"))  # written atomically: nothing half-written left


@pytest.mark.parametrize("suffix", ["nbi", "nbc"])
def test_garbled_numba_cache_files_are_removed_and_recompiled(kernel_cache, tmp_path, suffix):
    cache, first, kdir = _fresh_copy(kernel_cache, tmp_path)
    garbled = sorted((kdir / "__pycache__").glob(f"housner_terms_*.{suffix}"))
    assert garbled
    for p in garbled:
        p.write_bytes(os.urandom(400))  # before: UnpicklingError on every later run
    again = _simulate(cache)
    assert again["theta"] == first["theta"]
    assert again["repairs"]["numba_caches"] >= 1 and again["repairs"]["kernel_files"] == 0
    assert _simulate(cache)["repairs"] == {"kernel_files": 0, "numba_caches": 0, "numba_retries": 0}


def test_numba_failing_to_load_at_the_call_is_retried_without_its_cache(kernel_cache, tmp_path):
    cache, first, _kdir = _fresh_copy(kernel_cache, tmp_path)
    again = _simulate(cache, "garble-after-load")
    assert again["theta"] == first["theta"]
    assert again["repairs"]["numba_retries"] == 1
    assert _simulate(cache)["repairs"] == {"kernel_files": 0, "numba_caches": 0, "numba_retries": 0}


# ----------------------------------------------------------------------------
# 5. atomic run directories
def _run(out: Path, n: int, scale: float = 1.0, histories: bool = True) -> Path:
    """A small run directory written by write_run (``n`` motions), as `housner run` writes one."""
    spec = Specimen.bachmann2017()
    base = elcentro().to_model_scale(10).with_duration(4.0)
    motions = [base.scaled(amplitude=scale * (0.6 + 0.1 * i)) for i in range(n)]
    df, hist, info = run_engines(spec, motions, {"housner": {}}, jobs=1, use_cache=False, progress=False)
    meta = {
        "scenario": {"name": out.name, "description": "test run", "motions": {"source": "record"}},
        "specimen": spec.describe(),
        "motions": {"source": "record", "S": 1.0},
        "n_motions": n,
        "engines": info,
        "analysis": {"reference": "housner"},
        "failures": [],
        "wall_s": {"total": 1.0},
        "provenance": provenance(),
    }
    write_run(out, df, hist if histories else {}, motions, RunMeta.from_json(meta))
    return out


def test_a_run_directory_mixing_two_runs_is_refused_with_one_line(tmp_path, capsys):
    a, b = _run(tmp_path / "a", 4), _run(tmp_path / "b", 3, scale=1.3)
    meta = json.loads((a / "run.json").read_text())
    assert meta["complete"] is True and set(meta["content"]) == {"results.parquet", "histories.parquet", "motions.npz"}
    assert main(["report", str(a)]) == 0
    capsys.readouterr()
    shutil.copy(b / "results.parquet", a / "results.parquet")  # before: the report took it, exit 0
    status = main(["report", str(a)])
    err = capsys.readouterr().err
    assert status != 0
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err
    assert "incomplete or mixes two runs: results.parquet does not match run.json; run again" in lines[0]
    with pytest.raises(IncompleteRunError, match="results.parquet does not match run.json"):
        load_results(a)


def test_a_run_killed_while_moving_its_files_is_refused(tmp_path, monkeypatch):
    out = _run(tmp_path / "run", 4)
    import housner.scenarios.execution.rundir as rundir

    real, calls = os.replace, []

    def killed(src, dst):
        calls.append(Path(dst).name)
        if len(calls) == 3:  # run.json marked incomplete, results.parquet moved: killed here
            raise KeyboardInterrupt
        return real(src, dst)

    monkeypatch.setattr(rundir.os, "replace", killed)
    with pytest.raises(KeyboardInterrupt):
        _run(out, 3, scale=1.3)
    monkeypatch.setattr(rundir.os, "replace", real)
    assert calls[:2] == ["run.json", "results.parquet"]
    with pytest.raises(IncompleteRunError, match="its writing did not finish"):
        load_results(out)
    assert not list(out.glob(".housner-run-*"))  # the temporary folder went with it
    _run(out, 3, scale=1.3)  # a rerun writes a whole run again
    assert len(load_results(out)) == 3


def test_stale_files_of_the_previous_run_go_and_old_runs_are_read_with_a_warning(tmp_path):
    out = _run(tmp_path / "run", 3)
    (out / "report.html").write_text("<html>the previous run's page</html>")
    _run(out, 2, histories=False)
    assert not (out / "histories.parquet").exists() and not (out / "report.html").exists()
    assert len(load_results(out)) == 2
    # another run's histories.parquet dropped in: not listed in run.json
    _run(tmp_path / "other", 2)
    shutil.copy(tmp_path / "other" / "histories.parquet", out / "histories.parquet")
    with pytest.raises(IncompleteRunError, match="histories.parquet is not listed in run.json"):
        load_results(out)
    # a run directory written before the marker: read, with a warning
    old = _run(tmp_path / "old", 2)
    meta = json.loads((old / "run.json").read_text())
    del meta["complete"], meta["content"]
    (old / "run.json").write_text(json.dumps(meta))
    with pytest.warns(UnverifiedRunWarning, match="written before runs carried a completion marker"):
        assert len(load_results(old)) == 2
    # a temporary folder of a writer that was killed (its process is gone) is cleaned up by the next write
    dead = out / ".housner-run-999999999-x"
    dead.mkdir()
    _run(out, 2)
    assert not dead.exists()
    assert isinstance(pd.read_parquet(out / "results.parquet"), pd.DataFrame)


RUN_WITH_EFFECT = textwrap.dedent(
    """
    import json, sys
    from housner import GroundMotion, Specimen
    from housner.effects import load_plugin, make_effect
    from housner.scenarios.execution.runner import run_engines

    load_plugin(sys.argv[2])  # the library's own effects need no generated kernel; a user's moment term does
    spec = Specimen.bachmann2017()
    motions = [GroundMotion.free_vibration(f * spec.alpha, 2.0) for f in (0.3, 0.5, 0.7, 0.4)]
    fx = (make_effect("pivot_friction", moment=0.05),)
    df, _, info = run_engines(spec, motions, {"housner": {}}, effects=fx, jobs=int(sys.argv[1]), use_cache=False,
                              progress=False)
    print(json.dumps({"ok": int((df.status == "ok").sum()), "repairs": info["housner"]["kernel_cache_repairs"],
                      "theta": [round(v, 12) for v in df.theta_max_over_alpha]}))
    """
)


@pytest.mark.parametrize("jobs", [1, 2])
def test_kernel_repairs_made_by_the_processes_of_a_run_are_counted_in_its_info(kernel_cache, tmp_path, jobs):
    cache, _, kdir = _fresh_copy(kernel_cache, tmp_path)
    env = {k: v for k, v in os.environ.items() if k != "HOUSNER_KERNEL_DIR"}
    env["HOUSNER_CACHE_DIR"] = str(cache)

    def run() -> dict:
        plugin = Path(__file__).resolve().parents[1] / "examples" / "effects" / "pivot_friction.py"
        res = subprocess.run(
            [sys.executable, "-c", RUN_WITH_EFFECT, str(jobs), str(plugin)],
            capture_output=True,
            text=True,
            env=env,
            timeout=300,
        )
        assert res.returncode == 0, res.stderr
        return json.loads(res.stdout.strip().splitlines()[-1])

    healthy = run()
    assert healthy["ok"] == 4 and healthy["repairs"] == 0
    files = sorted(kdir.glob("housner_terms_*.py"))
    assert len(files) > 2  # the fixture's kernel, and the plugin's that the healthy run generated
    for p in files:
        p.write_bytes(p.read_bytes()[:2000])
    damaged = run()
    # every record computed as before, and the run's info counts the damaged kernel files rebuilt (the
    # plugin's; whichever process of the run loaded each first, the planning process or a worker)
    assert damaged["ok"] == 4 and damaged["theta"] == healthy["theta"]
    assert damaged["repairs"] >= 1
    assert run()["repairs"] == 0  # healed
