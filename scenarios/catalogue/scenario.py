"""The scenario catalogue: declarative TOML files in this folder, read and validated here.

A scenario names a specimen, a motion source (an RDK ensemble fitted to a
record, a record, a suite of records, pulses on a grid, free-vibration
releases), the engines to run and what to analyse. Everything a run produces
follows from the file and its seed.

A record is a shipped one (:data:`housner.scenarios.motions.records.RECORDS`) or a user's
``.AT2`` / ``.csv`` file, its path relative to the scenario file's folder;
record files are read, and refused with a one-line error, when the scenario
is loaded.
"""

from __future__ import annotations

import difflib
import sys
from collections import OrderedDict
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

from housner.scenarios.catalogue.schema import (
    _TOML_LINE_RE,
    DEFAULT_RDK_MODEL,
    RDK_MODELS,
    ScenarioError,
    _check_analysis,
    _check_table,
    _File,
    _grid,
    _is_path,
    _table_line,
    check_motions,
    read_effects,
    read_engines,
    read_specimen,
)
from housner.scenarios.catalogue.study_table import read_study

__all__ = ["SCENARIOS", "Scenario", "ScenarioError", "list_scenarios", "load_scenario"]

HERE = Path(__file__).resolve().parent


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
    effects : tuple of housner.effects.Effect
        The [[effects]] tables; each engine runs without and with them.
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
    raw_text: str = field(default="", repr=False)
    #: Physical effects of the [[effects]] tables (housner.effects); the runner runs every engine
    #: without them and with them.
    effects: tuple = ()
    #: The [study] table (housner.scenarios.studies.Study): stripes and sizes to run and fit fragility curves to;
    #: None: a run.
    study: Any = None
    #: Record files read from the [motions] table: key -> [(motion, facts)]; None until read.
    _files: dict | None = field(default=None, init=False, repr=False, compare=False)

    @property
    def source(self) -> str:
        """Motion source: one of rdk, record, records, pulses, free_vibration."""
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
        if src == "records":
            return len(self._read_files()["records"])
        if src == "free_vibration":
            return len(self.motions["theta0_over_alpha"])
        return len(self.pulse_grid()[0])

    def pulse_grid(self) -> tuple[np.ndarray, np.ndarray]:
        """Flattened (omega_p/p, a_p/(g tan alpha)) pairs of a pulse scenario, row-major in omega."""
        text = self.raw_text
        w = _grid(self.path, "omega_ratio", self.motions["omega_ratio"], text)
        a = _grid(self.path, "accel_ratio", self.motions["accel_ratio"], text)
        W, A = np.meshgrid(w, a, indexing="ij")
        return W.ravel(), A.ravel()

    # ------------------------------------------------------------------ records
    def _error(self, key: str | None, message: str) -> ScenarioError:
        return _File(self.path or Path(f"scenario {self.name!r}"), self.raw_text).error("motions", key, message)

    def _record_path(self, written: str) -> Path:
        """A record path as written in the file: relative to the scenario file's folder, or absolute."""
        p = Path(written)
        if p.is_absolute():
            return p
        return (self.path.parent if self.path is not None else Path.cwd()) / p

    def _read_file(self, key: str, written: str) -> tuple[GroundMotion, dict]:
        """One record file, and its facts for the metadata; any failure is one ScenarioError naming key and path."""
        from housner.scenarios.motions.records import RECORD_SUFFIXES, RECORDS, file_sha256, read_record_file

        path = self._record_path(written)
        what = f"[motions] {key!r} names {written!r}"
        if path.suffix.lower() in RECORD_SUFFIXES and not path.exists():
            hint = f"; shipped records: {', '.join(RECORDS)}" if key == "record" else ""
            raise self._error(key, f"{what}: no such file {path} (relative paths start at the scenario's folder{hint})")
        if key == "record" and path.is_dir():
            raise self._error(
                key,
                f"{what}: {path} is a folder; 'record' names one file (a folder of records is "
                'source = "records" with records = "FOLDER")',
            )
        try:
            motion = read_record_file(path)
            sha = file_sha256(path)
        except (OSError, ValueError) as e:
            raise self._error(key, f"{what}: {_one_line(e)}") from None
        facts = {
            "name": motion.name,
            "provenance": f"{motion.provenance}; file {path.resolve()} (sha256 {sha[:16]})",
            "dt": motion.dt,
            "n": motion.n,
            "file": written,
            "path": str(path.resolve()),
            "sha256": sha,
        }
        return GroundMotion(motion.acc, motion.dt, motion.name, facts["provenance"]), facts

    def _suite_files(self) -> list[str]:
        """The files of ``records`` (a folder: its .AT2 and .csv files sorted by name; or a list), as written."""
        from housner.scenarios.motions.records import RECORD_SUFFIXES

        spec = self.motions["records"]
        if isinstance(spec, str):
            folder = self._record_path(spec)
            what = f"[motions] 'records' names folder {spec!r}"
            if not folder.exists():
                raise self._error(
                    "records", f"{what}: no such folder {folder} (relative paths start at the scenario's folder)"
                )
            if not folder.is_dir():
                raise self._error("records", f"{what}: {folder} is a file; give a folder or a list of files")
            try:
                names = sorted(p.name for p in folder.iterdir() if p.suffix.lower() in RECORD_SUFFIXES and p.is_file())
            except OSError as e:
                raise self._error("records", f"{what}: cannot list {folder} ({e.strerror or e})") from None
            if not names:
                raise self._error("records", f"{what}: {folder} holds no .AT2 or .csv file")
            return [str(Path(spec) / name) for name in names]
        if not spec:
            raise self._error("records", "[motions] 'records' is an empty list; name at least one .AT2 or .csv file")
        for v in spec:
            if not isinstance(v, str):
                raise self._error("records", f"[motions] 'records' must hold file paths (strings), got {v!r}")
        return list(spec)

    def _read_files(self) -> dict:
        """Read the record files the [motions] table names, once (load_scenario does it, to fail early)."""
        if self._files is not None:
            return self._files
        files: dict[str, list] = {}
        src, m = self.source, self.motions
        if src in ("rdk", "record") and _is_path(m.get("record", "elcentro")):
            files["record"] = [self._read_file("record", m["record"])]
        elif src == "records":
            written = self._suite_files()
            seen: dict[str, str] = {}
            for w in written:  # names are checked before the files are read
                stem = Path(w).stem
                if stem in seen:
                    raise self._error(
                        "records",
                        f"[motions] 'records': {seen[stem]!r} and {w!r} would both be motion {stem!r}; "
                        "every record needs a name (file stem) of its own",
                    )
                seen[stem] = w
            files["records"] = [self._read_file("records", w) for w in written]
        self._files = files
        return files

    def _record(self) -> tuple[GroundMotion, dict]:
        """The record of an rdk or record source, and its facts (name, provenance, dt, n; file and sha256)."""
        files = self._read_files()
        if "record" in files:
            return files["record"][0]
        from housner.scenarios.motions.records import load_record

        record = load_record(self.motions.get("record", "elcentro"))
        return record, {"name": record.name, "provenance": record.provenance, "dt": record.dt, "n": record.n}

    def build_motions(
        self, n: int | None = None, *, seed: int | None = None, band_check: bool = False
    ) -> tuple[list[GroundMotion], dict]:
        """Generate the scenario's motions at model scale, and metadata for the report.

        Parameters
        ----------
        n : int, optional
            Number of motions (RDK ensembles only; motion i does not depend on n).
        seed : int, optional
            Override the scenario's seed (RDK only).
        band_check : bool
            RDK only: also compare the ensemble's mean 5 % spectra with the
            record's, per third-octave band (PSa 0.05-3 s, Sd 0.5-3 s, at
            prototype scale, before ``amplitude``; :func:`housner.scenarios.motions.bands.band_check`).
            About 2 s per 100 motions, so off unless asked (the runner asks).

        Returns
        -------
        motions : list of GroundMotion
        meta : dict
            Source-specific facts: ``S``; the ``record`` (name, provenance,
            dt [s], n; for a file also ``file``, ``path``, ``sha256``) or, for a
            suite, ``records`` (one such dict per motion); for RDK the ``model``,
            ``rdk_params``, ``seed``, for the matched model ``matched_gain``,
            and with ``band_check`` the ``band_check`` table.
        """
        src = self.source
        m = self.motions
        meta: dict[str, Any] = {"source": src, "S": self.S}
        amp = float(m.get("amplitude", 1.0))
        if src == "records":
            suite = self._read_files()["records"]
            meta["records"] = [facts for _, facts in suite]
            return [_to_model(g, amp, self.S) for g, _ in suite], meta
        if src in ("rdk", "record"):
            record, meta["record"] = self._record()
            if src == "record":
                return [_to_model(record, amp, self.S)], meta
            if n is not None and (isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1):
                raise ValueError(f"`n` (number of motions) must be a positive integer, got {n!r}")
            if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
                raise ValueError(f"`seed` must be a non-negative integer, got {seed!r}")
            n = int(m.get("n", 100)) if n is None else int(n)
            seed = int(m.get("seed", 0)) if seed is None else int(seed)
            model = m.get("model", DEFAULT_RDK_MODEL)
            try:
                fit = _fit(model, record)
            except ValueError as e:  # a user's record the model cannot be fitted to
                raise self._error(
                    "record", f"[motions] cannot fit model {model!r} to record {record.name!r}: {_one_line(e)}"
                ) from None
            meta["model"] = model
            meta["seed"] = seed
            if model == "matched":
                from housner.scenarios.motions import rdk_match

                meta["rdk_params"] = fit.params.describe()
                meta["matched_gain"] = _gain_facts(fit)
                proto = rdk_match.simulate_matched(fit, n, seed)
            else:
                from housner.scenarios.motions import rdk

                meta["rdk_params"] = fit.describe()
                proto = rdk.simulate(fit, n, seed)
            if band_check:
                meta["band_check"] = _band_facts(proto, record, seed)
            return [_to_model(g, amp, self.S) for g in proto], meta
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
        from housner import pulses

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

    def check_engines(self, names: list[str] | None = None) -> None:
        """Instantiate every engine to run with its [engines.NAME] settings, to refuse bad settings
        before any work (imports the engines' packages).

        Parameters
        ----------
        names : list of str, optional
            Engines to check (default: the scenario's).

        Raises
        ------
        ScenarioError
            An engine name is unknown or its settings are refused; the message names
            the file and the [engines.NAME] table.
        """
        from housner.engines.base import ENGINES, engine_class

        where = f"{self.path}" if self.path else f"scenario {self.name!r}"
        for name in names if names is not None else self.engines:
            if name not in ENGINES:
                raise ValueError(f"{unknown_choice('engine', name, ENGINES)}")
            settings = self.engine_settings.get(name, {})
            line = _table_line(self.raw_text, f"engines.{name}") if settings else None
            at = f"{where} line {line}" if line is not None else where
            cls = engine_class(name)
            try:
                cls(**settings)
            except (TypeError, ValueError) as e:
                msg = str(e)
                if isinstance(e, TypeError) and "unexpected keyword argument" in msg:
                    import inspect

                    known = [p for p in inspect.signature(cls).parameters if p not in ("self", "args", "kwargs")]
                    bad = [k for k in settings if k not in known]
                    close = difflib.get_close_matches(bad[0], known, n=1) if bad else []
                    hint = f"; did you mean {close[0]!r}?" if close else ""
                    msg = f"unknown setting {bad[0] if bad else '?'!r}{hint} (settings: {', '.join(known) or 'none'})"
                raise ScenarioError(f"{at}: [engines.{name}] {msg}") from None
        self.check_effects(names)

    def check_effects(self, names: list[str] | None = None) -> None:
        """Refuse, by name, an engine to run that does not realise every effect of [[effects]].

        Raises
        ------
        ScenarioError
            Naming the file, the engine, the effect and what the engine realises.
        """
        from housner.engines.base import ENGINES, engine_class

        where = f"{self.path}" if self.path else f"scenario {self.name!r}"
        for name in names if names is not None else self.engines:
            if name not in ENGINES:
                continue  # check_engines names it
            realised = engine_class(name).effects_supported
            for e in self.effects:
                if e.name not in realised:
                    can = ", ".join(sorted(realised)) or "none"
                    ok = [n for n in ENGINES if all(x.name in engine_class(n).effects_supported for x in self.effects)]
                    raise ScenarioError(
                        f"{where}: [[effects]] engine {name!r} cannot realise effect {e.name!r} (it realises: {can});"
                        f" run the effects on {', '.join(repr(n) for n in ok) or 'no engine'} (names = [...])"
                    )
            if self.effects:
                why = engine_class(name)(**self.engine_settings.get(name, {})).effect_refusal(
                    self.specimen, tuple(self.effects)
                )
                if why:
                    raise ScenarioError(f"{where}: [[effects]] {why}")

    def describe(self) -> dict:
        """The scenario as plain data (for run.json and the cache key)."""
        return {"name": self.name, "file": str(self.path) if self.path else None, **self.raw}


