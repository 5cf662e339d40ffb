"""The shared scenario runner: every engine on the very same motions.

Work is split into chunks of (engine, motions) and run in a process pool (the
default), in this process (``jobs=1``), or on a Dask distributed cluster
(``scheduler=ADDRESS``). A record that fails in one engine becomes a row with
``status = "failed"`` and its error; the other results are kept. Results are
cached by content: specimen, motion samples, engine name, settings and version,
and the suite's code version.

Outputs in the run directory:

- ``results.parquet``: one row per (engine, motion) with ``engine``, ``motion_id``,
  ``motion_name``, ``theta_max_over_alpha`` (inf when overturned, NaN when failed),
  ``overturned``, ``n_impacts``, ``wall_s``, ``status``, ``error``, ``cached``;
- ``histories.parquet``: ``engine``, ``motion_id``, ``t`` [s], ``theta`` [rad];
- ``motions.npz``: the ensemble's accelerations [m/s^2] and steps [s];
- ``run.json``: scenario, specimen, engine settings and versions, seed, metadata
  (fitted RDK parameters), failures, wall time per engine, provenance.
"""

from __future__ import annotations

import concurrent.futures as cf
import hashlib
import json
import math
import multiprocessing as mp
import os
import platform
import subprocess
import sys
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from engines.base import engine_class, get_engine
from housner.motion import GroundMotion
from housner.specimen import Specimen
from scenarios.catalogue import Scenario, load_scenario

__all__ = ["RunResult", "run_engines", "run_scenario", "code_version", "default_cache_dir"]

RESULT_COLUMNS = [
    "engine",
    "motion_id",
    "motion_name",
    "theta_max_over_alpha",
    "overturned",
    "n_impacts",
    "wall_s",
    "status",
    "error",
    "cached",
]


def default_cache_dir() -> Path:
    """``$HOUSNER_CACHE_DIR`` or ``~/.cache/housner``."""
    env = os.environ.get("HOUSNER_CACHE_DIR")
    return Path(env) if env else Path.home() / ".cache" / "housner"


_CODE_VERSION: str | None = None


def code_version() -> str:
    """Hash of the suite's physics and engine sources (part of every cache key)."""
    global _CODE_VERSION
    if _CODE_VERSION is None:
        import engines
        import housner

        h = hashlib.sha256(housner.__version__.encode())
        for pkg in (housner, engines):
            root = Path(pkg.__file__).parent
            for f in sorted(root.rglob("*")):
                if f.suffix in (".py", ".xml", ".urdf") and "__pycache__" not in f.parts:
                    h.update(f.relative_to(root).as_posix().encode())
                    h.update(f.read_bytes())
        _CODE_VERSION = h.hexdigest()[:16]
    return _CODE_VERSION


def _jsonable(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if math.isfinite(v) else str(v)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.bool_,)):
        return bool(x)
    if isinstance(x, Path):
        return str(x)
    return x


def cache_key(specimen: Specimen, motion: GroundMotion, engine: str, settings: dict, version: str) -> str:
    """Content hash of everything that determines one (engine, motion) result."""
    payload = json.dumps(
        _jsonable(
            {
                "specimen": specimen.describe(),
                "motion": motion.content_hash(),
                "engine": engine,
                "settings": settings,
                "engine_version": version,
                "code": code_version(),
            }
        ),
        sort_keys=True,
    )
    return hashlib.sha256(payload.encode()).hexdigest()


# --------------------------------------------------------------------------
# Worker side
_ENGINE_CACHE: dict[str, Any] = {}


def _worker_engine(name: str, settings: dict):
    key = name + json.dumps(_jsonable(settings), sort_keys=True)
    eng = _ENGINE_CACHE.get(key)
    if eng is None:
        eng = get_engine(name, **settings)
        _ENGINE_CACHE[key] = eng
    return eng


