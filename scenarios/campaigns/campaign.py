"""Measurement campaigns: a specimen and its measured records, read from a campaign directory.

A campaign is a directory with ``campaign.toml`` (name, ``[specimen]``, one
``[[record]]`` per test) and one CSV per record with the columns ``time``
[s], ``ground_acc`` [m/s^2] and ``theta`` [rad], and optional extra measured
channels ``ground_acc_<what>`` [m/s^2] (``ground_acc_vertical``: the vertical
table acceleration), which the record's motion carries in ``channels`` (see
docs/reference/campaign-format.md). A
header cell may name another unit in brackets (``time [ms]``,
``ground_acc [g]``, ``theta [deg]``, see :func:`housner.motion.parse_unit`);
the reader converts once, to SI. A time column without a unit whose step is
outside 1e-5 .. 0.1 s is refused (milliseconds taken for seconds).
:func:`load_campaign` reads it into a :class:`Campaign` whose records carry
the measured rotation and the ground motion that drives a model of the same
test (:class:`housner.GroundMotion`, with the initial angle of a
free-vibration release).

Paths: a record's ``file`` and ``[specimen] mesh`` are relative to the campaign folder and must resolve
(symbolic links and ``..`` followed) inside it; a record outside is left out like an unreadable one, a
mesh outside refuses the campaign, unless ``allow_outside=True`` (``housner diagnose --allow-outside``).

Errors: a malformed ``campaign.toml`` (also a value of the wrong type) raises
:class:`housner.errors.DataFileError` naming the key (and the line); a malformed record file is reported with its
file, line and column in :attr:`Campaign.skipped` and left out, the other
records are kept, unless more than half of the records cannot be read (theta
written in degrees, say): then the campaign is refused with one line that
gives the count and the most common cause, rather than diagnosed on the rest.

References
----------
Bachmann, J. A., Strand, M., Vassiliou, M. F., Broccardo, M., Stojadinovic, B.
(2017). Probabilistic validation of the Housner rocking model. COMPDYN 2017,
section 3 (specimen, free-vibration and shake-table tests, 500 Hz, 0.8 mrad).
"""

from __future__ import annotations

import difflib
import math
import re
import sys
from collections import Counter
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path

import numpy as np

from housner.calibration import estimate_noise
from housner.errors import DataFileError, unknown_choice
from housner.impacts import noise_crossings
from housner.motion import GroundMotion
from housner.readers import (
    CHANNEL_PREFIX,
    QUANTITIES,
    read_csv_header,
    read_csv_si,
    require_samples,
    uniform_step,
)
from housner.scenarios.campaigns.sensor_noise import WHITE, SensorNoise
from housner.specimen import Specimen

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = [
    "KINDS", "OVERTURN_ANGLE", "Campaign", "MeasuredRecord", "OutcomeRecord", "estimate_release", "load_campaign",
]

#: Record kinds of the format.
KINDS = ("free_vibration", "ground_motion")
#: A measured block has overturned once |theta| reaches this angle [rad]: it lies on its side at
#: pi/2; the 10 % margin allows for the sensor and for the block bouncing on the table.
OVERTURN_ANGLE = 0.9 * math.pi / 2
#: |theta| beyond pi/2 by more than this [rad] is not a rotation of a block on a table.
_THETA_SLACK = 0.1
#: The release fit of a free-vibration record uses the samples until the block has fallen by
#: this fraction of its initial angle [-]: there theta0 - theta(t) ~ c t^2 + d t^4 holds to the noise.
_RELEASE_DROP = 0.3
#: A free-vibration record must start at least this many noise sigmas away from rest [-].
_RELEASE_MIN_SIGMAS = 10.0

