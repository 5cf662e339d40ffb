"""Readers of measured data: units in headers and CSV columns, converted once to SI here, and the input rules
every reader of a record applies.

Every file the suite reads (records, campaigns) goes through these functions, or through the readers of
ground-motion record files built on them (:mod:`housner.readers.motion_files`: PEER AT2, motion CSV); SI
inside
after them.

Accelerations are stored in m/s^2 (SI inside). A CSV column is converted once, from the unit written
in its header (``time [ms]``, ``ground_acc [g]``, ``theta [deg]``; SI when none is written). Between
samples the acceleration is taken as linear in time.

Units understood (:func:`parse_unit`), with the factor to SI:

* time: ``s`` (sec, seconds) 1, ``ms`` (msec) 1e-3, ``us`` (µs) 1e-6;
* acceleration: ``m/s^2`` 1, ``g`` 9.80665, ``cm/s^2`` (gal, CM/S/S,
  CM/SEC/SEC, cm/s2) 0.01, ``mm/s^2`` 1e-3, ``in/s^2`` 0.0254, ``ft/s^2`` 0.3048;
* angle: ``rad`` 1, ``mrad`` 1e-3, ``urad`` (µrad) 1e-6, ``deg`` (°, degrees) pi/180.

One input rule for every reader: an acceleration without a unit above :data:`PLAUSIBLE_ACC` (5 g)
and one in a declared unit above :data:`DECLARED_ACC_CEILING` (50 g, after conversion) are refused
with the file, line and column; a record needs :data:`MIN_RECORD_SAMPLES` samples
(:func:`require_samples`); a file whose first line is not a CSV header of names is refused
without quoting that line (a message never echoes a file that is not a record).
"""

from __future__ import annotations

import csv
import difflib
import io
import math
import re
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np

from housner.errors import DataFileError
from housner.units import G

__all__ = [
    "CHANNEL_PREFIX",
    "DECLARED_ACC_CEILING",
    "MIN_RECORD_SAMPLES",
    "PLAUSIBLE_ACC",
    "QUANTITIES",
    "SI_UNITS",
    "UNIT_CHOICES",
    "CsvColumns",
    "check_declared_acceleration",
    "excerpt",
    "parse_unit",
    "read_csv_columns",
    "read_csv_header",
    "read_csv_si",
    "require_samples",
    "uniform_step",
]

#: Relative tolerance on sample spacing for a CSV time column to count as uniform.
_UNIFORM_RTOL = 1e-6
#: Jitter of a rounded time column accepted as uniform: this share of the step, or half a unit of the
#: last written digit, whichever is larger [-].
_ROUNDING_SHARE = 0.01

#: A time column written without a unit is read in seconds only if its step lies in this range [s]:
#: 10 Hz to 100 kHz covers every strong-motion and shake-table record; a step outside it is far
#: more likely milliseconds (or microseconds) taken for seconds than a real record.
PLAUSIBLE_STEP = (1e-5, 0.1)

#: The fewest samples a measured or user-given record may have [-]: the calibration's noise estimate and
#: impact detection need 16 (:mod:`housner.free_vibration.calibration`); a shorter file is a stub or a truncated export.
#: One rule for every reader of records: campaigns and the records of a scenario.
MIN_RECORD_SAMPLES = 16

#: The quantity each column of the suite's CSV formats measures (docs/reference/campaign-format.md), SI unit
#: in brackets.
QUANTITIES = {"time": "time", "ground_acc": "acceleration", "theta": "angle"}

#: SI unit of each quantity.
SI_UNITS = {"time": "s", "acceleration": "m/s^2", "angle": "rad"}

#: Extra measured channels of a motion are accelerations named ``ground_acc_<what>`` [m/s^2].
CHANNEL_PREFIX = "ground_acc_"

