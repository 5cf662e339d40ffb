"""The metadata of a run and of a study as values: run.json's :class:`RunMeta` and the tables it shares with study.json.

Each table of run.json is a frozen value of its own, its fields the table's keys
(:class:`housner._values.JsonValue`): the scenario as run (:class:`ScenarioCopy`), the specimen
(:class:`SpecimenFacts`), each engine's facts (:class:`EngineFacts`), the [analysis] table
(:class:`RunAnalysis`), the failed records, the effects, the provenance; the motions' facts, the engines'
measured errors, the Table 2 spread and a campaign's facts are values of the modules that compute them
(:mod:`housner.scenarios.motions.build`, :mod:`housner.scenarios.runs.chaos`,
:mod:`housner.scenarios.runs.spread`, :mod:`housner.scenarios.runs.campaign_run`).
:mod:`housner.scenarios.execution.rundir` writes run.json from :meth:`RunMeta.to_json` and reads it back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

from housner._values import JsonValue, json_number, plain, read_as
from housner.scenarios.execution.rundir import effect_data, provenance

if TYPE_CHECKING:
    import pandas as pd

    from housner.scenarios.motions.build import MotionFacts
    from housner.scenarios.runs.campaign_run import CampaignFacts
    from housner.scenarios.runs.chaos import EngineErrors
    from housner.scenarios.runs.spread import Table2Spread

__all__ = [
    "EffectData",
    "EffectsFacts",
    "EngineFacts",
    "FailedRecord",
    "Provenance",
    "RunAnalysis",
    "RunMeta",
    "ScenarioCopy",
    "SpecimenFacts",
    "build_run_meta",
]


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

    @classmethod
    def of(cls, effects: Any) -> EffectsFacts:
        """The facts of a sequence of effect objects: their label and each one's data."""
        from housner.scenarios.catalogue.schema import effects_label

        return cls(effects_label(effects), tuple(EffectData.of(e) for e in effects))


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


def build_run_meta(
    *,
    scenario: dict,
    specimen: Any,
    motions: MotionFacts,
    n_motions: int,
    engines: dict[str, dict],
    analysis: dict,
    results: pd.DataFrame,
    wall_s: dict[str, float],
    engine_errors: dict[str, EngineErrors] | None = None,
    table2_spread: Table2Spread | None = None,
    effects: tuple = (),
    campaign: CampaignFacts | None = None,
) -> RunMeta:
    """The metadata of a run just computed (a scenario's or a campaign's), as :func:`write_run` writes it.

    Parameters
    ----------
    scenario : dict
        The scenario as run (``Scenario.describe()``, or a campaign's name, description and file).
    specimen : Specimen
        The specimen run (its ``describe()`` is kept).
    motions : MotionFacts
        Facts of the ground motions.
    n_motions : int
        Motions of the run.
    engines : dict
        Series name -> the runner's info on it (:func:`run_engines`), in run.json's order.
    analysis : dict
        The [analysis] table.
    results : DataFrame
        The run's rows: those whose ``status`` is not ``"ok"`` become its failed records.
    wall_s : dict
        Wall times [s] of the run's parts.
    engine_errors, table2_spread, campaign
        As in :class:`RunMeta` (none, when not given).
    effects : tuple
        The scenario's [[effects]] as effect objects (none: no ``effects`` key).

    The provenance is this process's, now.
    """
    fails = results[results["status"] != "ok"]
    return RunMeta(
        scenario=ScenarioCopy(scenario),
        specimen=SpecimenFacts.from_json(specimen.describe()),
        motions=motions,
        n_motions=n_motions,
        engines={n: EngineFacts.from_json(v) for n, v in engines.items()},
        analysis=RunAnalysis.from_json(analysis),
        failures=tuple(
            FailedRecord.from_json(r) for r in fails[["engine", "motion_id", "motion_name", "error"]].to_dict("records")
        ),
        engine_errors=engine_errors or {},
        wall_s=wall_s,
        provenance=Provenance.current(),
        table2_spread=table2_spread,
        effects=EffectsFacts.of(effects) if effects else None,
        campaign=campaign,
    )


def _motion_facts():
    """:class:`housner.scenarios.motions.build.MotionFacts` (imported when first needed: the motions' builder
    loads the ground-motion models)."""
    from housner.scenarios.motions.build import MotionFacts

    return MotionFacts
