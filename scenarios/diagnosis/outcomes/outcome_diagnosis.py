"""Outcome records: predict P(overturn) from an ensemble, find the effect the outcomes need, judge it against the
baselines and the floor. :func:`diagnose_outcomes` runs the mission loop on a campaign's outcome records: the
plain model (:mod:`housner.scenarios.diagnosis.outcomes.outcome_models`), where it fails, the effective contact
``contact_inside`` and every library effect the records can feel
(:mod:`housner.scenarios.diagnosis.outcomes.outcome_effects`), each fitted on the log loss and added by a
one-sided Diebold-Mariano test, on folds that keep each ground motion's records together, repeated over fold
seeds; then the verdict (:mod:`housner.scenarios.diagnosis.outcomes.outcome_validation`). The method step by step
is in ``docs/explanation/diagnosis.md`` ("Outcome records").

References
----------
Diebold, F. X., Mariano, R. S. (1995). Comparing predictive accuracy. Journal of
Business & Economic Statistics 13(3), 253-263.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.campaigns.campaign_records import OutcomeRecord
from housner.scenarios.diagnosis.outcomes.engine_ensemble import EngineEnsemble, ScoringRuns, score_engine_model
from housner.scenarios.diagnosis.outcomes.outcome_effects import outcome_effects
from housner.scenarios.diagnosis.outcomes.outcome_models import (
    Geometry,
    OverturnTables,
    cross_validate,
    overturn_tables,
)
from housner.scenarios.diagnosis.outcomes.outcome_results import (
    Miss,
    MissBand,
    OutcomeCandidate,
    OutcomeDiagnosis,
    OutcomeGeometry,
    OutcomeMisses,
    OutcomeRepeats,
    OutcomeStep,
)
from housner.scenarios.diagnosis.outcomes.outcome_scores import (
    OutcomeScores,
    calibration_table,
    outcome_floor,
    outcome_scores,
    point_scores,
    seed_spread,
)
from housner.scenarios.diagnosis.outcomes.outcome_transfer import FrozenOutcomeModel, transfer_outcomes
from housner.scenarios.diagnosis.outcomes.outcome_validation import (
    BASELINES,
    REPEATS,
    baseline_fit,
    baseline_oof,
    baselines_show_skill,
    compare_log_loss,
    grouped_folds,
    judge_outcome_model,
    repeat_seeds,
)
from housner.scenarios.diagnosis.selection.forward_selection import Round, forward_selection
from housner.scenarios.diagnosis.verdict.status import status_rule
from housner.scenarios.execution.options import RunOptions
from housner.units import G

__all__ = [
    "CONTACT",
    "LEVEL",
    "OutcomeEvidence",
    "diagnose_outcomes",
]

#: Family-wise level of the test that adds an effect [-].
LEVEL = 0.05
#: The outcome records' own effect: a contact inside the footprint (a convex or uneven base), an effective alpha
#: with its spread; it pairs with restitution (its tables hold both).
CONTACT = "contact_inside"


# ----------------------------------------------------------------------------
# where it fails
def _misses(step: OutcomeStep, ids, y, pga, pgv) -> list[Miss]:
    pred = step.p >= 0.5
    out = []
    for i in np.flatnonzero(pred != y):
        out.append(
            Miss(
                model=step.name,
                id=ids[i],
                observed="overturned" if y[i] else "stood",
                predicted_p=float(step.p[i]),
                pga_g=float(pga[i] / G),
                pgv_over_pga_s=float(pgv[i] / pga[i]),
            )
        )
    return out


def _pointer(step: OutcomeStep, y, pga, pgv, geo: Geometry) -> OutcomeMisses:
    """The plain model's misses at P = 0.5, counted over thirds of the records' PGV/PGA, and the overturns below the
    block's static threshold (which the input contradicts)."""
    pred = step.p >= 0.5
    fn = ~pred & y
    fp = pred & ~y
    ratio = pgv / pga
    edges = np.percentile(ratio, [100 / 3, 200 / 3])
    band = np.searchsorted(edges, ratio)
    bands = tuple(
        MissBand(name, int(np.sum(fn & (band == k))), int(np.sum(fp & (band == k))))
        for k, name in enumerate(("short", "middle", "long"))
    )
    b_low = min(geo.bracket["pos"][0], geo.bracket["neg"][0], geo.b_pos, geo.b_neg)
    threshold = b_low / geo.h  # tan(alpha) of the smallest alpha: the uplift threshold in g
    below = int(np.sum(y & (pga < threshold * G)))
    return OutcomeMisses(int(fn.sum()), int(fp.sum()), bands, below, float(threshold))