def _to_model(g: GroundMotion, amplitude: float, S: float) -> GroundMotion:
    """A prototype-scale motion (record or simulated) times ``amplitude``, compressed in time by sqrt(S)."""
    return g.scaled(amplitude=amplitude).to_model_scale(S)


def _one_line(e: Exception) -> str:
    return "; ".join(line.strip() for line in str(e).splitlines() if line.strip()) or type(e).__name__


#: Fitted ground-motion models, oldest first: (model, record name, content hash of the record's
#: samples and step) -> RDKParams or MatchedRDK. A record file that changes has another hash, so
#: its fit is redone; the fits are deterministic (fixed fit seed).
_FITS: OrderedDict[tuple[str, str, str], Any] = OrderedDict()
_FITS_SIZE = 8


def _fit(model: str, record: GroundMotion):
    """The model of ``RDK_MODELS`` fitted to ``record`` (cached, see :data:`_FITS`)."""
    key = (model, record.name, record.content_hash())
    if key in _FITS:
        _FITS.move_to_end(key)
        return _FITS[key]
    if model == "matched":
        from housner.scenarios.motions import rdk_match

        fit = rdk_match.fit_matched(record, params=_fit(DEFAULT_RDK_MODEL, record))
    elif model == DEFAULT_RDK_MODEL:
        from housner.scenarios.motions import rdk

        fit = rdk.fit(record)
    else:
        raise unknown_choice("RDK model", model, RDK_MODELS)
    _FITS[key] = fit
    while len(_FITS) > _FITS_SIZE:
        _FITS.popitem(last=False)
    return fit


