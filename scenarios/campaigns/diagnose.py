"""Which physical effect is missing: fit candidate effects, score them on held-out records, add them greedily.

The question a campaign asks of a model is not only "does it match?" but,
when it does not, "what is missing?". :func:`diagnose` answers it with the
effect library (:data:`housner.effects.EFFECTS`) and the analytic engine:

1. **Split.** The ground-motion records are split at random (seeded) into a
   training share and a held-out share; the free-vibration records always
   train (they pin p and r, seed section 3.2).
2. **Fit.** Each candidate effect's parameters are fitted to the training
   records by minimising the mean time-history error of
   :mod:`housner.scenarios.campaigns.compare` (the error over the measured window, in units of
   alpha) within the effect's bounds: a grid over the bounds (logarithmic
   where they span more than a factor 20), a finer grid around the best
   point, then a bounded local search (Brent in one dimension, Powell in
   more). Rocking is chaotic, so the error is not smooth in the parameters;
   the grid keeps the search from stopping in a local dip.
3. **Score.** Every fitted candidate is scored on the held-out records. Its
   improvement is the mean of the paired per-record differences
   d_i = e_i(current model) - e_i(candidate) [alpha], with the standard error
   s_d / sqrt(n) of that mean.
4. **Decide.** An improvement counts (``significant``) only when (a) the
   one-sided Wilcoxon signed-rank test of the paired differences rejects "no
   improvement" at a family-wise level of 5 % over the candidates tried in
   the round (Bonferroni: 0.05/9 per test for 9 candidates; a rank test,
   because the differences are heavy-tailed: most records barely change and
   a few that part from the measurement by chaos change a lot), and (b) the
   mean improvement is at least :data:`PRACTICAL` (a tenth) of the sensor
   noise sigma/alpha: a fall that small is within what the model's own
   conventions move (the significance itself is the records' business: it
   is judged against the spread of the differences over the records, never
   against one sensor sigma per record, so that a small effect that many
   records prove is kept). Before the folds are refitted, a candidate must
   pass the same two checks on its training records at a lenient 5 %
   (:data:`SCREEN_LEVEL`): fitted there, its fall is larger than held out,
   so a candidate the held-out test would accept passes the screen.
5. **Greedy.** The best significant candidate is added, all parameters of
   the model are refitted jointly (a Nelder-Mead search from the conditional
   fits; with a single parameter its own fit stands), and the remaining
   candidates are tried again on top of it, while the held-out error keeps
   falling significantly. Effects that cannot be
   combined with those already in (two mechanics effects, a foundation and a
   restitution law) are not tried. When no single effect helps, the pairs
   among the three that lowered the training error most (by more than the
   noise floor) are fitted together (each given the other's own fit, then
   both at once from these two starts; the effects already in keep their
   parameters) and tested
   as three more candidates of the round (Bonferroni over them all): some
   errors need two effects at once (a mis-measured p also mis-states
   Housner's r, seed eq. 4, which depends on the inertia).

Effects may also be added by hand (``add``): they enter first, in the order
given, fitted the same way, and the ladder shows what each one did.

No verdict is made of non-finite numbers. A candidate whose model gives a
non-finite theta history on any record is rejected, with the record, in its
round (before any score); an effect added by hand that does so stops the
diagnosis with :class:`NonFiniteHistory` naming it and the first record; a
score or a floor that is not finite all the same stops it with
:class:`NonFiniteScore` (both ``ValueError``: the command line's exit status 2,
bad input, as the model handed in is at fault and the same command can only
fail again).

The cross-validation (folds, scorers, out-of-fold errors) is
:mod:`housner.scenarios.campaigns.crossval`'s, a candidate's trial (fit,
screen, fold refits, judgement, pairs) :mod:`housner.scenarios.campaigns.trial`'s
with the free-vibration check of :mod:`housner.scenarios.campaigns.fv_check`,
the fitting :mod:`housner.scenarios.campaigns.fitting`'s, the folds and the
per-record errors :mod:`housner.scenarios.campaigns.scoring`'s, the result
classes :mod:`housner.scenarios.campaigns.results`' and the verdict
:mod:`housner.scenarios.campaigns.verdict`'s (its floor
:mod:`housner.scenarios.campaigns.floor`'s); this module is the greedy search
and its conclusion (the public names of the others it uses are importable from
here too).

Cost, and where it is saved
---------------------------
The time goes into simulations of the records, each cut to its error window::

    time ~ sum over evaluations of (records x c_rec + window samples x c_smp)
           + families x replicas x (truth on a 4x finer grid, 1-4x substeps, + K scoring runs)

An evaluation is one model on the fitting records: per candidate a grid (18 + 9 points for one
parameter, 82 + 25 for two), a local search (up to 14 and 20 points), and when it is held out K
fold refits of up to 9-10 points each on (K - 1)/K of the records; pairs, probes and the joint
refits add their own. Measured on 2 cores (the benchmark, ``benchmarks/bench_diagnose.py``):
c_rec ~ 0.3 ms per record (the engine's and the score's overhead), c_smp ~ 20-50 ns per window
sample for Housner's kernel, a free vibration ~ 3-5 ms more at 500 Hz (its release search grows
as its samples squared), and a mechanics kernel (a 50 Hz flexible foundation) ~ 2.5 ms per second of
record whatever the rate; one floor family ~ 0.6 s for 103 records of 6 s at 500 Hz, ~ 3 s for 103
records of 20-30 s at 2000 Hz. So records x length x rate x candidates: 103 records at 500 Hz
take ~ 25 s, most of it the flexible foundation's grid; at 2000 Hz and 20-30 s the plain search
took ~ 210 s before the economies below, ~ 60 s with them.

The economies, each said in ``Diagnosis.settings["economies"]`` when it applies:

* a campaign sampled at q >= 2 times :data:`SEARCH_RATE` is searched on every q-th sample
  (:func:`housner.scenarios.campaigns.scoring.decimated`: theta as sampled, the table acceleration
  through an anti-alias filter); the ladder is scored again on every sample (:meth:`_Search.full_rate`),
  and the floors and the verdict are on every sample;
* on a campaign whose ground motions' windows last more than
  :data:`housner.scenarios.campaigns.crossval.FIT_SECONDS`, models with an effect that replaces the
  equation of motion are fitted on the free vibrations and a spread subset of the ground motions
  (their screens, held-out errors and tests on all records);
* the floor's family loop measures the widest family second when the narrowest puts the final
  model far from its floor, and stops there when it is not at the widest's either
  (:meth:`_Search.floor_family`).

Two more save time without changing any number: a grid point whose records scored first (the free
vibrations, then the shortest windows) already put its loss above the grid's best so far is not
scored further (:meth:`housner.scenarios.campaigns.scoring.Scorer.loss_below`; a non-finite history on
the records it skips goes unseen there, as a point is abandoned only when it cannot be the best), and
a scorer keeps the errors of the last models it scored. The records are already simulated on both
cores (numba threads over the records, and threads for the mechanics kernels).

References
----------
Bachmann, J. A., Strand, M., Vassiliou, M. F., Broccardo, M., Stojadinovic, B.
(2017). Probabilistic validation of the Housner rocking model. COMPDYN 2017.
Hastie, T., Tibshirani, R., Friedman, J. (2009). The Elements of Statistical
Learning, 2nd ed., ch. 7 (held-out assessment) and sec. 3.3 (forward
stepwise selection).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Sequence
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

from scipy import stats as sps

from housner.effects import available_effects
from housner.errors import unknown_choice
from housner.scenarios.campaigns.campaign import Campaign, load_campaign
from housner.scenarios.campaigns.compare import compare
from housner.scenarios.campaigns.crossval import CVModel
from housner.scenarios.campaigns.fitting import build_model, effect_objective, fit_effect, joint_refit
from housner.scenarios.campaigns.floor import N_REPLICAS, measure_floor
from housner.scenarios.campaigns.localise import measured_features
from housner.scenarios.campaigns.model_form import FAMILIES
from housner.scenarios.campaigns.pointers import order_drift
from housner.scenarios.campaigns.probes import PROBES
from housner.scenarios.campaigns.residual import RATIO_MISFIT, Z_MISFIT, residual_test
from housner.scenarios.campaigns.results import Candidate, Diagnosis, Step
from housner.scenarios.campaigns.scoring import (
    DEFAULT_FOLDS,
    SEARCH_RATE,
    NonFiniteHistory,
    check_finite,
    check_train_fraction,
)
from housner.scenarios.campaigns.sensor import assess_sensor
from housner.scenarios.campaigns.trial import (
    PRACTICAL,
    Trials,
    compatible,
    fmt_params,
    held_text,
    judge,
    rank_key,
    sem,
)
from housner.scenarios.campaigns.verdict import decide

__all__ = ["FAMILY_JUMP", "LEVEL", "MAX_EFFECTS", "diagnose"]

#: Family-wise significance level of a round of candidates (one-sided, Bonferroni) [-].
LEVEL = 0.05
#: Most effects the greedy search adds [-].
MAX_EFFECTS = 3
#: The floor's family loop measures the widest family second when the narrowest puts the final model's
#: ground motions more than this many times RATIO_MISFIT above their floor [-] (:meth:`_Search.floor_family`).
FAMILY_JUMP = 2.0


class _Search(Trials):
    """One diagnosis under way: the ladder so far and the current model, on :class:`Trials`' folds and candidates.

    Parameters as :class:`housner.scenarios.campaigns.trial.Trials`.
    """

    def __init__(self, campaign: Campaign, folds: int, seed, level: float, engine_settings, say: Callable):
        super().__init__(campaign, folds, seed, level, engine_settings, say)
        self._start()

    def _start(self) -> None:
        """The plain model: the baseline step, and the current model."""
        self.base = CVModel([], [[] for _ in range(self.k_folds)])
        base_train_errors = self.allsc.errors([])
        self.base_train = self.allsc.weigh(base_train_errors)  # the loss of these errors: not simulated again
        self.noise_loss = self.allsc.noise_loss()
        self.base_held = base_train_errors.copy()  # no fitted parameter: out-of-fold errors are the plain errors
        h = self.base_held
        baseline = Step((), None, False, self.base_train, float(h.mean()), sem(h), math.nan, math.nan, False, h)
        self.say(f"baseline: held-out error {baseline.heldout_error:.4f} +- {baseline.heldout_se:.4f} alpha "
                 f"(sigma/alpha {self.floor:.4f}); {self.k_folds}-fold cross-validation")  # fmt: skip
        self.steps = [baseline]
        self.cur, self.cur_held, self.cur_train = self.base, self.base_held, self.base_train
        #: each step's cross-validated fit and the level it was judged at (full_rate rescores them)
        self.step_cvs: list[CVModel] = [self.base]
        self.step_levels: list[float] = [math.nan]
        self._search_state: tuple | None = None

    # -- the ladder
    def add_by_hand(self, name: str) -> None:
        """Add effect ``name`` whatever its significance (``add`` of :func:`diagnose`).

        Raises :class:`NonFiniteHistory` naming ``name`` and the first record when the model with it
        gives a non-finite theta history (anywhere in its fit).
        """
        reason = compatible(self.campaign, build_model(self.cur.full), name)
        if reason:
            raise ValueError(f"cannot add {name!r} to {[n for n, _ in self.cur.full] or 'the plain model'}: {reason}")
        try:
            self._add_by_hand(name)
        except NonFiniteHistory as e:
            on = f" on top of {', '.join(n for n, _p in self.cur.full)}" if self.cur.full else ""
            raise NonFiniteHistory(
                f"effect {name!r}, added by hand{on}, gives a non-finite theta history on record {e.record!r}: "
                "the model is refused before any score",
                e.effects, e.record,
            ) from e  # fmt: skip

    def _add_by_hand(self, name: str) -> None:
        fit_sc, fit_train = self.fit_sets([*(n for n, _p in self.cur.full), name])
        params, _tr, _n = fit_effect(name, effect_objective(fit_sc, build_model(self.cur.full), []), self.spec,
                                     pinned=self.pinned)  # fmt: skip
        cv_new = self.add_cv(self.cur, name, params, fit_train)
        full, tr = joint_refit(cv_new.full, fit_sc, self.spec, pinned=self.pinned)
        if fit_sc is not self.allsc:
            tr = self.allsc.loss(build_model(full))  # the training error on every record
        cv_new = self.refit_folds(CVModel(full, cv_new.folds), train=fit_train)
        he = self.oof(cv_new)
        sig, d, se, _z, _p, _why = judge(self.cur_held, he, self.level_for(1), self.floor)
        self.steps.append(Step(tuple(cv_new.full), name, True, tr, float(he.mean()), sem(he), d, se, sig, he))
        self.step_cvs.append(cv_new)
        self.step_levels.append(self.level_for(1))
        self.cur, self.cur_held, self.cur_train = cv_new, he, tr
        self.say(f"+ {name} (by hand) {fmt_params(params)}: held-out error {he.mean():.4f}")

    def greedy(self, cands: list[str], max_effects: int, pairs: bool) -> tuple[list[list[Candidate]], list[str], float]:
        """The greedy rounds (module docstring, step 5): every round, the selected effects, the first round's level."""
        rounds: list[list[Candidate]] = []
        selected: list[str] = []
        first_level = self.level_for(len(cands))
        for rnd in range(1, max_effects + 1):
            in_model = {n for n, _ in self.cur.full}
            pool = [n for n in cands
                    if n not in in_model and not compatible(self.campaign, build_model(self.cur.full), n)]  # fmt: skip
            if not pool:
                break
            zc = self.level_for(len(pool))
            if rnd == 1:
                first_level = zc
            if self.cur_train - self.noise_loss <= PRACTICAL * self.floor:
                why = (f"the training error {self.cur_train:.4f} alpha is within {PRACTICAL * self.floor:.4f} of "
                       f"the sensor noise ({self.noise_loss:.4f}): nothing is left for an effect to lower by a "
                       "tenth of the noise; not searched")  # fmt: skip
                rounds.append([self.candidate(n, {}, rnd, math.nan, zc, reason=why) for n in pool])
                self.say(f"round {rnd}: {why}")
                break
            results, chosen = self.round(rnd, pool, zc, pairs)
            rounds.append(results)
            if chosen is None:
                break
            self.accept(*chosen, zc)
            selected.extend(chosen[0].effect.split(" + "))
        return rounds, selected, first_level

    def round(self, rnd: int, pool: list[str], zc: float, pairs: bool) -> tuple[list[Candidate], tuple | None]:
        """Every candidate of ``pool`` tried (then pairs, when none passes): the round, best first, and its choice."""
        results, models = [], {}
        for name in pool:
            t0 = time.perf_counter()
            c, cv_new = self.try_candidate(name, rnd, zc)
            results.append(c)
            models[name] = cv_new
            held = held_text(c, cv_new is not None)
            self.say(f"round {rnd}: {name:32s} {fmt_params(c.params):40s} {held} ({time.perf_counter() - t0:.1f} s)")
        results.sort(key=rank_key)
        best = results[0]
        if best.significant:
            return results, (best, models[best.effect])
        chosen = None
        if pairs:
            tried = self.try_pairs(results, self.level_for(len(pool) + 3))
            results.extend(p[0] for p in tried)
            results.sort(key=rank_key)
            good = sorted((p for p in tried if p[0].significant), key=lambda p: -p[0].improvement)
            if good:
                chosen = (good[0][0], good[0][1])
        return results, chosen

    def accept(self, cand: Candidate, cv_new: CVModel, zc: float) -> None:
        """Add the chosen candidate: all parameters refitted jointly, a new step of the ladder."""
        fit_sc, fit_train = self.fit_sets([n for n, _p in cv_new.full])
        full, tr = joint_refit(cv_new.full, fit_sc, self.spec, pinned=self.pinned)
        if fit_sc is not self.allsc:
            tr = self.allsc.loss(build_model(full))  # the training error on every record
        cv_new = self.refit_folds(CVModel(full, cv_new.folds), train=fit_train)
        he = self.oof(cv_new)
        _sig, d, se, _z, _p, _why = judge(self.cur_held, he, zc, self.floor)
        self.steps.append(Step(tuple(cv_new.full), cand.effect, False, tr, float(he.mean()), sem(he), d, se, True, he))
        self.step_cvs.append(cv_new)
        self.step_levels.append(zc)
        self.cur, self.cur_held, self.cur_train = cv_new, he, tr
        self.say(f"+ {cand.effect}: held-out error {he.mean():.4f} +- {sem(he):.4f} alpha")

    # -- the records as measured
    def full_rate(self) -> None:
        """The ladder on the records as measured, when the search ran on decimated ones.

        Each step keeps the search's fits; its training error, its out-of-fold errors and its paired
        fall from the step before are taken again on every sample and judged again at its round's
        level (a step the search took whose fall is not significant on every sample is said so in
        ``economies``; it stays in the ladder). The search's own figures are kept for :meth:`probe`.
        """
        if self.decimation == 1 or self.rate == "full":
            return
        self._search_state = (self.cur_held, self.cur_train, self.noise_loss, self.base_held, self.base_train)
        rates = sorted({round(1.0 / r.dt, 3) for r in self.campaign.records})
        rate = f"{rates[0]:g} Hz" if len(rates) == 1 else f"{rates[0]:g}-{rates[-1]:g} Hz"
        q = self.decimation
        self.use_rate("full")
        self.noise_loss = self.allsc.noise_loss()
        base_errors = self.allsc.errors([])
        steps: list[Step] = []
        prev = base_errors
        for i, (st, cv, lev) in enumerate(zip(self.steps, self.step_cvs, self.step_levels, strict=True)):
            if i == 0:
                he, tr = base_errors.copy(), self.allsc.weigh(base_errors)
                steps.append(replace(st, train_error=tr, heldout_error=float(he.mean()), heldout_se=sem(he),
                                     heldout_errors=he))  # fmt: skip
            else:
                he, tr = self.oof(cv), self.allsc.loss(build_model(cv.full))
                sig, d, se, _z, pval, _why = judge(prev, he, lev, self.floor)
                if st.significant and not sig and not st.by_hand:
                    self.economies.append(
                        f"On every sample the fall of step {i} (+ {st.added}) is {d:+.4f} +- {se:.4f} alpha, "
                        f"p = {pval:.2g}: not significant at its round's level {lev:.2g}, as it was on every "
                        f"{q}th sample; it stays in the ladder."
                    )  # fmt: skip
                steps.append(replace(st, train_error=tr, heldout_error=float(he.mean()), heldout_se=sem(he),
                                     improvement=d, improvement_se=se,
                                     significant=sig if st.by_hand else st.significant, heldout_errors=he))  # fmt: skip
            prev = he
        self.steps = steps
        self.base_held, self.base_train = steps[0].heldout_errors, steps[0].train_error
        self.cur_held, self.cur_train = steps[-1].heldout_errors, steps[-1].train_error
        self.economies.insert(0, (
            f"The search ran on every {q}th sample ({rate} thinned to {rates[0] / q:g} Hz; {SEARCH_RATE:g} Hz is "
            "what the physics needs: the fits' ranges are set for it, the fastest, a 100 Hz foundation, has 5 samples "
            "a period): theta as sampled (its noise stays white of the same sigma, so a record's error is the same "
            "mean over fewer samples), the table acceleration through an anti-alias filter (zero-phase, below the "
            "new Nyquist frequency). The candidates' fits, held-out errors and tests, the pairs and the probes are "
            "on those samples; the ladder's errors, the floors and the verdict on every sample."
        ))  # fmt: skip
        self.say(f"the ladder on every sample ({rate}): held-out error {steps[0].heldout_error:.4f} -> "
                 f"{steps[-1].heldout_error:.4f} alpha")  # fmt: skip

    @contextmanager
    def _at_search_rate(self):
        """The search's records and figures for a while (:meth:`probe`), when :meth:`full_rate` left them."""
        if self._search_state is None or self.rate != "full":
            yield
            return
        full = (self.cur_held, self.cur_train, self.noise_loss, self.base_held, self.base_train)
        self.cur_held, self.cur_train, self.noise_loss, self.base_held, self.base_train = self._search_state
        self.use_rate("search")
        try:
            yield
        finally:
            self.use_rate("full")
            self.cur_held, self.cur_train, self.noise_loss, self.base_held, self.base_train = full

    # -- the verdict
    def conclude(self, library: list[str], selected: list[str], compare_steps: bool, n_rep: int, seed,
                 added: Sequence[str] = ()):
        """Both ends of the ladder against their measured floors: the verdict and the two floors.

        The baseline's and the final model's comparisons always run (the verdict's localisation), the
        other steps' on request; the steps get their comparisons.
        """
        last = len(self.steps) - 1
        cmps = {i: compare(self.campaign, "housner", build_model(list(self.steps[i].effects)), self.engine_settings)
                for i in range(len(self.steps)) if compare_steps or i in (0, last)}  # fmt: skip
        self.steps = [replace(s, comparison=cmps[i]) if i in cmps else s for i, s in enumerate(self.steps)]
        seed_int = seed if isinstance(seed, int) else 0
        # One family of correct integrators per campaign (housner.scenarios.campaigns.model_form): the closest to the
        # library's conventions at which the final model's ground motions are at the floor (not a
        # misfit, and within RATIO_MISFIT of it both on the mean, which counts the records chaos carries
        # off, and on the 10 %-trimmed mean, the typical record), the widest when none is; the baseline is judged
        # against the same family. (Its floor is another: a correct model of other physics leaves
        # another error, as chaos carries its records elsewhere.)
        kinds = [r.kind for r in self.campaign.records]
        self.say("measuring the correct-model floor (parametric bootstrap over correct integrators)")
        family, floor_fin = self.floor_family(n_rep, seed_int, kinds)
        self.family = family
        floor_base = floor_fin if not self.cur.full else measure_floor(
            self.allsc, [], self.base.folds, self.fold_of, n_replicas=n_rep, seed=seed_int, family=family)  # fmt: skip
        for what, v in (("the plain model's held-out error", self.base_held),
                        ("the final model's held-out error", self.cur_held),
                        ("the plain model's correct-model floor", floor_base.mean),
                        ("the final model's correct-model floor", floor_fin.mean)):  # fmt: skip
            check_finite(what, v, self.ids)
        self.say(f"floor: correct integrators of the family {family!r}")
        probes = self.probe()
        mf = measured_features(self.campaign)
        drift = order_drift([self.base_held - floor_base.mean, self.cur_held - floor_fin.mean],
                            (mf.energy_record, mf.energy_amplitude, mf.energy_ratio))  # fmt: skip
        verdict = decide(
            n_records=len(self.ids), baseline=residual_test(self.base_held, floor_base, kinds),
            final=residual_test(self.cur_held, floor_fin, kinds), selected=selected, params=dict(self.cur.full),
            baseline_cmp=self.steps[0].comparison, final_cmp=self.steps[-1].comparison, library=library,
            added=added, drift=drift, family=family, probes=probes,
        )  # fmt: skip
        return verdict, (floor_base, floor_fin)

    def floor_family(self, n_rep: int, seed_int: int, kinds: list[str]) -> tuple[str, object]:
        """The family of correct integrators of the verdict, and the final model's floor under it.

        The families of :data:`FAMILIES` narrowest first, until the final model's ground motions are
        at their floor (not a misfit, and within RATIO_MISFIT of it on the mean and on the trimmed
        mean); the widest when at none. Stopped early: when the narrowest family puts them more than
        :data:`FAMILY_JUMP` x RATIO_MISFIT above their floor, the widest is measured next, and when
        they are not at its floor either, the families between are not measured (they are nested:
        each spans the conventions of the narrower ones, so their floors lie below the widest's, and
        the answer, the widest, is the one the whole loop gives); ``economies`` says so.
        """
        fams = list(FAMILIES)
        done: dict[str, tuple] = {}

        def measure(family: str) -> tuple:
            if family not in done:
                fl = measure_floor(self.allsc, self.cur.full, self.cur.folds, self.fold_of, n_replicas=n_rep,
                                   seed=seed_int, family=family)  # fmt: skip
                gm = residual_test(self.cur_held, fl, kinds).groups.get("ground_motion")
                ratio = math.nan if gm is None else max(gm["ratio"], gm["ratio_trimmed"])
                done[family] = (fl, gm is None or not gm["misfit"] and ratio <= RATIO_MISFIT, ratio)
            return done[family]

        for i, family in enumerate(fams):
            fl, at_floor, ratio = measure(family)
            if at_floor:
                return family, fl
            if i == 0 and len(fams) > 2 and ratio > FAMILY_JUMP * RATIO_MISFIT:
                wide, wide_at_floor, wide_ratio = measure(fams[-1])
                if not wide_at_floor:
                    skipped = ", ".join(repr(f) for f in fams[1:-1])
                    self.economies.append(
                        f"The floor's family loop stopped early: the final model's ground motions are {ratio:.2f}x "
                        f"their floor under the narrowest family ({fams[0]!r}, more than {FAMILY_JUMP:g} x "
                        f"{RATIO_MISFIT:g}) and {wide_ratio:.2f}x it under the widest ({fams[-1]!r}, not at it "
                        f"either), so the families between ({skipped}) were not measured: nested, their floors "
                        f"lie below the widest's."
                    )  # fmt: skip
                    self.say(f"floor: not at it under {fams[0]!r} ({ratio:.2f}x) nor under {fams[-1]!r} "
                             f"({wide_ratio:.2f}x); the families between not measured")  # fmt: skip
                    return fams[-1], wide
        return fams[-1], done[fams[-1]][0]

    def probe(self) -> list[dict]:
        """Physics outside the library tried on top of the final model (:mod:`housner.scenarios.campaigns.probes`).

        Each probe is fitted on top of the final model and judged on its out-of-fold errors like a
        candidate, at the verdict's level (Bonferroni over the probes), and against its kernel with
        its physics faded out. Returns, for each that lowers the error
        significantly: {probe, class, params, error, error_with, improvement, se, z, p}.
        """
        with self._at_search_rate():
            return self._probe()

    def _probe(self) -> list[dict]:
        if self.cur_train - self.noise_loss <= PRACTICAL * self.floor:
            return []  # nothing above the sensor noise for a probe to take (as a round of the search)
        out = []
        # a significant probe turns the verdict into a misfit: it is held to the verdict's own level,
        # z > Z_MISFIT one-sided (1.3e-3), over the probes (Bonferroni); at the search's 5 % one correct
        # campaign in twenty would be called a misfit
        level = float(sps.norm.sf(Z_MISFIT)) / len(PROBES)
        for name, cls_name in PROBES.items():
            c, _cv = self.try_candidate(name, 0, level)  # fitted, screened and judged as a candidate is
            self.say(f"probe {name} {fmt_params(c.params)}: {held_text(c, _cv is not None)}")
            if c.significant:
                out.append({"probe": name, "class": cls_name, "params": c.params, "error": float(self.cur_held.mean()),
                            "error_with": c.heldout_error, "improvement": c.improvement, "se": c.improvement_se,
                            "z": c.z, "p": c.pvalue})  # fmt: skip
        return out

    def selection_frequency(self, rounds: list[list[Candidate]]) -> dict[str, float]:
        """Effect -> share of the folds in which it was the best candidate of its round [-]."""
        sel_freq: dict[str, float] = {}
        for r in rounds:
            cv_c = [c for c in r if c.fold_wins is not None]
            wins: dict[str, int] = {}
            for k in range(self.k_folds):
                best_k = max(cv_c, key=lambda c, k=k: c.fold_wins[k], default=None)
                if best_k is not None and best_k.fold_wins[k] > 0:
                    wins[best_k.effect] = wins.get(best_k.effect, 0) + 1
            for c in cv_c:
                sel_freq[c.effect] = max(sel_freq.get(c.effect, 0.0), wins.get(c.effect, 0) / self.k_folds)
        return sel_freq


