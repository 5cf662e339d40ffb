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

The fitting is :mod:`housner.scenarios.campaigns.fitting`'s, the folds and the per-record
errors :mod:`housner.scenarios.campaigns.scoring`'s, the result classes
:mod:`housner.scenarios.campaigns.results`' and the verdict :mod:`housner.scenarios.campaigns.verdict`'s;
this module is the search (their public names are importable from here too).

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
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from housner.scenarios.campaigns.campaign import Campaign, load_campaign
from housner.scenarios.campaigns.compare import compare, features, observe, on_grid, simulate_records
from housner.scenarios.campaigns.fitting import (
    FIT_BOUNDS,
    build_model,
    effect_objective,
    fit_effect,
    joint_refit,
    param_dims,
)
from housner.scenarios.campaigns.localise import measured_features
from housner.scenarios.campaigns.model_form import FAMILIES
from housner.scenarios.campaigns.probes import PROBES
from housner.scenarios.campaigns.results import Candidate, Diagnosis, Step
from housner.scenarios.campaigns.scoring import DEFAULT_FOLDS, Scorer, check_train_fraction, cv_folds, split_records
from housner.scenarios.campaigns.verdict import (
    N_REPLICAS,
    RATIO_MISFIT,
    Z_MISFIT,
    decide,
    measure_floor,
    order_drift,
    residual_test,
)
from scipy import stats as sps

from housner.effects import Effect, apply_effects, available_effects, effect_class, make_effect
from housner.errors import unknown_choice

__all__ = [
    "DEFAULT_FOLDS",
    "FIT_BOUNDS",
    "Candidate",
    "Diagnosis",
    "Step",
    "cv_folds",
    "diagnose",
    "fit_effect",
    "split_records",
]

#: Family-wise significance level of a round of candidates (one-sided, Bonferroni) [-].
LEVEL = 0.05
#: An improvement must be at least this fraction of the sensor noise sigma/alpha per record [-]: the
#: smallest fall taken for physics rather than for the model's own conventions. Measured on a plain
#: campaign written by an independent integrator (tests/campaign_generators.py, 60 ground motions):
#: feeding the library's model its input 0.05 samples early or late moves the records' median error
#: by 0.02 sigma (and the mean by more, through the one or two records it carries off by chaos, which
#: the rank test discounts). A 12 ms sensor lag lowers the error by ~0.9 sigma, an 8 ms one by ~0.5.
PRACTICAL = 0.1
#: Older name of PRACTICAL (the margin was a whole sigma, which dropped small effects many records prove).
NOISE_MARGIN = PRACTICAL
#: One-sided level of the training-record screen a candidate passes before its folds are refitted [-].
SCREEN_LEVEL = 0.05
#: Most effects the greedy search adds [-].
MAX_EFFECTS = 3
#: search runs on the free vibrations and this many ground motions spread over the campaign, the
#: local search that ends the fit on all records [-].
MECHANICS_GRID_RECORDS = 12
#: Local search budget of a fold's refit, started from the fit on all records (Brent iterations).
FOLD_ITERATIONS = 8
#: Nelder-Mead evaluations per parameter of a fold's joint refit.
FOLD_JOINT_FEV = 6
#: Free-vibration localisation quantities a candidate must not contradict (seed section 3.2: they
#: pin p and r), and the |z| beyond which it does (when it is also worse than the current model's).
FV_CHECK = ("p", "energy_ratio")
FV_Z = 3.0


# ----------------------------------------------------------------------------
# the diagnosis
def _paired(base: np.ndarray, new: np.ndarray) -> tuple[float, float]:
    d = base - new
    if d.size < 2:
        return float(d.mean()) if d.size else math.nan, math.nan
    return float(d.mean()), float(d.std(ddof=1) / math.sqrt(d.size))


def _judge(cur: np.ndarray, new: np.ndarray, test_level: float, floor: float):
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


def _compatible(campaign: Campaign, model_effects: list, name: str) -> str:
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



@dataclass
class _CV:
    """A model fitted on all records (``full``) and without each fold (``folds``), as (name, parameters) pairs."""

    full: list[tuple[str, dict]]
    folds: list[list[tuple[str, dict]]]


