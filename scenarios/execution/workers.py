"""Where the runner's records are simulated: in this process, in a fault-tolerant process pool, or on Dask.

Work is split into chunks of (engine, motions, effects); each chunk runs where it is
sent (:mod:`housner.scenarios.execution.chunks`): in one batched call where the engine
batches (the analytic engine), else record by record, each ok record's cache entry
written by the process that computed it. Pool workers report a chunk's records as they
finish (a batched chunk at once, in bulk) and get their next chunk while they run the
current one, so that they never wait for the parent. A worker that dies (killed,
crashed in native code, out of memory) loses only the records it had not reported:
the record it was running is retried once in a fresh worker, then listed as failed
with the reason (``killed by SIGKILL``...), and the rest of its chunk is re-queued; in a
batched chunk, where the record that killed it is unknown, each unfinished record is
retried alone once. Ctrl-C stops the workers at once and raises :class:`RunInterrupted`.
"""

from __future__ import annotations

import asyncio
import multiprocessing as mp
import multiprocessing.connection
import os
import queue as _queue
import runpy
import signal
import sys
import threading
import time
from collections import deque
from contextlib import contextmanager
from dataclasses import dataclass, replace
from multiprocessing.reduction import ForkingPickler
from typing import Any

from housner.motion import GroundMotion
from housner.scenarios.execution.chunks import (
    WORKER_FILE,
    WORKER_RUN_NAME,
    run_chunk,
    unpack,
    worker_main,
)
from housner.specimen import Specimen

__all__ = ["RunInterrupted", "SchedulerError", "connect_scheduler"]


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
class Chunk:
    """Records of one engine sent to a worker together; ``id`` identifies it (never its size)."""

    id: int
    engine: str
    settings: dict
    items: list[tuple[int, GroundMotion]]
    effects: tuple = ()
    batched: bool = False  # one simulate_many call for the chunk (the engine batches)
    keys: dict[int, str] | None = None  # motion_id -> cache key, for the process that computes to store the entry

    def part(self, chunk_id: int, items: list[tuple[int, GroundMotion]], batched: bool | None = None) -> Chunk:
        """Some of this chunk's records, as a chunk of their own."""
        return replace(self, id=chunk_id, items=items, batched=self.batched if batched is None else batched)


def failed_record(i: int, msg: str) -> dict:
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


_STOP = object()  # ends a worker's sender thread