_LENGTH = {"m": 1.0, "cm": 0.01, "mm": 1e-3, "in": 0.0254, "inch": 0.0254, "inches": 0.0254, "ft": 0.3048}
_ACC_EXPR = re.compile(r"^(m|cm|mm|in|inch|inches|ft)(?:/(?:s|sec)(?:\^2|2|/s|/sec)|\.?(?:s|sec)\^-2)$")
_NAMED_UNITS: dict[str, tuple[str, str, float]] = {}
for _q, _names, _label, _f in (
    ("time", ("s", "sec", "secs", "second", "seconds"), "s", 1.0),
    ("time", ("ms", "msec", "millisecond", "milliseconds"), "ms", 1e-3),
    ("time", ("us", "usec", "microsecond", "microseconds"), "us", 1e-6),
    ("acceleration", ("g", "g's"), "g", G),
    ("acceleration", ("gal", "gals"), "cm/s^2", 0.01),
    ("angle", ("rad", "rads", "radian", "radians"), "rad", 1.0),
    ("angle", ("mrad", "milliradian", "milliradians"), "mrad", 1e-3),
    ("angle", ("urad", "microradian", "microradians"), "urad", 1e-6),
    ("angle", ("deg", "degs", "degree", "degrees", "°"), "deg", math.pi / 180.0),
):
    for _n in _names:
        _NAMED_UNITS[_n] = (_q, _label, _f)
#: The units understood for each quantity, as listed in messages.
UNIT_CHOICES = {
    "time": "s, ms, us",
    "acceleration": "m/s^2, g, cm/s^2 (gal), mm/s^2, in/s^2, ft/s^2",
    "angle": "rad, mrad, urad, deg",
}


def parse_unit(text: str) -> tuple[str, str, float] | None:
    """Read a unit as written in a file header.

    Parameters
    ----------
    text : str
        The unit, e.g. ``"ms"``, ``"CM/SEC/SEC"``, ``"m/s²"``, ``"gal"``, ``"deg"``
        (case, spaces, ``**2``, ``^2``, ``2`` and ``²`` are all accepted).

    Returns
    -------
    (quantity, label, factor) or None
        ``quantity`` is ``"time"``, ``"acceleration"`` or ``"angle"``, ``label``
        the canonical unit, ``factor`` what multiplies a value in that unit to
        give SI (s, m/s^2, rad). None when the unit is not understood.
    """
    s = str(text).strip().lower().replace(" ", "")
    s = s.replace("\u00b5", "u").replace("\u03bc", "u").replace("\u00b2", "^2").replace("**2", "^2")
    if s in _NAMED_UNITS:
        return _NAMED_UNITS[s]
    m = _ACC_EXPR.match(s)
    if m:
        length = m.group(1)
        label = {"inch": "in", "inches": "in"}.get(length, length) + "/s^2"
        return "acceleration", label, _LENGTH[length]
    return None


def require_samples(path: str | Path, n: int, line: int | None = None) -> None:
    """Refuse a record file of fewer than :data:`MIN_RECORD_SAMPLES` samples (DataFileError naming the file)."""
    if n < MIN_RECORD_SAMPLES:
        raise DataFileError(path, f"only {n} samples; a record needs at least {MIN_RECORD_SAMPLES}", line=line)


class CsvColumns(NamedTuple):
    """Columns read by :func:`read_csv_si`, converted to SI."""

    #: One array per requested column, in SI (s, m/s^2, rad).
    values: list[np.ndarray]
    #: 1-based file line of each row.
    lines: np.ndarray
    #: Unit of each column as the header (or ``default_units``) gave it, canonical label; None when not given.
    units: list[str | None]


_HEADER_UNIT = re.compile(r"^(.*?)\s*[\[(]\s*([^\])]*?)\s*[\])]\s*$")


def _split_header_cell(cell: str) -> tuple[str, str | None]:
    cell = cell.replace("\ufeff", "").strip()
    m = _HEADER_UNIT.match(cell)
    if m and m.group(1):
        return m.group(1).strip(), m.group(2)
    return cell, None


