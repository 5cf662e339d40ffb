"""Which physical effect is missing: fit candidate effects, score them on held-out records, add them greedily.

:func:`diagnose` asks a campaign "what is missing?" of a model with the effect library
(:data:`housner.effects.EFFECTS`) and the analytic engine, running in turn the steps that live beside it
(the folds of :mod:`~housner.scenarios.diagnosis.selection.crossval` and
:mod:`~housner.scenarios.diagnosis.selection.record_scoring`, the fits of
:mod:`~housner.scenarios.diagnosis.selection.fitting`, a candidate's trial in
:mod:`~housner.scenarios.diagnosis.selection.candidate_trial` and
:mod:`~housner.scenarios.diagnosis.selection.free_vibration_check`, the search and its ladder in
:mod:`~housner.scenarios.diagnosis.selection.history_search` through
:mod:`~housner.scenarios.diagnosis.selection.forward_selection`, the results of
:mod:`housner.scenarios.diagnosis.results`), then draws the conclusion: the floors
(:mod:`~housner.scenarios.diagnosis.verdict.correct_model_floor`), the probes and the verdict
(:mod:`~housner.scenarios.diagnosis.verdict.decision`). The method, step by step, and what it costs are in
``docs/explanation/diagnosis.md`` ("The search, step by step", "What a diagnosis costs").
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

from scipy import stats as sps

from housner.effects import available_effects
from housner.errors import unknown_choice
from housner.scenarios.campaigns.campaign import Campaign, load_campaign
from housner.scenarios.diagnosis.comparison.localise import measured_features
from housner.scenarios.diagnosis.comparison.pointers import order_drift
from housner.scenarios.diagnosis.comparison.record_comparison import compare
from housner.scenarios.diagnosis.economies import FloorLoopStopped
from housner.scenarios.diagnosis.results import Candidate, Diagnosis, DiagnosisSettings, Step
from housner.scenarios.diagnosis.selection.candidate_trial import TrialSetup, fmt_params, held_text, try_candidate
from housner.scenarios.diagnosis.selection.crossval import Folds, cross_validation
from housner.scenarios.diagnosis.selection.fitting import build_model
from housner.scenarios.diagnosis.selection.free_vibration_check import FreeVibrationCheck
from housner.scenarios.diagnosis.selection.history_search import (
    GreedyRounds,
    SearchState,
    add_by_hand,
    at_full_rate,
    greedy,
    start,
)
from housner.scenarios.diagnosis.selection.paired_test import PRACTICAL
from housner.scenarios.diagnosis.selection.probes import PROBES, ProbeFinding
from housner.scenarios.diagnosis.selection.record_scoring import DEFAULT_FOLDS, check_finite
from housner.scenarios.diagnosis.sensor_assessment import assess_sensor
from housner.scenarios.diagnosis.verdict.correct_model_floor import N_REPLICAS, Floor, measure_floor
from housner.scenarios.diagnosis.verdict.decision import Verdict, decide
from housner.scenarios.diagnosis.verdict.integrator_families import FAMILIES
from housner.scenarios.diagnosis.verdict.residual_test import RATIO_MISFIT, Z_MISFIT, residual_test

__all__ = [
    "FAMILY_JUMP",
    "LEVEL",
    "MAX_EFFECTS",
    "Conclusion",
    "conclude",
    "diagnose",
    "floor_family",
    "probe",
    "selection_frequency",
]

#: Family-wise significance level of a round of candidates (one-sided, Bonferroni) [-].
LEVEL = 0.05
#: Most effects the greedy search adds [-].
MAX_EFFECTS = 3
#: The floor's family loop measures the widest family second when the narrowest puts the final model's
#: ground motions more than this many times RATIO_MISFIT above their floor [-] (:func:`floor_family`).
FAMILY_JUMP = 2.0


@dataclass(frozen=True)
class Conclusion:
    """What :func:`conclude` draws from the ladder.

    Attributes
    ----------
    verdict : Verdict
    floors : (Floor, Floor)
        The measured correct-model floor of the plain and of the final model.
    steps : tuple of Step
        The ladder, each step with its comparison where it was run.
    family : str
        The family of correct integrators the final model's floor was measured over.
    family_plain : str
        The plain model's (its own family loop: the same model gets the same floor whatever is added).
    """

    verdict: Verdict
    floors: tuple[Floor, Floor]
    steps: tuple[Step, ...]
    family: str
    family_plain: str = ""


def conclude(
    setup: TrialSetup,
    state: SearchState,
    search: tuple[TrialSetup, SearchState],
    *,
    library: list[str],
    selected: list[str],
    compare_steps: bool,
    n_replicas: int,
    seed,
    added: Sequence[str] = (),
    search_ran: str = "ran",
) -> Conclusion:
    """Both ends of the ladder against their measured floors: the verdict and the two floors.

    ``setup`` and ``state`` are on the records as measured, ``search`` the same on the search's (the
    probes run there, as the candidates did). The baseline's and the final model's comparisons always
    run (the verdict's localisation), the other steps' on request; the steps get their comparisons.
    """
    cv, plain, final = setup.cv, state.plain, state.current
    last = len(state.steps) - 1
    comparisons = {
        i: compare(cv.campaign, "housner", build_model(list(state.steps[i].effects)), cv.engine_settings)
        for i in range(len(state.steps))
        if compare_steps or i in (0, last)
    }
    steps = tuple(replace(s, comparison=comparisons[i]) if i in comparisons else s for i, s in enumerate(state.steps))
    seed_int = seed if isinstance(seed, int) else 0
    # Each model's family of correct integrators (housner.scenarios.diagnosis.verdict.integrator_families): the
    # closest to the library's conventions at which its ground motions are at the floor (not a misfit, and within
    # RATIO_MISFIT of it both on the mean, which counts the records chaos carries off, and on the 10 %-trimmed
    # mean, the typical record), the widest when none is. The plain model runs its own loop, so that it gets the
    # same floor whatever is added to it (its floor differs from the final model's anyway: a correct model of
    # other physics leaves another error, as chaos carries its records elsewhere). One yardstick across the
    # ladder: when the plain model is at its floor under a family, the final model's loop starts there, so that
    # an addition never makes the floor narrower and turns a model at its floor into a misfit (issue 51).
    kinds = [r.kind for r in cv.campaign.records]
    setup.progress("measuring the correct-model floor (parametric bootstrap over correct integrators)")
    if not final.model.full:
        family, floor_final, _early, _at = floor_family(
            setup, state, n_replicas, seed_int, kinds, who="the plain model"
        )
        family_plain, floor_plain = family, floor_final
    else:
        family_plain, floor_plain, early, plain_at = floor_family(
            setup, state, n_replicas, seed_int, kinds, model=plain, who="the plain model"
        )
        family, floor_final, _early, _at = floor_family(
            setup,
            state,
            n_replicas,
            seed_int,
            kinds,
            said_before=early,
            narrowest=family_plain if plain_at else None,
        )
    for what, v in (
        ("the plain model's held-out error", plain.heldout_errors),
        ("the final model's held-out error", final.heldout_errors),
        ("the plain model's correct-model floor", floor_plain.mean),
        ("the final model's correct-model floor", floor_final.mean),
    ):
        check_finite(what, v, cv.folds.ids)
    setup.progress(
        f"floor: correct integrators of the family {family!r}"
        + (f" (the plain model: {family_plain!r})" if family_plain != family else "")
    )
    probes = probe(*search)
    mf = measured_features(cv.campaign)
    drift = order_drift(
        [plain.heldout_errors - floor_plain.mean, final.heldout_errors - floor_final.mean],
        (mf.energy_record, mf.energy_amplitude, mf.energy_ratio),
    )
    verdict = decide(
        n_records=len(cv.folds.ids),
        baseline=residual_test(plain.heldout_errors, floor_plain, kinds),
        final=residual_test(final.heldout_errors, floor_final, kinds),
        selected=selected,
        params=dict(final.model.full),
        baseline_cmp=steps[0].comparison,
        final_cmp=steps[-1].comparison,
        library=library,
        added=added,
        drift=drift,
        family=family,
        probes=probes,
        family_plain=family_plain,
        search=search_ran,
    )
    return Conclusion(verdict, (floor_plain, floor_final), steps, family, family_plain)


def floor_family(
    setup: TrialSetup,
    state: SearchState,
    n_replicas: int,
    seed: int,
    kinds: list[str],
    model=None,
    who: str = "the final model",
    said_before: bool = False,
    narrowest: str | None = None,
) -> tuple[str, Floor, bool, bool]:
    """The family of correct integrators of a model's verdict, its floor under it, whether the loop stopped
    early, and whether the model is at its floor under that family.

    ``model`` is the search's current model (default the final one, ``state.current``; the plain model,
    ``state.plain``, runs the same loop), ``who`` names it in ``economies``; ``said_before``: the other model's loop
    stopped early and said why at length (this one's line is then short).
    The families of :data:`FAMILIES` narrowest first, until the model's ground motions are
    at their floor (not a misfit, and within RATIO_MISFIT of it on the mean and on the trimmed
    mean); the widest when at none. Stopped early: when the narrowest family puts them more than
    :data:`FAMILY_JUMP` x RATIO_MISFIT above their floor, the widest is measured next, and when
    they are not at its floor either, the families between are not measured (they are nested:
    each spans the conventions of the narrower ones, so their floors lie below the widest's, and
    the answer, the widest, is the one the whole loop gives); ``economies`` says so. ``narrowest``: the loop
    starts at that family (the plain model's, where the plain model is at its floor under it).
    """
    families = list(FAMILIES)
    if narrowest is not None:
        families = families[families.index(narrowest) :]
    final = state.current if model is None else model
    measured: dict[str, tuple[Floor, bool, float]] = {}

    def measure(family: str) -> tuple[Floor, bool, float]:
        """The final model's floor under ``family``, whether its ground motions are at it, and their ratio."""
        if family not in measured:
            floor = measure_floor(
                setup.scorers.every_record,
                final.model.full or [],
                final.model.folds,
                setup.cv.folds.fold_of,
                n_replicas=n_replicas,
                seed=seed,
                family=family,
            )
            gm = residual_test(final.heldout_errors, floor, kinds).groups.get("ground_motion")
            ratio = math.nan if gm is None else gm.robust_ratio
            measured[family] = (floor, gm is None or not gm.misfit and ratio <= RATIO_MISFIT, ratio)
        return measured[family]

    for i, family in enumerate(families):
        floor, at_floor, ratio = measure(family)
        if at_floor:
            return family, floor, False, True
        if i == 0 and len(families) > 2 and ratio > FAMILY_JUMP * RATIO_MISFIT:
            widest, widest_at_floor, widest_ratio = measure(families[-1])
            if not widest_at_floor:
                setup.economies.append(
                    FloorLoopStopped(
                        "final" if who == "the final model" else "plain",
                        said_before,
                        float(ratio),
                        float(widest_ratio),
                        tuple(families),
                        FAMILY_JUMP,
                        RATIO_MISFIT,
                    )
                )
                setup.progress(
                    f"floor of {who}: not at it under {families[0]!r} ({ratio:.2f}x) nor under "
                    f"{families[-1]!r} ({widest_ratio:.2f}x); the families between not "
                    "measured"
                )
                return families[-1], widest, True, False
    return families[-1], measured[families[-1]][0], False, False


def probe(setup: TrialSetup, state: SearchState) -> list[ProbeFinding]:
    """Physics outside the library tried on top of the final model
    (:mod:`housner.scenarios.diagnosis.selection.probes`).

    Each probe is fitted on top of the final model and judged on its out-of-fold errors like a
    candidate, at the verdict's level (Bonferroni over the probes), and against its kernel with
    its physics faded out; on the search's records (``setup`` and ``state`` at its rate). Returns
    those that lower the error significantly.
    """
    final = state.current
    if final.train_loss - state.noise_loss <= PRACTICAL * setup.cv.noise_floor:
        return []  # nothing above the sensor noise for a probe to take (as a round of the search)
    out = []
    # a significant probe turns the verdict into a misfit: it is held to the verdict's own level,
    # z > Z_MISFIT one-sided (1.3e-3), over the probes (Bonferroni); at the search's 5 % one correct
    # campaign in twenty would be called a misfit
    level = float(sps.norm.sf(Z_MISFIT)) / len(PROBES)
    for name, class_name in PROBES.items():
        trial = try_candidate(setup, final, name, 0, level)  # fitted, screened and judged as a candidate is
        c = trial.candidate
        setup.progress(f"probe {name} {fmt_params(c.params)}: {held_text(c, trial.model is not None)}")
        if c.significant:
            out.append(
                ProbeFinding(
                    probe=name,
                    class_name=class_name,
                    params=c.params,
                    error=float(final.heldout_errors.mean()),
                    error_with=c.heldout_error,
                    improvement=c.improvement,
                    se=c.improvement_se,
                    z=c.z,
                    p=c.pvalue,
                )
            )
    return out


def selection_frequency(folds: Folds, rounds: list[list[Candidate]]) -> dict[str, float]:
    """Effect -> share of the folds in which it was the best candidate of its round [-]."""
    frequency: dict[str, float] = {}
    for r in rounds:
        held_out = [c for c in r if c.fold_wins is not None]
        wins: dict[str, int] = {}
        for k in range(folds.count):
            best = max(held_out, key=lambda c, k=k: c.fold_wins[k], default=None)
            if best is not None and best.fold_wins[k] > 0:
                wins[best.effect] = wins.get(best.effect, 0) + 1
        for c in held_out:
            frequency[c.effect] = max(frequency.get(c.effect, 0.0), wins.get(c.effect, 0) / folds.count)
    return frequency


def diagnose(
    campaign: Campaign | str | Path,
    *,
    effects: Iterable[str] | None = None,
    add: Sequence[str] = (),
    folds: int = DEFAULT_FOLDS,
    seed=0,
    max_effects: int = MAX_EFFECTS,
    level: float = LEVEL,
    engine_settings: dict | None = None,
    compare_steps: bool = True,
    pairs: bool = True,
    n_replicas: int | None = None,
    progress: Callable[[str], None] | None = None,
) -> Diagnosis:
    """Find the physical effect(s) missing from the Housner model of a campaign, and say what remains.

    Parameters
    ----------
    campaign : Campaign or path
        The measurements (a path is read with :func:`housner.scenarios.campaigns.campaign.load_campaign`).
    effects : iterable of str, optional
        Candidate effects (registry names); default every registered effect.
    add : sequence of str
        Effects to add by hand first, in order (fitted, whatever their significance).
    folds : int
        Cross-validation folds K [-]: every record is held out once.
    seed : int
        Seed of the fold assignment (and of the floor's bootstrap).
    max_effects : int
        Most effects the greedy search adds.
    level : float
        Family-wise significance level of each round [-].
    engine_settings : dict, optional
        Settings of the analytic engine (``r``, ``substeps``).
    compare_steps : bool
        Also run the full :func:`housner.scenarios.diagnosis.comparison.record_comparison.compare` for the intermediate
        steps of the ladder
        (the baseline's and the final model's are always run: the verdict needs their localisation).
    pairs : bool
        When no single effect helps significantly, also try the pairs among the three that lowered
        the training error most, fitted jointly.
    n_replicas : int, optional
        Replicas of the floor's parametric bootstrap (default
        :data:`housner.scenarios.diagnosis.verdict.correct_model_floor.N_REPLICAS`).
    progress : callable, optional
        Called with a line of text as the search goes.

    Returns
    -------
    Diagnosis
        With its :class:`housner.scenarios.diagnosis.verdict.decision.Verdict` (the method:
        ``docs/explanation/diagnosis.md``, "The search, step by step" and "The verdict").
    """
    t_start = time.perf_counter()
    if not isinstance(campaign, Campaign):
        campaign = load_campaign(campaign)
    # the sensor first: its noise as measured, its faults masked or corrected
    # (housner.scenarios.diagnosis.sensor_assessment)
    campaign = assess_sensor(campaign, engine_settings)
    candidates = _checked(campaign, effects, add, folds, max_effects, level)
    n_replicas = N_REPLICAS if n_replicas is None else int(n_replicas)
    cv = cross_validation(campaign, folds, seed, engine_settings)
    setup = TrialSetup(
        cv,
        cv.search,
        FreeVibrationCheck(campaign, engine_settings, cv.measured),
        level,
        [],
        progress or (lambda s: None),
    )
    state = start(setup)
    for name in add:
        state = add_by_hand(setup, state, name)
    state, found = greedy(setup, state, candidates, max_effects, pairs)
    full_setup, full_state = at_full_rate(setup, state)
    tried, search_ran = _what_the_search_did(found, candidates)
    end = conclude(
        full_setup,
        full_state,
        (setup, state),
        library=tried,
        selected=found.selected,
        compare_steps=compare_steps,
        n_replicas=n_replicas,
        seed=seed,
        added=list(add),
        search_ran=search_ran,
    )
    settings = DiagnosisSettings(
        effects=tuple(candidates),
        add=tuple(add),
        folds=cv.folds.count,
        seed=seed if isinstance(seed, (int, type(None))) else str(seed),
        max_effects=max_effects,
        level=level,
        practical=PRACTICAL,
        pairs=pairs,
        replicas=n_replicas,
        engine_settings=dict(engine_settings or {}),
        floor_family=end.family,
        floor_family_plain=end.family_plain,
        search=search_ran,
        decimation=cv.decimation,
        economies=tuple(setup.economies),
    )
    diag = _diagnosis(campaign, cv.folds, found, end, list(add), cv.noise_floor, settings)
    diag.elapsed = time.perf_counter() - t_start
    return diag


def _what_the_search_did(found: GreedyRounds, candidates: list[str]) -> tuple[list[str], str]:
    """The effects the search tried, and what it did
    (:class:`housner.scenarios.diagnosis.verdict.decision.VerdictFacts`'s
    ``search``). The library is claimed only where the search tried it: a first round skipped (the training error
    already at the sensor noise) tried no effect, and no round (no candidate: effects=[], or max_effects=0) none."""
    skipped = found.first_unsearched
    tried = candidates if found.rounds and not skipped else []
    return tried, "ran" if tried else "skipped" if skipped else "off" if not candidates else "none_left"


def _diagnosis(
    campaign: Campaign,
    folds: Folds,
    found: GreedyRounds,
    end: Conclusion,
    added: list[str],
    noise_floor: float,
    settings: DiagnosisSettings,
) -> Diagnosis:
    """The :class:`Diagnosis` of the search and its conclusion."""
    verdict = end.verdict
    return Diagnosis(
        campaign=campaign,
        baseline=end.steps[0],
        steps=list(end.steps),
        candidates=found.rounds[0] if found.rounds else [],
        rounds=found.rounds,
        selected=found.selected,
        added=added,
        noise_floor=noise_floor,
        test_level=found.first_level,
        train_ids=folds.ids,
        heldout_ids=folds.ids,
        settings=settings,
        folds=folds.members,
        verdict=verdict,
        floors=end.floors,
        selection_frequency=selection_frequency(folds, found.rounds),
    )


def _checked(campaign: Campaign, effects, add, folds, max_effects, level) -> list[str]:
    """The candidate effects, after checking :func:`diagnose`'s arguments."""
    names_all = available_effects()
    candidates = list(names_all if effects is None else effects)
    for n in [*candidates, *add]:
        if n not in names_all:
            raise unknown_choice("effect", n, names_all)
    if len(set(add)) != len(add):
        raise ValueError(f"`add` names an effect twice: {list(add)}")
    if not (isinstance(max_effects, int) and max_effects >= 0):
        raise ValueError(f"`max_effects` must be a non-negative integer, got {max_effects!r}")
    if not 0.0 < level < 1.0:
        raise ValueError(f"`level` must lie in (0, 1), got {level!r}")
    if not (isinstance(folds, int) and folds >= 2):
        raise ValueError(f"`folds` must be an integer of at least 2, got {folds!r}")
    n = len(campaign.records)
    if n < 4:
        raise ValueError(
            f"campaign {campaign.name!r} has {n} usable record(s); the diagnosis needs at least 4 "
            "(some to fit on, some to judge on)"
        )
    return candidates