class _Worker:
    """One worker process, its pipe, and the chunks given to it (run in order, the first once started).

    Chunks are sent by a thread of the parent's, so that the parent never waits on a pipe
    while a worker is busy or starting; the process itself runs ``chunks.py`` by its path
    (:data:`~housner.scenarios.execution.chunks.WORKER_FILE`), without the package's imports.
    """

    def __init__(self, ctx: Any):
        parent, child = ctx.Pipe()
        if os.path.isfile(WORKER_FILE):  # the module by its path: none of the package's imports
            target, args = runpy.run_path, (WORKER_FILE, {"_CONN": child}, WORKER_RUN_NAME)
        else:  # installed where files have no path (a zip): by its name
            target, args = worker_main, (child,)
        with _sigint_ignored():
            self.proc = ctx.Process(target=target, args=args, daemon=True, name="housner-worker")
            self.proc.start()
        child.close()
        self.conn = parent
        self.chunks: deque[Chunk] = deque()  # given to it, in order
        self.running = False  # the first of `chunks` has started
        self.next = 0  # records of the running chunk reported so far
        self.ready = False  # the process has started and can run records
        self._outbox: _queue.SimpleQueue = _queue.SimpleQueue()
        self._sender = threading.Thread(target=self._send_loop, name="housner-sender", daemon=True)
        self._sender.start()

    def _send_loop(self) -> None:
        while True:
            msg = self._outbox.get()
            if msg is _STOP:
                return
            try:
                self.conn.send_bytes(msg)
            except Exception:  # the worker died (broken pipe) or the pipe was closed: the parent's loop sees it
                return

    def takes(self, chunk: Chunk) -> bool:
        """Whether to give it ``chunk`` now: when idle, or as the next of a batched chunk (prefetched)."""
        return not self.chunks or (len(self.chunks) == 1 and self.chunks[0].batched and chunk.batched)

    def give(self, chunk: Chunk, specimen: Specimen, cache_dir: str | None, thetas: bool) -> None:
        """Queue ``chunk`` for it. The message is pickled here (an object that cannot be raises here, as
        ``Connection.send`` would) and sent by the sender thread, as ``send`` sends it."""
        keys = chunk.keys if cache_dir is not None else None
        msg = (chunk.id, chunk.engine, chunk.settings, specimen, chunk.items, chunk.effects, chunk.batched, cache_dir,
               keys, thetas)  # fmt: skip
        data = ForkingPickler.dumps(msg)
        self.chunks.append(chunk)
        self._outbox.put(data)

    def ask_to_exit(self) -> None:
        self._outbox.put(ForkingPickler.dumps(None))
        self._outbox.put(_STOP)

    def stop(self, wait: float) -> None:
        """Ask the worker to exit, wait ``wait`` seconds, then terminate and kill it."""
        if wait > 0:
            self.ask_to_exit()
            self.proc.join(wait)
        if self.proc.is_alive():
            self.proc.terminate()
            self.proc.join(0.5)
        if self.proc.is_alive():
            self.proc.kill()
            self.proc.join(0.5)
        self._outbox.put(_STOP)
        self._sender.join(0.5)
        self.conn.close()


class _Pool:
    """Worker processes, started as the work needs them and kept until :meth:`close`: across the runs
    of one caller (a study's sizes, through its progress bar: :meth:`Progress.pool_for`), or one run."""

    def __init__(self, jobs: int):
        self.jobs = jobs
        self.ctx = mp.get_context("spawn")
        self.workers: list[_Worker] = []

    def start(self) -> _Worker:
        w = _Worker(self.ctx)
        self.workers.append(w)
        return w

    def drop(self, w: _Worker) -> None:
        """Forget a worker that died (its process is reaped, its pipe closed)."""
        self.workers.remove(w)
        w.stop(0.0)

    def kill(self) -> None:
        """Stop every worker at once (Ctrl-C, an error)."""
        for w in self.workers:
            w.stop(0.0)
        self.workers.clear()

    def close(self, wait: float = 5.0) -> None:
        """Ask every worker to exit, all together, and reap them (killing those still there after ``wait`` s)."""
        for w in self.workers:
            w.ask_to_exit()
        for w in self.workers:
            w.stop(wait)
        self.workers.clear()


