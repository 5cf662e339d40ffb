"""Readers of ground-motion record files: PEER AT2 and the motion CSV, converted once to SI here.

A PEER AT2 file is read in the acceleration unit its header names (g, cm/s^2, m/s^2, in/s^2, ...); a
motion CSV in the units its header writes in brackets (``time [ms]``, ``ground_acc [g]``; SI when none is
written), through the CSV parser of :mod:`housner.readers.measured_data`. Accelerations come out in m/s^2, steps in s.
Both apply the input rules of :mod:`housner.readers.measured_data` (units understood, acceleration bounds), and their
errors name the file, line and column.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from housner.errors import DataFileError
from housner.readers.measured_data import (
    CHANNEL_PREFIX,
    UNIT_CHOICES,
    check_declared_acceleration,
    excerpt,
    parse_unit,
    read_csv_header,
    read_csv_si,
    uniform_step,
)
from housner.units import G

__all__ = ["read_at2", "read_csv_motion"]


_NPTS_DT = re.compile(r"NPTS\s*=\s*(\d+)\s*,?\s*DT\s*=\s*([0-9.EeDd+-]+)", re.IGNORECASE)


def read_at2(path: str | Path, *, units: str | None = None) -> tuple[np.ndarray, float, str]:
    """Read a PEER AT2 record: its acceleration [m/s^2] (converted from the units its header names), DT [s]
    and provenance.

    Accepts the 1999 PEER layout and the NGA-West2 layout (4 header lines,
    the fourth with ``NPTS= n, DT= dt``), CRLF line endings, and files
    with more free-text header lines before the NPTS line or a trailing
    ``***`` end marker.

    The acceleration unit is read from the header lines up to the NPTS
    line: a phrase ``UNITS OF <unit>`` / ``units are (<unit>)`` /
    ``UNITS: <unit>``, or an acceleration unit written out (``CM/SEC/SEC``,
    ``GAL``, ...); g, cm/s^2, m/s^2, mm/s^2, in/s^2 and ft/s^2 are understood
    (:func:`~housner.readers.measured_data.parse_unit`). A header that names no unit, names one that is not
    an acceleration (a velocity file in ``CM/SEC``), or names two different
    ones is refused with an error naming the file and the line.

    Parameters
    ----------
    path : path
        The file.
    units : str, optional
        Acceleration unit to use when the header names none (e.g. ``"g"``);
        if the header names one, it must agree.
    """
    path = Path(path)
    given = _acc_unit_arg(units)
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
        raise DataFileError(path, "no 'NPTS= n, DT= dt' header line in the first 50 lines; is this a PEER AT2 file?")
    npts = int(m.group(1))
    try:
        dt = float(m.group(2).replace("D", "E").replace("d", "e"))
    except ValueError:
        raise DataFileError(path, f"cannot read DT from {m.group(0)!r}", line=header_line + 1) from None
    unit_label, factor, unit_where = _at2_units(path, lines[: header_line + 1], given)
    values: list[float] = []
    starts: list[tuple[int, int]] = []  # (index of the line's first value, 1-based line): a sample's line
    for i in range(header_line + 1, len(lines)):
        line = lines[i].strip()
        if not line:
            continue
        if line.startswith("*"):
            break
        starts.append((len(values), i + 1))
        for tok in line.split():
            try:
                v = float(tok.replace("D", "E"))
            except ValueError:
                raise DataFileError(path, f"not a number: {excerpt(tok)}", line=i + 1) from None
            if not math.isfinite(v):
                raise DataFileError(path, f"acceleration is not finite: {excerpt(tok)}", line=i + 1)
            values.append(v)
    if not values:
        raise DataFileError(path, "no acceleration samples after the header", line=header_line + 1)
    if len(values) != npts:
        raise DataFileError(path, f"header says NPTS={npts} but {len(values)} samples follow", line=header_line + 1)
    if not (dt > 0 and math.isfinite(dt)):
        raise DataFileError(path, f"DT must be positive, got {dt}", line=header_line + 1)
    title = " / ".join(s.strip() for s in lines[1:header_line] if s.strip())[:200]
    conv = f"g -> m/s^2 with g = {G}" if unit_label == "g" else f"{unit_label} -> m/s^2 x {factor:g}"
    acc = np.asarray(values) * factor
    first, line_of = zip(*starts, strict=True)
    sample_lines = np.repeat(np.asarray(line_of), np.diff(np.append(first, len(values))))
    check_declared_acceleration(path, None, acc, sample_lines, unit_label)
    return acc, dt, f"{path.name} (PEER AT2, {conv}; units {unit_where}); {title}"


def read_csv_motion(
    path: str | Path,
    *,
    time_column: str = "time",
    acc_column: str = "ground_acc",
    units: str | None = None,
) -> tuple[np.ndarray, float, str, dict[str, np.ndarray]]:
    """Read a CSV with a header line, a time column and an acceleration column: acceleration [m/s^2], step [s],
    provenance and extra channels [m/s^2].

    The header may give each column's unit in brackets: ``time [ms]``,
    ``ground_acc [g]`` (see :func:`~housner.readers.measured_data.parse_unit` for the units understood);
    the values are converted once, here, to s and m/s^2. Without a unit the
    time column is read in seconds (a step outside 1e-5 .. 0.1 s is then
    refused as implausible) and the acceleration in ``units``.

    Parameters
    ----------
    path : path
        The file (UTF-8, with or without a byte-order mark).
    time_column, acc_column : str
        Column names (without the bracketed unit). Every other column named
        ``ground_acc_<what>`` (e.g. ``ground_acc_vertical [m/s^2]``) is read as
        an extra channel of the motion, for effects that read it.
    units : str, optional
        Unit of the acceleration column when the header gives none
        (default m/s^2); if the header gives one, it must agree.

    Sampling must be uniform to a relative 1e-6 of the step; errors name the
    file, line and column.
    """
    path = Path(path)
    default = _acc_unit_arg(units)
    # extra measured channels: every column named ground_acc_<what> [m/s^2 unless its header says]
    extra = [c for c in dict.fromkeys(read_csv_header(path)) if c.startswith(CHANNEL_PREFIX) and c != acc_column]
    quantities = {time_column: "time", acc_column: "acceleration", **{c: "acceleration" for c in extra}}
    table = read_csv_si(path, quantities, default_units={acc_column: units} if units else None)
    t, a = table.values[:2]
    dt = uniform_step(path, t, table.lines, time_column, assumed_seconds=table.units[0] is None)
    unit = table.units[1] or (default[1] if default else "m/s^2")
    provenance = f"{path.name} (CSV, {unit} -> m/s^2" + (f"; channels {', '.join(extra)})" if extra else ")")
    channels = dict(zip(extra, table.values[2:], strict=True))
    return a, dt, provenance, channels


def _acc_unit_arg(units: str | None) -> tuple[str, str, float] | None:
    """Check a ``units`` argument of the readers: None or an acceleration unit."""
    if units is None:
        return None
    u = parse_unit(units)
    if u is None or u[0] != "acceleration":
        raise ValueError(f"`units` must be an acceleration unit ({UNIT_CHOICES['acceleration']}), got {units!r}")
    return u


_UNITS_PHRASE = re.compile(r"\bUNITS?\b\s*(?:(?:OF|ARE|IS|IN|=|:)\s*)*\(?\s*([^\s,;()]+)", re.IGNORECASE)
_ACC_WRITTEN = re.compile(
    r"(?<![A-Za-z])(?:cm|mm|m|in|ft)\s*/\s*(?:s|sec)\s*(?:/\s*(?:s|sec)|\^\s*2|\*\*\s*2|2|\u00b2)(?![A-Za-z0-9])"
    r"|(?<![A-Za-z])gals?(?![A-Za-z])",
    re.IGNORECASE,
)


def _at2_units(path: Path, header: list[str], given: tuple[str, str, float] | None) -> tuple[str, float, str]:
    """Acceleration unit of an AT2 header: (label, factor to m/s^2, where it was found)."""
    found: dict[str, tuple[float, int]] = {}
    unread: list[tuple[str, int]] = []
    for i, line in enumerate(header):
        for m in _UNITS_PHRASE.finditer(line):
            tok = m.group(1).rstrip(".:")
            u = parse_unit(tok)
            if u is not None and u[0] == "acceleration":
                found.setdefault(u[1], (u[2], i + 1))
            else:
                unread.append((tok, i + 1))
        for m in _ACC_WRITTEN.finditer(line):
            u = parse_unit(m.group(0))
            if u is not None:
                found.setdefault(u[1], (u[2], i + 1))
    if len(found) > 1:
        (a, (_, la)), (b, (_, lb)) = list(found.items())[:2]
        raise DataFileError(
            path, f"the header names two acceleration units, {a} (line {la}) and {b} (line {lb})", line=lb
        )
    if found:
        label, (factor, line) = next(iter(found.items()))
        if given is not None and given[1] != label:
            raise DataFileError(path, f"the header says {label} but units={given[1]!r} was given", line=line)
        return label, factor, f"from header line {line}"
    if given is not None:
        return given[1], given[2], "given by the caller"
    if unread:
        tok, line = unread[0]
        raise DataFileError(
            path,
            f"cannot read the acceleration units {excerpt(tok)} in the header (understood: "
            f'{UNIT_CHOICES["acceleration"]}); declare the unit: `units = "g"` in the scenario\'s '
            '[motions] table, units="g" in Python',
            line=line,
        )
    raise DataFileError(
        path,
        f"the header (lines 1-{len(header)}) names no acceleration units (expected e.g. 'UNITS OF G' or "
        '\'CM/SEC/SEC\'); declare the unit: `units = "g"` (or "cm/s^2", ...) in the scenario\'s [motions] '
        'table, units="g" in Python',
        line=len(header),
    )