# ----------------------------------------------------------------------------
def diagnose_outcomes(
    campaign: Campaign,
    *,
    folds: int = 5,
    seed: int = 0,
    repeats: int = REPEATS,
    model: FrozenOutcomeModel | None = None,
    effects: Sequence[str] | None = None,
    engine_model: EngineEnsemble | None = None,
    run_options: RunOptions | None = None,
    progress: Callable[[str], None] | None = None,
) -> OutcomeDiagnosis:
    """The mission loop on a campaign's outcome records: plain model, misses, effect, error falling, verdict.

    Parameters
    ----------
    campaign : Campaign
        With outcome records (:attr:`Campaign.outcomes`): the table motion and overturned or not.
    folds : int
        Cross-validation folds [-] (at least 2), stratified by outcome, each ground motion's records (the
        campaign's groups) in one fold; the model and the baselines share them.
    seed : int
        Seed of the first repeat's folds (the others follow it), of the bootstrap intervals and of the simulated
        floor.
    repeats : int
        Repeats of the cross-validation, each on its own folds [-]: each runs the forward selection; the final
        model is the one most of them end in, and every score is given over them.
    model : FrozenOutcomeModel, optional
        A model fitted on another campaign, scored frozen on this one (the transfer).
    effects : sequence of str, optional
        The library effects searched, by registry name (default every one; an empty sequence searches none, not
        even the effective contact). Those the records cannot feel are left out with their reason.
    engine_model : EngineEnsemble, optional
        A 3D engine's ensemble (:func:`~housner.scenarios.diagnosis.outcomes.engine_ensemble.engine_ensemble`), run
        on the records and scored as an outcome model on the same folds, beside the planar final model.
    run_options : RunOptions, optional
        How the engine's runs execute (workers, cache); the default runner's otherwise.
    progress : callable, optional
        Receives one line per stage.

    Returns
    -------
    OutcomeDiagnosis

    Raises
    ------
    ValueError
        Fewer than 10 outcome records, or all of one outcome (nothing to score), or more folds than the
        smaller class has records.
    """
    say = progress or (lambda line: None)
    t_start = time.perf_counter()
    recs, y, folds = _checked_outcomes(campaign, folds)
    ids = [r.id for r in recs]
    pga = np.array([r.pga for r in recs])
    pgv = np.array([r.pgv for r in recs])
    motions = [r.motion for r in recs]
    geo = Geometry.of(campaign)
    groups = np.asarray(campaign.outcome_groups)
    seeds = repeat_seeds(seed, repeats)
    fold_of = [grouped_folds(y, groups, folds, s) for s in seeds]
    say(
        f"{len(recs)} outcome records ({int(y.sum())} overturned) of {np.unique(groups).size} ground motions; "
        f"{folds} folds stratified by outcome that keep a ground motion's records together, {len(seeds)} repeats; "
        f"block h {geo.h:.4f} m, alpha+ {geo.alpha_pos:.4f}, alpha- {geo.alpha_neg:.4f} rad"
    )
    searched, left_out = outcome_effects(campaign.specimen, effects)
    tables = overturn_tables(motions, geo, campaign.specimen, say, effects=searched)
    rounds = _rounds(tables, effects)
    steps, rep, candidates = _repeated_ladder(tables, y, groups, fold_of, seeds, rounds, say)
    plain, final = steps[0], steps[-1]
    say(f"plain model: held-out log loss {plain.scores.log_loss:.3f}, accuracy {plain.scores.accuracy:.3f}")
    pointer = _pointer(plain, y, pga, pgv, geo)
    say(f"where it fails: {pointer.missed} overturns missed, {pointer.false} predicted that did not happen")
    base_p = {n: np.array([baseline_oof(n, pga, pgv, y, f) for f in fold_of]) for n in BASELINES}
    baselines = {n: outcome_scores(p.mean(axis=0), y, groups=groups, seed=seed) for n, p in base_p.items()}
    floor = outcome_floor(final.p, y, seed=seed)
    shown = baselines_show_skill(base_p, y, groups)
    judged_plain, judged = _judged(plain, final, base_p, y, groups, floor, seed, shown)
    status = status_rule(True, len(steps) > 1, judged_plain.misfit, judged.misfit, judged.powered)
    fits = {n: baseline_fit(n, pga, pgv, y) for n in BASELINES}
    transfer = None
    if model is not None:
        transfer = transfer_outcomes(model, motions, geo, campaign.specimen, y, pga, pgv, groups, seed=seed, say=say)
    engine = None
    if engine_model is not None:
        runs = ScoringRuns(y, groups, fold_of, seed, plain, final, base_p, shown)
        engine = score_engine_model(campaign, engine_model, recs, tables, runs, run_options, say)
    misses = _misses(plain, ids, y, pga, pgv) + (_misses(final, ids, y, pga, pgv) if final is not plain else [])
    diag = OutcomeDiagnosis(
        campaign=campaign.name,
        ids=ids,
        observed=y,
        pga=pga,
        pgv=pgv,
        steps=steps,
        candidates=candidates,
        baselines=baselines,
        baseline_p={n: p.mean(axis=0) for n, p in base_p.items()},
        floor=floor,
        pointer=pointer,
        misses=misses,
        status=status,
        geometry=_geometry_summary(geo),
        folds=folds,
        seed=seed,
        calibration=calibration_table(final.p, y),
        groups=groups,
        repeats=rep,
        baseline_spread={n: seed_spread([point_scores(q, y) for q in p]) for n, p in base_p.items()},
        judgement=judged,
        judgement_plain=judged_plain,
        baseline_fits=fits,
        transfer=transfer,
        engine_model=engine,
        searched=tuple(t.effect for t in tables.effects.values()),
        left_out=(*left_out, *tables.left_out),
    )
    diag.elapsed = time.perf_counter() - t_start
    return diag


