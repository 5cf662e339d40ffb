"""Candidate effects tried on top of the current model: fitted, screened, refitted in every fold and judged.

A candidate is fitted to all records (:func:`housner.scenarios.diagnosis.selection.fitting.fit_effect`), then
held out only when its training error falls by more than :data:`PRACTICAL` of the sensor noise, it
does not contradict the free vibrations (:mod:`housner.scenarios.diagnosis.selection.free_vibration_check`) and, on the
records it was fitted to, its fall per record passes the screen (:data:`SCREEN_LEVEL`). Held out, it
is refitted in every fold and judged on its out-of-fold errors against the current model's
(:func:`judge`, a :class:`Judgement`: a one-sided Wilcoxon signed-rank test and the practical margin);
an effect that brings its own kernel must also beat that kernel with its physics faded out. When no
single effect helps, pairs are fitted together (:func:`try_pairs`). A candidate (or pair) whose model
gives a non-finite theta history anywhere in its fit is rejected, with the record named in its
reason (:class:`housner.scenarios.diagnosis.selection.record_scoring.NonFiniteHistory`).

Every trial is a plain function of a :class:`TrialSetup` (the cross-validation and the scorers in use)
and the :class:`CurrentModel` it is tried on; it returns a :class:`Trial`. The greedy search that uses
them is :mod:`housner.scenarios.diagnosis.diagnose`'s.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
from scipy import stats as sps

from housner.effects import Effect, apply_effects, effect_class, make_effect
from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.diagnosis.economies import Economy, MechanicsSubset
from housner.scenarios.diagnosis.results import Candidate, names_label
from housner.scenarios.diagnosis.selection.crossval import (
    FOLD_ITERATIONS,
    CrossValidation,
    CVModel,
    Scorers,
    add_to_folds,
    refit_folds,
)
from housner.scenarios.diagnosis.selection.fitting import (
    build_model,
    effect_objective,
    fit_effect,
    joint_refit,
    param_dims,
)
from housner.scenarios.diagnosis.selection.free_vibration_check import FreeVibrationCheck
from housner.scenarios.diagnosis.selection.paired_test import PRACTICAL, Judgement, judge, sem
from housner.scenarios.diagnosis.selection.reasons import Reason
from housner.scenarios.diagnosis.selection.record_scoring import NonFiniteHistory, Scorer

__all__ = [
    "SCREEN_LEVEL",
    "CurrentModel",
    "Trial",
    "TrialSetup",
    "compatible",
    "fit_records",
    "fmt_params",
    "held_text",
    "at_neutral",
    "judged_candidate",
    "neutral_distance",
    "rank_key",
    "not_finite",
    "try_candidate",
    "try_pairs",
]

#: One-sided level of the training-record screen a candidate passes before its folds are refitted [-].
SCREEN_LEVEL = 0.05


@dataclass(frozen=True)
class CurrentModel:
    """The model candidates are tried on top of.

    Attributes
    ----------
    model : CVModel
        Its fit on all records and in every fold.
    heldout_errors : ndarray
        Its out-of-fold error of every record [alpha].
    train_loss : float
        Its training loss on every record [alpha].
    """

    model: CVModel
    heldout_errors: np.ndarray
    train_loss: float


@dataclass(frozen=True)
class TrialSetup:
    """What every trial of a diagnosis runs on.

    Attributes
    ----------
    cv : CrossValidation
    scorers : Scorers
        The scorers in use (``cv.search`` during the search and the probes).
    free_vibrations : FreeVibrationCheck
        The check a candidate must pass before it is held out.
    level : float
        Family-wise significance level of a round [-].
    economies : list of Economy
        Where the diagnosis subsampled or stopped early: plain sentences, appended as they happen
        (``Diagnosis.settings.economies``).
    progress : callable
        Called with a line of text as the search goes.
    """

    cv: CrossValidation
    scorers: Scorers
    free_vibrations: FreeVibrationCheck
    level: float
    economies: list[Economy]
    progress: Callable[[str], None]

    def level_for(self, tests: int) -> float:
        """The per-test level of a round of ``tests`` tests (Bonferroni) [-]."""
        return self.level / max(tests, 1)


@dataclass(frozen=True)
class Trial:
    """A candidate tried on top of the current model.

    Attributes
    ----------
    candidate : Candidate
    model : CVModel or None
        The model with it, fitted on all records and in every fold (None: it was not held out).
    effects : tuple of str
        The effect it adds, or the two of a pair.
    subset_only : bool
        Its training error was taken on the mechanics grid's subset of records only: not comparable
        with the current model's (:func:`try_pairs` leaves it out).
    """

    candidate: Candidate
    model: CVModel | None
    effects: tuple[str, ...]
    subset_only: bool = False


def compatible(campaign: Campaign, model_effects: list, name: str) -> str:
    """'' if ``name`` can join the model, else the reason."""
    cls = effect_class(name)
    try:
        probe = cls.neutral(campaign.specimen)
    except (ValueError, TypeError):
        probe = None
    if probe is None:
        return ""
    try:
        apply_effects(campaign.specimen, campaign.records[0].motion, [*model_effects, probe])
    except (ValueError, TypeError) as e:
        return str(e)
    if cls.changes_mechanics and any(type(e).changes_mechanics for e in model_effects):
        return "the model already has an effect that replaces the equation of motion"
    for e in model_effects:
        if type(e).changes_mechanics and name in type(e).conflicts:
            return f"cannot be combined with {e.name!r}"
        if cls.changes_mechanics and e.name in cls.conflicts:
            return f"cannot be combined with {e.name!r}"
    return ""


def rank_key(c: Candidate) -> float:
    """Sort key of a round's candidates: the largest improvement first, those without one last."""
    return -c.improvement if math.isfinite(c.improvement) else math.inf