def _gain_facts(fit) -> dict:
    """The spectral gain of a MatchedRDK as plain data (units in the keys)."""
    d = fit.describe()
    keys = ("gain_centres_s", "gain", "fir_length_s", "n_fit", "iterations", "worst_band_ratio_per_iteration")
    return {"model": d["model"], **{k: d[k] for k in keys}, "fit_seed": d["fit_seed"]}


def _band_facts(proto: list[GroundMotion], record: GroundMotion, seed: int) -> dict:
    """The band check of a prototype-scale ensemble against its record, as plain data for run.json."""
    from housner.scenarios.motions import bands

    check = bands.band_check(proto, record)
    keep = ("centre_s", "lo_s", "hi_s", "ratio", "ci95_lo", "ci95_hi", "verdict")

    def table(t, t_range) -> dict:
        bands = [{k: row[k] for k in keep} for row in t.rows()]
        return {"range_s": list(t_range), "passed": t.passed, "bands": bands}

    return {
        "what": (
            f"5 % damped spectra, mean of {len(proto)} motions (seed {seed}) / record {record.name!r}, "
            "per third-octave band, at prototype scale, before 'amplitude'"
        ),
        "record": record.name,
        "damping": check.damping,
        "bounds": list(check.psa.bounds),
        "passed": check.passed,
        "psa": table(check.psa, bands.DEFAULT_PSA_RANGE),
        "sd": table(check.sd, bands.DEFAULT_SD_RANGE),
    }


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