def _rounds(tables: OverturnTables, effects) -> tuple[tuple[str, ...], ...]:
    """The candidates of each round: the effective contact and every tabulated library effect, then the contact's
    pair with restitution (the one pair with a table of its own)."""
    if effects is not None and not list(effects):
        return ()
    singles = (CONTACT, *tables.effects)
    pairs = (f"{CONTACT}+restitution",) if "restitution" in tables.effects else ()
    return (singles, pairs) if pairs else (singles,)


def _repeated_ladder(tables, y, groups, fold_of, seeds, rounds, say) -> tuple[list[OutcomeStep], OutcomeRepeats, list]:
    """The forward selection on each repeat's folds; the final model most repeats end in; its ladder scored over
    every repeat (:func:`_over_repeats`); and the first repeat's candidates."""
    runs = []
    for s, fold in zip(seeds, fold_of, strict=True):
        plain_r = _step("plain", None, tables, y, fold, s, groups)
        runs.append(_add_effects(plain_r, tables, y, fold, s, groups, rounds, say))
        say(f"repeat (fold seed {s}): {runs[-1][0][-1].name}")
    rep = _consensus(seeds, runs, rounds[0] if rounds else ())
    say(f"final model: {rep.chosen} ({rep.finals.count(rep.chosen)} of {len(seeds)} repeats)")
    ladder = next(steps for steps, _c, _t in runs if steps[-1].name == rep.chosen)
    steps, prev = [], None
    for rung in ladder:
        prev = _over_repeats(rung.name, prev, runs, tables, y, fold_of, seeds, groups)
        steps.append(prev)
    return steps, rep, runs[0][1]


def _judged(plain: OutcomeStep, final: OutcomeStep, base_p: dict, y, groups, floor, seed: int, shown: bool):
    """The plain and the final model judged (:func:`judge_outcome_model`): an outcome model is a misfit when a
    baseline fitted on the same folds predicts better, when it has no skill over the base rate where the records
    could show one, or when its probabilities fail their floor; the one status rule reads these. ``shown`` is
    :func:`baselines_show_skill` of the baselines (whether the records could show a model's skill)."""
    plain_floor = outcome_floor(plain.p, y, seed=seed)
    judged_plain = judge_outcome_model(plain.p_repeats, base_p, y, groups, plain_floor, baseline_skill=shown)
    if final is plain:
        return judged_plain, judged_plain
    return judged_plain, judge_outcome_model(final.p_repeats, base_p, y, groups, floor, baseline_skill=shown)


