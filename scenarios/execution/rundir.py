"""The run directory: its files, the results columns, run.json's encoding, writing and reading it, provenance.

The one owner of the format: :func:`write_run` writes ``results.parquet`` (the columns of
:data:`RESULT_COLUMNS`, and :data:`CAMPAIGN_COLUMNS` for a campaign's run), ``histories.parquet``,
``motions.npz`` and ``run.json`` (the run's :class:`RunMeta`, non-finite floats as strings,
:func:`jsonable`; the manifest of :data:`DATA_FILES`), and :func:`load_results`, :func:`read_motions` and
:func:`read_histories` read them (for :mod:`housner.reports.run.page` and
:mod:`housner.reports.assertions.runs`). A run counts only once it is written completely: an incomplete or
mixed directory is refused (:class:`IncompleteRunError`), a run.json from before the marker read with an
:class:`UnverifiedRunWarning`. The files, their columns and how a run is written are in
``docs/reference/run-directory.md``.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import platform
import shutil
import subprocess
import tempfile
import time
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

import housner
from housner._values import JsonValue, json_number, plain, read_as
from housner.errors import DataFileError
from housner.motion import GroundMotion
from housner.scenarios.execution.tables import REQUIRED_COLUMNS

if TYPE_CHECKING:
    from housner.scenarios.motions.build import MotionFacts
    from housner.scenarios.runs.campaign_run import CampaignFacts
    from housner.scenarios.runs.chaos import EngineErrors
    from housner.scenarios.runs.spread import Table2Spread

RESULT_COLUMNS = [
    "engine",
    "motion_id",
    "motion_name",
    "theta_max_over_alpha",
    "overturned",
    "n_impacts",
    "wall_s",
    "status",
    "error",
    "cached",
    "effects",
]

#: The columns a campaign's run adds after :data:`RESULT_COLUMNS` (:mod:`housner.scenarios.runs.campaign_run`).
CAMPAIGN_COLUMNS = ["record_id", "observed_overturned"]

#: Files a run writes into its directory (``report.html`` is written by the CLI after it).
RUN_FILES = ("results.parquet", "histories.parquet", "motions.npz", "run.json", "report.html")
RESULTS_FILE, HISTORIES_FILE, MOTIONS_FILE, RUN_FILE, REPORT_FILE = RUN_FILES
#: The files run.json's content key covers (those written before it).
DATA_FILES = (RESULTS_FILE, HISTORIES_FILE, MOTIONS_FILE)
#: Prefix of the temporary folder a run is written into, inside its directory.
_TMP_PREFIX = ".housner-run-"


class IncompleteRunError(DataFileError):
    """A run directory whose writing did not finish, or whose files are not those its run.json was written with.

    Attributes
    ----------
    path : pathlib.Path
        The run directory.
    file : str
        The file that does not match (``run.json`` when the run is marked incomplete).
    """

    def __init__(self, run_dir: str | Path, file: str, why: str):
        self.path, self.file, self.line, self.column = Path(run_dir), file, None, None
        ValueError.__init__(self, f"run directory {self.path} is incomplete or mixes two runs: {why}; run again")


class UnverifiedRunWarning(UserWarning):
    """A run directory written before run.json carried its completion marker: read, but not checked."""


@dataclass(frozen=True, eq=False)
class ScenarioCopy(JsonValue):
    """The scenario as run, as run.json and study.json keep it (``Scenario.describe()``): its file's own tables.

    A copy of the user's TOML file (name and path first, then its tables in the file's order), kept as the table
    it is; what the reports and the verdicts read of it has a property.

    Attributes
    ----------
    table : dict
        ``name``, ``file`` (the scenario file's path, None for one built in code), then the file's tables
        (``description``, ``specimen``, ``motions``, ``engines``, ``analysis``, ...).
    """

    table: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        return dict(self.table)

    @classmethod
    def from_json(cls, data: Any) -> ScenarioCopy:
        if isinstance(data, ScenarioCopy):
            return data
        return cls(dict(data) if isinstance(data, dict) else {})

    @property
    def name(self) -> str:
        """The scenario's name ("" when not stated)."""
        return str(self.table.get("name") or "")

    @property
    def description(self) -> str:
        """Its description ("" when not stated)."""
        return str(self.table.get("description") or "")

    @property
    def file(self) -> str | None:
        """The scenario file it was read from (None: built in code, or not stated)."""
        f = self.table.get("file")
        return str(f) if f else None

    @property
    def motion_table(self) -> dict:
        """Its [motions] table as written (empty when absent)."""
        m = self.table.get("motions")
        return m if isinstance(m, dict) else {}

    @property
    def amplitude(self) -> float:
        """The [motions] amplitude factor on the motions [-] (1 when not stated)."""
        return json_number(self.motion_table.get("amplitude", 1.0))

    @property
    def record(self) -> str | None:
        """The record the [motions] table names (None when it names none)."""
        r = self.motion_table.get("record")
        return str(r) if r else None


@dataclass(frozen=True, eq=False)
class SpecimenFacts(JsonValue):
    """The specimen's geometry and derived figures (``Specimen.describe()``), SI units named in the fields.

    A field the file does not hold is None (and left out when the value is written again).
    """

    name: str | None = None
    height_m: float | None = None
    width_m: float | None = None
    depth_m: float | None = None
    mass_kg: float | None = None
    I0_kgm2: float | None = None
    alpha_rad: float | None = None
    R_m: float | None = None
    p_1_s: float | None = None
    r_housner: float | None = None
    extra: dict = field(default_factory=dict)


@dataclass(frozen=True, eq=False)
class Provenance(JsonValue):
    """Where and with what a run or study was computed (:func:`provenance`).

    Attributes
    ----------
    versions : dict
        Package -> version (``housner``, ``python``, ``numpy``, the engines' packages).
    git_commit, platform : str or None
    cpus : int or None
    created : str or None
        The creation time (ISO 8601).
    """

    versions: dict[str, str] | None = None
    git_commit: str | None = None
    platform: str | None = None
    cpus: int | None = None
    created: str | None = None
    extra: dict = field(default_factory=dict)

    @classmethod
    def current(cls) -> Provenance:
        """This process's provenance, now."""
        return cls.from_json(provenance())


@dataclass(frozen=True, eq=False)
class EffectData(JsonValue):
    """An effect as plain data: its registry name and parameter values (written flat: ``{"name", **params}``)."""

    name: str
    params: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        return {"name": self.name, **self.params}

    @classmethod
    def from_json(cls, data: Any) -> EffectData:
        if isinstance(data, EffectData):
            return data
        d = dict(data) if isinstance(data, dict) else {}
        return cls(str(d.pop("name", "")), d)

    @classmethod
    def of(cls, effect: Any) -> EffectData:
        """The data of an effect object (:func:`effect_data`)."""
        return cls.from_json(effect_data(effect))


@dataclass(frozen=True, eq=False)
class EffectsFacts(JsonValue):
    """A set of effects in one label (e.g. ``restitution(r=0.95)``) and each effect's data."""

    label: str = ""
    effects: tuple[EffectData, ...] = ()


@dataclass(frozen=True, eq=False)
class EngineFacts(JsonValue):
    """One engine's (or one series') facts of a run or a study (the runner's, :func:`run_engines`).

    Attributes
    ----------
    settings : dict
        The settings it ran with (None: the engine's default).
    version : str or None
        Its package's version.
    wall_s : float or None
        Engine time summed over the records computed [s].
    cached, cache_rejected, worker_deaths, kernel_cache_repairs : int or None
        Records taken from the cache, cache entries refused, worker processes that died, damaged kernel-cache
        entries rebuilt.
    elapsed_s : float or None
        Wall time of the runner's call [s].
    engine : str or None
        For a series with the scenario's [[effects]]: the engine without them.
    effects : tuple of EffectData or None
        For such a series: its effects.
    """

    settings: dict = field(default_factory=dict)
    version: str | None = None
    wall_s: float | None = None
    cached: int | None = None
    cache_rejected: int | None = None
    worker_deaths: int | None = None
    kernel_cache_repairs: int | None = None
    elapsed_s: float | None = None
    engine: str | None = None
    effects: tuple[EffectData, ...] | None = None
    extra: dict = field(default_factory=dict)

    @classmethod
    def from_json(cls, data: Any) -> EngineFacts:
        out = super().from_json(data)
        return out if isinstance(out.settings, dict) else replace(out, settings={})


@dataclass(frozen=True, eq=False)
class FailedRecord(JsonValue):
    """A record an engine failed on: ``engine``, ``motion_id``, ``motion_name`` and the ``error``."""

    engine: str = ""
    motion_id: int = 0
    motion_name: str = ""
    error: str = ""


@dataclass(frozen=True, eq=False)
class RunAnalysis(JsonValue):
    """The scenario's [analysis] table as run.json keeps it.

    Attributes
    ----------
    reference : str or None
        The reference engine (None: the analytic model).
    paper_percentiles : dict or None
        Percentile [%] (as written, e.g. ``"25"``) -> the seed paper's theta_max/alpha there, a number or
        ``"overturn"``.
    paper_note : str or None
        What the suite cannot reproduce of the paper's study.
    seed_spread : int or None
        Independent ensembles of the Table 2 spread.
    """

    reference: str | None = None
    paper_percentiles: dict[str, float | str] | None = None
    paper_note: str | None = None
    seed_spread: int | None = None
    extra: dict = field(default_factory=dict)

    @property
    def paper_targets(self) -> dict[float, float]:
        """Percentile [%] -> the paper's theta_max/alpha [-] (inf: overturn), the numbers only (empty: none)."""
        out = {float(k): json_number(v) for k, v in (self.paper_percentiles or {}).items()}
        return {q: v for q, v in out.items() if not math.isnan(v)}


@dataclass(frozen=True, eq=False)
class RunMeta(JsonValue):
    """A run's metadata: what run.json holds besides its completion marker, one field per key.

    :func:`write_run` writes it (:meth:`to_json`, the keys in the order of the fields) and
    :meth:`from_json` reads it back from run.json, that of an earlier version too: a key it
    lacks takes its field's default (an empty value, or None), a key this version does not
    know is kept in ``extra``. Every table is a value of its own (its fields the table's keys);
    a non-finite number read back is a float (run.json writes it "inf", "-inf" or "nan").

    Attributes
    ----------
    scenario : ScenarioCopy
        The scenario as run (``Scenario.describe()``): ``name``, ``description``, ``file``,
        ``motions`` (its [motions] table), ...
    specimen : SpecimenFacts
        The specimen's geometry and derived figures (``Specimen.describe()``), SI units
        named in the fields (``height_m``, ``alpha_rad``, ``p_1_s``, ...).
    motions : MotionFacts
        Facts of the ground motions (``build_motions``): ``source``, the size ratio ``S``,
        ``seed``, the record's facts, the fitted model, the band check, ...
    n_motions : int or None
        Motions of the run (None: not stated, as in a table written by another tool).
    engines : dict of EngineFacts
        Series name -> its engine's facts: ``settings``, ``version``, ``wall_s`` [s],
        ``cached``, and for a series with the scenario's [[effects]] ``engine`` and ``effects``.
    analysis : RunAnalysis
        The scenario's [analysis] table (``reference``, ``paper_percentiles``, ...).
    failures : tuple of FailedRecord
        The failed records: ``engine``, ``motion_id``, ``motion_name``, ``error``.
    engine_errors : dict of EngineErrors
        Engine -> its measured free-rocking r and p errors (:mod:`housner.scenarios.runs.chaos`).
    wall_s : dict
        Wall times [s] of the run's parts (``motions``, ``total``).
    provenance : Provenance
        Versions, git commit, platform, CPUs and the creation time (:func:`provenance`).
    table2_spread : Table2Spread or None
        The spread of Table 2 over independent ensembles (``seed_spread``), when measured.
    effects : EffectsFacts or None
        The scenario's [[effects]]: ``label`` and each effect's data, when it lists any.
    campaign : CampaignFacts or None
        Set when the run is a measured campaign's (``housner run CAMPAIGN``,
        :mod:`housner.scenarios.runs.campaign_run`): its ``name`` and ``path``, its records (``n_records``,
        ``n_outcomes``, ``n_overturned``, ``skipped``), the planar engines' ``geometry`` effects (``label``,
        ``effects``), the 3D engines' ``mesh`` settings and the ``scan``'s pivots; None for a scenario's run.
    complete : bool or None
        run.json's completion marker as read (None: not read from a file, or an earlier
        version's run.json without one); :func:`write_run` writes its own.
    content : dict or None
        run.json's content key as read (size and SHA-256 of each data file).
    extra : dict
        Keys of run.json this version does not know, as read.
    """

    scenario: ScenarioCopy = field(default_factory=ScenarioCopy)
    specimen: SpecimenFacts = field(default_factory=SpecimenFacts)
    motions: MotionFacts = field(default_factory=lambda: _motion_facts()())
    n_motions: int | None = None
    engines: dict[str, EngineFacts] = field(default_factory=dict)
    analysis: RunAnalysis = field(default_factory=RunAnalysis)
    failures: tuple[FailedRecord, ...] = ()
    engine_errors: dict[str, EngineErrors] = field(default_factory=dict)
    wall_s: dict = field(default_factory=dict)
    provenance: Provenance = field(default_factory=Provenance)
    table2_spread: Table2Spread | None = None
    effects: EffectsFacts | None = None
    campaign: CampaignFacts | None = None
    complete: bool | None = None
    content: dict | None = None
    extra: dict = field(default_factory=dict)

    #: Keys written whatever their value, in this order; then the optional ones, when set.
    _ALWAYS = (
        "scenario",
        "specimen",
        "motions",
        "n_motions",
        "engines",
        "analysis",
        "failures",
        "engine_errors",
        "wall_s",
        "provenance",
    )
    _OPTIONAL = ("table2_spread", "effects", "campaign", "complete", "content")
    _MARKERS = 2  # the last optional keys: the completion marker and the content key, written last

    @classmethod
    def from_json(cls, data: Any) -> RunMeta:
        """The metadata of a run.json's contents (a missing or null table becomes an empty one)."""
        from housner.scenarios.runs.campaign_run import CampaignFacts
        from housner.scenarios.runs.chaos import EngineErrors
        from housner.scenarios.runs.spread import Table2Spread

        if isinstance(data, RunMeta):
            return data
        data = data if isinstance(data, dict) else {}

        def table(key: str) -> dict:
            v = data.get(key)
            return v if isinstance(v, dict) else {}

        def optional(key: str, kind):
            v = data.get(key)
            return None if v is None else kind.from_json(v)

        failures = data.get("failures")
        n = data.get("n_motions")
        return cls(
            scenario=ScenarioCopy.from_json(table("scenario")),
            specimen=SpecimenFacts.from_json(table("specimen")),
            motions=_motion_facts().from_json(table("motions")),
            n_motions=None if n is None else read_as(int, n),
            engines={str(k): EngineFacts.from_json(v) for k, v in table("engines").items()},
            analysis=RunAnalysis.from_json(table("analysis")),
            failures=tuple(FailedRecord.from_json(r) for r in failures) if isinstance(failures, list) else (),
            engine_errors={str(k): EngineErrors.from_json(v) for k, v in table("engine_errors").items()},
            wall_s=table("wall_s"),
            provenance=Provenance.from_json(table("provenance")),
            table2_spread=optional("table2_spread", Table2Spread),
            effects=optional("effects", EffectsFacts),
            campaign=optional("campaign", CampaignFacts),
            complete=data.get("complete"),
            content=data.get("content"),
            extra={k: v for k, v in data.items() if k not in cls._ALWAYS and k not in cls._OPTIONAL},
        )

    def to_json(self) -> dict:
        """run.json's keys and values, in its order: the fields, then ``extra`` (n_motions and the optional ones only
        when set)."""
        out = {k: plain(getattr(self, k)) for k in self._ALWAYS if not (k == "n_motions" and self.n_motions is None)}
        data, markers = self._OPTIONAL[: -self._MARKERS], self._OPTIONAL[-self._MARKERS :]
        out.update({k: plain(getattr(self, k)) for k in data if getattr(self, k) is not None})
        out.update(self.extra)
        out.update({k: getattr(self, k) for k in markers if getattr(self, k) is not None})
        return out

    @property
    def reference(self) -> str:
        """The reference engine the scenario asks for (``[analysis] reference``, default the analytic model)."""
        return self.analysis.reference or "housner"

    def engine(self, name: str) -> EngineFacts:
        """The facts of series ``name`` (empty when the run has none)."""
        return self.engines.get(name) or EngineFacts()

    def engine_settings(self, name: str) -> dict:
        """The settings series ``name`` ran with (empty when not recorded)."""
        return self.engine(name).settings or {}

    @property
    def effect_series(self) -> dict[str, str]:
        """Series that are an engine with the scenario's [[effects]]: series -> the engine without them."""
        return {n: str(v.engine) for n, v in self.engines.items() if v.effects and v.engine is not None}

    @property
    def is_campaign(self) -> bool:
        """Whether the run is a measured campaign's (``housner run CAMPAIGN``), not a scenario's."""
        return self.campaign is not None

    @property
    def effects_label(self) -> str:
        """The scenario's [[effects]] in one label, e.g. ``restitution(r=0.95)`` ("" without effects)."""
        return self.effects.label if self.effects is not None else ""


def _motion_facts():
    """:class:`housner.scenarios.motions.build.MotionFacts` (imported when first needed: the motions' builder
    loads the ground-motion models)."""
    from housner.scenarios.motions.build import MotionFacts

    return MotionFacts


def jsonable(x: Any, *, nonfinite: str = "string") -> Any:
    """``x`` as plain JSON data, recursively: numpy scalars and arrays, paths, tuples made plain.

    Non-finite floats, which strict JSON cannot hold, become the strings "inf", "-inf" and "nan"
    (``nonfinite="string"``, run.json: :func:`housner.reports.run.page` reads them back as numbers) or null
    (``nonfinite="null"``, diagnosis.json: "no value").
    """
    if nonfinite not in ("string", "null"):
        raise ValueError(f"`nonfinite` must be 'string' or 'null', got {nonfinite!r}")
    if isinstance(x, dict):
        return {str(k): jsonable(v, nonfinite=nonfinite) for k, v in x.items()}
    if isinstance(x, (list, tuple, np.ndarray)):
        return [jsonable(v, nonfinite=nonfinite) for v in x]
    if isinstance(x, (np.bool_, bool)):
        return bool(x)
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if math.isfinite(v) else (str(v) if nonfinite == "string" else None)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, Path):
        return str(x)
    return x