_SPECIMEN_KEYS = {"height": "2H [m]", "width": "2B [m]", "depth": "[m]", "mass": "[kg]", "p": "[1/s] (optional)"}
#: A specimen from a scan mesh (:func:`housner.scan.specimen_from_mesh`), in place of the block's dimensions.
_MESH_KEYS = {
    "mesh": "file [m], relative to campaign.toml",
    "azimuth": "[deg] (optional, 0)",
    "contact": "hull | flat:TOL (optional, hull)",
    "density": "[kg/m^3] (optional, 2700)",
}
_RECORD_KEYS = {
    "id": "str",
    "kind": "str",
    "file": "str",
    "overturned": "bool (optional; required for a record without theta)",
    "theta_max": "[rad] (optional, outcome records)",
    "residual_displacement": "[m] (optional, outcome records)",
    "pgv": "[m/s] (optional, outcome records: the measured peak table velocity)",
}
#: The numeric keys of an outcome record: each, where given, a number >= 0 in SI.
_OUTCOME_KEYS = ("theta_max", "residual_displacement", "pgv")
_TOP_KEYS = {"name", "description", "specimen", "record"}


@dataclass(frozen=True, eq=False)
class MeasuredRecord:
    """One measured test.

    Attributes
    ----------
    id : str
        Record id from campaign.toml.
    kind : str
        ``"free_vibration"`` or ``"ground_motion"``.
    file : pathlib.Path
        The CSV file.
    motion : GroundMotion
        The measured ground acceleration [m/s^2] on the record's sample grid.
        A free-vibration record starts at the release: ``theta0`` is the
        measured initial angle [rad] and ``theta_dot0`` = 0.
    t : ndarray
        Sample times [s], starting at 0 (at the release for a free-vibration
        record whose file starts with a hold; see ``t_offset``).
    theta : ndarray
        Measured rotation [rad] at ``t``.
    noise : float
        Standard deviation of the measurement noise on theta [rad], estimated
        from the record (:func:`housner.calibration.estimate_noise`).
    overturned : bool
        The block overturned: |theta| reached :data:`OVERTURN_ANGLE`, or the
        campaign says so (``overturned = true`` in the record's table).
    t_offset : float
        Time in the file of the first sample kept [s] (the release of a
        free-vibration record held before it; else the file's first time).
    hold : ndarray
        The theta samples of the hold before a free vibration's release [rad] (the block still at
        ``theta0``: a quiet part for the sensor's noise); empty when the record starts at the release.
    noise_model : SensorNoise
        The correlation in time of the sensor's noise (:mod:`housner.scenarios.campaigns.sensor_noise`):
        white until the campaign's sensor is assessed (:func:`housner.scenarios.campaigns.sensor.assess_sensor`).
    valid : ndarray of bool or None
        Samples the sensor recorded truly (None: all). A sensor fault's samples (saturation, a spike, a
        dropout) are False: no error is taken on them.
    clip : tuple of float
        The sensor's range (low, high) [rad]: a saturating sensor reads no further (default unbounded).
    position : int
        The record's place among the campaign's ``[[record]]`` tables, the recording order, counting the
        records that could not be read (-1: not from a campaign file).
    """

    id: str
    kind: str
    file: Path
    motion: GroundMotion
    t: np.ndarray
    theta: np.ndarray
    noise: float
    overturned: bool
    t_offset: float = 0.0
    hold: np.ndarray = field(default_factory=lambda: np.zeros(0))
    noise_model: SensorNoise = WHITE
    valid: np.ndarray | None = None
    clip: tuple[float, float] = (-math.inf, math.inf)
    position: int = -1

    @property
    def dt(self) -> float:
        """Sample step [s]."""
        return self.motion.dt

    @property
    def theta_max(self) -> float:
        """Largest measured |theta| [rad] (pi/2 when overturned)."""
        return math.pi / 2 if self.overturned else float(np.max(np.abs(self.theta)))

    @property
    def is_free_vibration(self) -> bool:
        return self.kind == "free_vibration"

    @cached_property
    def impacts(self) -> np.ndarray:
        """Indices of the measured impacts (read-only), derived once per record: zero crossings of theta with a
        hysteresis of 4 noise sigmas (:func:`housner.impacts.noise_crossings`; for each, the first sample beyond
        the band on the new side). The error window of every comparison and every scorer counts them."""
        imp = noise_crossings(self.theta, self.noise)
        imp.flags.writeable = False
        return imp