def _checked_outcomes(campaign: Campaign, folds: int) -> tuple[list[OutcomeRecord], np.ndarray, int]:
    """The campaign's outcome records, their outcomes (True: overturned) and the number of folds [-], checked:
    ValueError for fewer than 10 records, one outcome only, or folds outside 2 .. records of the smaller outcome."""
    recs: list[OutcomeRecord] = list(campaign.outcomes)
    y = np.array([r.overturned for r in recs], dtype=bool)
    if len(recs) < 10:
        raise ValueError(f"campaign {campaign.name!r}: {len(recs)} outcome records; scoring outcomes needs 10")
    if y.all() or not y.any():
        raise ValueError(
            f"campaign {campaign.name!r}: every record {'overturned' if y.all() else 'stood'}; "
            "scores of outcomes need both"
        )
    folds = int(folds)
    if folds < 2 or folds > min(int(y.sum()), int((~y).sum())):
        raise ValueError(
            f"`folds` must lie in 2 .. {min(int(y.sum()), int((~y).sum()))} (records of the smaller "
            f"outcome), got {folds}"
        )
    return recs, y, folds


def _step(name: str, prev: OutcomeStep | None, tables, y, fold, seed: int, groups) -> OutcomeStep:
    """Model ``name`` cross-validated on the folds of one repeat: its held-out probabilities and scores, and the
    paired fall of the held-out log loss from ``prev`` (none for the first model), clustered by ground motion."""
    p, params, fold_params = cross_validate(name, tables, y, fold)
    if not np.all(np.isfinite(p)):
        raise RuntimeError(f"model {name} gave no probability for {int(np.sum(~np.isfinite(p)))} records")
    fall = (0.0, 0.0, math.nan)
    if prev is not None:
        c = compare_log_loss(p, prev.p, y, groups)
        fall = (c.advantage, c.se, c.p_better)
    return OutcomeStep(name, params, fold_params, p, _quick_scores(p, y), *fall)


def _quick_scores(p, y) -> OutcomeScores:
    """The scores of one repeat's step, without intervals (the reported ladder has them: :func:`_over_repeats`)."""
    return outcome_scores(p, y, n_boot=0)


def _over_repeats(name: str, prev: OutcomeStep | None, runs, tables, y, fold_of, seeds, groups) -> OutcomeStep:
    """Model ``name`` over every repeat's folds (taken from the repeats where its selection tried it, else
    cross-validated anew: a pair is tried only where its first effect was added): its mean held-out probabilities,
    their scores with intervals that resample whole ground motions, each score's mean and range over the repeats,
    and its paired fall from ``prev``. Its fit is the one of the first repeat that tried it (the reported ladder is
    one repeat's own, so one did)."""
    ps = []
    for (_steps, _c, tried), fold in zip(runs, fold_of, strict=True):
        step = tried.get(name)
        ps.append(step.p if step is not None else cross_validate(name, tables, y, fold)[0])
    first = next(tried[name] for _steps, _c, tried in runs if name in tried)
    p_rep = np.array(ps)
    fall = (0.0, 0.0, math.nan)
    if prev is not None:
        c = compare_log_loss(p_rep, prev.p_repeats, y, groups)
        fall = (c.advantage, c.se, c.p_better)
    p_mean = p_rep.mean(axis=0)
    return OutcomeStep(
        name,
        first.params,
        first.fold_params,
        p_mean,
        outcome_scores(p_mean, y, groups=groups, seed=seeds[0]),
        *fall,
        over_seeds=seed_spread([point_scores(q, y) for q in p_rep]),
        p_repeats=p_rep,
    )


def _consensus(seeds, runs, searched) -> OutcomeRepeats:
    """The repeats' final models, the share of repeats that hold each effect searched, and the one most end in."""
    finals = tuple(steps[-1].name for steps, _c, _t in runs)
    effects = sorted({e for f in finals if f != "plain" for e in f.split("+")} | set(searched))
    share = {e: sum(e in f.split("+") for f in finals) / len(finals) for e in effects}
    chosen = max(sorted(set(finals)), key=lambda f: (finals.count(f), -len(f.split("+")) * (f != "plain")))
    return OutcomeRepeats(tuple(int(s) for s in seeds), finals, share, chosen)


