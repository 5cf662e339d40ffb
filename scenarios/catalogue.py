"""The scenario catalogue: declarative TOML files in this folder, read and validated here.

A scenario names a specimen, a motion source (an RDK ensemble fitted to a
record, a record, pulses on a grid, free-vibration releases), the engines to
run and what to analyse. Everything a run produces follows from the file and
its seed.
"""

from __future__ import annotations

import difflib
import functools
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from housner.errors import unknown_choice
from housner.motion import GroundMotion
from housner.specimen import Specimen

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["SCENARIOS", "Scenario", "ScenarioError", "list_scenarios", "load_scenario"]

HERE = Path(__file__).resolve().parent

SPECIMEN_PRESETS = {"bachmann2017": Specimen.bachmann2017}
MOTION_SOURCES = ("rdk", "record", "pulses", "free_vibration")
PULSES = ("symmetric_ricker", "antisymmetric_ricker", "one_sine")

# Allowed keys per table: key -> expected type(s). Unknown keys get "did you mean".
_SCHEMA: dict[str, dict[str, Any]] = {
    "": {
        "name": str,
        "description": str,
        "specimen": dict,
        "motions": dict,
        "engines": dict,
        "analysis": dict,
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
        "n": int,
        "seed": int,
        "prototype_height": float,
        "S": float,
        "amplitude": float,
        "theta0_over_alpha": list,
        "duration": float,
        "dt": float,
        "pulse": str,
        "omega_ratio": (list, dict),
        "accel_ratio": (list, dict),
    },
    "engines": {"names": list},
    "analysis": {"reference": str, "paper_percentiles": dict, "seed_spread": int},
}


class ScenarioError(ValueError):
    """A scenario file is invalid; the message names the file and the key."""


