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
from scenarios.compare import (
    ERROR_CLIP,
    Comparison,
    compare,
    error_window,
    release_sensitivities,
    scored_error,
    simulate_records,
)

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
#: Grid points per parameter of an effect with several parameters, and of the zoom around its best
#: point [-]: a 9 x 9 grid puts a point within 7 % of any frequency in 10-100 Hz (log-spaced), and the
#: error of a flexible foundation's fit doubles within ~10 % of its frequency (measured on a
#: synthetic 25 Hz campaign), so a coarser grid can land outside the basin.
N_GRID_MULTI = 9
N_ZOOM_MULTI = 5
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
#: Effects that replace the equation of motion run their own (slower, 10-100x) kernels: their grid
#: search runs on the free vibrations and this many ground motions spread over the campaign, the
#: local search that ends the fit on all records [-].
MECHANICS_GRID_RECORDS = 12
#: Cross-validation folds [-]: every record is held out once, so the answer rests on all of them
#: and depends far less on the assignment than one random split does.
DEFAULT_FOLDS = 5
#: Local search budget of a fold's refit, started from the fit on all records (Brent iterations).
FOLD_ITERATIONS = 8
#: Nelder-Mead evaluations per parameter of a fold's joint refit.
FOLD_JOINT_FEV = 6
#: Free-vibration localisation quantities a candidate must not contradict (seed section 3.2: they
#: pin p and r), and the |z| beyond which it does (when it is also worse than the current model's).
FV_CHECK = ("p", "energy_ratio")
FV_Z = 3.0
#: Share of the sensor noise a fit can still remove from a record's error [-]: no model scores a
#: record below its noise sigma/alpha but by fitting noise, and a handful of parameters fitted to
#: thousands of samples remove a fraction K/n of its variance (with 10 parameters and 1000 samples:
#: 0.5 % of sigma); the noise estimated from a record is within a few per cent. So when the current
#: model's training error stands less than NOISE_MARGIN above NOISE_FIT x the noise, no candidate can
#: lower it by NOISE_MARGIN and the round is not searched.
NOISE_FIT = 0.9


