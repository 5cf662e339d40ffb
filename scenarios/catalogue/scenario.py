"""The scenario catalogue: declarative TOML files in this folder, read and validated here.

A scenario names a specimen, a motion source (an RDK ensemble fitted to a
record, a record, a suite of records, pulses on a grid, free-vibration
releases), the engines to run and what to analyse. Everything a run produces
follows from the file and its seed.

A record is a shipped one (:data:`housner.scenarios.motions.records.RECORDS`) or a user's
``.AT2`` / ``.csv`` file, its path relative to the scenario file's folder;
record files are read, and refused with a one-line error, when the scenario
is loaded. A record path must resolve (symbolic links and ``..`` followed)
inside the scenario file's folder, unless ``load_scenario(...,
allow_outside=True)``; a record needs at least 16 samples, as a campaign's does
(:data:`housner.readers.measured_data.MIN_RECORD_SAMPLES`).
"""

from __future__ import annotations

import difflib
import inspect
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from housner.engines.base import ENGINES, engine_class
from housner.errors import one_line, unknown_choice
from housner.motion import GroundMotion
from housner.readers.measured_data import require_samples
from housner.specimen import Specimen

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from housner.scenarios.catalogue.schema import (
    TOML_LINE_RE,
    ScenarioError,
    ScenarioFile,
    check_analysis,
    check_motions,
    check_table,
    is_path,
    parse_grid,
    read_effects,
    read_engines,
    read_plugins,
    read_specimen,
    table_line,
)
from housner.scenarios.catalogue.study_table import read_study
from housner.scenarios.motions.records import RECORD_SUFFIXES, RECORDS, file_sha256, read_record_file

