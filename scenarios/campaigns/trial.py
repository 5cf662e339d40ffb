"""Candidate effects tried on top of the current model: fitted, screened, refitted in every fold and judged.

A candidate is fitted to all records (:func:`housner.scenarios.campaigns.fitting.fit_effect`), then
held out only when its training error falls by more than :data:`PRACTICAL` of the sensor noise, it
does not contradict the free vibrations (:mod:`housner.scenarios.campaigns.fv_check`) and, on the
records it was fitted to, its fall per record passes the screen (:data:`SCREEN_LEVEL`). Held out, it
is refitted in every fold and judged on its out-of-fold errors against the current model's
(:func:`judge`: a one-sided Wilcoxon signed-rank test and the practical margin); an effect that
brings its own kernel must also beat that kernel with its physics faded out. When no single effect
helps, pairs are fitted together (:meth:`Trials.try_pairs`). A candidate (or pair) whose model
gives a non-finite theta history anywhere in its fit is rejected, with the record named in its
reason (:class:`housner.scenarios.campaigns.scoring.NonFiniteHistory`). The greedy search that
uses them is :mod:`housner.scenarios.campaigns.diagnose`'s.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from scipy import stats as sps

from housner.effects import Effect, apply_effects, effect_class, make_effect
from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.campaigns.crossval import FOLD_ITERATIONS, CrossValidation, CVModel
from housner.scenarios.campaigns.fitting import build_model, effect_objective, fit_effect, joint_refit, param_dims
from housner.scenarios.campaigns.fv_check import FreeVibrationCheck
from housner.scenarios.campaigns.results import Candidate
from housner.scenarios.campaigns.scoring import NonFiniteHistory

__all__ = ["NOISE_MARGIN", "PRACTICAL", "SCREEN_LEVEL", "Trials", "rejected_text"]

#: An improvement must be at least this fraction of the sensor noise sigma/alpha per record [-]: the
#: smallest fall taken for physics rather than for the model's own conventions.
#: Why 0.1: docs/results.md#defaults-trial.
PRACTICAL = 0.1
#: Older name of PRACTICAL (the margin was a whole sigma, which dropped small effects many records prove).
NOISE_MARGIN = PRACTICAL
#: One-sided level of the training-record screen a candidate passes before its folds are refitted [-].
SCREEN_LEVEL = 0.05


def _paired(base: np.ndarray, new: np.ndarray) -> tuple[float, float]:
    d = base - new
    if d.size < 2:
        return float(d.mean()) if d.size else math.nan, math.nan
    return float(d.mean()), float(d.std(ddof=1) / math.sqrt(d.size))


def judge(cur: np.ndarray, new: np.ndarray, test_level: float, floor: float):
    """Is the held-out improvement from ``cur`` to ``new`` (per-record errors) significant?

    Returns (significant, mean improvement, its standard error, z = mean / se, p-value, reason).
    The p-value is the one-sided Wilcoxon signed-rank test of the paired differences (records the
    change leaves exactly as they were drop out): the differences are heavy-tailed (most records
    barely change, a few that diverge by chaos change a lot), where a rank test keeps its power
    and its level and a t-test on the mean does not.
    """
    d_all = cur - new
    d, se = _paired(cur, new)
    z = d / se if se > 0 else (math.inf if d > 0 else 0.0)
    nz = d_all[d_all != 0.0]
    if nz.size == 0:
        return False, d, se, z, 1.0, "changes nothing"
    pval = float(sps.wilcoxon(nz, alternative="greater", zero_method="wilcox").pvalue) if nz.size >= 2 else 1.0
    need = PRACTICAL * floor
    if not d > 0:
        return False, d, se, z, pval, "no improvement"
    if pval > test_level:
        return False, d, se, z, pval, f"within its uncertainty (p = {pval:.2g} > {test_level:.2g})"
    if d < need:
        return False, d, se, z, pval, f"below a tenth of the sensor noise ({d:.4f} < {need:.4f} alpha)"
    return True, d, se, z, pval, f"p = {pval:.2g} <= {test_level:.2g} and {d:.4f} >= {need:.4f} alpha"


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


def sem(v: np.ndarray) -> float:
    return float(np.std(v, ddof=1) / math.sqrt(v.size)) if v.size > 1 else math.nan


def rank_key(c: Candidate) -> float:
    return -c.improvement if math.isfinite(c.improvement) else math.inf


def fmt_params(p: dict) -> str:
    return ", ".join(f"{k}={v:.4g}" for k, v in p.items())


def held_text(c: Candidate, held_out: bool = True) -> str:
    """A candidate's held-out result in a line of progress (its reason when it was not held out)."""
    if not held_out:
        return c.reason
    return f"held-out {c.heldout_error:.4f} improvement {c.improvement:+.4f} +- {c.improvement_se:.4f} " \
           f"{'*' if c.significant else ' '}"  # fmt: skip


