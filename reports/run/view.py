"""A run directory as the report reads it: results, run.json, motions and histories, and what follows from them.

:class:`Run` loads the files through :mod:`housner.scenarios.execution.rundir` (the one owner of
their format) and derives, lazily, what the report's sections share: the
reference and the engine order, the usable and failed rows, the engine
comparison (:func:`housner.scenarios.execution.tables.compare_engines` with the report's fixed
bootstrap seed, so that pages are reproducible), the specimen, the motions and
the stored histories.
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
from housner.errors import DataFileError
from housner.motion import GroundMotion
from housner.reports import figures
from housner.reports.page import esc
from housner.scenarios.execution.rundir import json_number, load_results, read_histories, read_motions
from housner.scenarios.execution.tables import compare_engines, split_failed
from housner.scenarios.motions.records import RECORDS, file_sha256, read_record_file
from housner.scenarios.runs.chaos import RECORD_RTOL, chaos_floor, errors_from_dict, floor_check, floor_verdict
from housner.scenarios.runs.spread import equivalent_amplitude, record_against_ensemble
from housner.stats import KS_MAX, OVERTURN_TOL

#: Bootstrap resamples for percentile intervals (Efron and Tibshirani 1993, ch. 13, ask for at
#: least 1000 for percentile intervals) and the fixed seed that makes pages reproducible.
N_BOOT = 2000


BOOT_SEED = 0


QUARTILES = (25.0, 50.0, 75.0)


@dataclass
class Run:
    """A loaded run directory with lazily read motions and histories."""

    path: Path
    results: pd.DataFrame
    meta: dict

    @classmethod
    def load(cls, run_dir: str | Path) -> Run:
        path = Path(run_dir)
        if not path.is_dir():
            raise DataFileError(path, "not a directory (expected a run directory with results.parquet)")
        results = load_results(path)
        meta = results.attrs.get("run", {})
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
        return split_failed(self.results)

    @property
    def ok(self) -> pd.DataFrame:
        return self.split[0]

    @property
    def failed(self) -> pd.DataFrame:
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
        names = list(dict.fromkeys(self.results["engine"]))
        want = (self.meta.get("analysis") or {}).get("reference") or "housner"
        if want in names:
            return want
        return names[0] if names else want

    @property
    def reference_is_requested(self) -> bool:
        want = (self.meta.get("analysis") or {}).get("reference") or "housner"
        return want == self.reference

    @property
    def others(self) -> list[str]:
        return [e for e in self.engines if e != self.reference]

    @cached_property
    def colors(self) -> dict[str, str]:
        return figures.engine_colors(self.engines, self.reference)

    @property
    def specimen(self) -> dict:
        return self.meta.get("specimen") or {}

    @property
    def alpha(self) -> float:
        return json_number(self.specimen.get("alpha_rad"))

    @property
    def motions_meta(self) -> dict:
        return self.meta.get("motions") or {}

    @property
    def S(self) -> float:
        """Size ratio prototype / model of the motions (1 when not stated)."""
        S = json_number(self.motions_meta.get("S", 1.0))
        return S if math.isfinite(S) and S > 0 else 1.0

    @property
    def source(self) -> str:
        return str(self.motions_meta.get("source", ""))

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

    @cached_property
    def comparison(self) -> pd.DataFrame:
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
    def motions(self) -> dict | None:
        return read_motions(self.path)

    @cached_property
    def record_gap(self) -> dict:
        """:func:`housner.scenarios.runs.spread.record_against_ensemble` for this run: the record among its ensemble."""
        record, why = source_record(self)
        if record is None:
            raise DataFileError(self.path / "run.json", why)
        if self.motions is None:
            raise DataFileError(self.path / "motions.npz", "missing: the ensemble is needed")
        specimen = self.specimen_obj
        amp = json_number(((self.meta.get("scenario") or {}).get("motions") or {}).get("amplitude", 1.0))
        settings = {
            k: v
            for k, v in ((self.meta.get("engines") or {}).get(self.reference, {}).get("settings") or {}).items()
            if v is not None
        }
        ids = self.ok.loc[self.ok["engine"] == self.reference, "motion_id"].to_numpy(int)
        motions = motion_list(self)
        return record_against_ensemble(
            specimen,
            record,
            [motions[i] for i in ids if i < len(motions)],
            self.S,
            amplitude=amp if math.isfinite(amp) else 1.0,
            engine=self.reference,
            settings=settings,
            ensemble_values=self.values(self.reference),
        )

    @cached_property
    def paper_factors(self) -> dict | None:
        """``equivalent_amplitude`` (:mod:`housner.scenarios.runs.spread`) of this ensemble for the paper's percentiles.

        The analytic model with the specimen's own r (the paper's numerical column is Housner's model),
        whatever the run's reference: how much stronger, in effect, the paper's motions were.
        """
        analysis = self.meta.get("analysis") or {}
        targets = {float(k): json_number(v) for k, v in (analysis.get("paper_percentiles") or {}).items()}
        targets = {q: v for q, v in targets.items() if not math.isnan(v)}
        if not targets or self.motions is None:
            return None
        ids = self.ok.loc[self.ok["engine"] == self.reference, "motion_id"].to_numpy(int)
        motions = motion_list(self)
        return equivalent_amplitude(
            self.specimen_obj, [motions[i] for i in ids if i < len(motions)], targets, seed=BOOT_SEED
        )

    @cached_property
    def chaos_floors(self) -> dict:
        """Engine -> :class:`housner.scenarios.runs.chaos.ChaosFloor` at the report's agreement tolerance.

        The analytic model perturbed by each engine's measured r and p errors (stored by the
        run in run.json's ``engine_errors``) on the motions that engine and the reference both
        computed. Empty when the run stored no errors (the reference is not the analytic model,
        or an older run) or has no motions.
        """
        stored = self.meta.get("engine_errors") or {}
        if not stored or self.motions is None or self.reference != "housner":
            return {}
        motions = motion_list(self)
        r = ((self.meta.get("engines") or {}).get(self.reference, {}).get("settings") or {}).get("r")
        ref_ok = set(self.ok.loc[self.ok["engine"] == self.reference, "motion_id"].to_numpy(int))
        out = {}
        for e in self.others:
            d = stored.get(e)
            if not d or "error" in d:
                continue
            ids = sorted(ref_ok & set(self.ok.loc[self.ok["engine"] == e, "motion_id"].to_numpy(int)))
            ms = [motions[i] for i in ids if i < len(motions)]
            if ms:
                out[e] = chaos_floor(self.specimen_obj, ms, errors_from_dict(d), r=json_number(r) if r else None,
                                     rtol=RECORD_RTOL, atol=0.0)  # fmt: skip
        return out

    @cached_property
    def specimen_obj(self):
        """The run's specimen as a :class:`housner.Specimen` (from run.json)."""
        sp = self.specimen
        return Specimen(
            height=json_number(sp.get("height_m")),
            width=json_number(sp.get("width_m")),
            depth=json_number(sp.get("depth_m")),
            mass=json_number(sp.get("mass_kg")),
            I0=json_number(sp.get("I0_kgm2")),
            name=str(sp.get("name", "specimen")),
        )

    def motion_dt(self, motion_id: int) -> float:
        m = self.motions
        if m is not None and "dt" in m and motion_id < len(m["dt"]):
            return float(m["dt"][motion_id])
        return math.nan

    def histories(self, motion_ids: Iterable[int]) -> dict[tuple[str, int], tuple[np.ndarray, np.ndarray]]:
        """(engine, motion_id) -> (t [s], theta [rad]) for the given motions (empty when not stored)."""
        ids = {int(i) for i in motion_ids}
        return read_histories(self.path, ids, {i: self.motion_dt(i) for i in ids})


