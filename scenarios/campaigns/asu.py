"""The ASU granite shake-table tests (2021) as a campaign: ``housner campaign from-asu DATA OUT``.

The tests of the virtual-shake-robot project (Chen et al. 2024) shook two granite specimens, SP1 and SP2,
with the same table motions and recorded whether each overturned. :func:`import_asu` writes one specimen's
tests as a campaign directory (``docs/reference/campaign-format.md``): ``campaign.toml`` (the scan mesh as
the specimen, one ``[[record]]`` per test in the order of testing, with its outcome, the measured table
PGV and, as its ``group``, the ground motion it played), a copy of the mesh, and ``records/Test###.csv``
with ``time`` [s] and ``ground_acc`` [m/s^2] at 200 Hz, read from the compact derived data set or from the
project's original files, which it processes as the data set's README says. The two forms of ``DATA``, how
the original files are processed, how the PGV is taken and how bad input is refused are in
``docs/how-to/real-shake-table-tests.md`` ("The data", "2. Import the tests as a campaign").

References
----------
Chen, Z., Arrowsmith, J. R., Das, J., et al. (2024). Virtual Shake Robot: simulating dynamics of
precariously balanced rocks for overturning and large-displacement processes. Seismica 3(1),
doi:10.26443/seismica.v3i1.692. Data: github.com/ZhiangChen/virtual_shake_robot_pybullet.
"""

from __future__ import annotations

import csv
import difflib
import json
import math
import os
import re
import shutil
import sys
import time
import zipfile
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.csv as pacsv
from scipy import signal

from housner.errors import DataFileError
from housner.scenarios.execution.outputs import check_output_dir
from housner.units import G

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["GRANITE_DENSITY", "NPZ_NAME", "ImportResult", "import_asu"]

#: The compact derived data set's file (see its README).
NPZ_NAME = "asu_granite_200hz.npz"
#: Folder of the ``Test###.txt`` files in the original repository.
RAW_SUBDIR = Path("data", "Shake_Table_Response")
#: Sample rate of the original files [Hz] and of the campaign's records [Hz].
RAW_RATE, RATE = 800, 200
#: Decimation filter: taps, cut-off [Hz] and Kaiser window's beta, as the README states them.
FILTER_TAPS, FILTER_CUTOFF, FILTER_BETA = 161, 85.0, 8.0
#: Displacement channel: inches per volt (the project's NOTES.docx), and metres per inch.
INCH_PER_VOLT, METRE_PER_INCH = 5.9797e-4, 0.0254
#: PGV from the displacement: Butterworth low-pass order [-] and cut-off [Hz] before differentiating.
PGV_ORDER, PGV_CUTOFF = 4, 20.0
#: Density of the granite specimens [kg/m^3] (the VSR paper's value for the scans' mass).
GRANITE_DENSITY = 2700.0
#: How a campaign written here starts its description; a folder whose campaign.toml says so may be replaced.
MARK = "imported by housner campaign from-asu"
#: Columns of the original files (0-based): the acceleration [g] and the displacement [V]; 8 in all.
_ACC_COL, _DISP_COL, _N_COLS = 1, 5, 8
_NPZ_KEYS = ("acc_mps2", "disp_m", "test", "offset", "n_samples", "dt")


@dataclass(frozen=True)
class ImportResult:
    """What :func:`import_asu` wrote.

    Attributes
    ----------
    out : pathlib.Path
        The campaign directory.
    n_records : int
        Records written.
    n_overturned : int
        Of which the specimen overturned.
    left_out : tuple of (str, str)
        (test id, reason) of each listed test with a file that was not imported, in test order.
    n_absent : int
        Tests that ``index.csv`` lists without a file (``present == 0``).
    elapsed : float
        Wall time of the import [s].
    """

    out: Path
    n_records: int
    n_overturned: int
    left_out: tuple[tuple[str, str], ...]
    n_absent: int
    elapsed: float

    @property
    def summary(self) -> str:
        """One line: what was imported, what was left out and why, the time taken."""
        text = f"imported {self.n_records} records ({self.n_overturned} overturned) into {self.out}"
        text += f" in {self.elapsed:.1f} s"
        if self.left_out:
            ids = ", ".join(t for t, _ in self.left_out[:5]) + (", ..." if len(self.left_out) > 5 else "")
            text += f"; left out: {len(self.left_out)} ({ids}; reasons above)"
        if self.n_absent:
            text += f"; {self.n_absent} test{'s' if self.n_absent != 1 else ''} listed without a file"
        return text


