"""Outcome records: predict P(overturn) from an ensemble, find the effect the outcomes need, judge at the floor.

A test whose only measurement is whether the block overturned (and the table motion) is scored as a
probability. :func:`diagnose_outcomes` runs the mission loop on a campaign's outcome records: the plain model
(the scan's planar block, its uncertain pivots and table amplitude sampled into an ensemble per record, a
lapse rate as the outcomes' noise model), where it fails, the effects ``contact_inside`` and ``restitution``
fitted on the log loss with cross-validation and added by a one-sided Diebold-Mariano test, and the verdict
against the floor and logistic baselines on PGA and PGV. The ensembles are computed once as tables of
overturns over a grid of the effects' parameters, which the fits reweight. The method step by step is in
``docs/explanation/diagnosis.md`` ("Outcome records"); the scores are
:mod:`housner.scenarios.diagnosis.outcomes.outcome_scores`', the result classes
:mod:`housner.scenarios.diagnosis.outcomes.outcome_results`'.

References
----------
Diebold, F. X., Mariano, R. S. (1995). Comparing predictive accuracy. Journal of
Business & Economic Statistics 13(3), 253-263.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from housner.model import theta_max_many
from housner.rocking_params import RockingParams
from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.campaigns.campaign_records import OutcomeRecord
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
    per_record_log_loss,
    point_scores,
    seed_spread,
)
from housner.scenarios.diagnosis.outcomes.outcome_validation import (
    BASELINES,
    REPEATS,
    baseline_oof,
    compare_log_loss,
    grouped_folds,
    judge_outcome_model,
    repeat_seeds,
)
from housner.scenarios.diagnosis.selection.forward_selection import Round, forward_selection
from housner.scenarios.diagnosis.verdict.status import status_rule
from housner.units import G

__all__ = [
    "ALPHA_GRID",
    "AMPLITUDE_SPREAD",
    "OUTCOME_EFFECTS",
    "ROUNDS",
    "R_GRID",
    "Geometry",
    "OutcomeEvidence",
    "diagnose_outcomes",
]

#: The table's amplitude is sampled within +-this share [-] (a 2 % calibration of the accelerometer, and a
#: nearby record for the chaos of a long one).
AMPLITUDE_SPREAD = 0.02
#: Points of the effective-contact grid (alpha_eff, log-spaced) [-].
ALPHA_GRID = 28
#: The grid spans alpha_eff from this share of the plain model's smaller alpha up to its larger alpha [-].
ALPHA_GRID_LOW = 0.25
#: Restitution values tried [-] (besides Housner's impact law of each geometry, which needs no parameter).
R_GRID = (0.95, 0.9, 0.8, 0.7, 0.6)
#: Log-normal spreads of alpha_eff the fit chooses from [-] (0.3: alpha known to within about 30 %).
SPREADS = (0.02, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.7)
#: Lapse rates the fit chooses from [-]: the share of outcomes the model does not decide (:func:`_lapse`).
LAPSES = (0.0005, 0.001, 0.002, 0.005, 0.01, 0.02, 0.04, 0.08, 0.15, 0.25)
#: Points of the finer grid of log(alpha_eff) the fit searches (the weights interpolate between the runs) [-].
_MU_POINTS = 80
#: Family-wise level of the test that adds an effect [-].
LEVEL = 0.05
#: The candidate effects of outcome records, and what each stands for.
OUTCOME_EFFECTS = {
    "contact_inside": "a contact inside the footprint (a convex or uneven base): an effective alpha, with its spread",
    "restitution": "the impacts' restitution r, fitted (Housner's law fixes it from the geometry)",
}


@dataclass(frozen=True)
class Geometry:
    """The planar block behind an outcome model: centre-of-mass height, pivots, inertia.

    Attributes
    ----------
    h : float
        Centre-of-mass height above the contact [m].
    b_pos, b_neg : float
        Horizontal distance from the centre of mass to the +x and -x pivot [m].
    ic : float
        Centroidal moment of inertia about the rocking axis [kg m^2].
    mass : float
        [kg]
    bracket : dict
        ``{"pos": (lo, hi), "neg": (lo, hi)}``: each pivot's range of b [m] (the specimen's uncertainty).
    """

    h: float
    b_pos: float
    b_neg: float
    ic: float
    mass: float
    bracket: dict = field(default_factory=dict)

    @property
    def alpha_pos(self) -> float:
        return math.atan2(self.b_pos, self.h)

    @property
    def alpha_neg(self) -> float:
        return math.atan2(self.b_neg, self.h)

    def params(self, b_pos: float | None = None, b_neg: float | None = None, r: float | None = None):
        """RockingParams of the block with these pivots [m]; ``r`` None is Housner's impact law (angular
        momentum about the landing pivot, per side), else one r [-] for every impact."""
        bp = self.b_pos if b_pos is None else b_pos
        bn = self.b_neg if b_neg is None else b_neg
        params = RockingParams.from_pivots(bp, bn, self.h, self.ic, self.mass)
        return params if r is None else replace(params, r=r, r_pos=None, r_neg=None)

    @classmethod
    def of(cls, campaign: Campaign) -> Geometry:
        """The campaign's block: from its scan mesh (with the bracket of alpha) or from its dimensions."""
        scan = campaign.scan
        if scan is not None:
            h = scan.pos.h
            bracket = {s: tuple(h * math.tan(a) for a in scan.alpha_bracket[s]) for s in ("pos", "neg")}
            return cls(h, scan.pos.b, scan.neg.b, scan.centroidal_inertia, scan.mass, bracket)
        s = campaign.specimen
        return cls(s.H, s.B, s.B, s.centroidal_inertia, s.mass, {"pos": (s.B, s.B), "neg": (s.B, s.B)})