def fmt_params(p: dict) -> str:
    """Parameters as ``k=v`` in a line of progress."""
    return ", ".join(f"{k}={v:.4g}" for k, v in p.items())


def held_text(c: Candidate, held_out: bool = True) -> str:
    """A candidate's held-out result in a line of progress (its reason when it was not held out)."""
    if not held_out:
        return c.reason.line() if c.reason is not None else ""
    return (
        f"held-out {c.heldout_error:.4f} improvement {c.improvement:+.4f} +- {c.improvement_se:.4f} "
        f"{'*' if c.significant else ' '}"
    )


def not_finite(e: NonFiniteHistory) -> Reason:
    """A rejected candidate's reason: its history is not finite on a record."""
    return Reason("rejected_not_finite", {"record": e.record})


def judged_candidate(
    setup: TrialSetup,
    current: CurrentModel,
    effects: tuple[str, ...],
    params: dict,
    round_no: int,
    train_error: float,
    test_level: float,
    heldout: np.ndarray | None = None,
    reason: Reason | None = None,
) -> Candidate:
    """The candidate ``effects`` of round ``round_no``, judged on its out-of-fold errors ``heldout`` against
    the current model's (None: not held out, for ``reason``)."""
    if heldout is None:  # not held out: no figures, and ``reason`` says why
        judged, wins, error, se = Judgement(False, math.nan, math.nan, math.nan, 1.0, reason), None, math.nan, math.nan
    else:
        judged = judge(current.heldout_errors, heldout, test_level, setup.cv.noise_floor)
        wins, error, se = setup.cv.folds.means(current.heldout_errors - heldout), float(heldout.mean()), sem(heldout)
    return Candidate(
        effects=tuple(effects),
        params=params,
        base=current.model.names,
        round=round_no,
        train_error=train_error,
        heldout_error=error,
        heldout_se=se,
        **vars(judged),  # improvement, its se, z, pvalue, significant and reason, under the same names
        heldout_errors=heldout,
        fold_wins=wins,
    )


def _has_mechanics(names: Sequence[str]) -> bool:
    return any(effect_class(n).changes_mechanics for n in names)


