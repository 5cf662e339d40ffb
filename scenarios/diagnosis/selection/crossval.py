"""The diagnosis' cross-validation: the folds, their scorers, and a model fitted on all records and in every fold.

Every record of the campaign is dealt into one of K folds (:class:`Folds`,
:func:`housner.scenarios.diagnosis.selection.record_scoring.cv_folds`); a model is held as its fit on all records and
its K refits without each fold (:class:`CVModel`), and each record is scored out of fold: by the model
fitted without it (:meth:`Scorers.out_of_fold`). The search of :mod:`housner.scenarios.diagnosis.diagnose`
builds on it. Everything here is an immutable value, built once by :func:`cross_validation`.

A campaign sampled far above what the physics needs is searched on its records decimated
(:func:`housner.scenarios.diagnosis.selection.record_scoring.decimated`, factor ``decimation``): the search's scorers
(:attr:`CrossValidation.search`) run on them, and the scorers of the records as measured
(:attr:`CrossValidation.full`) score what the verdict judges.

A model with an effect that replaces the equation of motion runs a kernel 10-100x slower than
Housner's. On a campaign whose ground motions' error windows last more than :data:`FIT_SECONDS`
in all, such a model is fitted (grids, local searches, joint and fold refits) on the free
vibrations and a spread subset of the ground motions within that time (:attr:`Scorers.fit`,
:attr:`Scorers.fit_fold_train`; :attr:`Scorers.thinned`); every screen, held-out error and test stays
on all records. On smaller campaigns (up to 60 records of 8 s at any rate) :attr:`Scorers.fit` is
:attr:`Scorers.every_record`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from housner.effects import available_effects, effect_class
from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.diagnosis.comparison.localise import measured_features
from housner.scenarios.diagnosis.selection.fitting import build_model, effect_objective, fit_effect, joint_refit
from housner.scenarios.diagnosis.selection.record_scoring import Scorer, cv_folds, decimated

__all__ = [
    "FIT_SECONDS",
    "FOLD_ITERATIONS",
    "FOLD_JOINT_FEV",
    "MECHANICS_GRID_RECORDS",
    "MECHANICS_GRID_SECONDS",
    "CVModel",
    "CrossValidation",
    "Folds",
    "Scorers",
    "add_to_folds",
    "cross_validation",
    "refit_folds",
]

#: A mechanics effect's grid search runs on the free vibrations and this many ground motions spread
#: over the campaign, the local search that ends the fit on all records [-].
MECHANICS_GRID_RECORDS = 12
#: ... and at most this long in all [s of error windows] (fewer of them, still spread, on long records;
#: 12 records of 6 s fit in it).
MECHANICS_GRID_SECONDS = 60.0
#: A model with a mechanics effect is fitted on every record when the ground motions' error windows
#: last at most this long in all [s] (60 records of 8 s), else on the free vibrations and ground
#: motions spread over the campaign within it (module docstring).
FIT_SECONDS = 480.0
#: Local search budget of a fold's refit, started from the fit on all records (Brent iterations).
FOLD_ITERATIONS = 8
#: Nelder-Mead evaluations per parameter of a fold's joint refit.
FOLD_JOINT_FEV = 6


@dataclass(frozen=True)
class CVModel:
    """A model fitted on all records (``full``) and without each fold (``folds``), as (name, parameters) pairs."""

    full: list[tuple[str, dict]]
    folds: list[list[tuple[str, dict]]]

    @property
    def names(self) -> tuple[str, ...]:
        """The effects of the model, in the order added."""
        return tuple(n for n, _params in self.full)


@dataclass(frozen=True)
class Folds:
    """Every record of a campaign dealt into one of ``count`` folds.

    Attributes
    ----------
    ids : list of str
        Every record, in campaign order.
    count : int
        K, the number of folds [-].
    members : list of list of str
        The records of each fold.
    fold_of : ndarray of int
        The fold of each record of ``ids``.
    """

    ids: list[str]
    count: int
    members: list[list[str]]
    fold_of: np.ndarray

    def means(self, per_record: np.ndarray) -> np.ndarray:
        """The mean of ``per_record`` (one value per record of ``ids``) over each fold's records."""
        return np.array([per_record[self.fold_of == k].mean() for k in range(self.count)])

    def training_ids(self, k: int, among: set[str] | None = None) -> list[str]:
        """The records outside fold ``k`` (those of ``among`` only, when given), in campaign order."""
        return [i for n, i in enumerate(self.ids) if self.fold_of[n] != k and (among is None or i in among)]


