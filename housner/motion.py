"""Ground motions: uniformly sampled horizontal ground acceleration.

Accelerations are stored in m/s^2; records in g (PEER AT2) are converted once,
in the reader. Between samples the acceleration is taken as linear in time.
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from housner.errors import DataFileError
from housner.units import G

__all__ = ["GroundMotion"]

#: Relative tolerance on sample spacing for a CSV time column to count as uniform.
_UNIFORM_RTOL = 1e-6

_NPTS_DT = re.compile(r"NPTS\s*=\s*(\d+)\s*,?\s*DT\s*=\s*([0-9.EeDd+-]+)", re.IGNORECASE)


@dataclass(frozen=True, eq=False)
class GroundMotion:
    """Horizontal ground acceleration sampled at a uniform step.

    Parameters
    ----------
    acc : array_like
        Ground acceleration ug''(t_k) [m/s^2], positive along +x, t_k = k dt.
    dt : float
        Sample step [s].
    name : str
        Identifier used in results tables and messages.
    provenance : str
        Where the samples came from (file, generator and seed, scaling).
    theta0, theta_dot0 : float
        Initial state of the block at t = 0 [rad, rad/s]; non-zero for a
        free-vibration release. Engines start from it.

    Notes
    -----
    Samples are linear between grid points; ``t`` = k dt, k = 0 .. n-1.
    """

    acc: np.ndarray
    dt: float
    name: str = "motion"
    provenance: str = ""
    theta0: float = 0.0
    theta_dot0: float = 0.0
    _hash: str | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        try:
            acc = np.array(self.acc, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"`acc` of motion {self.name!r} must be numeric") from None
        if acc.ndim != 1:
            raise ValueError(f"`acc` of motion {self.name!r} must be one-dimensional, got shape {acc.shape}")
        if acc.size == 0:
            raise ValueError(f"`acc` of motion {self.name!r} is empty")
        bad = np.flatnonzero(~np.isfinite(acc))
        if bad.size:
            raise ValueError(f"`acc` of motion {self.name!r} is not finite at sample {bad[0]} (value {acc[bad[0]]})")
        dt = float(self.dt)
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"`dt` of motion {self.name!r} must be positive and finite, got {self.dt!r}")
        for key in ("theta0", "theta_dot0"):
            v = float(getattr(self, key))
            if not math.isfinite(v):
                raise ValueError(f"`{key}` of motion {self.name!r} must be finite, got {v!r}")
            object.__setattr__(self, key, v)
        if abs(self.theta0) >= math.pi / 2:
            raise ValueError(f"`theta0` of motion {self.name!r} must lie within (-pi/2, pi/2), got {self.theta0}")
        acc.setflags(write=False)
        object.__setattr__(self, "acc", acc)
        object.__setattr__(self, "dt", dt)

    # ------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.acc.size)

    def __len__(self) -> int:
        return self.n

    @property
    def duration(self) -> float:
        """Time of the last sample, (n - 1) dt [s]."""
        return (self.n - 1) * self.dt

    @property
    def t(self) -> np.ndarray:
        """Sample times [s]."""
        return np.arange(self.n) * self.dt

    @property
    def pga(self) -> float:
        """Peak ground acceleration max |ug''| [m/s^2]."""
        return float(np.max(np.abs(self.acc)))

    def content_hash(self) -> str:
        """SHA-256 of samples, step and initial state (for result caching)."""
        if self._hash is None:
            import hashlib

            h = hashlib.sha256()
            h.update(np.ascontiguousarray(self.acc).tobytes())
            h.update(np.array([self.dt, self.theta0, self.theta_dot0]).tobytes())
            object.__setattr__(self, "_hash", h.hexdigest())
        return self._hash

    # ------------------------------------------------------------------
    def scaled(self, amplitude: float = 1.0, time: float = 1.0, name: str | None = None) -> GroundMotion:
        """Scale amplitude and time.

        Parameters
        ----------
        amplitude : float
            Factor on the accelerations [-].
        time : float
            Factor on the time axis [-]: the new step is ``time * dt``. The
            sqrt(S) compression from a prototype S times larger to the model
            (seed eq. 9, omega_model = omega_prototype sqrt(S)) is
            ``time = 1 / sqrt(S)``; see :meth:`to_model_scale`.
        """
        for key, v in (("amplitude", amplitude), ("time", time)):
            if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v)):
                raise ValueError(f"`{key}` must be a finite number, got {v!r}")
        if time <= 0:
            raise ValueError(f"`time` must be positive, got {time!r}")
        prov = self.provenance
        if amplitude != 1.0 or time != 1.0:
            prov = f"{prov}; scaled amplitude x{amplitude:g}, time x{time:g}".lstrip("; ")
        return GroundMotion(
            acc=self.acc * amplitude,
            dt=self.dt * time,
            name=name or self.name,
            provenance=prov,
            theta0=self.theta0,
            theta_dot0=self.theta_dot0 / time,
        )

    def to_model_scale(self, S: float) -> GroundMotion:
        """Compress time by sqrt(S) for a model S times smaller than the prototype (seed eq. 9)."""
        if not (math.isfinite(S) and S > 0):
            raise ValueError(f"`S` must be positive and finite, got {S!r}")
        return self.scaled(time=1.0 / math.sqrt(S))

    def with_duration(self, duration: float) -> GroundMotion:
        """Cut or pad with zeros to ``duration`` [s] (free rocking after the shaking)."""
        if not (math.isfinite(duration) and duration > 0):
            raise ValueError(f"`duration` must be positive and finite, got {duration!r}")
        n = int(round(duration / self.dt)) + 1
        acc = np.zeros(n)
        k = min(n, self.n)
        acc[:k] = self.acc[:k]
        return GroundMotion(acc, self.dt, self.name, self.provenance, self.theta0, self.theta_dot0)

    @classmethod
    def free_vibration(cls, theta0: float, duration: float, dt: float = 0.002, name: str | None = None) -> GroundMotion:
        """No ground motion; the block is released at rest from ``theta0`` [rad]."""
        if not (math.isfinite(duration) and duration > 0):
            raise ValueError(f"`duration` must be positive and finite, got {duration!r}")
        n = int(round(duration / dt)) + 1
        return cls(np.zeros(n), dt, name or f"free vibration theta0={theta0:.4g}", "free-vibration release", theta0)

    # ------------------------------------------------------------------
    @classmethod
    def from_at2(cls, path: str | Path, name: str | None = None) -> GroundMotion:
        """Read a PEER AT2 record (units of g) and convert to m/s^2.

        Accepts the 1999 PEER layout and the NGA-West2 layout (4 header lines,
        the fourth with ``NPTS= n, DT= dt``), CRLF line endings, and files
        with more free-text header lines before the NPTS line or a trailing
        ``***`` end marker.
        """
        path = Path(path)
        try:
            text = path.read_bytes().decode("utf-8", errors="replace")
        except OSError as e:
            raise DataFileError(path, f"cannot read: {e.strerror or e}") from None
        lines = text.splitlines()
        header_line = None
        for i, line in enumerate(lines[:50]):
            m = _NPTS_DT.search(line)
            if m:
                header_line = i
                break
        if header_line is None:
            raise DataFileError(
                path, "no 'NPTS= n, DT= dt' header line in the first 50 lines; is this a PEER AT2 file?"
            )
        npts = int(m.group(1))
        try:
            dt = float(m.group(2).replace("D", "E").replace("d", "e"))
        except ValueError:
            raise DataFileError(path, f"cannot read DT from {m.group(0)!r}", line=header_line + 1) from None
        values: list[float] = []
        for i in range(header_line + 1, len(lines)):
            line = lines[i].strip()
            if not line:
                continue
            if line.startswith("*"):
                break
            for tok in line.split():
                try:
                    v = float(tok.replace("D", "E"))
                except ValueError:
                    raise DataFileError(path, f"not a number: {tok!r}", line=i + 1) from None
                if not math.isfinite(v):
                    raise DataFileError(path, f"acceleration is not finite: {tok!r}", line=i + 1)
                values.append(v)
        if not values:
            raise DataFileError(path, "no acceleration samples after the header", line=header_line + 1)
        if len(values) != npts:
            raise DataFileError(path, f"header says NPTS={npts} but {len(values)} samples follow", line=header_line + 1)
        if not (dt > 0 and math.isfinite(dt)):
            raise DataFileError(path, f"DT must be positive, got {dt}", line=header_line + 1)
        title = " / ".join(s.strip() for s in lines[1:header_line] if s.strip())[:200]
        return cls(
            acc=np.asarray(values) * G,
            dt=dt,
            name=name or path.stem,
            provenance=f"{path.name} (PEER AT2, g -> m/s^2 with g = {G}); {title}",
        )

    @classmethod
    def from_csv(
        cls,
        path: str | Path,
        *,
        time_column: str = "time",
        acc_column: str = "ground_acc",
        units: str = "m/s^2",
        name: str | None = None,
    ) -> GroundMotion:
        """Read a CSV with a header line, a time column [s] and an acceleration column.

        ``units`` is ``"m/s^2"`` or ``"g"``. Sampling must be uniform to a
        relative 1e-6 of the step; errors name the file, line and column.
        """
        path = Path(path)
        if units not in ("m/s^2", "g"):
            raise ValueError(f"`units` must be 'm/s^2' or 'g', got {units!r}")
        (t, a), lines = read_csv_columns(path, [time_column, acc_column])
        dt = uniform_step(path, t, lines, time_column)
        scale = G if units == "g" else 1.0
        return cls(acc=a * scale, dt=dt, name=name or path.stem, provenance=f"{path.name} (CSV, {units})")


def read_csv_columns(path: Path, columns: list[str]) -> tuple[list[np.ndarray], np.ndarray]:
    """Read named numeric columns from a CSV with a header line.

    Returns the columns and the 1-based file line of each row.

    Raises :class:`DataFileError` naming the file, line and column of the first
    missing column, unparsable or non-finite value, or short row.
    """
    try:
        fh = open(path, newline="", encoding="utf-8")
    except OSError as e:
        raise DataFileError(path, f"cannot read: {e.strerror or e}") from None
    with fh:
        reader = csv.reader(fh)
        try:
            header = next(reader)
        except StopIteration:
            raise DataFileError(path, "file is empty (expected a header line)", line=1) from None
        header = [h.strip() for h in header]
        idx = []
        for c in columns:
            if c not in header:
                raise DataFileError(path, f"missing column `{c}` (header has: {', '.join(header)})", line=1)
            idx.append(header.index(c))
        out: list[list[float]] = [[] for _ in columns]
        lines: list[int] = []
        for row in reader:
            lineno = reader.line_num
            if not row or all(not x.strip() for x in row):
                continue
            for k, (c, j) in enumerate(zip(columns, idx, strict=True)):
                if j >= len(row):
                    raise DataFileError(
                        path, f"row has {len(row)} fields, expected {len(header)}", line=lineno, column=c
                    )
                tok = row[j].strip()
                try:
                    v = float(tok)
                except ValueError:
                    raise DataFileError(path, f"not a number: {tok!r}", line=lineno, column=c) from None
                if not math.isfinite(v):
                    raise DataFileError(path, f"value is not finite: {tok!r}", line=lineno, column=c)
                out[k].append(v)
            lines.append(lineno)
    if not out[0]:
        raise DataFileError(path, "no data rows after the header", line=2)
    return [np.asarray(v) for v in out], np.asarray(lines)


def uniform_step(path: Path, t: np.ndarray, lines: np.ndarray, column: str = "time") -> float:
    """The step of a uniformly sampled time column [s]; errors name the first bad line.

    ``lines`` holds the 1-based file line of each sample.
    """
    if t.size < 2:
        raise DataFileError(path, "need at least two samples", line=int(lines[0]) if lines.size else 2, column=column)
    d = np.diff(t)
    dt = float(np.median(d))
    if not dt > 0:
        raise DataFileError(path, f"time does not increase (median step {dt})", line=2, column=column)
    bad = np.flatnonzero(np.abs(d - dt) > _UNIFORM_RTOL * dt + 1e-12 * abs(t[-1]))
    if bad.size:
        k = int(bad[0])
        raise DataFileError(
            path,
            f"non-uniform sampling: step {d[k]:.9g} s between t={t[k]:.9g} and t={t[k + 1]:.9g}, expected {dt:.9g} s",
            line=int(lines[k + 1]),
            column=column,
        )
    return dt
