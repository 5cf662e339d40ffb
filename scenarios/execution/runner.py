"""Run engines on motions: plan -> execute -> table, every engine on the very same records.

:func:`run_engines` plans the work (for each engine: its settings and version,
the cache key of every record, the records the cache already holds, chunks of
the others), executes the chunks (in this process, in a fault-tolerant process pool
by default, :mod:`housner.scenarios.execution.workers`, or on a Dask cluster,
:mod:`housner.scenarios.execution.cluster`; an engine that batches runs each chunk
in one call; every record reported as it
finishes and stored in the cache, :mod:`housner.scenarios.execution.cache`) and
returns the table: one row per (engine, motion), always all of them, a record that
failed a row with ``status = "failed"`` and its error. It never sees a scenario.
How it executes is a :class:`~housner.scenarios.execution.options.RunOptions`.
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

import housner
from housner.engines.base import engine_class
from housner.motion import GroundMotion
from housner.scenarios.catalogue.schema import effects_label
from housner.scenarios.execution.cache import cache_keys, code_version, runner_logger
from housner.scenarios.execution.chunks import (
    REPAIRS,
    engine_batches,
    entry_file,
    entry_path,
    iter_chunk,
    load_entry,
    repairs_so_far,
    store_entry,
)
from housner.scenarios.execution.cluster import run_dask
from housner.scenarios.execution.options import RunOptions
from housner.scenarios.execution.rundir import RESULT_COLUMNS
from housner.scenarios.execution.workers import Chunk, Progress, RunInterrupted, failed_record, run_pool
from housner.specimen import Specimen

#: Most records per chunk (without ``chunk_size``): for an engine that runs record by record, and one that batches.
CHUNK_CAP, BATCH_CAP = 10, 40


def run_engines(
    specimen: Specimen,
    motions: list[GroundMotion],
    engines: dict[str, dict],
    options: RunOptions | None = None,
    *,
    effects: tuple = (),
    histories: bool = True,
    **execution,
) -> tuple[pd.DataFrame, dict[tuple[str, int], np.ndarray], dict]:
    """Run every engine on every motion (with ``effects``, if any).

    Parameters
    ----------
    specimen : Specimen
    motions : list of GroundMotion
        The shared ensemble; ``motion_id`` is the index in this list.
    engines : dict
        Engine name -> settings overrides.
    options : RunOptions, optional
        How the records execute: worker processes (``jobs``, default one per CPU; 1 runs in this
        process) or a Dask ``scheduler``, the result cache (``cache_dir``, ``use_cache``), the
        progress bar, ``chunk_size``. A bar of the caller's (``housner.scenarios.execution.workers.Progress``,
        e.g. one over a whole study) as ``progress`` is advanced, not closed, and keeps its runs'
        worker processes from one run to the next until the caller closes it.
    effects : tuple of housner.effects.Effect
        Physical effects every engine realises in every record (``Engine.simulate``'s ``effects``);
        an engine that cannot realise one fails each record, naming it. Part of the cache key.
    histories : bool
        Keep each record's theta history (returned, and in memory until then). False keeps only
        the record's figures, so memory stays flat over many records (the cache still stores it).
    **execution
        :class:`RunOptions` fields as keywords (``jobs=1``, ``cache_dir=...``), over ``options``.

    Returns
    -------
    results : DataFrame
        One row per (engine, motion), always all of them; see the module docstring.
    histories : dict
        (engine, motion_id) -> theta on the motion's grid [rad], float32.
    info : dict
        Per engine: settings, version, wall seconds (engine time, summed over records; a batched
        chunk's time is shared evenly by its records), ``cached`` (entries reused), ``cache_rejected``
        (entries found but refused: another key, checksum mismatch, unreadable; recomputed),
        ``worker_deaths`` (worker processes that died while running its records), ``kernel_cache_repairs``
        (damaged generated-kernel cache entries that the processes running its records removed and rebuilt)
        and ``elapsed_s``.

    Raises
    ------
    TypeError
        A keyword that is not a :class:`RunOptions` field (naming it).
    ValueError
        An option out of its range (``jobs`` or ``chunk_size`` not a positive integer...).
    RunInterrupted
        Ctrl-C: the workers are stopped at once; the records finished so far are in the cache.
    SchedulerError
        ``scheduler`` is an address no scheduler answers at.

    Notes
    -----
    Fault tolerance (process pool): workers report records as they finish. A worker that
    dies (killed, crashed in native code, out of memory) loses only the records it had not
    reported; the record it was running is retried once in a fresh worker, then listed as
    failed with the reason (e.g. ``worker process killed by SIGKILL``). In a batched chunk,
    where the record that killed it is unknown, each unfinished record is retried alone,
    once. Every (engine, motion) of the run has exactly one row.
    """
    opts = RunOptions.merged(options, execution, "run_engines")
    jobs, scheduler = opts.local_jobs(), opts.scheduler
    n_workers, per_worker = _workers_and_chunks(scheduler, jobs)
    plan = _plan(
        specimen, motions, engines, effects, opts.cache_folder(), n_workers, opts.chunk_size, per_worker, histories
    )
    if plan.rows and opts.progress:
        _say_reused(plan, len(engines) * len(motions))
    elapsed = _execute(plan, specimen, jobs, scheduler, opts.progress)
    for name in plan.info:
        plan.info[name]["elapsed_s"] = elapsed
    df, histories = _table(plan.rows, list(engines), motions, effects)
    return df, histories, plan.info


@dataclass
class _Plan:
    """What a run has to do: the rows found in the cache, the chunks left to run, and where results go."""

    rows: dict[tuple[str, int], dict]  # (engine, motion_id) -> record, cached or computed
    keys: dict[tuple[str, int], str]  # (engine, motion_id) -> cache key
    info: dict[str, dict]  # engine -> settings, version, counters
    chunks: list[Chunk]
    cache_dir: Path | None  # None: the cache is not used
    histories: bool = True  # False: a record's theta is dropped once it is cached
    store_here: bool = True  # False: the process that computes a record stores its entry (pool, this process)

    def store(self, name: str, r: dict) -> None:
        """Take a computed record: into the rows, its time into the engine's total, into the cache if it is ok
        (unless the process that computed it stored it already)."""
        r["cached"] = False
        self.info[name][REPAIRS] += r.pop(REPAIRS, 0)
        self.rows[(name, r["motion_id"])] = r
        self.info[name]["wall_s"] += r["wall_s"]
        if self.store_here and self.cache_dir is not None and r["status"] == "ok":
            k = self.keys[(name, r["motion_id"])]
            try:
                store_entry(entry_path(self.cache_dir, k), k, r)
            except OSError:
                pass  # a read-only cache must not fail the run
        if not self.histories:
            r.pop("theta", None)


def _workers_and_chunks(scheduler, jobs: int) -> tuple[int, int]:
    """Workers the chunks are sized for, and chunks per worker: the ``jobs`` processes (1: this process),
    4 chunks each; on Dask, the cluster's worker threads, 16 chunks each."""
    if scheduler is None:
        return jobs, 4
    # Dask: as many chunks per worker thread as make the last ones short (records differ 10-fold in
    # length: an overturn ends one early); a task costs milliseconds. With 4 per worker, 2 workers ran
    # an engine-bound study 1.74 x faster than one, the last chunk keeping one worker alone.
    return _cluster_threads(scheduler, jobs), 16


def _cluster_threads(scheduler, default: int) -> int:
    """Worker threads of a Dask client's cluster (``default`` for an address, or a cluster that will not say)."""
    try:
        return max(1, int(sum(scheduler.nthreads().values())))
    except Exception:  # an address string, or a cluster that cannot answer now: the chunks are only sized by it
        return default


def _plan(
    specimen,
    motions,
    engines: dict,
    effects: tuple,
    cache_dir: Path | None,
    n_workers: int,
    chunk_size: int | None,
    per_worker: int = 4,
    histories: bool = True,
) -> _Plan:
    """Probe each engine (settings, version), take what the cache holds, cut the rest into chunks."""
    plan = _Plan({}, {}, {}, [], cache_dir, histories)
    per_engine: list[list[Chunk]] = []
    for name, settings in engines.items():
        repaired = repairs_so_far()  # a damaged kernel found while planning (the cache keys load the effects' kernels)
        probe = engine_class(name)(**settings)
        full_settings, version = probe.settings(), probe.version()
        plan.info[name] = {
            "settings": full_settings,
            "version": version,
            "wall_s": 0.0,
            "cached": 0,
            "cache_rejected": 0,
            "worker_deaths": 0,
            REPAIRS: 0,
        }
        todo = []
        keys = cache_keys(specimen, motions, name, full_settings, version, effects)
        plan.info[name][REPAIRS] += repairs_so_far() - repaired
        for i, k in enumerate(keys):
            plan.keys[(name, i)] = k
            row = _cached_row(plan, name, i, k)
            if row is not None:
                plan.rows[(name, i)] = row
            else:
                todo.append((i, motions[i]))
        batched = engine_batches(probe)
        cap = BATCH_CAP if batched else CHUNK_CAP
        size = chunk_size or max(1, min(cap, math.ceil(len(todo) / (per_worker * n_workers))))
        per_engine.append(
            [
                Chunk(0, name, settings, part, effects, batched, {i: plan.keys[(name, i)] for i, _ in part})
                for part in _parts(todo, size, n_workers, guided=not (chunk_size or batched))
            ]
        )
    # Engines interleaved, chunk by chunk: the progress bar's rate (and time left) then mixes fast
    # and slow engines from the start instead of extrapolating the fastest one.
    for k in range(max((len(p) for p in per_engine), default=0)):
        for p in per_engine:
            if k < len(p):
                p[k].id = len(plan.chunks)
                plan.chunks.append(p[k])
    return plan


def _parts(todo: list, size: int, n_workers: int, *, guided: bool) -> list[list]:
    """``todo`` cut into chunks of ``size``; ``guided``: the last ``n_workers * size`` records in chunks of a
    quarter of it, so that the run does not end on one worker with a whole chunk of slow records left
    (records of one engine differ up to 10-fold in time; a chunk of 10 Drake records is about 50 s)."""
    tail = min(len(todo), n_workers * size) if guided and n_workers > 1 else 0
    small = max(1, math.ceil(size / 4))
    bulk, end = todo[: len(todo) - tail], todo[len(todo) - tail :]
    head = [bulk[c : c + size] for c in range(0, len(bulk), size)]
    return head + [end[c : c + small] for c in range(0, len(end), small)]


def _say_reused(plan: _Plan, total: int) -> None:
    """Say on stderr that records come from the result cache, from where, and why they are valid."""
    print(
        f"reusing {len(plan.rows)} of {total} records from the result cache in {plan.cache_dir} (computed earlier "
        f"by housner {housner.__version__}, physics and engine code {code_version()}, with the same engine "
        "versions, settings and motions; --no-cache recomputes them)",
        file=sys.stderr,
        flush=True,
    )


def _cached_row(plan: _Plan, name: str, i: int, k: str) -> dict | None:
    """The cached record of (engine, motion) under key ``k``, or None (counted when an entry was refused)."""
    if plan.cache_dir is None:
        return None
    path = entry_file(plan.cache_dir, k)
    row, problem = load_entry(path, k)
    if problem is not None:
        plan.info[name]["cache_rejected"] += 1
        runner_logger.warning("housner: warning: cache entry %s (%s, motion %d) %s; recomputed", path, name, i, problem)
    if row is None:
        return None
    if not plan.histories:
        row.pop("theta", None)
    row.update(motion_id=i, cached=True)
    plan.info[name]["cached"] += 1
    return row


def _execute(plan: _Plan, specimen, jobs: int, scheduler, progress) -> float:
    """Run the plan's chunks (in this process, a process pool or on Dask); returns the wall time [s]."""
    chunks = plan.chunks
    total = sum(len(c.items) for c in chunks)
    if scheduler is not None:
        how = "on the Dask cluster"
    elif jobs == 1:
        how = "in this process"
    else:
        how = f"starting {min(jobs, len(chunks))} worker processes"
    own_bar = not isinstance(progress, Progress)
    bar = Progress(total, progress, how) if own_bar else progress
    if not own_bar:
        bar.advance(len(plan.rows))  # the records the cache held count as done

    def on_record(name: str, r: dict) -> None:
        plan.store(name, r)
        bar.update(name)

    cache_dir = None if plan.cache_dir is None else str(plan.cache_dir)
    deaths: dict[tuple[str, int], list[str]] = {}
    worker_deaths: dict[str, int] = {}
    t_start = time.perf_counter()
    try:
        if chunks:
            if scheduler is not None:  # the cluster's workers need not see this machine's cache: stored here
                run_dask(chunks, specimen, scheduler, on_record)
            elif jobs == 1:
                plan.store_here = False
                for c in chunks:
                    for rows in iter_chunk(
                        c.engine,
                        c.settings,
                        specimen,
                        c.items,
                        c.effects,
                        batched=c.batched,
                        cache_dir=cache_dir,
                        keys=c.keys,
                    ):
                        for r in rows:
                            on_record(c.engine, r)
            else:
                plan.store_here = False
                pool = None if own_bar else bar.pool_for(jobs)
                run_pool(
                    chunks,
                    specimen,
                    jobs,
                    on_record,
                    deaths,
                    worker_deaths=worker_deaths,
                    pool=pool,
                    cache_dir=cache_dir,
                    thetas=plan.histories,
                )
    except KeyboardInterrupt:
        bar.close()
        raise RunInterrupted(bar.done, total if own_bar else bar.total, cached=plan.cache_dir is not None) from None
    if own_bar:
        bar.close()
    for name, n in worker_deaths.items():
        plan.info[name]["worker_deaths"] += n
    return time.perf_counter() - t_start


def _table(rows: dict, engines: list[str], motions: list[GroundMotion], effects: tuple):
    """The results table (one row per engine and motion, always all of them) and the histories of the ok rows."""
    for name in engines:
        for i in range(len(motions)):
            if (name, i) not in rows:  # cannot happen by design; never leave a record out silently
                rows[(name, i)] = failed_record(i, "no result came back from the workers")
    table, histories = [], {}
    label = effects_label(effects)
    for (name, i), r in sorted(rows.items(), key=lambda kv: (engines.index(kv[0][0]), kv[0][1])):
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
                "effects": label,
            }
        )
        if ok and "theta" in r:
            histories[(name, i)] = np.asarray(r["theta"], dtype=np.float32)
    return pd.DataFrame(table, columns=RESULT_COLUMNS), histories