def fit_records(setup: TrialSetup, names: Sequence[str]) -> tuple[Scorer, list[Scorer]]:
    """The records a model of effects ``names`` is fitted on: (all, each fold's training records).

    Every record, unless the campaign is ``thinned`` and the model has an effect that replaces the
    equation of motion (:mod:`housner.scenarios.diagnosis.selection.crossval`): then the free vibrations and a
    spread subset of the ground motions (said once in ``economies``).
    """
    sc = setup.scorers
    if not (sc.thinned and _has_mechanics(names)):
        return sc.every_record, sc.fold_train
    if not any(isinstance(e, MechanicsSubset) for e in setup.economies):
        recs, fit = sc.every_record.records, sc.fit.records
        setup.economies.append(
            MechanicsSubset(
                fitted=sum(r.kind != "free_vibration" for r in fit),
                ground_motions=sum(r.kind != "free_vibration" for r in recs),
                fitted_s=float(sum(r.theta.size * r.dt for r in fit if r.kind != "free_vibration")),
                total_s=float(sum(r.theta.size * r.dt for r in recs if r.kind != "free_vibration")),
                grid_records=len(sc.mechanics_grid.records),
            )
        )
    return sc.fit, sc.fit_fold_train


def _fitted_as_mechanics(setup: TrialSetup, names: Sequence[str]) -> bool:
    """Whether the model's new effect is fitted as a mechanics effect is: its grid on the mechanics grid's
    records (a mechanics effect; on a thinned campaign, any effect of a model with one)."""
    if effect_class(names[-1]).changes_mechanics:
        return True
    return setup.scorers.thinned and _has_mechanics(names)


def try_candidate(setup: TrialSetup, current: CurrentModel, name: str, round_no: int, test_level: float) -> Trial:
    """Fit ``name`` on top of the current model and, when it may pass, in every fold.

    A candidate whose model gives a non-finite history on a record is rejected (not held out).
    """
    try:
        return _fit_candidate(setup, current, name, round_no, test_level)
    except NonFiniteHistory as e:
        rejected = judged_candidate(setup, current, (name,), {}, round_no, math.nan, test_level, reason=not_finite(e))
        return Trial(rejected, None, (name,))


def _fit_candidate(setup: TrialSetup, current: CurrentModel, name: str, round_no: int, test_level: float) -> Trial:
    """:func:`try_candidate`'s work: the fit on all records, the screen, the fold refits and the judgement."""
    cv, every = setup.cv, setup.scorers.every_record
    fixed = build_model(current.model.full)
    names = [*current.model.names, name]
    fit_scorer, fit_train = fit_records(setup, names)
    if _fitted_as_mechanics(setup, names):
        start, stopped = _mechanics_start(setup, current, name, fixed, round_no, test_level, fit_scorer)
        if stopped is not None:
            return stopped
        params, train_error, _nev = fit_effect(
            name,
            effect_objective(fit_scorer, fixed, []),
            cv.specimen,
            start=start,
            local_only=True,
            local_iterations=FOLD_ITERATIONS,
            pinned=cv.pinned,
        )
    else:
        # a parameter the localisation measures directly (a sensor offset: the rotation at rest, to
        # microradians) is taken as measured (cv.pinned): a grid over its bounds can find a basin
        # of the wrong sign, a local search a value off by its own tolerance
        params, train_error, _nev = fit_effect(
            name, effect_objective(fit_scorer, fixed, []), cv.specimen, pinned=cv.pinned
        )
    if fit_scorer is not every:
        train_error = every.loss([*fixed, make_effect(name, **params)])  # the training error on every record
    why = _not_held_out(setup, current, name, params, fixed, train_error)
    if why:
        return Trial(
            judged_candidate(setup, current, (name,), params, round_no, train_error, test_level, reason=why),
            None,
            (name,),
        )
    with_it = add_to_folds(cv, current.model, name, params, fit_train)
    heldout = setup.scorers.out_of_fold(with_it)
    cand = judged_candidate(setup, current, (name,), params, round_no, train_error, test_level, heldout)
    cand = _beyond_neutral(setup, cand, with_it, len(current.model.full))
    return Trial(_beyond_kernel(setup, cand, fixed, [(name, params)], heldout, test_level), with_it, (name,))


