"""A measured campaign run as a scenario: every engine on the campaign's records and specimen, scored on its outcomes.

``housner run CAMPAIGN`` (a folder holding ``campaign.toml``, docs/reference/campaign-format.md) runs the
named engines on the campaign's ground-motion records (and its free-vibration releases, from their
measured theta0) and writes the run directory of a scenario run
(:mod:`housner.scenarios.execution.rundir`), with two more columns: ``record_id`` and
``observed_overturned``, the campaign's outcome of each record (NA where it has none: a free vibration).

What each engine is given:

1. A planar engine (every engine without ``mesh_engine = True``) gets the campaign's :class:`Specimen`. From a
   scan mesh that is the symmetric block of :meth:`housner.scan.ScanSpecimen.specimen`, always with the effect
   ``asymmetric_pivots(e = (b- - b+)/2)``: the specimen's own geometry, not a studied effect, so the run holds
   only these rows. A plain block campaign gets no effect.
2. A 3D engine (``mesh_engine = True``) gets the settings ``mesh`` (the mesh file's absolute path),
   ``azimuth`` [deg], ``density`` [kg/m^3] and ``contact`` of ``[specimen]``, no effect.

Everything is checked before the first simulation (:func:`check_campaign_engines`): an unknown engine, a 3D
engine on a campaign without a mesh, a planar engine that cannot realise the specimen's asymmetry, each in one
line. :func:`outcome_table` scores each engine's predicted outcomes against the measured ones.
"""

from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from housner._values import JsonValue
from housner.engines.base import ENGINES, engine_class
from housner.errors import unknown_choice
from housner.motion import GroundMotion
from housner.scenarios.campaigns.campaign import Campaign, load_campaign
from housner.scenarios.catalogue.schema import effects_label
from housner.scenarios.diagnosis.outcomes.outcome_scores import outcome_scores
from housner.scenarios.execution.options import RunOptions
from housner.scenarios.execution.outputs import check_output_dir
from housner.scenarios.execution.run_meta import EffectsFacts, build_run_meta
from housner.scenarios.execution.rundir import RUN_FILES, write_run
from housner.scenarios.execution.runner import run_engines
from housner.scenarios.motions.build import MotionFacts
from housner.scenarios.runs.run import RunResult
from housner.specimen import Specimen

__all__ = [
    "CAMPAIGN_FILE",
    "P_CLIP",
    "CampaignFacts",
    "CampaignInput",
    "OutcomeScore",
    "PublishedScore",
    "ScanPivots",
    "campaign_input",
    "check_campaign_engines",
    "is_campaign",
    "outcome_table",
    "published_rows",
    "run_campaign",
]

#: The file that makes a folder a campaign.
CAMPAIGN_FILE = "campaign.toml"
#: A deterministic engine predicts P(overturn) 0 or 1; its log loss is taken with P clipped to [P_CLIP, 1 - P_CLIP]
#: [-]: one surprising record then costs -ln(0.01) = 4.6 nats instead of infinity (the report's caption says so).
P_CLIP = 0.01
#: The reference engine of a campaign run's distribution comparison (the analytic model).
REFERENCE = "housner"
#: Seed of the scores' bootstrap over the records (pages reproducible).
SCORE_SEED = 0

#: Published outcome scores of other models on a campaign, reported elsewhere and not recomputed here, keyed by a
#: pattern of the campaign's name (the names ``housner campaign from-asu`` writes). Figures: docs/results.md,
#: "Real shake-table tests".
_PUBLISHED = (
    (
        re.compile(r"^ASU granite shake-table tests .*specimen SP1$"),
        {
            "model": "VSR's PyBullet model, best of 25 parameter sets (Chen et al. 2024)",
            "accuracy": 0.821,
            "f1": 0.735,
            "n_predicted": 149,
            "n_overturned": 243,
            "note": "reported elsewhere, not recomputed, not the same test list",
        },
    ),
)


@dataclass(frozen=True, eq=False)
class ScanPivots(JsonValue):
    """A scan specimen's two pivots: their distances from the centre of mass [m], its height [m], the two
    slendernesses [rad] and its mass [kg]."""

    b_pos_m: float
    b_neg_m: float
    h_m: float
    alpha_pos_rad: float
    alpha_neg_rad: float
    mass_kg: float


