"""The shared scenario runner: every engine on the very same motions.

Work is split into chunks of (engine, motions) and run in a process pool (the
default), in this process (``jobs=1``), or on a Dask distributed cluster
(``scheduler=ADDRESS``). A record that fails in one engine becomes a row with
``status = "failed"`` and its error; the other results are kept. Every
(engine, motion) of a run has exactly one row.

Faults. Pool workers report every record as it finishes. A worker that dies
(killed, crashed in native code, out of memory) loses only the record it was
running: that record is retried once in a fresh worker, then listed as failed
with the reason (``killed by SIGKILL``...); the rest of its chunk is re-queued.
Ctrl-C stops the workers at once and raises :class:`RunInterrupted`; finished
records are already in the cache, so re-running resumes.

Cache. Results are cached by content: specimen, motion samples, engine name,
settings and version, and the suite's code version. Each entry stores its key
and a SHA-256 of its payload (key, row fields, theta bytes); an entry under the
wrong key or failing its checksum is reported (a warning on the
``housner.runner`` logger, ``cache_rejected`` in the run info) and recomputed.

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

import asyncio
import hashlib
import json
import logging
import math
import multiprocessing as mp
import multiprocessing.connection
import os
import platform
import signal
import subprocess
import sys
import threading
import time
import traceback
from collections import deque
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from engines.base import engine_class, get_engine
from housner.motion import GroundMotion
from housner.specimen import Specimen
from scenarios._outputs import check_output_dir
from scenarios.catalogue import Scenario, load_scenario
from scenarios.schema import effects_label

__all__ = [
    "RunInterrupted",
    "RunResult",
    "SchedulerError",
    "code_version",
    "connect_scheduler",
    "default_cache_dir",
    "run_engines",
    "run_scenario",
]

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
    "effects",
]


#: Files a run writes into its directory (``report.html`` is written by the CLI after it).
RUN_FILES = ("results.parquet", "histories.parquet", "motions.npz", "run.json", "report.html")


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


def cache_key(
    specimen: Specimen, motion: GroundMotion, engine: str, settings: dict, version: str, effects: tuple = ()
) -> str:
    """Content hash of everything that determines one (engine, effects, motion) result."""
    content = {
        "specimen": specimen.describe(),
        "motion": motion.content_hash(),
        "engine": engine,
        "settings": settings,
        "engine_version": version,
        "code": code_version(),
    }
    if effects:  # no key for none: results without effects keep their cache entries
        content["effects"] = [effect_data(e) for e in effects]
    payload = json.dumps(_jsonable(content), sort_keys=True)
    return hashlib.sha256(payload.encode()).hexdigest()


# --------------------------------------------------------------------------
# Worker side
_ENGINE_CACHE: dict[str, Any] = {}

#: Test hook, read in pool worker processes only (never in the calling process):
#: ``ENGINE:MOTION_ID:SIGNAL[:MARKER]`` makes the worker that is about to simulate
#: that record die by ``SIGNAL`` (``KILL``, ``SEGV``, ...), as a killed, crashed or
#: out-of-memory worker would. With ``MARKER`` (a file path) it happens once: the
#: first worker to get there creates the file atomically and dies, later ones run.
CRASH_ENV = "HOUSNER_TEST_CRASH"
_IN_WORKER = False


def _maybe_crash(name: str, motion_id: int) -> None:
    spec = os.environ.get(CRASH_ENV)
    if not spec or not _IN_WORKER:
        return
    parts = spec.split(":", 3)
    if len(parts) < 3 or parts[0] != name or parts[1] != str(motion_id):
        return
    if len(parts) == 4:
        try:
            os.close(os.open(parts[3], os.O_CREAT | os.O_EXCL | os.O_WRONLY))
        except FileExistsError:
            return
    sig = getattr(signal, "SIG" + parts[2].upper())
    try:
        import resource

        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))  # a deliberate crash leaves no core file
    except (ImportError, ValueError, OSError):
        pass
    os.kill(os.getpid(), sig)


def _warm_up(eng: Any, specimen: Specimen) -> None:
    """Run the engine once on 20 ms of free rocking, so that compilation and model
    building are done before the first record (its ``wall_s`` is then the record's own)."""
    try:
        eng.simulate(specimen, GroundMotion.free_vibration(0.3 * specimen.alpha, 0.02, 0.002, name="warm-up"))
    except Exception:
        pass  # a real record will report whatever is wrong


def _worker_engine(name: str, settings: dict, specimen: Specimen | None = None):
    key = name + json.dumps(_jsonable(settings), sort_keys=True)
    eng = _ENGINE_CACHE.get(key)
    if eng is None:
        eng = get_engine(name, **settings)
        if specimen is not None:
            _warm_up(eng, specimen)
        _ENGINE_CACHE[key] = eng
    return eng


def effect_data(effect: Any) -> dict:
    """An effect as plain data: its registry name and parameter values (for cache keys and run.json)."""
    return {"name": effect.name, **{k: getattr(effect, k) for k in type(effect).params}}


def _simulate_one(eng: Any, specimen: Specimen, i: int, motion: GroundMotion, effects: tuple = ()) -> dict:
    t0 = time.perf_counter()
    try:
        resp = eng.simulate(specimen, motion, effects) if effects else eng.simulate(specimen, motion)
        theta = np.asarray(resp.theta, dtype=np.float32)  # checked finite by Engine.simulate (check_response)
        return {
            "motion_id": i,
            "status": "ok",
            "error": "",
            "wall_s": time.perf_counter() - t0,
            "theta_max_over_alpha": float(resp.theta_max_over_alpha),
            "overturned": bool(resp.overturned),
            "n_impacts": int(resp.n_impacts),
            "theta": theta,
        }
    except Exception as e:
        tb = traceback.extract_tb(e.__traceback__)
        where = f" ({tb[-1].filename.rsplit('/', 1)[-1]}:{tb[-1].lineno})" if tb else ""
        return {
            "motion_id": i,
            "status": "failed",
            "error": f"{type(e).__name__}: {e}{where}",
            "wall_s": time.perf_counter() - t0,
        }


def _iter_chunk(
    name: str, settings: dict, specimen: Specimen, items: list[tuple[int, GroundMotion]], effects: tuple = ()
):
    """Yield one result dict per record, as each finishes; failures are data, not exceptions."""
    try:
        eng = _worker_engine(name, settings, specimen)
    except Exception as e:  # the engine itself cannot start: every record of the chunk fails
        msg = f"{type(e).__name__}: {e}"
        for i, _ in items:
            yield {"motion_id": i, "status": "failed", "error": msg, "wall_s": 0.0}
        return
    for i, motion in items:
        _maybe_crash(name, i)
        yield _simulate_one(eng, specimen, i, motion, effects)


def _run_chunk(
    name: str, settings: dict, specimen: Specimen, items: list[tuple[int, GroundMotion]], effects: tuple = ()
) -> list[dict]:
    """Run one engine on a few motions; every failure is caught and returned as data."""
    return list(_iter_chunk(name, settings, specimen, items, effects))


def _worker_main(conn: Any) -> None:
    """Body of a pool worker process: run the chunks it is sent, reporting every record as it finishes.

    Messages to the parent: ``("ready", None, None)`` once started, ``("rec", chunk_id, row)``
    per record, ``("done", chunk_id, None)`` per chunk. ``None`` from the parent (or a closed
    pipe) ends the process.
    """
    global _IN_WORKER
    _IN_WORKER = True
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    conn.send(("ready", None, None))
    while True:
        try:
            msg = conn.recv()
        except (EOFError, OSError):
            return
        if msg is None:
            return
        chunk_id, name, settings, specimen, items, effects = msg
        for row in _iter_chunk(name, settings, specimen, items, effects):
            conn.send(("rec", chunk_id, row))
        conn.send(("done", chunk_id, None))


# --------------------------------------------------------------------------
# Parent side
class RunInterrupted(KeyboardInterrupt):
    """Ctrl-C during a run: the workers were stopped, the finished records are in the cache.

    Attributes
    ----------
    done, total : int
        Records finished before the interrupt, and records to compute.
    cached : bool
        Whether the finished records were written to the cache (False with ``use_cache=False``).
    """

    def __init__(self, done: int, total: int, cached: bool = True):
        self.done = done
        self.total = total
        self.cached = cached
        super().__init__(f"interrupted after {done} of {total} records")


class SchedulerError(ConnectionError):
    """The Dask scheduler cannot be reached (the message names its address)."""


#: Seconds to wait for a Dask scheduler to answer before giving up.
SCHEDULER_TIMEOUT_S = 5.0


def connect_scheduler(address: str, timeout: float = SCHEDULER_TIMEOUT_S):
    """Connect to the Dask distributed scheduler at ``address``.

    Parameters
    ----------
    address : str
        Scheduler address, e.g. ``tcp://host:8786``.
    timeout : float
        Seconds to wait for the connection.

    Returns
    -------
    distributed.Client

    Raises
    ------
    SchedulerError
        No scheduler answered within ``timeout`` (the message names the address).
    """
    _probe_scheduler(address, timeout)
    from distributed import Client

    try:
        return Client(address, timeout=timeout, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as e:
        detail = str(e).splitlines()[0] if str(e) else type(e).__name__
        if isinstance(e, TimeoutError) or "timed out" in detail.lower():
            detail = f"no answer within {timeout:g} s; is a scheduler running there?"
        raise SchedulerError(f"cannot reach the Dask scheduler at {address}: {detail}") from None


_SCHEMES = ("tcp", "tls", "inproc", "ucx", "ws", "wss")


def _probe_scheduler(address: str, timeout: float) -> None:
    """Refuse an unknown scheme, and a TCP address where nothing listens, at once (a
    Client would retry until its timeout, and leave a traceback behind on a bad scheme)."""
    import socket
    from urllib.parse import urlsplit

    scheme, sep, _rest = address.partition("://")
    if not sep:
        scheme, address_url = "tcp", f"tcp://{address}"
    else:
        address_url = address
    if scheme not in _SCHEMES:
        raise SchedulerError(
            f"cannot reach the Dask scheduler at {address}: unknown scheme {scheme!r} (known: {', '.join(_SCHEMES)})"
        )
    if scheme not in ("tcp", "tls"):
        return
    try:
        parts = urlsplit(address_url)
        host, port = parts.hostname, parts.port or 8786
    except ValueError as e:
        raise SchedulerError(f"cannot reach the Dask scheduler at {address}: malformed address ({e})") from None
    if not host:
        raise SchedulerError(f"cannot reach the Dask scheduler at {address}: no host in the address")
    try:
        socket.create_connection((host, port), timeout=timeout).close()
    except TimeoutError:
        raise SchedulerError(f"cannot reach the Dask scheduler at {address}: no answer within {timeout:g} s") from None
    except OSError as e:
        raise SchedulerError(
            f"cannot reach the Dask scheduler at {address}: {e.strerror or e}; is a scheduler running there?"
        ) from None
    try:  # something listens: ask it who it is, in a loop of our own (no half-built Client left behind)
        kind = asyncio.run(_identity(address_url, timeout))
    except Exception as e:
        kind = f"no Dask reply: {type(e).__name__}"
    if kind != "Scheduler":
        raise SchedulerError(
            f"cannot use {address}: it does not answer like a Dask scheduler ({kind}); check the address and port"
        )


async def _identity(address: str, timeout: float) -> str:
    from distributed.comm import connect

    comm = await connect(address, timeout=timeout)
    try:
        await comm.write({"op": "identity", "reply": True})
        reply = await asyncio.wait_for(comm.read(), timeout)
    finally:
        await comm.close()
    return reply.get("type", "no type") if isinstance(reply, dict) else type(reply).__name__


@dataclass
class _Chunk:
    """Records of one engine sent to a worker together; ``id`` identifies it (never its size)."""

    id: int
    engine: str
    settings: dict
    items: list[tuple[int, GroundMotion]]
    effects: tuple = ()


def _failed(i: int, msg: str) -> dict:
    return {"motion_id": i, "status": "failed", "error": msg, "wall_s": 0.0}


def _death_reason(exitcode: int | None) -> str:
    """What a worker's exit code says about its death."""
    if exitcode is None:
        return "died (exit status unknown)"
    if exitcode < 0:
        try:
            name = signal.Signals(-exitcode).name
        except ValueError:
            name = f"signal {-exitcode}"
        why = {
            "SIGKILL": "killed, or out of memory",
            "SIGSEGV": "crash in native code",
            "SIGBUS": "crash in native code",
            "SIGABRT": "aborted by native code",
            "SIGTERM": "terminated",
        }.get(name)
        return f"killed by {name}" + (f" ({why})" if why else "")
    return f"exited with status {exitcode}"


@contextmanager
def _sigint_ignored():
    """Hold Ctrl-C back while starting a worker.

    Where the platform allows, SIGINT is *blocked*: the child inherits the mask (across fork and exec)
    and so never sees a Ctrl-C before its main sets SIG_IGN, and a Ctrl-C that arrives meanwhile stays
    pending in the parent and is delivered as soon as the start returns (ignoring it instead loses a
    Ctrl-C that arrives while a worker starts, and the run goes on).
    Elsewhere it is ignored for that moment, which the child inherits likewise."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            yield
        finally:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


class _Worker:
    """One worker process and its pipe; runs one chunk at a time."""

    def __init__(self, ctx: Any):
        parent, child = ctx.Pipe()
        with _sigint_ignored():
            self.proc = ctx.Process(target=_worker_main, args=(child,), daemon=True, name="housner-worker")
            self.proc.start()
        child.close()
        self.conn = parent
        self.chunk: _Chunk | None = None
        self.next = 0  # index in chunk.items of the record in progress
        self.ready = False  # the process has started and can run records

    def give(self, chunk: _Chunk, specimen: Specimen) -> bool:
        self.chunk, self.next = chunk, 0
        try:
            self.conn.send((chunk.id, chunk.engine, chunk.settings, specimen, chunk.items, chunk.effects))
            return True
        except OSError:  # it died while idle
            return False

    def stop(self, wait: float) -> None:
        """Ask the worker to exit, wait ``wait`` seconds, then terminate and kill it."""
        if wait > 0:
            try:
                self.conn.send(None)
            except OSError:
                pass
            self.proc.join(wait)
        if self.proc.is_alive():
            self.proc.terminate()
            self.proc.join(0.5)
        if self.proc.is_alive():
            self.proc.kill()
            self.proc.join(0.5)
        self.conn.close()


def _run_pool(
    chunks: list[_Chunk],
    specimen: Specimen,
    jobs: int,
    on_record: Any,
    deaths: dict[tuple[str, int], list[str]],
) -> None:
    """Run ``chunks`` on ``jobs`` worker processes, calling ``on_record(engine, row)`` per record.

    Records come back one by one, so a worker that dies loses only the record it
    was running. That record is retried once in a fresh worker (the chunk's other
    unfinished records are simply re-queued); if it kills its worker again it is
    listed as failed with both reasons. ``deaths`` collects (engine, motion_id) ->
    reasons. After ``2 jobs + 8`` deaths the rest of the work fails instead of
    spawning more workers.
    """
    ctx = mp.get_context("spawn")
    queue = deque(chunks)
    next_id = max((c.id for c in chunks), default=0) + 1
    workers: list[_Worker] = []
    n_dead, max_dead = 0, 2 * jobs + 8
    last_reason = ""

    def lost(w: _Worker) -> None:
        nonlocal next_id, n_dead, last_reason
        w.proc.join(2.0)
        reason = last_reason = _death_reason(w.proc.exitcode)
        n_dead += 1
        w.conn.close()
        workers.remove(w)
        chunk, rest = w.chunk, w.chunk.items[w.next :] if w.chunk else []
        if not rest:
            return
        if not w.ready:  # it died starting up, before any record: nothing to blame, run the chunk elsewhere
            queue.appendleft(chunk)
            return
        (i, m), rest = rest[0], rest[1:]
        if rest:
            queue.appendleft(_Chunk(next_id, chunk.engine, chunk.settings, rest, chunk.effects))
            next_id += 1
        reasons = deaths.setdefault((chunk.engine, i), [])
        reasons.append(reason)
        if len(reasons) >= 2:
            msg = f"the worker process died while simulating this record: {reasons[0]}; on the retry: {reasons[1]}"
            on_record(chunk.engine, _failed(i, msg))
        else:
            queue.append(_Chunk(next_id, chunk.engine, chunk.settings, [(i, m)], chunk.effects))  # the one retry, last
            next_id += 1

    def give(w: _Worker, chunk: _Chunk) -> None:
        if not w.give(chunk, specimen):  # it died while idle: nothing of the chunk ran
            w.chunk = None
            queue.appendleft(chunk)
            lost(w)

    try:
        while queue or any(w.chunk is not None for w in workers):
            if n_dead > max_dead:
                msg = f"not run: {n_dead} worker processes died (the last {last_reason}); gave up"
                for w in workers:
                    if w.chunk is not None:
                        rest = w.chunk.items[w.next :]
                        queue.appendleft(_Chunk(0, w.chunk.engine, w.chunk.settings, rest, w.chunk.effects))
                        w.chunk = None
                for c in queue:
                    for i, _ in c.items:
                        on_record(c.engine, _failed(i, msg))
                queue.clear()
                break
            for w in [w for w in workers if w.chunk is None]:
                if queue:
                    give(w, queue.popleft())
            while queue and len(workers) < jobs:
                w = _Worker(ctx)
                workers.append(w)
                give(w, queue.popleft())
            busy = {w.conn: w for w in workers if w.chunk is not None}
            for conn in mp.connection.wait(list(busy)):
                w = busy[conn]
                try:
                    kind, _cid, row = conn.recv()
                except (EOFError, OSError):
                    lost(w)
                    continue
                if kind == "ready":
                    w.ready = True
                elif kind == "rec":
                    on_record(w.chunk.engine, row)
                    w.next += 1
                else:  # "done"
                    w.chunk = None
    except BaseException:  # Ctrl-C or an error here: stop the workers now, do not wait for them
        for w in workers:
            w.stop(0.0)
        raise
    for w in workers:
        w.stop(5.0)


def _run_dask(chunks: list[_Chunk], specimen: Specimen, scheduler: Any, on_record: Any) -> None:
    """Run ``chunks`` on a Dask cluster; a task that fails twice (Dask retries it once) fails its records."""
    from distributed import Client, as_completed

    client = scheduler if isinstance(scheduler, Client) else connect_scheduler(scheduler)
    futs: dict[Any, _Chunk] = {}
    try:
        for c in chunks:
            f = client.submit(_run_chunk, c.engine, c.settings, specimen, c.items, c.effects, pure=False, retries=1)
            futs[f] = c
        for f in as_completed(futs):
            c = futs[f]
            try:
                res = f.result()
            except Exception as e:  # the worker died or the task could not run, twice
                res = [_failed(i, f"Dask task failed twice: {type(e).__name__}: {e}") for i, _ in c.items]
            for r in res:
                on_record(c.engine, r)
    except BaseException:
        client.cancel(list(futs))
        raise
    finally:
        if not isinstance(scheduler, Client):
            client.close(timeout=2)


class _Progress:
    """Progress on stderr. Until the first record comes back (workers starting, engines
    loading and, after an update, numba compiling for 10-20 s) one line says so; the bar,
    and with it the time-left estimate, starts with the first finished record, so the
    estimate is made of simulation time only."""

    def __init__(self, total: int, enabled: bool, how: str):
        self.total = total
        self.done = 0
        self.enabled = enabled and total > 0
        self.bar = None
        if self.enabled:
            print(
                f"simulating {total} records: {how}; loading the engines "
                "(the first run after an update compiles them, 10-20 s)...",
                file=sys.stderr,
                flush=True,
            )

    def update(self, engine: str) -> None:
        self.done += 1
        if not self.enabled:
            return
        if self.bar is None:
            from tqdm.auto import tqdm

            self.bar = tqdm(
                total=self.total,
                initial=self.done,
                desc="simulating",
                unit="run",
                file=sys.stderr,
                dynamic_ncols=True,
            )
        else:
            self.bar.update(1)
        self.bar.set_postfix_str(engine, refresh=False)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


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


# --------------------------------------------------------------------------
# Result cache: one .npz per key, holding theta and the row, with the key and a checksum.
_log = logging.getLogger("housner.runner")


def _entry_checksum(key: str, meta: dict, theta: np.ndarray) -> str:
    """SHA-256 of an entry's payload: its key, its row fields (canonical JSON) and theta's bytes."""
    h = hashlib.sha256()
    h.update(key.encode())
    h.update(b"\0")
    h.update(json.dumps({k: v for k, v in meta.items() if k != "sha256"}, sort_keys=True).encode())
    h.update(b"\0")
    h.update(np.ascontiguousarray(theta, dtype="<f4").tobytes())
    return h.hexdigest()


def _load_cached(path: Path, key: str) -> tuple[dict | None, str | None]:
    """Read a cache entry.

    Returns
    -------
    row : dict or None
        The stored row with ``theta``, or None (absent or rejected).
    problem : str or None
        Why an existing entry was rejected (unreadable, another key, checksum mismatch).
    """
    if not path.exists():
        return None, None
    try:
        with np.load(path, allow_pickle=False) as z:
            meta = json.loads(str(z["row"]))
            theta = np.asarray(z["theta"])
    except Exception as e:
        return None, f"is unreadable ({type(e).__name__})"
    if not isinstance(meta, dict) or "sha256" not in meta or "key" not in meta:
        return None, "has no key or checksum (older or foreign format)"
    if meta["key"] != key:
        return None, f"holds the result of another key ({str(meta['key'])[:12]}...)"
    if meta["sha256"] != _entry_checksum(key, meta, theta):
        return None, "fails its checksum (edited or corrupted)"
    try:
        row = {k: v for k, v in meta.items() if k not in ("key", "sha256")}
        row["theta_max_over_alpha"] = float(row["theta_max_over_alpha"])
        row["theta"] = theta
        if row.get("status") != "ok":
            return None, f"has status {row.get('status')!r}"
    except (KeyError, TypeError, ValueError) as e:
        return None, f"has a malformed row ({type(e).__name__}: {e})"
    return row, None


def _store_cached(path: Path, key: str, row: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    meta = {k: v for k, v in row.items() if k not in ("theta", "motion_id")}
    meta["theta_max_over_alpha"] = str(meta["theta_max_over_alpha"])
    meta["key"] = key
    theta = np.ascontiguousarray(row["theta"], dtype=np.float32)
    meta["sha256"] = _entry_checksum(key, meta, theta)
    tmp = path.with_suffix(f".{os.getpid()}.tmp.npz")
    np.savez_compressed(tmp, theta=theta, row=np.array(json.dumps(meta)))
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
    effects: tuple = (),
) -> tuple[pd.DataFrame, dict[tuple[str, int], np.ndarray], dict]:
    """Run every engine on every motion (with ``effects``, if any).

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
    chunk_size : int, optional
        Records per chunk sent to a worker (default: about a quarter of each worker's share, 1 to 10).
    effects : tuple of housner.effects.Effect
        Physical effects every engine realises in every record (``Engine.simulate``'s ``effects``);
        an engine that cannot realise one fails each record, naming it. Part of the cache key.

    Returns
    -------
    results : DataFrame
        One row per (engine, motion), always all of them; see the module docstring.
    histories : dict
        (engine, motion_id) -> theta on the motion's grid [rad], float32.
    info : dict
        Per engine: settings, version, wall seconds (engine time, summed over records),
        ``cached`` (entries reused), ``cache_rejected`` (entries found but refused: another
        key, checksum mismatch, unreadable; recomputed), ``worker_deaths`` (worker processes
        that died while running one of its records) and ``elapsed_s``.

    Raises
    ------
    RunInterrupted
        Ctrl-C: the workers are stopped at once; the records finished so far are in the cache.
    SchedulerError
        ``scheduler`` is an address no scheduler answers at.

    Notes
    -----
    Fault tolerance (process pool): workers report each record as it finishes. A
    worker that dies (killed, crashed in native code, out of memory) loses only the
    record it was running; that record is retried once in a fresh worker, then listed
    as failed with the reason (e.g. ``worker process killed by SIGKILL``). Every
    (engine, motion) of the run has exactly one row.
    """
    if jobs is not None and (not isinstance(jobs, (int, np.integer)) or isinstance(jobs, bool) or jobs < 1):
        raise ValueError(f"`jobs` must be a positive integer, got {jobs!r}")
    if chunk_size is not None and (not isinstance(chunk_size, (int, np.integer)) or chunk_size < 1):
        raise ValueError(f"`chunk_size` must be a positive integer, got {chunk_size!r}")
    cache_dir = Path(cache_dir) if cache_dir else default_cache_dir()
    jobs = jobs or os.cpu_count() or 1
    rows: dict[tuple[str, int], dict] = {}
    keys: dict[tuple[str, int], str] = {}
    info: dict[str, dict] = {}
    per_engine: list[list[tuple[str, dict, list]]] = []
    for name, settings in engines.items():
        cls = engine_class(name)
        probe = cls(**settings)
        full_settings = probe.settings()
        version = probe.version()
        info[name] = {
            "settings": full_settings,
            "version": version,
            "wall_s": 0.0,
            "cached": 0,
            "cache_rejected": 0,
            "worker_deaths": 0,
        }
        todo = []
        for i, m in enumerate(motions):
            k = cache_key(specimen, m, name, full_settings, version, effects)
            keys[(name, i)] = k
            row, problem = _load_cached(cache_dir / k[:2] / f"{k}.npz", k) if use_cache else (None, None)
            if problem is not None:
                info[name]["cache_rejected"] += 1
                _log.warning(
                    "housner: warning: cache entry %s (%s, motion %d) %s; recomputed",
                    cache_dir / k[:2] / f"{k}.npz",
                    name,
                    i,
                    problem,
                )
            if row is not None:
                row.update(motion_id=i, cached=True)
                rows[(name, i)] = row
                info[name]["cached"] += 1
            else:
                todo.append((i, m))
        n_workers = 1 if scheduler is None and jobs == 1 else max(jobs, 1)
        size = chunk_size or max(1, min(10, math.ceil(len(todo) / (4 * n_workers))))
        per_engine.append([(name, settings, todo[c : c + size], effects) for c in range(0, len(todo), size)])
    # Engines interleaved, chunk by chunk: the progress bar's rate (and time left) then mixes fast
    # and slow engines from the start instead of extrapolating the fastest one.
    chunks: list[_Chunk] = []
    for k in range(max((len(p) for p in per_engine), default=0)):
        for p in per_engine:
            if k < len(p):
                chunks.append(_Chunk(len(chunks), *p[k]))

    total = sum(len(c.items) for c in chunks)
    if scheduler is not None:
        how = "on the Dask cluster"
    elif jobs == 1:
        how = "in this process"
    else:
        how = f"starting {min(jobs, len(chunks))} worker processes"
    bar = _Progress(total, progress, how)

    def on_record(name: str, r: dict) -> None:
        r["cached"] = False
        rows[(name, r["motion_id"])] = r
        info[name]["wall_s"] += r["wall_s"]
        if use_cache and r["status"] == "ok":
            k = keys[(name, r["motion_id"])]
            try:
                _store_cached(cache_dir / k[:2] / f"{k}.npz", k, r)
            except OSError:
                pass  # a read-only cache must not fail the run
        bar.update(name)

    deaths: dict[tuple[str, int], list[str]] = {}
    t_start = time.perf_counter()
    try:
        if chunks:
            if scheduler is not None:
                _run_dask(chunks, specimen, scheduler, on_record)
            elif jobs == 1:
                for c in chunks:
                    for r in _iter_chunk(c.engine, c.settings, specimen, c.items, c.effects):
                        on_record(c.engine, r)
            else:
                _run_pool(chunks, specimen, jobs, on_record, deaths)
    except KeyboardInterrupt:
        bar.close()
        raise RunInterrupted(bar.done, total, cached=use_cache) from None
    bar.close()
    elapsed = time.perf_counter() - t_start
    for (name, _i), reasons in deaths.items():
        info[name]["worker_deaths"] += len(reasons)

    table = []
    histories = {}
    for name in engines:
        for i in range(len(motions)):
            if (name, i) not in rows:  # cannot happen by design; never leave a record out silently
                rows[(name, i)] = _failed(i, "no result came back from the workers")
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
                "effects": effects_label(effects),
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


def effects_series(engine: str, effects: tuple) -> str:
    """The series name of an engine's records with ``effects``, e.g. ``housner + restitution(r=0.95)``."""
    return f"{engine} + {effects_label(effects)}"


def _with_effects(scenario, motions, eng_settings, results, histories, info, **run) -> tuple:
    """Run every engine again with the scenario's [[effects]]; its rows join the run as series "ENGINE + EFFECTS".

    The rows keep the engine's name in ``effects_series`` form in ``engine`` (so the statistics, the
    report and the pytest assertions compare them like any engine, against the same engine without
    the effects) and the effects in ``effects``; ``info`` gets one entry per series, with ``engine``
    and ``effects``.
    """
    eff = scenario.effects
    res_e, hist_e, info_e = run_engines(scenario.specimen, motions, eng_settings, effects=eff, **run)
    series = {name: effects_series(name, eff) for name in eng_settings}
    res_e = res_e.assign(engine=res_e["engine"].map(series))
    hist = {**histories, **{(series[n], i): th for (n, i), th in hist_e.items()}}
    data = [effect_data(e) for e in eff]
    info = {**info, **{series[n]: {**v, "engine": n, "effects": data} for n, v in info_e.items()}}
    return pd.concat([results, res_e], ignore_index=True), hist, info


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
    scenario.check_engines(names)  # unknown names and refused settings fail here, naming the file
    out = Path(out) if out else Path("runs") / scenario.name
    check_output_dir(out, "run directory", files=RUN_FILES)  # before the work, not after it
    t0 = time.perf_counter()
    motions, mmeta = scenario.build_motions(n_motions, seed=seed, band_check=True)  # the report shows the bands
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
    if scenario.effects:
        results, histories, info = _with_effects(
            scenario,
            motions,
            eng_settings,
            results,
            histories,
            info,
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

        spread = seed_spread(scenario, k, cache_dir=cache_dir, use_cache=use_cache)
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
    if scenario.effects:
        meta["effects"] = {
            "label": effects_label(scenario.effects),
            "effects": [effect_data(e) for e in scenario.effects],
        }
    write_run(out, results, histories, motions, meta)
    return RunResult(results, histories, motions, meta, out)
