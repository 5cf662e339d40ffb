"""The schema of a scenario file: allowed keys and types per table, checks with line numbers, one-line errors.

:func:`housner.scenarios.catalogue.scenario.load_scenario` reads a TOML file and passes each
table through the checks here before any work: an unknown key gets "did you
mean", a value out of range names the file, the table, the key and (found by
a plain scan of the text, as tomllib keeps no positions) its line.
"""

from __future__ import annotations

import difflib
import math
import re
from pathlib import Path
from typing import Any

import numpy as np

from housner.effects import available_effects, load_plugin, make_effect
from housner.engines.base import ENGINES
from housner.errors import one_line, unknown_choice
from housner.readers.measured_data import parse_unit
from housner.scenarios.motions.build import DEFAULT_RDK_MODEL, RDK_MODELS
from housner.scenarios.motions.records import RECORDS
from housner.specimen import Specimen

SPECIMEN_PRESETS = {"bachmann2017": Specimen.bachmann2017}
MOTION_SOURCES = ("rdk", "record", "records", "pulses", "free_vibration")
PULSES = ("symmetric_ricker", "antisymmetric_ricker", "one_sine", "mavroeidis_papageorgiou")

# Allowed keys per table: key -> expected type(s). Unknown keys get "did you mean".
_SCHEMA: dict[str, dict[str, Any]] = {
    "": {
        "name": str,
        "description": str,
        "specimen": dict,
        "motions": dict,
        "engines": dict,
        "analysis": dict,
        "effects": list,
        "plugins": list,
        "study": dict,
    },
    "specimen": {
        "preset": str,
        "height": float,
        "width": float,
        "depth": float,
        "mass": float,
        "p": float,
        "I0": float,
        "name": str,
    },
    "motions": {
        "source": str,
        "record": str,
        "records": (str, list),
        "units": str,
        "model": str,
        "n": int,
        "seed": int,
        "prototype_height": float,
        "S": float,
        "amplitude": float,
        "theta0_over_alpha": list,
        "duration": float,
        "dt": float,
        "pulse": str,
        "gamma": float,
        "nu": float,
        "omega_ratio": (list, dict),
        "accel_ratio": (list, dict),
    },
    "engines": {"names": list},
    "analysis": {"reference": str, "paper_percentiles": dict, "paper_note": str, "seed_spread": int},
    "study": {
        "intensity": str,
        "levels": list,
        "period": float,
        "prototype_heights": list,
        "S": list,
        "thresholds": list,
        "bootstrap": int,
        "seed": int,
        "histories": bool,
    },
}


class ScenarioError(ValueError):
    """A scenario file is invalid; the message names the file, the key and, where known, the line."""


_TABLE_RE = re.compile(r"^\s*\[\s*([A-Za-z0-9_.\-\"' ]+?)\s*\]")
TOML_LINE_RE = re.compile(r"\(at line (\d+), column (\d+)\)")


def _key_line(text: str, table: str, key: str) -> int | None:
    """1-based line of ``key = ...`` in ``[table]`` ("" = top level) of a TOML text, or None.

    A plain scan (tomllib keeps no positions): good for the flat files of the
    catalogue, None when the key is written in a way it does not recognise.
    """
    current = ""
    pat = re.compile(rf"^\s*[\"']?{re.escape(key)}[\"']?\s*=")
    for n, line in enumerate(text.splitlines(), start=1):
        m = _TABLE_RE.match(line)
        if m and not line.lstrip().startswith("[["):
            current = m.group(1).replace('"', "").replace("'", "").strip()
            continue
        if current == table and pat.match(line):
            return n
    if table and "." not in table:  # an inline table: `motions = { n = 0 }` or `[engines.x]`
        return _key_line(text, "", table)
    return None


class ScenarioFile:
    """A scenario file being checked: builds messages that name the file, the line and the key."""

    def __init__(self, path: Path, text: str):
        self.path = path
        self.text = text

    def error(self, table: str, key: str | None, message: str) -> ScenarioError:
        line = _key_line(self.text, table, key) if key is not None else None
        if line is None and key is not None:  # the key is a table of its own: [key] or [table.key]
            line = table_line(self.text, f"{table}.{key}" if table else key)
        if line is None and table:
            line = table_line(self.text, table)
        where = f"{self.path} line {line}" if line is not None else f"{self.path}"
        return ScenarioError(f"{where}: {message}")