@dataclass(frozen=True, eq=False)
class CampaignFacts(JsonValue):
    """run.json's ``campaign`` table: what a campaign's run was given by its campaign (:func:`campaign_facts`).

    Attributes
    ----------
    name, path : str
        The campaign's name and folder.
    n_records, n_outcomes, n_overturned : int
        Its records run, those with a measured outcome, and those overturned.
    skipped : int
        Records that could not be read, left out.
    geometry : EffectsFacts
        The planar engines' geometry effects (empty for a plain block).
    mesh : dict or None
        The 3D engines' settings (``mesh`` [path], ``azimuth`` [deg], ``density`` [kg/m^3], ``contact``); None
        without a scan mesh.
    scan : ScanPivots or None
        The scan's pivots, for a scan specimen.
    """

    name: str = ""
    path: str = ""
    n_records: int | None = None
    n_outcomes: int | None = None
    n_overturned: int | None = None
    skipped: int | None = None
    geometry: EffectsFacts = field(default_factory=EffectsFacts)
    mesh: dict | None = None
    scan: ScanPivots | None = None

    _ALWAYS = ("mesh",)


@dataclass(frozen=True, eq=False)
class OutcomeScore(JsonValue):
    """An engine's predicted outcomes scored against the campaign's measured ones (:func:`outcome_table`).

    Attributes
    ----------
    engine : str
    n_failed : int
        Records with an outcome the engine failed on (left out).
    p_clip : float
        The log loss's clip of the engine's 0/1 predictions [-].
    accuracy, f1, log_loss, brier, precision, recall, roc_auc : float or None
        The scores (:func:`~housner.scenarios.diagnosis.outcomes.outcome_scores.outcome_scores`); None for an
        engine without a scored record.
    accuracy_ci, f1_ci, log_loss_ci, brier_ci, precision_ci, recall_ci, roc_auc_ci : tuple of float or None
        Their 95 % bootstrap intervals (None: no interval).
    n, n_overturned, n_predicted : int
        Records scored, measured overturns, predicted overturns.
    tp, fp, fn, tn : int or None
        The confusion matrix (None for an engine without a scored record).
    """

    engine: str
    n_failed: int = 0
    p_clip: float = math.nan
    accuracy: float | None = None
    f1: float | None = None
    log_loss: float | None = None
    brier: float | None = None
    precision: float | None = None
    recall: float | None = None
    roc_auc: float | None = None
    accuracy_ci: tuple[float, float] | None = None
    f1_ci: tuple[float, float] | None = None
    log_loss_ci: tuple[float, float] | None = None
    brier_ci: tuple[float, float] | None = None
    precision_ci: tuple[float, float] | None = None
    recall_ci: tuple[float, float] | None = None
    roc_auc_ci: tuple[float, float] | None = None
    n: int = 0
    n_overturned: int = 0
    n_predicted: int = 0
    tp: int | None = None
    fp: int | None = None
    fn: int | None = None
    tn: int | None = None


@dataclass(frozen=True, eq=False)
class PublishedScore(JsonValue):
    """A published outcome score of another model on a campaign (reported elsewhere, not recomputed)."""

    model: str
    accuracy: float
    f1: float
    n_predicted: int
    n_overturned: int
    note: str


def is_campaign(path: str | Path) -> bool:
    """Whether ``path`` is a folder holding ``campaign.toml``, or that file (``housner run`` then runs a campaign)."""
    p = Path(path)
    return (p.is_dir() and (p / CAMPAIGN_FILE).is_file()) or (p.name == CAMPAIGN_FILE and p.is_file())


def is_mesh_engine(name: str) -> bool:
    """Whether engine ``name`` simulates the scan mesh in 3D (its class says ``mesh_engine = True``)."""
    return bool(getattr(engine_class(name), "mesh_engine", False))