def _check_table(path: Path, table: str, data: dict) -> None:
    allowed = _SCHEMA[table]
    for key, value in data.items():
        if table == "engines" and key != "names":
            if not isinstance(value, dict):
                raise ScenarioError(f"{path}: [engines.{key}] must be a table of engine settings")
            continue
        where = f"[{table}] " if table else ""
        if key not in allowed:
            close = difflib.get_close_matches(key, allowed, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise ScenarioError(f"{path}: unknown key {where}{key!r}{hint} (allowed: {', '.join(sorted(allowed))})")
        expected = allowed[key]
        types = expected if isinstance(expected, tuple) else (expected,)
        if float in types:
            types = types + (int,)
        if not isinstance(value, types) or (isinstance(value, bool) and bool not in types):
            names = " or ".join(t.__name__ for t in types if t is not int or float not in types)
            raise ScenarioError(f"{path}: {where}{key!r} must be {names}, got {value!r}")
        if table and isinstance(value, dict) and table != "analysis":
            continue
        if isinstance(value, dict) and key in _SCHEMA:
            _check_table(path, key, value)


def _grid(path: Path, key: str, spec: Any) -> np.ndarray:
    if isinstance(spec, list):
        arr = np.asarray(spec, dtype=float)
    else:
        extra = set(spec) - {"start", "stop", "num"}
        if extra or not {"start", "stop", "num"} <= set(spec):
            raise ScenarioError(f"{path}: [motions] {key!r} must be a list or {{start, stop, num}}, got {spec!r}")
        arr = np.linspace(float(spec["start"]), float(spec["stop"]), int(spec["num"]))
    if arr.size == 0 or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise ScenarioError(f"{path}: [motions] {key!r} must hold positive finite numbers")
    return arr


@dataclass
class Scenario:
    """A validated scenario.

    Attributes
    ----------
    name, description : str
    specimen : Specimen
    motions : dict
        The [motions] table (source and its parameters).
    engines : list of str
        Engine names to run by default.
    engine_settings : dict
        Per-engine settings overrides ([engines.NAME] tables).
    analysis : dict
        Reference engine, the paper's values, extra analyses.
    path : Path
        The file it came from.
    """

    name: str
    description: str
    specimen: Specimen
    motions: dict
    engines: list[str]
    engine_settings: dict = field(default_factory=dict)
    analysis: dict = field(default_factory=dict)
    path: Path | None = None
    raw: dict = field(default_factory=dict, repr=False)

    @property
    def source(self) -> str:
        """Motion source: one of rdk, record, pulses, free_vibration."""
        return self.motions["source"]

    @property
    def seed(self) -> int | None:
        """Seed of the stochastic ensemble (None for deterministic sources)."""
        return self.motions.get("seed")

    @property
    def S(self) -> float:
        """Size ratio prototype / model, S = R_prototype / R_model [-] (1 when the scenario has no prototype)."""
        if "S" in self.motions:
            return float(self.motions["S"])
        if "prototype_height" in self.motions:
            return float(self.motions["prototype_height"]) / self.specimen.height
        return 1.0

    @property
    def n_motions(self) -> int:
        """Number of motions the scenario defines."""
        src = self.source
        if src == "rdk":
            return int(self.motions.get("n", 100))
        if src == "record":
            return 1
        if src == "free_vibration":
            return len(self.motions["theta0_over_alpha"])
        return len(self.pulse_grid()[0])

    def pulse_grid(self) -> tuple[np.ndarray, np.ndarray]:
        """Flattened (omega_p/p, a_p/(g tan alpha)) pairs of a pulse scenario, row-major in omega."""
        w = _grid(self.path, "omega_ratio", self.motions["omega_ratio"])
        a = _grid(self.path, "accel_ratio", self.motions["accel_ratio"])
        W, A = np.meshgrid(w, a, indexing="ij")
        return W.ravel(), A.ravel()

    def build_motions(self, n: int | None = None, *, seed: int | None = None) -> tuple[list[GroundMotion], dict]:
        """Generate the scenario's motions at model scale, and metadata for the report.

        Parameters
        ----------
        n : int, optional
            Number of motions (RDK ensembles only; motion i does not depend on n).
        seed : int, optional
            Override the scenario's seed (RDK only).

        Returns
        -------
        motions : list of GroundMotion
        meta : dict
            Source-specific facts (fitted RDK parameters, record, scaling S).
        """
        src = self.source
        m = self.motions
        meta: dict[str, Any] = {"source": src, "S": self.S}
        if src in ("rdk", "record"):
            from scenarios.records import RECORDS

            rec_name = m.get("record", "elcentro")
            if rec_name not in RECORDS:
                raise unknown_choice("record", rec_name, RECORDS)
            record = RECORDS[rec_name]()
            meta["record"] = {"name": record.name, "provenance": record.provenance, "dt": record.dt, "n": record.n}
            amp = float(m.get("amplitude", 1.0))
            if src == "record":
                motions = [record.scaled(amplitude=amp).to_model_scale(self.S)]
            else:
                from scenarios import rdk

                params = _rdk_fit(rec_name)
                meta["rdk_params"] = params.describe()
                n = int(m.get("n", 100)) if n is None else int(n)
                if n <= 0:
                    raise ValueError(f"`n` must be positive, got {n}")
                seed = int(m.get("seed", 0)) if seed is None else int(seed)
                meta["seed"] = seed
                proto = rdk.simulate(params, n, seed)
                motions = [g.scaled(amplitude=amp).to_model_scale(self.S) for g in proto]
            return motions, meta
        if src == "free_vibration":
            alpha = self.specimen.alpha
            dur = float(m.get("duration", 10.0))
            dt = float(m.get("dt", 0.002))
            motions = [
                GroundMotion.free_vibration(a * alpha, dur, dt, name=f"release {a:.2f} alpha")
                for a in m["theta0_over_alpha"]
            ]
            meta["theta0_over_alpha"] = list(m["theta0_over_alpha"])
            return motions, meta
        # pulses
        from scenarios import pulses

        W, A = self.pulse_grid()
        p = self.specimen.p
        a_up = self.specimen.uplift_acceleration
        dt = float(m.get("dt", 0.002))
        kind = m.get("pulse", "symmetric_ricker")
        motions = []
        for w, a in zip(W, A, strict=True):
            if kind == "one_sine":
                g = pulses.one_sine(a * a_up, w * p, dt=dt, p=p)
            else:
                g = pulses.ricker(a * a_up, w * p, kind=kind.split("_")[0], dt=dt, p=p)
            motions.append(
                GroundMotion(g.acc, g.dt, f"{kind} w/p={w:.3g} a/gtan={a:.3g}", g.provenance, g.theta0, g.theta_dot0)
            )
        meta.update({"pulse": kind, "omega_ratio": W.tolist(), "accel_ratio": A.tolist()})
        return motions, meta

    def describe(self) -> dict:
        """The scenario as plain data (for run.json and the cache key)."""
        return {"name": self.name, "file": str(self.path) if self.path else None, **self.raw}


@functools.lru_cache(maxsize=8)
def _rdk_fit(record_name: str):
    """RDK parameters fitted to a shipped record (deterministic; cached for repeated ensembles)."""
    from scenarios import rdk
    from scenarios.records import RECORDS

    return rdk.fit(RECORDS[record_name]())


def _discover() -> dict[str, Path]:
    return {p.stem: p for p in sorted(HERE.glob("*.toml"))}


#: Registry of the shipped scenarios: name -> file.
SCENARIOS: dict[str, Path] = _discover()


def list_scenarios() -> list[tuple[str, str]]:
    """(name, description) of every shipped scenario."""
    out = []
    for name in SCENARIOS:
        try:
            out.append((name, load_scenario(name).description))
        except Exception as e:  # a broken file is listed, not fatal
            out.append((name, f"INVALID: {e}"))
    return out


def load_scenario(name_or_path: str | Path) -> Scenario:
    """Load and validate a scenario by catalogue name or by path to a TOML file."""
    p = Path(name_or_path)
    if p.suffix == ".toml" or p.exists():
        path = p
        if not path.exists():
            raise ScenarioError(f"scenario file {path} does not exist")
    else:
        name = str(name_or_path)
        if name not in SCENARIOS:
            raise unknown_choice("scenario", name, SCENARIOS)
        path = SCENARIOS[name]
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as e:
        raise ScenarioError(f"{path}: invalid TOML: {e}") from None
    _check_table(path, "", raw)
    for required in ("specimen", "motions"):
        if required not in raw:
            raise ScenarioError(f"{path}: missing table [{required}]")

    spec_t = dict(raw["specimen"])
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
        raise ScenarioError(f"{path}: [specimen] {e}") from None

    mot = dict(raw["motions"])
    src = mot.get("source")
    if src not in MOTION_SOURCES:
        raise ScenarioError(f"{path}: [motions] {unknown_choice('source', src, MOTION_SOURCES)}")
    need = {"free_vibration": ["theta0_over_alpha"], "pulses": ["omega_ratio", "accel_ratio"]}.get(src, [])
    for k in need:
        if k not in mot:
            raise ScenarioError(f"{path}: [motions] source {src!r} needs key {k!r}")
    if src == "pulses" and mot.get("pulse", "symmetric_ricker") not in PULSES:
        raise ScenarioError(f"{path}: [motions] {unknown_choice('pulse', mot['pulse'], PULSES)}")
    for k in ("prototype_height", "S", "duration", "dt"):
        if k in mot and not (math.isfinite(mot[k]) and mot[k] > 0):
            raise ScenarioError(f"{path}: [motions] {k!r} must be positive, got {mot[k]!r}")
    if src == "free_vibration":
        bad = [a for a in mot["theta0_over_alpha"] if not (isinstance(a, (int, float)) and 0 < a < 1)]
        if bad:
            raise ScenarioError(f"{path}: [motions] 'theta0_over_alpha' values must lie in (0, 1), got {bad}")

    eng_t = dict(raw.get("engines", {}))
    names = list(eng_t.pop("names", ["housner"]))
    from engines.base import ENGINES

    for n in names + list(eng_t):
        if n not in ENGINES:
            raise ScenarioError(f"{path}: [engines] {unknown_choice('engine', n, ENGINES)}")
    scen = Scenario(
        name=raw.get("name", path.stem),
        description=raw.get("description", ""),
        specimen=specimen,
        motions=mot,
        engines=names,
        engine_settings=eng_t,
        analysis=dict(raw.get("analysis", {})),
        path=path,
        raw=raw,
    )
    if src == "pulses":
        scen.pulse_grid()  # validate the grids now
    return scen
