"""A run directory as the CLI, the report and users read it: results, run.json, motions and histories, and what
follows from them.

:class:`Run` loads the files through :mod:`housner.scenarios.execution.rundir` (the one owner of
their format, and of the run's metadata, :class:`~housner.scenarios.execution.rundir.RunMeta`) and
derives, lazily, what ``housner run``'s verdicts and the report's sections share: the reference and
the engine order, the usable and failed rows, the engine comparison
(:func:`housner.scenarios.execution.tables.compare_engines` with a fixed bootstrap seed, so that
pages are reproducible), each engine's verdict (:mod:`housner.scenarios.runs.verdicts`), the chaos
floors, the record against its ensemble, the specimen, the motions and the stored histories.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
import pandas as pd

from housner import Specimen
from housner._values import json_number
from housner.engines.base import engine_class
from housner.errors import DataFileError, EngineError
from housner.motion import GroundMotion
from housner.scenarios.execution.run_meta import RunMeta, SpecimenFacts
from housner.scenarios.execution.rundir import StoredMotions, load_results, read_histories, read_motions
from housner.scenarios.execution.tables import EngineSummary, compare_engines, engine_summaries, split_failed
from housner.scenarios.motions.build import MotionFacts, RecordFacts
from housner.scenarios.motions.records import RECORDS, file_sha256, read_record_file
from housner.scenarios.runs.campaign_run import (
    CampaignFacts,
    OutcomeScore,
    PublishedScore,
    outcome_table,
    published_rows,
)
from housner.scenarios.runs.chaos import RECORD_RTOL, chaos_floor
from housner.scenarios.runs.spread import EquivalentAmplitudes, RecordGap, equivalent_amplitude, record_against_ensemble
from housner.scenarios.runs.verdicts import EngineVerdict, engine_verdict

__all__ = ["BOOT_SEED", "N_BOOT", "QUARTILES", "Run", "motion_list", "source_record"]

#: Bootstrap resamples for percentile intervals (Efron and Tibshirani 1993, ch. 13, ask for at
#: least 1000 for percentile intervals) and the fixed seed that makes pages reproducible.
N_BOOT = 2000
BOOT_SEED = 0

#: Percentile levels [%] of the comparison table and the report's percentile tables.
QUARTILES = (25.0, 50.0, 75.0)


@dataclass
class Run:
    """A loaded run directory with lazily read motions and histories.

    Attributes
    ----------
    path : pathlib.Path
        The run directory.
    results : pandas.DataFrame
        Its results table, the runner's optional columns filled where another tool left them out.
    meta : RunMeta
        Its run.json (empty for a table without one).
    """

    path: Path
    results: pd.DataFrame
    meta: RunMeta

    @classmethod
    def load(cls, run_dir: str | Path) -> Run:
        """Read the run directory ``run_dir`` (:func:`housner.scenarios.execution.rundir.load_results`)."""
        path = Path(run_dir)
        if not path.is_dir():
            raise DataFileError(path, "not a directory (expected a run directory with results.parquet)")
        results = load_results(path)
        meta = RunMeta.from_json(results.attrs.get("run", {}))
        results = results.copy()
        results["engine"] = results["engine"].astype(str)
        if "motion_name" not in results.columns:
            results["motion_name"] = results["motion_id"].astype(str)
        # Tables written by other tools may lack the runner's optional columns.
        for col, default in (("wall_s", math.nan), ("cached", False), ("error", "")):
            if col not in results.columns:
                results[col] = default
        return cls(path=path, results=results, meta=meta)

    # --- derived facts
    @cached_property
    def split(self) -> tuple[pd.DataFrame, pd.DataFrame]:
        """(usable rows, failed rows) of the results table."""
        return split_failed(self.results)

    @property
    def ok(self) -> pd.DataFrame:
        """The usable rows."""
        return self.split[0]

    @property
    def failed(self) -> pd.DataFrame:
        """The failed rows."""
        return self.split[1]

    @cached_property
    def engines(self) -> list[str]:
        """Engine names, the reference first, then in the order of the results table."""
        names = list(dict.fromkeys(self.results["engine"]))
        ref = self.reference
        if ref in names:
            names.remove(ref)
            names.insert(0, ref)
        return names

    @cached_property
    def reference(self) -> str:
        """The reference engine: the one the scenario asks for, or the table's first when that one is not in it."""
        names = list(dict.fromkeys(self.results["engine"]))
        want = self.meta.reference
        if want in names:
            return want
        return names[0] if names else want

    @property
    def reference_is_requested(self) -> bool:
        """Whether the reference is the one the scenario asks for (not a stand-in)."""
        return self.meta.reference == self.reference

    @property
    def others(self) -> list[str]:
        """The engines other than the reference, in order."""
        return [e for e in self.engines if e != self.reference]

    @property
    def specimen(self) -> SpecimenFacts:
        """The specimen's facts from run.json (``Specimen.describe()``; empty when not stored)."""
        return self.meta.specimen

    @property
    def alpha(self) -> float:
        """The specimen's slenderness alpha [rad] (NaN when not stored)."""
        return json_number(self.specimen.alpha_rad)

    @property
    def motions_meta(self) -> MotionFacts:
        """The ground motions' facts from run.json."""
        return self.meta.motions

    @property
    def S(self) -> float:
        """Size ratio prototype / model of the motions (1 when not stated)."""
        S = json_number(1.0 if self.motions_meta.S is None else self.motions_meta.S)
        return S if math.isfinite(S) and S > 0 else 1.0

    @property
    def source(self) -> str:
        """Where the motions come from: ``rdk``, ``record``, ``records``, ``pulses``, ``free_vibration`` or ""."""
        return str(self.motions_meta.source or "")

    def values(self, engine: str) -> np.ndarray:
        """theta_max/alpha of the usable records of ``engine`` [-] (+inf = overturned)."""
        ok = self.ok
        return ok.loc[ok["engine"] == engine, "theta_max_over_alpha"].to_numpy(np.float64)

    def by_motion(self, engine: str) -> pd.Series:
        """theta_max/alpha of ``engine`` indexed by motion_id, NaN where failed."""
        r = self.results[self.results["engine"] == engine].set_index("motion_id")
        v = r["theta_max_over_alpha"].astype(np.float64)
        v = v.where(~r["overturned"].astype(bool), np.inf)
        return v.where(r["status"].astype(str) == "ok", np.nan)

    @property
    def campaign(self) -> CampaignFacts | None:
        """run.json's ``campaign`` table when the run is a measured campaign's (``housner run CAMPAIGN``), else None."""
        return self.meta.campaign if self.meta.is_campaign else None

    @cached_property
    def outcome_scores(self) -> list[OutcomeScore]:
        """Each engine's predicted outcomes against the campaign's measured ones
        (:func:`housner.scenarios.runs.campaign_run.outcome_table`, seed :data:`BOOT_SEED`); empty for a
        scenario's run or a campaign without outcomes."""
        if self.campaign is None:
            return []
        rows = outcome_table(self.results, self.engines, seed=BOOT_SEED)
        return rows if any(r.n or r.n_failed for r in rows) else []

    @property
    def published_outcomes(self) -> list[PublishedScore]:
        """Published outcome scores of other models on this campaign (reported elsewhere, not recomputed)."""
        return published_rows(self.campaign.name) if self.campaign is not None else []

    def reference_ids(self) -> np.ndarray:
        """motion_id of the reference's usable records."""
        return self.ok.loc[self.ok["engine"] == self.reference, "motion_id"].to_numpy(int)

    @cached_property
    def comparison(self) -> pd.DataFrame:
        """Every engine against the reference (:func:`~housner.scenarios.execution.tables.compare_engines`)."""
        return compare_engines(
            self.results,
            self.reference,
            q=QUARTILES,
            ci=0.90,
            p_ci=0.95,
            n_boot=N_BOOT,
            seed=BOOT_SEED,
            rtol=RECORD_RTOL,
            atol=0.0,
        )

    @cached_property
    def summaries(self) -> dict[str, EngineSummary]:
        """Engine -> its row of :attr:`comparison` as a value (records, percentiles, P[overturn], distances to the
        reference: :class:`~housner.scenarios.execution.tables.EngineSummary`), the reference first."""
        return engine_summaries(self.comparison)

    def verdicts(self, floors: dict | None = None) -> dict[str, EngineVerdict]:
        """Engine -> its verdict against the reference, for every engine but the series with the scenario's
        [[effects]] (an effect is meant to move the distribution: it gets no verdict).

        ``floors`` are the chaos floors to judge against (default :attr:`chaos_floors`; a caller that could not
        compute them passes those it has).
        """
        floors = self.chaos_floors if floors is None else floors
        skip = set(self.meta.effect_series) | set(self.mesh_engines)
        return {e: engine_verdict(self.summaries[e], floors.get(e)) for e in self.others if e not in skip}

    @property
    def mesh_engines(self) -> list[str]:
        """The run's 3D scan-mesh engines (``mesh_engine``): their theta is a 3D body's tilt, not the planar block's
        rotation, so they get no distribution verdict against a planar reference (a campaign scores their
        outcomes)."""
        out = []
        for e in self.engines:
            try:
                cls = engine_class(e)
            except (ImportError, ValueError, EngineError):  # not importable here: judged as a planar engine
                continue
            if getattr(cls, "mesh_engine", False):
                out.append(e)
        return out

    @cached_property
    def motions(self) -> StoredMotions | None:
        """The arrays of motions.npz (None when absent)."""
        return read_motions(self.path)

    def reference_motions(self) -> list[GroundMotion]:
        """The motions of the reference's usable records, in the order of the results table."""
        motions = motion_list(self)
        return [motions[i] for i in self.reference_ids() if i < len(motions)]

    @cached_property
    def record_gap(self) -> RecordGap:
        """:func:`housner.scenarios.runs.spread.record_against_ensemble` for this run: the record among its ensemble."""
        record, why = source_record(self)
        if record is None:
            raise DataFileError(self.path / "run.json", why)
        if self.motions is None:
            raise DataFileError(self.path / "motions.npz", "missing: the ensemble is needed")
        amp = self.meta.scenario.amplitude
        settings = {k: v for k, v in self.meta.engine_settings(self.reference).items() if v is not None}
        return record_against_ensemble(
            self.specimen_obj,
            record,
            self.reference_motions(),
            self.S,
            amplitude=amp if math.isfinite(amp) else 1.0,
            engine=self.reference,
            settings=settings,
            ensemble_values=self.values(self.reference),
        )

    @cached_property
    def paper_factors(self) -> EquivalentAmplitudes | None:
        """``equivalent_amplitude`` (:mod:`housner.scenarios.runs.spread`) of this ensemble for the paper's percentiles.

        The analytic model with the specimen's own r (the paper's numerical column is Housner's model),
        whatever the run's reference: how much stronger, in effect, the paper's motions were.
        """
        targets = self.meta.analysis.paper_targets
        if not targets or self.motions is None:
            return None
        return equivalent_amplitude(self.specimen_obj, self.reference_motions(), targets, seed=BOOT_SEED)

    @cached_property
    def chaos_floors(self) -> dict:
        """Engine -> :class:`housner.scenarios.runs.chaos.ChaosFloor` at the report's agreement tolerance.

        The analytic model perturbed by each engine's measured r and p errors (stored by the
        run in run.json's ``engine_errors``) on the motions that engine and the reference both
        computed. Empty when the run stored no errors (the reference is not the analytic model,
        or an older run) or has no motions.
        """
        stored = self.meta.engine_errors
        if not stored or self.motions is None or self.reference != "housner":
            return {}
        motions = motion_list(self)
        r = self.meta.engine_settings(self.reference).get("r")
        ref_ok = set(self.reference_ids())
        out = {}
        for e in self.others:
            d = stored.get(e)
            if d is None or d.error is not None:
                continue
            ids = sorted(ref_ok & set(self.ok.loc[self.ok["engine"] == e, "motion_id"].to_numpy(int)))
            ms = [motions[i] for i in ids if i < len(motions)]
            if ms:
                out[e] = chaos_floor(
                    self.specimen_obj,
                    ms,
                    d,
                    r=json_number(r) if r else None,
                    rtol=RECORD_RTOL,
                    atol=0.0,
                )
        return out

    @cached_property
    def specimen_obj(self) -> Specimen:
        """The run's specimen as a :class:`housner.Specimen` (from run.json)."""
        sp = self.specimen
        return Specimen(
            height=json_number(sp.height_m),
            width=json_number(sp.width_m),
            depth=json_number(sp.depth_m),
            mass=json_number(sp.mass_kg),
            I0=json_number(sp.I0_kgm2),
            name=str("specimen" if sp.name is None else sp.name),
        )

    def motion_dt(self, motion_id: int) -> float:
        """The step [s] of motion ``motion_id`` (NaN when motions.npz does not hold it)."""
        m = self.motions
        if m is not None and motion_id < len(m.dt):
            return float(m.dt[motion_id])
        return math.nan

    def histories(self, motion_ids: Iterable[int]) -> dict[tuple[str, int], tuple[np.ndarray, np.ndarray]]:
        """(engine, motion_id) -> (t [s], theta [rad]) for the given motions (empty when not stored)."""
        ids = {int(i) for i in motion_ids}
        return read_histories(self.path, ids, {i: self.motion_dt(i) for i in ids})