def effect_data(effect: Any) -> dict:
    """An effect as plain data: its registry name and parameter values (for cache keys and run.json)."""
    return {"name": effect.name, **{k: getattr(effect, k) for k in type(effect).param_specs}}


def _git_commit() -> str:
    try:
        return subprocess.run(
            ["git", "rev-parse", "HEAD"],
            cwd=Path(__file__).parent,
            capture_output=True,
            text=True,
            timeout=5,
        ).stdout.strip()
    except Exception:
        return ""


def provenance() -> dict:
    """Versions of the suite, Python and the engines' packages, and the git commit."""
    versions = {"housner": housner.__version__, "python": platform.python_version(), "numpy": np.__version__}
    for mod in ("mujoco", "pybullet", "scipy", "numba", "pandas"):
        try:
            from importlib.metadata import version

            versions[mod] = version(mod)
        except Exception:
            pass
    return {
        "versions": versions,
        "git_commit": _git_commit(),
        "platform": platform.platform(),
        "cpus": os.cpu_count(),
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    }


def write_run(
    out: Path,
    results: pd.DataFrame,
    histories: dict[tuple[str, int], np.ndarray],
    motions: list[GroundMotion],
    meta: RunMeta,
) -> None:
    """Write results.parquet, histories.parquet, motions.npz and run.json into ``out``, as one run.

    The files are written into a temporary folder inside ``out`` and moved into place, run.json
    last, with its completion marker and content key (docs/reference/run-directory.md); while they move, run.json
    says the directory is incomplete. A previous run's files that this run does not write
    (histories.parquet when there are none, the previous report.html) are removed with it, when
    the run.json there is housner's; files of those names that no run wrote are left, and the
    readers refuse the directory while they lie there. ``meta`` is the run's :class:`RunMeta`
    (its own ``complete`` and ``content`` are not written: these are the write's).
    """
    out.mkdir(parents=True, exist_ok=True)
    _remove_stale_temporaries(out)
    tmp = Path(tempfile.mkdtemp(prefix=f"{_TMP_PREFIX}{os.getpid()}-", dir=out))
    try:
        _write_files(tmp, results, histories, motions)
        content = {name: _digest(tmp / name) for name in DATA_FILES if (tmp / name).is_file()}
        manifest = jsonable(replace(meta, complete=None, content=None).to_json())
        (tmp / RUN_FILE).write_text(json.dumps({**manifest, "complete": True, "content": content}, indent=2))
        previous_ours = _is_ours(out / RUN_FILE)
        # from here on the directory says it is incomplete until run.json is moved in, last
        _replace_text(out / RUN_FILE, json.dumps({**manifest, "complete": False}, indent=2))
        for name in DATA_FILES:
            if name in content:
                os.replace(tmp / name, out / name)
        # the previous run's files this one does not replace (a user's own are left, and the readers refuse
        # the directory while they lie there: nothing is deleted without a word)
        for name in (n for n in (*DATA_FILES, REPORT_FILE) if n not in content):
            if previous_ours and (out / name).is_file():
                (out / name).unlink()
        os.replace(tmp / RUN_FILE, out / RUN_FILE)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _write_files(d: Path, results: pd.DataFrame, histories: dict, motions: list[GroundMotion]) -> None:
    """results.parquet, histories.parquet (when there are histories) and motions.npz, into folder ``d``."""
    results.to_parquet(d / RESULTS_FILE, index=False)
    parts = []
    for (name, i), theta in histories.items():
        n = len(theta)
        parts.append(
            pd.DataFrame(
                {
                    "engine": pd.Categorical([name] * n),
                    "motion_id": np.full(n, i, dtype=np.int32),
                    "t": (np.arange(n) * motions[i].dt).astype(np.float32),
                    "theta": theta,
                }
            )
        )
    if parts:
        pd.concat(parts, ignore_index=True).to_parquet(d / HISTORIES_FILE, index=False)
    lengths = np.array([m.n for m in motions])
    acc = np.zeros((len(motions), int(lengths.max()) if len(motions) else 0), dtype=np.float32)
    for i, m in enumerate(motions):
        acc[i, : m.n] = m.acc
    np.savez_compressed(
        d / MOTIONS_FILE,
        acc=acc,
        n=lengths,
        dt=np.array([m.dt for m in motions]),
        theta0=np.array([m.theta0 for m in motions]),
        names=np.array([m.name for m in motions]),
    )