@dataclass(frozen=True)
class _Test:
    """One row of ``index.csv``."""

    number: int
    line: int  # in index.csv
    present: bool
    outcome: str  # the outcome column's text
    source: str  # file name of its Test###.txt ("" when the column is absent)
    record: str = ""  # the ground motion it played, the `record` column ("" when absent): the record's group

    @property
    def id(self) -> str:
        return f"Test{self.number:03d}"


def import_asu(
    data: str | Path,
    out: str | Path,
    *,
    specimen: str = "SP1",
    flags: str | None = None,
    mesh: str | Path | None = None,
    azimuth: float = 0.0,
    contact: str = "hull",
    progress: Callable[[str], None] | None = None,
) -> ImportResult:
    """Write the ASU granite shake-table tests of one specimen as a campaign directory.

    Parameters
    ----------
    data : str or pathlib.Path
        The data folder: ``index.csv`` with ``asu_granite_200hz.npz``, or with the original
        ``Test###.txt`` files (``docs/how-to/real-shake-table-tests.md``, "The data").
    out : str or pathlib.Path
        The campaign directory to write: new, empty, or a previous import (replaced).
    specimen : str
        The specimen, ``SP1`` or ``SP2``; names the campaign, the default outcome column and mesh.
    flags : str, optional
        The column of ``index.csv`` holding the outcomes (1 overturned, 0 not); default
        ``overturn_<specimen>``. Rows without 0 or 1 there are left out.
    mesh : str or pathlib.Path, optional
        The specimen's scan mesh [m]; default ``DATA/<specimen>.obj`` (or the original repository's
        ``DATA/data/<specimen>_PBRmodel/<specimen>.obj``). Copied into OUT.
    azimuth : float
        Shaking direction [deg] from the mesh's x axis, in [0, 360).
    contact : str
        ``hull`` or ``flat:TOL``, as :func:`housner.scan.specimen_from_mesh` takes it.
    progress : callable, optional
        Called with one line per test left out, as it is found.

    Returns
    -------
    ImportResult

    Raises
    ------
    housner.errors.DataFileError
        DATA, ``index.csv``, the npz or OUT are unusable (one line naming the file, line and column);
        also when no test at all can be imported.
    ValueError
        From :func:`housner.scan.specimen_from_mesh`: the mesh or the azimuth is refused.
    """
    start = time.perf_counter()
    data, out = Path(data), Path(out)
    flags = f"overturn_{specimen}" if flags is None else flags
    npz, folders = _locate(data)
    tests = _read_index(data / "index.csv", flags, need_source=npz is None)
    mesh_path, contact = _check_mesh(data, specimen, mesh, azimuth, contact)
    replace = _check_out(out)

    omitted = _Omissions(progress or (lambda line: None))
    source = _NpzSource(npz) if npz is not None else _TxtSource(data, folders)
    chosen = _choose_tests(tests, source, flags, omitted)
    with _staging(out) as tmp:
        written = _write_records(tmp / "records", chosen, source, omitted, data / "index.csv")
        shutil.copyfile(mesh_path, tmp / mesh_path.name)
        spec = {"mesh": mesh_path.name, "azimuth": azimuth, "contact": contact}
        (tmp / "campaign.toml").write_text(_campaign_toml(data, specimen, flags, spec, written), encoding="utf-8")
        _move_into_place(tmp, out, replace)
    return ImportResult(
        out=out,
        n_records=len(written),
        n_overturned=sum(over for _, over, _ in written),
        left_out=omitted.in_test_order(),
        n_absent=sum(not t.present for t in tests),
        elapsed=time.perf_counter() - start,
    )


class _Omissions:
    """The tests left out of an import, each with its reason; each is said (one line) as it is found."""

    def __init__(self, say: Callable[[str], None]):
        self.items: list[tuple[str, str]] = []
        self.say = say

    def add(self, test: _Test, reason: str) -> None:
        """Leave ``test`` out for ``reason``."""
        self.items.append((test.id, reason))
        self.say(f"{test.id}: {reason}: left out")

    def in_test_order(self) -> tuple[tuple[str, str], ...]:
        """(test id, reason) of each test left out, by test number."""
        return tuple(sorted(self.items, key=lambda item: int(item[0][4:])))