def _run_chunk(name: str, settings: dict, specimen: Specimen, items: list[tuple[int, GroundMotion]]) -> list[dict]:
    """Run one engine on a few motions; every failure is caught and returned as data."""
    out = []
    try:
        eng = _worker_engine(name, settings)
    except Exception as e:  # the engine itself cannot start: every record of the chunk fails
        msg = f"{type(e).__name__}: {e}"
        return [{"motion_id": i, "status": "failed", "error": msg, "wall_s": 0.0} for i, _ in items]
    for i, motion in items:
        t0 = time.perf_counter()
        try:
            resp = eng.simulate(specimen, motion)
            theta = np.asarray(resp.theta, dtype=np.float32)
            if not np.all(np.isfinite(theta)):
                raise FloatingPointError("non-finite theta in the response")
            out.append(
                {
                    "motion_id": i,
                    "status": "ok",
                    "error": "",
                    "wall_s": time.perf_counter() - t0,
                    "theta_max_over_alpha": float(resp.theta_max_over_alpha),
                    "overturned": bool(resp.overturned),
                    "n_impacts": int(resp.n_impacts),
                    "theta": theta,
                }
            )
        except Exception as e:
            tb = traceback.extract_tb(e.__traceback__)
            where = f" ({tb[-1].filename.rsplit('/', 1)[-1]}:{tb[-1].lineno})" if tb else ""
            out.append(
                {
                    "motion_id": i,
                    "status": "failed",
                    "error": f"{type(e).__name__}: {e}{where}",
                    "wall_s": time.perf_counter() - t0,
                }
            )
    return out


# --------------------------------------------------------------------------
@dataclass
class RunResult:
    """What a run produced (also written to ``out``)."""

    results: pd.DataFrame
    histories: dict[tuple[str, int], np.ndarray]
    motions: list[GroundMotion]
    meta: dict = field(default_factory=dict)
    out: Path | None = None

    @property
    def failures(self) -> pd.DataFrame:
        """Rows whose engine failed on the record (engine, motion, error)."""
        return self.results[self.results["status"] != "ok"]


def _load_cached(path: Path) -> dict | None:
    try:
        with np.load(path, allow_pickle=False) as z:
            row = json.loads(str(z["row"]))
            row["theta"] = z["theta"]
        row["theta_max_over_alpha"] = float(row["theta_max_over_alpha"])
        return row
    except Exception:
        return None


