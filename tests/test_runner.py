"""The shared runner: rows per (engine, motion), failures kept apart, cache, process pool and Dask."""

import json
import math

import numpy as np
import pandas as pd
import pytest

import housner
from housner import GroundMotion, Specimen
from housner.engines.analytic import HousnerEngine
from housner.engines.base import ENGINES, register_engine
from housner.scenarios.execution.runner import run_engines
from housner.scenarios.runs.run import run_scenario

SPEC = Specimen.bachmann2017()


def motions(n=4, seed=1):
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        t = np.arange(0, 3.0, 0.002)
        a = 2.5 * np.sin(2 * np.pi * 2.0 * t + rng.uniform(0, 6)) * np.exp(-((t - 1.0) ** 2))
        out.append(GroundMotion(a, 0.002, name=f"m{i}"))
    return out


@register_engine("failing-housner")
class FailingEngine(HousnerEngine):
    """The analytic engine, except that it fails on motions named 'm1' (to test error handling)."""

    def _simulate(self, specimen, motion, effects):
        if motion.name == "m1":
            raise RuntimeError("solver diverged on purpose")
        return super()._simulate(specimen, motion, effects)


@pytest.fixture(autouse=True)
def _cleanup_registry():
    yield
    ENGINES.setdefault("failing-housner", FailingEngine)


def test_rows_and_failures_kept_apart(tmp_path):
    ms = motions()
    df, hist, info = run_engines(
        SPEC, ms, {"housner": {}, "failing-housner": {}}, jobs=1, cache_dir=tmp_path, progress=False
    )
    assert list(df.columns[:4]) == ["engine", "motion_id", "motion_name", "theta_max_over_alpha"]
    assert len(df) == 8
    bad = df[df.status == "failed"]
    assert list(zip(bad.engine, bad.motion_id, strict=True)) == [("failing-housner", 1)]
    assert "solver diverged on purpose" in bad.error.iloc[0]
    assert math.isnan(bad.theta_max_over_alpha.iloc[0])
    good = df[df.status == "ok"]
    assert len(good) == 7
    # The failing engine is the analytic one elsewhere: identical results on the other records.
    a = df[df.engine == "housner"].set_index("motion_id").theta_max_over_alpha
    b = df[(df.engine == "failing-housner") & (df.status == "ok")].set_index("motion_id").theta_max_over_alpha
    assert np.array_equal(a.loc[b.index].to_numpy(), b.to_numpy())
    assert set(hist) == {("housner", i) for i in range(4)} | {("failing-housner", i) for i in (0, 2, 3)}
    assert len(hist[("housner", 0)]) == ms[0].n


def test_cache_reuses_results(tmp_path):
    ms = motions()
    df1, _, _ = run_engines(SPEC, ms, {"housner": {}}, jobs=1, cache_dir=tmp_path, progress=False)
    df2, h2, info = run_engines(SPEC, ms, {"housner": {}}, jobs=1, cache_dir=tmp_path, progress=False)
    assert info["housner"]["cached"] == 4 and df2.cached.all() and not df1.cached.any()
    pd.testing.assert_series_equal(df1.theta_max_over_alpha, df2.theta_max_over_alpha)
    # Another setting is another key: nothing reused.
    _, _, info3 = run_engines(SPEC, ms, {"housner": {"r": 0.9}}, jobs=1, cache_dir=tmp_path, progress=False)
    assert info3["housner"]["cached"] == 0


def test_a_run_says_when_and_from_where_it_reuses_cached_results(tmp_path, capsys, monkeypatch):
    """A fresh checkout reading a cache other checkouts filled says so, names the folder and what the key holds."""
    from housner.scenarios.execution import cache

    ms = motions()
    run_engines(SPEC, ms[:2], {"housner": {}}, jobs=1, cache_dir=tmp_path, progress=True)
    assert "reusing" not in capsys.readouterr().err  # nothing cached yet: nothing said
    run_engines(SPEC, ms, {"housner": {}}, jobs=1, cache_dir=tmp_path, progress=True)
    err = capsys.readouterr().err
    assert f"reusing 2 of 4 records from the result cache in {tmp_path}" in err and "--no-cache" in err
    assert f"housner {housner.__version__}" in err and cache.code_version() in err
    # the version is part of the key: another version reuses nothing
    monkeypatch.setattr(cache, "_CODE_VERSION", None)
    monkeypatch.setattr(housner, "__version__", housner.__version__ + ".post1")
    _, _, info = run_engines(SPEC, ms, {"housner": {}}, jobs=1, cache_dir=tmp_path, progress=False)
    assert info["housner"]["cached"] == 0