def _mechanics_start(
    setup: TrialSetup,
    current: CurrentModel,
    name: str,
    fixed: list,
    round_no: int,
    test_level: float,
    fit_scorer: Scorer,
) -> tuple[dict, Trial | None]:
    """Where a mechanics effect's fit starts, or the trial it stays when its basin does not pay.

    10-100x slower kernels: the grid finds the basin on a spread subset of the records, the local
    search then fits on all of them (on ``fit_scorer``'s, :func:`fit_records`).
    """
    cv, sc = setup.cv, setup.scorers
    margin = PRACTICAL * cv.noise_floor
    grid = sc.mechanics_grid
    start, err_grid, _n = fit_effect(name, effect_objective(grid, fixed, []), cv.specimen, pinned=cv.pinned)
    gain_grid = grid.loss(fixed) - err_grid
    if not gain_grid > margin:
        why = Reason("grid_fall_small", {"records": len(grid.records), "fall": gain_grid, "margin": margin})
        cand = judged_candidate(setup, current, (name,), start, round_no, err_grid, test_level, reason=why)
        return start, Trial(cand, None, (name,), subset_only=True)
    # the basin found on the subset must carry over to every record before the (costly) local fit
    on_all = fit_scorer is sc.every_record
    err_fit = fit_scorer.loss([*fixed, make_effect(name, **start)])
    before = current.train_loss if on_all else fit_scorer.loss(fixed)
    if not before - err_fit > margin:
        on = 0 if on_all else len(fit_scorer.records)
        why = Reason("subset_fall_small", {"records": on, "fall": before - err_fit, "margin": margin})
        cand = judged_candidate(setup, current, (name,), start, round_no, err_fit, test_level, reason=why)
        return start, Trial(cand, None, (name,), subset_only=not on_all)
    return start, None


def neutral_distance(specimen, model: CVModel, start: int) -> dict[str, tuple[float, float, float]]:
    """How far each parameter of the effects ``model.full[start:]`` lies from its neutral value, in its own
    uncertainty: ``"name.key"`` -> (fitted value, its neutral value, its grouped-jackknife standard error).

    The folds of the cross-validation are a delete-a-group jackknife: fold k's fit leaves group k out, so the
    standard error of a parameter is sqrt((K - 1) / K sum_k (x_k - mean x)^2) over its K fold refits (Efron &
    Tibshirani 1993, ch. 11). The fold refits start from the fit on all records and stop after
    :data:`FOLD_ITERATIONS` local steps, so this can only understate the spread, never overstate it.
    """
    out = {}
    k = len(model.folds)
    for j in range(start, len(model.full)):
        name, params = model.full[j]
        neutral = {d.key: d.neutral for d in param_dims(name, specimen)}
        for key, value in params.items():
            xs = np.array([float(f[j][1][key]) for f in model.folds], dtype=float)
            se = math.sqrt((k - 1) / k * float(np.sum((xs - xs.mean()) ** 2))) if k > 1 else math.nan
            n = neutral.get(key)
            out[f"{name}.{key}"] = (float(value), math.nan if n is None else float(n), se)
    return out


def at_neutral(distances: dict[str, tuple[float, float, float]], names: Sequence[str]) -> list[str]:
    """The effects of ``names`` whose every parameter lies within one standard error of its neutral value (an
    infinite neutral value, a stiff foundation's, is never within): effects that cannot be told from the plain
    model (:func:`neutral_distance`'s figures)."""
    out = []
    for name in names:
        mine = [v for key, v in distances.items() if key.split(".", 1)[0] == name]
        if mine and all(math.isfinite(n) and abs(x - n) <= se for x, n, se in mine):
            out.append(name)
    return out


def _beyond_neutral(setup: TrialSetup, cand: Candidate, model: CVModel, start: int) -> Candidate:
    """``cand``, not significant when an effect it adds sits within its uncertainty of its neutral value.

    An effect at its neutral value is the plain model: whatever the held-out error does, it is not evidence
    of that effect (issue 51). A significant fall then comes from the fit moving within the noise of its
    parameter, and is said so.
    """
    if not cand.significant:
        return cand
    dist = neutral_distance(setup.cv.specimen, model, start)
    names = [n for n, _p in model.full[start:]]
    idle = at_neutral(dist, names)
    if not idle:
        return cand
    rows = [(key, x, n, se) for key, (x, n, se) in dist.items() if key.split(".", 1)[0] in idle]
    why = Reason("at_neutral", {"params": rows, "fall": cand.improvement})
    return replace(cand, significant=False, reason=why)