def _store_cached(path: Path, row: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    meta = {k: v for k, v in row.items() if k not in ("theta", "motion_id")}
    meta["theta_max_over_alpha"] = str(meta["theta_max_over_alpha"])
    tmp = path.with_suffix(f".{os.getpid()}.tmp.npz")
    np.savez_compressed(tmp, theta=row["theta"], row=np.array(json.dumps(meta)))
    os.replace(tmp, path)


def run_engines(
    specimen: Specimen,
    motions: list[GroundMotion],
    engines: dict[str, dict],
    *,
    jobs: int | None = None,
    scheduler: str | Any | None = None,
    cache_dir: Path | None = None,
    use_cache: bool = True,
    progress: bool = True,
    chunk_size: int | None = None,
) -> tuple[pd.DataFrame, dict[tuple[str, int], np.ndarray], dict]:
    """Run every engine on every motion.

    Parameters
    ----------
    specimen : Specimen
    motions : list of GroundMotion
        The shared ensemble; ``motion_id`` is the index in this list.
    engines : dict
        Engine name -> settings overrides.
    jobs : int, optional
        Worker processes (default: the number of CPUs); 1 runs in this process.
    scheduler : str or distributed.Client, optional
        Address of a Dask distributed scheduler (or a Client) to run the chunks on.
    cache_dir : Path, optional
        Result cache (default :func:`default_cache_dir`); ``use_cache=False`` ignores it.
    progress : bool
        Show a progress bar with the estimated time left (tqdm, on stderr).

    Returns
    -------
    results : DataFrame
        One row per (engine, motion); see the module docstring.
    histories : dict
        (engine, motion_id) -> theta on the motion's grid [rad], float32.
    info : dict
        Per engine: settings, version, wall seconds, cached count.
    """
    cache_dir = Path(cache_dir) if cache_dir else default_cache_dir()
    jobs = jobs or os.cpu_count() or 1
    rows: dict[tuple[str, int], dict] = {}
    keys: dict[tuple[str, int], str] = {}
    info: dict[str, dict] = {}
    pending: list[tuple[str, dict, list[tuple[int, GroundMotion]]]] = []
    for name, settings in engines.items():
        cls = engine_class(name)
        probe = cls(**settings)
        full_settings = probe.settings()
        version = probe.version()
        info[name] = {"settings": full_settings, "version": version, "wall_s": 0.0, "cached": 0}
        todo = []
        for i, m in enumerate(motions):
            k = cache_key(specimen, m, name, full_settings, version)
            keys[(name, i)] = k
            row = _load_cached(cache_dir / k[:2] / f"{k}.npz") if use_cache else None
            if row is not None:
                row.update(motion_id=i, cached=True)
                rows[(name, i)] = row
                info[name]["cached"] += 1
            else:
                todo.append((i, m))
        n_workers = 1 if scheduler is None and jobs == 1 else max(jobs, 1)
        size = chunk_size or max(1, min(10, math.ceil(len(todo) / (4 * n_workers))))
        for c in range(0, len(todo), size):
            pending.append((name, settings, todo[c : c + size]))

    total = sum(len(c[2]) for c in pending)
    bar = None
    if progress and total:
        from tqdm.auto import tqdm

        bar = tqdm(total=total, desc="simulating", unit="run", file=sys.stderr, dynamic_ncols=True)

    def collect(name: str, result: list[dict], n_items: int) -> None:
        for r in result:
            r["cached"] = False
            rows[(name, r["motion_id"])] = r
            info[name]["wall_s"] += r["wall_s"]
            if use_cache and r["status"] == "ok":
                k = keys[(name, r["motion_id"])]
                try:
                    _store_cached(cache_dir / k[:2] / f"{k}.npz", r)
                except OSError:
                    pass  # a read-only cache must not fail the run
        if bar is not None:
            bar.set_postfix_str(name)
            bar.update(n_items)

    t_start = time.perf_counter()
    if pending:
        if scheduler is not None:
            from distributed import Client, as_completed

            client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
            try:
                futs = {}
                for name, settings, items in pending:
                    f = client.submit(_run_chunk, name, settings, specimen, items, pure=False)
                    futs[f] = (name, len(items))
                for f in as_completed(futs):
                    name, n_items = futs[f]
                    collect(name, f.result(), n_items)
            finally:
                if not isinstance(scheduler, Client):
                    client.close()
        elif jobs == 1:
            for name, settings, items in pending:
                collect(name, _run_chunk(name, settings, specimen, items), len(items))
        else:
            ctx = mp.get_context("spawn")
            with cf.ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) as pool:
                futs = {pool.submit(_run_chunk, n, s, specimen, items): (n, len(items)) for n, s, items in pending}
                for f in cf.as_completed(futs):
                    name, n_items = futs[f]
                    try:
                        res = f.result()
                    except Exception as e:  # a worker process died: its records fail, the rest stand
                        items = next(c[2] for c in pending if c[0] == name and len(c[2]) == n_items)
                        res = [
                            {"motion_id": i, "status": "failed", "error": f"worker died: {e}", "wall_s": 0.0}
                            for i, _ in items
                        ]
                    collect(name, res, n_items)
    if bar is not None:
        bar.close()
    elapsed = time.perf_counter() - t_start

    table = []
    histories = {}
    for (name, i), r in sorted(rows.items(), key=lambda kv: (list(engines).index(kv[0][0]), kv[0][1])):
        ok = r["status"] == "ok"
        table.append(
            {
                "engine": name,
                "motion_id": i,
                "motion_name": motions[i].name,
                "theta_max_over_alpha": r.get("theta_max_over_alpha", math.nan) if ok else math.nan,
                "overturned": bool(r.get("overturned", False)) if ok else False,
                "n_impacts": int(r.get("n_impacts", 0)) if ok else 0,
                "wall_s": float(r.get("wall_s", 0.0)),
                "status": r["status"],
                "error": r.get("error", ""),
                "cached": bool(r.get("cached", False)),
            }
        )
        if ok:
            histories[(name, i)] = np.asarray(r["theta"], dtype=np.float32)
    df = pd.DataFrame(table, columns=RESULT_COLUMNS)
    for name in info:
        info[name]["elapsed_s"] = elapsed
    return df, histories, info


def _git_commit() -> str:
    try:
        return subprocess.run(
            ["git", "rev-parse", "HEAD"],
            cwd=Path(__file__).parent,
            capture_output=True,
            text=True,
            timeout=5,
        ).stdout.strip()
    except Exception:
        return ""