# ----------------------------------------------------------------------------
# the ensembles
def _overturns(accs: list, dts: np.ndarray, geo: Geometry, specimen, settings: list) -> np.ndarray:
    """Overturned or not, per record and per setting (b_pos, b_neg, r, amplitude): (records, settings) bool."""
    out = np.empty((len(accs), len(settings)), dtype=bool)
    for j, (bp, bn, r, amp) in enumerate(settings):
        rows = accs if amp == 1.0 else [a * amp for a in accs]
        _, ov, _ = theta_max_many(specimen, rows, dts, params=geo.params(bp, bn, r))
        out[:, j] = ov
    return out


def _bracket_points(geo: Geometry) -> list[tuple[float, float]]:
    """The pivots' (b_pos, b_neg) over their bracket: low, as built, high on each side (9 at most)."""
    pts = []
    for bp in sorted({geo.bracket["pos"][0], geo.b_pos, geo.bracket["pos"][1]}):
        for bn in sorted({geo.bracket["neg"][0], geo.b_neg, geo.bracket["neg"][1]}):
            pts.append((bp, bn))
    return pts


@dataclass(frozen=True)
class _Tables:
    """The overturn tables every model reads."""

    plain: np.ndarray  # (records, bracket points x amplitudes)
    rest: np.ndarray  # (records, bracket points, len(R_GRID))
    contact: np.ndarray  # (records, ALPHA_GRID, 1 + len(R_GRID)): Housner's law, then R_GRID
    log_alpha: np.ndarray  # (ALPHA_GRID,)


