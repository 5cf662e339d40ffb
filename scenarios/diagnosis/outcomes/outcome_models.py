"""The outcome models: the planar block behind a campaign's outcome records, the overturn tables of its ensembles
over a grid of the effects' parameters (computed once), and each model's probabilities and fits on those tables
(:mod:`housner.scenarios.diagnosis.outcomes.outcome_diagnosis` runs them; ``docs/explanation/diagnosis.md``,
"Outcome records", says why each is built so)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from housner.effects import available_effects
from housner.model import theta_max_many
from housner.motion import GroundMotion
from housner.rocking_params import RockingParams
from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.diagnosis.outcomes.outcome_effects import LeftOut, OutcomeEffect, effect_table
from housner.scenarios.diagnosis.outcomes.outcome_scores import per_record_log_loss

__all__ = [
    "ALPHA_GRID",
    "ALPHA_GRID_LOW",
    "AMPLITUDE_SPREAD",
    "ENGINE_PREFIX",
    "UNIFORM",
    "LAPSES",
    "OUTCOME_MODELS",
    "R_GRID",
    "SPREADS",
    "EngineRuns",
    "Geometry",
    "OverturnTables",
    "cross_validate",
    "known_model",
    "lapse_mix",
    "outcome_model",
    "overturn_tables",
]

#: The table's amplitude is sampled within +-this share [-] (a 2 % calibration of the accelerometer, and a
#: nearby record for the chaos of a long one).
AMPLITUDE_SPREAD = 0.02
#: Points of the effective-contact grid (alpha_eff, log-spaced) [-].
ALPHA_GRID = 28
#: The grid spans alpha_eff from this share of the plain model's smaller alpha up to its larger alpha [-].
ALPHA_GRID_LOW = 0.25
#: Restitution values the effective contact is tried with [-] (besides Housner's impact law of each geometry, which
#: needs no parameter); restitution alone is the library effect's, on its own grid.
R_GRID = (0.95, 0.9, 0.8, 0.7, 0.6)
#: Log-normal spreads of alpha_eff the fit chooses from [-] (0.3: alpha known to within about 30 %).
SPREADS = (0.02, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.7)
#: Lapse rates the fit chooses from [-]: the share of outcomes the model does not decide (:func:`lapse_mix`).
LAPSES = (0.0005, 0.001, 0.002, 0.005, 0.01, 0.02, 0.04, 0.08, 0.15, 0.25)
#: The name of a 3D engine's ensemble as an outcome model is this prefix and the engine's name.
ENGINE_PREFIX = "engine:"
#: The suffix of an engine model whose orientation is not fitted: every azimuth of its ensemble weighs alike.
UNIFORM = "@uniform"
#: Points of the finer grid of log(alpha_eff) the fit searches (the weights interpolate between the runs) [-].
_MU_POINTS = 80


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
class OverturnTables:
    """The overturn tables every model reads.

    Attributes
    ----------
    plain : ndarray of bool
        (records, bracket points x amplitudes).
    contact : ndarray of bool
        (records, ALPHA_GRID, 1 + len(R_GRID)): Housner's law, then R_GRID.
    log_alpha : ndarray
        (ALPHA_GRID,) [log rad].
    effects : dict of str to EffectTable
        The library effects tabulated (:mod:`housner.scenarios.diagnosis.outcomes.outcome_effects`), by name.
    left_out : list of LeftOut
        The library effects the records cannot test, with the reason.
    engines : dict of str to EngineRuns
        A 3D engine's ensemble on the records, by engine name.
    """

    plain: np.ndarray
    contact: np.ndarray
    log_alpha: np.ndarray
    effects: dict = field(default_factory=dict)
    left_out: list = field(default_factory=list)
    engines: dict = field(default_factory=dict)


def overturn_tables(
    motions: list[GroundMotion], geo: Geometry, specimen, say: Callable, alphas=None, effects: list[OutcomeEffect] = ()
) -> OverturnTables:
    """Every record's overturns (its table motion in ``motions``) over the models' grids: the pivots over their
    bracket and the table's amplitude (the plain model), the effective contact's grid of alpha with Housner's impact
    law and :data:`R_GRID` (default: from :data:`ALPHA_GRID_LOW` of the smaller alpha to the larger,
    :data:`ALPHA_GRID` points; ``alphas`` [rad] gives another, for a model fitted on another block, and an empty
    one none), and each library effect of ``effects`` over its grid and the bracket."""
    accs = [mo.acc for mo in motions]
    dts = np.array([mo.dt for mo in motions])
    pts = _bracket_points(geo)
    amps = (1.0 - AMPLITUDE_SPREAD, 1.0, 1.0 + AMPLITUDE_SPREAD)
    t0 = time.perf_counter()
    plain = _overturns(accs, dts, geo, specimen, [(bp, bn, None, a) for bp, bn in pts for a in amps])
    say(f"plain model: {len(pts)} pivot pairs x {len(amps)} amplitudes, {time.perf_counter() - t0:.1f} s")
    if alphas is None:
        lo = ALPHA_GRID_LOW * min(geo.alpha_pos, geo.alpha_neg)
        alphas = np.geomspace(lo, max(geo.alpha_pos, geo.alpha_neg), ALPHA_GRID)
    alphas = np.asarray(alphas, dtype=float)
    bs = geo.h * np.tan(alphas)
    contact = _overturns(accs, dts, geo, specimen, [(b, b, r, 1.0) for b in bs for r in (None, *R_GRID)])
    contact = contact.reshape(len(accs), alphas.size, 1 + len(R_GRID))
    say(
        f"contact tables: {contact.shape[1] * contact.shape[2]} runs of "
        f"{len(accs)} records, {time.perf_counter() - t0:.1f} s in all"
    )
    starts = [geo.params(bp, bn) for bp, bn in pts]
    tabled, left = {}, []
    for eff in effects:
        t1 = time.perf_counter()
        got = effect_table(eff, motions, specimen, starts)
        if isinstance(got, LeftOut):
            left.append(got)
            say(f"{eff.name}: left out (its own solver: its table would take over {got.steps:.2g} steps)")
            continue
        tabled[eff.name] = got
        solver = "" if math.isnan(got.steps) else f", {got.steps:.2g} solver steps"
        say(
            f"{eff.name}: {len(eff.values)} values of {eff.param} x {len(pts)} pivot pairs{solver}, "
            f"{time.perf_counter() - t1:.1f} s"
        )
    return OverturnTables(plain, contact, np.log(alphas), tabled, left)


# ----------------------------------------------------------------------------
# the models: each maps (tables, records, params) to P, and fits its params on records
def _p_plain(t: OverturnTables, idx, params) -> np.ndarray:
    return lapse_mix(t.plain[idx].mean(axis=1), params["lapse"])


def _weights(log_alpha: np.ndarray, mu, sigma: float) -> np.ndarray:
    """Log-normal weights over the alpha grid, one row per centre ``mu`` (log alpha_eff) [-]."""
    w = np.exp(-0.5 * ((log_alpha[None, :] - np.atleast_1d(mu)[:, None]) / sigma) ** 2)
    return w / w.sum(axis=1, keepdims=True)


def _p_contact(t: OverturnTables, idx, params) -> np.ndarray:
    w = _weights(t.log_alpha, math.log(params["alpha_eff"]), params["spread"])[0]
    j = 0 if params.get("r") is None else 1 + R_GRID.index(params["r"])
    return lapse_mix(t.contact[idx, :, j] @ w, params["lapse"])


def lapse_mix(p: np.ndarray, lapse: float) -> np.ndarray:
    """P with a share ``lapse`` [-] of outcomes decided by what the model does not hold (a placement, a knock):
    lapse/2 + (1 - lapse) P. It keeps the probabilities off 0 and 1 by what the data show, and leaves the
    side of 1/2 that each record is on (so the accuracy) unchanged."""
    return 0.5 * lapse + (1.0 - lapse) * p


def _log_loss(p, y) -> float:
    return float(np.mean(per_record_log_loss(p, y)))


def _fit_plain(t: OverturnTables, idx, y) -> dict:
    """The plain model fits only its lapse: how often the outcomes escape any model (not a physical effect)."""
    return min(({"lapse": e} for e in LAPSES), key=lambda q: _log_loss(_p_plain(t, idx, q), y[idx]))


def _fit_contact(with_r: bool):
    def fit(t: OverturnTables, idx, y) -> dict:
        mus = np.linspace(t.log_alpha[0], t.log_alpha[-1], _MU_POINTS)
        best, best_v = None, math.inf
        for r in (None, *R_GRID) if with_r else (None,):
            j = 0 if r is None else 1 + R_GRID.index(r)
            table = t.contact[idx, :, j]
            for sigma in SPREADS:
                P0 = table @ _weights(t.log_alpha, mus, sigma).T  # (records, mus)
                yy = np.repeat(y[idx][:, None], mus.size, axis=1)
                for lapse in LAPSES:
                    ll = np.mean(per_record_log_loss(lapse_mix(P0, lapse), yy), axis=0)
                    k = int(np.argmin(ll))
                    if ll[k] < best_v:
                        best_v = float(ll[k])
                        best = {"alpha_eff": float(math.exp(mus[k])), "spread": sigma, "lapse": lapse}
                        if with_r:
                            best["r"] = r
        return best

    return fit


#: Model name -> (probabilities, fit) of the models with tables of their own; a library effect's model is
#: :func:`outcome_model`'s.
OUTCOME_MODELS = {
    "plain": (_p_plain, _fit_plain),
    "contact_inside": (_p_contact, _fit_contact(False)),
    "contact_inside+restitution": (_p_contact, _fit_contact(True)),
}


def _p_effect(name: str):
    def predict(t: OverturnTables, idx, params) -> np.ndarray:
        table = t.effects[name]
        j = table.column(params[table.effect.param])
        return lapse_mix(table.overturned[idx, :, j].mean(axis=1), params["lapse"])

    return predict


def _fit_effect(name: str):
    def fit(t: OverturnTables, idx, y) -> dict:
        table = t.effects[name]
        shares = table.overturned[idx].mean(axis=1)  # (records, values)
        best, best_v = None, math.inf
        for j, v in enumerate(table.effect.values):
            for lapse in LAPSES:
                ll = _log_loss(lapse_mix(shares[:, j], lapse), y[idx])
                if ll < best_v:
                    best_v, best = ll, {table.effect.param: float(v), "lapse": lapse}
        return best

    return fit


@dataclass(frozen=True)
class EngineRuns:
    """A 3D engine's ensemble on the records (:mod:`housner.scenarios.diagnosis.outcomes.engine_ensemble`).

    Attributes
    ----------
    overturned : ndarray
        (records, members): 1.0 overturned, 0.0 stood, NaN a run that failed.
    azimuth : ndarray
        (members,) [deg]: the azimuth each member ran at.
    """

    overturned: np.ndarray
    azimuth: np.ndarray

    def orientations(self) -> list[tuple[float, ...]]:
        """The sets of azimuths an orientation fit chooses from [deg]: all of them (the orientation unknown), each
        alone, and each with the opposite one (the same rock shaken the other way first)."""
        az = sorted(set(self.azimuth.tolist()))
        options = [tuple(az), *((a,) for a in az), *((a, a + 180.0) for a in az if a < 180.0 and a + 180.0 in az)]
        return list(dict.fromkeys(options))  # one option once: with two opposite azimuths, their pair is all of them

    def share(self, idx, azimuths) -> np.ndarray:
        """P(overturn) of records ``idx``: the share of their runs at ``azimuths`` [deg] that overturn [-]."""
        cols = np.isin(self.azimuth, np.asarray(azimuths, dtype=float))
        return np.nanmean(self.overturned[np.asarray(idx)][:, cols], axis=1)


def _engine_of(name: str) -> tuple[str, bool]:
    """(engine, fitted orientation?) of the model ``engine:NAME`` or ``engine:NAME@uniform``."""
    engine = name.removeprefix(ENGINE_PREFIX)
    return engine.removesuffix(UNIFORM), not engine.endswith(UNIFORM)


def _p_engine(name: str):
    engine, _fitted = _engine_of(name)

    def predict(t: OverturnTables, idx, params) -> np.ndarray:
        return lapse_mix(t.engines[engine].share(idx, params["azimuths"]), params["lapse"])

    return predict


def _fit_engine(name: str):
    """A 3D engine's ensemble fits its lapse and, unless ``@uniform``, which of the unrecorded orientations the
    rock stood in (:meth:`EngineRuns.orientations`): nothing of the engine's physics is fitted."""
    engine, fitted = _engine_of(name)

    def fit(t: OverturnTables, idx, y) -> dict:
        runs = t.engines[engine]
        options = runs.orientations() if fitted else runs.orientations()[:1]
        best, best_v = None, math.inf
        for az in options:
            share = runs.share(idx, az)
            for lapse in LAPSES:
                ll = _log_loss(lapse_mix(share, lapse), y[idx])
                if ll < best_v:
                    best_v, best = ll, {"azimuths": list(az), "lapse": lapse}
        return best

    return fit