def rejected_text(e: NonFiniteHistory) -> str:
    """A rejected candidate's reason: its history is not finite on a record."""
    return f"rejected: its theta history is not finite on record {e.record!r} (no score is made of NaN)"


class Trials(CrossValidation):
    """Candidates tried on top of the current model of a campaign's cross-validation.

    Parameters
    ----------
    campaign, folds, seed, engine_settings
        As :class:`housner.scenarios.campaigns.crossval.CrossValidation`.
    level : float
        Family-wise significance level of a round [-].
    say : callable
        Called with a line of text as the search goes.

    The current model is the search's (:mod:`housner.scenarios.campaigns.diagnose`): its
    cross-validated fit ``cur``, out-of-fold errors ``cur_held`` [alpha] and training loss
    ``cur_train`` [alpha].
    """

    cur: CVModel
    cur_held: np.ndarray
    cur_train: float

    def __init__(self, campaign: Campaign, folds: int, seed, level: float, engine_settings, say):
        super().__init__(campaign, folds, seed, engine_settings)
        self.level, self.say = level, say
        self.fv = FreeVibrationCheck(campaign, engine_settings, self.measured)
        #: (effect, round) of the mechanics candidates whose training error was taken on the grid's subset
        #: of records only (not comparable with the current model's on all records: :meth:`try_pairs`)
        self.subset_only: set[tuple[str, int]] = set()
        #: where the diagnosis subsampled or stopped early: plain sentences (Diagnosis.settings["economies"])
        self.economies: list[str] = []

    def fit_sets(self, names) -> tuple:
        """The records a model of effects ``names`` is fitted on: (all, each fold's training records).

        Every record, unless the campaign is ``thinned`` and the model has an effect that replaces the
        equation of motion (:mod:`housner.scenarios.campaigns.crossval`): then the free vibrations and a
        spread subset of the ground motions (said once in ``economies``).
        """
        if not (self.thinned and any(effect_class(n).changes_mechanics for n in names)):
            return self.allsc, self.train_sc
        note = "fitted on the free vibrations and"
        if not any(note in e for e in self.economies):
            recs, fit = self.allsc.records, self.fit_sc.records
            n_gm = sum(r.kind != "free_vibration" for r in recs)
            m_gm = sum(r.kind != "free_vibration" for r in fit)
            secs = sum(r.theta.size * r.dt for r in recs if r.kind != "free_vibration")
            fsecs = sum(r.theta.size * r.dt for r in fit if r.kind != "free_vibration")
            self.economies.append(
                f"Models with an effect that replaces the equation of motion (its kernel 10-100x slower) were "
                f"{note} {m_gm} of the {n_gm} ground motions, spread over the campaign ({fsecs:.0f} of "
                f"{secs:.0f} s of error windows; their grids on {len(self.mech_sc.records)} records); their "
                "training errors, screens, held-out errors and tests are on every record."
            )  # fmt: skip
        return self.fit_sc, self.fit_train_sc

    def _mechanics_path(self, names) -> bool:
        """Whether the model's new effect is fitted as a mechanics effect is: its grid on ``mech_sc`` (a
        mechanics effect; on a thinned campaign, any effect of a model with one)."""
        if effect_class(names[-1]).changes_mechanics:
            return True
        return self.thinned and any(effect_class(n).changes_mechanics for n in names)

    def level_for(self, m: int) -> float:
        return self.level / max(m, 1)

    def candidate(self, name, params, rnd, tr_err, test_level, he=None, reason="") -> Candidate:
        """The candidate ``name`` of round ``rnd``, judged on its out-of-fold errors ``he`` (None: not held out)."""
        base = tuple(n for n, _ in self.cur.full)
        if he is None:
            return Candidate(name, params, base, rnd, tr_err, math.nan, math.nan, math.nan, math.nan, math.nan, 1.0,
                             False, reason, None)  # fmt: skip
        sig, d, se, z, pval, why = judge(self.cur_held, he, test_level, self.floor)
        wins = self.fold_means(self.cur_held - he)
        return Candidate(name, params, base, rnd, tr_err, float(he.mean()), sem(he), d, se, z, pval, sig, why, he,
                         wins)  # fmt: skip

    def try_candidate(self, name: str, rnd: int, test_level: float) -> tuple[Candidate, CVModel | None]:
        """Fit ``name`` on top of the current model and, when it may pass, in every fold.

        A candidate whose model gives a non-finite history on a record is rejected (not held out).
        """
        try:
            return self._try_candidate(name, rnd, test_level)
        except NonFiniteHistory as e:
            return self.candidate(name, {}, rnd, math.nan, test_level, reason=rejected_text(e)), None

    def _try_candidate(self, name: str, rnd: int, test_level: float) -> tuple[Candidate, CVModel | None]:
        fixed = build_model(self.cur.full)
        names = [*(n for n, _p in self.cur.full), name]
        fit_sc, fit_train = self.fit_sets(names)
        if self._mechanics_path(names):
            start, rejected = self._mechanics_start(name, fixed, rnd, test_level, fit_sc)
            if rejected is not None:
                return rejected, None
            params, tr_err, _nev = fit_effect(name, effect_objective(fit_sc, fixed, []), self.spec, start=start,
                                              local_only=True, local_iterations=FOLD_ITERATIONS,
                                              pinned=self.pinned)  # fmt: skip
        else:
            # a parameter the localisation measures directly (a sensor offset: the rotation at rest, to
            # microradians) is taken as measured (self.pinned): a grid over its bounds can find a basin
            # of the wrong sign, a local search a value off by its own tolerance
            params, tr_err, _nev = fit_effect(name, effect_objective(fit_sc, fixed, []), self.spec,
                                              pinned=self.pinned)  # fmt: skip
        if fit_sc is not self.allsc:
            tr_err = self.allsc.loss([*fixed, make_effect(name, **params)])  # the training error on every record
        why = self._not_held_out(name, params, fixed, tr_err)
        if why:
            return self.candidate(name, params, rnd, tr_err, test_level, reason=why), None
        cv_new = self.add_cv(self.cur, name, params, fit_train)
        he = self.oof(cv_new)
        cand = self.candidate(name, params, rnd, tr_err, test_level, he)
        return self._beyond_kernel(cand, fixed, [(name, params)], he, test_level), cv_new

    def _mechanics_start(self, name: str, fixed: list, rnd: int, test_level: float,
                         fit_sc=None) -> tuple[dict, Candidate | None]:  # fmt: skip
        """Where a mechanics effect's fit starts, or the candidate it stays when its basin does not pay.

        10-100x slower kernels: the grid finds the basin on a spread subset of the records, the local
        search then fits on all of them (on ``fit_sc``'s, :meth:`fit_sets`).
        """
        fit_sc = self.allsc if fit_sc is None else fit_sc
        margin = PRACTICAL * self.floor
        start, e_sub, _n = fit_effect(name, effect_objective(self.mech_sc, fixed, []), self.spec, pinned=self.pinned)
        gain_sub = self.mech_sc.loss(fixed) - e_sub
        if not gain_sub > margin:
            why = f"error on {len(self.mech_sc.records)} records falls by {gain_sub:+.4f} < " \
                  f"{margin:.4f} alpha (a tenth of the sensor noise): not fitted further"  # fmt: skip
            self.subset_only.add((name, rnd))
            return start, self.candidate(name, start, rnd, e_sub, test_level, reason=why)
        # the basin found on the subset must carry over to every record before the (costly) local fit
        e_all = fit_sc.loss([*fixed, make_effect(name, **start)])
        base = self.cur_train if fit_sc is self.allsc else fit_sc.loss(fixed)
        if not base - e_all > margin:
            on = "all records" if fit_sc is self.allsc else f"the {len(fit_sc.records)} records it is fitted on"
            why = f"the subset's best point lowers the error on {on} by {base - e_all:+.4f} < " \
                  f"{margin:.4f} alpha (a tenth of the sensor noise): not fitted further"  # fmt: skip
            if fit_sc is not self.allsc:
                self.subset_only.add((name, rnd))
            return start, self.candidate(name, start, rnd, e_all, test_level, reason=why)
        return start, None

    def _beyond_kernel(self, cand: Candidate, fixed: list, members: list, he: np.ndarray, test_level: float):
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
        why = self._kernel_control(fixed, members, he, test_level)
        return replace(cand, significant=False, reason=why) if why else cand

    def _kernel_control(self, fixed: list, members: list, he: np.ndarray, test_level: float) -> str:
        """'' when ``members`` (name, params) beat their own kernel with their physics faded out, else why not.

        A mechanics effect fades at the end of its fit bounds nearest its neutral value (its own kernel
        stays in use); an effect that brings kernel terms (a probe, a user's term) fades to a millionth
        of its range off its neutral value, so that the terms' kernel stays in use too.
        """
        for k, (name, _params) in enumerate(members):
            cls = effect_class(name)
            uses_terms = cls.terms is not Effect.terms
            if not (cls.changes_mechanics or (uses_terms and not cls.fast_path)):
                continue
            faded = {}
            for d in param_dims(name, self.spec):
                n = d.neutral
                if cls.changes_mechanics:
                    faded[d.key] = d.hi if n is None or n >= d.hi else (d.lo if n <= d.lo else n)
                else:
                    base = n if n is not None and math.isfinite(n) else d.lo
                    faded[d.key] = min(max(base + 1e-6 * (d.hi - d.lo), d.lo), d.hi)
            ctrl_model = [*fixed, *[make_effect(m, **(faded if i == k else p)) for i, (m, p) in enumerate(members)]]
            ctrl = self.allsc.errors(ctrl_model)
            sig, _d, _stderr, _z, pval, _why = judge(ctrl, he, test_level, self.floor)
            if not sig:
                return (f"its kernel's numerics, not its physics: the same kernel with {name} faded out "
                        f"({fmt_params(faded)}) does as well (p = {pval:.2g})")  # fmt: skip
        return ""

    def _not_held_out(self, name: str, params: dict, fixed: list, tr_err: float) -> str:
        """Why a candidate fitted on all records is not held out ('' when it is)."""
        margin = PRACTICAL * self.floor
        gain = self.cur_train - tr_err
        if not gain > margin:
            return f"training error falls by {gain:+.4f} < {margin:.4f} alpha (a tenth of the sensor noise): " \
                   "not held out"  # fmt: skip
        bad = self.fv.reason([*fixed, make_effect(name, **params)])
        if bad:
            return bad
        # The screen (module docstring, step 4): on the records it was fitted to, the effect does at
        # least as well as out of fold (in expectation); when even there its fall per record is not
        # significant at SCREEN_LEVEL, or below the practical margin, the fold refits (5 more fits, the
        # costliest part for a mechanics effect) cannot pass and are not run. (The training loss weighs
        # the free vibrations as a group, so it can fall while the mean per record does not.)
        d_in = self.cur_held - self.allsc.errors([*fixed, make_effect(name, **params)])
        gain_in = float(np.mean(d_in))
        if not gain_in > margin:
            return f"even on the records it was fitted to, the mean error per record falls by {gain_in:+.4f} < " \
                   f"{margin:.4f} alpha (a tenth of the sensor noise): not held out"  # fmt: skip
        nz = d_in[d_in != 0.0]
        p_in = float(sps.wilcoxon(nz, alternative="greater").pvalue) if nz.size >= 2 else 1.0
        if p_in > SCREEN_LEVEL:
            return f"even on the records it was fitted to, its fall is within its uncertainty (p = {p_in:.2g} > " \
                   f"{SCREEN_LEVEL}): not held out"  # fmt: skip
        return ""

    def try_pairs(self, results: list[Candidate], test_level: float) -> list[tuple[Candidate, CVModel | None, float]]:
        """The pairs among the three candidates that lowered the training error most, fitted together."""
        # Only candidates that lowered the training error by more than the noise floor pair up:
        # the others are fitting noise (and cost time). A mechanics candidate stopped on the grid's
        # subset of records did not (its fall there was below the margin); its error there is on other
        # records than the current model's, so it is not compared with it.
        helped = sorted((c for c in results if c.train_error < self.cur_train - PRACTICAL * self.floor
                         and (c.effect, c.round) not in self.subset_only),
                        key=lambda c: c.train_error)  # fmt: skip
        fixed = build_model(self.cur.full)
        out = []
        for i, j in ((0, 1), (0, 2), (1, 2)):
            if j >= len(helped):
                continue
            a, b = helped[i], helped[j]
            if compatible(self.campaign, [*fixed, make_effect(a.effect, **a.params)], b.effect):
                continue
            try:
                out.append(self._pair(a, b, fixed, test_level))
            except NonFiniteHistory as e:
                name, why = f"{a.effect} + {b.effect}", rejected_text(e)
                self.say(f"round {a.round}: {name:32s} {why} (pair)")
                out.append((self.candidate(name, {}, a.round, math.nan, test_level, reason=why), None, math.nan))
        return out

    def _fit_given(self, name: str, before: list, after: list, fit_sc) -> dict:
        """Effect ``name`` fitted between the effects ``before`` and ``after`` on ``fit_sc``'s records; on a
        thinned campaign a model with a mechanics effect finds its basin on ``mech_sc`` first."""
        if fit_sc is self.allsc:
            return fit_effect(name, effect_objective(fit_sc, before, after), self.spec, pinned=self.pinned)[0]
        start, _e, _n = fit_effect(name, effect_objective(self.mech_sc, before, after), self.spec, pinned=self.pinned)
        return fit_effect(name, effect_objective(fit_sc, before, after), self.spec, start=start, local_only=True,
                          local_iterations=FOLD_ITERATIONS, pinned=self.pinned)[0]  # fmt: skip

    def _pair(self, a: Candidate, b: Candidate, fixed: list, test_level: float):
        """Candidates ``a`` and ``b`` fitted together on top of the current model, and judged."""
        n0 = len(self.cur.full)
        names = [*(n for n, _p in self.cur.full), a.effect, b.effect]
        fit_sc, fit_train = self.fit_sets(names)
        # Two starts, each effect's own fit with the other fitted given it, then both together from
        # each (the joint optimum of correlated parameters lies along a narrow valley that a single
        # local search from one start often misses); the model's own effects keep their parameters.
        pb = self._fit_given(b.effect, [*fixed, make_effect(a.effect, **a.params)], [], fit_sc)
        pa = self._fit_given(a.effect, fixed, [make_effect(b.effect, **b.params)], fit_sc)
        starts = ([(a.effect, a.params), (b.effect, pb)], [(a.effect, pa), (b.effect, b.params)])
        tries = [joint_refit([*self.cur.full, *s], fit_sc, self.spec, 30, free_from=n0, pinned=self.pinned)
                 for s in starts]  # fmt: skip
        both, tr = min(tries, key=lambda x: x[1])
        if fit_sc is not self.allsc:
            tr = self.allsc.loss(build_model(both))  # the training error on every record
        name = f"{a.effect} + {b.effect}"
        prm = {f"{n}.{k}": v for n, p in both[n0:] for k, v in p.items()}
        bad = self.fv.reason(build_model(both))
        if bad:
            return self.candidate(name, prm, a.round, tr, test_level, reason=bad), None, tr
        cv_new = self.refit_folds(CVModel(both, [[*f, *both[n0:]] for f in self.cur.folds]), free_from=n0,
                                  train=fit_train)  # fmt: skip
        he = self.oof(cv_new)
        cand = self.candidate(name, prm, a.round, tr, test_level, he)
        cand = self._beyond_kernel(cand, build_model(self.cur.full), both[n0:], he, test_level)
        self.say(f"round {a.round}: {name:32s} {fmt_params(prm):40s} {held_text(cand)} (pair)")
        return cand, cv_new, tr
