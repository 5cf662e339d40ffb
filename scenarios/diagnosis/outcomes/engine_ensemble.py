"""A 3D scan-mesh engine as an outcome model: each record's P(overturn) is the share of an ensemble of the engine's
runs that overturn, the ensemble spanning what the campaign does not record (the rock's azimuth on the table, the
friction), scored on the diagnosis's own folds with nothing of the engine's physics fitted (only the lapse, and
which of the unrecorded orientations the rock stood in). The runs go through the runner, so they are cached, run in
parallel and a failed record is kept and named. The method is in ``docs/explanation/diagnosis.md`` ("A 3D engine
as an outcome model")."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from housner._values import JsonValue
from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.diagnosis.outcomes.outcome_models import ENGINE_PREFIX, UNIFORM, EngineRuns, cross_validate
from housner.scenarios.diagnosis.outcomes.outcome_scores import (
    OutcomeScores,
    SeedSpread,
    outcome_floor,
    outcome_scores,
    point_scores,
    seed_spread,
)
from housner.scenarios.diagnosis.outcomes.outcome_validation import (
    OutcomeJudgement,
    PairedComparison,
    compare_log_loss,
    judge_outcome_model,
)
from housner.scenarios.execution.options import RunOptions

if TYPE_CHECKING:
    from housner.scenarios.diagnosis.outcomes.outcome_results import OutcomeStep

__all__ = [
    "AZIMUTHS",
    "FRICTIONS",
    "EngineEnsemble",
    "EngineModelScore",
    "ScoringRuns",
    "engine_ensemble",
    "engine_table",
    "score_engine_model",
]

#: Azimuths of the default ensemble [count]: evenly spaced over the full turn from the campaign's own, since a
#: campaign that does not record the rock's orientation on the table leaves every azimuth as likely.
AZIMUTHS = 8
#: Friction coefficients of the default ensemble [-]: the middle of the 0.6-0.8 the Virtual Shake Robot study gave
#: granite on the steel table (the sensitivity to the range is measured, docs/results.md).
FRICTIONS = (0.7,)


@dataclass(frozen=True, eq=False)
class EngineEnsemble(JsonValue):
    """The runs of a 3D engine that make one outcome model: every azimuth with every friction.

    Attributes
    ----------
    engine : str
        A registered 3D scan-mesh engine (``mujoco-3d``, ``pybullet-3d``).
    azimuths : tuple of float
        Shaking directions [deg] from the mesh x axis, in [0, 360).
    frictions : tuple of float
        Coulomb friction coefficients rock/table [-].
    timestep : float or None
        The engine's largest step [s] (None: its default).
    amplitudes : tuple of float
        Factors on the table acceleration [-]: an outcome near its threshold flips under a change of the input far
        below any accelerometer's calibration, so P samples it as the planar model's ensemble does.
    """

    engine: str
    azimuths: tuple[float, ...]
    frictions: tuple[float, ...]
    timestep: float | None = None
    amplitudes: tuple[float, ...] = (1.0,)

    @property
    def size(self) -> int:
        return len(self.azimuths) * len(self.frictions) * len(self.amplitudes)

    @property
    def member_azimuths(self) -> tuple[float, ...]:
        """The azimuth of each member [deg], in :meth:`members` order."""
        return tuple(a for a in self.azimuths for _f in self.frictions for _k in self.amplitudes)

    def members(self) -> list[dict]:
        """Each run's settings over the campaign's mesh settings (azimuth-major, then friction) and the factor on
        the table acceleration it runs at (``amplitude``, not an engine setting), innermost."""
        step = {} if self.timestep is None else {"timestep": self.timestep}
        return [
            {"azimuth": a, "friction": f, **step, "amplitude": k}
            for a in self.azimuths
            for f in self.frictions
            for k in self.amplitudes
        ]


def engine_ensemble(
    campaign: Campaign,
    engine: str,
    *,
    azimuths: int = AZIMUTHS,
    frictions: Sequence[float] = FRICTIONS,
    timestep: float | None = None,
    amplitudes: Sequence[float] = (1.0,),
) -> EngineEnsemble:
    """The ensemble of ``engine`` on ``campaign``'s scan mesh: ``azimuths`` directions evenly spaced from the
    campaign's own (1: the campaign's azimuth alone, for a campaign that records it), each with every friction of
    ``frictions`` and every factor on the table acceleration of ``amplitudes``. ValueError in one line for a campaign
    without a mesh, a planar engine or a bad count."""
    from housner.scenarios.runs.campaign_run import campaign_input, check_campaign_engines, is_mesh_engine

    if campaign.scan is None:
        raise ValueError(
            f"--engine-model: campaign {campaign.name!r} has no [specimen] mesh; a 3D engine needs the rock's scan"
        )
    if not is_mesh_engine(engine):
        raise ValueError(f"--engine-model: {engine!r} is not a 3D scan-mesh engine (mujoco-3d, pybullet-3d)")
    if int(azimuths) != azimuths or not 1 <= azimuths <= 72:
        raise ValueError(f"--engine-azimuths must be an integer in 1 .. 72, got {azimuths!r}")
    fr = tuple(float(f) for f in frictions)
    if not fr or not all(0.0 < f <= 10.0 for f in fr):
        raise ValueError(f"--engine-frictions must be numbers in (0, 10], got {list(frictions)!r}")
    amps = tuple(float(k) for k in amplitudes)
    if not amps or not all(0.5 <= k <= 2.0 for k in amps):
        raise ValueError(f"--engine-amplitudes must be factors in [0.5, 2], got {list(amplitudes)!r}")
    a0 = float(campaign.scan.azimuth)
    az = tuple(round((a0 + 360.0 * k / azimuths) % 360.0, 9) for k in range(int(azimuths)))
    ens = EngineEnsemble(engine, az, fr, None if timestep is None else float(timestep), amps)
    inp = campaign_input(campaign)
    base = check_campaign_engines(inp, [engine])[engine]
    from housner.engines.base import engine_class

    for member in ens.members():  # every member's settings refused before any run
        settings = {k: v for k, v in member.items() if k != "amplitude"}
        try:
            engine_class(engine)(**{**base, **settings})
        except (TypeError, ValueError) as e:
            raise ValueError(f"--engine-model {engine}: {' '.join(str(e).split())}") from None
    return ens


def engine_table(
    campaign: Campaign,
    ensemble: EngineEnsemble,
    records: Sequence,
    options: RunOptions | None = None,
    say: Callable[[str], None] | None = None,
) -> tuple[np.ndarray, float]:
    """Overturned or not for each of ``records`` (the campaign's outcome records) and each member of ``ensemble``:
    ((records, members) float, 1.0 overturned, 0.0 stood, NaN a run that failed), and the wall time [s].

    Each member is one :func:`~housner.scenarios.execution.runner.run_engines` call on the records' table motions,
    so its runs are cached (a second diagnosis reads them back) and a record that fails is kept as NaN, named by
    ``say``. ValueError where a record has no member that ran.
    """
    from housner.scenarios.execution.runner import run_engines
    from housner.scenarios.runs.campaign_run import campaign_input

    say = say or (lambda line: None)
    inp = campaign_input(campaign)
    base = dict(inp.mesh)
    motions = [r.motion for r in records]
    opts = options or RunOptions(progress=False)
    t0 = time.perf_counter()
    out = np.full((len(motions), ensemble.size), np.nan)
    for j, member in enumerate(ensemble.members()):
        t1 = time.perf_counter()
        settings = {k: v for k, v in member.items() if k != "amplitude"}
        amp = member["amplitude"]
        runs_on = motions if amp == 1.0 else [mo.scaled(amp) for mo in motions]
        res, _hist, _info = run_engines(
            inp.specimen, runs_on, {ensemble.engine: {**base, **settings}}, opts, histories=False
        )
        res = res.sort_values("motion_id")
        ok = (res["status"] != "failed").to_numpy()
        out[ok, j] = res["overturned"].to_numpy()[ok].astype(float)
        failed = [records[i].id for i in np.flatnonzero(~ok)]
        say(
            f"{ensemble.engine} azimuth {member['azimuth']:g} deg, friction {member['friction']:g}"
            + (f", table acceleration x {amp:g}" if amp != 1.0 else "")
            + ": "
            f"{int(np.nansum(out[:, j]))} of {len(motions)} overturn, {time.perf_counter() - t1:.1f} s"
            + (f"; failed: {', '.join(failed)}" if failed else "")
        )
    none = [records[i].id for i in np.flatnonzero(np.all(np.isnan(out), axis=1))]
    if none:
        raise ValueError(f"--engine-model {ensemble.engine}: no run of the ensemble finished for {', '.join(none)}")
    return out, time.perf_counter() - t0


@dataclass(frozen=True, eq=False)
class EngineModelScore(JsonValue):
    """A 3D engine's ensemble scored as an outcome model on the diagnosis's folds, twice: with the rock's
    orientation fitted on the training folds (which of the ensemble's azimuths it stood in), and with every
    azimuth weighed alike (the orientation unknown).

    Attributes
    ----------
    ensemble : EngineEnsemble
    azimuths : tuple of float
        The orientation fitted on every record [deg]: the ensemble's azimuths whose runs make P.
    lapse : float
        The lapse fitted on every record with it [-] (each fold's own fits scored it).
    fold_agreement : float
        Share of the fits without one fold (every repeat) that chose the same azimuths [-].
    scores : OutcomeScores
        Of the held-out P (orientation fitted), the mean over the repeats (intervals resample whole ground
        motions).
    over_seeds : dict of str to SeedSpread
        Each score's mean and range over the repeats.
    against_final, against_plain : PairedComparison
        The engine against the planar final and plain models, record by record on the same folds, clustered by
        ground motion (positive advantage: the engine predicts better).
    judgement : OutcomeJudgement
        The engine against the baselines and its floor, by the rule that judges the planar model.
    uniform_over_seeds : dict of str to SeedSpread
        The scores with every azimuth weighed alike (only the lapse fitted).
    uniform_against_final : PairedComparison
        That model against the planar final model.
    member_overturns : tuple of int
        Records each member overturns [count], in :meth:`EngineEnsemble.members` order.
    flip_share : float
        Share of records whose runs disagree [-]: the spread the unrecorded azimuth and friction leave.
    failed_runs : int
        Runs of the ensemble that failed [count] (their records scored on the other members).
    wall_s : float
        Wall time of the ensemble's runs [s] (cached runs read back).
    """

    ensemble: EngineEnsemble
    azimuths: tuple[float, ...]
    lapse: float
    fold_agreement: float
    scores: OutcomeScores
    over_seeds: dict[str, SeedSpread]
    against_final: PairedComparison
    against_plain: PairedComparison
    judgement: OutcomeJudgement
    uniform_over_seeds: dict[str, SeedSpread]
    uniform_against_final: PairedComparison
    member_overturns: tuple[int, ...]
    flip_share: float
    failed_runs: int
    wall_s: float


@dataclass(frozen=True)
class ScoringRuns:
    """What an engine model is scored beside: the records' outcomes and groups, every repeat's folds, the planar
    plain and final models (their held-out P per repeat) and the baselines' held-out P on the same folds."""

    y: np.ndarray
    groups: np.ndarray
    fold_of: list
    seed: int
    plain: OutcomeStep
    final: OutcomeStep
    baseline_p: dict
    baseline_skill: bool


def score_engine_model(
    campaign: Campaign,
    ensemble: EngineEnsemble,
    records: Sequence,
    tables,
    runs: ScoringRuns,
    options: RunOptions | None = None,
    say: Callable[[str], None] | None = None,
) -> EngineModelScore:
    """``ensemble`` run on ``records`` (:func:`engine_table`) and scored as an outcome model on the folds of every
    repeat of ``runs``, beside the planar models and the baselines scored on the same folds."""
    say = say or (lambda line: None)
    table, wall = engine_table(campaign, ensemble, records, options, say)
    azimuth = np.array(ensemble.member_azimuths)
    t = replace(tables, engines={**tables.engines, ensemble.engine: EngineRuns(table, azimuth)})
    y, groups = runs.y, runs.groups
    fitted, uniform = ENGINE_PREFIX + ensemble.engine, ENGINE_PREFIX + ensemble.engine + UNIFORM
    cv = [cross_validate(fitted, t, y, fold) for fold in runs.fold_of]
    p_rep = np.array([p for p, _q, _fq in cv])
    params = cv[0][1]
    chosen = [q["azimuths"] for _p, _q, fq in cv for q in fq]
    u_rep = np.array([cross_validate(uniform, t, y, fold)[0] for fold in runs.fold_of])
    p = p_rep.mean(axis=0)
    floor = outcome_floor(p, y, seed=runs.seed)
    share = np.nanmean(table, axis=1)
    score = EngineModelScore(
        ensemble=ensemble,
        azimuths=tuple(params["azimuths"]),
        lapse=float(params["lapse"]),
        fold_agreement=float(np.mean([c == params["azimuths"] for c in chosen])),
        scores=outcome_scores(p, y, groups=groups, seed=runs.seed),
        over_seeds=seed_spread([point_scores(q, y) for q in p_rep]),
        against_final=compare_log_loss(p_rep, runs.final.p_repeats, y, groups),
        against_plain=compare_log_loss(p_rep, runs.plain.p_repeats, y, groups),
        judgement=judge_outcome_model(p_rep, runs.baseline_p, y, groups, floor, baseline_skill=runs.baseline_skill),
        uniform_over_seeds=seed_spread([point_scores(q, y) for q in u_rep]),
        uniform_against_final=compare_log_loss(u_rep, runs.final.p_repeats, y, groups),
        member_overturns=tuple(int(v) for v in np.nansum(table, axis=0)),
        flip_share=float(np.mean((share > 0.0) & (share < 1.0))),
        failed_runs=int(np.sum(np.isnan(table))),
        wall_s=wall,
    )
    say(
        f"{fitted}: held-out log loss {score.scores.log_loss:.3f} with its orientation fitted "
        f"({', '.join(f'{a:g}' for a in score.azimuths)} deg), {score.uniform_over_seeds['log_loss'].mean:.3f} with "
        f"every azimuth alike (planar final {runs.final.scores.log_loss:.3f})"
    )
    return score