@dataclass(frozen=True, eq=False)
class OutcomeRecord:
    """One test of which only the table motion and the outcome were measured (no theta channel).

    Attributes
    ----------
    id : str
    kind : str
        ``"ground_motion"``.
    file : pathlib.Path
    motion : GroundMotion
        The measured table acceleration [m/s^2].
    overturned : bool
        The observed outcome.
    theta_max : float or None
        Measured largest |theta| [rad], where it was measured.
    residual_displacement : float or None
        Measured residual displacement of the block [m], where measured.
    pgv_measured : float or None
        The measured peak table velocity [m/s] (from a displacement channel), where given.
    """

    id: str
    kind: str
    file: Path
    motion: GroundMotion
    overturned: bool
    theta_max: float | None = None
    residual_displacement: float | None = None
    pgv_measured: float | None = None

    @property
    def dt(self) -> float:
        """Sample step [s]."""
        return self.motion.dt

    @property
    def pga(self) -> float:
        """Peak table acceleration [m/s^2]."""
        return float(np.max(np.abs(self.motion.acc)))

    @cached_property
    def pgv(self) -> float:
        """Peak table velocity [m/s]: the measured one where given, else the acceleration integrated after a
        high-pass (:meth:`housner.GroundMotion.pgv`)."""
        return self.pgv_measured if self.pgv_measured is not None else self.motion.pgv()


@dataclass(eq=False)
class Campaign:
    """A measurement campaign: the specimen and its records.

    Attributes
    ----------
    name : str
    specimen : Specimen
        From ``[specimen]`` (2H, 2B, depth, mass, optional p).
    records : list of MeasuredRecord
        The records that were read, in the order of campaign.toml.
    skipped : list of (str, str, str)
        (record id, file, error message) of each record left out.
    path : pathlib.Path
        The campaign directory.
    outcomes : list of OutcomeRecord
        The records with only an observed outcome (no theta channel), in the order of campaign.toml.
    scan : housner.scan.ScanSpecimen or None
        The specimen's scan-mesh derivation (per-side alpha, p, its alpha bracket) when ``[specimen]`` names a
        ``mesh``; ``specimen`` is then its equivalent block.
    sensor : housner.scenarios.campaigns.sensor.SensorReport or None
        What the assessment of the theta sensor found (its noise, its faults and what was done about them);
        None until :func:`housner.scenarios.campaigns.sensor.assess_sensor` ran.
    """

    name: str
    specimen: Specimen
    records: list[MeasuredRecord]
    skipped: list[tuple[str, str, str]] = field(default_factory=list)
    path: Path = Path(".")
    outcomes: list[OutcomeRecord] = field(default_factory=list)
    scan: object = None
    sensor: object = None
    _cache: dict = field(default_factory=dict, init=False, repr=False)

    @property
    def free_vibration(self) -> list[MeasuredRecord]:
        """The free-vibration records."""
        return [r for r in self.records if r.kind == "free_vibration"]

    @property
    def ground_motion(self) -> list[MeasuredRecord]:
        """The ground-motion (shake-table) records."""
        return [r for r in self.records if r.kind == "ground_motion"]

    def record(self, rid: str) -> MeasuredRecord:
        """The record with id ``rid`` (ValueError listing the ids when unknown)."""
        for r in self.records:
            if r.id == rid:
                return r
        raise unknown_choice("record", rid, [r.id for r in self.records])

    def __len__(self) -> int:
        return len(self.records)

    def __repr__(self) -> str:
        outcomes = f" + {len(self.outcomes)} outcome records" if self.outcomes else ""
        return (
            f"Campaign({self.name!r}, {len(self.free_vibration)} free-vibration + {len(self.ground_motion)} "
            f"ground-motion records{outcomes}, {len(self.skipped)} skipped)"
        )


# ----------------------------------------------------------------------------
# campaign.toml
def _table_line(text: str, table: str, index: int = 0) -> int | None:
    """1-based line of the ``[table]`` header (or of the ``index``-th ``[[table]]``); None if absent."""
    hdr = re.compile(
        rf"^\s*\[\[\s*{re.escape(table)}\s*\]\]" if table == "record" else rf"^\s*\[\s*{re.escape(table)}\s*\]"
    )
    hits = [i for i, ln in enumerate(text.splitlines()) if hdr.match(ln)]
    return hits[index] + 1 if len(hits) > index else None


def _plain_table_line(text: str, table: str) -> int | None:
    """1-based line of a ``[table]`` header (also for a name the format wants as ``[[table]]``); None if absent."""
    hdr = re.compile(rf"^\s*\[\s*{re.escape(table)}\s*\]")
    return next((i + 1 for i, ln in enumerate(text.splitlines()) if hdr.match(ln)), None)