def _choose_tests(tests: list[_Test], source, flags: str, omitted: _Omissions) -> list[_Test]:
    """The listed tests with a file and an outcome of 0 or 1 in column ``flags``, by test number. The others
    with a file are left out, and so is every motion of the source that ``index.csv`` does not list."""
    for number, where in sorted(source.held().items()):  # motions without a row in index.csv: no outcome
        if number not in {t.number for t in tests}:
            omitted.add(_Test(number, 0, False, "", ""), f"in {where} but not listed in index.csv (no outcome)")

    chosen = []
    for t in sorted((t for t in tests if t.present), key=lambda t: t.number):
        if t.outcome.strip() in ("0", "1", "0.0", "1.0"):
            chosen.append(t)
        elif t.outcome.strip() == "":
            omitted.add(t, f"no outcome in column {flags} (index.csv line {t.line})")
        else:
            omitted.add(t, f"outcome {t.outcome!r} in column {flags} is not 0 or 1 (index.csv line {t.line})")
    return chosen


@contextmanager
def _staging(out: Path):
    """A fresh hidden folder beside ``out`` to write the campaign into; removed on leaving, whether the campaign
    was moved into place or an error stopped the import (which then leaves no half campaign)."""
    tmp = out.parent / f".{out.name}.from-asu-{os.getpid()}"
    shutil.rmtree(tmp, ignore_errors=True)
    try:
        yield tmp
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _write_records(folder: Path, chosen: list[_Test], source, omitted: _Omissions, index: Path) -> list:
    """Write each chosen test's table acceleration to ``folder/<id>.csv``; a test whose motion cannot be read is
    left out. Returns (test, overturned, measured PGV [m/s]) of each written; DataFileError naming ``index`` when
    none could be."""
    folder.mkdir(parents=True)
    written = []
    for t in chosen:
        try:
            acc, disp = source.motion(t)
        except _LeftOut as e:
            omitted.add(t, str(e))
            continue
        _write_record(folder / f"{t.id}.csv", acc)
        written.append((t, float(t.outcome) == 1.0, _table_pgv(disp, 1.0 / RATE)))
    if not written:
        raise DataFileError(index, f"no test could be imported ({len(omitted.items)} left out)")
    return written


# ---------------------------------------------------------------- checks before any work


def _locate(data: Path) -> tuple[Path | None, list[Path]]:
    """The npz, or (None, the folders holding Test###.txt files)."""
    if not data.is_dir():
        raise DataFileError(data, "no such folder (DATA: the ASU data set's folder)")
    if (data / NPZ_NAME).is_file():
        return data / NPZ_NAME, []
    folders = [d for d in (data, data / RAW_SUBDIR) if d.is_dir() and any(d.glob("Test*.txt"))]
    if not folders:
        raise DataFileError(data, f"holds neither {NPZ_NAME} nor Test###.txt files (here or in {RAW_SUBDIR})")
    return None, folders