def _read_text(path: Path) -> str:
    try:
        raw = path.read_bytes()
    except OSError as e:
        raise DataFileError(path, f"cannot read: {e.strerror or e}") from None
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = raw[: e.start].count(b"\n") + 1
        raise DataFileError(
            path, f"not UTF-8 text (byte 0x{raw[e.start]:02x}); save the file as UTF-8", line=line
        ) from None


def _header_cells(path: Path, reader) -> list[tuple[str, str | None]]:
    """The header line of a CSV as (name, unit written in brackets or None) per cell."""
    try:
        raw_header = next(reader)
    except StopIteration:
        raise DataFileError(path, "file is empty (expected a header line)", line=1) from None
    return [_split_header_cell(h) for h in raw_header]


def read_csv_header(path: str | Path) -> list[str]:
    """The column names of a CSV's header line, without their bracketed units.

    Raises :class:`DataFileError` (naming the file) when it cannot be read, is not UTF-8 or is empty.
    """
    path = Path(path)
    reader = csv.reader(io.StringIO(_read_text(path), newline=""))
    return [name for name, _unit in _header_cells(path, reader)]


def read_csv_si(
    path: str | Path,
    columns: Mapping[str, str | None],
    *,
    default_units: Mapping[str, str] | None = None,
) -> CsvColumns:
    """Read named numeric columns from a CSV with a header line, in SI.

    Parameters
    ----------
    path : path
        The file: UTF-8 (a byte-order mark is skipped), a header line, then one
        row per sample. A header cell may carry its unit in brackets,
        ``time [ms]`` or ``theta (deg)``; the values are converted once, here.
    columns : mapping
        Column name -> quantity (``"time"``, ``"acceleration"``, ``"angle"``,
        or None for a dimensionless column that may carry no unit).
    default_units : mapping, optional
        Column name -> unit used when the header gives none (SI otherwise);
        a unit in the header must agree with it.

    Returns
    -------
    CsvColumns
        The columns in SI, the file line of each row, and the unit each column
        was read in (None where SI was assumed).

    Raises
    ------
    DataFileError
        Naming the file, line and column of a missing column, an unknown or
        mismatched unit, an unparsable or non-finite value, or a short row.
    """
    path = Path(path)
    text = _read_text(path)
    reader = csv.reader(io.StringIO(text, newline=""))
    cells = _header_cells(path, reader)
    names = [n for n, _u in cells]
    idx: list[int] = []
    factors: list[float] = []
    units: list[str | None] = []
    for c, quantity in columns.items():
        if c not in names:
            raise _missing_column(path, c, columns, names, text.partition("\n")[0].rstrip("\r"))
        j = names.index(c)
        factor, label = _column_unit(path, c, quantity, cells[j][1], (default_units or {}).get(c))
        idx.append(j)
        factors.append(factor)
        units.append(label)
    out, lines = _read_rows(path, reader, list(zip(columns, idx, strict=True)), len(names))
    values = [np.asarray(v) * f if f != 1.0 else np.asarray(v) for v, f in zip(out, factors, strict=True)]
    for (c, quantity), v, u in zip(columns.items(), values, units, strict=True):
        if quantity == "acceleration" and u is None:  # read in m/s^2 because nothing said otherwise
            _check_plausible_acceleration(path, c, v, np.asarray(lines))
        elif quantity == "acceleration":  # a declared unit is checked too, after conversion
            check_declared_acceleration(path, c, v, np.asarray(lines), u)
    return CsvColumns(values, np.asarray(lines), units)