def _key_line(text: str, key: str, table: str | None = None, index: int = 0) -> int | None:
    """1-based line of ``key = ...`` in ``[table]`` (the ``index``-th ``[[table]]``) or at the top level.

    Falls back to the table's header line when the key is not written there; None when nothing is found.
    """
    lines = text.splitlines()
    start = 0
    if table is not None:
        head = _table_line(text, table, index)
        if head is None:
            return None
        start = head
    pat = re.compile(rf"^\s*{re.escape(key)}\s*=")
    for i in range(start, len(lines)):
        if re.match(r"^\s*\[", lines[i]):
            break
        if pat.match(lines[i]):
            return i + 1
    return start if table is not None else None


def _unknown_key(path: Path, text: str, where: str, key: str, allowed, table=None, index=0) -> DataFileError:
    close = difflib.get_close_matches(key, list(allowed), n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    return DataFileError(
        path,
        f"unknown key {where}{key!r}{hint} (allowed: {', '.join(sorted(allowed))})",
        line=_key_line(text, key, table, index),
    )


def _read_toml(path: Path) -> tuple[dict, str]:
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise DataFileError(path, "no campaign.toml here (a campaign is a directory with campaign.toml)") from None
    except OSError as e:
        raise DataFileError(path, f"cannot read: {e.strerror or e}") from None
    try:
        text = raw.decode("utf-8-sig")  # TOML is UTF-8; an editor's byte-order mark is skipped
    except UnicodeDecodeError as e:
        line = raw[: e.start].count(b"\n") + 1
        raise DataFileError(path, f"not UTF-8 text (byte 0x{raw[e.start]:02x})", line=line) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        m = re.search(r"line (\d+)", str(e))
        raise DataFileError(path, f"not valid TOML: {e}", line=int(m.group(1)) if m else None) from None
    return data, text


def _specimen(path: Path, text: str, data: dict, allow_outside: bool = False) -> tuple[Specimen, object]:
    """The campaign's specimen, and its scan derivation (None unless ``[specimen]`` names a ``mesh``)."""
    spec = data.get("specimen")
    if spec is None:
        raise DataFileError(path, "missing table [specimen] (height, width, depth, mass, optional p)")
    if not isinstance(spec, dict):
        raise DataFileError(
            path,
            f"`specimen` must be a table ([specimen] with height, width, depth, mass, optional p), "
            f"got {type(spec).__name__} {spec!r}",
            line=_key_line(text, "specimen") or _table_line(text, "specimen"),
        )
    if "mesh" in spec:
        return _mesh_specimen(path, text, spec, str(data.get("name", path.parent.name)), allow_outside)
    for key in spec:
        if key not in _SPECIMEN_KEYS:
            raise _unknown_key(path, text, "[specimen] ", key, {**_SPECIMEN_KEYS, "mesh": ""}, "specimen")
    kwargs = {}
    for key, unit in _SPECIMEN_KEYS.items():
        if key not in spec:
            if key == "p":
                continue
            raise DataFileError(path, f"missing key [specimen] {key!r} {unit}", line=_table_line(text, "specimen"))
        v = spec[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
            raise DataFileError(
                path,
                f"[specimen] {key!r} must be a positive number {unit}, got {v!r}",
                line=_key_line(text, key, "specimen"),
            )
        kwargs[key] = float(v)
    try:
        return Specimen(name=str(data.get("name", path.parent.name)), **kwargs), None
    except ValueError as e:
        raise DataFileError(path, f"[specimen]: {e}", line=_table_line(text, "specimen")) from None


def _mesh_specimen(path: Path, text: str, spec: dict, name: str, allow_outside: bool) -> tuple[Specimen, object]:
    """``[specimen] mesh = ...``: the equivalent planar block of a scan mesh (:mod:`housner.scan`)."""
    from housner.scan import specimen_from_mesh

    for key in spec:
        if key not in _MESH_KEYS:
            raise _unknown_key(path, text, "[specimen] (with a mesh) ", key, _MESH_KEYS, "specimen")
    kinds = {"mesh": str, "azimuth": (int, float), "contact": str, "density": (int, float)}
    for key, kind in kinds.items():
        if key in spec and (isinstance(spec[key], bool) or not isinstance(spec[key], kind)):
            raise DataFileError(path, f"[specimen] {key!r} must be {_MESH_KEYS[key]}, got {spec[key]!r}",
                                line=_key_line(text, key, "specimen"))  # fmt: skip
    mesh = Path(spec["mesh"])
    mesh = mesh if mesh.is_absolute() else path.parent / mesh
    outside = None if allow_outside else _outside(mesh, path.parent, "the files it names")
    if outside is not None:
        raise DataFileError(path, f"[specimen] 'mesh' {spec['mesh']!r} {outside}",
                            line=_key_line(text, "mesh", "specimen"))  # fmt: skip
    try:
        scan = specimen_from_mesh(
            mesh,
            azimuth=float(spec.get("azimuth", 0.0)),
            contact=spec.get("contact", "hull"),
            density=float(spec.get("density", 2700.0)),
            name=name,
        )
    except DataFileError:
        raise
    except ValueError as e:
        raise DataFileError(path, f"[specimen]: {e}", line=_table_line(text, "specimen")) from None
    return scan.specimen(), scan


def _record_entries(path: Path, text: str, data: dict) -> list[dict]:
    recs = data.get("record")
    if recs is None:
        raise DataFileError(path, "no [[record]] tables: a campaign needs at least one record")
    if not isinstance(recs, list) or not all(isinstance(r, dict) for r in recs):
        got = recs if not isinstance(recs, list) else next(r for r in recs if not isinstance(r, dict))
        raise DataFileError(
            path,
            f"`record` must be an array of tables ([[record]] with id, kind, file), got {type(got).__name__} {got!r}",
            line=_key_line(text, "record") or _table_line(text, "record") or _plain_table_line(text, "record"),
        )
    if not recs:
        raise DataFileError(
            path, "`record` is empty: a campaign needs at least one [[record]]", line=_key_line(text, "record")
        )
    seen: dict[str, int] = {}
    out = []
    for i, rec in enumerate(recs):
        where = f"[[record]] #{i + 1} "
        for key in rec:
            if key not in _RECORD_KEYS:
                raise _unknown_key(path, text, where, key, _RECORD_KEYS, "record", i)
        for key in ("id", "kind", "file"):
            if key not in rec:
                raise DataFileError(
                    path, f"missing key {where}{key!r} ({_RECORD_KEYS[key]})", line=_table_line(text, "record", i)
                )
            if not isinstance(rec[key], str) or not rec[key].strip():
                raise DataFileError(
                    path, f"{where}{key!r} must be a non-empty string, got {rec[key]!r}",
                    line=_key_line(text, key, "record", i),
                )  # fmt: skip
        rid = rec["id"]
        if rid in seen:
            raise DataFileError(
                path,
                f"{where}'id' {rid!r} is already used by [[record]] #{seen[rid] + 1}",
                line=_key_line(text, "id", "record", i),
            )
        seen[rid] = i
        if rec["kind"] not in KINDS:
            close = difflib.get_close_matches(rec["kind"], KINDS, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise DataFileError(
                path,
                f"{where}'kind' must be one of {', '.join(KINDS)}, got {rec['kind']!r}{hint}",
                line=_key_line(text, "kind", "record", i),
            )
        if "overturned" in rec and not isinstance(rec["overturned"], bool):
            raise DataFileError(
                path, f"{where}'overturned' must be true or false, got {rec['overturned']!r}",
                line=_key_line(text, "overturned", "record", i),
            )  # fmt: skip
        for key in _OUTCOME_KEYS:
            v = rec.get(key, 0.0)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise DataFileError(
                    path, f"{where}{key!r} must be a number >= 0 {_RECORD_KEYS[key].split(' (')[0]}, got {v!r}",
                    line=_key_line(text, key, "record", i),
                )  # fmt: skip
        out.append(rec)
    return out


# ----------------------------------------------------------------------------
# records
def estimate_release(t, theta, noise: float) -> tuple[int, float]:
    """Release sample and initial angle of a free-vibration record, robust to noise.

    The block is at rest at theta0 (possibly held for a while) and falls
    freely from the release on; near the release
    theta(t) = theta0 + c tau^2 + d tau^4 with tau = max(t - t_r, 0) (the
    cubic term vanishes because theta' = 0 at the release). The model is
    fitted by least squares over the samples until the block has fallen by
    30 % of its angle, profiling the release time t_r over the samples; a
    hold (t_r > 0) is accepted only when it lowers the squared residual by
    more than ln(n) noise^2 (the Bayesian information criterion's price of
    one more parameter).

    Parameters
    ----------
    t : array_like
        Uniform sample times [s].
    theta : array_like
        Measured rotation [rad].
    noise : float
        Noise standard deviation [rad].

    Returns
    -------
    k_release : int
        Index of the sample nearest the release (0 when the record starts at it).
    theta0 : float
        Fitted angle at that sample [rad]; its standard error is about
        2 noise / sqrt(samples in the fit) (0.1-0.2 mrad at 500 Hz and 0.8 mrad).

    Raises
    ------
    ValueError
        The record does not start away from rest (|theta0| below 10 noise
        sigmas) or never falls.
    """
    t = np.asarray(t, dtype=float)
    th = np.asarray(theta, dtype=float)
    k0 = min(th.size, 9)
    start = float(np.median(th[:k0]))
    sigma = max(float(noise), 1e-12)
    if abs(start) < _RELEASE_MIN_SIGMAS * sigma:
        raise ValueError(
            f"a free-vibration record must start from a released tilt: the first samples are at "
            f"{start:.3g} rad, within {_RELEASE_MIN_SIGMAS:g} noise sigmas ({sigma:.2g} rad) of rest"
        )
    s = math.copysign(1.0, start)
    fallen = np.flatnonzero(s * (start - th) > _RELEASE_DROP * abs(start))
    if fallen.size == 0:
        far = float(np.max(s * th))
        if far > abs(start) + _RELEASE_DROP * abs(start):
            raise ValueError(
                f"the free-vibration record never rocks back toward rest: theta moves away from its release "
                f"at {start:.4g} rad to {s * far:.4g} rad (the block toppled; a release beyond the overturning "
                f"angle cannot calibrate p or r)"
            )
        raise ValueError("the free-vibration record never falls from its initial tilt")
    kw = int(fallen[0])
    # candidate releases: every sample up to where the record has clearly left the plateau
    left = np.flatnonzero(s * (start - th[:kw]) > 4.0 * sigma)
    k_hi = int(left[0]) if left.size else kw
    cands = np.arange(0, max(k_hi, 1))
    if cands.size > 400:
        cands = cands[-400:]
    y = th[: kw + 1]
    tt = t[: kw + 1]
    fits = []
    for kr in cands:
        tau = np.maximum(tt - t[kr], 0.0) / max(tt[-1] - t[kr], 1e-12)
        A = np.column_stack((np.ones_like(tau), tau**2, tau**4))
        coef, *_ = np.linalg.lstsq(A, y, rcond=None)
        fits.append((float(np.sum((y - A @ coef) ** 2)), int(kr), float(coef[0])))
    best = min(fits)
    at_start = fits[0] if fits[0][1] == 0 else best
    # A hold is one more parameter: accept it only when it lowers the residual by more than the
    # Bayesian-information price of a parameter, ln(n) sigma^2 (noise alone would not).
    if at_start[0] - best[0] <= math.log(y.size) * sigma * sigma:
        best = at_start
    return best[1], best[2]


def _outside(path: Path, folder: Path, what: str = "records") -> str | None:
    """None if ``path`` resolves (links and ``..`` followed) inside ``folder``; else the end of the message."""
    inside = folder.resolve()
    try:
        if path.resolve().is_relative_to(inside):
            return None
    except (OSError, RuntimeError):  # a loop of symbolic links (RuntimeError before Python 3.13)
        return "cannot be resolved (a loop of symbolic links?)"
    return (f"resolves outside the campaign folder {inside} ({what} must lie inside it; pass --allow-outside "
            "to read it anyway, allow_outside=True in Python)")  # fmt: skip


def _read_record(root: Path, rec: dict, specimen: Specimen) -> MeasuredRecord | OutcomeRecord:
    path = (root / rec["file"]).resolve() if not Path(rec["file"]).is_absolute() else Path(rec["file"])
    header = read_csv_header(path)
    if "theta" not in header and "ground_acc" in header and rec["kind"] == "ground_motion":
        return _read_outcome_record(path, rec)
    # optional extra channels: every column named ground_acc_<what> (e.g. ground_acc_vertical [m/s^2])
    extra = [c for c in dict.fromkeys(header) if c.startswith(CHANNEL_PREFIX)]
    quantities = {**QUANTITIES, **{c: "acceleration" for c in extra}}
    table = read_csv_si(path, quantities)  # converted to SI from the units in the header (none: SI)
    (t, acc, theta), lines = table.values[:3], table.lines
    channels = dict(zip(extra, table.values[3:], strict=True))
    dt = uniform_step(path, t, lines, "time", assumed_seconds=table.units[0] is None)
    bad = np.flatnonzero(np.abs(theta) > math.pi / 2 + _THETA_SLACK)
    if bad.size:
        k = int(bad[0])
        raise DataFileError(
            path,
            f"|theta| = {abs(theta[k]):.4g} rad is beyond pi/2: not a rotation in rad of a block on a table "
            "(degrees or another unit? write it in the header, e.g. `theta [deg]`)",
            line=int(lines[k]),
            column="theta",
        )
    require_samples(path, theta.size, line=int(lines[-1]))
    noise = estimate_noise(theta)
    overturned = bool(rec.get("overturned", False)) or bool(np.max(np.abs(theta)) >= OVERTURN_ANGLE)
    k_rel = 0
    theta0 = 0.0
    if rec["kind"] == "free_vibration":
        try:
            k_rel, theta0 = estimate_release(t, theta, noise)
        except ValueError as e:
            raise DataFileError(path, str(e), line=int(lines[0]), column="theta") from None
        if abs(theta0) >= specimen.alpha:
            raise DataFileError(
                path,
                f"released at theta0 = {theta0:.4g} rad, beyond alpha = {specimen.alpha:.4g} rad: the block "
                "would overturn without rocking",
                line=int(lines[0]),
                column="theta",
            )
    t_off = float(t[k_rel])
    theta_file = theta
    acc = acc[k_rel:]
    theta = theta[k_rel:]
    try:
        motion = GroundMotion(
            acc=acc,
            dt=dt,
            name=rec["id"],
            provenance=f"{path.name} (campaign record, {rec['kind']})",
            theta0=theta0,
            theta_dot0=0.0,
            channels={c: a[k_rel:] for c, a in channels.items()},
        )
    except ValueError as e:  # a channel name the format does not allow
        raise DataFileError(path, str(e), line=1) from None
    return MeasuredRecord(
        id=rec["id"],
        kind=rec["kind"],
        file=path,
        motion=motion,
        t=np.arange(theta.size) * dt,
        theta=theta,
        noise=noise,
        overturned=overturned,
        t_offset=t_off,
        hold=np.array(theta_file[:k_rel]),
    )


def _read_outcome_record(path: Path, rec: dict) -> OutcomeRecord:
    """A ground-motion record without a theta column: the table motion and the observed outcome."""
    if "overturned" not in rec:
        raise DataFileError(
            path,
            f"record {rec['id']!r} has no theta column and no outcome: write `overturned = true` or `false` in its "
            "[[record]] table (a record needs a measured theta or an observed outcome)",
            line=1,
        )
    table = read_csv_si(path, {"time": "time", "ground_acc": "acceleration"})
    (t, acc), lines = table.values[:2], table.lines
    dt = uniform_step(path, t, lines, "time", assumed_seconds=table.units[0] is None)
    require_samples(path, acc.size, line=int(lines[-1]))
    motion = GroundMotion(acc=acc, dt=dt, name=rec["id"], provenance=f"{path.name} (campaign outcome record)")
    return OutcomeRecord(
        id=rec["id"],
        kind=rec["kind"],
        file=path,
        motion=motion,
        overturned=bool(rec["overturned"]),
        theta_max=rec.get("theta_max"),
        residual_displacement=rec.get("residual_displacement"),
        pgv_measured=None if rec.get("pgv") is None else float(rec["pgv"]),
    )


def load_campaign(path: str | Path, allow_outside: bool = False) -> Campaign:
    """Read a measurement campaign.

    Parameters
    ----------
    path : path
        The campaign directory (or its ``campaign.toml``).
    allow_outside : bool
        Read record files and a mesh that resolve outside the campaign folder (default False: such a
        record is left out and listed in ``skipped``, such a mesh refuses the campaign, each with one
        line naming the key, the path and the folder).

    Returns
    -------
    Campaign
        Records that could not be read are listed in ``skipped`` with the
        error (file, line and column), the others kept.

    Raises
    ------
    housner.errors.DataFileError
        (a ValueError) ``campaign.toml`` is missing or malformed (the message
        names the key and, where known, the line), or more than half of the
        records could not be read: then one line names the campaign, the
        count ("87 of 103 records could not be read") and the most common
        cause with one example file. A minority of unreadable records is
        left out and listed in ``skipped``.

    Notes
    -----
    A free-vibration record starts at the release: its initial angle is
    fitted to the first samples (:func:`estimate_release`) and becomes the
    motion's ``theta0`` (with ``theta_dot0`` = 0); samples of a hold before
    the release are dropped. A record file whose time column does not start
    at 0 is taken as starting at its first sample.
    """
    p = Path(path)
    toml = p if p.suffix == ".toml" else p / "campaign.toml"
    root = toml.parent
    data, text = _read_toml(toml)
    for key in data:
        if key not in _TOP_KEYS:
            raise _unknown_key(toml, text, "", key, _TOP_KEYS)
    name = data.get("name", root.name)
    for key in ("name", "description"):
        v = data.get(key, "")
        if not isinstance(v, str):
            raise DataFileError(toml, f"{key!r} must be a string, got {v!r}", line=_key_line(text, key))
    specimen, scan = _specimen(toml, text, data, allow_outside)
    entries = _record_entries(toml, text, data)
    records, outcomes, skipped, errors = [], [], [], []
    for i, rec in enumerate(entries):
        try:
            outside = None if allow_outside else _outside(root / rec["file"], root)
            if outside is not None:
                raise DataFileError(toml, f"record {rec['id']!r}: file {rec['file']!r} {outside}",
                                    line=_key_line(text, "file", "record", i))  # fmt: skip
            r = _read_record(root, rec, specimen)
            if isinstance(r, MeasuredRecord):
                r = replace(r, position=i)
        except DataFileError as e:
            skipped.append((rec["id"], rec["file"], str(e)))
            errors.append(e)
            continue
        (outcomes if isinstance(r, OutcomeRecord) else records).append(r)
    if 2 * len(skipped) > len(entries):
        raise DataFileError(toml, _unreadable_message(name, len(entries), skipped, errors))
    return Campaign(name=name, specimen=specimen, records=records, skipped=skipped, path=root, outcomes=outcomes,
                    scan=scan)  # fmt: skip


def _cause(e: DataFileError) -> tuple[str, str]:
    """The message of a record's error without its file and line, and that message with its numbers blanked
    (errors of the same cause share the latter)."""
    text = " ".join(str(e).split())  # one line
    where = str(e.path) + (f" line {e.line}" if e.line is not None else "") + (
        f", column `{e.column}`" if e.column is not None else "")  # fmt: skip
    msg = text[len(where) + 2 :] if text.startswith(where + ": ") else text
    return msg, re.sub(r"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?", "#", msg)


def _unreadable_message(name: str, n: int, skipped: list, errors: list[DataFileError]) -> str:
    """One line: the campaign, how many of its ``n`` records could not be read, the most common cause, an example."""
    causes = [_cause(e) for e in errors]
    key, k = Counter(c[1] for c in causes).most_common(1)[0]
    first = next(i for i, c in enumerate(causes) if c[1] == key)
    ex = errors[first]
    where = f"record {skipped[first][0]!r}, {skipped[first][1]}"
    where += (f" line {ex.line}" if ex.line is not None else "") + (
        f", column `{ex.column}`" if ex.column is not None else "")  # fmt: skip
    none = "no record could be read: " if len(errors) == n else ""
    return (
        f"campaign {name!r}: {none}{len(errors)} of {n} records could not be read, more than half, so the campaign "
        f"is not diagnosed; most common cause ({k} of them): {causes[first][0]} (e.g. {where})"
    )