def _read_scenario_text(path: Path) -> str:
    """The file's text; every way of failing to read it becomes a ScenarioError naming the file."""
    try:
        data = path.read_bytes()
    except IsADirectoryError:
        raise ScenarioError(f"{path}: is a directory, not a scenario file") from None
    except OSError as e:
        raise ScenarioError(f"{path}: cannot read the scenario file ({e.strerror or type(e).__name__})") from None
    try:
        return data.decode("utf-8-sig")  # an editor's byte-order mark is skipped
    except UnicodeDecodeError as e:
        line = data[: e.start].count(b"\n") + 1
        raise ScenarioError(
            f"{path} line {line}: not UTF-8 text (byte 0x{data[e.start]:02x} at offset {e.start}); "
            "a scenario is a UTF-8 TOML file"
        ) from None


def _resolve(name_or_path: str | Path) -> Path:
    """The file of a catalogue name or a path (a name with a path separator or a suffix is a path)."""
    text = str(name_or_path)
    p = Path(name_or_path)
    if isinstance(name_or_path, Path) or p.suffix or "/" in text or "\\" in text or p.exists():
        if p.is_dir():
            raise ScenarioError(
                f"{p}: is a directory, not a scenario file (give a .toml file or one of: {', '.join(SCENARIOS)})"
            )
        if not p.exists():
            raise ScenarioError(f"scenario file {p} does not exist")
        return p
    if text not in SCENARIOS:
        raise unknown_choice("scenario", text, SCENARIOS)
    return SCENARIOS[text]