@dataclass(frozen=True)
class Scorers:
    """The scorers of a diagnosis on one version of the records (decimated for the search, or as measured).

    Attributes
    ----------
    rate : str
        ``"search"`` or ``"full"``: the records they score.
    folds : Folds
    every_record : Scorer
        All records.
    fold_train, fold_held : list of Scorer
        Each fold's training records (the others) and its held-out records.
    mechanics_grid : Scorer
        The spread subset a mechanics effect's grid search runs on (module docstring).
    fit, fit_fold_train : Scorer, list of Scorer
        The records a model with a mechanics effect is fitted on, in all and in each fold (``every_record``
        and ``fold_train`` themselves unless the campaign is ``thinned``).
    """

    rate: str
    folds: Folds
    every_record: Scorer
    fold_train: list[Scorer]
    fold_held: list[Scorer]
    mechanics_grid: Scorer
    fit: Scorer
    fit_fold_train: list[Scorer]

    @property
    def thinned(self) -> bool:
        """Whether models with a mechanics effect are fitted on a subset of the records (module docstring)."""
        return self.fit is not self.every_record

    def out_of_fold(self, model: CVModel) -> np.ndarray:
        """Out-of-fold error of every record [alpha]: each scored by ``model`` fitted without its fold."""
        out = np.empty(len(self.folds.ids))
        for k in range(self.folds.count):
            out[self.folds.fold_of == k] = self.fold_held[k].errors(build_model(model.folds[k]))
        return out


@dataclass(frozen=True)
class CrossValidation:
    """A campaign's folds and scorers, and what its localisation measures directly (:func:`cross_validation`).

    Attributes
    ----------
    campaign : Campaign
    specimen : Specimen
    engine_settings : dict or None
        Settings of the analytic engine.
    folds : Folds
    decimation : int
        The factor the search's records are decimated by (1: they are the records as measured).
    search, full : Scorers
        On the search's records and on the records as measured (the same object when ``decimation`` is 1).
    noise_floor : float
        Mean sensor noise sigma / alpha of the records [-].
    measured : dict
        The measured localisation quantities
        (:func:`housner.scenarios.diagnosis.comparison.localise.measured_features`).
    pinned : dict
        Effect name -> the parameters the localisation measures directly (``Effect.measured_params``).
    """

    campaign: Campaign
    specimen: object
    engine_settings: dict | None
    folds: Folds
    decimation: int
    search: Scorers
    full: Scorers
    noise_floor: float
    measured: dict
    pinned: dict