@dataclass(frozen=True)
class OutcomeEvidence:
    """Outcomes (overturned or not) as the evidence of the forward selection
    (:func:`housner.scenarios.diagnosis.selection.forward_selection.forward_selection`): each candidate
    cross-validated on the overturn tables, its paired fall of the held-out log loss tested at :data:`LEVEL` over
    the candidates of its round (Bonferroni); the state is the ladder of :class:`OutcomeStep`, the plain model
    first."""

    tables: OverturnTables
    y: np.ndarray
    fold: np.ndarray
    seed: int
    groups: np.ndarray
    rounds: tuple[tuple[str, ...], ...]
    say: Callable[[str], None]

    def pool(self, state: tuple[OutcomeStep, ...], number: int) -> tuple[str, ...]:
        """Round ``number``'s candidates that extend the current model (never re-tries what is in)."""
        if number > len(self.rounds):
            return ()
        return tuple(n for n in self.rounds[number - 1] if _extends(n, state[-1].name))

    def not_searched(self, state, rnd: Round) -> None:
        return None  # outcomes always leave a log loss to lower

    def run(self, state: tuple[OutcomeStep, ...], rnd: Round) -> tuple[list[OutcomeStep], OutcomeStep | None]:
        """Every candidate of the round cross-validated; the chosen one is the lowest held-out log loss among
        those whose fall is significant."""
        cur = state[-1]
        tried = [_step(n, cur, self.tables, self.y, self.fold, self.seed, self.groups) for n in rnd.pool]
        level = LEVEL / max(len(tried), 1)
        for c in tried:
            self.say(
                f"  {c.name}: held-out log loss {c.scores.log_loss:.3f} ({c.improvement:+.3f} "
                f"+- {c.improvement_se:.3f}, p {c.p_value:.2g}) {c.params}"
            )
        good = [c for c in tried if c.improvement > 0 and c.p_value < level]
        return tried, min(good, key=lambda c: c.scores.log_loss) if good else None

    def accept(self, state: tuple[OutcomeStep, ...], rnd: Round, chosen: OutcomeStep) -> tuple[OutcomeStep, ...]:
        return (*state, chosen)

    def effects(self, chosen: OutcomeStep) -> tuple[str, ...]:
        return (chosen.name,)


def _add_effects(
    plain: OutcomeStep, tables, y, fold, seed: int, groups, rounds, say
) -> tuple[list[OutcomeStep], list[OutcomeCandidate], dict[str, OutcomeStep]]:
    """Forward selection from the plain model through the one selection of the diagnosis, with
    :class:`OutcomeEvidence`, on one repeat's folds. Returns the models kept (the plain one first), every candidate
    tried, and every model cross-validated, by name."""
    evidence = OutcomeEvidence(tables, y, fold, seed, groups, rounds, say)
    steps, found = forward_selection(evidence, (plain,), len(rounds))
    candidates = [
        OutcomeCandidate(
            name=c.name,
            log_loss=c.scores.log_loss,
            improvement=c.improvement,
            improvement_se=c.improvement_se,
            p_value=c.p_value,
            added=c.name in found.selected,
            params=c.params,
        )
        for tried in found.rounds
        for c in tried
    ]
    tried = {"plain": plain, **{c.name: c for r in found.rounds for c in r}}
    return list(steps), candidates, tried


def _geometry_summary(geo: Geometry) -> OutcomeGeometry:
    """The block's geometry as the diagnosis reports it, in SI (m, rad, kg m^2, kg)."""
    return OutcomeGeometry(
        h_m=geo.h,
        b_pos_m=geo.b_pos,
        b_neg_m=geo.b_neg,
        alpha_pos_rad=geo.alpha_pos,
        alpha_neg_rad=geo.alpha_neg,
        centroidal_inertia_kgm2=geo.ic,
        mass_kg=geo.mass,
        b_bracket_m={k: (float(v[0]), float(v[1])) for k, v in geo.bracket.items()},
    )


def _extends(name: str, current: str) -> bool:
    """A candidate of the next round adds to the current model (never re-tries what is in)."""
    if current == "plain":
        return True
    return name != current and set(current.split("+")) < set(name.split("+"))