def run_pool(
    chunks: list[Chunk],
    specimen: Specimen,
    jobs: int,
    on_record: Any,
    deaths: dict[tuple[str, int], list[str]],
    *,
    worker_deaths: dict[str, int] | None = None,
    pool: _Pool | None = None,
    cache_dir: str | None = None,
    thetas: bool = True,
) -> None:
    """Run ``chunks`` on ``jobs`` worker processes, calling ``on_record(engine, row)`` per record.

    Records come back as they finish, so a worker that dies loses only the records it
    had not reported. The record it was running is retried once in a fresh worker (the
    chunk's other unfinished records are simply re-queued); if it kills its worker again
    it is listed as failed with both reasons. In a batched chunk the record that killed
    the worker is unknown: each of its unfinished records is retried alone, once (that
    death counts as its first try). ``deaths`` collects (engine, motion_id) -> reasons;
    ``worker_deaths`` counts, per engine, the workers that died running its records.
    After ``2 jobs + 8`` deaths the rest of the work fails instead of spawning more
    workers.

    ``pool`` (with ``jobs`` workers) is used and left running; without it a pool is
    started and closed here. ``cache_dir``: the workers store each ok record's entry
    (the chunks' ``keys``). ``thetas``: the workers send the histories back.
    """
    own = pool is None or pool.jobs != jobs
    if own:
        pool = _Pool(jobs)
    worker_deaths = {} if worker_deaths is None else worker_deaths
    todo = deque(chunks)
    next_id = max((c.id for c in chunks), default=0) + 1
    n_dead, max_dead = 0, 2 * jobs + 8
    last_reason = ""

    def lost(w: _Worker) -> None:
        nonlocal next_id, n_dead, last_reason
        w.proc.join(2.0)
        reason = last_reason = _death_reason(w.proc.exitcode)
        n_dead += 1
        pool.drop(w)
        given = list(w.chunks)
        if not w.running:  # no chunk of its had started (it died starting up, or idle): run them elsewhere
            todo.extendleft(reversed(given))
            return
        chunk, rest = given[0], given[0].items[w.next :]
        todo.extendleft(reversed(given[1:]))  # prefetched, never started
        if not rest:
            return
        worker_deaths[chunk.engine] = worker_deaths.get(chunk.engine, 0) + 1
        if chunk.batched and len(rest) > 1:  # which record killed it is unknown: each is retried alone, last
            for i, m in rest:
                deaths.setdefault((chunk.engine, i), []).append(f"{reason}, running it in a batch of {len(rest)}")
                todo.append(chunk.part(next_id, [(i, m)], batched=False))
                next_id += 1
            return
        (i, m), rest = rest[0], rest[1:]
        if rest:
            todo.appendleft(chunk.part(next_id, rest))
            next_id += 1
        reasons = deaths.setdefault((chunk.engine, i), [])
        reasons.append(reason)
        if len(reasons) >= 2:
            msg = f"the worker process died while simulating this record: {reasons[0]}; on the retry: {reasons[1]}"
            on_record(chunk.engine, failed_record(i, msg))
        else:
            todo.append(chunk.part(next_id, [(i, m)], batched=False))  # the one retry, last
            next_id += 1

    def give_out() -> None:
        for w in pool.workers:
            while todo and w.takes(todo[0]):
                w.give(todo.popleft(), specimen, cache_dir, thetas)
        while todo and len(pool.workers) < jobs:
            w = pool.start()
            while todo and w.takes(todo[0]):
                w.give(todo.popleft(), specimen, cache_dir, thetas)

    def give_up() -> None:
        msg = f"not run: {n_dead} worker processes died (the last {last_reason}); gave up"
        for w in pool.workers:
            if w.chunks:
                first = w.chunks[0]
                todo.extendleft(reversed(list(w.chunks)[1:]))
                todo.appendleft(first.part(0, first.items[w.next :] if w.running else first.items))
                w.chunks.clear()
        for c in todo:
            for i, _ in c.items:
                on_record(c.engine, failed_record(i, msg))
        todo.clear()
        pool.kill()

    def take(w: _Worker) -> None:
        """Read one message of ``w`` and act on it."""
        try:
            kind, _cid, payload = w.conn.recv()
        except (EOFError, OSError):
            lost(w)
            return
        if kind == "ready":
            w.ready = True
        elif kind == "start":
            w.running, w.next = True, 0
        elif kind == "rec":
            rows = unpack(payload)
            w.next += len(rows)
            for row in rows:
                on_record(w.chunks[0].engine, row)
        else:  # "done"
            w.chunks.popleft()
            w.running, w.next = False, 0

    try:
        while todo or any(w.chunks for w in pool.workers):
            if n_dead > max_dead:
                give_up()
                break
            give_out()
            busy = {w.conn: w for w in pool.workers if w.chunks}
            for conn in mp.connection.wait(list(busy)):
                take(busy[conn])
    except KeyboardInterrupt:
        # A worker stores a record's entry, then reports it: take the reports already on their way, so that
        # the records counted as done are those in the cache; then stop the workers at once.
        try:
            _drain(pool, take)
        finally:
            pool.kill()
        raise
    except BaseException:  # an error here: stop the workers now, do not wait for them
        pool.kill()
        raise
    if own:
        pool.close()