def _read_index(path: Path, flags: str, *, need_source: bool) -> list[_Test]:
    """The rows of ``index.csv``; a missing column or a malformed test number or ``present`` refuses it."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            reader = csv.reader(f)
            header = [h.strip() for h in next(reader, [])]
            rows = [(reader.line_num, row) for row in reader if any(c.strip() for c in row)]
    except FileNotFoundError:
        raise DataFileError(path, "no such file (the list of tests and their outcomes)") from None
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise DataFileError(path, f"cannot be read ({e})") from None
    for name in ("test", "present", *(["source_path"] if need_source else [])):
        if name not in header:
            raise DataFileError(path, f"no column `{name}` (columns: {', '.join(header)})", line=1)
    if flags not in header:
        outcome_cols = [h for h in header if h.startswith("overturn_")]
        msg = f"no outcome column `{flags}`"
        close = difflib.get_close_matches(flags, outcome_cols, n=1)
        msg += f"; did you mean `{close[0]}`?" if close else ""
        msg += f" (outcome columns: {', '.join(outcome_cols) or 'none'}; choose one with --flags COLUMN)"
        raise DataFileError(path, msg, line=1)
    col = {name: header.index(name) for name in header}
    tests, seen = [], {}
    for line, row in rows:
        if len(row) != len(header):
            raise DataFileError(path, f"{len(row)} cells, the header has {len(header)}", line=line)
        cell = {name: row[i].strip() for name, i in col.items()}
        try:
            number = int(cell["test"])
        except ValueError:
            raise DataFileError(path, f"{cell['test']!r} is not a test number", line=line, column="test") from None
        if cell["present"] not in ("0", "1"):
            raise DataFileError(path, f"{cell['present']!r} is not 0 or 1", line=line, column="present")
        if number in seen:
            raise DataFileError(path, f"test {number} is listed twice (also line {seen[number]})", line=line)
        seen[number] = line
        source = Path(cell["source_path"].replace("\\", "/")).name if "source_path" in cell else ""
        tests.append(_Test(number, line, cell["present"] == "1", cell[flags], source, cell.get("record", "")))
    return tests


def _check_mesh(data: Path, specimen: str, mesh: str | Path | None, azimuth: float, contact: str) -> tuple[Path, str]:
    """The mesh file, checked by :func:`housner.scan.specimen_from_mesh` (its errors are one line), and the
    contact written plainly."""
    from housner.scan import specimen_from_mesh

    if mesh is not None:
        path = Path(mesh)
        if not path.is_file():
            raise DataFileError(path, "no such file (--mesh: the specimen's scan mesh)")
    else:
        candidates = [data / f"{specimen}.obj", data / "data" / f"{specimen}_PBRmodel" / f"{specimen}.obj"]
        path = next((p for p in candidates if p.is_file()), None)
        if path is None:
            raise DataFileError(candidates[0], f"no mesh of specimen {specimen}; give one with --mesh FILE")
    scan = specimen_from_mesh(path, azimuth=azimuth, contact=contact, density=GRANITE_DENSITY)
    return path, scan.contact


def _check_out(out: Path) -> bool:
    """Whether OUT is a previous import to replace; refuses a non-empty folder that is not one."""
    if out.exists() and not out.is_dir():
        raise DataFileError(out, "exists and is not a folder (OUT: the campaign directory to write)")
    check_output_dir(out.parent, "OUT's parent folder")
    if not out.exists() or not any(out.iterdir()):
        return False
    refuse = "is not empty and not a campaign written by `housner campaign from-asu`: give a new or empty folder"
    try:
        doc = tomllib.loads((out / "campaign.toml").read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        raise DataFileError(out, refuse) from None
    if not str(doc.get("description", "")).startswith(MARK):
        raise DataFileError(out, refuse)
    ours = {"campaign.toml", "records", str(doc.get("specimen", {}).get("mesh", ""))}
    files = {Path(str(r.get("file", ""))).name for r in doc.get("record", []) if isinstance(r, dict)}
    foreign = [p.name for p in out.iterdir() if p.name not in ours]
    if (out / "records").is_dir():
        foreign += [f"records/{p.name}" for p in (out / "records").iterdir() if p.name not in files]
    if foreign:
        raise DataFileError(
            out,
            f"a previous import, but it now also holds {foreign[0]!r}: not replaced "
            "(move that file away, or give another folder)",
        )
    return True


# ---------------------------------------------------------------- sources of the motions


class _LeftOut(Exception):
    """A test that cannot be imported; the message is the reason (file, line)."""


class _NpzSource:
    """Motions from the compact data set: already processed, float32, 200 Hz."""

    def __init__(self, path: Path):
        try:
            with np.load(path) as z:
                self._read(path, z)
        except (OSError, ValueError, zipfile.BadZipFile) as e:
            if isinstance(e, DataFileError):
                raise
            raise DataFileError(path, f"cannot be read ({e})") from None
        n_total = self.acc.size
        bad = [t for t, (o, n) in self.slices.items() if o < 0 or n < 2 or o + n > n_total]
        if bad:
            raise DataFileError(path, f"test {bad[0]}'s `offset`/`n_samples` lie outside the arrays")
        self.name = path.name

    def _read(self, path: Path, z) -> None:
        missing = [k for k in _NPZ_KEYS if k not in z.files]
        if missing:
            raise DataFileError(path, f"has no array `{missing[0]}` (arrays: {', '.join(z.files)})")
        dt = float(z["dt"])
        if not math.isclose(dt, 1.0 / RATE, rel_tol=1e-9):
            raise DataFileError(path, f"`dt` is {dt!r} s, not {1.0 / RATE} s (200 Hz)")
        self.acc, self.disp = z["acc_mps2"], z["disp_m"]
        columns = zip(z["test"], z["offset"], z["n_samples"], strict=True)
        self.slices = {int(t): (int(o), int(n)) for t, o, n in columns}

    def held(self) -> dict[int, str]:
        """Test number -> where its motion is."""
        return dict.fromkeys(self.slices, self.name)

    def motion(self, test: _Test) -> tuple[np.ndarray, np.ndarray]:
        if test.number not in self.slices:
            raise _LeftOut(f"not in {self.name} (index.csv line {test.line})")
        o, n = self.slices[test.number]
        return self.acc[o : o + n], self.disp[o : o + n]


class _TxtSource:
    """Motions from the original ``Test###.txt`` files, processed as the data set's README says."""

    def __init__(self, data: Path, folders: list[Path]):
        self.data, self.folders = data, folders
        self.h = signal.firwin(FILTER_TAPS, FILTER_CUTOFF, window=("kaiser", FILTER_BETA), fs=RAW_RATE)

    def held(self) -> dict[int, str]:
        """Test number -> where its motion is."""
        found = {}
        for d in reversed(self.folders):  # DATA's own files first, as motion() looks
            for p in d.glob("Test*.txt"):
                if re.fullmatch(r"Test\d+\.txt", p.name):
                    found[int(p.stem[4:])] = str(p)
        return found

    def motion(self, test: _Test) -> tuple[np.ndarray, np.ndarray]:
        name = test.source or f"{test.id}.txt"
        path = next((d / name for d in self.folders if (d / name).is_file()), None)
        if path is None:
            where = " or ".join(str(d) for d in (self.data, self.data / RAW_SUBDIR))
            raise _LeftOut(f"{name} not found in {where} (index.csv line {test.line})")
        acc_g, disp_v = _read_txt(path)
        acc = (acc_g - acc_g.mean()) * G  # the accelerometer's DC bias: the whole-record mean
        disp = disp_v * (INCH_PER_VOLT * METRE_PER_INCH)
        step = RAW_RATE // RATE
        return signal.resample_poly(acc, 1, step, window=self.h), signal.resample_poly(disp, 1, step, window=self.h)


