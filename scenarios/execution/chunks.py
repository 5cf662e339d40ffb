"""One chunk of records, run wherever it is sent: simulated, each record's cache entry written, packed.

A chunk is the records of one engine sent to a worker together. Where the engine
batches (its own ``simulate_many``, as the analytic engine's: one compiled call for
the whole chunk), the chunk is one call; otherwise its records run one at a time and
are reported as each finishes. A record that fails is data (``status = "failed"`` and
its error), never an exception. Each ok record's cache entry (its own file, key and
checksum: :func:`store_entry`) is written before the record is reported, so that a
record counted as done is in the cache.

This module is the worker's side and imports nothing of ``housner.scenarios`` (only
the standard library, numpy and, when a chunk runs, ``housner.engines``): pool
worker processes load it by its path (:data:`WORKER_FILE`, ``runpy``), so that they
start in a fraction of a second instead of importing the package's layers (pandas,
scipy, the campaigns). The cache entry format lives here for the same reason;
:mod:`housner.scenarios.execution.cache` re-exports it.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import signal
import struct
import sys
import threading
import time
import traceback
import zipfile
import zlib
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any

import numpy as np

from housner.engines.base import Engine, get_engine
from housner.motion import GroundMotion

#: This file: what a pool worker process runs (``runpy.run_path(WORKER_FILE, run_name=WORKER_RUN_NAME)``).
WORKER_FILE = os.path.abspath(__file__)
WORKER_RUN_NAME = "__housner_worker__"

#: Test hook, read in pool worker processes only (never in the calling process):
#: ``ENGINE:MOTION_ID:SIGNAL[:MARKER]`` makes the worker that is about to simulate
#: that record die by ``SIGNAL`` (``KILL``, ``SEGV``, ...), as a killed, crashed or
#: out-of-memory worker would. With ``MARKER`` (a file path) it happens once: the
#: first worker to get there creates the file atomically and dies, later ones run.
#: In a batched chunk every record of the chunk is "about to be simulated" when the batch starts.
CRASH_ENV = "HOUSNER_TEST_CRASH"
_IN_WORKER = False
_ENGINE_CACHE: dict[str, Any] = {}


# --------------------------------------------------------------------------
# The cache entry: one .npz per key, holding theta and the row, with the key and a checksum.

#: The row field that carries, from the process that computed a record, the damaged kernel-cache entries it
#: repaired meanwhile (never stored in the cache; the runner adds it to the engine's info).
REPAIRS = "kernel_cache_repairs"


def _entry_checksum(key: str, meta: dict, theta: np.ndarray) -> str:
    """SHA-256 of an entry's payload: its key, its row fields (canonical JSON) and theta's bytes."""
    h = hashlib.sha256()
    h.update(key.encode())
    h.update(b"\0")
    h.update(json.dumps({k: v for k, v in meta.items() if k != "sha256"}, sort_keys=True).encode())
    h.update(b"\0")
    h.update(np.ascontiguousarray(theta, dtype="<f4").tobytes())
    return h.hexdigest()


def entry_path(cache_dir: str | Path, key: str) -> Path:
    """Where the entry of ``key`` lives: ``cache_dir/<first two hex digits>/<key>.npz``."""
    return Path(cache_dir) / key[:2] / f"{key}.npz"


def entry_file(cache_dir: str | Path, key: str) -> str:
    """:func:`entry_path` as a string, made without pathlib (the plan looks up every record's)."""
    return os.path.join(cache_dir, key[:2], key + ".npz")


def load_entry(path: str | Path, key: str) -> tuple[dict | None, str | None]:
    """Read a cache entry.

    Returns
    -------
    row : dict or None
        The stored row with ``theta``, or None (absent or rejected).
    problem : str or None
        Why an existing entry was rejected (unreadable, another key, checksum mismatch).
    """
    try:
        z = np.load(path, allow_pickle=False)
    except FileNotFoundError:  # no entry (one failed open: no separate check whether it exists)
        return None, None
    except Exception as e:
        return None, f"is unreadable ({type(e).__name__})"
    try:
        with z:
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


def store_entry(path: str | Path, key: str, row: dict) -> None:
    """Write one record's entry (its row, theta, key and checksum) atomically: a temporary file, then a rename."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    _write_entry(os.fspath(path), key, row)


#: .npy headers by dtype and shape: a C-ordered array's header is its dtype's and shape's alone.
_NPY_HEADERS: dict[tuple[np.dtype, tuple[int, ...]], bytes] = {}


def _npy(a: np.ndarray) -> bytes:
    """``a`` as ``np.save`` writes it: a header, then the samples in C order.

    The header is made by numpy once per dtype and shape (an entry's theta has its record's length,
    its row the length of its text), then reused: making it was half the time an entry's bytes took to make.
    """
    if a.dtype.hasobject or (a.flags.f_contiguous and not a.flags.c_contiguous):
        return _npy_by_numpy(a)  # written otherwise (pickled, or in Fortran order): numpy's alone
    key = (a.dtype, a.shape)
    head = _NPY_HEADERS.get(key)
    if head is None:
        data = _npy_by_numpy(a)
        if len(_NPY_HEADERS) >= 4096:
            _NPY_HEADERS.clear()
        _NPY_HEADERS[key] = data[: len(data) - a.nbytes]
        return data
    return head + a.tobytes()


def _npy_by_numpy(a: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array(buf, a, allow_pickle=False)
    return buf.getvalue()


#: How an entry's temporary file is opened: as ``open(path, "wb")`` opens it (os.open adds O_CLOEXEC).
_NEW_FILE = os.O_WRONLY | os.O_CREAT | os.O_TRUNC | getattr(os, "O_BINARY", 0)
_ZIP_DATE = (1 << 5) | 1  # 1980-01-01 as a DOS date: the date np.savez gives its members


def _zip_stored(members: list[tuple[str, bytes]]) -> bytes:
    """A zip archive of ``members`` (name, bytes), stored (not deflated): what ``np.savez`` writes, made
    without ``zipfile``'s per-archive machinery (a tenth of a millisecond an entry)."""
    parts, central, offset = [], [], 0
    for name, data in members:
        n = name.encode()
        crc, size = zlib.crc32(data), len(data)
        # What the local header and the central directory's record both give: flags, method, time, date, CRC,
        # both sizes, the name's and the extra field's lengths.
        common = (0, zipfile.ZIP_STORED, 0, _ZIP_DATE, crc, size, size, len(n), 0)
        head = struct.pack(zipfile.structFileHeader, zipfile.stringFileHeader, 20, 0, *common)
        central.append(
            struct.pack(
                zipfile.structCentralDir, zipfile.stringCentralDir, 20, 3, 20, 0, *common, 0, 0, 0, 0o600 << 16, offset
            )
            + n
        )
        parts += [head, n, data]
        offset += len(head) + len(n) + size
    cd = b"".join(central)
    end = struct.pack(
        zipfile.structEndArchive, zipfile.stringEndArchive, 0, 0, len(members), len(members), len(cd), offset, 0
    )
    return b"".join([*parts, cd, end])


def _write_entry(path: str, key: str, row: dict) -> None:
    """The entry: an ``.npz`` of ``theta`` and ``row`` (as ``np.savez`` writes it; read by ``np.load``),
    made in memory and written with one call, to a temporary file renamed into place.

    Stored, not deflated: deflating theta (float32, to about 45 %) cost as much time as a quarter of
    the analytic record it stores, in the process that simulates it. Deflated entries (written by earlier
    versions) read the same.
    """
    meta = {k: v for k, v in row.items() if k not in ("theta", "motion_id", REPAIRS)}
    meta["theta_max_over_alpha"] = str(meta["theta_max_over_alpha"])
    meta["key"] = key
    theta = np.ascontiguousarray(row["theta"], dtype=np.float32)
    meta["sha256"] = _entry_checksum(key, meta, theta)
    data = _zip_stored([("theta.npy", _npy(theta)), ("row.npy", _npy(np.array(json.dumps(meta))))])
    tmp = f"{path}.{os.getpid()}.tmp"
    try:
        fd = os.open(tmp, _NEW_FILE, 0o666)  # what open(tmp, "wb") does, without its buffer and checks
        try:
            view = memoryview(data)
            while view:
                view = view[os.write(fd, view) :]
        finally:
            os.close(fd)
        os.replace(tmp, path)
    except BaseException:
        with suppress(OSError):
            os.unlink(tmp)
        raise


#: Cache folders this process made or found (each entry's folder is made once per process).
_FOLDERS: set[str] = set()


def store_entries(cache_dir: str | Path, keys: dict[int, str], rows: list[dict]) -> None:
    """Write the entry of every ok row of a chunk (one file each, its own key and checksum).

    A cache that cannot be written (read-only, full) skips the entry: it must not fail the run.
    """
    for r in rows:
        key = keys.get(r["motion_id"])
        if r["status"] != "ok" or key is None:
            continue
        path = entry_file(cache_dir, key)
        folder = os.path.dirname(path)
        entry = {**r, "cached": False}  # the row as the runner holds it
        try:
            if folder not in _FOLDERS:
                os.makedirs(folder, exist_ok=True)
                _FOLDERS.add(folder)
            try:
                _write_entry(path, key, entry)
            except FileNotFoundError:  # its folder was removed meanwhile
                os.makedirs(folder, exist_ok=True)
                _write_entry(path, key, entry)
        except OSError:
            pass


# --------------------------------------------------------------------------
# Simulating
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


def _warm_up(eng: Any, specimen: Any) -> None:
    """Run the engine once on 20 ms of free rocking (twice, batched, where it batches: the code its chunks
    run), so that compilation and model building are done before the first record (its ``wall_s`` is then
    the record's own)."""
    m = GroundMotion.free_vibration(0.3 * specimen.alpha, 0.02, 0.002, name="warm-up")
    try:
        if engine_batches(eng):
            with _one_thread():
                eng.simulate_many(specimen, [m, m])
        else:
            eng.simulate(specimen, m)
    except Exception:
        pass  # a real record will report whatever is wrong


def _settings_id(name: str, settings: dict) -> str:
    try:
        return name + json.dumps(settings, sort_keys=True, default=repr)
    except (TypeError, ValueError):
        return name + repr(sorted(settings.items(), key=repr))


def _worker_engine(name: str, settings: dict, specimen: Any = None):
    key = _settings_id(name, settings)
    eng = _ENGINE_CACHE.get(key)
    if eng is None:
        eng = get_engine(name, **settings)
        if specimen is not None:
            _warm_up(eng, specimen)
        _ENGINE_CACHE[key] = eng
    return eng


def engine_batches(engine: Any) -> bool:
    """Whether ``engine`` (an instance or class) batches records: its own ``simulate_many``, written with its
    ``simulate``.

    A subclass that changes ``simulate`` or ``_simulate`` but inherits a parent's
    ``simulate_many`` (which would bypass the change) runs record by record.
    """
    cls = engine if isinstance(engine, type) else type(engine)

    def owner(attr: str) -> type:
        return next((k for k in cls.__mro__ if attr in vars(k)), Engine)

    own = owner("simulate_many")
    return own is not Engine and all(issubclass(own, owner(a)) for a in ("simulate", "_simulate"))


@contextmanager
def _one_thread():
    """Numba kernels on one thread meanwhile: a chunk runs on the one core its worker (or a 1-job run) was given."""
    numba = sys.modules.get("numba")
    if numba is None:
        yield
        return
    n = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(n)


def _ok_row(i: int, resp: Any, wall: float) -> dict:
    return {
        "motion_id": i,
        "status": "ok",
        "error": "",
        "wall_s": wall,
        "theta_max_over_alpha": float(resp.theta_max_over_alpha),
        "overturned": bool(resp.overturned),
        "n_impacts": int(resp.n_impacts),
        "theta": np.asarray(resp.theta, dtype=np.float32),  # checked finite by the engine (check_response)
    }


def _failed_row(i: int, e: BaseException, wall: float) -> dict:
    tb = traceback.extract_tb(e.__traceback__)
    where = f" ({tb[-1].filename.rsplit('/', 1)[-1]}:{tb[-1].lineno})" if tb else ""
    return {"motion_id": i, "status": "failed", "error": f"{type(e).__name__}: {e}{where}", "wall_s": wall}


def _simulate_one(eng: Any, specimen: Any, i: int, motion: Any, effects: tuple = ()) -> dict:
    t0 = time.perf_counter()
    try:
        resp = eng.simulate(specimen, motion, effects) if effects else eng.simulate(specimen, motion)
        return _ok_row(i, resp, time.perf_counter() - t0)
    except Exception as e:
        return _failed_row(i, e, time.perf_counter() - t0)


def _simulate_batch(eng: Any, specimen: Any, items: list, effects: tuple) -> list[dict]:
    """The chunk in one ``simulate_many`` call; each record's ``wall_s`` is its share of the call.

    A record the engine fails on is returned in its place (``errors="return"``); anything else
    the call raises reruns the chunk record by record, so that the failing record is named.
    """
    t0 = time.perf_counter()
    try:
        with _one_thread():
            out = eng.simulate_many(specimen, [m for _, m in items], effects, errors="return")
    except Exception:
        return [_simulate_one(eng, specimen, i, m, effects) for i, m in items]
    share = (time.perf_counter() - t0) / len(items)
    return [
        _failed_row(i, r, share) if isinstance(r, BaseException) else _ok_row(i, r, share)
        for (i, _), r in zip(items, out, strict=True)
    ]


def iter_chunk(
    name: str,
    settings: dict,
    specimen: Any,
    items: list,
    effects: tuple = (),
    *,
    batched: bool = False,
    cache_dir: str | None = None,
    keys: dict[int, str] | None = None,
):
    """Run one engine on a chunk; yield lists of result rows as they finish (failures are data).

    Parameters
    ----------
    name, settings : str, dict
        The engine and its settings.
    specimen : Specimen
    items : list of (int, GroundMotion)
        (motion_id, motion) of the chunk.
    effects : tuple
        Physical effects of every record.
    batched : bool
        Run the chunk in one ``simulate_many`` call (one list yielded); else record by
        record (one list per record, as each finishes).
    cache_dir, keys : str and dict, optional
        Write each ok record's cache entry (``keys``: motion_id -> cache key) before
        yielding it. None: the caller stores them.
    """
    try:
        eng = _worker_engine(name, settings, specimen)
    except Exception as e:  # the engine itself cannot start: every record of the chunk fails
        msg = f"{type(e).__name__}: {e}"
        yield [{"motion_id": i, "status": "failed", "error": msg, "wall_s": 0.0} for i, _ in items]
        return
    for rows in _parts(eng, name, specimen, items, effects, batched):
        if cache_dir is not None and keys:
            store_entries(cache_dir, keys, rows)
        yield rows


def repairs_so_far() -> int:
    """Damaged kernel-cache entries repaired so far in this process (housner.effects.codegen.kernel_cache_repairs)."""
    from housner.effects.codegen import kernel_cache_repairs

    return sum(kernel_cache_repairs().values())


def _counted(rows: list[dict], before: int) -> list[dict]:
    """``rows``, the first carrying the kernel-cache repairs made while they were computed (when there were)."""
    n = repairs_so_far() - before
    if n and rows:
        rows[0][REPAIRS] = n
    return rows


def _parts(eng: Any, name: str, specimen: Any, items: list, effects: tuple, batched: bool):
    """The chunk's rows: all at once from one batched call, or one record at a time."""
    if batched and len(items) > 1:
        for i, _ in items:
            _maybe_crash(name, i)
        before = repairs_so_far()
        yield _counted(_simulate_batch(eng, specimen, items, effects), before)
        return
    for i, m in items:
        _maybe_crash(name, i)
        before = repairs_so_far()
        yield _counted([_simulate_one(eng, specimen, i, m, effects)], before)


def run_chunk(name: str, settings: dict, specimen: Any, items: list, effects: tuple = (), batched: bool = False):
    """A whole chunk's rows, packed (:func:`pack`; the task a Dask worker runs: its caller stores the entries)."""
    rows = [r for part in iter_chunk(name, settings, specimen, items, effects, batched=batched) for r in part]
    return pack(rows, thetas=True)


# --------------------------------------------------------------------------
# Rows in bulk: one message per chunk (or record), figures and histories as arrays
def pack(rows: list[dict], thetas: bool) -> dict:
    """Rows as columns: the figures as arrays, every theta in one float32 array (``thetas``), failures' errors."""
    n = len(rows)
    ok = [r["status"] == "ok" for r in rows]
    out = {
        "motion_id": np.array([r["motion_id"] for r in rows], dtype=np.int64),
        "ok": np.array(ok, dtype=bool),
        "error": {j: r["error"] for j, r in enumerate(rows) if not ok[j]},
        "wall_s": np.array([r["wall_s"] for r in rows], dtype=np.float64),
        "theta_max_over_alpha": np.array([r.get("theta_max_over_alpha", np.nan) for r in rows], dtype=np.float64),
        "overturned": np.array([bool(r.get("overturned", False)) for r in rows], dtype=bool),
        "n_impacts": np.array([int(r.get("n_impacts", 0)) for r in rows], dtype=np.int64),
        REPAIRS: np.array([int(r.get(REPAIRS, 0)) for r in rows], dtype=np.int64),
        "theta": None,
    }
    if thetas:
        th = [r["theta"] if ok[j] and "theta" in r else np.empty(0, np.float32) for j, r in enumerate(rows)]
        offsets = np.zeros(n + 1, dtype=np.int64)
        np.cumsum([len(t) for t in th], out=offsets[1:])
        out["theta"] = np.concatenate(th).astype(np.float32, copy=False) if n else np.empty(0, np.float32)
        out["offsets"] = offsets
    return out


def unpack(packed: dict) -> list[dict]:
    """The rows of :func:`pack` (the same fields and Python types as the rows it was given; theta as a view)."""
    rows = []
    th, off = packed["theta"], packed.get("offsets")
    repairs = packed.get(REPAIRS)
    for j, i in enumerate(packed["motion_id"].tolist()):
        wall = float(packed["wall_s"][j])
        extra = {REPAIRS: int(repairs[j])} if repairs is not None and repairs[j] else {}
        if not packed["ok"][j]:
            rows.append({"motion_id": i, "status": "failed", "error": packed["error"][j], "wall_s": wall, **extra})
            continue
        r = {
            "motion_id": i,
            "status": "ok",
            "error": "",
            "wall_s": wall,
            "theta_max_over_alpha": float(packed["theta_max_over_alpha"][j]),
            "overturned": bool(packed["overturned"][j]),
            "n_impacts": int(packed["n_impacts"][j]),
        }
        if th is not None:
            r["theta"] = th[off[j] : off[j + 1]]
        rows.append({**r, **extra})
    return rows


# --------------------------------------------------------------------------
# A pool worker process
def worker_main(conn: Any) -> None:
    """Body of a pool worker process: run the chunks it is sent, in order, reporting as records finish.

    From the parent: ``(chunk_id, engine, settings, specimen, items, effects, batched, cache_dir, keys,
    thetas)`` per chunk; ``None`` (or a closed pipe) ends the process. To the parent:
    ``("ready", None, None)`` once started, ``("start", chunk_id, None)`` as a chunk begins,
    ``("rec", chunk_id, packed_rows)`` per finished part (:func:`pack`: the whole chunk when batched,
    else one record), ``("done", chunk_id, None)`` per chunk. Numba kernels run on one thread: the
    pool's processes are its parallelism.
    """
    global _IN_WORKER
    _IN_WORKER = True
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    if "numba" in sys.modules:
        sys.modules["numba"].set_num_threads(1)
    else:
        os.environ["NUMBA_NUM_THREADS"] = "1"
    # Importing MuJoCo loads its GL context, whose GLFW binding asks a child Python for the library's
    # version; a worker stopped meanwhile (Ctrl-C, SIGTERM) leaves that child writing into a closed pipe,
    # and its BrokenPipeError traceback lands on the run's stderr. A worker never renders: no GL context
    # (MuJoCo's own switch; a value the user set stays).
    os.environ.setdefault("MUJOCO_GL", "disable")
    try:
        conn.send(("ready", None, None))
        while True:
            try:
                msg = conn.recv()
            except (EOFError, OSError):
                return
            if msg is None:
                return
            chunk_id, name, settings, specimen, items, effects, batched, cache_dir, keys, thetas = msg
            conn.send(("start", chunk_id, None))
            for rows in iter_chunk(
                name, settings, specimen, items, effects, batched=batched, cache_dir=cache_dir, keys=keys
            ):
                conn.send(("rec", chunk_id, pack(rows, thetas)))
            conn.send(("done", chunk_id, None))
    except (BrokenPipeError, ConnectionResetError, EOFError):
        # the parent is gone or stopping (Ctrl-C, SIGTERM): nothing to report to, nothing to print
        return


if __name__ == WORKER_RUN_NAME:  # a pool worker: runpy.run_path(WORKER_FILE, {"_CONN": conn}, WORKER_RUN_NAME)
    worker_main(globals().pop("_CONN"))
    # Done: leave at once. Tearing the interpreter down (numba, the engines' libraries) takes a worker
    # tenths of a second, which its parent would wait for; a worker has nothing left to flush but its streams.
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)