def diagnose(
    campaign: Campaign | str | Path,
    *,
    effects: Iterable[str] | None = None,
    add: Sequence[str] = (),
    folds: int = DEFAULT_FOLDS,
    train_fraction: float | None = None,
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
    train_fraction : float, optional
        Older interface: the share of records to fit on; sets K = round(1 / (1 - train_fraction)).
    seed : int
        Seed of the fold assignment (and of the floor's bootstrap).
    max_effects : int
        Most effects the greedy search adds.
    level : float
        Family-wise significance level of each round [-].
    engine_settings : dict, optional
        Settings of the analytic engine (``r``, ``substeps``).
    compare_steps : bool
        Also run the full :func:`housner.scenarios.campaigns.compare.compare` for the intermediate steps of the ladder
        (the baseline's and the final model's are always run: the verdict needs their localisation).
    pairs : bool
        When no single effect helps significantly, also try the pairs among the three that lowered
        the training error most, fitted jointly.
    n_replicas : int, optional
        Replicas of the floor's parametric bootstrap (default :data:`housner.scenarios.campaigns.floor.N_REPLICAS`).
    progress : callable, optional
        Called with a line of text as the search goes.

    Returns
    -------
    Diagnosis
        With its :class:`housner.scenarios.campaigns.verdict.Verdict` (see the module docstrings of this module and
        of :mod:`housner.scenarios.campaigns.verdict`).
    """
    t_start = time.perf_counter()
    if not isinstance(campaign, Campaign):
        campaign = load_campaign(campaign)
    # the sensor first: its noise as measured, its faults masked or corrected (housner.scenarios.campaigns.sensor)
    campaign = assess_sensor(campaign, engine_settings)
    cands, folds = _checked(campaign, effects, add, folds, train_fraction, max_effects, level)
    n_rep = N_REPLICAS if n_replicas is None else int(n_replicas)
    search = _Search(campaign, folds, seed, level, engine_settings, progress or (lambda s: None))
    for name in add:
        search.add_by_hand(name)
    rounds, selected, first_level = search.greedy(cands, max_effects, pairs)
    search.full_rate()
    # the library is claimed only where the search tried it: a first round skipped (the training error already at
    # the sensor noise) tried no effect
    tried = [] if rounds and all("not searched" in c.reason for c in rounds[0]) else cands
    verdict, floors = search.conclude(tried, selected, compare_steps, n_rep, seed, added=list(add))
    if campaign.sensor is not None:
        verdict = replace(verdict, text=verdict.text + campaign.sensor.verdict_sentence())
    if search.economies:
        # what ran on fewer samples or stopped early: said where the verdict is read
        verdict = replace(verdict, text=verdict.text + " How it was computed: " + " ".join(search.economies))
    diag = Diagnosis(
        campaign=campaign,
        baseline=search.steps[0],
        steps=search.steps,
        candidates=rounds[0] if rounds else [],
        rounds=rounds,
        selected=selected,
        added=list(add),
        noise_floor=search.floor,
        test_level=first_level,
        train_ids=search.ids,
        heldout_ids=search.ids,
        settings={
            "effects": cands,
            "add": list(add),
            "folds": search.k_folds,
            "seed": seed if isinstance(seed, (int, type(None))) else str(seed),
            "max_effects": max_effects,
            "level": level,
            "practical": PRACTICAL,
            "pairs": pairs,
            "replicas": n_rep,
            "engine_settings": dict(engine_settings or {}),
            "floor_family": search.family,
            "decimation": search.decimation,
            "economies": list(search.economies),
        },
        folds=search.fold_ids,
        verdict=verdict,
        floors=floors,
        selection_frequency=search.selection_frequency(rounds),
    )
    diag.elapsed = time.perf_counter() - t_start
    return diag


def _checked(campaign: Campaign, effects, add, folds, train_fraction, max_effects, level) -> tuple[list[str], int]:
    """The candidate effects and the folds asked for, after checking :func:`diagnose`'s arguments."""
    names_all = available_effects()
    cands = list(names_all if effects is None else effects)
    for n in [*cands, *add]:
        if n not in names_all:
            raise unknown_choice("effect", n, names_all)
    if len(set(add)) != len(add):
        raise ValueError(f"`add` names an effect twice: {list(add)}")
    if not (isinstance(max_effects, int) and max_effects >= 0):
        raise ValueError(f"`max_effects` must be a non-negative integer, got {max_effects!r}")
    if not 0.0 < level < 1.0:
        raise ValueError(f"`level` must lie in (0, 1), got {level!r}")
    if train_fraction is not None:
        folds = max(2, int(round(1.0 / (1.0 - check_train_fraction(train_fraction)))))
    if not (isinstance(folds, int) and folds >= 2):
        raise ValueError(f"`folds` must be an integer of at least 2, got {folds!r}")
    n = len(campaign.records)
    if n < 4:
        raise ValueError(
            f"campaign {campaign.name!r} has {n} usable record(s); the diagnosis needs at least 4 "
            "(some to fit on, some to judge on)"
        )
    return cands, folds