def _column_unit(
    path: Path, column: str, quantity: str | None, written: str | None, default: str | None
) -> tuple[float, str | None]:
    """The unit a CSV column is read in: (factor to SI, canonical label or None where SI is assumed).

    ``written`` is the unit in the column's header cell, ``default`` the caller's ``default_units`` entry;
    the header's unit wins and the default must agree with it. Refuses (naming the file, line 1 and the
    column) a unit on a dimensionless column, a unit that is unknown or of another quantity, and a default
    that contradicts the header.
    """
    factor, label = 1.0, None
    for source, u_text in (("header", written), ("default", default)):
        if u_text is None:
            continue
        u = parse_unit(u_text)
        if quantity is None:
            raise DataFileError(
                path, f"column `{column}` takes no unit, got [{excerpt(u_text, quote=False)}]", line=1, column=column
            )
        if u is None or u[0] != quantity:
            what = "unknown unit" if u is None else f"{u[0]} unit"
            raise DataFileError(
                path,
                f"{what} [{excerpt(u_text, quote=False)}] for {quantity} (use {UNIT_CHOICES[quantity]}; "
                f"SI {SI_UNITS[quantity]})",
                line=1,
                column=column,
            )
        if source == "default" and label is not None and label != u[1]:
            raise DataFileError(
                path,
                f"the header says [{excerpt(written, quote=False)}] but units={default!r} was given",
                line=1,
                column=column,
            )
        if label is None:
            factor, label = u[2], u[1]
    return factor, label


def _read_rows(path: Path, reader, wanted: list[tuple[str, int]], n_fields: int) -> tuple[list[list[float]], list[int]]:
    """The values of the wanted columns, as written (before any unit conversion), and the file line of each row.

    ``wanted`` holds (column name, field index) pairs; blank rows are skipped. Refuses (naming the file, line
    and column) a short row, a value that is not a number or not finite, and a file with no data rows.
    """
    out: list[list[float]] = [[] for _ in wanted]
    lines: list[int] = []
    for row in reader:
        lineno = reader.line_num
        if not row or all(not x.strip() for x in row):
            continue
        for k, (c, j) in enumerate(wanted):
            if j >= len(row):
                raise DataFileError(path, f"row has {len(row)} fields, expected {n_fields}", line=lineno, column=c)
            tok = row[j].strip()
            try:
                v = float(tok)
            except ValueError:
                raise DataFileError(path, f"not a number: {excerpt(tok)}", line=lineno, column=c) from None
            if not math.isfinite(v):
                raise DataFileError(path, f"value is not finite: {excerpt(tok)}", line=lineno, column=c)
            out[k].append(v)
        lines.append(lineno)
    if not lines:
        raise DataFileError(path, "no data rows after the header", line=2)
    return out, lines


#: A header cell longer than this is shown cut to it in messages [characters].
_SHOWN_NAME = 40
#: At most this many header names are listed in a "missing column" message.
_SHOWN_NAMES = 10
#: A first line longer than this is not taken for a header of names [characters] (100 columns of 20).
_HEADER_MAX = 2000


def excerpt(text: str, *, quote: bool = True) -> str:
    """A piece of a file for a message: cut to :data:`_SHOWN_NAME` characters, control characters escaped.

    Parameters
    ----------
    text : str
        The piece of the file (a value, a unit, a header cell).
    quote : bool
        Show it as a quoted Python string literal; otherwise bare, for text set in brackets or backticks.
    """
    cut = text if len(text) <= _SHOWN_NAME else text[:_SHOWN_NAME] + "..."
    return repr(cut) if quote else "".join(ch if ch.isprintable() else repr(ch)[1:-1] for ch in cut)


def _looks_like_header(first: str, names: list[str], wanted) -> bool:
    """True if a CSV's first line reads as a header of short column names, so that listing them echoes no
    content of a file that is not a record: printable, not too long, comma-separated, no ``:`` fields, and
    naming at least one column of the formats (``time``, ``ground_acc``, ``theta``, ``ground_acc_<what>``)
    or of the call."""
    first = first.replace("\ufeff", "")
    if len(first) > _HEADER_MAX or not first.isprintable() or ":" in first or "," not in first:
        return False
    known = {*QUANTITIES, *wanted}
    return any(n in known or n.startswith(CHANNEL_PREFIX) for n in names)