# ----------------------------------------------------------------------------
# records and errors
def _train_fraction(train_fraction) -> float:
    tf = float(train_fraction)
    if not 0.0 < tf < 1.0:
        raise ValueError(f"`train_fraction` must lie in (0, 1), got {train_fraction!r}")
    return tf


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
    tf = _train_fraction(train_fraction)
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
        self._fv = np.array([r.kind == "free_vibration" for r in self.records])
        # the release angle of a free vibration as a nuisance parameter costs one more run of each
        # (compare.release_error); the basin-finding grids of the mechanics effects do without it
        self.release_angle = True

    def subset(self, ids: Sequence[str]) -> _Scorer:
        out = _Scorer.__new__(_Scorer)
        keep = [i for i, r in enumerate(self.records) if r.id in set(ids)]
        out.campaign = self.campaign
        out.records = [self.records[i] for i in keep]
        out.ends = [self.ends[i] for i in keep]
        out.engine_settings = self.engine_settings
        out.n_evaluations = 0
        out._fv = self._fv[keep]
        out.release_angle = self.release_angle
        return out

    def loss(self, effects: Sequence[Any]) -> float:
        """The fitting objective [alpha]: the mean error of the free vibrations and the mean error of
        the ground motions, averaged with equal weights (one group alone: its mean).

        A free vibration is not chaotic: a correct model scores its noise to within ~2 %, so a few of
        them pin p, r and the contact law (seed section 3.2), while a ground motion's error scatters by
        tens of per cent with the chaos. A plain mean over ~60 records would let that scatter outvote
        the three free vibrations, and fits (the fold refits above all) would wander off what they pin.
        """
        return self._weigh(self.errors(effects))

    def noise_loss(self) -> float:
        """:meth:`loss` of a model that left nothing but the sensor noise [alpha]: each record's noise
        sigma / alpha in place of its error, the least a model can score without fitting noise."""
        alpha = self.campaign.specimen.alpha
        return self._weigh(np.array([r.noise / alpha for r in self.records]))

    def _weigh(self, e: np.ndarray) -> float:
        fv = self._fv
        if fv.all() or not fv.any():
            return float(e.mean())
        return 0.5 * float(e[fv].mean()) + 0.5 * float(e[~fv].mean())

    def errors(self, effects: Sequence[Any]) -> np.ndarray:
        """Error per record [alpha]; a record the model fails on scores the clip value (1)."""
        self.n_evaluations += 1
        alpha = self.campaign.specimen.alpha
        spec = self.campaign.specimen
        res = simulate_records(spec, self.records, "housner", effects, self.engine_settings)
        sens = (release_sensitivities(spec, self.records, res, "housner", effects, self.engine_settings)
                if self.release_angle else [None] * len(res))  # fmt: skip
        out = np.empty(len(self.records))
        for k, (rec, r, end) in enumerate(zip(self.records, res, self.ends, strict=True)):
            out[k] = ERROR_CLIP if isinstance(r, str) else scored_error(r.theta, rec, end, alpha, sens[k])
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
    local_iterations: int = 14,
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
    local_iterations : int
        Budget of the local search: Brent iterations (one parameter); Powell
        evaluations are 10/14 of it per parameter (more).

    Returns
    -------
    (params, error, n_evaluations)

    Notes
    -----
    One parameter: a grid of :data:`N_GRID` points (plus the neutral value
    when it lies inside the bounds, so the fit is never worse than the effect
    switched off), a zoom grid of :data:`N_ZOOM` points over +-1 step around
    the best, then a bounded Brent search over +-1 zoom step. d parameters:
    a grid of :data:`N_GRID_MULTI` points per parameter, a zoom grid of
    :data:`N_ZOOM_MULTI` points per parameter over +-1 step around the best,
    then a bounded Powell search of at most 10 d evaluations.
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
        npd = N_GRID if len(dims) == 1 else N_GRID_MULTI
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
        else:
            # a zoom grid of N_ZOOM_MULTI points per parameter over +-1 step around the best point
            zaxes = [np.linspace(max(a, u - st), min(b, u + st), N_ZOOM_MULTI)
                     for a, b, u, st in zip(lo, hi, best_u, step, strict=True)]  # fmt: skip
            zpts = np.array(np.meshgrid(*zaxes, indexing="ij")).reshape(len(dims), -1).T
            zvals = np.array([f_u(p) for p in zpts])
            if zvals.min() <= f_u(best_u):
                best_u = zpts[int(np.argmin(zvals))]
        step = step / ((N_ZOOM - 1) / 2) if len(dims) == 1 else step / ((N_ZOOM_MULTI - 1) / 2)
    else:
        step = (hi - lo) / (N_GRID - 1)
    if len(dims) == 1:
        a = max(lo[0], best_u[0] - step[0])
        b = min(hi[0], best_u[0] + step[0])
        if b > a:
            res = optimize.minimize_scalar(
                lambda x: f_u([x]), bounds=(a, b), method="bounded",
                options={"xatol": 1e-3 * step[0], "maxiter": local_iterations},
            )  # fmt: skip
            if res.fun <= f_u(best_u):
                best_u = np.array([res.x])
    else:
        res = optimize.minimize(
            f_u, best_u, method="Powell", bounds=list(zip(lo, hi, strict=True)),
            options={"maxfev": max(2, local_iterations * 10 // 14) * len(dims), "xtol": 1e-3, "ftol": 1e-4},
        )  # fmt: skip
        if res.fun <= f_u(best_u):
            best_u = np.asarray(res.x)
    params = {d.key: d.from_u(float(x)) for d, x in zip(dims, best_u, strict=True)}
    return params, f_u(best_u), len(cache)


def _objective(scorer: _Scorer, before: list, after: list) -> Callable[[Any], float]:
    """Training loss (:meth:`_Scorer.loss`) of ``before + [effect] + after`` as a function of ``effect``."""

    def f(effect) -> float:
        return scorer.loss([*before, effect, *after])

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
            return scorer.loss([_make(n, p) for n, p in build(u)])
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
        Per record, out of fold [alpha] (None when not held out).
    fold_wins : ndarray
        Per fold: mean improvement on that fold's records [alpha] (None when not held out).
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
    fold_wins: np.ndarray = field(repr=False, compare=False, default=None)

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
            "fold_improvements": None if self.fold_wins is None else [float(x) for x in self.fold_wins],
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
        Mean sigma/alpha of the records [-]: the sensor noise alone (the verdict uses the measured
        correct-model floor, ``floors``).
    test_level : float
        The per-test significance level of the first round, ``level`` / candidates [-].
    train_ids, heldout_ids : list of str
        Every record (cross-validation: each trains in K - 1 folds and is held out in one).
    settings : dict
    folds : list of list of str
        Record ids of each fold.
    verdict : scenarios.verdict.Verdict
    floors : (Floor, Floor)
        The measured correct-model floor of the plain and of the final model.
    selection_frequency : dict
        Effect -> share of the folds in which it was the best candidate of its round [-].
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
    folds: list = field(default_factory=list)
    verdict: Any = None
    floors: tuple = ()
    selection_frequency: dict = field(default_factory=dict)
    elapsed: float = math.nan

    @property
    def status(self) -> str:
        """The verdict's status (see :data:`scenarios.verdict.STATUSES`)."""
        return self.verdict.status if self.verdict is not None else "inconclusive"

    @property
    def final(self) -> Step:
        return self.steps[-1]

    @property
    def reduction(self) -> float:
        """Fraction of the baseline held-out error removed by the final model [-]."""
        b = self.baseline.heldout_error
        return (b - self.final.heldout_error) / b if b > 0 else 0.0

    def summary(self) -> str:
        """One paragraph: the verdict in words, then the ladder with its figures."""
        parts = [self.verdict.text if self.verdict is not None else ""]
        chosen = self.steps[1:]
        if chosen:
            ladder = []
            for st in chosen:
                prm = "; ".join(
                    ", ".join(f"{k} = {_fmt_num(v)}" for k, v in dict(st.effects)[n].items()) for n in st.added_names
                )
                how = " (by hand)" if st.by_hand else ""
                ladder.append(
                    f"+ {st.added}{how} ({prm}): held-out error {st.heldout_error:.4f} +- {st.heldout_se:.4f} alpha, "
                    f"improvement {st.improvement:.4f} +- {st.improvement_se:.4f}"
                    f"{'' if st.significant else ', not significant'}"
                )
            parts.append("Ladder: " + "; ".join(ladder) + ".")
            parts.append(
                f"In all the held-out error fell by {100 * self.reduction:.0f} % "
                f"({self.baseline.heldout_error:.4f} -> {self.final.heldout_error:.4f} alpha)."
            )
        elif self.candidates:
            best = self.candidates[0]
            if math.isfinite(best.improvement):
                parts.append(
                    f"The best candidate, {best.effect}, would change the held-out error by "
                    f"{best.improvement:+.4f} +- {best.improvement_se:.4f} alpha ({best.reason})."
                )
        k = self.settings.get("folds", "?")
        parts.append(f"({k}-fold cross-validation: every record held out once; sensor noise sigma/alpha "
                     f"{self.noise_floor:.4f}.)")  # fmt: skip
        return " ".join(p for p in parts if p)

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
            "folds": [list(f) for f in self.folds],
            "selection_frequency": dict(self.selection_frequency),
            "verdict": None if self.verdict is None else self.verdict.to_dict(),
            "floor": None
            if not self.floors
            else {
                "baseline": {
                    "per_record": [float(x) for x in self.floors[0].mean],
                    "perturbation": self.floors[0].perturbation,
                    "replicas": self.floors[0].n_replicas,
                },
                "final": {
                    "per_record": [float(x) for x in self.floors[1].mean],
                    "perturbation": self.floors[1].perturbation,
                    "replicas": self.floors[1].n_replicas,
                },
            },
            "localisation": {
                "baseline": self.baseline.comparison.summary() if self.baseline.comparison is not None else None,
                "final": self.final.comparison.summary() if self.final.comparison is not None else None,
            },
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


def cv_folds(campaign: Campaign, folds: int = DEFAULT_FOLDS, seed=0) -> list[list[str]]:
    """Every record in one of ``folds`` folds: free vibrations dealt first, then ground motions, each shuffled.

    Dealing the free vibrations first spreads them over different folds, so each is held out once
    and the others train (they pin p and r, seed section 3.2).

    Parameters
    ----------
    campaign : Campaign
    folds : int
        Number of folds K [-], at least 2.
    seed : int, SeedSequence or Generator
        Seed of the assignment.

    Returns
    -------
    list of K lists of record ids, each in campaign order.
    """
    k = int(folds)
    if k < 2:
        raise ValueError(f"`folds` must be at least 2, got {folds!r}")
    rng = np.random.default_rng(seed)
    out: list[list[str]] = [[] for _ in range(k)]
    j = 0
    for group in ([r.id for r in campaign.free_vibration], [r.id for r in campaign.ground_motion]):
        for i in rng.permutation(len(group)):
            out[j % k].append(group[int(i)])
            j += 1
    order = {r.id: i for i, r in enumerate(campaign.records)}
    return [sorted(f, key=order.__getitem__) for f in out]


@dataclass
class _CV:
    """A model fitted on all records (``full``) and without each fold (``folds``)."""

    full: list[tuple[str, dict]]
    folds: list[list[tuple[str, dict]]]


def _fv_metrics(campaign: Campaign, effects: list, engine_settings) -> dict:
    """Free-vibration localisation (p, energy ratio) of a model, observed through the campaign's sensor."""
    from scenarios.compare import features, observe, on_grid

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
        The measurements (a path is read with :func:`scenarios.campaign.load_campaign`).
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
        Also run the full :func:`scenarios.compare.compare` for the intermediate steps of the ladder
        (the baseline's and the final model's are always run: the verdict needs their localisation).
    pairs : bool
        When no single effect helps significantly, also try the pairs among the three that lowered
        the training error most, fitted jointly.
    n_replicas : int, optional
        Replicas of the floor's parametric bootstrap (default :data:`scenarios.verdict.N_REPLICAS`).
    progress : callable, optional
        Called with a line of text as the search goes.

    Returns
    -------
    Diagnosis
        With its :class:`scenarios.verdict.Verdict` (see the module docstrings of this module and
        of :mod:`scenarios.verdict`).
    """
    from housner.effects import available_effects, effect_class
    from scenarios.localise import measured_features
    from scenarios.verdict import N_REPLICAS, decide, measure_floor, residual_test

    t_start = time.perf_counter()
    if not isinstance(campaign, Campaign):
        from scenarios.campaign import load_campaign

        campaign = load_campaign(campaign)
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
        folds = max(2, int(round(1.0 / (1.0 - _train_fraction(train_fraction)))))
    if not (isinstance(folds, int) and folds >= 2):
        raise ValueError(f"`folds` must be an integer of at least 2, got {folds!r}")
    ids = [r.id for r in campaign.records]
    if len(ids) < 4:
        raise ValueError(
            f"campaign {campaign.name!r} has {len(ids)} usable record(s); the diagnosis needs at least 4 "
            "(some to fit on, some to judge on)"
        )
    n_rep = N_REPLICAS if n_replicas is None else int(n_replicas)
    say = progress or (lambda s: None)
    spec = campaign.specimen
    k_folds = min(folds, len(ids) // 2)
    fold_ids = cv_folds(campaign, k_folds, seed)
    pos = {rid: i for i, rid in enumerate(ids)}
    fold_of = np.empty(len(ids), dtype=int)
    for k, f in enumerate(fold_ids):
        fold_of[[pos[i] for i in f]] = k
    allsc = _Scorer(campaign, ids, engine_settings)
    train_sc = [allsc.subset([i for i in ids if fold_of[pos[i]] != k]) for k in range(k_folds)]
    held_sc = [allsc.subset(fold_ids[k]) for k in range(k_folds)]
    gm_ids = [r.id for r in campaign.ground_motion]
    step = max(1, len(gm_ids) // MECHANICS_GRID_RECORDS)
    mech_sc = allsc.subset([r.id for r in campaign.free_vibration] + gm_ids[::step][:MECHANICS_GRID_RECORDS])
    mech_sc.release_angle = False
    kinds = [r.kind for r in campaign.records]
    floor = float(np.mean([r.noise for r in campaign.records])) / spec.alpha
    measured_fv = {k: v for k, v in measured_features(campaign).metrics().items() if k in FV_CHECK}

    def build(model: list[tuple[str, dict]]) -> list:
        return [_make(n, p) for n, p in model]

    def oof(cv: _CV) -> np.ndarray:
        out = np.empty(len(ids))
        for k in range(k_folds):
            out[fold_of == k] = held_sc[k].errors(build(cv.folds[k]))
        return out

    def fold_means(v: np.ndarray) -> np.ndarray:
        return np.array([v[fold_of == k].mean() for k in range(k_folds)])

    def refit_folds(cv: _CV, free_from: int = 0) -> _CV:
        return _CV(cv.full, [_joint_refit(cv.folds[k], train_sc[k], spec, FOLD_JOINT_FEV, free_from)[0]
                             for k in range(k_folds)])  # fmt: skip

    def add_cv(cv: _CV, name: str, params: dict) -> _CV:
        per = []
        for k in range(k_folds):
            obj = _objective(train_sc[k], build(cv.folds[k]), [])
            pk, _e, _n = fit_effect(name, obj, spec, start=params, local_only=True, local_iterations=FOLD_ITERATIONS)
            per.append([*cv.folds[k], (name, pk)])
        return _CV([*cv.full, (name, params)], per)

    base = _CV([], [[] for _ in range(k_folds)])
    base_train_errors = allsc.errors([])
    base_train = allsc.loss([])
    noise_loss = allsc.noise_loss()
    base_held = base_train_errors.copy()  # no fitted parameter: out-of-fold errors are the plain errors
    baseline = Step((), None, False, base_train, float(base_held.mean()), _se(base_held), math.nan, math.nan, False,
                    base_held)  # fmt: skip
    say(f"baseline: held-out error {baseline.heldout_error:.4f} +- {baseline.heldout_se:.4f} alpha "
        f"(sigma/alpha {floor:.4f}); {k_folds}-fold cross-validation")  # fmt: skip
    steps = [baseline]
    cur, cur_held, cur_train = base, base_held, base_train
    cur_fvz = _fv_z(_fv_metrics(campaign, [], engine_settings), measured_fv)

    def fv_reason(model_effects: list) -> str:
        z = _fv_z(_fv_metrics(campaign, model_effects, engine_settings), measured_fv)
        for k, v in z.items():
            if abs(v) > FV_Z and abs(v) > abs(cur_fvz.get(k, 0.0)):
                m = measured_fv[k]
                return (f"contradicts the free vibrations: {k} is {v:+.1f} standard errors from the measured "
                        f"{m.value:.4g} +- {m.se:.2g}")  # fmt: skip
        return ""

    def level_for(m: int) -> float:
        return level / max(m, 1)

    def candidate(name, params, cv_new, rnd, tr_err, test_level, he=None, reason=""):
        if he is None:
            return Candidate(name, params, tuple(n for n, _ in cur.full), rnd, tr_err, math.nan, math.nan, math.nan,
                             math.nan, math.nan, 1.0, False, reason, None)  # fmt: skip
        sig, d, se, z, pval, why = _judge(cur_held, he, test_level, floor)
        wins = fold_means(cur_held - he)
        return Candidate(name, params, tuple(n for n, _ in cur.full), rnd, tr_err, float(he.mean()), _se(he), d, se,
                         z, pval, sig, why, he, wins)  # fmt: skip

    def try_candidate(name: str, rnd: int, test_level: float):
        fixed = build(cur.full)
        if effect_class(name).changes_mechanics:
            # 10-100x slower kernels: the grid finds the basin on a spread subset of the records, the
            # local search then fits on all of them
            start, e_sub, _n = fit_effect(name, _objective(mech_sc, fixed, []), spec)
            gain_sub = mech_sc.loss(fixed) - e_sub
            if not gain_sub > NOISE_MARGIN * floor:
                why = f"error on {len(mech_sc.records)} records falls by {gain_sub:+.4f} < " \
                      f"{NOISE_MARGIN * floor:.4f} alpha (noise floor): not fitted further"  # fmt: skip
                return candidate(name, start, None, rnd, e_sub, test_level, reason=why), None
            # the basin found on the subset must carry over to every record before the (costly) local fit
            e_all = allsc.loss([*fixed, _make(name, start)])
            if not cur_train - e_all > NOISE_MARGIN * floor:
                why = f"the subset's best point lowers the error on all records by {cur_train - e_all:+.4f} < " \
                      f"{NOISE_MARGIN * floor:.4f} alpha (noise floor): not fitted further"  # fmt: skip
                return candidate(name, start, None, rnd, e_all, test_level, reason=why), None
            params, tr_err, _nev = fit_effect(name, _objective(allsc, fixed, []), spec, start=start, local_only=True,
                                              local_iterations=FOLD_ITERATIONS)  # fmt: skip
        else:
            params, tr_err, _nev = fit_effect(name, _objective(allsc, fixed, []), spec)
        gain = cur_train - tr_err
        if not gain > NOISE_MARGIN * floor:
            why = f"training error falls by {gain:+.4f} < {NOISE_MARGIN * floor:.4f} alpha (noise floor): not held out"
            return candidate(name, params, None, rnd, tr_err, test_level, reason=why), None
        bad = fv_reason([*fixed, _make(name, params)])
        if bad:
            return candidate(name, params, None, rnd, tr_err, test_level, reason=bad), None
        # The held-out test asks the mean error per record to fall by the noise margin. On the records
        # it was fitted to, the effect does at least as well as out of fold (in expectation): when even
        # there it falls by less, the fold refits (5 more fits, the costliest part for a mechanics
        # effect) cannot pass and are not run. (The training loss weighs the free vibrations as a
        # group, so it can fall while the mean per record does not.)
        gain_in = float(np.mean(cur_held - allsc.errors([*fixed, _make(name, params)])))
        if not gain_in > NOISE_MARGIN * floor:
            why = f"even on the records it was fitted to, the mean error per record falls by {gain_in:+.4f} < " \
                  f"{NOISE_MARGIN * floor:.4f} alpha (noise floor): not held out"  # fmt: skip
            return candidate(name, params, None, rnd, tr_err, test_level, reason=why), None
        cv_new = add_cv(cur, name, params)
        he = oof(cv_new)
        return candidate(name, params, cv_new, rnd, tr_err, test_level, he), cv_new

    # effects added by hand
    for name in add:
        reason = _compatible(campaign, build(cur.full), name)
        if reason:
            raise ValueError(f"cannot add {name!r} to {[n for n, _ in cur.full] or 'the plain model'}: {reason}")
        params, _tr, _n = fit_effect(name, _objective(allsc, build(cur.full), []), spec)
        cv_new = add_cv(cur, name, params)
        full, tr = _joint_refit(cv_new.full, allsc, spec)
        cv_new = refit_folds(_CV(full, cv_new.folds))
        he = oof(cv_new)
        sig, d, se, _z, _p, _why = _judge(cur_held, he, level_for(1), floor)
        steps.append(Step(tuple(cv_new.full), name, True, tr, float(he.mean()), _se(he), d, se, sig, he))
        cur, cur_held, cur_train = cv_new, he, tr
        say(f"+ {name} (by hand) {_fmt_params(params)}: held-out error {he.mean():.4f}")

    def try_pairs(results, test_level):
        # Only candidates that lowered the training error by more than the noise floor pair up:
        # the others are fitting noise (and cost time).
        helped = sorted((c for c in results if c.train_error < cur_train - NOISE_MARGIN * floor),
                        key=lambda c: c.train_error)  # fmt: skip
        fixed = build(cur.full)
        n0 = len(cur.full)
        out = []
        for i, j in ((0, 1), (0, 2), (1, 2)):
            if j >= len(helped):
                continue
            a, b = helped[i], helped[j]
            if _compatible(campaign, [*fixed, _make(a.effect, a.params)], b.effect):
                continue
            # Two starts, each effect's own fit with the other fitted given it, then both together from
            # each (the joint optimum of correlated parameters lies along a narrow valley that a single
            # local search from one start often misses); the model's own effects keep their parameters.
            pb, _e, _n = fit_effect(b.effect, _objective(allsc, [*fixed, _make(a.effect, a.params)], []), spec)
            pa, _e, _n = fit_effect(a.effect, _objective(allsc, fixed, [_make(b.effect, b.params)]), spec)
            tries = [
                _joint_refit([*cur.full, (a.effect, a.params), (b.effect, pb)], allsc, spec, 30, free_from=n0),
                _joint_refit([*cur.full, (a.effect, pa), (b.effect, b.params)], allsc, spec, 30, free_from=n0),
            ]
            both, tr = min(tries, key=lambda x: x[1])
            name = f"{a.effect} + {b.effect}"
            prm = {f"{n}.{k}": v for n, p in both[n0:] for k, v in p.items()}
            bad = fv_reason(build(both))
            if bad:
                out.append((candidate(name, prm, None, a.round, tr, test_level, reason=bad), None, tr))
                continue
            cv_new = refit_folds(_CV(both, [[*f, *both[n0:]] for f in cur.folds]), free_from=n0)
            he = oof(cv_new)
            cand = candidate(name, prm, cv_new, a.round, tr, test_level, he)
            say(
                f"round {a.round}: {name:32s} {_fmt_params(prm):40s} held-out {he.mean():.4f} improvement "
                f"{cand.improvement:+.4f} +- {cand.improvement_se:.4f} {'*' if cand.significant else ' '} (pair)"
            )
            out.append((cand, cv_new, tr))
        return out

    rounds: list[list[Candidate]] = []
    selected: list[str] = []
    first_level = level_for(len(cands))
    for rnd in range(1, max_effects + 1):
        in_model = {n for n, _ in cur.full}
        pool = [n for n in cands if n not in in_model and not _compatible(campaign, build(cur.full), n)]
        if not pool:
            break
        zc = level_for(len(pool))
        if rnd == 1:
            first_level = zc
        reach = cur_train - NOISE_MARGIN * floor
        if reach <= NOISE_FIT * noise_loss:
            why = (f"the training error {cur_train:.4f} alpha is within {NOISE_MARGIN * floor:.4f} of the sensor "
                   f"noise ({noise_loss:.4f}): no effect can lower it by the noise margin; not searched")
            rounds.append([candidate(n, {}, None, rnd, math.nan, zc, reason=why) for n in pool])
            say(f"round {rnd}: {why}")
            break
        results, models = [], {}
        for name in pool:
            t0 = time.perf_counter()
            c, cv_new = try_candidate(name, rnd, zc)
            results.append(c)
            models[name] = cv_new
            held = f"held-out {c.heldout_error:.4f} improvement {c.improvement:+.4f} +- {c.improvement_se:.4f} " \
                   f"{'*' if c.significant else ' '}" if cv_new is not None else c.reason  # fmt: skip
            say(f"round {rnd}: {name:32s} {_fmt_params(c.params):40s} {held} ({time.perf_counter() - t0:.1f} s)")
        results.sort(key=_rank)
        best = results[0]
        chosen = None
        if best.significant:
            chosen = (best, models[best.effect])
        elif pairs:
            tried = try_pairs(results, level_for(len(pool) + 3))
            results.extend(p[0] for p in tried)
            results.sort(key=_rank)
            good = sorted((p for p in tried if p[0].significant), key=lambda p: -p[0].improvement)
            if good:
                chosen = (good[0][0], good[0][1])
        rounds.append(results)
        if chosen is None:
            break
        cand, cv_new = chosen
        full, tr = _joint_refit(cv_new.full, allsc, spec)
        cv_new = refit_folds(_CV(full, cv_new.folds))
        he = oof(cv_new)
        _sig, d, se, _z, _p, _why = _judge(cur_held, he, zc, floor)
        steps.append(Step(tuple(cv_new.full), cand.effect, False, tr, float(he.mean()), _se(he), d, se, True, he))
        selected.extend(cand.effect.split(" + "))
        cur, cur_held, cur_train = cv_new, he, tr
        say(f"+ {cand.effect}: held-out error {he.mean():.4f} +- {_se(he):.4f} alpha")

    # the verdict: both ends of the ladder against their measured floors
    # the baseline's and the final model's comparisons always (the verdict's localisation), the rest on request
    last = len(steps) - 1
    cmps = {i: compare(campaign, "housner", build(list(steps[i].effects)), engine_settings)
            for i in range(len(steps)) if compare_steps or i in (0, last)}  # fmt: skip
    steps = [_with_comparison(s, cmps[i]) if i in cmps else s for i, s in enumerate(steps)]
    seed_int = seed if isinstance(seed, int) else 0
    say("measuring the correct-model floor (parametric bootstrap)")
    floor_base = measure_floor(allsc, [], base.folds, fold_of, n_replicas=n_rep, seed=seed_int)
    floor_fin = floor_base if not cur.full else measure_floor(allsc, cur.full, cur.folds, fold_of,
                                                               n_replicas=n_rep, seed=seed_int)  # fmt: skip
    res_base = residual_test(base_held, floor_base, kinds)
    res_fin = residual_test(cur_held, floor_fin, kinds)
    verdict = decide(
        n_records=len(ids), baseline=res_base, final=res_fin, selected=selected, params=dict(cur.full),
        baseline_cmp=steps[0].comparison, final_cmp=steps[-1].comparison, library=cands,
    )  # fmt: skip
    say(f"verdict: {verdict.status}")
    sel_freq: dict[str, float] = {}
    for r in rounds:
        cv_c = [c for c in r if c.fold_wins is not None]
        wins: dict[str, int] = {}
        for k in range(k_folds):
            best_k = max(cv_c, key=lambda c: c.fold_wins[k], default=None)
            if best_k is not None and best_k.fold_wins[k] > 0:
                wins[best_k.effect] = wins.get(best_k.effect, 0) + 1
        for c in cv_c:
            sel_freq[c.effect] = max(sel_freq.get(c.effect, 0.0), wins.get(c.effect, 0) / k_folds)
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
        train_ids=ids,
        heldout_ids=ids,
        settings={
            "effects": cands,
            "add": list(add),
            "folds": k_folds,
            "seed": seed if isinstance(seed, (int, type(None))) else str(seed),
            "max_effects": max_effects,
            "level": level,
            "noise_margin": NOISE_MARGIN,
            "pairs": pairs,
            "replicas": n_rep,
            "engine_settings": dict(engine_settings or {}),
        },
        folds=fold_ids,
        verdict=verdict,
        floors=(floor_base, floor_fin),
        selection_frequency=sel_freq,
    )
    diag.elapsed = time.perf_counter() - t_start
    return diag


def _rank(c: Candidate) -> float:
    return -c.improvement if math.isfinite(c.improvement) else math.inf


def _with_comparison(step: Step, cmp: Comparison) -> Step:
    from dataclasses import replace

    return replace(step, comparison=cmp)


def _se(v: np.ndarray) -> float:
    return float(np.std(v, ddof=1) / math.sqrt(v.size)) if v.size > 1 else math.nan


def _fmt_params(p: dict) -> str:
    return ", ".join(f"{k}={v:.4g}" for k, v in p.items())