@dataclass(frozen=True, eq=False)
class CampaignInput:
    """What a campaign gives the engines.

    Attributes
    ----------
    campaign : Campaign
    specimen : Specimen
        The planar engines' block (symmetric: the mean of the scan's pivots).
    motions : list of GroundMotion
        The ground-motion records (theta ones, then outcome ones, each in the campaign's order), then the free
        vibrations (with their measured theta0 [rad]); ``motion_id`` is the index.
    record_ids : list of str
        The record of each motion.
    observed : list of bool or None
        The measured outcome of each motion (None: a free vibration, which has no outcome to score).
    geometry : tuple of effects
        The effects that make the planar block the specimen (``asymmetric_pivots`` of a scan; empty for a block).
    mesh : dict or None
        The 3D engines' settings (``mesh`` [absolute path], ``azimuth`` [deg], ``density`` [kg/m^3],
        ``contact``); None without a scan mesh.
    """

    campaign: Campaign
    specimen: Specimen
    motions: list[GroundMotion]
    record_ids: list[str]
    observed: list
    geometry: tuple
    mesh: dict | None

    @property
    def n_ground_motion(self) -> int:
        return sum(o is not None for o in self.observed)


def campaign_input(campaign: Campaign) -> CampaignInput:
    """The specimen, motions, outcomes and geometry effects of ``campaign`` (ValueError: no ground-motion record)."""
    gm = [*campaign.ground_motion, *campaign.outcomes]
    if not gm:
        raise ValueError(
            f"campaign {campaign.name!r} ({campaign.path}) has no ground-motion records: nothing to run the engines "
            f"on ({len(campaign.free_vibration)} free-vibration records; `housner diagnose` reads those)"
        )
    fv = campaign.free_vibration
    geometry: tuple = ()
    mesh = None
    specimen = campaign.specimen
    scan = campaign.scan
    if scan is not None:
        from housner.effects import AsymmetricPivots

        specimen = scan.specimen()
        e = 0.5 * (scan.neg.b - scan.pos.b)
        geometry = (AsymmetricPivots(e=e),) if e != 0.0 else ()
        mesh = {
            "mesh": str(Path(scan.path).resolve()),
            "azimuth": float(scan.azimuth),
            "density": float(scan.density),
            "contact": str(scan.contact),
        }
    return CampaignInput(
        campaign=campaign,
        specimen=specimen,
        motions=[r.motion for r in (*gm, *fv)],
        record_ids=[r.id for r in (*gm, *fv)],
        observed=[bool(r.overturned) for r in gm] + [None] * len(fv),
        geometry=geometry,
        mesh=mesh,
    )


def check_campaign_engines(inp: CampaignInput, names: list[str]) -> dict[str, dict]:
    """Engine -> the settings it runs with, each engine checked before any work (ValueError in one line).

    Refused: an unknown name; a 3D engine on a campaign without a mesh, or one that refuses the mesh settings; a
    planar engine that cannot realise the specimen's geometry effect (its registry's ``effects_supported``, the
    effect's bounds on this specimen, the engine's own :meth:`~housner.engines.base.Engine.effect_refusal`).
    """
    where = f"campaign {inp.campaign.name!r}"
    out = {}
    for name in names:
        if name not in ENGINES:
            raise ValueError(str(unknown_choice("engine", name, ENGINES)))
        cls = engine_class(name)
        if is_mesh_engine(name):
            if inp.mesh is None:
                raise ValueError(
                    f"engine {name!r} simulates a scan mesh in 3D, but {where} has no [specimen] mesh (a plain "
                    "block): run a planar engine on it"
                )
            try:
                cls(**inp.mesh)
            except (TypeError, ValueError) as e:
                why = " ".join(str(e).split())
                raise ValueError(f"engine {name!r} refuses {where}'s mesh settings: {why}") from None
            out[name] = dict(inp.mesh)
            continue
        for eff in inp.geometry:
            if eff.name not in cls.effects_supported:
                can = ", ".join(sorted(cls.effects_supported)) or "none"
                raise ValueError(
                    f"engine {name!r} cannot realise effect {eff.name!r} (it realises: {can}), which {where}'s scan "
                    f"specimen needs (its pivots lie {_pivots_text(inp)}); run a 3D engine or one that realises it"
                )
        for eff in inp.geometry:
            try:
                eff.check(inp.specimen)
            except ValueError as e:
                raise ValueError(
                    f"{where}: the scan specimen's geometry {effects_label(inp.geometry)} is refused: {e}"
                ) from None
        why = cls().effect_refusal(inp.specimen, inp.geometry) if inp.geometry else None
        if why:
            raise ValueError(f"{where}: {why}")
        out[name] = {}
    return out


