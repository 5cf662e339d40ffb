"""Where the runner's records are simulated in parallel on this machine: a fault-tolerant process pool.

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
The same chunks run on a Dask cluster in :mod:`housner.scenarios.execution.cluster`;
:class:`Progress` is the progress bar of both.
"""

from __future__ import annotations

import multiprocessing as mp
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
from multiprocessing.connection import wait as wait_for_connections
from multiprocessing.reduction import ForkingPickler
from typing import Any

from housner.motion import GroundMotion
from housner.scenarios.execution.chunks import (
    WORKER_FILE,
    WORKER_RUN_NAME,
    unpack,
    worker_main,
)
from housner.specimen import Specimen

__all__ = ["Chunk", "Progress", "RunInterrupted", "failed_record", "run_pool"]


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
_PROTOCOL = 5  # of the chunks' messages (see _Worker.give)


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
        ``Connection.send`` would) and sent by the sender thread, as ``send`` sends it.

        Pickle protocol 5: a motion's samples go into the message, and come out of it in the worker,
        without the extra copy protocol 4 makes on each side (the parent pickles a chunk of motions in half
        the time, the worker unpickles it in a third; the same arrays, read-only as in the parent)."""
        keys = chunk.keys if cache_dir is not None else None
        msg = (
            chunk.id,
            chunk.engine,
            chunk.settings,
            specimen,
            chunk.items,
            chunk.effects,
            chunk.batched,
            cache_dir,
            keys,
            thetas,
        )
        data = ForkingPickler.dumps(msg, _PROTOCOL)
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


class _PoolRun:
    """The state of one :func:`run_pool` call: the chunks left to give out, the deaths so far, and the
    steps of its loop (give work out, take a message, account for a worker that died, give up)."""

    def __init__(
        self,
        pool: _Pool,
        chunks: list[Chunk],
        specimen: Specimen,
        jobs: int,
        on_record: Any,
        deaths: dict[tuple[str, int], list[str]],
        worker_deaths: dict[str, int],
        cache_dir: str | None,
        thetas: bool,
    ):
        self.pool = pool
        self.specimen, self.jobs, self.on_record = specimen, jobs, on_record
        self.deaths, self.worker_deaths = deaths, worker_deaths
        self.cache_dir, self.thetas = cache_dir, thetas
        self.todo = deque(chunks)
        self.next_id = max((c.id for c in chunks), default=0) + 1
        self.n_dead, self.max_dead = 0, 2 * jobs + 8
        self.last_reason = ""

    def new_part(self, chunk: Chunk, items: list[tuple[int, GroundMotion]], batched: bool | None = None) -> Chunk:
        """Some of ``chunk``'s records as a chunk of their own, under the next free id."""
        part = chunk.part(self.next_id, items, batched=batched)
        self.next_id += 1
        return part

    def loop(self) -> None:
        """Give out the chunks and take the workers' messages until every chunk is done (or the run gives up)."""
        while self.todo or any(w.chunks for w in self.pool.workers):
            if self.n_dead > self.max_dead:
                self.give_up()
                break
            self.give_out()
            busy = {w.conn: w for w in self.pool.workers if w.chunks}
            for conn in wait_for_connections(list(busy)):
                self.take(busy[conn])

    def give_out(self) -> None:
        """Give the next chunks to the workers that take them, starting workers up to ``jobs``."""
        todo = self.todo
        for w in self.pool.workers:
            while todo and w.takes(todo[0]):
                w.give(todo.popleft(), self.specimen, self.cache_dir, self.thetas)
        while todo and len(self.pool.workers) < self.jobs:
            w = self.pool.start()
            while todo and w.takes(todo[0]):
                w.give(todo.popleft(), self.specimen, self.cache_dir, self.thetas)

    def take(self, w: _Worker) -> None:
        """Read one message of ``w`` and act on it."""
        try:
            kind, _cid, payload = w.conn.recv()
        except (EOFError, OSError):
            self.lost(w)
            return
        if kind == "ready":
            w.ready = True
        elif kind == "start":
            w.running, w.next = True, 0
        elif kind == "rec":
            rows = unpack(payload)
            w.next += len(rows)
            for row in rows:
                self.on_record(w.chunks[0].engine, row)
        else:  # "done"
            w.chunks.popleft()
            w.running, w.next = False, 0

    def lost(self, w: _Worker) -> None:
        """A worker died: count it, and queue again (or fail) the records it had not reported."""
        w.proc.join(2.0)
        reason = self.last_reason = _death_reason(w.proc.exitcode)
        self.n_dead += 1
        self.pool.drop(w)
        given = list(w.chunks)
        if not w.running:  # no chunk of its had started (it died starting up, or idle): run them elsewhere
            self.todo.extendleft(reversed(given))
            return
        chunk, rest = given[0], given[0].items[w.next :]
        self.todo.extendleft(reversed(given[1:]))  # prefetched, never started
        if not rest:
            return
        self.worker_deaths[chunk.engine] = self.worker_deaths.get(chunk.engine, 0) + 1
        if chunk.batched and len(rest) > 1:  # which record killed it is unknown: each is retried alone, last
            for i, m in rest:
                self.deaths.setdefault((chunk.engine, i), []).append(f"{reason}, running it in a batch of {len(rest)}")
                self.todo.append(self.new_part(chunk, [(i, m)], batched=False))
            return
        self.retry_or_fail(chunk, rest, reason)

    def retry_or_fail(self, chunk: Chunk, rest: list[tuple[int, GroundMotion]], reason: str) -> None:
        """After a death in a chunk run record by record: its other records re-queued first, the record that
        was running retried once, last, or listed as failed if it had killed a worker before."""
        (i, m), rest = rest[0], rest[1:]
        if rest:
            self.todo.appendleft(self.new_part(chunk, rest))
        reasons = self.deaths.setdefault((chunk.engine, i), [])
        reasons.append(reason)
        if len(reasons) >= 2:
            msg = f"the worker process died while simulating this record: {reasons[0]}; on the retry: {reasons[1]}"
            self.on_record(chunk.engine, failed_record(i, msg))
        else:
            self.todo.append(self.new_part(chunk, [(i, m)], batched=False))  # the one retry, last

    def give_up(self) -> None:
        """Too many workers died: fail every record not yet reported, and stop the workers."""
        msg = f"not run: {self.n_dead} worker processes died (the last {self.last_reason}); gave up"
        todo = self.todo
        for w in self.pool.workers:
            if w.chunks:
                first = w.chunks[0]
                todo.extendleft(reversed(list(w.chunks)[1:]))
                todo.appendleft(first.part(0, first.items[w.next :] if w.running else first.items))
                w.chunks.clear()
        for c in todo:
            for i, _ in c.items:
                self.on_record(c.engine, failed_record(i, msg))
        todo.clear()
        self.pool.kill()


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
    run = _PoolRun(pool, chunks, specimen, jobs, on_record, deaths, worker_deaths, cache_dir, thetas)
    try:
        run.loop()
    except KeyboardInterrupt:
        # A worker stores a record's entry, then reports it: take the reports already on their way, so that
        # the records counted as done are those in the cache; then stop the workers at once.
        try:
            _drain(pool, run.take)
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
        ready = wait_for_connections(list(busy), timeout=min(quiet, left)) if busy else []
        if not ready:
            return
        for conn in ready:
            take(busy[conn])


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