def motion_list(run: Run):
    m = run.motions
    out = []
    names = m.get("names", [])
    for i, (n, dt) in enumerate(zip(m["n"], m["dt"], strict=True)):
        name = str(names[i]) if i < len(names) else f"motion {i}"
        out.append(GroundMotion(np.asarray(m["acc"][i, : int(n)], dtype=float), float(dt), name=name))
    return out


def source_record(run: Run):
    """(the record the run's motions come from, at prototype scale, None) or (None, why not)."""
    scen = run.meta.get("scenario") or {}
    facts = run.motions_meta.get("record") or {}
    key = (scen.get("motions") or {}).get("record") or facts.get("name")
    if not key:
        return None, "run.json names no record"
    if facts.get("path"):  # a user's file: read it again if it has not changed since the run
        path = Path(facts["path"])
        try:
            same = file_sha256(path) == facts.get("sha256")
        except OSError:
            return None, f"Record file {esc(path)} is no longer there"
        if not same:
            return None, f"Record file {esc(path)} has changed since the run"
        return read_record_file(path), ""
    if key not in RECORDS:
        return None, f"Record {esc(key)!r} is not in the catalogue (housner.scenarios.motions.records.RECORDS)"
    return RECORDS[key](), ""




#: Fewest records of each engine that a distribution verdict is drawn from: one record moves the KS distance
#: by 1/n, so below 3 / KS_MAX = 20 records a single record's difference is a third of the tolerance
#: or more, and one record gives KS 0 or 1 whatever the engines do. Fewer records: "inconclusive".
MIN_RECORDS = math.ceil(3 / KS_MAX)