def test_process_pool_matches_in_process(tmp_path):
    ms = motions(6)
    d1, h1, _ = run_engines(SPEC, ms, {"housner": {}}, jobs=1, use_cache=False, progress=False)
    d2, h2, _ = run_engines(SPEC, ms, {"housner": {}}, jobs=2, use_cache=False, progress=False, chunk_size=2)
    assert np.array_equal(d1.theta_max_over_alpha.to_numpy(), d2.theta_max_over_alpha.to_numpy())
    assert all(np.array_equal(h1[k], h2[k]) for k in h1)


def test_dask_cluster_matches(tmp_path):
    distributed = pytest.importorskip("distributed")
    ms = motions(3)
    d1, _, _ = run_engines(SPEC, ms, {"housner": {}}, jobs=1, use_cache=False, progress=False)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as lc:
        with distributed.Client(lc) as client:
            d2, _, _ = run_engines(SPEC, ms, {"housner": {}}, scheduler=client, use_cache=False, progress=False)
            d3, _, _ = run_engines(
                SPEC, ms, {"housner": {}}, scheduler=lc.scheduler_address, use_cache=False, progress=False
            )
    assert np.array_equal(d1.theta_max_over_alpha.to_numpy(), d2.theta_max_over_alpha.to_numpy())
    assert np.array_equal(d1.theta_max_over_alpha.to_numpy(), d3.theta_max_over_alpha.to_numpy())


def test_run_scenario_writes_the_run_directory(tmp_path):
    run = run_scenario(
        "free-vibration",
        engines=["housner"],
        out=tmp_path / "run",
        jobs=1,
        cache_dir=tmp_path / "cache",
        progress=False,
    )
    out = tmp_path / "run"
    df = pd.read_parquet(out / "results.parquet")
    assert len(df) == 8 and (df.status == "ok").all()
    # Free rocking from below alpha never overturns and peaks at the release angle.
    assert not df.overturned.any()
    np.testing.assert_allclose(df.theta_max_over_alpha, [0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9], rtol=1e-9)
    h = pd.read_parquet(out / "histories.parquet")
    assert set(h.motion_id) == set(range(8))
    meta = json.loads((out / "run.json").read_text())
    assert meta["engines"]["housner"]["settings"] == {"r": None, "substeps": None}
    assert meta["specimen"]["p_1_s"] == pytest.approx(4.8883)
    assert run.failures.empty


# ----------------------------------------------------------------------------
# cache integrity: every entry carries its key and a SHA-256 of its payload
def _entry(cache_dir, motion):
    from housner.engines.base import get_engine
    from housner.scenarios.execution.cache import cache_key

    eng = get_engine("housner")
    k = cache_key(SPEC, motion, "housner", eng.settings(), eng.version())
    return cache_dir / k[:2] / f"{k}.npz"


def test_cache_entry_copied_over_another_key_is_detected_and_recomputed(tmp_path, caplog):
    import shutil

    ms = motions()
    df1, h1, _ = run_engines(SPEC, ms, {"housner": {}}, jobs=1, cache_dir=tmp_path, progress=False)
    # Motion 0 overturns, motion 3 does not: serving 3's entry for 0 would change the results.
    assert df1.theta_max_over_alpha[0] == np.inf and df1.theta_max_over_alpha[3] < 1
    shutil.copyfile(_entry(tmp_path, ms[3]), _entry(tmp_path, ms[0]))  # a valid entry, under the wrong key
    with caplog.at_level("WARNING", logger="housner.runner"):
        df2, h2, info = run_engines(SPEC, ms, {"housner": {}}, jobs=1, cache_dir=tmp_path, progress=False)
    assert info["housner"]["cache_rejected"] == 1 and info["housner"]["cached"] == 3
    assert list(df2.cached) == [False, True, True, True]
    assert any("another key" in r.getMessage() and "motion 0" in r.getMessage() for r in caplog.records)
    pd.testing.assert_series_equal(df1.theta_max_over_alpha, df2.theta_max_over_alpha)
    assert np.array_equal(h1[("housner", 0)], h2[("housner", 0)])
    # The recomputed entry was written back, correct: the next run trusts all four.
    _, _, info3 = run_engines(SPEC, ms, {"housner": {}}, jobs=1, cache_dir=tmp_path, progress=False)
    assert info3["housner"]["cached"] == 4 and info3["housner"]["cache_rejected"] == 0