def _read_txt(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Columns 2 (acceleration [g]) and 6 (displacement [V]) of an original file; _LeftOut if malformed."""
    try:
        table = pd.read_csv(
            path,
            sep="\t",
            header=None,
            skiprows=1,
            names=range(_N_COLS + 1),
            dtype=np.float64,
            skipinitialspace=True,
            skip_blank_lines=False,
            engine="c",
        )
        x = table.to_numpy()
    except (ValueError, pd.errors.ParserError, UnicodeDecodeError):
        x = None
    except OSError as e:
        raise _LeftOut(f"{path}: cannot be read ({e.strerror or e})") from None
    if x is None or np.isnan(x[:, :_N_COLS]).any() or not np.isnan(x[:, _N_COLS]).all() or len(x) < 2 * FILTER_TAPS:
        raise _LeftOut(_txt_problem(path))
    t = x[:, 0]
    rate = (len(t) - 1) / (t[-1] - t[0]) if t[-1] > t[0] else math.nan
    if not abs(rate - RAW_RATE) <= 1e-3 * RAW_RATE:  # the times are printed with 6 digits
        raise _LeftOut(f"{path}: sampled at {rate:.6g} Hz (column 1), not {RAW_RATE} Hz")
    return x[:, _ACC_COL], x[:, _DISP_COL]


def _txt_problem(path: Path) -> str:
    """The first malformed line of an original file, in words (only run on a file that failed to parse)."""
    with open(path, encoding="utf-8", errors="replace") as f:
        lines = f.read().splitlines()
    if not lines:
        return f"{path}: empty"
    if _numbers(lines[0].rstrip().split("\t")) is not None:
        return f"{path} line 1: numbers where the header row should be"
    for i, text in enumerate(lines[1:], start=2):
        cells = text.rstrip("\r\n").split("\t")
        if cells and cells[-1].strip() == "":  # the original files end each line with a tab
            cells = cells[:-1]
        if len(cells) != _N_COLS:
            return f"{path} line {i}: {len(cells)} columns, expected {_N_COLS} (tab-separated)"
        bad = next((j for j, c in enumerate(cells) if _numbers([c]) is None), None)
        if bad is not None:
            return f"{path} line {i}, column {bad + 1}: {cells[bad].strip()!r} is not a number"
    return f"{path}: only {len(lines) - 1} samples, too short to decimate (at least {2 * FILTER_TAPS})"


def _numbers(cells: list[str]) -> list[float] | None:
    """The cells as finite floats, or None."""
    try:
        values = [float(c) for c in cells]
    except ValueError:
        return None
    return values if all(math.isfinite(v) for v in values) else None


# ---------------------------------------------------------------- what is written


def _table_pgv(disp: np.ndarray, dt: float) -> float:
    """Peak table velocity [m/s] from the displacement [m] sampled at ``dt`` [s] (the README's ``pgv_meas_disp_mps``:
    docs/how-to/real-shake-table-tests.md, "The data")."""
    sos = signal.butter(PGV_ORDER, PGV_CUTOFF, fs=1.0 / dt, output="sos")
    return float(np.abs(np.gradient(signal.sosfiltfilt(sos, np.asarray(disp, dtype=np.float64)), dt)).max())


def _write_record(path: Path, acc: np.ndarray) -> None:
    """``time`` [s] and ``ground_acc`` [m/s^2] at 200 Hz, the units declared in the header.

    The declared unit lets the campaign reader take the table's real spikes above 5 g (test 183:
    5.9 g), which it refuses as a likely cm/s^2 column when the header gives no unit. The
    acceleration is stored as float32 (the data set's precision; far below the sensor's 6e-4 g step)
    and written as the shortest text that reads back to the same float32, so nothing is lost; the
    time i / 200 reads back exactly too. Arrow writes all 490 records in about a second.
    """
    acc32 = np.asarray(acc, dtype=np.float32) + np.float32(0.0)  # + 0 turns -0.0 into 0.0
    table = pa.table({"time": np.arange(acc32.size) / RATE, "ground_acc": acc32})
    with open(path, "wb") as f:
        f.write(b"time [s],ground_acc [m/s^2]\n")
        pacsv.write_csv(table, f, write_options=pacsv.WriteOptions(include_header=False))


def _toml_str(s: str) -> str:
    """A TOML basic string (JSON's escapes are TOML's; DEL is escaped too)."""
    return json.dumps(s, ensure_ascii=False).replace("\x7f", "\\u007f")


def _campaign_toml(data: Path, specimen: str, flags: str, spec: dict, written: list) -> str:
    """The text of campaign.toml: the specimen from its mesh, then the records in the order of testing."""
    desc = (
        f"{MARK} from {data.resolve()}; source: virtual-shake-robot project, Seismica doi "
        f"10.26443/seismica.v3i1.692; outcomes from column {flags}"
    )
    lines = [
        f"name = {_toml_str(f'ASU granite shake-table tests (2021), specimen {specimen}')}",
        f"description = {_toml_str(desc)}",
        "",
        "[specimen]",
        f"mesh = {_toml_str(spec['mesh'])}          # scan mesh [m], relative to this file",
        f"azimuth = {float(spec['azimuth'])!r}             # [deg] shaking direction from the mesh x axis",
        f"contact = {_toml_str(spec['contact'])}          # hull | flat:TOL",
        f"density = {GRANITE_DENSITY!r}          # [kg/m^3]",
    ]
    for test, overturned, pgv in written:
        lines += [
            "",
            "[[record]]",
            f'id = "{test.id}"',
            'kind = "ground_motion"',
            f'file = "records/{test.id}.csv"',
            f"overturned = {'true' if overturned else 'false'}",
            f"pgv = {float(f'{pgv:.6g}')!r}           # [m/s] measured table PGV, from the displacement channel",
        ]
        if test.record:  # the ground motion it played: the tests of its other scalings share the group
            lines.append(f"group = {_toml_str(test.record)}")
    return "\n".join(lines) + "\n"


def _move_into_place(tmp: Path, out: Path, replace: bool) -> None:
    """Rename the finished campaign to OUT; a previous import there is removed only after that."""
    old = out.parent / f".{out.name}.replaced-{os.getpid()}"
    if replace:
        out.rename(old)
    elif out.exists():
        out.rmdir()  # empty (checked)
    try:
        tmp.rename(out)
    except OSError:
        if replace:
            old.rename(out)
        raise
    shutil.rmtree(old, ignore_errors=True)
