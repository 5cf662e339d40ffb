"""The run directory: its files, the results columns, run.json's encoding, writing it and its provenance.

The one owner of the format (readers: :mod:`reports.html`, :mod:`reports.assertions`):

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

from housner.motion import GroundMotion

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


def jsonable(x: Any, *, nonfinite: str = "string") -> Any:
    """``x`` as plain JSON data, recursively: numpy scalars and arrays, paths, tuples made plain.

    Non-finite floats, which strict JSON cannot hold, become the strings "inf", "-inf" and "nan"
    (``nonfinite="string"``, run.json: :func:`reports.html` reads them back as numbers) or null
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
    (out / "run.json").write_text(json.dumps(jsonable(meta), indent=2))