def _pivots_text(inp: CampaignInput) -> str:
    scan = inp.campaign.scan
    return f"b+ = {scan.pos.b:.4g} m and b- = {scan.neg.b:.4g} m from the centre of mass, h = {scan.h:.4g} m"


def run_campaign(
    campaign: Campaign | str | Path,
    *,
    engines: list[str],
    out: str | Path,
    options: RunOptions | None = None,
    allow_outside: bool = False,
    say=None,
    **execution,
) -> RunResult:
    """Run ``engines`` on a campaign's records and specimen and write the run directory ``out``.

    Parameters
    ----------
    campaign : Campaign or path
        A loaded campaign or its folder.
    engines : list of str
        Registered engine names (planar or 3D, see the module docstring); the analytic model ``housner`` is the
        reference of the distribution comparison.
    out : path
        The run directory (checked writable before the work).
    options : RunOptions, optional
        How the records execute (see :func:`housner.scenarios.execution.runner.run_engines`); cached like a
        scenario's records.
    allow_outside : bool
        Read record files and a mesh outside the campaign folder.
    say : callable, optional
        Takes one line of progress (the command prints it), before the engines start.
    **execution
        :class:`RunOptions` fields as keywords, over ``options``.

    Returns
    -------
    RunResult
        Its ``meta.campaign`` says the run is a campaign's (path, name, records, geometry, mesh).
    """
    opts = RunOptions.merged(options, execution, "run_campaign")
    t0 = time.perf_counter()
    if not isinstance(campaign, Campaign):
        campaign = load_campaign(campaign, allow_outside=allow_outside)
    inp = campaign_input(campaign)
    if not engines:
        raise ValueError("give the engines to run on a campaign: --engines NAME[,NAME...]")
    settings = check_campaign_engines(inp, list(engines))
    out = Path(out)
    check_output_dir(out, "run directory", files=RUN_FILES)
    t_load = time.perf_counter() - t0
    if say is not None:
        say(
            f"campaign {campaign.name}: {inp.n_ground_motion} ground-motion + {len(inp.motions) - inp.n_ground_motion}"
            f" free-vibration records x engines {', '.join(engines)} -> {out}"
            + (f"; planar engines with {effects_label(inp.geometry)}" if inp.geometry else "")
        )
    results, histories, info = campaign_results(inp, settings, engines, opts)
    meta = build_run_meta(
        scenario={"name": campaign.name, "description": _description(campaign), "file": str(campaign.path.resolve())},
        specimen=inp.specimen,
        motions=MotionFacts(
            source="campaign",
            campaign=campaign.name,
            n_ground_motion=inp.n_ground_motion,
            n_free_vibration=len(inp.motions) - inp.n_ground_motion,
        ),
        n_motions=len(inp.motions),
        engines={n: info[n] for n in engines},
        analysis={"reference": REFERENCE},
        results=results,
        wall_s={"load": t_load, "total": time.perf_counter() - t0},
        campaign=campaign_facts(inp),
    )
    write_run(out, results, histories, inp.motions, meta)
    return RunResult(results, histories, inp.motions, meta, out)


def campaign_results(
    inp: CampaignInput, settings: dict[str, dict], engines: list[str], opts: RunOptions
) -> tuple[pd.DataFrame, dict, dict]:
    """Every engine on the campaign's records: (results, histories, engine info) of
    :func:`housner.scenarios.execution.runner.run_engines`.

    The planar engines of ``settings`` (engine -> settings, :func:`check_campaign_engines`) run with the
    specimen's geometry effect, the 3D ones without; the rows come in the order of ``engines``, then of the
    records, with each record's id and measured outcome (:func:`with_records`).
    """
    planar = {n: s for n, s in settings.items() if not is_mesh_engine(n)}
    mesh = {n: s for n, s in settings.items() if is_mesh_engine(n)}
    parts, histories, info = [], {}, {}
    for group, effects in ((planar, inp.geometry), (mesh, ())):
        if group:
            res, hist, inf = run_engines(inp.specimen, inp.motions, group, opts, effects=effects)
            parts.append(res)
            histories.update(hist)
            info.update(inf)
    order = {n: k for k, n in enumerate(engines)}
    results = pd.concat(parts, ignore_index=True)
    results = results.sort_values(
        ["engine", "motion_id"],
        key=lambda s: s.map(order) if s.name == "engine" else s,
        kind="stable",
        ignore_index=True,
    )
    return with_records(results, inp), histories, info


