"""The run directory: its files, the results columns, run.json's encoding, writing and reading it, provenance.

The one owner of the format: :func:`write_run` writes it, :func:`load_results`,
:func:`read_motions` and :func:`read_histories` read it (for :mod:`housner.reports.run.page`
and :mod:`housner.reports.assertions.runs`):

- ``results.parquet``: one row per (engine, motion) with the columns of
  :data:`RESULT_COLUMNS`: ``engine`` (or the series "ENGINE + EFFECTS" of a
  scenario's [[effects]]), ``motion_id``, ``motion_name``,
  ``theta_max_over_alpha`` (inf when overturned, NaN when failed),
  ``overturned``, ``n_impacts``, ``wall_s``, ``status``, ``error``,
  ``cached``, ``effects`` ("" for none);
- ``histories.parquet``: ``engine``, ``motion_id``, ``t`` [s], ``theta`` [rad];
- ``motions.npz``: the ensemble's accelerations [m/s^2] and steps [s];
- ``run.json``: scenario, specimen, engine settings and versions, seed,
  metadata, failures, wall times, provenance; non-finite floats are written
  as the strings "inf", "-inf", "nan" (:func:`jsonable`).
"""

from __future__ import annotations

import json
import math
import os
import platform
import subprocess
import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

import housner
from housner.errors import DataFileError
from housner.motion import GroundMotion
from housner.scenarios.execution.tables import REQUIRED_COLUMNS

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
RESULTS_FILE, HISTORIES_FILE, MOTIONS_FILE, RUN_FILE, REPORT_FILE = RUN_FILES


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


def json_number(x: Any) -> float:
    """A number from run.json, where non-finite floats are written as strings ("inf", "nan")."""
    if isinstance(x, str) and x.strip().lower() in ("overturn", "overturned"):
        return math.inf
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def effect_data(effect: Any) -> dict:
    """An effect as plain data: its registry name and parameter values (for cache keys and run.json)."""
    return {"name": effect.name, **{k: getattr(effect, k) for k in type(effect).params}}


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
    meta: dict,
) -> None:
    """Write results.parquet, histories.parquet, motions.npz and run.json into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    results.to_parquet(out / RESULTS_FILE, index=False)
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
        pd.concat(parts, ignore_index=True).to_parquet(out / HISTORIES_FILE, index=False)
    lengths = np.array([m.n for m in motions])
    acc = np.zeros((len(motions), int(lengths.max()) if len(motions) else 0), dtype=np.float32)
    for i, m in enumerate(motions):
        acc[i, : m.n] = m.acc
    np.savez_compressed(
        out / MOTIONS_FILE,
        acc=acc,
        n=lengths,
        dt=np.array([m.dt for m in motions]),
        theta0=np.array([m.theta0 for m in motions]),
        names=np.array([m.name for m in motions]),
    )
    (out / RUN_FILE).write_text(json.dumps(jsonable(meta), indent=2))


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
    df.attrs["run"] = read_run_json(path.parent / RUN_FILE)
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


def read_motions(run_dir: Path) -> dict | None:
    """The arrays of ``motions.npz`` (acc [m/s^2], n, dt [s], theta0 [rad], names), None when absent."""
    f = run_dir / MOTIONS_FILE
    if not f.is_file():
        return None
    try:
        with np.load(f, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except Exception as e:
        raise DataFileError(f, f"cannot read: {e}") from None


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
