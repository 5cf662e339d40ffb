"""Where the runner's records are simulated: in this process, in a fault-tolerant process pool, or on Dask.

Work is split into chunks of (engine, motions, effects). Pool workers report
every record as it finishes. A worker that dies (killed, crashed in native
code, out of memory) loses only the record it was running: that record is
retried once in a fresh worker, then listed as failed with the reason
(``killed by SIGKILL``...); the rest of its chunk is re-queued. Ctrl-C stops
the workers at once and raises :class:`RunInterrupted`.
"""

from __future__ import annotations

import asyncio
import json
import multiprocessing as mp
import multiprocessing.connection
import os
import signal
import sys
import threading
import time
import traceback
from collections import deque
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np
from housner.engines.base import get_engine
from housner.scenarios.execution.rundir import jsonable

from housner.motion import GroundMotion
from housner.specimen import Specimen

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
    key = name + json.dumps(jsonable(settings), sort_keys=True)
    eng = _ENGINE_CACHE.get(key)
    if eng is None:
        eng = get_engine(name, **settings)
        if specimen is not None:
            _warm_up(eng, specimen)
        _ENGINE_CACHE[key] = eng
    return eng


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
    try:
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
    except (BrokenPipeError, ConnectionResetError, EOFError):
        # the parent is gone or stopping (Ctrl-C, SIGTERM): nothing to report to, nothing to print
        return


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

    def advance(self, n: int) -> None:
        """Count ``n`` records as done without running them (found in the cache)."""
        if n <= 0:
            return
        self.done += n
        if self.bar is not None:
            self.bar.update(n)

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