def motion_list(run: Run) -> list[GroundMotion]:
    """The run's motions as stored in motions.npz (model scale), one :class:`GroundMotion` per motion_id."""
    m = run.motions
    out = []
    names = m.names if m.names is not None else []
    for i, (n, dt) in enumerate(zip(m.n, m.dt, strict=True)):
        name = str(names[i]) if i < len(names) else f"motion {i}"
        out.append(GroundMotion(np.asarray(m.acc[i, : int(n)], dtype=float), float(dt), name=name))
    return out


def source_record(run: Run) -> tuple[GroundMotion | None, str]:
    """(the record the run's motions come from, at prototype scale, "") or (None, why not, in plain text)."""
    facts = run.motions_meta.record or RecordFacts()
    key = run.meta.scenario.record or facts.name
    if not key:
        return None, "run.json names no record"
    if facts.path:  # a user's file: read it again if it has not changed since the run
        path = Path(facts.path)
        try:
            same = file_sha256(path) == facts.sha256
        except OSError:
            return None, f"Record file {path} is no longer there"
        if not same:
            return None, f"Record file {path} has changed since the run"
        return read_record_file(path), ""
    if key not in RECORDS:
        return None, f"Record {key!r} is not in the catalogue (housner.scenarios.motions.records.RECORDS)"
    return RECORDS[key](), ""
