"""Which physical effect is missing: fit candidate effects, score them on held-out records, add them greedily.

The question a campaign asks of a model is not only "does it match?" but,
when it does not, "what is missing?". :func:`diagnose` answers it with the
effect library (:data:`housner.effects.EFFECTS`) and the analytic engine:

1. **Split.** The ground-motion records are split at random (seeded) into a
   training share and a held-out share; the free-vibration records always
   train (they pin p and r, seed section 3.2).
2. **Fit.** Each candidate effect's parameters are fitted to the training
   records by minimising the mean time-history error of
   :mod:`scenarios.compare` (the error over the measured window, in units of
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
   mean improvement is larger than the noise floor sigma/alpha (sigma the
   records' noise; 0.8 mrad -> 0.0054 for the seed specimen), the error a
   perfect model still shows: an improvement smaller than what the sensor
   noise alone contributes to the error is not physics the measurement can
   resolve, however many records vouch for it. A model that already explains
   the data to the noise has no room for such an improvement, so nothing is
   added.
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

References
----------
Bachmann, J. A., Strand, M., Vassiliou, M. F., Broccardo, M., Stojadinovic, B.
(2017). Probabilistic validation of the Housner rocking model. COMPDYN 2017.
Hastie, T., Tibshirani, R., Friedman, J. (2009). The Elements of Statistical
Learning, 2nd ed., ch. 7 (held-out assessment) and sec. 3.3 (forward
stepwise selection).
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy import optimize

from housner.errors import unknown_choice
from scenarios.campaign import Campaign, MeasuredRecord
from scenarios.compare import ERROR_CLIP, Comparison, compare, error_window, record_error, simulate_records

__all__ = [
    "FIT_BOUNDS",
    "Candidate",
    "Diagnosis",
    "Step",
    "diagnose",
    "fit_effect",
    "split_records",
]

#: Family-wise significance level of a round of candidates (one-sided, Bonferroni) [-].
LEVEL = 0.05
#: An improvement must exceed this fraction of the noise floor sigma/alpha [-]: a gain smaller than
#: the error a perfect model still shows is below what the measurement resolves (on synthetic
#: campaigns, chaos alone moves the held-out error of a correct model by up to ~0.7 of it).
NOISE_MARGIN = 1.0
#: Grid points per parameter of the coarse search (one-parameter effects) [-].
N_GRID = 17
#: Grid points of the zoom around the best coarse point [-].
N_ZOOM = 9
#: Most effects the greedy search adds [-].
MAX_EFFECTS = 3
#: Search ranges that differ from the effect's own bounds, with the reason.
#: flexible_foundation.frequency: below 10 Hz the block would settle by more than g/(2 pi 10 Hz)^2 = 2.5 mm
#: under its own weight (not a rocking test on a table); above 100 Hz an impact lasts about half a
#: vertical period, 5 ms or less, under 2.5 samples at 500 Hz: what the sensor can resolve of it is an
#: instantaneous impact law (``restitution``), while the kernel needs ever more substeps per sample.
#: flexible_foundation.damping_ratio: an over-damped pad (above 1) is left out of the search; its
#: kernel's step shrinks with the damping (cost x2 at 1, x4 at 2) and the time budget goes elsewhere.
FIT_BOUNDS: dict[tuple[str, str], tuple[float, float]] = {
    ("flexible_foundation", "frequency"): (10.0, 100.0),
    ("flexible_foundation", "damping_ratio"): (0.0, 1.0),
}
#: Effects that replace the equation of motion run their own (slower, 10-100x) kernels; they are
#: fitted on the first free-vibration record and at most this many training ground motions [-].
MAX_MECHANICS_FIT_RECORDS = 8


# ----------------------------------------------------------------------------
# records and errors
def split_records(campaign: Campaign, train_fraction: float = 0.5, seed=0) -> tuple[list[str], list[str]]:
    """Training and held-out record ids: free vibration trains, ground motions are split at random.

    Parameters
    ----------
    campaign : Campaign
    train_fraction : float
        Share of the ground-motion records used for fitting [-], in (0, 1).
    seed : int, SeedSequence or Generator
        Seed of the split.

    Returns
    -------
    (train_ids, heldout_ids) : lists of str
        Held-out ids are ground-motion records only (at least two).
    """
    tf = float(train_fraction)
    if not 0.0 < tf < 1.0:
        raise ValueError(f"`train_fraction` must lie in (0, 1), got {train_fraction!r}")
    gm = [r.id for r in campaign.ground_motion]
    if len(gm) < 4:
        raise ValueError(
            f"campaign {campaign.name!r} has {len(gm)} ground-motion record(s); the diagnosis needs at least 4 "
            "(some to fit on, at least two to judge on)"
        )
    rng = np.random.default_rng(seed)
    order = rng.permutation(len(gm))
    n_train = min(max(int(round(tf * len(gm))), 1), len(gm) - 2)
    train = [r.id for r in campaign.free_vibration] + [gm[i] for i in sorted(order[:n_train])]
    held = [gm[i] for i in sorted(order[n_train:])]
    return train, held


class _Scorer:
    """Per-record time-history errors of a list of effects on a fixed set of records."""

    def __init__(self, campaign: Campaign, ids: Sequence[str], engine_settings: dict | None = None):
        self.campaign = campaign
        alpha = campaign.specimen.alpha
        recs = [campaign.record(i) for i in ids]
        self.ends = [error_window(r, alpha) for r in recs]
        # Only the window counts, so the model is run to its end (plus the largest time lag the
        # library allows, 0.1 s, and a margin): the rest of a record would cost time and change nothing.
        self.records: list[MeasuredRecord] = [_truncated(r, end) for r, end in zip(recs, self.ends, strict=True)]
        self.engine_settings = dict(engine_settings or {})
        self.n_evaluations = 0

    def subset(self, ids: Sequence[str]) -> _Scorer:
        out = _Scorer.__new__(_Scorer)
        keep = [i for i, r in enumerate(self.records) if r.id in set(ids)]
        out.campaign = self.campaign
        out.records = [self.records[i] for i in keep]
        out.ends = [self.ends[i] for i in keep]
        out.engine_settings = self.engine_settings
        out.n_evaluations = 0
        return out

    def errors(self, effects: Sequence[Any]) -> np.ndarray:
        """Error per record [alpha]; a record the model fails on scores the clip value (1)."""
        self.n_evaluations += 1
        alpha = self.campaign.specimen.alpha
        res = simulate_records(self.campaign.specimen, self.records, "housner", effects, self.engine_settings)
        out = np.empty(len(self.records))
        for k, (rec, r, end) in enumerate(zip(self.records, res, self.ends, strict=True)):
            out[k] = ERROR_CLIP if isinstance(r, str) else record_error(r.theta, rec.theta, end, alpha)
        return out


#: Samples simulated beyond the end of the error window [s] (the library's largest time lag is 0.1 s).
_WINDOW_SLACK = 0.25


def _truncated(rec: MeasuredRecord, end: int) -> MeasuredRecord:
    from dataclasses import replace

    from housner.motion import GroundMotion

    n = min(rec.theta.size, end + int(math.ceil(_WINDOW_SLACK / rec.dt)))
    if n >= rec.theta.size:
        return rec
    mo = rec.motion
    motion = GroundMotion(mo.acc[:n], mo.dt, mo.name, mo.provenance, mo.theta0, mo.theta_dot0)
    return replace(rec, motion=motion, t=rec.t[:n], theta=rec.theta[:n])


# ----------------------------------------------------------------------------
# fitting
@dataclass(frozen=True)
class _Dim:
    key: str
    lo: float
    hi: float
    log: bool
    neutral: float | None

    def to_u(self, x: float) -> float:
        return math.log(x) if self.log else x

    def from_u(self, u: float) -> float:
        x = math.exp(u) if self.log else u
        return min(max(x, self.lo), self.hi)

    @property
    def u_bounds(self) -> tuple[float, float]:
        return self.to_u(self.lo), self.to_u(self.hi)


def _dims(name: str, specimen) -> list[_Dim]:
    from housner.effects import effect_class

    cls = effect_class(name)
    dims = []
    for key, spec in cls.params.items():
        b = FIT_BOUNDS.get((name, key)) or spec.bounds_for(specimen)
        if b is None:
            raise ValueError(f"effect {name!r}: parameter `{key}` has no bounds to fit within")
        lo, hi = float(b[0]), float(b[1])
        neutral = spec.neutral_for(specimen)
        dims.append(_Dim(key, lo, hi, lo > 0 and hi / lo >= 20.0, neutral))
    return dims


def _make(name: str, params: dict[str, float]):
    from housner.effects import make_effect

    return make_effect(name, **params)


def fit_effect(
    name: str,
    objective: Callable[[Any], float],
    specimen,
    *,
    start: dict[str, float] | None = None,
    local_only: bool = False,
) -> tuple[dict[str, float], float, int]:
    """Fit one effect's parameters by minimising ``objective(effect)`` within the bounds.

    Parameters
    ----------
    name : str
        Registered effect name.
    objective : callable
        Effect instance -> training error [alpha].
    specimen : Specimen
        For specimen-dependent bounds.
    start : dict, optional
        Starting parameters (for ``local_only``).
    local_only : bool
        Skip the grids: a local search from ``start``.

    Returns
    -------
    (params, error, n_evaluations)

    Notes
    -----
    One parameter: a grid of :data:`N_GRID` points (plus the neutral value
    when it lies inside the bounds, so the fit is never worse than the effect
    switched off), a zoom grid of :data:`N_ZOOM` points over +-1 step around
    the best, then a bounded Brent search over +-1 zoom step. d parameters:
    a grid of N_GRID^(1/d) (at least 3) points per parameter, then a bounded
    Powell search of at most 10 d evaluations.
    """
    dims = _dims(name, specimen)
    cache: dict[tuple, float] = {}

    def f_u(u) -> float:
        params = {d.key: d.from_u(float(x)) for d, x in zip(dims, np.atleast_1d(u), strict=True)}
        key = tuple(round(v, 12) for v in params.values())
        if key not in cache:
            try:
                cache[key] = float(objective(_make(name, params)))
            except ValueError:
                cache[key] = math.inf  # a combination the effect refuses (e.g. an impossible inertia)
        return cache[key]

    if not dims:
        return {}, float(objective(_make(name, {}))), 1
    lo = np.array([d.u_bounds[0] for d in dims])
    hi = np.array([d.u_bounds[1] for d in dims])
    if start is not None:
        best_u = np.array([d.to_u(min(max(float(start[d.key]), d.lo), d.hi)) for d in dims])
    else:
        best_u = None
    if not local_only or best_u is None:
        npd = N_GRID if len(dims) == 1 else max(3, int(round(N_GRID ** (1.0 / len(dims)))))
        axes = []
        for d, a, b in zip(dims, lo, hi, strict=True):
            ax = np.linspace(a, b, npd)
            if d.neutral is not None and d.lo <= d.neutral <= d.hi:
                ax = np.union1d(ax, [d.to_u(d.neutral)])
            axes.append(ax)
        pts = np.array(np.meshgrid(*axes, indexing="ij")).reshape(len(dims), -1).T
        vals = np.array([f_u(p) for p in pts])
        best_u = pts[int(np.argmin(vals))]
        step = (hi - lo) / (npd - 1)
        if len(dims) == 1:
            z = np.linspace(max(lo[0], best_u[0] - step[0]), min(hi[0], best_u[0] + step[0]), N_ZOOM)
            zvals = np.array([f_u([x]) for x in z])
            if zvals.min() <= f_u(best_u):
                best_u = np.array([z[int(np.argmin(zvals))]])
            step = step / ((N_ZOOM - 1) / 2)
    else:
        step = (hi - lo) / (N_GRID - 1)
    if len(dims) == 1:
        a = max(lo[0], best_u[0] - step[0])
        b = min(hi[0], best_u[0] + step[0])
        if b > a:
            res = optimize.minimize_scalar(
                lambda x: f_u([x]), bounds=(a, b), method="bounded", options={"xatol": 1e-3 * step[0], "maxiter": 14}
            )
            if res.fun <= f_u(best_u):
                best_u = np.array([res.x])
    else:
        res = optimize.minimize(
            f_u, best_u, method="Powell", bounds=list(zip(lo, hi, strict=True)),
            options={"maxfev": 10 * len(dims), "xtol": 1e-3, "ftol": 1e-4},
        )  # fmt: skip
        if res.fun <= f_u(best_u):
            best_u = np.asarray(res.x)
    params = {d.key: d.from_u(float(x)) for d, x in zip(dims, best_u, strict=True)}
    return params, f_u(best_u), len(cache)


def _objective(scorer: _Scorer, before: list, after: list) -> Callable[[Any], float]:
    """Mean training error of the model ``before + [effect] + after`` as a function of ``effect``."""

    def f(effect) -> float:
        return float(np.mean(scorer.errors([*before, effect, *after])))

    return f


def _joint_refit(
    model: list[tuple[str, dict]], scorer: _Scorer, specimen, maxfev_per_dim: int = 15, free_from: int = 0
) -> tuple[list[tuple[str, dict]], float]:  # fmt: skip
    """Local search over the parameters of the model's effects ``free_from`` on, from their current values.

    Bounded Nelder-Mead; the effects before ``free_from`` keep their parameters. Returns the model
    and its training error.
    """
    dims: list[tuple[int, _Dim]] = []
    for i, (name, _p) in enumerate(model):
        if i >= free_from:
            dims += [(i, d) for d in _dims(name, specimen)]

    def build(u) -> list[tuple[str, dict]]:
        out = [(n, dict(p)) for n, p in model]
        for (i, d), x in zip(dims, u, strict=True):
            out[i][1][d.key] = d.from_u(float(x))
        return out

    def f(u) -> float:
        try:
            return float(np.mean(scorer.errors([_make(n, p) for n, p in build(u)])))
        except ValueError:
            return math.inf

    u0 = np.array([d.to_u(min(max(model[i][1][d.key], d.lo), d.hi)) for i, d in dims])
    f0 = f(u0)
    if len(dims) < 2:
        return model, f0  # one parameter: its own grid-and-Brent fit is already the best we do
    # Nelder-Mead from a simplex of half a zoom step per parameter: it follows the narrow diagonal
    # valleys of correlated parameters (p and r both set the free-vibration decay and timing), where
    # one-parameter-at-a-time searches stall.
    lo = np.array([d.u_bounds[0] for _i, d in dims])
    hi = np.array([d.u_bounds[1] for _i, d in dims])
    h = (hi - lo) / ((N_GRID - 1) * (N_ZOOM - 1))
    simplex = [u0]
    for k in range(len(dims)):
        v = u0.copy()
        v[k] = v[k] + h[k] if v[k] + h[k] <= hi[k] else v[k] - h[k]
        simplex.append(v)
    res = optimize.minimize(
        f, u0, method="Nelder-Mead", bounds=list(zip(lo, hi, strict=True)),
        options={"maxfev": maxfev_per_dim * len(dims), "initial_simplex": np.array(simplex), "xatol": 1e-3 * h.min(),
                 "fatol": 1e-5},
    )  # fmt: skip
    if res.fun < f0:
        return build(res.x), float(res.fun)
    return model, f0


# ----------------------------------------------------------------------------
# results
@dataclass(frozen=True)
class Candidate:
    """One candidate effect, fitted on the training records and scored on the held-out ones.

    Attributes
    ----------
    effect : str
        Registered name.
    params : dict
        Fitted parameters (units of the effect's ParamSpec).
    base : tuple of str
        Effects already in the model it was added to.
    round : int
        Greedy round (1 = against the starting model).
    train_error : float
        Mean training error [alpha].
    heldout_error, heldout_se : float
        Mean held-out error [alpha] and its standard error.
    improvement, improvement_se : float
        Mean paired held-out improvement over the model it was added to [alpha], and its standard error.
    z : float
        improvement / improvement_se.
    pvalue : float
        One-sided Wilcoxon signed-rank p-value of the paired held-out differences.
    significant : bool
        See the module docstring (p-value below the Bonferroni level and improvement above the noise floor).
    reason : str
        Why it is (not) significant, in words.
    heldout_errors : ndarray
        Per held-out record [alpha].
    """

    effect: str
    params: dict
    base: tuple
    round: int
    train_error: float
    heldout_error: float
    heldout_se: float
    improvement: float
    improvement_se: float
    z: float
    pvalue: float
    significant: bool
    reason: str
    heldout_errors: np.ndarray = field(repr=False, compare=False, default=None)

    def to_dict(self) -> dict:
        return {
            "effect": self.effect,
            "params": _clean(self.params),
            "base": list(self.base),
            "round": self.round,
            "train_error": self.train_error,
            "heldout_error": self.heldout_error,
            "heldout_se": self.heldout_se,
            "improvement": self.improvement,
            "improvement_se": self.improvement_se,
            "z": self.z,
            "pvalue": self.pvalue,
            "significant": self.significant,
            "reason": self.reason,
        }


@dataclass(frozen=True)
class Step:
    """One rung of the error ladder: the model with the effects so far.

    Attributes
    ----------
    effects : tuple of (str, dict)
        (name, fitted parameters) of each effect in the model, in the order added.
    added : str or None
        The effect this step added (None for the baseline); two effects that
        only help together enter in one step, written ``"a + b"``.
    by_hand : bool
        Added with ``add`` rather than by the greedy search.
    train_error, heldout_error, heldout_se : float
        [alpha].
    improvement, improvement_se : float
        Mean paired held-out improvement over the previous step [alpha] (NaN for the baseline).
    significant : bool
    heldout_errors : ndarray
        Per held-out record [alpha].
    comparison : Comparison or None
        The full comparison of this model with the campaign (localisation included).
    """

    effects: tuple
    added: str | None
    by_hand: bool
    train_error: float
    heldout_error: float
    heldout_se: float
    improvement: float
    improvement_se: float
    significant: bool
    heldout_errors: np.ndarray = field(repr=False, compare=False, default=None)
    comparison: Comparison | None = field(repr=False, compare=False, default=None)

    @property
    def names(self) -> list[str]:
        return [n for n, _p in self.effects]

    @property
    def added_names(self) -> tuple[str, ...]:
        """The registered names of the effect(s) this step added."""
        return tuple(self.added.split(" + ")) if self.added else ()

    def label(self) -> str:
        return "Housner (baseline)" if not self.effects else " + ".join(self.names)

    def to_dict(self) -> dict:
        return {
            "effects": [{"name": n, "params": _clean(p)} for n, p in self.effects],
            "added": self.added,
            "by_hand": self.by_hand,
            "train_error": self.train_error,
            "heldout_error": self.heldout_error,
            "heldout_se": self.heldout_se,
            "improvement": _nan_none(self.improvement),
            "improvement_se": _nan_none(self.improvement_se),
            "significant": self.significant,
        }


@dataclass(eq=False)
class Diagnosis:
    """The result of :func:`diagnose`.

    Attributes
    ----------
    campaign : Campaign
    baseline : Step
        The plain Housner model.
    steps : list of Step
        The error ladder: baseline, then each added effect.
    candidates : list of Candidate
        The first round: every candidate against the starting model, best first.
    rounds : list of list of Candidate
        Every greedy round, each best first.
    selected : list of str
        Effects the greedy search added (after the hand-added ones).
    added : list of str
        Effects added by hand.
    noise_floor : float
        Mean sigma/alpha of the held-out records [-]: the error of a perfect model.
    test_level : float
        The per-test significance level of the first round, ``level`` / candidates [-].
    train_ids, heldout_ids : list of str
    settings : dict
    elapsed : float
        Wall time [s].
    """

    campaign: Campaign
    baseline: Step
    steps: list[Step]
    candidates: list[Candidate]
    rounds: list[list[Candidate]]
    selected: list[str]
    added: list[str]
    noise_floor: float
    test_level: float
    train_ids: list[str]
    heldout_ids: list[str]
    settings: dict
    elapsed: float = math.nan

    @property
    def final(self) -> Step:
        return self.steps[-1]

    @property
    def reduction(self) -> float:
        """Fraction of the baseline held-out error removed by the final model [-]."""
        b = self.baseline.heldout_error
        return (b - self.final.heldout_error) / b if b > 0 else 0.0

    def summary(self) -> str:
        """One paragraph: what fails, which effect explains it with which parameters, how much the error fell."""
        b = self.baseline
        parts = [
            f"Campaign {self.campaign.name!r}: the plain Housner model's held-out time-history error is "
            f"{b.heldout_error:.4f} +- {b.heldout_se:.4f} alpha (noise floor {self.noise_floor:.4f})."
        ]
        cmp = b.comparison
        if cmp is not None:
            bad = cmp.discrepancies()
            if bad:
                from scenarios.compare import METRICS

                txt = "; ".join(
                    f"{METRICS[k][0]}: measured {m.value:.4g}, model {x.value:.4g}" for k, _z, m, x in bad[:3]
                )
                parts.append(f"Where it fails: {txt}.")
            else:
                parts.append("No localisation quantity differs from the measurement by more than 3 standard errors.")
        chosen = self.steps[1:]
        if not chosen:
            best = self.candidates[0] if self.candidates else None
            extra = ""
            if best is not None:
                extra = (
                    f" The best candidate, {best.effect}, would change it by {best.improvement:+.4f} +- "
                    f"{best.improvement_se:.4f} alpha ({best.reason})."
                )
            parts.append(f"No effect is needed: nothing improves the held-out error significantly.{extra}")
        else:
            for s in chosen:
                prm = "; ".join(
                    ", ".join(f"{k} = {_fmt_num(v)}" for k, v in dict(s.effects)[n].items()) for n in s.added_names
                )
                how = (
                    "added by hand"
                    if s.by_hand
                    else ("explain it together" if len(s.added_names) > 1 else "explains it")
                )
                parts.append(
                    f"{s.added} ({prm}) {how}: held-out error {s.heldout_error:.4f} +- {s.heldout_se:.4f} alpha "
                    f"(improvement {s.improvement:.4f} +- {s.improvement_se:.4f}"
                    f"{'' if s.significant else ', not significant'})."
                )
            parts.append(
                f"In all the held-out error fell by {100 * self.reduction:.0f} % "
                f"({b.heldout_error:.4f} -> {self.final.heldout_error:.4f} alpha)."
            )
        return " ".join(parts)

    def to_dict(self) -> dict:
        """Plain data for JSON: baseline, candidates, selected, final, ladder, rounds, settings."""

        def err(step: Step) -> dict:
            return {
                "heldout_error": step.heldout_error,
                "heldout_se": step.heldout_se,
                "train_error": step.train_error,
                "noise_floor": self.noise_floor,
                "effects": [{"name": n, "params": _clean(p)} for n, p in step.effects],
            }

        return {
            "campaign": self.campaign.name,
            "baseline": err(self.baseline),
            "candidates": [c.to_dict() for c in self.candidates],
            "selected": list(self.selected),
            "added": list(self.added),
            "final": {**err(self.final), "reduction": self.reduction},
            "ladder": [s.to_dict() for s in self.steps],
            "rounds": [[c.to_dict() for c in r] for r in self.rounds],
            "test_level": self.test_level,
            "train_ids": list(self.train_ids),
            "heldout_ids": list(self.heldout_ids),
            "skipped": [list(s) for s in self.campaign.skipped],
            "settings": self.settings,
            "summary": self.summary(),
            "elapsed_s": self.elapsed,
        }

    def to_json(self, path: str | Path | None = None) -> str:
        """The JSON text of :meth:`to_dict`; also written to ``path`` when given."""
        text = json.dumps(_sanitize(self.to_dict()), indent=2, allow_nan=False, default=_json_default)
        if path is not None:
            Path(path).write_text(text + "\n")
        return text


def _fmt_num(v: float) -> str:
    return f"{v:.4g}"


def _nan_none(v: float):
    return None if v is None or (isinstance(v, float) and not math.isfinite(v)) else v


def _clean(params: dict) -> dict:
    return {k: _nan_none(float(v)) for k, v in params.items()}


def _json_default(o):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def _sanitize(x):
    """NaN and infinities as JSON null, recursively (strict JSON has no NaN)."""
    if isinstance(x, dict):
        return {k: _sanitize(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_sanitize(v) for v in x]
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    return x


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
    from scipy import stats as sps

    d_all = cur - new
    d, se = _paired(cur, new)
    z = d / se if se > 0 else (math.inf if d > 0 else 0.0)
    nz = d_all[d_all != 0.0]
    if nz.size == 0:
        return False, d, se, z, 1.0, "changes nothing"
    pval = float(sps.wilcoxon(nz, alternative="greater", zero_method="wilcox").pvalue) if nz.size >= 2 else 1.0
    need = NOISE_MARGIN * floor
    if not d > 0:
        return False, d, se, z, pval, "no improvement"
    if pval > test_level:
        return False, d, se, z, pval, f"within its uncertainty (p = {pval:.2g} > {test_level:.2g})"
    if d < need:
        return False, d, se, z, pval, f"below the noise floor margin ({d:.4f} < {need:.4f} alpha)"
    return True, d, se, z, pval, f"p = {pval:.2g} <= {test_level:.2g} and {d:.4f} >= {need:.4f} alpha"


def _compatible(campaign: Campaign, model_effects: list, name: str) -> str:
    """'' if ``name`` can join the model, else the reason."""
    from housner.effects import apply_effects, effect_class

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


def diagnose(
    campaign: Campaign | str | Path,
    *,
    effects: Iterable[str] | None = None,
    add: Sequence[str] = (),
    train_fraction: float = 0.5,
    seed=0,
    max_effects: int = MAX_EFFECTS,
    level: float = LEVEL,
    engine_settings: dict | None = None,
    compare_steps: bool = True,
    pairs: bool = True,
    progress: Callable[[str], None] | None = None,
) -> Diagnosis:
    """Find the physical effect(s) missing from the Housner model of a campaign.

    Parameters
    ----------
    campaign : Campaign or path
        The measurements (a path is read with :func:`scenarios.campaign.load_campaign`).
    effects : iterable of str, optional
        Candidate effects (registry names); default every registered effect.
    add : sequence of str
        Effects to add by hand first, in order (fitted, whatever their significance).
    train_fraction : float
        Share of the ground-motion records used for fitting [-].
    seed : int
        Seed of the split of the ground-motion records.
    max_effects : int
        Most effects the greedy search adds.
    level : float
        Family-wise significance level of each round [-].
    engine_settings : dict, optional
        Settings of the analytic engine (``r``, ``substeps``).
    compare_steps : bool
        Also run the full :func:`scenarios.compare.compare` (localisation
        included) for every step of the ladder, for the report.
    pairs : bool
        When no single effect helps significantly, also try the pairs among
        the three that lowered the training error most, fitted jointly.
    progress : callable, optional
        Called with a line of text as the search goes.

    Returns
    -------
    Diagnosis
        See the module docstring for the method. ``selected`` is empty when
        the plain model already explains the data within the noise.
    """
    t_start = time.perf_counter()
    if not isinstance(campaign, Campaign):
        from scenarios.campaign import load_campaign

        campaign = load_campaign(campaign)
    from housner.effects import available_effects

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
    say = progress or (lambda s: None)
    spec = campaign.specimen
    train_ids, held_ids = split_records(campaign, train_fraction, seed)
    train = _Scorer(campaign, train_ids, engine_settings)
    held = _Scorer(campaign, held_ids, engine_settings)
    fv_ids = [r.id for r in campaign.free_vibration]
    gm_train = [i for i in train_ids if i not in set(fv_ids)]
    train_mech = train.subset(fv_ids[:1] + gm_train[:MAX_MECHANICS_FIT_RECORDS])
    floor = float(np.mean([campaign.record(i).noise for i in held_ids])) / spec.alpha

    def build(model: list[tuple[str, dict]]) -> list:
        return [_make(n, p) for n, p in model]

    def scorer_for(model_effects: list) -> _Scorer:
        return train_mech if any(type(e).changes_mechanics for e in model_effects) else train

    base_train = float(np.mean(train.errors([])))
    base_held = held.errors([])
    baseline = Step((), None, False, base_train, float(base_held.mean()), _se(base_held), math.nan, math.nan, False,
                    base_held)  # fmt: skip
    say(f"baseline: held-out error {baseline.heldout_error:.4f} +- {baseline.heldout_se:.4f} alpha "
        f"(noise floor {floor:.4f})")  # fmt: skip
    steps = [baseline]
    model: list[tuple[str, dict]] = []
    cur_held, cur_train = base_held, base_train

    def try_candidate(name: str, model: list[tuple[str, dict]], rnd: int, cur: np.ndarray, test_level: float):
        fixed = build(model)
        from housner.effects import effect_class

        sc = train_mech if effect_class(name).changes_mechanics else scorer_for(fixed)

        def objective(effect) -> float:
            return float(np.mean(sc.errors([*fixed, effect])))

        params, tr_err, _nev = fit_effect(name, objective, spec)
        he = held.errors([*fixed, _make(name, params)])
        sig, d, se, z, pval, why = _judge(cur, he, test_level, floor)
        return Candidate(name, params, tuple(n for n, _ in model), rnd, tr_err, float(he.mean()), _se(he), d, se,
                         z, pval, sig, why, he)  # fmt: skip

    def level_for(m: int) -> float:
        return level / max(m, 1)

    # effects added by hand
    for name in add:
        reason = _compatible(campaign, build(model), name)
        if reason:
            raise ValueError(f"cannot add {name!r} to {[n for n, _ in model] or 'the plain model'}: {reason}")
        c = try_candidate(name, model, 0, cur_held, level_for(1))
        model = [*model, (name, c.params)]
        model, tr = _joint_refit(model, scorer_for(build(model)), spec)
        he = held.errors(build(model))
        sig, d, se, _z, _p, _why = _judge(cur_held, he, level_for(1), floor)
        steps.append(Step(tuple(model), name, True, tr, float(he.mean()), _se(he), d, se, sig, he))
        cur_held, cur_train = he, tr
        say(f"+ {name} (by hand) {_fmt_params(c.params)}: held-out error {he.mean():.4f}")

    def _try_pairs(results, model, cur_train, cur_held, test_level):
        # Only candidates that lowered the training error by more than the noise floor pair up:
        # the others are fitting noise (and cost time).
        helped = sorted(
            (c for c in results if c.train_error < cur_train - NOISE_MARGIN * floor), key=lambda c: c.train_error
        )
        fixed = build(model)
        out = []
        for i, j in ((0, 1), (0, 2), (1, 2)):
            if j >= len(helped):
                continue
            a, b = helped[i], helped[j]
            if _compatible(campaign, [*fixed, _make(a.effect, a.params)], b.effect):
                continue
            # Two starts, each effect's own fit with the other fitted given it, then both together
            # from each (the joint optimum of correlated parameters lies along a narrow valley that
            # a single local search from one start often misses); the model's own effects keep their
            # parameters, so that the improvement is the pair's.
            sc = scorer_for([*fixed, _make(a.effect, a.params), _make(b.effect, b.params)])
            pb, _e, _n = fit_effect(b.effect, _objective(sc, [*fixed, _make(a.effect, a.params)], []), spec)
            pa, _e, _n = fit_effect(a.effect, _objective(sc, fixed, [_make(b.effect, b.params)]), spec)
            tries = [
                _joint_refit([*model, (a.effect, a.params), (b.effect, pb)], sc, spec, 30, free_from=len(model)),
                _joint_refit([*model, (a.effect, pa), (b.effect, b.params)], sc, spec, 30, free_from=len(model)),
            ]
            both, tr = min(tries, key=lambda x: x[1])
            he = held.errors(build(both))
            sig, d, se, z, pval, why = _judge(cur_held, he, test_level, floor)
            name = f"{a.effect} + {b.effect}"
            prm = {f"{n}.{k}": v for n, p in both[len(model) :] for k, v in p.items()}
            cand = Candidate(name, prm, tuple(n for n, _ in model), a.round, tr, float(he.mean()), _se(he), d, se,
                             z, pval, sig, why, he)  # fmt: skip
            say(f"round {a.round}: {name:32s} {_fmt_params(prm):40s} held-out {he.mean():.4f} improvement "
                f"{d:+.4f} +- {se:.4f} {'*' if sig else ' '} (pair)")  # fmt: skip
            out.append((cand, both, tr, he))
        return out

    rounds: list[list[Candidate]] = []
    selected: list[str] = []
    first_level = level_for(len(cands))
    for rnd in range(1, max_effects + 1):
        in_model = {n for n, _ in model}
        pool = [n for n in cands if n not in in_model and not _compatible(campaign, build(model), n)]
        if not pool:
            break
        zc = level_for(len(pool))
        if rnd == 1:
            first_level = zc
        results = []
        for name in pool:
            t0 = time.perf_counter()
            c = try_candidate(name, model, rnd, cur_held, zc)
            results.append(c)
            say(f"round {rnd}: {name:32s} {_fmt_params(c.params):40s} held-out {c.heldout_error:.4f} "
                f"improvement {c.improvement:+.4f} +- {c.improvement_se:.4f} "
                f"{'*' if c.significant else ' '} ({time.perf_counter() - t0:.1f} s)")  # fmt: skip
        results.sort(key=lambda c: -c.improvement if math.isfinite(c.improvement) else math.inf)
        best = results[0]
        if best.significant:
            rounds.append(results)
            model = [*model, (best.effect, best.params)]
            model, tr = _joint_refit(model, scorer_for(build(model)), spec)
            he = held.errors(build(model))
            _sig, d, se, _z, _p, _why = _judge(cur_held, he, level_for(len(pool)), floor)
            steps.append(Step(tuple(model), best.effect, False, tr, float(he.mean()), _se(he), d, se, True, he))
            selected.append(best.effect)
            cur_held, cur_train = he, tr
            say(f"+ {best.effect}: held-out error {he.mean():.4f} +- {_se(he):.4f} alpha")
            continue
        # No effect helps alone. Two effects may (a mis-stated p also mis-states Housner's r): fit the
        # pairs among the three that lowered the training error most jointly, as three more tests.
        tried = _try_pairs(results, model, cur_train, cur_held, level_for(len(pool) + 3)) if pairs else []
        results.extend(p[0] for p in tried)
        results.sort(key=lambda c: -c.improvement if math.isfinite(c.improvement) else math.inf)
        rounds.append(results)
        good = sorted((p for p in tried if p[0].significant), key=lambda p: -p[0].improvement)
        if not good:
            break
        cand, model, tr, he = good[0]
        d, se = cand.improvement, cand.improvement_se
        steps.append(Step(tuple(model), cand.effect, False, tr, float(he.mean()), _se(he), d, se, True, he))
        selected.extend(cand.effect.split(" + "))
        cur_held, cur_train = he, tr
        say(f"+ {cand.effect}: held-out error {he.mean():.4f} +- {_se(he):.4f} alpha")

    if compare_steps:
        done = []
        for s in steps:
            cmp = compare(campaign, "housner", build(list(s.effects)), engine_settings)
            done.append(_with_comparison(s, cmp))
        steps = done
    diag = Diagnosis(
        campaign=campaign,
        baseline=steps[0],
        steps=steps,
        candidates=rounds[0] if rounds else [],
        rounds=rounds,
        selected=selected,
        added=list(add),
        noise_floor=floor,
        test_level=first_level,
        train_ids=train_ids,
        heldout_ids=held_ids,
        settings={
            "effects": cands,
            "add": list(add),
            "train_fraction": train_fraction,
            "seed": seed if isinstance(seed, (int, type(None))) else str(seed),
            "max_effects": max_effects,
            "level": level,
            "noise_margin": NOISE_MARGIN,
            "pairs": pairs,
            "engine_settings": dict(engine_settings or {}),
        },
    )
    diag.elapsed = time.perf_counter() - t_start
    return diag


def _with_comparison(step: Step, cmp: Comparison) -> Step:
    from dataclasses import replace

    return replace(step, comparison=cmp)


def _se(v: np.ndarray) -> float:
    return float(np.std(v, ddof=1) / math.sqrt(v.size)) if v.size > 1 else math.nan


def _fmt_params(p: dict) -> str:
    return ", ".join(f"{k}={v:.4g}" for k, v in p.items())