def _description(campaign: Campaign) -> str:
    return f"measured campaign {campaign.path.resolve()}"


def with_records(results: pd.DataFrame, inp: CampaignInput) -> pd.DataFrame:
    """``results`` with the record of each row (``record_id``) and its measured outcome (``observed_overturned``,
    nullable boolean: NA for a record without one)."""
    ids = np.asarray(inp.record_ids, dtype=object)
    obs = pd.array(inp.observed, dtype="boolean")
    mid = results["motion_id"].to_numpy(int)
    return results.assign(record_id=ids[mid], observed_overturned=obs[mid])


def campaign_facts(inp: CampaignInput) -> CampaignFacts:
    """run.json's ``campaign`` table: what the run was given by its campaign."""
    c = inp.campaign
    y = [o for o in inp.observed if o is not None]
    scan = None
    if c.scan is not None:
        s = c.scan
        scan = ScanPivots(
            b_pos_m=s.pos.b,
            b_neg_m=s.neg.b,
            h_m=s.h,
            alpha_pos_rad=math.atan2(s.pos.b, s.h),
            alpha_neg_rad=math.atan2(s.neg.b, s.h),
            mass_kg=s.mass,
        )
    return CampaignFacts(
        name=c.name,
        path=str(c.path.resolve()),
        n_records=len(inp.motions),
        n_outcomes=len(y),
        n_overturned=int(sum(y)),
        skipped=len(c.skipped),
        geometry=EffectsFacts.of(inp.geometry),
        mesh=inp.mesh,
        scan=scan,
    )


# ----------------------------------------------------------------------------
# scores
def outcome_table(
    results: pd.DataFrame, engines: list[str] | None = None, *, seed: int = SCORE_SEED
) -> list[OutcomeScore]:
    """Each engine's predicted outcomes scored against the measured ones (:func:`outcome_scores`).

    Parameters
    ----------
    results : DataFrame
        A campaign run's table (with ``observed_overturned``).
    engines : list of str, optional
        The engines, in this order (default: the table's order).
    seed : int
        Seed of the bootstrap over the records (95 % percentile intervals).

    Returns
    -------
    list of OutcomeScore
        Per engine: ``engine``, the scores of :func:`outcome_scores` (accuracy, F1, log loss, brier, ... with
        ``_ci`` intervals, the counts ``n``, ``n_predicted``, ``n_overturned``, ``tp``, ``fp``, ``fn``, ``tn``),
        ``n_failed`` (records with an outcome the engine failed on: left out) and ``p_clip`` (the log loss's
        clip of the engine's 0/1 predictions). An engine without a scored record has only the counts.
    """
    if "observed_overturned" not in results.columns:
        return []
    names = engines if engines is not None else list(dict.fromkeys(results["engine"].astype(str)))
    rows = []
    for name in names:
        sub = results[(results["engine"].astype(str) == name) & results["observed_overturned"].notna()]
        ok = sub[sub["status"].astype(str) == "ok"]
        row = {"engine": name, "n_failed": int(len(sub) - len(ok)), "p_clip": P_CLIP}
        if len(ok):
            p = np.clip(ok["overturned"].to_numpy(float), P_CLIP, 1.0 - P_CLIP)
            row.update(outcome_scores(p, ok["observed_overturned"].to_numpy(bool), seed=seed).to_dict())
        else:
            row.update(n=0, n_predicted=0, n_overturned=int(sub["observed_overturned"].astype(bool).sum()))
        rows.append(OutcomeScore.from_json(row))
    return rows


def published_rows(campaign_name: str) -> list[PublishedScore]:
    """Published scores of other models on this campaign (reported elsewhere, not recomputed); empty for most."""
    return [PublishedScore.from_json(row) for pattern, row in _PUBLISHED if pattern.search(campaign_name or "")]