def _beyond_kernel(
    setup: TrialSetup, cand: Candidate, fixed: list, members: list, heldout: np.ndarray, test_level: float
) -> Candidate:
    """``cand``, not significant when its gain is its kernel's numerics rather than its physics.

    An effect that brings its own equation of motion (sliding, a flexible foundation) is solved by
    its own kernel, whose numerics differ from the rigid block's as another correct integrator's
    do; on a chaotic record that alone changes the error. So its out-of-fold errors must also
    beat those of the same kernel with the physics faded out (each parameter at the end of its
    fit bounds nearest its neutral value: the highest friction coefficient, the stiffest
    foundation fitted) at the round's level.
    """
    if not cand.significant:
        return cand
    why = _kernel_control(setup, fixed, members, heldout, test_level)
    return replace(cand, significant=False, reason=why) if why else cand


def _faded_params(name: str, specimen) -> dict:
    """Effect ``name``'s parameters with its physics faded out (:func:`_kernel_control`)."""
    cls = effect_class(name)
    faded = {}
    for d in param_dims(name, specimen):
        n = d.neutral
        if cls.changes_mechanics:
            faded[d.key] = d.hi if n is None or n >= d.hi else (d.lo if n <= d.lo else n)
        else:
            base = n if n is not None and math.isfinite(n) else d.lo
            faded[d.key] = min(max(base + 1e-6 * (d.hi - d.lo), d.lo), d.hi)
    return faded


def _kernel_control(
    setup: TrialSetup, fixed: list, members: list, heldout: np.ndarray, test_level: float
) -> Reason | None:
    """None when ``members`` (name, params) beat their own kernel with their physics faded out, else why not.

    A mechanics effect fades at the end of its fit bounds nearest its neutral value (its own kernel
    stays in use); an effect that brings kernel terms (a probe, a user's term) fades to a millionth
    of its range off its neutral value, so that the terms' kernel stays in use too.
    """
    for k, (name, _params) in enumerate(members):
        cls = effect_class(name)
        uses_terms = cls.terms is not Effect.terms
        if not (cls.changes_mechanics or (uses_terms and not cls.fast_path)):
            continue
        faded = _faded_params(name, setup.cv.specimen)
        control = [*fixed, *[make_effect(m, **(faded if i == k else p)) for i, (m, p) in enumerate(members)]]
        judged = judge(setup.scorers.every_record.errors(control), heldout, test_level, setup.cv.noise_floor)
        if not judged.significant:
            return Reason("kernel_numerics", {"effect": name, "faded": faded, "p": judged.pvalue})
    return None


def _not_held_out(
    setup: TrialSetup, current: CurrentModel, name: str, params: dict, fixed: list, train_error: float
) -> Reason | None:
    """Why a candidate fitted on all records is not held out (None when it is)."""
    margin = PRACTICAL * setup.cv.noise_floor
    gain = current.train_loss - train_error
    if not gain > margin:
        return Reason("training_fall_small", {"fall": gain, "margin": margin})
    bad = setup.free_vibrations.reason([*fixed, make_effect(name, **params)])
    if bad:
        return bad
    # The screen (docs/explanation/diagnosis.md, "The search, step by step", step 4): on the records it
    # was fitted to, the effect does at least as well as out of fold (in expectation); when even there
    # its fall per record is not significant at SCREEN_LEVEL, or below the practical margin, the fold
    # refits (5 more fits, the costliest part for a mechanics effect) cannot pass and are not run. (The
    # training loss weighs the free vibrations as a group, so it can fall while the mean per record
    # does not.)
    falls = current.heldout_errors - setup.scorers.every_record.errors([*fixed, make_effect(name, **params)])
    mean_fall = float(np.mean(falls))
    if not mean_fall > margin:
        return Reason("fitted_fall_small", {"fall": mean_fall, "margin": margin})
    nonzero = falls[falls != 0.0]
    p_fitted = float(sps.wilcoxon(nonzero, alternative="greater").pvalue) if nonzero.size >= 2 else 1.0
    if p_fitted > SCREEN_LEVEL:
        return Reason("fitted_within_uncertainty", {"p": p_fitted, "level": SCREEN_LEVEL})
    return None