def _tables(accs, dts, geo: Geometry, specimen, say: Callable) -> _Tables:
    pts = _bracket_points(geo)
    amps = (1.0 - AMPLITUDE_SPREAD, 1.0, 1.0 + AMPLITUDE_SPREAD)
    t0 = time.perf_counter()
    plain = _overturns(accs, dts, geo, specimen, [(bp, bn, None, a) for bp, bn in pts for a in amps])
    say(f"plain model: {len(pts)} pivot pairs x {len(amps)} amplitudes, {time.perf_counter() - t0:.1f} s")
    rest = _overturns(accs, dts, geo, specimen, [(bp, bn, r, 1.0) for bp, bn in pts for r in R_GRID])
    rest = rest.reshape(len(accs), len(pts), len(R_GRID))
    lo = ALPHA_GRID_LOW * min(geo.alpha_pos, geo.alpha_neg)
    hi = max(geo.alpha_pos, geo.alpha_neg)
    alphas = np.geomspace(lo, hi, ALPHA_GRID)
    bs = geo.h * np.tan(alphas)
    contact = _overturns(accs, dts, geo, specimen, [(b, b, r, 1.0) for b in bs for r in (None, *R_GRID)])
    contact = contact.reshape(len(accs), ALPHA_GRID, 1 + len(R_GRID))
    say(
        f"effect tables: {len(pts) * len(R_GRID) + contact.shape[1] * contact.shape[2]} runs of "
        f"{len(accs)} records, {time.perf_counter() - t0:.1f} s in all"
    )
    return _Tables(plain, rest, contact, np.log(alphas))


# ----------------------------------------------------------------------------
# the models: each maps (tables, records, params) to P, and fits its params on records
def _p_plain(t: _Tables, idx, params) -> np.ndarray:
    return _lapse(t.plain[idx].mean(axis=1), params["lapse"])


def _p_rest(t: _Tables, idx, params) -> np.ndarray:
    j = R_GRID.index(params["r"])
    return _lapse(t.rest[idx, :, j].mean(axis=1), params["lapse"])


def _weights(log_alpha: np.ndarray, mu, sigma: float) -> np.ndarray:
    """Log-normal weights over the alpha grid, one row per centre ``mu`` (log alpha_eff) [-]."""
    w = np.exp(-0.5 * ((log_alpha[None, :] - np.atleast_1d(mu)[:, None]) / sigma) ** 2)
    return w / w.sum(axis=1, keepdims=True)


def _p_contact(t: _Tables, idx, params) -> np.ndarray:
    w = _weights(t.log_alpha, math.log(params["alpha_eff"]), params["spread"])[0]
    j = 0 if params.get("r") is None else 1 + R_GRID.index(params["r"])
    return _lapse(t.contact[idx, :, j] @ w, params["lapse"])


def _lapse(p: np.ndarray, lapse: float) -> np.ndarray:
    """P with a share ``lapse`` [-] of outcomes decided by what the model does not hold (a placement, a knock):
    lapse/2 + (1 - lapse) P. It keeps the probabilities off 0 and 1 by what the data show, and leaves the
    side of 1/2 that each record is on (so the accuracy) unchanged."""
    return 0.5 * lapse + (1.0 - lapse) * p


def _log_loss(p, y) -> float:
    return float(np.mean(per_record_log_loss(p, y)))


def _fit_plain(t: _Tables, idx, y) -> dict:
    """The plain model fits only its lapse: how often the outcomes escape any model (not a physical effect)."""
    return min(({"lapse": e} for e in LAPSES), key=lambda q: _log_loss(_p_plain(t, idx, q), y[idx]))


def _fit_rest(t: _Tables, idx, y) -> dict:
    qs = ({"r": r, "lapse": e} for r in R_GRID for e in LAPSES)
    return min(qs, key=lambda q: _log_loss(_p_rest(t, idx, q), y[idx]))


def _fit_contact(with_r: bool):
    def fit(t: _Tables, idx, y) -> dict:
        mus = np.linspace(t.log_alpha[0], t.log_alpha[-1], _MU_POINTS)
        best, best_v = None, math.inf
        for r in (None, *R_GRID) if with_r else (None,):
            j = 0 if r is None else 1 + R_GRID.index(r)
            table = t.contact[idx, :, j]
            for sigma in SPREADS:
                P0 = table @ _weights(t.log_alpha, mus, sigma).T  # (records, mus)
                yy = np.repeat(y[idx][:, None], mus.size, axis=1)
                for lapse in LAPSES:
                    ll = np.mean(per_record_log_loss(_lapse(P0, lapse), yy), axis=0)
                    k = int(np.argmin(ll))
                    if ll[k] < best_v:
                        best_v = float(ll[k])
                        best = {"alpha_eff": float(math.exp(mus[k])), "spread": sigma, "lapse": lapse}
                        if with_r:
                            best["r"] = r
        return best

    return fit


