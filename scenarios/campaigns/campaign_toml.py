"""``campaign.toml``: reading it and checking it against the campaign format.

A campaign is a directory with ``campaign.toml``: ``name``, ``description``,
a ``[specimen]`` table (2H, 2B, depth, mass and an optional p, or a scan
``mesh``) and one ``[[record]]`` table per test (``id``, ``kind``, ``file``, the optional
outcome keys and an optional ``group``: records played under the same ground
motion share one), see docs/reference/campaign-format.md.
:func:`read_campaign_toml` reads and checks it; the campaign with its records
is read by :func:`housner.scenarios.campaigns.campaign.load_campaign`.

Errors: a malformed ``campaign.toml`` (also a value of the wrong type) raises
:class:`housner.errors.DataFileError` naming the key and, where known, its line
(:func:`key_line`). A ``[specimen] mesh`` that resolves outside the campaign
folder refuses the campaign unless ``allow_outside`` (:func:`path_outside`).
"""

from __future__ import annotations

import difflib
import math
import re
import sys
from dataclasses import dataclass, replace
from pathlib import Path

from housner.errors import DataFileError
from housner.scenarios.campaigns.campaign_records import KINDS
from housner.specimen import Specimen
from housner.units import G

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["CampaignFile", "key_line", "path_outside", "read_campaign_toml"]

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
    "group": "str (optional: records of one ground motion, e.g. played at several scalings, share a group)",
}
#: The numeric keys of an outcome record: each, where given, a number >= 0 in SI.
_OUTCOME_KEYS = ("theta_max", "residual_displacement", "pgv")
_TOP_KEYS = {"name", "description", "g", "specimen", "record"}
#: The local gravity a campaign may state [m/s^2]: the Earth's surface spans 9.76-9.84 (poles to equator,
#: sea level to mountain laboratories); a value outside is a unit slip or a typo.
G_RANGE = (9.7, 9.9)


@dataclass(frozen=True, eq=False)
class CampaignFile:
    """A ``campaign.toml`` read and checked.

    Attributes
    ----------
    path : pathlib.Path
        The ``campaign.toml``.
    text : str
        Its text (for the line of a key in a later message, :func:`key_line`).
    name : str
        The campaign's name (its folder's name when ``name`` is not given).
    specimen : Specimen
        From ``[specimen]``.
    scan : housner.scan.ScanSpecimen or None
        The scan-mesh derivation when ``[specimen]`` names a ``mesh``.
    records : list of dict
        The ``[[record]]`` tables, checked, in the file's order.
    g : float
        The local gravity where the campaign was measured [m/s^2] (``g``; default standard gravity).
    """

    path: Path
    text: str
    name: str
    specimen: Specimen
    scan: object
    records: list[dict]
    g: float = G


def read_campaign_toml(toml: Path, allow_outside: bool = False) -> CampaignFile:
    """Read ``campaign.toml`` and check its keys, its ``[specimen]`` and its ``[[record]]`` tables.

    Parameters
    ----------
    toml : pathlib.Path
        The ``campaign.toml`` file.
    allow_outside : bool
        Accept a ``[specimen] mesh`` that resolves outside the campaign folder.

    Returns
    -------
    CampaignFile

    Raises
    ------
    housner.errors.DataFileError
        The file is missing, not TOML, or a key or value is wrong: one line naming the key and, where known, the line.
    """
    data, text = _read_toml(toml)
    for key in data:
        if key not in _TOP_KEYS:
            raise _unknown_key(toml, text, "", key, _TOP_KEYS)
    name = data.get("name", toml.parent.name)
    for key in ("name", "description"):
        v = data.get(key, "")
        if not isinstance(v, str):
            raise DataFileError(toml, f"{key!r} must be a string, got {v!r}", line=key_line(text, key))
    g = _gravity(toml, text, data)
    specimen, scan = _specimen(toml, text, data, allow_outside)
    if g != G:
        if scan is not None:
            raise DataFileError(
                toml,
                f"`g` = {g} m/s^2 with a [specimen] mesh: a scan-mesh specimen is derived at standard gravity "
                f"({G} m/s^2) only; leave `g` out",
                line=key_line(text, "g"),
            )
        # p and I0 related at the campaign's g, p^2 = m g R / I0 (a stated p was measured there): Housner's r,
        # which depends on I0, is the block's own
        specimen = replace(specimen, g=g, p=specimen.p if "p" in data["specimen"] else None, I0=None)
    entries = _record_entries(toml, text, data)
    return CampaignFile(path=toml, text=text, name=name, specimen=specimen, scan=scan, records=entries, g=g)