def load_scenario(name_or_path: str | Path) -> Scenario:
    """Load and validate a scenario by catalogue name or by path to a TOML file.

    Raises
    ------
    ScenarioError
        The file cannot be read, is not UTF-8 or not TOML, or a key is unknown,
        missing or out of range; the message names the file, the key and, where
        it can be found, the line.
    ValueError
        ``name_or_path`` is neither a file nor a catalogue name (the choices are listed).
    """
    path = _resolve(name_or_path)
    text = _read_scenario_text(path)
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        m = _TOML_LINE_RE.search(str(e))
        where = f"{path} line {m.group(1)}" if m else f"{path}"
        raise ScenarioError(f"{where}: invalid TOML: {e}") from None
    f = _File(path, text)
    _check_table(f, "", raw)
    for required in ("specimen", "motions"):
        if required not in raw:
            raise ScenarioError(f"{path}: missing table [{required}]")
    name = raw.get("name", path.stem)
    if not name.strip() or name in (".", "..") or any(c in name for c in "/\\\0"):
        raise f.error("", "name", f"'name' must be a plain name (it names the run directory runs/NAME), got {name!r}")

    specimen = read_specimen(f, raw["specimen"])
    mot = dict(raw["motions"])
    check_motions(f, mot)
    names, eng_t = read_engines(f, raw.get("engines", {}))
    src = mot["source"]
    analysis = dict(raw.get("analysis", {}))
    _check_analysis(f, analysis)
    effects = read_effects(f, raw.get("effects", []), specimen)
    scen = Scenario(
        name=name,
        description=raw.get("description", ""),
        specimen=specimen,
        motions=mot,
        engines=names,
        engine_settings=eng_t,
        analysis=analysis,
        path=path,
        raw=raw,
        raw_text=text,
        effects=effects,
    )
    if "study" in raw:
        scen.study = read_study(f, raw["study"], mot, specimen, scen.S)
    scen.check_effects()
    if src == "pulses":
        scen.pulse_grid()  # validate the grids now
    scen._read_files()  # record files: read now, so that a bad one fails before any work
    return scen