def _missing_column(path: Path, column: str, wanted, names: list[str], first: str) -> DataFileError:
    """The error of a column the header lacks: the names listed only when the first line looks like a header."""
    if not _looks_like_header(first, names, wanted):
        example = ",".join(wanted)
        return DataFileError(
            path,
            f"the first line is not a CSV header with a `{column}` column ({len(first)} characters; a record "
            f"starts with a header line such as `{example}`)",
            line=1,
        )
    close = difflib.get_close_matches(column, names, n=1)
    hint = f"; did you mean `{excerpt(close[0], quote=False)}`?" if close else ""
    listed = ", ".join(excerpt(n, quote=False) for n in names[:_SHOWN_NAMES])
    more = f", ... ({len(names)} columns)" if len(names) > _SHOWN_NAMES else ""
    return DataFileError(path, f"missing column `{column}`{hint} (header has: {listed}{more})", line=1)


#: The largest ground or table acceleration read without a declared unit [m/s^2]: 5 g. Recorded
#: earthquake peaks stay below about 4 g; a column above this bound is almost surely in other units.
PLAUSIBLE_ACC = 5.0 * G


#: The largest acceleration read in a declared unit [m/s^2]: 50 g. Table and ground motions do not exceed a
#: few g, and unfiltered sensor spikes stay near 6 g (the ASU granite tests' reach 5.9 g, read in m/s^2), so the
#: 5 g bound of an undeclared unit would refuse real records; a declared column above 50 g is a wrong unit
#: (``[g]`` written over values in m/s^2 or cm/s^2) or a damaged file, not a motion.
DECLARED_ACC_CEILING = 50.0 * G


def check_declared_acceleration(
    path: Path, column: str | None, values: np.ndarray, lines: np.ndarray, unit: str
) -> None:
    """Refuse an acceleration read in a declared unit whose peak, converted to m/s^2, exceeds 50 g."""
    if values.size == 0:
        return
    k = int(np.argmax(np.abs(values)))
    peak = float(abs(values[k]))
    if peak <= DECLARED_ACC_CEILING:
        return
    raise DataFileError(
        path,
        f"peak {peak:.4g} m/s^2 = {peak / G:.3g} g, read in the declared unit {unit}, is above "
        f"{DECLARED_ACC_CEILING / G:g} g, beyond any table or ground motion: the unit is wrong or the file "
        "is damaged",
        line=int(lines[k]),
        column=column,
    )


def _check_plausible_acceleration(path: Path, column: str, values: np.ndarray, lines: np.ndarray) -> None:
    """Refuse an acceleration column read in m/s^2 (no unit in its header) whose peak exceeds 5 g.

    Names the likely unit (cm/s^2 or mm/s^2: the peak divided by 100 or 1000 is a plausible
    acceleration) and how to declare it in the header.
    """
    if values.size == 0:
        return
    k = int(np.argmax(np.abs(values)))
    peak = float(abs(values[k]))
    if peak <= PLAUSIBLE_ACC:
        return
    likely = next((unit for unit, f in (("cm/s^2", 100.0), ("mm/s^2", 1000.0)) if peak / f <= PLAUSIBLE_ACC), None)
    guess = f"the values look like {likely}" if likely else "the values are not an acceleration in m/s^2"
    raise DataFileError(
        path,
        f"peak {peak:.4g} m/s^2 = {peak / G:.3g} g, read in m/s^2 because the header gives no unit, is above "
        f"the plausible {PLAUSIBLE_ACC / G:g} g: {guess}; declare the unit in the header, e.g. "
        f"`{column} [{likely or 'cm/s^2'}]` (or `{column} [g]`)",
        line=int(lines[k]),
        column=column,
    )