def known_model(name: str) -> bool:
    """Whether ``name`` is an outcome model: one with its own tables, or a single registered effect."""
    if name in OUTCOME_MODELS:
        return True
    return "+" not in name and name in available_effects()


def outcome_model(name: str) -> tuple[Callable, Callable]:
    """(probabilities, fit) of model ``name``: :data:`OUTCOME_MODELS`, a 3D engine's ensemble (``engine:NAME``, its
    orientation fitted; ``engine:NAME@uniform``, not), or a library effect's on its table."""
    if name in OUTCOME_MODELS:
        return OUTCOME_MODELS[name]
    if name.startswith(ENGINE_PREFIX):
        return _p_engine(name), _fit_engine(name)
    return _p_effect(name), _fit_effect(name)


def cross_validate(name: str, t: OverturnTables, y: np.ndarray, fold: np.ndarray) -> tuple[np.ndarray, dict, list]:
    """Out-of-fold P of model ``name``, its fit on all records, and its fit without each fold."""
    predict, fit = outcome_model(name)
    p = np.empty(y.size)
    fold_params = []
    for f in range(int(fold.max()) + 1):
        te = np.flatnonzero(fold == f)
        tr = np.flatnonzero(fold != f)
        q = fit(t, tr, y)
        fold_params.append(q)
        p[te] = predict(t, te, q)
    return p, fit(t, np.arange(y.size), y), fold_params
