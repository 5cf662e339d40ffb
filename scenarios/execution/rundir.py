"""The run directory: its files, the results columns, run.json's encoding, writing and reading it, provenance.

The one owner of the format: :func:`write_run` writes ``results.parquet`` (the columns of
:data:`RESULT_COLUMNS`, and :data:`CAMPAIGN_COLUMNS` for a campaign's run), ``histories.parquet``,
``motions.npz`` and ``run.json`` (the run's :class:`RunMeta`, non-finite floats as strings,
:func:`jsonable`; the manifest of :data:`DATA_FILES`), and :func:`load_results`, :func:`read_motions` and
:func:`read_histories` read them (for :mod:`housner.reports.run.page` and
:mod:`housner.reports.assertions.runs`). A run counts only once it is written completely: an incomplete or
mixed directory is refused (:class:`IncompleteRunError`), a run.json from before the marker read with an
:class:`UnverifiedRunWarning`. The files, their columns and how a run is written are in
``docs/reference/run-directory.md``.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import platform
import shutil
import subprocess
import tempfile
import time
import warnings
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

import housner
from housner.errors import DataFileError
from housner.motion import GroundMotion
from housner.scenarios.execution.tables import REQUIRED_COLUMNS

if TYPE_CHECKING:
    from housner.scenarios.execution.run_meta import RunMeta

#: The columns of one engine's outcome on one record, as the runner writes them (a run's and a study's table).
OUTCOME_COLUMNS = ["theta_max_over_alpha", "overturned", "n_impacts", "wall_s", "status", "error", "cached"]

RESULT_COLUMNS = ["engine", "motion_id", "motion_name", *OUTCOME_COLUMNS, "effects"]

#: The columns a campaign's run adds after :data:`RESULT_COLUMNS` (:mod:`housner.scenarios.runs.campaign_run`).
CAMPAIGN_COLUMNS = ["record_id", "observed_overturned"]

#: Files a run writes into its directory (``report.html`` is written by the CLI after it).
RUN_FILES = ("results.parquet", "histories.parquet", "motions.npz", "run.json", "report.html")
RESULTS_FILE, HISTORIES_FILE, MOTIONS_FILE, RUN_FILE, REPORT_FILE = RUN_FILES
#: The files run.json's content key covers (those written before it).
DATA_FILES = (RESULTS_FILE, HISTORIES_FILE, MOTIONS_FILE)
#: Prefix of the temporary folder a run is written into, inside its directory.
_TMP_PREFIX = ".housner-run-"


class IncompleteRunError(DataFileError):
    """A run directory whose writing did not finish, or whose files are not those its run.json was written with.

    Attributes
    ----------
    path : pathlib.Path
        The run directory.
    file : str
        The file that does not match (``run.json`` when the run is marked incomplete).
    """

    def __init__(self, run_dir: str | Path, file: str, why: str):
        self.path, self.file, self.line, self.column = Path(run_dir), file, None, None
        ValueError.__init__(self, f"run directory {self.path} is incomplete or mixes two runs: {why}; run again")


class UnverifiedRunWarning(UserWarning):
    """A run directory written before run.json carried its completion marker: read, but not checked."""


def jsonable(x: Any, *, nonfinite: str = "string") -> Any:
    """``x`` as plain JSON data, recursively: numpy scalars and arrays, paths, tuples made plain.

    Non-finite floats, which strict JSON cannot hold, become the strings "inf", "-inf" and "nan"
    (``nonfinite="string"``, run.json: :func:`housner.reports.run.page` reads them back as numbers) or null
    (``nonfinite="null"``, diagnosis.json: "no value").
    """
    if nonfinite not in ("string", "null"):
        raise ValueError(f"`nonfinite` must be 'string' or 'null', got {nonfinite!r}")
    if isinstance(x, dict):
        return {str(k): jsonable(v, nonfinite=nonfinite) for k, v in x.items()}
    if isinstance(x, (list, tuple, np.ndarray)):
        return [jsonable(v, nonfinite=nonfinite) for v in x]
    if isinstance(x, (np.bool_, bool)):
        return bool(x)
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if math.isfinite(v) else (str(v) if nonfinite == "string" else None)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, Path):
        return str(x)
    return x


def effect_data(effect: Any) -> dict:
    """An effect as plain data: its registry name and parameter values (for cache keys and run.json)."""
    return {"name": effect.name, **{k: getattr(effect, k) for k in type(effect).param_specs}}


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
    meta: RunMeta,
) -> None:
    """Write results.parquet, histories.parquet, motions.npz and run.json into ``out``, as one run.

    The files are written into a temporary folder inside ``out`` and moved into place, run.json
    last, with its completion marker and content key (docs/reference/run-directory.md); while they move, run.json
    says the directory is incomplete. A previous run's files that this run does not write
    (histories.parquet when there are none, the previous report.html) are removed with it, when
    the run.json there is housner's; files of those names that no run wrote are left, and the
    readers refuse the directory while they lie there. ``meta`` is the run's :class:`RunMeta`
    (its own ``complete`` and ``content`` are not written: these are the write's).
    """
    out.mkdir(parents=True, exist_ok=True)
    _remove_stale_temporaries(out)
    tmp = Path(tempfile.mkdtemp(prefix=f"{_TMP_PREFIX}{os.getpid()}-", dir=out))
    try:
        _write_files(tmp, results, histories, motions)
        content = {name: _digest(tmp / name) for name in DATA_FILES if (tmp / name).is_file()}
        manifest = jsonable(replace(meta, complete=None, content=None).to_json())
        (tmp / RUN_FILE).write_text(json.dumps({**manifest, "complete": True, "content": content}, indent=2))
        previous_ours = _is_ours(out / RUN_FILE)
        # from here on the directory says it is incomplete until run.json is moved in, last
        _replace_text(out / RUN_FILE, json.dumps({**manifest, "complete": False}, indent=2))
        for name in DATA_FILES:
            if name in content:
                os.replace(tmp / name, out / name)
        # the previous run's files this one does not replace (a user's own are left, and the readers refuse
        # the directory while they lie there: nothing is deleted without a word)
        for name in (n for n in (*DATA_FILES, REPORT_FILE) if n not in content):
            if previous_ours and (out / name).is_file():
                (out / name).unlink()
        os.replace(tmp / RUN_FILE, out / RUN_FILE)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _write_files(d: Path, results: pd.DataFrame, histories: dict, motions: list[GroundMotion]) -> None:
    """results.parquet, histories.parquet (when there are histories) and motions.npz, into folder ``d``."""
    results.to_parquet(d / RESULTS_FILE, index=False)
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
        pd.concat(parts, ignore_index=True).to_parquet(d / HISTORIES_FILE, index=False)
    lengths = np.array([m.n for m in motions])
    acc = np.zeros((len(motions), int(lengths.max()) if len(motions) else 0), dtype=np.float32)
    for i, m in enumerate(motions):
        acc[i, : m.n] = m.acc
    np.savez_compressed(
        d / MOTIONS_FILE,
        acc=acc,
        n=lengths,
        dt=np.array([m.dt for m in motions]),
        theta0=np.array([m.theta0 for m in motions]),
        names=np.array([m.name for m in motions]),
    )


def _digest(path: Path) -> dict:
    """A file's content key: its size [bytes] and SHA-256."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return {"bytes": path.stat().st_size, "sha256": h.hexdigest()}


def _replace_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (a temporary file beside it, then os.replace)."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _is_ours(path: Path) -> bool:
    """Whether ``path`` is a run.json housner wrote (a JSON object with housner's provenance)."""
    try:
        data = json.loads(path.read_bytes()) if path.is_file() else None
    except (OSError, ValueError):
        return False
    prov = data.get("provenance") if isinstance(data, dict) else None
    return isinstance(prov, dict) and isinstance(prov.get("versions"), dict) and "housner" in prov["versions"]


def _remove_stale_temporaries(out: Path) -> None:
    """Remove the temporary folders of runs killed while writing into ``out`` (their process is gone)."""
    for d in out.glob(f"{_TMP_PREFIX}*"):
        try:
            pid = int(d.name[len(_TMP_PREFIX) :].split("-", 1)[0])
            os.kill(pid, 0)  # raises when no such process
        except ProcessLookupError:
            shutil.rmtree(d, ignore_errors=True)
        except (ValueError, OSError):
            continue  # not ours to judge: a name of another form, or another user's live process


def check_run(run_dir: Path, meta: dict) -> None:
    """Refuse a run directory that is not one complete run (:class:`IncompleteRunError`).

    ``meta`` is its run.json. A run.json marked complete must list, with their size and SHA-256,
    exactly the files of :data:`DATA_FILES` present; one marked incomplete is refused; one
    without the marker (an earlier version's) is accepted with an :class:`UnverifiedRunWarning`.
    """
    if "complete" not in meta:
        if _is_ours(run_dir / RUN_FILE):
            warnings.warn(
                f"run directory {run_dir} was written before runs carried a completion marker: read as it is, "
                "not checked to hold one run's files (run it again to have it checked)",
                UnverifiedRunWarning,
                stacklevel=3,
            )
        return
    if meta.get("complete") is not True:
        raise IncompleteRunError(run_dir, RUN_FILE, "its writing did not finish (run.json is marked incomplete)")
    content = meta.get("content")
    if not isinstance(content, dict):
        raise IncompleteRunError(run_dir, RUN_FILE, "run.json has no content key")
    for name in DATA_FILES:
        path, want = run_dir / name, content.get(name)
        if want is None:
            if path.exists():
                raise IncompleteRunError(run_dir, name, f"{name} is not listed in run.json")
            continue
        if not path.is_file():
            raise IncompleteRunError(run_dir, name, f"{name} is missing")
        ok = isinstance(want, dict) and path.stat().st_size == want.get("bytes") and _digest(path) == want
        if not ok:
            raise IncompleteRunError(run_dir, name, f"{name} does not match run.json")


# ----------------------------------------------------------------------------
# reading
def load_results(path: str | Path) -> pd.DataFrame:
    """Read a results table from a run directory, a ``results.parquet`` or a CSV file.

    Parameters
    ----------
    path : str or pathlib.Path
        A run directory holding ``results.parquet`` (and ``run.json``), or the
        table itself (``.parquet`` or ``.csv``).

    Returns
    -------
    pandas.DataFrame
        One row per engine and motion. ``df.attrs["source"]`` holds the
        resolved path of the table and ``df.attrs["run"]`` the contents of
        ``run.json`` next to it (an empty dict if there is none).

    Raises
    ------
    IncompleteRunError
        The table is a run directory's whose writing did not finish, or whose files are not
        those its run.json was written with (:func:`check_run`).
    housner.errors.DataFileError
        When the path does not exist, cannot be read, or lacks a column of
        :data:`housner.scenarios.execution.tables.REQUIRED_COLUMNS` (the message names the file and the column).
    """
    path = Path(path).expanduser()
    if path.is_dir():
        table = path / RESULTS_FILE
        if not table.is_file():
            raise DataFileError(
                path, f"no {RESULTS_FILE} in this directory; is it a run directory? (`housner run SCENARIO --out DIR`)"
            )
        path = table
    elif not path.exists():
        raise DataFileError(path, f"no such file or directory (expected a run directory or a {RESULTS_FILE})")
    path = path.resolve()
    # a run directory's table counts only as part of one complete run: checked before it is read
    meta = read_run_json(path.parent / RUN_FILE)
    if isinstance(meta, dict) and meta and path.name == RESULTS_FILE:
        check_run(path.parent, meta)
    suffix = path.suffix.lower()
    try:
        df = pd.read_csv(path) if suffix == ".csv" else pd.read_parquet(path)
    except Exception as e:  # pyarrow and pandas raise many kinds; all mean "not a readable table"
        kind = "CSV" if suffix == ".csv" else "parquet"
        raise DataFileError(path, f"cannot read as {kind}: {e}") from None
    for col in REQUIRED_COLUMNS:
        if col not in df.columns:
            raise DataFileError(
                path,
                f"missing column `{col}` of the results table (has: {', '.join(map(str, df.columns))})",
                column=col,
            )
    df.attrs["source"] = str(path)
    df.attrs["run"] = meta
    return df


def read_run_json(path: Path) -> dict:
    """``run.json`` as a dict (empty when the file is absent); non-finite numbers stay strings."""
    if not path.is_file():
        return {}
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as e:
        raise DataFileError(path, f"invalid JSON: {e.msg} (column {e.colno})", line=e.lineno) from None
    except OSError as e:
        raise DataFileError(path, f"cannot read: {e.strerror or e}") from None


@dataclass(frozen=True, eq=False)
class StoredMotions:
    """The arrays of ``motions.npz``: one row per motion_id.

    Attributes
    ----------
    acc : numpy.ndarray
        (motions, samples) accelerations [m/s^2], zero-padded after each motion's ``n`` samples.
    n : numpy.ndarray
        Samples of each motion.
    dt : numpy.ndarray
        Step of each motion [s].
    theta0 : numpy.ndarray or None
        Initial rotation of each motion [rad] (None: not stored).
    names : numpy.ndarray or None
        Each motion's name (None: not stored).
    """

    acc: np.ndarray
    n: np.ndarray
    dt: np.ndarray
    theta0: np.ndarray | None = None
    names: np.ndarray | None = None


def read_motions(run_dir: Path) -> StoredMotions | None:
    """The arrays of ``motions.npz`` (acc [m/s^2], n, dt [s], theta0 [rad], names), None when absent."""
    f = run_dir / MOTIONS_FILE
    if not f.is_file():
        return None
    try:
        with np.load(f, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except Exception as e:
        raise DataFileError(f, f"cannot read: {e}") from None
    empty = np.zeros(0)
    return StoredMotions(
        acc=arrays.get("acc", np.zeros((0, 0))),
        n=arrays.get("n", empty),
        dt=arrays.get("dt", empty),
        theta0=arrays.get("theta0"),
        names=arrays.get("names"),
    )


def read_histories(run_dir: Path, motion_ids, dt: dict[int, float]) -> dict[tuple[str, int], tuple]:
    """(engine, motion_id) -> (t [s], theta [rad]) for the given motions (empty when not stored).

    ``dt`` maps a motion to its step [s]: the stored t is float32, so t is rebuilt from the step
    (long records stay uniform); a motion without a finite step keeps the stored t.
    """
    f = run_dir / HISTORIES_FILE
    ids = sorted({int(i) for i in motion_ids})
    if not ids or not f.is_file():
        return {}
    try:
        df = pd.read_parquet(f, filters=[("motion_id", "in", ids)])
    except Exception as e:
        raise DataFileError(f, f"cannot read: {e}") from None
    out = {}
    for (eng, mid), g in df.groupby(["engine", "motion_id"], sort=False, observed=True):
        theta = g["theta"].to_numpy(np.float64)
        step = dt.get(int(mid), math.nan)
        t = np.arange(theta.size) * step if math.isfinite(step) else g["t"].to_numpy(np.float64)
        out[(str(eng), int(mid))] = (t, theta)
    return out