def test_cache_entry_edited_by_hand_fails_its_checksum(tmp_path, caplog):
    ms = motions()
    df1, _, _ = run_engines(SPEC, ms, {"housner": {}}, jobs=1, cache_dir=tmp_path, progress=False)
    path = _entry(tmp_path, ms[2])
    with np.load(path, allow_pickle=False) as z:
        theta, row = z["theta"], json.loads(str(z["row"]))
    row["theta_max_over_alpha"], row["n_impacts"] = "9.99", 12345  # the sha256 field is left as it was
    np.savez_compressed(path, theta=theta, row=np.array(json.dumps(row)))
    garbage = _entry(tmp_path, ms[3])
    garbage.write_bytes(b"not an npz file")  # a truncated or foreign file
    with caplog.at_level("WARNING", logger="housner.runner"):
        df2, _, info = run_engines(SPEC, ms, {"housner": {}}, jobs=1, cache_dir=tmp_path, progress=False)
    assert info["housner"]["cache_rejected"] == 2 and info["housner"]["cached"] == 2
    messages = " | ".join(r.getMessage() for r in caplog.records)
    assert "checksum" in messages and "motion 2" in messages and "unreadable" in messages
    assert df2.theta_max_over_alpha[2] == df1.theta_max_over_alpha[2] != 9.99
    assert df2.n_impacts[2] == df1.n_impacts[2] != 12345
    assert list(df2.cached) == [True, True, False, False]


def test_bad_jobs_and_chunk_size_are_refused():
    with pytest.raises(ValueError, match="`jobs` must be a positive integer"):
        run_engines(SPEC, motions(1), {"housner": {}}, jobs=-2, use_cache=False, progress=False)
    with pytest.raises(ValueError, match="`chunk_size`"):
        run_engines(SPEC, motions(1), {"housner": {}}, jobs=1, chunk_size=0, use_cache=False, progress=False)


@register_engine("nan-housner")
class NanEngine(HousnerEngine):
    """The analytic engine, except that its history on motion 'm2' holds a NaN (a diverged solver)."""

    def _simulate(self, specimen, motion, effects):
        resp = super()._simulate(specimen, motion, effects)
        if motion.name == "m2":
            resp.theta[len(resp.theta) // 2] = math.nan
        return resp


def test_the_engine_base_checks_every_response_and_the_runner_keeps_the_others(tmp_path):
    from housner.engines.base import check_response
    from housner.errors import EngineError

    ms = motions()
    with pytest.raises(EngineError, match="engine 'nan-housner' returned a non-finite theta history on motion 'm2'"):
        NanEngine().simulate(SPEC, ms[2])
    resp = HousnerEngine().simulate(SPEC, ms[0])
    assert check_response(resp, "housner", ms[0]) is resp
    df, _, _ = run_engines(SPEC, ms, {"nan-housner": {}}, jobs=1, cache_dir=tmp_path, progress=False)
    assert list(df.status) == ["ok", "ok", "failed", "ok"]
    assert "non-finite theta history on motion 'm2'" in df.error[2]
    ENGINES.setdefault("nan-housner", NanEngine)


def test_guided_chunks_end_the_run_on_short_chunks():
    """The last n_workers * size records of an engine that runs record by record go out in quarter chunks:
    a run does not end with one worker on a whole chunk of slow records while the others idle."""
    from housner.scenarios.execution.runner import _parts

    parts = _parts(list(range(100)), 10, 2, guided=True)
    assert sum(parts, []) == list(range(100))  # every record once, in order
    assert [len(p) for p in parts[:8]] == [10] * 8 and all(len(p) <= 3 for p in parts[8:])
    assert [len(p) for p in _parts(list(range(100)), 10, 2, guided=False)] == [10] * 10
    assert [len(p) for p in _parts(list(range(100)), 10, 1, guided=True)] == [10] * 10  # one worker: no tail


def test_options_say_where_the_cache_is_and_how_many_workers_start(tmp_path, monkeypatch):
    """The one place the runner and the run's error measurement take the cache folder and the worker count from."""
    import os

    from housner.scenarios.execution.options import RunOptions

    monkeypatch.setenv("HOUSNER_CACHE_DIR", str(tmp_path / "env"))
    assert RunOptions().cache_folder() == tmp_path / "env"
    assert RunOptions(cache_dir=tmp_path / "mine").cache_folder() == tmp_path / "mine"
    assert RunOptions(cache_dir=tmp_path / "mine", use_cache=False).cache_folder() is None
    assert RunOptions(jobs=3).local_jobs() == 3 and RunOptions().local_jobs() == (os.cpu_count() or 1)