def _gravity(path: Path, text: str, data: dict) -> float:
    """The campaign's ``g`` [m/s^2], within :data:`G_RANGE`; standard gravity when not given."""
    if "g" not in data:
        return G
    v = data["g"]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not (G_RANGE[0] <= v <= G_RANGE[1]):
        raise DataFileError(
            path,
            f"`g` must be the local gravity in m/s^2, between {G_RANGE[0]} and {G_RANGE[1]}, got {v!r}",
            line=key_line(text, "g"),
        )
    return float(v)


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


def key_line(text: str, key: str, table: str | None = None, index: int = 0) -> int | None:
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
        line=key_line(text, key, table, index),
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
            line=key_line(text, "specimen") or _table_line(text, "specimen"),
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
                line=key_line(text, key, "specimen"),
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
            raise DataFileError(
                path,
                f"[specimen] {key!r} must be {_MESH_KEYS[key]}, got {spec[key]!r}",
                line=key_line(text, key, "specimen"),
            )
    mesh = Path(spec["mesh"])
    mesh = mesh if mesh.is_absolute() else path.parent / mesh
    outside = None if allow_outside else path_outside(mesh, path.parent, "the files it names")
    if outside is not None:
        raise DataFileError(
            path, f"[specimen] 'mesh' {spec['mesh']!r} {outside}", line=key_line(text, "mesh", "specimen")
        )
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
            line=key_line(text, "record") or _table_line(text, "record") or _plain_table_line(text, "record"),
        )
    if not recs:
        raise DataFileError(
            path, "`record` is empty: a campaign needs at least one [[record]]", line=key_line(text, "record")
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
                    path,
                    f"{where}{key!r} must be a non-empty string, got {rec[key]!r}",
                    line=key_line(text, key, "record", i),
                )
        rid = rec["id"]
        if rid in seen:
            raise DataFileError(
                path,
                f"{where}'id' {rid!r} is already used by [[record]] #{seen[rid] + 1}",
                line=key_line(text, "id", "record", i),
            )
        seen[rid] = i
        if rec["kind"] not in KINDS:
            close = difflib.get_close_matches(rec["kind"], KINDS, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise DataFileError(
                path,
                f"{where}'kind' must be one of {', '.join(KINDS)}, got {rec['kind']!r}{hint}",
                line=key_line(text, "kind", "record", i),
            )
        if "overturned" in rec and not isinstance(rec["overturned"], bool):
            raise DataFileError(
                path,
                f"{where}'overturned' must be true or false, got {rec['overturned']!r}",
                line=key_line(text, "overturned", "record", i),
            )
        if "group" in rec and (not isinstance(rec["group"], str) or not rec["group"].strip()):
            raise DataFileError(
                path,
                f"{where}'group' must be a non-empty string (the ground motion the record played), "
                f"got {rec['group']!r}",
                line=key_line(text, "group", "record", i),
            )
        for key in _OUTCOME_KEYS:
            v = rec.get(key, 0.0)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise DataFileError(
                    path,
                    f"{where}{key!r} must be a number >= 0 {_RECORD_KEYS[key].split(' (')[0]}, got {v!r}",
                    line=key_line(text, key, "record", i),
                )
        out.append(rec)
    return out


def path_outside(path: Path, folder: Path, what: str = "records") -> str | None:
    """None if ``path`` resolves (links and ``..`` followed) inside ``folder``; else the end of the message."""
    inside = folder.resolve()
    try:
        if path.resolve().is_relative_to(inside):
            return None
    except (OSError, RuntimeError):  # a loop of symbolic links (RuntimeError before Python 3.13)
        return "cannot be resolved (a loop of symbolic links?)"
    return (
        f"resolves outside the campaign folder {inside} ({what} must lie inside it; pass --allow-outside "
        "to read it anyway, allow_outside=True in Python)"
    )