def _drain(pool: _Pool, take: Any, quiet: float = 0.05, limit: float = 0.5) -> None:
    """Take the workers' messages until none comes for ``quiet`` seconds (``limit`` seconds at most)."""
    deadline = time.monotonic() + limit
    while (left := deadline - time.monotonic()) > 0:
        busy = {w.conn: w for w in pool.workers if w.chunks}
        ready = mp.connection.wait(list(busy), timeout=min(quiet, left)) if busy else []
        if not ready:
            return
        for conn in ready:
            take(busy[conn])


def run_dask(chunks: list[Chunk], specimen: Specimen, scheduler: Any, on_record: Any) -> None:
    """Run ``chunks`` on a Dask cluster; a task that fails twice (Dask retries it once) fails its records.

    ``scheduler`` is a connected client, used as it is (never the process's default client, which a
    command-line run has none of), or an address, connected to here and closed after. A worker that dies
    is the scheduler's to handle: its tasks are run again on the others (up to the scheduler's
    ``allowed-failures``, then they fail with ``KilledWorker`` and their records are listed as failed).
    The results (histories included) come back in bulk, one packed set per chunk; the caller stores the
    cache entries (a cluster's workers need not see this machine's cache)."""
    from distributed import Client, KilledWorker, as_completed

    client = scheduler if isinstance(scheduler, Client) else connect_scheduler(scheduler)
    futs: dict[Any, Chunk] = {}
    try:
        for c in chunks:
            f = client.submit(run_chunk, c.engine, c.settings, specimen, c.items, c.effects, c.batched, pure=False,
                              retries=1)  # fmt: skip
            futs[f] = c
        # Without a loop, as_completed takes the default client's, and a command-line run has no default client.
        for f in as_completed(futs, loop=client.loop):
            c = futs[f]
            try:
                res = unpack(f.result())
            except KilledWorker as e:  # the workers running it died, as often as the scheduler allows
                n = e.allowed_failures
                msg = (f"KilledWorker: the Dask workers running it died {n + 1} time(s), all that the scheduler "
                       f"allows (distributed.scheduler.allowed-failures = {n}); see the workers' logs")  # fmt: skip
                res = [failed_record(i, msg) for i, _ in c.items]
            except Exception as e:  # the task raised, or could not run, twice
                res = [failed_record(i, f"Dask task failed twice: {type(e).__name__}: {e}") for i, _ in c.items]
            for r in res:
                on_record(c.engine, r)
    except BaseException:
        client.cancel(list(futs))
        raise
    finally:
        if not isinstance(scheduler, Client):
            client.close(timeout=2)


class Progress:
    """Progress on stderr. Until the first record comes back (workers starting, engines
    loading and, after an update, numba compiling for 10-20 s) one line says so; the bar,
    and with it the time-left estimate, starts with the first finished record, so the
    estimate is made of simulation time only.

    A bar of the caller's spans several runs (a study's sizes): the worker processes of
    those runs are kept from one to the next (:meth:`pool_for`) and stopped by :meth:`close`,
    which the caller calls once, when its runs are over."""

    def __init__(self, total: int, enabled: bool, how: str):
        self.total = total
        self.done = 0
        self.enabled = enabled and total > 0
        self.bar = None
        self.pool: _Pool | None = None
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

    def pool_for(self, jobs: int) -> _Pool:
        """The worker processes of the runs under this bar (``jobs`` of them), kept until :meth:`close`."""
        if self.pool is None or self.pool.jobs != jobs:
            if self.pool is not None:
                self.pool.close()
            self.pool = _Pool(jobs)
        return self.pool

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
        if self.pool is not None:
            self.pool.close()
            self.pool = None