def try_pairs(setup: TrialSetup, current: CurrentModel, trials: Sequence[Trial], test_level: float) -> list[Trial]:
    """The pairs among the three candidates that lowered the training error most, fitted together."""
    # Only candidates that lowered the training error by more than the noise floor pair up:
    # the others are fitting noise (and cost time). A mechanics candidate stopped on the grid's
    # subset of records did not (its fall there was below the margin); its error there is on other
    # records than the current model's, so it is not compared with it.
    limit = current.train_loss - PRACTICAL * setup.cv.noise_floor
    helped = sorted(
        (t.candidate for t in trials if t.candidate.train_error < limit and not t.subset_only),
        key=lambda c: c.train_error,
    )
    fixed = build_model(current.model.full)
    out = []
    for first, second in ((0, 1), (0, 2), (1, 2)):
        if second >= len(helped):
            continue
        a, b = helped[first], helped[second]
        if compatible(setup.cv.campaign, [*fixed, make_effect(a.effect, **a.params)], b.effect):
            continue
        try:
            out.append(_pair(setup, current, a, b, test_level))
        except NonFiniteHistory as e:
            pair, why = (a.effect, b.effect), not_finite(e)
            setup.progress(f"round {a.round}: {names_label(pair):32s} {why.line()} (pair)")
            rejected = judged_candidate(setup, current, pair, {}, a.round, math.nan, test_level, reason=why)
            out.append(Trial(rejected, None, pair))
    return out


def _fit_given(setup: TrialSetup, name: str, before: list, after: list, fit_scorer: Scorer) -> dict:
    """Effect ``name`` fitted between the effects ``before`` and ``after`` on ``fit_scorer``'s records; on a
    thinned campaign a model with a mechanics effect finds its basin on the mechanics grid's records first."""
    cv = setup.cv
    if fit_scorer is setup.scorers.every_record:
        return fit_effect(name, effect_objective(fit_scorer, before, after), cv.specimen, pinned=cv.pinned)[0]
    start, _e, _n = fit_effect(
        name, effect_objective(setup.scorers.mechanics_grid, before, after), cv.specimen, pinned=cv.pinned
    )
    return fit_effect(
        name,
        effect_objective(fit_scorer, before, after),
        cv.specimen,
        start=start,
        local_only=True,
        local_iterations=FOLD_ITERATIONS,
        pinned=cv.pinned,
    )[0]


def _pair(setup: TrialSetup, current: CurrentModel, a: Candidate, b: Candidate, test_level: float) -> Trial:
    """Candidates ``a`` and ``b`` fitted together on top of the current model, and judged."""
    cv, every = setup.cv, setup.scorers.every_record
    n_before = len(current.model.full)
    pair = (a.effect, b.effect)
    fixed = build_model(current.model.full)
    fit_scorer, fit_train = fit_records(setup, [*current.model.names, *pair])
    # Two starts, each effect's own fit with the other fitted given it, then both together from
    # each (the joint optimum of correlated parameters lies along a narrow valley that a single
    # local search from one start often misses); the model's own effects keep their parameters.
    params_b = _fit_given(setup, b.effect, [*fixed, make_effect(a.effect, **a.params)], [], fit_scorer)
    params_a = _fit_given(setup, a.effect, fixed, [make_effect(b.effect, **b.params)], fit_scorer)
    starts = ([(a.effect, a.params), (b.effect, params_b)], [(a.effect, params_a), (b.effect, b.params)])
    tries = [
        joint_refit([*current.model.full, *s], fit_scorer, cv.specimen, 30, free_from=n_before, pinned=cv.pinned)
        for s in starts
    ]
    both, train_error = min(tries, key=lambda x: x[1])
    if fit_scorer is not every:
        train_error = every.loss(build_model(both))  # the training error on every record
    params = {f"{n}.{k}": v for n, p in both[n_before:] for k, v in p.items()}
    bad = setup.free_vibrations.reason(build_model(both))
    if bad:
        return Trial(
            judged_candidate(setup, current, pair, params, a.round, train_error, test_level, reason=bad), None, pair
        )
    with_both = refit_folds(
        cv, CVModel(both, [[*f, *both[n_before:]] for f in current.model.folds]), fit_train, free_from=n_before
    )
    heldout = setup.scorers.out_of_fold(with_both)
    cand = judged_candidate(setup, current, pair, params, a.round, train_error, test_level, heldout)
    cand = _beyond_neutral(setup, cand, with_both, n_before)
    cand = _beyond_kernel(setup, cand, fixed, both[n_before:], heldout, test_level)
    setup.progress(f"round {a.round}: {names_label(pair):32s} {fmt_params(params):40s} {held_text(cand)} (pair)")
    return Trial(cand, with_both, pair)
