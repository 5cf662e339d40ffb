"""Validation of an outcome model that a reviewer accepts: folds stratified by outcome that keep each ground motion's
records together, repeated over seeds; the baselines any model must beat, fitted on the same folds; paired
comparisons of held-out log losses whose standard errors are clustered by ground motion; and the judgement that
calls a model a misfit when a baseline predicts better, when it shows no skill over the base rate, or when its
probabilities are off (``docs/explanation/diagnosis.md``, "Outcome records")."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import special
from scipy import stats as sps
from sklearn.dummy import DummyClassifier
from sklearn.linear_model import LogisticRegression
from sklearn.model_selection import StratifiedGroupKFold
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

from housner.scenarios.diagnosis.outcomes.outcome_scores import OutcomeFloor, per_record_log_loss

__all__ = [
    "BASELINES",
    "LEVEL",
    "BaselineFit",
    "REPEATS",
    "OutcomeJudgement",
    "PairedComparison",
    "baseline_fit",
    "baseline_oof",
    "compare_log_loss",
    "grouped_folds",
    "baselines_show_skill",
    "judge_outcome_model",
    "repeat_seeds",
]

#: Repeats of the cross-validation, each with its own fold seed [-].
REPEATS = 5
#: One-sided level of each paired comparison of held-out log losses [-]. Not divided among the baselines: a
#: model is called a misfit when any one predicts better at this level, which errs on the side of saying so.
LEVEL = 0.05
#: The baselines, fitted on the same folds as the model: the base rate (the training folds' share of overturns,
#: what a model with no skill predicts) and logistic regressions on log PGA, log PGV and both.
BASELINES = ("base_rate", "logistic_pga", "logistic_pgv", "logistic_pga_pgv")
#: Inverse ridge strength of the logistic baselines on standardised features (scikit-learn's C) [-]: a penalty
#: of 1/(2 C) = 1e-3 on the squared coefficients keeps a fold whose outcomes a feature separates finite.
LOGISTIC_C = 500.0


def repeat_seeds(seed: int, repeats: int = REPEATS) -> tuple[int, ...]:
    """The fold seeds of the repeats: ``seed``, ``seed + 1``, ... [-]."""
    return tuple(int(seed) + i for i in range(int(repeats)))


def grouped_folds(y, groups, k: int, seed: int) -> np.ndarray:
    """Fold of every record [-]: ``k`` folds, each with about the same share of overturns, every group (the records
    of one ground motion) whole in one fold (scikit-learn's ``StratifiedGroupKFold``, shuffled with ``seed``).

    Raises
    ------
    ValueError
        Fewer groups than folds.
    """
    y = np.asarray(y, dtype=bool)
    groups = np.asarray(groups)
    n_groups = int(np.unique(groups).size)
    if n_groups < k:
        raise ValueError(f"`folds` must be at most the {n_groups} groups of records (ground motions), got {k}")
    fold = np.empty(y.size, dtype=np.int64)
    splitter = StratifiedGroupKFold(n_splits=int(k), shuffle=True, random_state=int(seed))
    for f, (_train, test) in enumerate(splitter.split(np.zeros((y.size, 1)), y, groups)):
        fold[test] = f
    return fold


def _features(name: str, pga, pgv) -> np.ndarray:
    """The features of baseline ``name``: none for the base rate, else log PGA, log PGV or both."""
    pga, pgv = np.asarray(pga, dtype=float), np.asarray(pgv, dtype=float)
    features = {
        "base_rate": lambda: np.zeros((pga.size, 1)),
        "logistic_pga": lambda: np.log(pga)[:, None],
        "logistic_pgv": lambda: np.log(pgv)[:, None],
        "logistic_pga_pgv": lambda: np.column_stack((np.log(pga), np.log(pgv))),
    }
    if name not in features:
        raise ValueError(f"unknown baseline {name!r}; the baselines are {', '.join(BASELINES)}")
    return features[name]()


def _fitted(name: str, X: np.ndarray, y: np.ndarray):
    """Baseline ``name`` fitted on features ``X`` and outcomes ``y`` (scikit-learn)."""
    if name == "base_rate":
        model = DummyClassifier(strategy="prior")
    else:
        model = make_pipeline(StandardScaler(), LogisticRegression(C=LOGISTIC_C, max_iter=1000))
    return model.fit(X, y)


def _p_true(model, X: np.ndarray) -> np.ndarray:
    return model.predict_proba(X)[:, list(model.classes_).index(True)]


def baseline_oof(name: str, pga, pgv, y, fold) -> np.ndarray:
    """Out-of-fold P(overturn) of baseline ``name`` (:data:`BASELINES`) [-], one fit per fold.

    Parameters
    ----------
    pga, pgv : array_like
        Peak table acceleration [m/s^2] and velocity [m/s] per record.
    y : array_like of bool
    fold : array_like of int
        Fold of every record: each record is predicted by the fit without its fold.
    """
    y = np.asarray(y, dtype=bool)
    X, fold = _features(name, pga, pgv), np.asarray(fold)
    p = np.empty(y.size)
    for f in np.unique(fold):
        test = fold == f
        p[test] = _p_true(_fitted(name, X[~test], y[~test]), X[test])
    return p


@dataclass(frozen=True)
class BaselineFit:
    """A baseline fitted on every record of a campaign, frozen, to predict another's.

    Attributes
    ----------
    name : str
        One of :data:`BASELINES`.
    rate : float
        The base rate's P(overturn) [-] (NaN for a regression).
    mean, scale : tuple of float
        The regression's standardisation of its features (log PGA [log m/s^2], log PGV [log m/s]).
    coef : tuple of float
        Its coefficients on the standardised features.
    intercept : float
    """

    name: str
    rate: float = math.nan
    mean: tuple[float, ...] = ()
    scale: tuple[float, ...] = ()
    coef: tuple[float, ...] = ()
    intercept: float = math.nan

    def predict(self, pga, pgv) -> np.ndarray:
        """P(overturn) of records with peak table acceleration ``pga`` [m/s^2] and velocity ``pgv`` [m/s]."""
        X = _features(self.name, pga, pgv)
        if self.name == "base_rate":
            return np.full(X.shape[0], self.rate)
        z = ((X - np.array(self.mean)) / np.array(self.scale)) @ np.array(self.coef) + self.intercept
        return special.expit(z)


def baseline_fit(name: str, pga, pgv, y) -> BaselineFit:
    """Baseline ``name`` fitted on every record (:class:`BaselineFit`)."""
    y = np.asarray(y, dtype=bool)
    model = _fitted(name, _features(name, pga, pgv), y)
    if name == "base_rate":
        return BaselineFit(name, rate=float(np.mean(y)))
    scaler, logistic = model[0], model[-1]
    return BaselineFit(
        name,
        mean=tuple(float(v) for v in scaler.mean_),
        scale=tuple(float(v) for v in scaler.scale_),
        coef=tuple(float(v) for v in logistic.coef_[0]),
        intercept=float(logistic.intercept_[0]),
    )


@dataclass(frozen=True)
class PairedComparison:
    """Two predictions of the same records on the same folds, compared by their held-out log losses.

    Attributes
    ----------
    advantage : float
        The mean per record of the other's log loss minus this one's [nats]: positive when this one predicts
        better. With several repeats, each record's log loss is its mean over the repeats.
    se : float
        Its standard error, clustered by group (the records of one ground motion move together) [nats].
    p_better, p_worse : float
        One-sided p-values that this one predicts better, and worse (Student's t with groups - 1 degrees of
        freedom) [-].
    n_groups : int
    """

    advantage: float
    se: float
    p_better: float
    p_worse: float
    n_groups: int


def compare_log_loss(p_model, p_other, y, groups) -> PairedComparison:
    """``p_model`` against ``p_other`` (each (n,) or (repeats, n) held-out probabilities) on the records ``y``.

    The test is Diebold and Mariano's on the paired differences of the log loss, with the standard error of their
    mean clustered by ``groups``: a ground motion played at several scalings gives records whose differences are
    alike, and counting them as independent would overstate the evidence.
    """
    y = np.asarray(y, dtype=bool)
    ll_model = np.atleast_2d(per_record_log_loss(p_model, y)).mean(axis=0)
    ll_other = np.atleast_2d(per_record_log_loss(p_other, y)).mean(axis=0)
    d = ll_other - ll_model
    _, g = np.unique(np.asarray(groups), return_inverse=True)
    n, n_groups = d.size, int(g.max()) + 1
    mean = float(d.mean())
    sums = np.bincount(g, weights=d - mean, minlength=n_groups)
    var = n_groups / max(n_groups - 1, 1) * float(np.sum(sums**2)) / n**2
    se = math.sqrt(var)
    if se > 0 and n_groups > 1:
        t = mean / se
        p_better, p_worse = float(sps.t.sf(t, n_groups - 1)), float(sps.t.cdf(t, n_groups - 1))
    else:
        p_better, p_worse = (0.0, 1.0) if mean > 0 else (1.0, 0.0) if mean < 0 else (1.0, 1.0)
    return PairedComparison(mean, se, p_better, p_worse, n_groups)


@dataclass(frozen=True)
class OutcomeJudgement:
    """What the held-out log loss of an outcome model says of it, against the baselines and its floor.

    Attributes
    ----------
    against : dict of str to PairedComparison
        The model against each baseline (:data:`BASELINES`), on the same folds.
    beaten_by : tuple of str
        The baselines that predict significantly better (``p_worse`` below :data:`LEVEL`).
    skill : bool
        The model predicts significantly better than the base rate.
    powered : bool
        Some prediction (the model or a baseline) is significantly better than the base rate: the records can tell
        a model with skill from one without.
    calibrated : bool
        Its log loss lies within what its own probabilities would score (the outcome floor).
    """

    against: dict[str, PairedComparison]
    beaten_by: tuple[str, ...]
    skill: bool
    powered: bool
    calibrated: bool

    @property
    def misfit(self) -> bool:
        """A baseline predicts better, the model has no skill where the records could show one, or its
        probabilities are off."""
        return bool(self.beaten_by) or (self.powered and not self.skill) or not self.calibrated


def baselines_show_skill(baselines: dict, y, groups) -> bool:
    """Whether any baseline but the base rate predicts significantly better than the base rate (name ->
    held-out probabilities on the same folds): whether the records could show a model's skill."""
    rate = baselines["base_rate"]
    return any(
        compare_log_loss(p, rate, y, groups).p_better < LEVEL for name, p in baselines.items() if name != "base_rate"
    )


def judge_outcome_model(
    p_model, baselines: dict, y, groups, floor: OutcomeFloor, baseline_skill: bool | None = None
) -> OutcomeJudgement:
    """The judgement of the held-out probabilities ``p_model`` ((n,) or (repeats, n)) against the baselines'
    (name -> probabilities on the same folds; ``base_rate`` among them) and the model's outcome ``floor``;
    ``baseline_skill`` is :func:`baselines_show_skill` of the same baselines where the caller has it already
    (it depends on the baselines alone)."""
    against = {name: compare_log_loss(p_model, p, y, groups) for name, p in baselines.items()}
    beaten = tuple(name for name, c in against.items() if c.p_worse < LEVEL)
    skill = against["base_rate"].p_better < LEVEL
    if baseline_skill is None:
        baseline_skill = baselines_show_skill(baselines, y, groups)
    return OutcomeJudgement(against, beaten, skill, skill or baseline_skill, floor.at_floor)
