"""The search of a theta-history campaign: the error ladder, as an immutable :class:`SearchState` advanced by
functions.

:func:`start` makes the plain model the first step; :func:`add_by_hand` adds an effect whatever its
significance; :func:`greedy` runs the rounds through the one forward selection with
:class:`HistoryEvidence` (each :func:`run_round`: every candidate tried by
:func:`housner.scenarios.diagnosis.selection.candidate_trial.try_candidate`, then pairs when none passes) and
:func:`accept` adds the chosen one; :func:`at_full_rate` scores the ladder again on the records as
measured when the search ran on decimated ones. Each returns a new state; what it did is said
through the :class:`housner.scenarios.diagnosis.selection.candidate_trial.TrialSetup`'s ``progress`` and, where a
figure was computed on fewer samples, its ``economies``. The steps of the search are those of
``docs/explanation/diagnosis.md``, "The search, step by step".
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

from housner.scenarios.diagnosis.economies import StepNotSignificant, ThinnedSearch
from housner.scenarios.diagnosis.results import Candidate, Step, names_label
from housner.scenarios.diagnosis.selection.candidate_trial import (
    CurrentModel,
    Trial,
    TrialSetup,
    compatible,
    fit_records,
    fmt_params,
    held_text,
    judged_candidate,
    rank_key,
    try_candidate,
    try_pairs,
)
from housner.scenarios.diagnosis.selection.crossval import CVModel, add_to_folds, refit_folds
from housner.scenarios.diagnosis.selection.fitting import build_model, effect_objective, fit_effect, joint_refit
from housner.scenarios.diagnosis.selection.forward_selection import Round, forward_selection
from housner.scenarios.diagnosis.selection.paired_test import PRACTICAL, judge, sem
from housner.scenarios.diagnosis.selection.reasons import Reason
from housner.scenarios.diagnosis.selection.record_scoring import SEARCH_RATE, NonFiniteHistory

__all__ = [
    "GreedyRounds",
    "HistoryEvidence",
    "SearchState",
    "accept",
    "add_by_hand",
    "at_full_rate",
    "greedy",
    "run_round",
    "start",
]


@dataclass(frozen=True)
class SearchState:
    """The search at one moment: the ladder so far and the current model, on one version of the records.

    Attributes
    ----------
    current : CurrentModel
        The model the next candidates are tried on (the ladder's last step).
    plain : CurrentModel
        The plain Housner model (no fitted parameter: its out-of-fold errors are its plain errors).
    noise_loss : float
        The training loss of the sensor noise alone [alpha].
    steps : tuple of Step
        The error ladder: the plain model, then each added effect.
    step_models : tuple of CVModel
        Each step's cross-validated fit (:func:`at_full_rate` scores them again).
    step_levels : tuple of float
        The level each step was judged at [-] (NaN for the plain model).
    """

    current: CurrentModel
    plain: CurrentModel
    noise_loss: float
    steps: tuple[Step, ...]
    step_models: tuple[CVModel, ...]
    step_levels: tuple[float, ...]

    def with_step(self, step: Step, model: CVModel, level: float, current: CurrentModel) -> SearchState:
        """The state with ``step`` (its fit ``model``, judged at ``level``) on the ladder and ``current`` now."""
        return replace(
            self,
            current=current,
            steps=(*self.steps, step),
            step_models=(*self.step_models, model),
            step_levels=(*self.step_levels, level),
        )


@dataclass(frozen=True)
class GreedyRounds:
    """What the greedy rounds found (:func:`greedy`).

    Attributes
    ----------
    rounds : list of list of Candidate
        Every round, best first.
    selected : list of str
        The effects the search added, in order.
    first_level : float
        The per-test level of the first round [-].
    first_unsearched : bool
        Whether the first round was not searched: the training error was already at the sensor noise.
    """

    rounds: list[list[Candidate]]
    selected: list[str]
    first_level: float
    first_unsearched: bool = False


def _step(effects, added, *, by_hand: bool, train_error: float, held, judged=None, significant: bool) -> Step:
    """A rung of the ladder from its out-of-fold errors ``held`` [alpha] and its paired fall ``judged`` (None: the
    plain model, which has none)."""
    return Step(
        effects=tuple(effects),
        added_effects=tuple(added),
        by_hand=by_hand,
        train_error=train_error,
        heldout_error=float(held.mean()),
        heldout_se=sem(held),
        improvement=math.nan if judged is None else judged.improvement,
        improvement_se=math.nan if judged is None else judged.improvement_se,
        significant=significant,
        heldout_errors=held,
    )


def start(setup: TrialSetup) -> SearchState:
    """The plain model: the baseline step, and the current model."""
    every, folds = setup.scorers.every_record, setup.cv.folds
    plain_errors = every.errors([])
    # the loss of these errors: not simulated again; no fitted parameter: out-of-fold errors are the plain errors
    plain = CurrentModel(CVModel([], [[] for _ in range(folds.count)]), plain_errors.copy(), every.weigh(plain_errors))
    held = plain.heldout_errors
    baseline = _step((), (), by_hand=False, train_error=plain.train_loss, held=held, significant=False)
    setup.progress(
        f"baseline: held-out error {baseline.heldout_error:.4f} +- {baseline.heldout_se:.4f} alpha "
        f"(sigma/alpha {setup.cv.noise_floor:.4f}); {folds.count}-fold cross-validation"
    )
    return SearchState(
        current=plain,
        plain=plain,
        noise_loss=every.noise_loss(),
        steps=(baseline,),
        step_models=(plain.model,),
        step_levels=(math.nan,),
    )


def add_by_hand(setup: TrialSetup, state: SearchState, name: str) -> SearchState:
    """``state`` with effect ``name`` added whatever its significance (``add`` of the diagnosis).

    Raises :class:`NonFiniteHistory` naming ``name`` and the first record when the model with it
    gives a non-finite theta history (anywhere in its fit).
    """
    model = state.current.model
    reason = compatible(setup.cv.campaign, build_model(model.full), name)
    if reason:
        raise ValueError(f"cannot add {name!r} to {list(model.names) or 'the plain model'}: {reason}")
    try:
        return _add_by_hand(setup, state, name)
    except NonFiniteHistory as e:
        on = f" on top of {', '.join(model.names)}" if model.full else ""
        raise NonFiniteHistory(
            f"effect {name!r}, added by hand{on}, gives a non-finite theta history on record {e.record!r}: "
            "the model is refused before any score",
            e.effects,
            e.record,
        ) from e


def _add_by_hand(setup: TrialSetup, state: SearchState, name: str) -> SearchState:
    """:func:`add_by_hand`'s work: the fit, the joint refit, the fold refits and the step."""
    cv, every, model = setup.cv, setup.scorers.every_record, state.current.model
    fit_scorer, fit_train = fit_records(setup, [*model.names, name])
    params, _train, _n = fit_effect(
        name, effect_objective(fit_scorer, build_model(model.full), []), cv.specimen, pinned=cv.pinned
    )
    with_it = add_to_folds(cv, model, name, params, fit_train)
    full, train_loss = joint_refit(with_it.full, fit_scorer, cv.specimen, pinned=cv.pinned)
    if fit_scorer is not every:
        train_loss = every.loss(build_model(full))  # the training error on every record
    with_it = refit_folds(cv, CVModel(full, with_it.folds), fit_train)
    held = setup.scorers.out_of_fold(with_it)
    level = setup.level_for(1)
    judged = judge(state.current.heldout_errors, held, level, cv.noise_floor)
    step = _step(
        with_it.full,
        (name,),
        by_hand=True,
        train_error=train_loss,
        held=held,
        judged=judged,
        significant=judged.significant,
    )
    setup.progress(f"+ {name} (by hand) {fmt_params(params)}: held-out error {held.mean():.4f}")
    return state.with_step(step, with_it, level, CurrentModel(with_it, held, train_loss))


@dataclass(frozen=True)
class HistoryEvidence:
    """Theta histories as the evidence of the forward selection
    (:func:`housner.scenarios.diagnosis.selection.forward_selection.forward_selection`): candidates fitted on the
    records' time-history error and judged on their out-of-fold errors (``docs/explanation/diagnosis.md``, "The
    search, step by step", steps 2-5).

    Attributes
    ----------
    setup : TrialSetup
    candidates : tuple of str
        The effects the search may add.
    pairs : bool
        Try pairs when no single effect passes.
    """

    setup: TrialSetup
    candidates: tuple[str, ...]
    pairs: bool

    def pool(self, state: SearchState, number: int) -> tuple[str, ...]:
        """The candidates not in the current model that can be combined with it."""
        model = state.current.model
        campaign = self.setup.cv.campaign
        return tuple(
            n for n in self.candidates if n not in model.names and not compatible(campaign, build_model(model.full), n)
        )

    def not_searched(self, state: SearchState, rnd: Round) -> list[Candidate] | None:
        """The round's candidates, not searched, when the training error is already at the sensor noise."""
        setup = self.setup
        margin = PRACTICAL * setup.cv.noise_floor
        train_loss = state.current.train_loss
        if train_loss - state.noise_loss > margin:
            return None
        why = Reason("at_noise", {"train": train_loss, "margin": margin, "noise": state.noise_loss})
        level = setup.level_for(len(rnd.pool))
        setup.progress(f"round {rnd.number}: {why.line()}")
        return [
            judged_candidate(setup, state.current, (n,), {}, rnd.number, math.nan, level, reason=why) for n in rnd.pool
        ]

    def run(self, state: SearchState, rnd: Round) -> tuple[list[Candidate], Trial | None]:
        return run_round(self.setup, state, rnd.number, list(rnd.pool), self.setup.level_for(len(rnd.pool)), self.pairs)

    def accept(self, state: SearchState, rnd: Round, chosen: Trial) -> SearchState:
        return accept(self.setup, state, chosen, self.setup.level_for(len(rnd.pool)))

    def effects(self, chosen: Trial) -> tuple[str, ...]:
        return tuple(chosen.effects)


def greedy(
    setup: TrialSetup, state: SearchState, candidates: list[str], max_effects: int, pairs: bool
) -> tuple[SearchState, GreedyRounds]:
    """The search's rounds through the one forward selection (:mod:`housner.scenarios.diagnosis.diagnose`'s module
    docstring, step 5): the state they end in, and what they found."""
    state, found = forward_selection(HistoryEvidence(setup, tuple(candidates), pairs), state, max_effects)
    first_level = setup.level_for(len(found.pools[0]) if found.pools else len(candidates))
    return state, GreedyRounds(
        found.rounds, found.selected, first_level, found.stopped_unsearched and len(found.rounds) == 1
    )


def run_round(
    setup: TrialSetup, state: SearchState, round_no: int, pool: list[str], test_level: float, pairs: bool
) -> tuple[list[Candidate], Trial | None]:
    """Every candidate of ``pool`` tried (then pairs, when none passes): the round, best first, and its choice."""
    trials: list[Trial] = []
    for name in pool:
        t0 = time.perf_counter()
        trial = try_candidate(setup, state.current, name, round_no, test_level)
        trials.append(trial)
        c = trial.candidate
        held = held_text(c, trial.model is not None)
        setup.progress(
            f"round {round_no}: {name:32s} {fmt_params(c.params):40s} {held} ({time.perf_counter() - t0:.1f} s)"
        )
    trials.sort(key=lambda t: rank_key(t.candidate))
    if trials[0].candidate.significant:
        return [t.candidate for t in trials], trials[0]
    chosen = None
    if pairs:
        tried = try_pairs(setup, state.current, trials, setup.level_for(len(pool) + 3))
        trials.extend(tried)
        trials.sort(key=lambda t: rank_key(t.candidate))
        good = sorted((t for t in tried if t.candidate.significant), key=lambda t: -t.candidate.improvement)
        if good:
            chosen = good[0]
    return [t.candidate for t in trials], chosen


def accept(setup: TrialSetup, state: SearchState, trial: Trial, test_level: float) -> SearchState:
    """``state`` with the chosen ``trial`` added: all parameters refitted jointly, a new step of the ladder."""
    cv, every = setup.cv, setup.scorers.every_record
    fit_scorer, fit_train = fit_records(setup, list(trial.model.names))
    full, train_loss = joint_refit(trial.model.full, fit_scorer, cv.specimen, pinned=cv.pinned)
    if fit_scorer is not every:
        train_loss = every.loss(build_model(full))  # the training error on every record
    with_it = refit_folds(cv, CVModel(full, trial.model.folds), fit_train)
    held = setup.scorers.out_of_fold(with_it)
    judged = judge(state.current.heldout_errors, held, test_level, cv.noise_floor)
    label = names_label(trial.effects)
    step = _step(
        with_it.full, trial.effects, by_hand=False, train_error=train_loss, held=held, judged=judged, significant=True
    )
    setup.progress(f"+ {label}: held-out error {held.mean():.4f} +- {sem(held):.4f} alpha")
    return state.with_step(step, with_it, test_level, CurrentModel(with_it, held, train_loss))


def at_full_rate(setup: TrialSetup, state: SearchState) -> tuple[TrialSetup, SearchState]:
    """The setup and the ladder on the records as measured, when the search ran on decimated ones.

    Each step keeps the search's fits; its training error, its out-of-fold errors and its paired
    fall from the step before are taken again on every sample and judged again at its round's
    level (a step the search took whose fall is not significant on every sample is said so in
    ``economies``; it stays in the ladder). ``setup`` and ``state`` themselves are returned when the
    search ran on the records as measured.
    """
    cv = setup.cv
    if cv.decimation == 1 or setup.scorers.rate == "full":
        return setup, state
    rates = sorted({round(1.0 / r.dt, 3) for r in cv.campaign.records})
    rate = f"{rates[0]:g} Hz" if len(rates) == 1 else f"{rates[0]:g}-{rates[-1]:g} Hz"
    full_setup = replace(setup, scorers=cv.full)
    noise_loss = cv.full.every_record.noise_loss()
    steps = _steps_at_full_rate(full_setup, state)
    setup.economies.insert(0, ThinnedSearch(cv.decimation, tuple(float(r) for r in rates), SEARCH_RATE))
    setup.progress(
        f"the ladder on every sample ({rate}): held-out error {steps[0].heldout_error:.4f} -> "
        f"{steps[-1].heldout_error:.4f} alpha"
    )
    plain = replace(state.plain, heldout_errors=steps[0].heldout_errors, train_loss=steps[0].train_error)
    current = replace(state.current, heldout_errors=steps[-1].heldout_errors, train_loss=steps[-1].train_error)
    return full_setup, replace(state, current=current, plain=plain, noise_loss=noise_loss, steps=steps)


def _steps_at_full_rate(full_setup: TrialSetup, state: SearchState) -> tuple[Step, ...]:
    """The ladder's steps scored again on every sample (:func:`at_full_rate`)."""
    every = full_setup.scorers.every_record
    plain_errors = every.errors([])
    steps: list[Step] = []
    previous = plain_errors
    for i, (step, model, level) in enumerate(zip(state.steps, state.step_models, state.step_levels, strict=True)):
        if i == 0:
            held, train_loss = plain_errors.copy(), every.weigh(plain_errors)
            steps.append(_rescored(step, held, train_loss))
        else:
            held, train_loss = full_setup.scorers.out_of_fold(model), every.loss(build_model(model.full))
            judged = judge(previous, held, level, full_setup.cv.noise_floor)
            if step.significant and not judged.significant and not step.by_hand:
                full_setup.economies.append(
                    StepNotSignificant(
                        step=i,
                        added=str(step.added),
                        improvement=float(judged.improvement),
                        improvement_se=float(judged.improvement_se),
                        pvalue=float(judged.pvalue),
                        level=float(level),
                        decimation=full_setup.cv.decimation,
                    )
                )
            steps.append(
                _rescored(
                    step,
                    held,
                    train_loss,
                    improvement=judged.improvement,
                    improvement_se=judged.improvement_se,
                    significant=judged.significant if step.by_hand else step.significant,
                )
            )
        previous = held
    return tuple(steps)


def _rescored(step: Step, held, train_loss: float, **judged) -> Step:
    """``step`` with its training error, its out-of-fold errors ``held`` [alpha] and what ``judged`` gives taken
    again."""
    return replace(
        step,
        train_error=train_loss,
        heldout_error=float(held.mean()),
        heldout_se=sem(held),
        heldout_errors=held,
        **judged,
    )