__all__ = ["SCENARIOS", "Scenario", "list_scenarios", "load_scenario"]

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
    #: Read record files that resolve outside the scenario file's folder (load_scenario's opt-out).
    allow_outside: bool = field(default=False, repr=False)
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
            return len(self.record_files()["records"])
        if src == "free_vibration":
            return len(self.motions["theta0_over_alpha"])
        return len(self.pulse_grid()[0])

    def pulse_grid(self) -> tuple[np.ndarray, np.ndarray]:
        """Flattened (omega_p/p, a_p/(g tan alpha)) pairs of a pulse scenario, row-major in omega."""
        text = self.raw_text
        w = parse_grid(self.path, "omega_ratio", self.motions["omega_ratio"], text)
        a = parse_grid(self.path, "accel_ratio", self.motions["accel_ratio"], text)
        W, A = np.meshgrid(w, a, indexing="ij")
        return W.ravel(), A.ravel()

    # ------------------------------------------------------------------ records
    def error(self, key: str | None, message: str) -> ScenarioError:
        """A one-line error about the [motions] table's ``key``, naming this scenario's file and the key's line."""
        return ScenarioFile(self.path or Path(f"scenario {self.name!r}"), self.raw_text).error("motions", key, message)

    def _record_path(self, written: str) -> Path:
        """A record path as written in the file: relative to the scenario file's folder, or absolute."""
        p = Path(written)
        if p.is_absolute():
            return p
        return (self.path.parent if self.path is not None else Path.cwd()) / p

    def _check_inside(self, key: str, written: str, path: Path) -> None:
        """Refuse a record path that resolves (links and ``..`` followed) outside the scenario file's folder."""
        if self.allow_outside:
            return
        folder = (self.path.parent if self.path is not None else Path.cwd()).resolve()
        try:
            if path.resolve().is_relative_to(folder):
                return
            why = f"resolves outside the scenario folder {folder}"
        except (OSError, RuntimeError):  # a loop of symbolic links (RuntimeError before Python 3.13)
            why = "cannot be resolved (a loop of symbolic links?)"
        raise self.error(
            key,
            f"[motions] {key!r} names {written!r}: it {why} (records must lie inside it: keep the scenario file "
            "in a folder above its records, pass --allow-outside to housner run, or "
            "load_scenario(..., allow_outside=True) in Python)",
        )

    def _read_file(self, key: str, written: str) -> tuple[GroundMotion, dict]:
        """One record file, and its facts for the metadata; any failure is one ScenarioError naming key and path."""
        path = self._record_path(written)
        self._check_inside(key, written, path)
        what = f"[motions] {key!r} names {written!r}"
        if path.suffix.lower() in RECORD_SUFFIXES and not path.exists():
            hint = f"; shipped records: {', '.join(RECORDS)}" if key == "record" else ""
            raise self.error(key, f"{what}: no such file {path} (relative paths start at the scenario's folder{hint})")
        if key == "record" and path.is_dir():
            raise self.error(
                key,
                f"{what}: {path} is a folder; 'record' names one file (a folder of records is "
                'source = "records" with records = "FOLDER")',
            )
        try:
            motion = read_record_file(path, units=self.motions.get("units"))
            require_samples(path, motion.n)  # the rule of every reader of records (campaigns too)
            sha = file_sha256(path)
        except (OSError, ValueError) as e:
            raise self.error(key, f"{what}: {one_line(e)}") from None
        facts = {
            "name": motion.name,
            "provenance": f"{motion.provenance}; file {path.resolve()} (sha256 {sha[:16]})",
            "dt": motion.dt,
            "n": motion.n,
            "file": written,
            "path": str(path.resolve()),
            "sha256": sha,
        }
        if motion.channels:
            facts["channels"] = sorted(motion.channels)
        return replace(motion, provenance=facts["provenance"]), facts

    def _suite_files(self) -> list[str]:
        """The files of ``records`` (a folder: its .AT2 and .csv files sorted by name; or a list), as written."""
        spec = self.motions["records"]
        if isinstance(spec, str):
            folder = self._record_path(spec)
            self._check_inside("records", spec, folder)
            what = f"[motions] 'records' names folder {spec!r}"
            if not folder.exists():
                raise self.error(
                    "records", f"{what}: no such folder {folder} (relative paths start at the scenario's folder)"
                )
            if not folder.is_dir():
                raise self.error("records", f"{what}: {folder} is a file; give a folder or a list of files")
            try:
                names = sorted(p.name for p in folder.iterdir() if p.suffix.lower() in RECORD_SUFFIXES and p.is_file())
            except OSError as e:
                raise self.error("records", f"{what}: cannot list {folder} ({e.strerror or e})") from None
            if not names:
                raise self.error("records", f"{what}: {folder} holds no .AT2 or .csv file")
            return [str(Path(spec) / name) for name in names]
        if not spec:
            raise self.error("records", "[motions] 'records' is an empty list; name at least one .AT2 or .csv file")
        for v in spec:
            if not isinstance(v, str):
                raise self.error("records", f"[motions] 'records' must hold file paths (strings), got {v!r}")
        return list(spec)

    def record_files(self) -> dict:
        """The record files of the [motions] table, read once: ``{"record" | "records": [(motion, facts), ...]}``.

        :func:`load_scenario` reads them, so that a bad one fails before any work.
        """
        if self._files is not None:
            return self._files
        files: dict[str, list] = {}
        src, m = self.source, self.motions
        if src in ("rdk", "record") and is_path(m.get("record", "elcentro")):
            files["record"] = [self._read_file("record", m["record"])]
        elif src == "records":
            written = self._suite_files()
            seen: dict[str, str] = {}
            for w in written:  # names are checked before the files are read
                stem = Path(w).stem
                if stem in seen:
                    raise self.error(
                        "records",
                        f"[motions] 'records': {seen[stem]!r} and {w!r} would both be motion {stem!r}; "
                        "every record needs a name (file stem) of its own",
                    )
                seen[stem] = w
            files["records"] = [self._read_file("records", w) for w in written]
        self._files = files
        return files

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
        where = f"{self.path}" if self.path else f"scenario {self.name!r}"
        for name in names if names is not None else self.engines:
            if name not in ENGINES:
                raise ValueError(f"{unknown_choice('engine', name, ENGINES)}")
            settings = self.engine_settings.get(name, {})
            line = table_line(self.raw_text, f"engines.{name}") if settings else None
            at = f"{where} line {line}" if line is not None else where
            cls = engine_class(name)
            try:
                cls(**settings)
            except (TypeError, ValueError) as e:
                msg = str(e)
                if isinstance(e, TypeError) and "unexpected keyword argument" in msg:
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

    def check_channels(self) -> None:
        """Refuse, by name, an effect that reads a motion channel (``ground_acc_vertical``) the motions lack.

        Only record files carry channels (extra ``ground_acc_<what>`` columns of a CSV); RDK ensembles,
        pulses and free vibrations carry none.
        """
        files = self.record_files()
        suite = files.get("records") or files.get("record") or []
        own = [(g.name, set(g.channels)) for g, _ in suite] if self.source in ("record", "records") else []
        for e in self.effects:
            for ch in e.channels:
                if not own:
                    raise self.error(
                        "source",
                        f"[[effects]] effect {e.name!r} reads the channel {ch!r}, which motions of source "
                        f"{self.source!r} do not carry (a record CSV with a {ch!r} column does)",
                    )
                lacking = next((name for name, chs in own if ch not in chs), None)
                if lacking is not None:
                    raise self.error(
                        "records" if self.source == "records" else "record",
                        f"[[effects]] effect {e.name!r} reads the channel {ch!r}, which record {lacking!r} "
                        f"does not carry (a CSV column {ch} [m/s^2])",
                    )

    def describe(self) -> dict:
        """The scenario as plain data (for run.json and the cache key)."""
        return {"name": self.name, "file": str(self.path) if self.path else None, **self.raw}


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


def load_scenario(name_or_path: str | Path, *, allow_outside: bool = False) -> Scenario:
    """Load and validate a scenario by catalogue name or by path to a TOML file.

    Parameters
    ----------
    name_or_path : str or pathlib.Path
        A catalogue name (:data:`SCENARIOS`) or a TOML file.
    allow_outside : bool
        Read record files that resolve outside the scenario file's folder (default False: refused
        with one line naming the key, the path and the folder).

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
        m = TOML_LINE_RE.search(str(e))
        where = f"{path} line {m.group(1)}" if m else f"{path}"
        raise ScenarioError(f"{where}: invalid TOML: {e}") from None
    f = ScenarioFile(path, text)
    check_table(f, "", raw)
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
    check_analysis(f, analysis)
    read_plugins(f, raw.get("plugins", []))  # before [[effects]]: they may name the plugins' effects
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
        allow_outside=allow_outside,
    )
    if "study" in raw:
        scen.study = read_study(f, raw["study"], mot, specimen, scen.S)
    scen.check_effects()
    if src == "pulses":
        scen.pulse_grid()  # validate the grids now
    scen.record_files()  # record files: read now, so that a bad one fails before any work
    scen.check_channels()
    return scen