def _fv_metrics(campaign: Campaign, effects: list, engine_settings) -> dict:
    """Free-vibration localisation (p, energy ratio) of a model, observed through the campaign's sensor."""
    fv = campaign.free_vibration
    if not fv:
        return {}
    res = simulate_records(campaign.specimen, fv, "housner", effects, engine_settings)
    index = {r.id: i for i, r in enumerate(campaign.records)}
    hist, over = {}, {}
    for rec, r in zip(fv, res, strict=True):
        if isinstance(r, str):
            continue
        hist[rec.id] = observe(on_grid(r, rec), rec, index[rec.id])
        over[rec.id] = bool(r.overturned)
    if not hist:
        return {}
    m = features(campaign, hist, over).metrics()
    return {k: m[k] for k in FV_CHECK}


def _fv_z(model: dict, measured: dict) -> dict[str, float]:
    out = {}
    for k in FV_CHECK:
        a, b = measured.get(k), model.get(k)
        if a is None or b is None or not (math.isfinite(a.value) and math.isfinite(b.value)):
            continue
        se = math.hypot(a.se if math.isfinite(a.se) else 0.0, b.se if math.isfinite(b.se) else 0.0)
        if se > 0:
            out[k] = (b.value - a.value) / se
    return out



class _Search:
    """One diagnosis under way: the campaign's folds and scorers, the ladder so far and the current model.

    Parameters
    ----------
    campaign : Campaign
    folds : int
        Cross-validation folds asked for [-] (at most half the records are used).
    seed : int, SeedSequence or Generator
        Seed of the fold assignment.
    level : float
        Family-wise significance level of a round [-].
    engine_settings : dict or None
        Settings of the analytic engine.
    say : callable
        Called with a line of text as the search goes.
    """

    def __init__(self, campaign: Campaign, folds: int, seed, level: float, engine_settings, say: Callable):
        self.campaign, self.spec, self.level, self.say = campaign, campaign.specimen, level, say
        self.engine_settings = engine_settings
        self.ids = ids = [r.id for r in campaign.records]
        self.k_folds = k_folds = min(folds, len(ids) // 2)
        self.fold_ids = cv_folds(campaign, k_folds, seed)
        pos = {rid: i for i, rid in enumerate(ids)}
        self.fold_of = np.empty(len(ids), dtype=int)
        for k, f in enumerate(self.fold_ids):
            self.fold_of[[pos[i] for i in f]] = k
        self.allsc = Scorer(campaign, ids, engine_settings)
        self.train_sc = [self.allsc.subset([i for i in ids if self.fold_of[pos[i]] != k]) for k in range(k_folds)]
        self.held_sc = [self.allsc.subset(self.fold_ids[k]) for k in range(k_folds)]
        gm_ids = [r.id for r in campaign.ground_motion]
        step = max(1, len(gm_ids) // MECHANICS_GRID_RECORDS)
        fv_ids = [r.id for r in campaign.free_vibration]
        self.mech_sc = self.allsc.subset(fv_ids + gm_ids[::step][:MECHANICS_GRID_RECORDS])
        self.mech_sc.release_angle = False
        self.floor = float(np.mean([r.noise for r in campaign.records])) / self.spec.alpha
        self.measured = measured_features(campaign).metrics()
        # parameters the localisation measures directly, far better than a fit to the histories can
        # (Effect.measured_params): taken as measured, never fitted
        self.pinned = {n: p for n in available_effects()
                       if (p := effect_class(n).measured_params(self.measured, self.spec))}  # fmt: skip
        self.measured_fv = {k: v for k, v in self.measured.items() if k in FV_CHECK}
        self._start()

    def _start(self) -> None:
        """The plain model: the baseline step, and the current model."""
        self.base = _CV([], [[] for _ in range(self.k_folds)])
        base_train_errors = self.allsc.errors([])
        self.base_train = self.allsc.loss([])
        self.noise_loss = self.allsc.noise_loss()
        self.base_held = base_train_errors.copy()  # no fitted parameter: out-of-fold errors are the plain errors
        h = self.base_held
        baseline = Step((), None, False, self.base_train, float(h.mean()), _se(h), math.nan, math.nan, False, h)
        self.say(f"baseline: held-out error {baseline.heldout_error:.4f} +- {baseline.heldout_se:.4f} alpha "
                 f"(sigma/alpha {self.floor:.4f}); {self.k_folds}-fold cross-validation")  # fmt: skip
        self.steps = [baseline]
        self.cur, self.cur_held, self.cur_train = self.base, self.base_held, self.base_train
        self.cur_fvz = _fv_z(_fv_metrics(self.campaign, [], self.engine_settings), self.measured_fv)

    # -- the cross-validated model
    def oof(self, cv: _CV) -> np.ndarray:
        """Out-of-fold error of every record [alpha]: each scored by the model fitted without its fold."""
        out = np.empty(len(self.ids))
        for k in range(self.k_folds):
            out[self.fold_of == k] = self.held_sc[k].errors(build_model(cv.folds[k]))
        return out

    def fold_means(self, v: np.ndarray) -> np.ndarray:
        return np.array([v[self.fold_of == k].mean() for k in range(self.k_folds)])

    def refit_folds(self, cv: _CV, free_from: int = 0) -> _CV:
        """Each fold's model refitted jointly (its effects ``free_from`` on) from where it stands."""
        return _CV(cv.full, [joint_refit(cv.folds[k], self.train_sc[k], self.spec, FOLD_JOINT_FEV, free_from,
                                         self.pinned)[0] for k in range(self.k_folds)])  # fmt: skip

    def add_cv(self, cv: _CV, name: str, params: dict) -> _CV:
        """``cv`` with effect ``name`` added: ``params`` on all records, refitted from them in each fold."""
        per = []
        for k in range(self.k_folds):
            obj = effect_objective(self.train_sc[k], build_model(cv.folds[k]), [])
            pk, _e, _n = fit_effect(name, obj, self.spec, start=params, local_only=True,
                                    local_iterations=FOLD_ITERATIONS, pinned=self.pinned)  # fmt: skip
            per.append([*cv.folds[k], (name, pk)])
        return _CV([*cv.full, (name, params)], per)

    # -- candidates
    def level_for(self, m: int) -> float:
        return self.level / max(m, 1)

    def fv_reason(self, model_effects: list) -> str:
        """Why a model contradicts the free vibrations (:data:`FV_CHECK` beyond :data:`FV_Z`), '' if it does not."""
        z = _fv_z(_fv_metrics(self.campaign, model_effects, self.engine_settings), self.measured_fv)
        for k, v in z.items():
            if abs(v) > FV_Z and abs(v) > abs(self.cur_fvz.get(k, 0.0)):
                m = self.measured_fv[k]
                return (f"contradicts the free vibrations: {k} is {v:+.1f} standard errors from the measured "
                        f"{m.value:.4g} +- {m.se:.2g}")  # fmt: skip
        return ""

    def candidate(self, name, params, rnd, tr_err, test_level, he=None, reason="") -> Candidate:
        """The candidate ``name`` of round ``rnd``, judged on its out-of-fold errors ``he`` (None: not held out)."""
        base = tuple(n for n, _ in self.cur.full)
        if he is None:
            return Candidate(name, params, base, rnd, tr_err, math.nan, math.nan, math.nan, math.nan, math.nan, 1.0,
                             False, reason, None)  # fmt: skip
        sig, d, se, z, pval, why = _judge(self.cur_held, he, test_level, self.floor)
        wins = self.fold_means(self.cur_held - he)
        return Candidate(name, params, base, rnd, tr_err, float(he.mean()), _se(he), d, se, z, pval, sig, why, he,
                         wins)  # fmt: skip

    def try_candidate(self, name: str, rnd: int, test_level: float) -> tuple[Candidate, _CV | None]:
        """Fit ``name`` on top of the current model and, when it may pass, in every fold."""
        fixed = build_model(self.cur.full)
        if effect_class(name).changes_mechanics:
            start, rejected = self._mechanics_start(name, fixed, rnd, test_level)
            if rejected is not None:
                return rejected, None
            params, tr_err, _nev = fit_effect(name, effect_objective(self.allsc, fixed, []), self.spec, start=start,
                                              local_only=True, local_iterations=FOLD_ITERATIONS,
                                              pinned=self.pinned)  # fmt: skip
        else:
            # a parameter the localisation measures directly (a sensor offset: the rotation at rest, to
            # microradians) is taken as measured (self.pinned): a grid over its bounds can find a basin
            # of the wrong sign, a local search a value off by its own tolerance
            params, tr_err, _nev = fit_effect(name, effect_objective(self.allsc, fixed, []), self.spec,
                                              pinned=self.pinned)  # fmt: skip
        why = self._not_held_out(name, params, fixed, tr_err)
        if why:
            return self.candidate(name, params, rnd, tr_err, test_level, reason=why), None
        cv_new = self.add_cv(self.cur, name, params)
        he = self.oof(cv_new)
        cand = self.candidate(name, params, rnd, tr_err, test_level, he)
        return self._beyond_kernel(cand, fixed, [(name, params)], he, test_level), cv_new

    def _mechanics_start(self, name: str, fixed: list, rnd: int, test_level: float) -> tuple[dict, Candidate | None]:
        """Where a mechanics effect's fit starts, or the candidate it stays when its basin does not pay.

        10-100x slower kernels: the grid finds the basin on a spread subset of the records, the local
        search then fits on all of them.
        """
        margin = PRACTICAL * self.floor
        start, e_sub, _n = fit_effect(name, effect_objective(self.mech_sc, fixed, []), self.spec, pinned=self.pinned)
        gain_sub = self.mech_sc.loss(fixed) - e_sub
        if not gain_sub > margin:
            why = f"error on {len(self.mech_sc.records)} records falls by {gain_sub:+.4f} < " \
                  f"{margin:.4f} alpha (a tenth of the sensor noise): not fitted further"  # fmt: skip
            return start, self.candidate(name, start, rnd, e_sub, test_level, reason=why)
        # the basin found on the subset must carry over to every record before the (costly) local fit
        e_all = self.allsc.loss([*fixed, make_effect(name, **start)])
        if not self.cur_train - e_all > margin:
            why = f"the subset's best point lowers the error on all records by {self.cur_train - e_all:+.4f} < " \
                  f"{margin:.4f} alpha (a tenth of the sensor noise): not fitted further"  # fmt: skip
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
            sig, _d, _se, _z, pval, _why = _judge(ctrl, he, test_level, self.floor)
            if not sig:
                return (f"its kernel's numerics, not its physics: the same kernel with {name} faded out "
                        f"({_fmt_params(faded)}) does as well (p = {pval:.2g})")  # fmt: skip
        return ""

    def _not_held_out(self, name: str, params: dict, fixed: list, tr_err: float) -> str:
        """Why a candidate fitted on all records is not held out ('' when it is)."""
        margin = PRACTICAL * self.floor
        gain = self.cur_train - tr_err
        if not gain > margin:
            return f"training error falls by {gain:+.4f} < {margin:.4f} alpha (a tenth of the sensor noise): " \
                   "not held out"  # fmt: skip
        bad = self.fv_reason([*fixed, make_effect(name, **params)])
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

    def try_pairs(self, results: list[Candidate], test_level: float) -> list[tuple[Candidate, _CV | None, float]]:
        """The pairs among the three candidates that lowered the training error most, fitted together."""
        # Only candidates that lowered the training error by more than the noise floor pair up:
        # the others are fitting noise (and cost time).
        helped = sorted((c for c in results if c.train_error < self.cur_train - PRACTICAL * self.floor),
                        key=lambda c: c.train_error)  # fmt: skip
        fixed = build_model(self.cur.full)
        out = []
        for i, j in ((0, 1), (0, 2), (1, 2)):
            if j >= len(helped):
                continue
            a, b = helped[i], helped[j]
            if _compatible(self.campaign, [*fixed, make_effect(a.effect, **a.params)], b.effect):
                continue
            out.append(self._pair(a, b, fixed, test_level))
        return out

    def _pair(self, a: Candidate, b: Candidate, fixed: list, test_level: float):
        """Candidates ``a`` and ``b`` fitted together on top of the current model, and judged."""
        n0 = len(self.cur.full)
        # Two starts, each effect's own fit with the other fitted given it, then both together from
        # each (the joint optimum of correlated parameters lies along a narrow valley that a single
        # local search from one start often misses); the model's own effects keep their parameters.
        pb, _e, _n = fit_effect(b.effect, effect_objective(self.allsc, [*fixed, make_effect(a.effect, **a.params)], []),
                                self.spec, pinned=self.pinned)  # fmt: skip
        pa, _e, _n = fit_effect(a.effect, effect_objective(self.allsc, fixed, [make_effect(b.effect, **b.params)]),
                                self.spec, pinned=self.pinned)  # fmt: skip
        starts = ([(a.effect, a.params), (b.effect, pb)], [(a.effect, pa), (b.effect, b.params)])
        tries = [joint_refit([*self.cur.full, *s], self.allsc, self.spec, 30, free_from=n0, pinned=self.pinned)
                 for s in starts]  # fmt: skip
        both, tr = min(tries, key=lambda x: x[1])
        name = f"{a.effect} + {b.effect}"
        prm = {f"{n}.{k}": v for n, p in both[n0:] for k, v in p.items()}
        bad = self.fv_reason(build_model(both))
        if bad:
            return self.candidate(name, prm, a.round, tr, test_level, reason=bad), None, tr
        cv_new = self.refit_folds(_CV(both, [[*f, *both[n0:]] for f in self.cur.folds]), free_from=n0)
        he = self.oof(cv_new)
        cand = self.candidate(name, prm, a.round, tr, test_level, he)
        cand = self._beyond_kernel(cand, build_model(self.cur.full), both[n0:], he, test_level)
        self.say(
            f"round {a.round}: {name:32s} {_fmt_params(prm):40s} held-out {he.mean():.4f} improvement "
            f"{cand.improvement:+.4f} +- {cand.improvement_se:.4f} {'*' if cand.significant else ' '} (pair)"
        )
        return cand, cv_new, tr

    # -- the ladder
    def add_by_hand(self, name: str) -> None:
        """Add effect ``name`` whatever its significance (``add`` of :func:`diagnose`)."""
        reason = _compatible(self.campaign, build_model(self.cur.full), name)
        if reason:
            raise ValueError(f"cannot add {name!r} to {[n for n, _ in self.cur.full] or 'the plain model'}: {reason}")
        params, _tr, _n = fit_effect(name, effect_objective(self.allsc, build_model(self.cur.full), []), self.spec,
                                     pinned=self.pinned)  # fmt: skip
        cv_new = self.add_cv(self.cur, name, params)
        full, tr = joint_refit(cv_new.full, self.allsc, self.spec, pinned=self.pinned)
        cv_new = self.refit_folds(_CV(full, cv_new.folds))
        he = self.oof(cv_new)
        sig, d, se, _z, _p, _why = _judge(self.cur_held, he, self.level_for(1), self.floor)
        self.steps.append(Step(tuple(cv_new.full), name, True, tr, float(he.mean()), _se(he), d, se, sig, he))
        self.cur, self.cur_held, self.cur_train = cv_new, he, tr
        self.say(f"+ {name} (by hand) {_fmt_params(params)}: held-out error {he.mean():.4f}")

    def greedy(self, cands: list[str], max_effects: int, pairs: bool) -> tuple[list[list[Candidate]], list[str], float]:
        """The greedy rounds (module docstring, step 5): every round, the selected effects, the first round's level."""
        rounds: list[list[Candidate]] = []
        selected: list[str] = []
        first_level = self.level_for(len(cands))
        for rnd in range(1, max_effects + 1):
            in_model = {n for n, _ in self.cur.full}
            pool = [n for n in cands
                    if n not in in_model and not _compatible(self.campaign, build_model(self.cur.full), n)]  # fmt: skip
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
            held = f"held-out {c.heldout_error:.4f} improvement {c.improvement:+.4f} +- {c.improvement_se:.4f} " \
                   f"{'*' if c.significant else ' '}" if cv_new is not None else c.reason  # fmt: skip
            self.say(f"round {rnd}: {name:32s} {_fmt_params(c.params):40s} {held} ({time.perf_counter() - t0:.1f} s)")
        results.sort(key=_rank)
        best = results[0]
        if best.significant:
            return results, (best, models[best.effect])
        chosen = None
        if pairs:
            tried = self.try_pairs(results, self.level_for(len(pool) + 3))
            results.extend(p[0] for p in tried)
            results.sort(key=_rank)
            good = sorted((p for p in tried if p[0].significant), key=lambda p: -p[0].improvement)
            if good:
                chosen = (good[0][0], good[0][1])
        return results, chosen

    def accept(self, cand: Candidate, cv_new: _CV, zc: float) -> None:
        """Add the chosen candidate: all parameters refitted jointly, a new step of the ladder."""
        full, tr = joint_refit(cv_new.full, self.allsc, self.spec, pinned=self.pinned)
        cv_new = self.refit_folds(_CV(full, cv_new.folds))
        he = self.oof(cv_new)
        _sig, d, se, _z, _p, _why = _judge(self.cur_held, he, zc, self.floor)
        self.steps.append(Step(tuple(cv_new.full), cand.effect, False, tr, float(he.mean()), _se(he), d, se, True, he))
        self.cur, self.cur_held, self.cur_train = cv_new, he, tr
        self.say(f"+ {cand.effect}: held-out error {he.mean():.4f} +- {_se(he):.4f} alpha")

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
        for family in FAMILIES:
            floor_fin = measure_floor(self.allsc, self.cur.full, self.cur.folds, self.fold_of, n_replicas=n_rep,
                                      seed=seed_int, family=family)  # fmt: skip
            gm = residual_test(self.cur_held, floor_fin, kinds).groups.get("ground_motion")
            if gm is None or not gm["misfit"] and max(gm["ratio"], gm["ratio_trimmed"]) <= RATIO_MISFIT:
                break
        self.family = family
        floor_base = floor_fin if not self.cur.full else measure_floor(
            self.allsc, [], self.base.folds, self.fold_of, n_replicas=n_rep, seed=seed_int, family=family)  # fmt: skip
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
        self.say(f"verdict: {verdict.status}")
        return verdict, (floor_base, floor_fin)

    def probe(self) -> list[dict]:
        """Physics outside the library tried on top of the final model (:mod:`housner.scenarios.campaigns.probes`).

        Each probe is fitted on top of the final model and judged on its out-of-fold errors like a
        candidate, at the verdict's level (Bonferroni over the probes), and against its kernel with
        its physics faded out. Returns, for each that lowers the error
        significantly: {probe, class, params, error, error_with, improvement, se, z, p}.
        """
        if self.cur_train - self.noise_loss <= PRACTICAL * self.floor:
            return []  # nothing above the sensor noise for a probe to take (as a round of the search)
        out = []
        # a significant probe turns the verdict into a misfit: it is held to the verdict's own level,
        # z > Z_MISFIT one-sided (1.3e-3), over the probes (Bonferroni); at the search's 5 % one correct
        # campaign in twenty would be called a misfit
        level = float(sps.norm.sf(Z_MISFIT)) / len(PROBES)
        for name, cls_name in PROBES.items():
            c, _cv = self.try_candidate(name, 0, level)  # fitted, screened and judged as a candidate is
            held = (f"held-out {c.heldout_error:.4f} improvement {c.improvement:+.4f} +- {c.improvement_se:.4f} "
                    f"{'*' if c.significant else ' '}") if _cv is not None else c.reason  # fmt: skip
            self.say(f"probe {name} {_fmt_params(c.params)}: {held}")
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
        Replicas of the floor's parametric bootstrap (default :data:`housner.scenarios.campaigns.verdict.N_REPLICAS`).
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
    cands, folds = _checked(campaign, effects, add, folds, train_fraction, max_effects, level)
    n_rep = N_REPLICAS if n_replicas is None else int(n_replicas)
    search = _Search(campaign, folds, seed, level, engine_settings, progress or (lambda s: None))
    for name in add:
        search.add_by_hand(name)
    rounds, selected, first_level = search.greedy(cands, max_effects, pairs)
    verdict, floors = search.conclude(cands, selected, compare_steps, n_rep, seed, added=list(add))
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


def _rank(c: Candidate) -> float:
    return -c.improvement if math.isfinite(c.improvement) else math.inf


def _se(v: np.ndarray) -> float:
    return float(np.std(v, ddof=1) / math.sqrt(v.size)) if v.size > 1 else math.nan


def _fmt_params(p: dict) -> str:
    return ", ".join(f"{k}={v:.4g}" for k, v in p.items())