def read_csv_columns(
    path: str | Path, columns: Sequence[str], quantities: Mapping[str, str | None] | None = None
) -> tuple[list[np.ndarray], np.ndarray]:
    """Read named numeric columns from a CSV with a header line, in SI.

    Returns the columns and the 1-based file line of each row. A column's
    quantity comes from ``quantities`` or, for the format's names, from
    :data:`QUANTITIES`; a unit in its header is converted (see
    :func:`read_csv_si`, which also says which units were given).

    Raises :class:`DataFileError` naming the file, line and column of the first
    missing column, unknown unit, unparsable or non-finite value, or short row.
    """
    q = {c: (quantities or {}).get(c, QUANTITIES.get(c)) for c in columns}
    table = read_csv_si(path, q)
    return table.values, table.lines


def _written_unit(t: np.ndarray) -> float:
    """The unit of the last digit the time stamps were written with [s] (10^-k, the coarsest that fits them)."""
    for k in range(13):
        u = 10.0**-k
        if np.max(np.abs(t / u - np.round(t / u))) < 1e-6:
            return u
    return 0.0


def uniform_step(
    path: Path, t: np.ndarray, lines: np.ndarray, column: str = "time", *, assumed_seconds: bool = False
) -> float:
    """The step of a uniformly sampled time column [s]; errors name the first bad line.

    ``lines`` holds the 1-based file line of each sample. With
    ``assumed_seconds`` (the header gave no unit and seconds were assumed) a
    step outside :data:`PLAUSIBLE_STEP` is refused: it is much more likely a
    column in milliseconds than a record sampled that slowly (or fast).
    """
    if t.size < 2:
        raise DataFileError(path, "need at least two samples", line=int(lines[0]) if lines.size else 2, column=column)
    d = np.diff(t)
    dt = float(np.median(d))
    if not dt > 0:
        raise DataFileError(path, f"time does not increase (median step {dt})", line=2, column=column)
    bad = np.flatnonzero(np.abs(d - dt) > _UNIFORM_RTOL * dt + 1e-12 * abs(t[-1]))
    if bad.size:
        # time stamps written rounded (acquisition software writes a fixed number of digits): uniform if
        # every sample lies within the rounding of a uniform grid fitted to them
        k_all = np.arange(t.size, dtype=float)
        dt_fit, t0 = np.polyfit(k_all, t, 1)
        dev = t - (t0 + dt_fit * k_all)
        tol = max(_ROUNDING_SHARE * dt_fit, 0.5 * _written_unit(t)) * (1 + 1e-9)
        if dt_fit > 0 and np.all(np.abs(dev) <= tol):
            warnings.warn(
                f"{path}: `{column}` is rounded (largest deviation {np.max(np.abs(dev)):.3g} s from a uniform step "
                f"of {dt_fit:.9g} s): read as uniform",
                stacklevel=2,
            )
            dt = float(dt_fit)
            bad = np.empty(0, dtype=int)
    if bad.size:
        k = int(bad[0])
        raise DataFileError(
            path,
            f"non-uniform sampling: step {d[k]:.9g} s between t={t[k]:.9g} and t={t[k + 1]:.9g}, expected {dt:.9g} s "
            f"(beyond the rounding of a uniform grid: resample the record to a uniform step)",
            line=int(lines[k + 1]),
            column=column,
        )
    lo, hi = PLAUSIBLE_STEP
    if assumed_seconds and not (lo * (1 - 1e-9) <= dt <= hi * (1 + 1e-9)):
        what = f"time step {dt:.6g} read in seconds (no unit in the header) is implausible (outside {lo:g} .. {hi:g} s)"
        if dt > hi:
            fix = f"if the column is in milliseconds write `{column} [ms]` in the header; if in seconds, `{column} [s]`"
        else:
            fix = f"write its unit in the header (`{column} [s]` to confirm seconds)"
        raise DataFileError(path, f"{what}: {fix}", line=int(lines[1]), column=column)
    return dt