def provenance() -> dict:
    """Versions of the suite, Python and the engines' packages, and the git commit."""
    import housner

    versions = {"housner": housner.__version__, "python": platform.python_version(), "numpy": np.__version__}
    for mod in ("mujoco", "pybullet", "scipy", "numba", "pandas"):
        try:
            from importlib.metadata import version

            versions[mod] = version(mod)
        except Exception:
            pass
    return {
        "versions": versions,
        "git_commit": _git_commit(),
        "platform": platform.platform(),
        "cpus": os.cpu_count(),
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    }


def write_run(
    out: Path,
    results: pd.DataFrame,
    histories: dict[tuple[str, int], np.ndarray],
    motions: list[GroundMotion],
    meta: dict,
) -> None:
    """Write results.parquet, histories.parquet, motions.npz and run.json into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    results.to_parquet(out / "results.parquet", index=False)
    parts = []
    for (name, i), theta in histories.items():
        n = len(theta)
        parts.append(
            pd.DataFrame(
                {
                    "engine": pd.Categorical([name] * n),
                    "motion_id": np.full(n, i, dtype=np.int32),
                    "t": (np.arange(n) * motions[i].dt).astype(np.float32),
                    "theta": theta,
                }
            )
        )
    if parts:
        pd.concat(parts, ignore_index=True).to_parquet(out / "histories.parquet", index=False)
    lengths = np.array([m.n for m in motions])
    acc = np.zeros((len(motions), int(lengths.max()) if len(motions) else 0), dtype=np.float32)
    for i, m in enumerate(motions):
        acc[i, : m.n] = m.acc
    np.savez_compressed(
        out / "motions.npz",
        acc=acc,
        n=lengths,
        dt=np.array([m.dt for m in motions]),
        theta0=np.array([m.theta0 for m in motions]),
        names=np.array([m.name for m in motions]),
    )
    (out / "run.json").write_text(json.dumps(_jsonable(meta), indent=2))


def run_scenario(
    scenario: Scenario | str | Path,
    *,
    engines: list[str] | None = None,
    n_motions: int | None = None,
    seed: int | None = None,
    out: str | Path | None = None,
    jobs: int | None = None,
    scheduler: str | Any | None = None,
    cache_dir: Path | None = None,
    use_cache: bool = True,
    progress: bool = True,
) -> RunResult:
    """Run a scenario on its engines (or ``engines``) and write the run directory.

    Parameters
    ----------
    scenario : Scenario or str or Path
        A loaded scenario, a catalogue name or a TOML file.
    engines : list of str, optional
        Override the scenario's engine list.
    n_motions : int, optional
        Fewer (or more) motions of an RDK ensemble; motion i is the same for any n.
    seed : int, optional
        Override the ensemble's seed.
    out : path, optional
        Run directory (default ``runs/<scenario>``).
    jobs, scheduler, cache_dir, use_cache, progress
        See :func:`run_engines`.
    """
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(scenario)
    names = list(engines) if engines else list(scenario.engines)
    for n in names:
        engine_class(n)  # unknown names fail here, listing the choices
    out = Path(out) if out else Path("runs") / scenario.name
    t0 = time.perf_counter()
    motions, mmeta = scenario.build_motions(n_motions, seed=seed)
    t_motions = time.perf_counter() - t0
    eng_settings = {n: dict(scenario.engine_settings.get(n, {})) for n in names}
    results, histories, info = run_engines(
        scenario.specimen,
        motions,
        eng_settings,
        jobs=jobs,
        scheduler=scheduler,
        cache_dir=cache_dir,
        use_cache=use_cache,
        progress=progress,
    )
    fails = results[results["status"] != "ok"]
    spread = None
    k = int(scenario.analysis.get("seed_spread", 0) or 0)
    if k > 1 and "housner" in names and n_motions is None and seed is None:
        from scenarios.analysis import seed_spread

        spread = seed_spread(scenario, k)
    meta = {
        "scenario": scenario.describe(),
        "specimen": scenario.specimen.describe(),
        "motions": mmeta,
        "n_motions": len(motions),
        "engines": info,
        "analysis": scenario.analysis,
        "failures": fails[["engine", "motion_id", "motion_name", "error"]].to_dict("records"),
        "wall_s": {"motions": t_motions, "total": time.perf_counter() - t0},
        "provenance": provenance(),
    }
    if spread is not None:
        meta["table2_spread"] = spread
    write_run(out, results, histories, motions, meta)
    return RunResult(results, histories, motions, meta, out)