@dataclass(frozen=True)
class EngineVerdict:
    """What a run says of one engine against the reference, in plain text (the page and the command line).

    Attributes
    ----------
    status : str
        The distribution verdict: ``"PASS"``, ``"FAIL"`` (against the default tolerances),
        ``"inconclusive"`` (fewer than :data:`MIN_RECORDS` records, none failed) or ``"no data"``.
    checks : tuple of (bool, str)
        Each criterion: met, and its figures.
    records : str or None
        The record-by-record verdict against the chaos floor
        (:func:`housner.scenarios.runs.chaos.floor_verdict`), None where the run has no floor.
    below_floor : bool or None
        Whether the record-by-record agreement lies below the chaos floor.
    """

    status: str
    checks: tuple
    records: str | None = None
    below_floor: bool | None = None
    #: The record-by-record figures in short: "28 % [20 %, 37 %] vs chaos floor 66 %" (None without a floor).
    records_short: str | None = None

    @property
    def ok(self) -> bool | None:
        """True for PASS, False for FAIL, None otherwise (as a page's badge takes it)."""
        return {"PASS": True, "FAIL": False}.get(self.status)

    def line(self) -> str:
        """One line for the command line: the distribution verdict, its figures, the record-by-record one."""
        figures = "; ".join(t for _, t in self.checks)
        if self.records_short:
            side = "below the floor" if self.below_floor else "at the floor"
            return f"{self.status}: {figures}; record by record: {self.records_short}, {side}"
        return f"{self.status}: {figures}"


def engine_verdict(row: pd.Series, floor=None) -> EngineVerdict:
    """The verdict of one engine (its row of the run's comparison table) against the default tolerances.

    ``floor`` is the engine's :class:`housner.scenarios.runs.chaos.ChaosFloor`, if the run has one.
    """
    ks, dp, nf = float(row["ks_distance"]), float(row["overturn_diff"]), int(row["n_failed"])
    if math.isnan(ks) or math.isnan(dp):
        return EngineVerdict("no data", ((False, "no usable records to compare"),))
    checks = (
        (ks <= KS_MAX, f"KS {ks:.3f} {'<=' if ks <= KS_MAX else '>'} {KS_MAX}"),
        (
            abs(dp) <= OVERTURN_TOL,
            f"|dP[overturn]| {abs(dp):.3f} {'<=' if abs(dp) <= OVERTURN_TOL else '>'} {OVERTURN_TOL}",
        ),
        (nf == 0, f"{nf} failed record{'s' if nf != 1 else ''}"),
    )
    n = int(row["n_ok"])
    if n < MIN_RECORDS and nf == 0:  # a failed record fails at any size; the two statistics need records
        status = "inconclusive"
        checks = ((False, f"only {n} record{'s' if n != 1 else ''} (a distribution verdict needs {MIN_RECORDS}: one "
                   f"record moves the KS distance by 1/n = {1 / max(n, 1):.2f})"), *checks)  # fmt: skip
    else:
        status = "PASS" if all(c for c, _ in checks) else "FAIL"
    paired = float(row.get("n_paired", 0) or 0)
    if floor is None or not paired > 0:  # (NaN: no paired records)
        return EngineVerdict(status, checks)
    n_pair = int(paired)
    k = int(round(float(row["agreement_share"]) * n_pair))
    lo, hi, below = floor_check(k, n_pair, floor)
    short = f"{k / n_pair:.0%} [{lo:.0%}, {hi:.0%}] vs chaos floor {floor.share:.0%}"
    return EngineVerdict(status, checks, floor_verdict(k, n_pair, floor), below, short)


def checks_html(v: EngineVerdict) -> list[str]:
    """Each criterion of a verdict as the page writes it: its figures, marked met or not."""
    return [f'<span class="{"ok" if c else "bad"}">{_html_figures(t)}</span>' for c, t in v.checks]


def _html_figures(text: str) -> str:
    """A criterion's plain text as the page writes it (entities for <=, > and Delta)."""
    return esc(text).replace("&lt;=", "&le;").replace("dP[", "&Delta;P[")