#: Model name -> (probabilities, fit); "plain" fits only the lapse.
_MODELS = {
    "plain": (_p_plain, _fit_plain),
    "restitution": (_p_rest, _fit_rest),
    "contact_inside": (_p_contact, _fit_contact(False)),
    "contact_inside+restitution": (_p_contact, _fit_contact(True)),
}


def _cross_validate(name: str, t: _Tables, y: np.ndarray, fold: np.ndarray) -> tuple[np.ndarray, dict, list]:
    """Out-of-fold P of model ``name``, its fit on all records, and its fit without each fold."""
    predict, fit = _MODELS[name]
    p = np.empty(y.size)
    fold_params = []
    for f in range(int(fold.max()) + 1):
        te = np.flatnonzero(fold == f)
        tr = np.flatnonzero(fold != f)
        q = fit(t, tr, y)
        fold_params.append(q)
        p[te] = predict(t, te, q)
    return p, fit(t, np.arange(y.size), y), fold_params


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
    accs = [np.asarray(r.motion.acc, dtype=np.float64) for r in recs]
    dts = np.array([r.dt for r in recs])
    geo = Geometry.of(campaign)
    groups = np.asarray(campaign.outcome_groups)
    seeds = repeat_seeds(seed, repeats)
    fold_of = [grouped_folds(y, groups, folds, s) for s in seeds]
    say(
        f"{len(recs)} outcome records ({int(y.sum())} overturned) of {np.unique(groups).size} ground motions; "
        f"{folds} folds stratified by outcome that keep a ground motion's records together, {len(seeds)} repeats; "
        f"block h {geo.h:.4f} m, alpha+ {geo.alpha_pos:.4f}, alpha- {geo.alpha_neg:.4f} rad"
    )
    tables = _tables(accs, dts, geo, campaign.specimen, say)
    runs = []
    for s, fold in zip(seeds, fold_of, strict=True):
        plain_r = _step("plain", None, tables, y, fold, s, groups)
        runs.append(_add_effects(plain_r, tables, y, fold, s, groups, say))
        say(f"repeat (fold seed {s}): {runs[-1][0][-1].name}")
    rep = _consensus(seeds, runs)
    say(f"final model: {rep.chosen} ({rep.finals.count(rep.chosen)} of {len(seeds)} repeats)")
    ladder = next(steps for steps, _c, _t in runs if steps[-1].name == rep.chosen)
    steps, prev = [], None
    for rung in ladder:
        prev = _over_repeats(rung.name, prev, runs, tables, y, fold_of, seeds, groups)
        steps.append(prev)
    plain, final = steps[0], steps[-1]
    say(f"plain model: held-out log loss {plain.scores.log_loss:.3f}, accuracy {plain.scores.accuracy:.3f}")
    pointer = _pointer(plain, y, pga, pgv, geo)
    say(f"where it fails: {pointer.missed} overturns missed, {pointer.false} predicted that did not happen")
    candidates = runs[0][1]
    base_p = {n: np.array([baseline_oof(n, pga, pgv, y, f) for f in fold_of]) for n in BASELINES}
    baselines = {n: outcome_scores(p.mean(axis=0), y, groups=groups, seed=seed) for n, p in base_p.items()}
    spread = {n: seed_spread([point_scores(q, y) for q in p]) for n, p in base_p.items()}
    floor = outcome_floor(final.p, y, seed=seed)
    # the one status rule of the diagnosis; an outcome model is a misfit when a baseline fitted on the same folds
    # predicts better, when it has no skill over the base rate where the records could show one, or when its
    # probabilities fail their floor (outcome_validation.judge_outcome_model); at least 10 records are checked above
    judged_plain = judge_outcome_model(plain.p_repeats, base_p, y, groups, outcome_floor(plain.p, y, seed=seed))
    judged = judge_outcome_model(final.p_repeats, base_p, y, groups, floor) if final is not plain else judged_plain
    status = status_rule(True, len(steps) > 1, judged_plain.misfit, judged.misfit, judged.powered)
    baseline_p = {n: p.mean(axis=0) for n, p in base_p.items()}
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
        baseline_p=baseline_p,
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
        baseline_spread=spread,
        judgement=judged,
        judgement_plain=judged_plain,
    )
    diag.elapsed = time.perf_counter() - t_start
    return diag


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
    p, params, fold_params = _cross_validate(name, tables, y, fold)
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
    """Model ``name`` over every repeat's folds (taken from the repeat where its selection tried it, else
    cross-validated anew): its mean held-out probabilities, their scores with intervals that resample whole ground
    motions, each score's mean and range over the repeats, and its paired fall from ``prev``."""
    ps, first = [], None
    for (_steps, _c, tried), fold in zip(runs, fold_of, strict=True):
        step = tried.get(name)
        p = step.p if step is not None else _cross_validate(name, tables, y, fold)[0]
        first = first or step
        ps.append(p)
    p_rep = np.array(ps)
    _, params, fold_params = (
        _cross_validate(name, tables, y, fold_of[0]) if first is None else (None, first.params, first.fold_params)
    )
    fall = (0.0, 0.0, math.nan)
    if prev is not None:
        c = compare_log_loss(p_rep, prev.p_repeats, y, groups)
        fall = (c.advantage, c.se, c.p_better)
    p_mean = p_rep.mean(axis=0)
    return OutcomeStep(
        name,
        params,
        fold_params,
        p_mean,
        outcome_scores(p_mean, y, groups=groups, seed=seeds[0]),
        *fall,
        over_seeds=seed_spread([point_scores(q, y) for q in p_rep]),
        p_repeats=p_rep,
    )