def table_line(text: str, table: str) -> int | None:
    for n, line in enumerate(text.splitlines(), start=1):
        m = _TABLE_RE.match(line)
        if m and m.group(1).replace('"', "").replace("'", "").strip() == table:
            return n
    return None


def check_table(f: ScenarioFile, table: str, data: dict) -> None:
    allowed = _SCHEMA[table]
    for key, value in data.items():
        if table == "engines" and key != "names":
            if not isinstance(value, dict):
                raise f.error(table, key, f"[engines.{key}] must be a table of engine settings")
            continue
        where = f"[{table}] " if table else ""
        if key not in allowed:
            close = difflib.get_close_matches(key, allowed, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise f.error(table, key, f"unknown key {where}{key!r}{hint} (allowed: {', '.join(sorted(allowed))})")
        expected = allowed[key]
        types = expected if isinstance(expected, tuple) else (expected,)
        if float in types:
            types = types + (int,)
        if not isinstance(value, types) or (isinstance(value, bool) and bool not in types):
            names = " or ".join(t.__name__ for t in types if t is not int or float not in types)
            raise f.error(table, key, f"{where}{key!r} must be {names}, got {value!r}")
        if isinstance(value, float) and not math.isfinite(value):
            raise f.error(table, key, f"{where}{key!r} must be a finite number, got {value!r}")
        if table and isinstance(value, dict) and table != "analysis":
            continue
        if isinstance(value, dict) and key in _SCHEMA:
            check_table(f, key, value)


def parse_grid(path: Path, key: str, spec: Any, text: str = "") -> np.ndarray:
    f = ScenarioFile(path, text)
    try:
        if isinstance(spec, list):
            arr = np.asarray(spec, dtype=float)
        else:
            extra = set(spec) - {"start", "stop", "num"}
            if extra or not {"start", "stop", "num"} <= set(spec):
                raise f.error("motions", key, f"[motions] {key!r} must be a list or {{start, stop, num}}, got {spec!r}")
            num = spec["num"]
            if isinstance(num, bool) or not isinstance(num, int) or num < 1:
                raise f.error("motions", key, f"[motions] {key!r}: 'num' must be a positive integer, got {num!r}")
            arr = np.linspace(float(spec["start"]), float(spec["stop"]), num)
    except (TypeError, ValueError) as e:
        if isinstance(e, ScenarioError):
            raise
        raise f.error("motions", key, f"[motions] {key!r} must hold numbers, got {spec!r}") from None
    if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise f.error("motions", key, f"[motions] {key!r} must hold positive finite numbers")
    return arr


def is_path(record: str) -> bool:
    """True if ``record`` names a file: not a shipped name, and with a suffix or a path separator."""
    return record not in RECORDS and (bool(Path(record).suffix) or "/" in record or "\\" in record)


def read_specimen(f: ScenarioFile, table: dict) -> Specimen:
    """The [specimen] table as a :class:`housner.Specimen`: a preset, optionally with keys replaced, or keys alone."""
    spec_t = dict(table)
    preset = spec_t.pop("preset", None)
    try:
        if preset is not None:
            if preset not in SPECIMEN_PRESETS:
                raise unknown_choice("specimen preset", preset, SPECIMEN_PRESETS)
            specimen = SPECIMEN_PRESETS[preset]()
            if spec_t:
                from dataclasses import replace

                if "p" not in spec_t and "I0" not in spec_t:
                    spec_t["p"] = specimen.p
                specimen = replace(specimen, **{"p": None, "I0": None, **spec_t})
        else:
            specimen = Specimen(**spec_t)
    except (ValueError, TypeError) as e:
        key = re.search(r"`(\w+)`", str(e))
        raise f.error("specimen", key.group(1) if key else None, f"[specimen] {e}") from None

    return specimen


def check_motions(f: ScenarioFile, mot: dict) -> None:
    """Check the [motions] table: its source, the keys the source needs, ranges and the record's name."""
    src = mot.get("source")
    if src not in MOTION_SOURCES:
        raise f.error("motions", "source", f"[motions] {unknown_choice('source', src, MOTION_SOURCES)}")
    need = {"free_vibration": ["theta0_over_alpha"], "pulses": ["omega_ratio", "accel_ratio"]}.get(src, [])
    for k in need:
        if k not in mot:
            raise f.error("motions", None, f"[motions] source {src!r} needs key {k!r}")
    if src == "pulses" and mot.get("pulse", "symmetric_ricker") not in PULSES:
        raise f.error("motions", "pulse", f"[motions] {unknown_choice('pulse', mot['pulse'], PULSES)}")
    for k in ("prototype_height", "S", "duration", "dt", "amplitude"):
        if k in mot and not (math.isfinite(mot[k]) and mot[k] > 0):
            raise f.error("motions", k, f"[motions] {k!r} must be positive and finite, got {mot[k]!r}")
    if "n" in mot and mot["n"] < 1:
        raise f.error("motions", "n", f"[motions] 'n' must be a positive integer, got {mot['n']!r}")
    if "seed" in mot and mot["seed"] < 0:
        raise f.error("motions", "seed", f"[motions] 'seed' must be a non-negative integer, got {mot['seed']!r}")
    if "dt" in mot and "duration" in mot and mot["dt"] >= mot["duration"]:
        raise f.error(
            "motions", "dt", f"[motions] 'dt' ({mot['dt']!r} s) must be below 'duration' ({mot['duration']!r} s)"
        )
    if "units" in mot:  # the acceleration unit of record files whose header names none
        u = parse_unit(mot["units"])
        if u is None or u[0] != "acceleration":
            raise f.error(
                "motions",
                "units",
                f"[motions] 'units' must be an acceleration unit (g, cm/s^2, m/s^2, "
                f"mm/s^2, in/s^2, ft/s^2), got {mot['units']!r}",
            )
    for key, sources in (
        ("record", ("rdk", "record")),
        ("records", ("records",)),
        ("model", ("rdk",)),
        ("units", ("rdk", "record", "records")),
    ):
        if key in mot and src not in sources:
            use = " or ".join(f"source = {s!r}" for s in sources)
            raise f.error("motions", key, f"[motions] {key!r} applies to {use}, not to source {src!r}")
    for key in ("gamma", "nu"):  # the shape of a Mavroeidis-Papageorgiou pulse
        if key in mot and not (src == "pulses" and mot.get("pulse") == "mavroeidis_papageorgiou"):
            raise f.error(
                "motions", key, f"[motions] {key!r} applies to pulse = 'mavroeidis_papageorgiou' (source = 'pulses')"
            )
    if "gamma" in mot and not mot["gamma"] > 1.0:
        raise f.error(
            "motions", "gamma", f"[motions] 'gamma' must exceed 1 (cycles under the envelope), got {mot['gamma']!r}"
        )
    if src == "records" and "records" not in mot:
        raise f.error(
            "motions", None, "[motions] source 'records' needs key 'records' (a folder, or a list of .AT2 / .csv files)"
        )
    if src in ("rdk", "record"):
        rec = mot.get("record", "elcentro")
        if not is_path(rec) and rec not in RECORDS:
            msg = unknown_choice("record", rec, RECORDS)
            raise f.error("motions", "record", f"[motions] {msg}, or a path to an .AT2 / .csv file")
    if mot.get("model", DEFAULT_RDK_MODEL) not in RDK_MODELS:
        raise f.error("motions", "model", f"[motions] {unknown_choice('model', mot['model'], RDK_MODELS)}")
    if src == "free_vibration":
        values = mot["theta0_over_alpha"]
        bad = [a for a in values if isinstance(a, bool) or not (isinstance(a, (int, float)) and 0 < a < 1)]
        if bad or not values:
            got = bad if bad else "an empty list"
            raise f.error(
                "motions", "theta0_over_alpha", f"[motions] 'theta0_over_alpha' values must lie in (0, 1), got {got}"
            )


def read_engines(f: ScenarioFile, table: dict) -> tuple[list[str], dict]:
    """The [engines] table: the engine names to run and the per-engine settings tables (all registered names)."""
    eng_t = dict(table)
    names = list(eng_t.pop("names", ["housner"]))
    if not names:
        raise f.error("engines", "names", "[engines] 'names' must list at least one engine")
    for n in names:
        if not isinstance(n, str):
            raise f.error("engines", "names", f"[engines] 'names' must hold engine names (strings), got {n!r}")
    for n in names + list(eng_t):
        if n not in ENGINES:
            key = "names" if n in names else None
            err = f.error("engines", key, f"[engines] {unknown_choice('engine', n, ENGINES)}")
            if key is None:
                line = table_line(f.text, f"engines.{n}")
                if line is not None:
                    err = ScenarioError(f"{f.path} line {line}: [engines] {unknown_choice('engine', n, ENGINES)}")
            raise err
    return names, eng_t


def check_analysis(f: ScenarioFile, analysis: dict) -> None:
    """The [analysis] table is read after the simulation (report): check it now."""
    ref = analysis.get("reference")
    if ref is not None:
        if ref not in ENGINES:
            raise f.error("analysis", "reference", f"[analysis] {unknown_choice('reference engine', ref, ENGINES)}")
    for k, v in (analysis.get("paper_percentiles") or {}).items():
        try:
            q = float(k)
        except ValueError:
            q = math.nan
        if not 0 < q < 100:
            raise f.error(
                "analysis",
                "paper_percentiles",
                f"[analysis] 'paper_percentiles' key {k!r} must be a percentile in (0, 100)",
            )
        ok = (isinstance(v, str) and v.strip().lower() in ("overturn", "overturned")) or (
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v >= 0
        )
        if not ok:
            raise f.error(
                "analysis",
                "paper_percentiles",
                f"[analysis] 'paper_percentiles' value for {k!r} must be a number >= 0 or \"overturn\", got {v!r}",
            )
    k = analysis.get("seed_spread")
    if k is not None and not 0 <= k <= 1000:
        raise f.error("analysis", "seed_spread", f"[analysis] 'seed_spread' must be between 0 and 1000, got {k!r}")


def _array_table_line(text: str, table: str, k: int) -> int | None:
    """1-based line of the ``k``-th ``[[table]]`` header (k from 0) of a TOML text, or None."""
    pat = re.compile(rf"^\s*\[\[\s*{re.escape(table)}\s*\]\]")
    lines = [n for n, line in enumerate(text.splitlines(), start=1) if pat.match(line)]
    return lines[k] if k < len(lines) else None


def read_plugins(f: ScenarioFile, entries: list) -> tuple[str, ...]:
    """Load the effects files of the top-level ``plugins`` list (paths relative to the scenario's folder).

    ``plugins = ["effects/pivot_friction.py"]`` does for a scenario what ``--plugin FILE`` does on the
    command line: the file's ``@register_effect`` classes join the registry, so that ``[[effects]]`` can
    name them (and the workers load the same file). Returns the effect names registered; a file that
    is missing, not ``.py``, registers no effect or fails to import is a one-line error naming the
    scenario, the key's line and the file.
    """
    names: list[str] = []
    for entry in entries:
        if not isinstance(entry, str):
            raise f.error("", "plugins", f"'plugins' must list Python files (strings), got {entry!r}")
        path = Path(entry).expanduser()
        if not path.is_absolute():
            path = f.path.parent / path
        try:
            names.extend(load_plugin(path))
        except Exception as e:  # a user's file: any failure is one line naming it
            raise f.error("", "plugins", f"plugin {entry!r}: {one_line(e)}") from None
    return tuple(names)


def read_effects(f: ScenarioFile, entries: list, specimen: Specimen) -> tuple:
    """The ``[[effects]]`` tables as effects of :mod:`housner.effects`, each checked against the specimen.

    Each table names an effect (``name = "rotational_damping"``) and gives its
    parameters in the units of the effect's ``params``; an unknown name or
    parameter, a missing one or a value out of bounds is a one-line error
    naming the file and the line of that ``[[effects]]``.
    """
    out = []
    for k, entry in enumerate(entries):
        line = _array_table_line(f.text, "effects", k)
        at = f"{f.path} line {line}" if line is not None else f"{f.path}"
        if not isinstance(entry, dict):
            raise ScenarioError(f"{at}: [[effects]] entries must be tables (name = ..., parameters), got {entry!r}")
        params = dict(entry)
        name = params.pop("name", None)
        if not isinstance(name, str):
            choices = ", ".join(available_effects())
            raise ScenarioError(f'{at}: [[effects]] needs name = "<effect>" (choices: {choices})')
        try:
            out.append(make_effect(name, specimen, **params))
        except (TypeError, ValueError) as e:
            raise ScenarioError(f"{at}: [[effects]] {e}") from None
    names = [e.name for e in out]
    dup = next((n for n in names if names.count(n) > 1), None)
    if dup is not None:
        raise ScenarioError(f"{f.path}: [[effects]] lists {dup!r} twice; give it once with all its parameters")
    return tuple(out)


def effects_label(effects) -> str:
    """A short text naming effects and their parameters, e.g. ``restitution(r=0.9532)``; "" for none."""
    parts = []
    for e in effects:
        vals = ", ".join(f"{k}={getattr(e, k):.4g}" for k in type(e).param_specs)
        parts.append(f"{e.name}({vals})")
    return " + ".join(parts)
