"""The diagnosis' cross-validation: the folds, their scorers, and a model fitted on all records and in every fold.

Every record of the campaign is dealt into one of K folds
(:func:`housner.scenarios.campaigns.scoring.cv_folds`); a model is held as
its fit on all records and its K refits without each fold
(:class:`CVModel`), and each record is scored out of fold: by the model
fitted without it (:meth:`CrossValidation.oof`). The search of
:mod:`housner.scenarios.campaigns.diagnose` builds on it.

A campaign sampled far above what the physics needs is searched on its records decimated
(:func:`housner.scenarios.campaigns.scoring.decimated`, factor ``decimation``): the scorers
then run on them, and :meth:`CrossValidation.use_rate` switches to the records as measured
(``"full"``) for what the verdict judges, and back (``"search"``).

A model with an effect that replaces the equation of motion runs a kernel 10-100x slower than
Housner's. On a campaign whose ground motions' error windows last more than :data:`FIT_SECONDS`
in all, such a model is fitted (grids, local searches, joint and fold refits) on the free
vibrations and a spread subset of the ground motions within that time (``fit_sc``,
``fit_train_sc``; ``thinned``); every screen, held-out error and test stays on all records. On
smaller campaigns (up to 60 records of 8 s at any rate) ``fit_sc`` is ``allsc``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from housner.effects import available_effects, effect_class
from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.campaigns.fitting import build_model, effect_objective, fit_effect, joint_refit
from housner.scenarios.campaigns.localise import measured_features
from housner.scenarios.campaigns.scoring import Scorer, cv_folds, decimated

__all__ = [
    "FIT_SECONDS",
    "FOLD_ITERATIONS",
    "FOLD_JOINT_FEV",
    "MECHANICS_GRID_RECORDS",
    "MECHANICS_GRID_SECONDS",
    "CVModel",
    "CrossValidation",
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


@dataclass
class CVModel:
    """A model fitted on all records (``full``) and without each fold (``folds``), as (name, parameters) pairs."""

    full: list[tuple[str, dict]]
    folds: list[list[tuple[str, dict]]]


class CrossValidation:
    """A campaign's folds and scorers, and what its localisation measures directly.

    Parameters
    ----------
    campaign : Campaign
    folds : int
        Cross-validation folds asked for [-] (at most half the records are used).
    seed : int, SeedSequence or Generator
        Seed of the fold assignment.
    engine_settings : dict or None
        Settings of the analytic engine.

    Attributes
    ----------
    ids : list of str
        Every record, in campaign order.
    k_folds : int
    fold_ids : list of list of str
        The records of each fold.
    fold_of : ndarray of int
        The fold of each record.
    allsc, train_sc, held_sc, mech_sc : Scorer
        All records; each fold's training and held-out records; the spread subset a mechanics
        effect's grid search runs on (at the rate :meth:`use_rate` chose last: the search's first).
    decimation : int
        The factor the search's records are decimated by (1: they are the records as measured).
    rate : str
        ``"search"`` or ``"full"``: the records the scorers run on now.
    floor : float
        Mean sensor noise sigma / alpha [-].
    measured : dict
        The measured localisation quantities (:func:`housner.scenarios.campaigns.localise.measured_features`).
    pinned : dict
        Effect name -> the parameters the localisation measures directly (``Effect.measured_params``).
    """

    def __init__(self, campaign: Campaign, folds: int, seed, engine_settings):
        self.campaign, self.spec = campaign, campaign.specimen
        self.engine_settings = engine_settings
        self.ids = ids = [r.id for r in campaign.records]
        self.k_folds = k_folds = min(folds, len(ids) // 2)
        self.fold_ids = cv_folds(campaign, k_folds, seed)
        pos = {rid: i for i, rid in enumerate(ids)}
        self.fold_of = np.empty(len(ids), dtype=int)
        for k, f in enumerate(self.fold_ids):
            self.fold_of[[pos[i] for i in f]] = k
        self.search_campaign, self.decimation = decimated(campaign)
        self._scorers: dict[str, tuple] = {}
        self._subsets: tuple[list[str], list[str]] | None = None
        self.rate = ""
        self.use_rate("search")
        self.floor = float(np.mean([r.noise for r in campaign.records])) / self.spec.alpha
        self.measured = measured_features(campaign).metrics()
        # parameters the localisation measures directly, far better than a fit to the histories can
        # (Effect.measured_params): taken as measured, never fitted
        self.pinned = {n: p for n in available_effects()
                       if (p := effect_class(n).measured_params(self.measured, self.spec))}  # fmt: skip

    def _scorer_set(self, campaign: Campaign, engine_settings) -> tuple:
        """(allsc, train_sc, held_sc, mech_sc, fit_sc, fit_train_sc) on the records of ``campaign``."""
        ids, pos = self.ids, {rid: i for i, rid in enumerate(self.ids)}
        allsc = Scorer(campaign, ids, engine_settings)
        train_sc = [allsc.subset([i for i in ids if self.fold_of[pos[i]] != k]) for k in range(self.k_folds)]
        held_sc = [allsc.subset(self.fold_ids[k]) for k in range(self.k_folds)]
        if self._subsets is None:
            self._subsets = self._spread_subsets(allsc)
        mech_ids, fit_ids = self._subsets
        mech_sc = allsc.subset(mech_ids)
        mech_sc.release_angle = False
        if len(fit_ids) == len(ids):
            fit_sc, fit_train_sc = allsc, train_sc
        else:
            fit_sc = allsc.subset(fit_ids)
            keep = set(fit_ids)
            fit_train_sc = [allsc.subset([i for i in ids if i in keep and self.fold_of[pos[i]] != k])
                            for k in range(self.k_folds)]  # fmt: skip
        return allsc, train_sc, held_sc, mech_sc, fit_sc, fit_train_sc

    def _spread_subsets(self, allsc: Scorer) -> tuple[list[str], list[str]]:
        """The records of the mechanics grids and of the fits of mechanics models (module docstring).

        Both hold every free vibration. The grids' ground motions: every ``step``-th of
        :data:`MECHANICS_GRID_RECORDS`, fewer (a larger step) while their windows last more than
        :data:`MECHANICS_GRID_SECONDS` (at least 4). The fits': all when their windows last at most
        :data:`FIT_SECONDS`, else as many spread evenly over the campaign as fit in it.
        """
        secs = {r.id: r.theta.size * r.dt for r in allsc.records}
        fv_ids = [r.id for r in allsc.records if r.kind == "free_vibration"]
        gm_ids = [r.id for r in allsc.records if r.kind != "free_vibration"]
        n = min(MECHANICS_GRID_RECORDS, len(gm_ids))
        while True:
            step = max(1, len(gm_ids) // MECHANICS_GRID_RECORDS) if n == MECHANICS_GRID_RECORDS else \
                max(1, len(gm_ids) // max(n, 1))  # fmt: skip
            grid = gm_ids[::step][:n]
            if n <= 4 or sum(secs[i] for i in grid) <= MECHANICS_GRID_SECONDS:
                break
            n -= 1
        fit = gm_ids
        if sum(secs[i] for i in gm_ids) > FIT_SECONDS:
            for m in range(len(gm_ids) - 1, 0, -1):
                pick = sorted({int(round(x)) for x in np.linspace(0, len(gm_ids) - 1, m)})
                fit = [gm_ids[i] for i in pick]
                if sum(secs[i] for i in fit) <= FIT_SECONDS:
                    break
        order = {rid: i for i, rid in enumerate(self.ids)}
        return (sorted(fv_ids + grid, key=order.__getitem__), sorted(fv_ids + fit, key=order.__getitem__))

    @property
    def thinned(self) -> bool:
        """Whether models with a mechanics effect are fitted on a subset of the records (module docstring)."""
        return self.fit_sc is not self.allsc

    def use_rate(self, rate: str) -> None:
        """Score on the search's records (``"search"``: decimated when ``decimation`` > 1) or on the
        records as measured (``"full"``); each set of scorers is built once."""
        if rate not in ("search", "full"):
            raise ValueError(f"`rate` must be 'search' or 'full', got {rate!r}")
        key = "full" if self.decimation == 1 else rate
        if key not in self._scorers:
            settings = self.engine_settings
            if key == "search" and settings and settings.get("substeps"):
                # the same integrator step on the decimated grid
                settings = {**settings, "substeps": int(settings["substeps"]) * self.decimation}
            self._scorers[key] = self._scorer_set(self.search_campaign if key == "search" else self.campaign,
                                                  settings)  # fmt: skip
        self.allsc, self.train_sc, self.held_sc, self.mech_sc, self.fit_sc, self.fit_train_sc = self._scorers[key]
        self.rate = rate

    def oof(self, cv: CVModel) -> np.ndarray:
        """Out-of-fold error of every record [alpha]: each scored by the model fitted without its fold."""
        out = np.empty(len(self.ids))
        for k in range(self.k_folds):
            out[self.fold_of == k] = self.held_sc[k].errors(build_model(cv.folds[k]))
        return out

    def fold_means(self, v: np.ndarray) -> np.ndarray:
        return np.array([v[self.fold_of == k].mean() for k in range(self.k_folds)])

    def refit_folds(self, cv: CVModel, free_from: int = 0, train: list[Scorer] | None = None) -> CVModel:
        """Each fold's model refitted jointly (its effects ``free_from`` on) from where it stands
        (on ``train[k]``, default each fold's training records)."""
        train = self.train_sc if train is None else train
        return CVModel(cv.full, [joint_refit(cv.folds[k], train[k], self.spec, FOLD_JOINT_FEV, free_from,
                                             self.pinned)[0] for k in range(self.k_folds)])  # fmt: skip

    def add_cv(self, cv: CVModel, name: str, params: dict, train: list[Scorer] | None = None) -> CVModel:
        """``cv`` with effect ``name`` added: ``params`` on all records, refitted from them in each fold
        (on ``train[k]``, default each fold's training records)."""
        train = self.train_sc if train is None else train
        per = []
        for k in range(self.k_folds):
            obj = effect_objective(train[k], build_model(cv.folds[k]), [])
            pk, _e, _n = fit_effect(name, obj, self.spec, start=params, local_only=True,
                                    local_iterations=FOLD_ITERATIONS, pinned=self.pinned)  # fmt: skip
            per.append([*cv.folds[k], (name, pk)])
        return CVModel([*cv.full, (name, params)], per)