def cross_validation(campaign: Campaign, folds: int, seed, engine_settings) -> CrossValidation:
    """The cross-validation of ``campaign``: its folds, both sets of scorers, its noise floor and pinned parameters.

    Parameters
    ----------
    campaign : Campaign
    folds : int
        Cross-validation folds asked for [-] (at most half the records are used).
    seed : int, SeedSequence or Generator
        Seed of the fold assignment.
    engine_settings : dict or None
        Settings of the analytic engine.
    """
    ids = [r.id for r in campaign.records]
    count = min(folds, len(ids) // 2)
    members = cv_folds(campaign, count, seed)
    position = {rid: i for i, rid in enumerate(ids)}
    fold_of = np.empty(len(ids), dtype=int)
    for k, fold in enumerate(members):
        fold_of[[position[i] for i in fold]] = k
    the_folds = Folds(ids, count, members, fold_of)
    search_campaign, decimation = decimated(campaign)
    search_settings = engine_settings
    if decimation > 1 and engine_settings and engine_settings.get("substeps"):
        # the same integrator step on the decimated grid
        search_settings = {**engine_settings, "substeps": int(engine_settings["substeps"]) * decimation}
    rate = "search" if decimation > 1 else "full"
    every = Scorer(search_campaign, ids, search_settings)
    subsets = _spread_subsets(every, ids)
    search = _scorer_set(rate, the_folds, every, subsets)
    full = (
        search if decimation == 1 else _scorer_set("full", the_folds, Scorer(campaign, ids, engine_settings), subsets)
    )
    measured = measured_features(campaign).metrics()
    # parameters the localisation measures directly, far better than a fit to the histories can
    # (Effect.measured_params): taken as measured, never fitted
    pinned = {n: p for n in available_effects() if (p := effect_class(n).measured_params(measured, campaign.specimen))}
    noise_floor = float(np.mean([r.noise for r in campaign.records])) / campaign.specimen.alpha
    return CrossValidation(
        campaign, campaign.specimen, engine_settings, the_folds, decimation, search, full, noise_floor, measured, pinned
    )


def _scorer_set(rate: str, folds: Folds, every: Scorer, subsets: tuple[list[str], list[str]]) -> Scorers:
    """The scorers of ``every``'s records: in each fold, on the mechanics grid's and the fits' subsets."""
    fold_train = [every.subset(folds.training_ids(k)) for k in range(folds.count)]
    fold_held = [every.subset(folds.members[k]) for k in range(folds.count)]
    grid_ids, fit_ids = subsets
    mechanics_grid = every.subset(grid_ids)
    mechanics_grid.release_angle = False
    if len(fit_ids) == len(folds.ids):
        fit, fit_fold_train = every, fold_train
    else:
        fit = every.subset(fit_ids)
        keep = set(fit_ids)
        fit_fold_train = [every.subset(folds.training_ids(k, keep)) for k in range(folds.count)]
    return Scorers(rate, folds, every, fold_train, fold_held, mechanics_grid, fit, fit_fold_train)


def _spread_subsets(every: Scorer, ids: list[str]) -> tuple[list[str], list[str]]:
    """The records of the mechanics grids and of the fits of mechanics models (module docstring).

    Both hold every free vibration. The grids' ground motions: every ``step``-th of
    :data:`MECHANICS_GRID_RECORDS`, fewer (a larger step) while their windows last more than
    :data:`MECHANICS_GRID_SECONDS` (at least 4). The fits': all when their windows last at most
    :data:`FIT_SECONDS`, else as many spread evenly over the campaign as fit in it.
    """
    seconds = {r.id: r.theta.size * r.dt for r in every.records}
    fv_ids = [r.id for r in every.records if r.kind == "free_vibration"]
    gm_ids = [r.id for r in every.records if r.kind != "free_vibration"]
    n = min(MECHANICS_GRID_RECORDS, len(gm_ids))
    while True:
        step = (
            max(1, len(gm_ids) // MECHANICS_GRID_RECORDS)
            if n == MECHANICS_GRID_RECORDS
            else max(1, len(gm_ids) // max(n, 1))
        )
        grid = gm_ids[::step][:n]
        if n <= 4 or sum(seconds[i] for i in grid) <= MECHANICS_GRID_SECONDS:
            break
        n -= 1
    fit = gm_ids
    if sum(seconds[i] for i in gm_ids) > FIT_SECONDS:
        for m in range(len(gm_ids) - 1, 0, -1):
            pick = sorted({int(round(x)) for x in np.linspace(0, len(gm_ids) - 1, m)})
            fit = [gm_ids[i] for i in pick]
            if sum(seconds[i] for i in fit) <= FIT_SECONDS:
                break
    order = {rid: i for i, rid in enumerate(ids)}
    return (sorted(fv_ids + grid, key=order.__getitem__), sorted(fv_ids + fit, key=order.__getitem__))


def refit_folds(cv: CrossValidation, model: CVModel, train: list[Scorer], free_from: int = 0) -> CVModel:
    """``model`` with each fold's fit refitted jointly (its effects ``free_from`` on) from where it stands,
    on ``train[k]``, fold ``k``'s training records."""
    return CVModel(
        model.full,
        [
            joint_refit(model.folds[k], train[k], cv.specimen, FOLD_JOINT_FEV, free_from, cv.pinned)[0]
            for k in range(cv.folds.count)
        ],
    )


def add_to_folds(cv: CrossValidation, model: CVModel, name: str, params: dict, train: list[Scorer]) -> CVModel:
    """``model`` with effect ``name`` added: ``params`` on all records, refitted from them in each fold
    (on ``train[k]``, fold ``k``'s training records)."""
    per_fold = []
    for k in range(cv.folds.count):
        objective = effect_objective(train[k], build_model(model.folds[k]), [])
        fold_params, _err, _n = fit_effect(
            name,
            objective,
            cv.specimen,
            start=params,
            local_only=True,
            local_iterations=FOLD_ITERATIONS,
            pinned=cv.pinned,
        )
        per_fold.append([*model.folds[k], (name, fold_params)])
    return CVModel([*model.full, (name, params)], per_fold)
