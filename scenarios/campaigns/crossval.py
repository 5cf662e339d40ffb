"""The diagnosis' cross-validation: the folds, their scorers, and a model fitted on all records and in every fold.

Every record of the campaign is dealt into one of K folds
(:func:`housner.scenarios.campaigns.scoring.cv_folds`); a model is held as
its fit on all records and its K refits without each fold
(:class:`CVModel`), and each record is scored out of fold: by the model
fitted without it (:meth:`CrossValidation.oof`). The search of
:mod:`housner.scenarios.campaigns.diagnose` builds on it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from housner.effects import available_effects, effect_class
from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.campaigns.fitting import build_model, effect_objective, fit_effect, joint_refit
from housner.scenarios.campaigns.localise import measured_features
from housner.scenarios.campaigns.scoring import Scorer, cv_folds

__all__ = ["FOLD_ITERATIONS", "FOLD_JOINT_FEV", "MECHANICS_GRID_RECORDS", "CVModel", "CrossValidation"]

#: A mechanics effect's grid search runs on the free vibrations and this many ground motions spread
#: over the campaign, the local search that ends the fit on all records [-].
MECHANICS_GRID_RECORDS = 12
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
        effect's grid search runs on.
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

    def oof(self, cv: CVModel) -> np.ndarray:
        """Out-of-fold error of every record [alpha]: each scored by the model fitted without its fold."""
        out = np.empty(len(self.ids))
        for k in range(self.k_folds):
            out[self.fold_of == k] = self.held_sc[k].errors(build_model(cv.folds[k]))
        return out

    def fold_means(self, v: np.ndarray) -> np.ndarray:
        return np.array([v[self.fold_of == k].mean() for k in range(self.k_folds)])

    def refit_folds(self, cv: CVModel, free_from: int = 0) -> CVModel:
        """Each fold's model refitted jointly (its effects ``free_from`` on) from where it stands."""
        return CVModel(cv.full, [joint_refit(cv.folds[k], self.train_sc[k], self.spec, FOLD_JOINT_FEV, free_from,
                                             self.pinned)[0] for k in range(self.k_folds)])  # fmt: skip

    def add_cv(self, cv: CVModel, name: str, params: dict) -> CVModel:
        """``cv`` with effect ``name`` added: ``params`` on all records, refitted from them in each fold."""
        per = []
        for k in range(self.k_folds):
            obj = effect_objective(self.train_sc[k], build_model(cv.folds[k]), [])
            pk, _e, _n = fit_effect(name, obj, self.spec, start=params, local_only=True,
                                    local_iterations=FOLD_ITERATIONS, pinned=self.pinned)  # fmt: skip
            per.append([*cv.folds[k], (name, pk)])
        return CVModel([*cv.full, (name, params)], per)