def _digest(path: Path) -> dict:
    """A file's content key: its size [bytes] and SHA-256."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return {"bytes": path.stat().st_size, "sha256": h.hexdigest()}


def _replace_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (a temporary file beside it, then os.replace)."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _is_ours(path: Path) -> bool:
    """Whether ``path`` is a run.json housner wrote (a JSON object with housner's provenance)."""
    try:
        data = json.loads(path.read_bytes()) if path.is_file() else None
    except (OSError, ValueError):
        return False
    prov = data.get("provenance") if isinstance(data, dict) else None
    return isinstance(prov, dict) and isinstance(prov.get("versions"), dict) and "housner" in prov["versions"]


def _remove_stale_temporaries(out: Path) -> None:
    """Remove the temporary folders of runs killed while writing into ``out`` (their process is gone)."""
    for d in out.glob(f"{_TMP_PREFIX}*"):
        try:
            pid = int(d.name[len(_TMP_PREFIX) :].split("-", 1)[0])
            os.kill(pid, 0)  # raises when no such process
        except ProcessLookupError:
            shutil.rmtree(d, ignore_errors=True)
        except (ValueError, OSError):
            continue  # not ours to judge: a name of another form, or another user's live process


def check_run(run_dir: Path, meta: dict) -> None:
    """Refuse a run directory that is not one complete run (:class:`IncompleteRunError`).

    ``meta`` is its run.json. A run.json marked complete must list, with their size and SHA-256,
    exactly the files of :data:`DATA_FILES` present; one marked incomplete is refused; one
    without the marker (an earlier version's) is accepted with an :class:`UnverifiedRunWarning`.
    """
    if "complete" not in meta:
        if _is_ours(run_dir / RUN_FILE):
            warnings.warn(
                f"run directory {run_dir} was written before runs carried a completion marker: read as it is, "
                "not checked to hold one run's files (run it again to have it checked)",
                UnverifiedRunWarning,
                stacklevel=3,
            )
        return
    if meta.get("complete") is not True:
        raise IncompleteRunError(run_dir, RUN_FILE, "its writing did not finish (run.json is marked incomplete)")
    content = meta.get("content")
    if not isinstance(content, dict):
        raise IncompleteRunError(run_dir, RUN_FILE, "run.json has no content key")
    for name in DATA_FILES:
        path, want = run_dir / name, content.get(name)
        if want is None:
            if path.exists():
                raise IncompleteRunError(run_dir, name, f"{name} is not listed in run.json")
            continue
        if not path.is_file():
            raise IncompleteRunError(run_dir, name, f"{name} is missing")
        ok = isinstance(want, dict) and path.stat().st_size == want.get("bytes") and _digest(path) == want
        if not ok:
            raise IncompleteRunError(run_dir, name, f"{name} does not match run.json")


# ----------------------------------------------------------------------------
# reading
def load_results(path: str | Path) -> pd.DataFrame:
    """Read a results table from a run directory, a ``results.parquet`` or a CSV file.

    Parameters
    ----------
    path : str or pathlib.Path
        A run directory holding ``results.parquet`` (and ``run.json``), or the
        table itself (``.parquet`` or ``.csv``).

    Returns
    -------
    pandas.DataFrame
        One row per engine and motion. ``df.attrs["source"]`` holds the
        resolved path of the table and ``df.attrs["run"]`` the contents of
        ``run.json`` next to it (an empty dict if there is none).

    Raises
    ------
    IncompleteRunError
        The table is a run directory's whose writing did not finish, or whose files are not
        those its run.json was written with (:func:`check_run`).
    housner.errors.DataFileError
        When the path does not exist, cannot be read, or lacks a column of
        :data:`housner.scenarios.execution.tables.REQUIRED_COLUMNS` (the message names the file and the column).
    """
    path = Path(path).expanduser()
    if path.is_dir():
        table = path / RESULTS_FILE
        if not table.is_file():
            raise DataFileError(
                path, f"no {RESULTS_FILE} in this directory; is it a run directory? (`housner run SCENARIO --out DIR`)"
            )
        path = table
    elif not path.exists():
        raise DataFileError(path, f"no such file or directory (expected a run directory or a {RESULTS_FILE})")
    path = path.resolve()
    # a run directory's table counts only as part of one complete run: checked before it is read
    meta = read_run_json(path.parent / RUN_FILE)
    if isinstance(meta, dict) and meta and path.name == RESULTS_FILE:
        check_run(path.parent, meta)
    suffix = path.suffix.lower()
    try:
        df = pd.read_csv(path) if suffix == ".csv" else pd.read_parquet(path)
    except Exception as e:  # pyarrow and pandas raise many kinds; all mean "not a readable table"
        kind = "CSV" if suffix == ".csv" else "parquet"
        raise DataFileError(path, f"cannot read as {kind}: {e}") from None
    for col in REQUIRED_COLUMNS:
        if col not in df.columns:
            raise DataFileError(
                path,
                f"missing column `{col}` of the results table (has: {', '.join(map(str, df.columns))})",
                column=col,
            )
    df.attrs["source"] = str(path)
    df.attrs["run"] = meta
    return df


def read_run_json(path: Path) -> dict:
    """``run.json`` as a dict (empty when the file is absent); non-finite numbers stay strings."""
    if not path.is_file():
        return {}
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as e:
        raise DataFileError(path, f"invalid JSON: {e.msg} (column {e.colno})", line=e.lineno) from None
    except OSError as e:
        raise DataFileError(path, f"cannot read: {e.strerror or e}") from None


@dataclass(frozen=True, eq=False)
class StoredMotions:
    """The arrays of ``motions.npz``: one row per motion_id.

    Attributes
    ----------
    acc : numpy.ndarray
        (motions, samples) accelerations [m/s^2], zero-padded after each motion's ``n`` samples.
    n : numpy.ndarray
        Samples of each motion.
    dt : numpy.ndarray
        Step of each motion [s].
    theta0 : numpy.ndarray or None
        Initial rotation of each motion [rad] (None: not stored).
    names : numpy.ndarray or None
        Each motion's name (None: not stored).
    """

    acc: np.ndarray
    n: np.ndarray
    dt: np.ndarray
    theta0: np.ndarray | None = None
    names: np.ndarray | None = None


def read_motions(run_dir: Path) -> StoredMotions | None:
    """The arrays of ``motions.npz`` (acc [m/s^2], n, dt [s], theta0 [rad], names), None when absent."""
    f = run_dir / MOTIONS_FILE
    if not f.is_file():
        return None
    try:
        with np.load(f, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except Exception as e:
        raise DataFileError(f, f"cannot read: {e}") from None
    empty = np.zeros(0)
    return StoredMotions(
        acc=arrays.get("acc", np.zeros((0, 0))),
        n=arrays.get("n", empty),
        dt=arrays.get("dt", empty),
        theta0=arrays.get("theta0"),
        names=arrays.get("names"),
    )


def read_histories(run_dir: Path, motion_ids, dt: dict[int, float]) -> dict[tuple[str, int], tuple]:
    """(engine, motion_id) -> (t [s], theta [rad]) for the given motions (empty when not stored).

    ``dt`` maps a motion to its step [s]: the stored t is float32, so t is rebuilt from the step
    (long records stay uniform); a motion without a finite step keeps the stored t.
    """
    f = run_dir / HISTORIES_FILE
    ids = sorted({int(i) for i in motion_ids})
    if not ids or not f.is_file():
        return {}
    try:
        df = pd.read_parquet(f, filters=[("motion_id", "in", ids)])
    except Exception as e:
        raise DataFileError(f, f"cannot read: {e}") from None
    out = {}
    for (eng, mid), g in df.groupby(["engine", "motion_id"], sort=False, observed=True):
        theta = g["theta"].to_numpy(np.float64)
        step = dt.get(int(mid), math.nan)
        t = np.arange(theta.size) * step if math.isfinite(step) else g["t"].to_numpy(np.float64)
        out[(str(eng), int(mid))] = (t, theta)
    return out