def _consensus(seeds, runs) -> OutcomeRepeats:
    """The repeats' final models, the share of repeats that hold each effect, and the one most end in."""
    finals = tuple(steps[-1].name for steps, _c, _t in runs)
    effects = sorted({e for f in finals if f != "plain" for e in f.split("+")} | set(OUTCOME_EFFECTS))
    share = {e: sum(e in f.split("+") for f in finals) / len(finals) for e in effects}
    chosen = max(sorted(set(finals)), key=lambda f: (finals.count(f), -len(f.split("+")) * (f != "plain")))
    return OutcomeRepeats(tuple(int(s) for s in seeds), finals, share, chosen)


#: The outcome candidates of each round: single effects first, then their pair on top of the one added.
ROUNDS = (("contact_inside", "restitution"), ("contact_inside+restitution",))


@dataclass(frozen=True)
class OutcomeEvidence:
    """Outcomes (overturned or not) as the evidence of the forward selection
    (:func:`housner.scenarios.diagnosis.selection.forward_selection.forward_selection`): each candidate
    cross-validated on the overturn tables, its paired fall of the held-out log loss tested at :data:`LEVEL` over
    the candidates of its round (Bonferroni); the state is the ladder of :class:`OutcomeStep`, the plain model
    first."""

    tables: _Tables
    y: np.ndarray
    fold: np.ndarray
    seed: int
    groups: np.ndarray
    say: Callable[[str], None]

    def pool(self, state: tuple[OutcomeStep, ...], number: int) -> tuple[str, ...]:
        """Round ``number``'s candidates that extend the current model (never re-tries what is in)."""
        if number > len(ROUNDS):
            return ()
        return tuple(n for n in ROUNDS[number - 1] if _extends(n, state[-1].name))

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
    plain: OutcomeStep, tables, y, fold, seed: int, groups, say
) -> tuple[list[OutcomeStep], list[OutcomeCandidate], dict[str, OutcomeStep]]:
    """Forward selection from the plain model through the one selection of the diagnosis, with
    :class:`OutcomeEvidence`, on one repeat's folds. Returns the models kept (the plain one first), every candidate
    tried, and every model cross-validated, by name."""
    evidence = OutcomeEvidence(tables, y, fold, seed, groups, say)
    steps, found = forward_selection(evidence, (plain,), len(ROUNDS))
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
