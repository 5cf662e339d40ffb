"""Scores of outcome predictions: proper scores and counts with intervals, calibration, the baselines, the floor.

A prediction of an outcome (overturned or not) is a probability. It is scored
with the proper scores, log loss and Brier, and with the counts a user reads
(accuracy, precision, recall, F1 at P >= 0.5), and the ROC AUC; every figure
carries a percentile interval from a bootstrap over the records (seeded).

The baselines are what a user would fit instead of running physics: logistic
regressions of the outcome on the logarithms of the measured PGA and PGV
(:func:`logistic_oof`), fitted on the same folds as the model, so that a row
of the table compares like with like.

The floor is the score a correct model would reach: if the outcomes were
drawn from the model's own probabilities, its log loss would scatter around
the mean entropy of those probabilities (:func:`outcome_floor`, simulated).

References
----------
Gneiting, T., Raftery, A. E. (2007). Strictly proper scoring rules, prediction,
and estimation. JASA 102(477), 359-378.
Efron, B., Tibshirani, R. (1993). An Introduction to the Bootstrap, ch. 13
(percentile intervals).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import optimize, special

from housner._values import read_fields, to_data
from housner.statistics.proportions import wilson_interval

__all__ = [
    "P_MIN",
    "SCORE_KEYS",
    "CalibrationBin",
    "OutcomeFloor",
    "OutcomeScores",
    "calibration_table",
    "logistic_oof",
    "outcome_floor",
    "outcome_scores",
    "per_record_log_loss",
    "stratified_folds",
]

#: The score keys of every row (model, baselines), in the order tables print them.
SCORE_KEYS = ("accuracy", "f1", "log_loss", "brier", "precision", "recall", "roc_auc")
#: Probabilities are kept within [P_MIN, 1 - P_MIN] where a log loss is taken [-]: a probability of exactly
#: 0 or 1 would make one surprising outcome cost an infinite score.
P_MIN = 1e-6
#: Bootstrap resamples of the records for the intervals [-].
N_BOOT = 1000
#: Ridge penalty of the logistic baselines (on standardised features) [-]: keeps a separable fold finite.
_RIDGE = 1e-3


@dataclass(frozen=True)
class OutcomeScores:
    """The scores of a prediction of outcomes (:func:`outcome_scores`): each of :data:`SCORE_KEYS` with its bootstrap
    interval (None where the resamples gave no finite value), and the counts.

    Attributes
    ----------
    accuracy, f1, log_loss, brier, precision, recall, roc_auc : float
        [-]; the log loss in nats.
    accuracy_ci, ..., roc_auc_ci : (float, float) or None
        Their percentile intervals.
    n, n_overturned, n_predicted : int
        Records, those that overturned, those predicted to (P >= 0.5).
    tp, fp, fn, tn : int
        The confusion matrix at P >= 0.5.
    """

    accuracy: float
    f1: float
    log_loss: float
    brier: float
    precision: float
    recall: float
    roc_auc: float
    accuracy_ci: tuple[float, float] | None
    f1_ci: tuple[float, float] | None
    log_loss_ci: tuple[float, float] | None
    brier_ci: tuple[float, float] | None
    precision_ci: tuple[float, float] | None
    recall_ci: tuple[float, float] | None
    roc_auc_ci: tuple[float, float] | None
    n: int
    n_overturned: int
    n_predicted: int
    tp: int
    fp: int
    fn: int
    tn: int

    def score(self, key: str) -> float:
        """The score ``key`` of :data:`SCORE_KEYS`."""
        return getattr(self, key)

    def interval(self, key: str) -> tuple[float, float] | None:
        """The interval of score ``key`` of :data:`SCORE_KEYS`."""
        return getattr(self, f"{key}_ci")

    def to_dict(self) -> dict:
        return to_data(self)

    @classmethod
    def from_dict(cls, data: dict) -> OutcomeScores:
        return read_fields(cls, data)


@dataclass(frozen=True)
class CalibrationBin:
    """One bin of the reliability table (:func:`calibration_table`): records whose P lies in [lo, hi).

    Attributes
    ----------
    lo, hi : float
        The bin's edges of P [-].
    n : int
    mean_p : float
        Their mean P [-].
    observed : float
        The share that overturned [-].
    observed_ci : (float, float)
        Its 95 % Wilson interval.
    """

    lo: float
    hi: float
    n: int
    mean_p: float
    observed: float
    observed_ci: tuple[float, float]


def stratified_folds(y, k: int, seed) -> np.ndarray:
    """Fold index of every record [-]: ``k`` folds, each with the same share of overturns (seeded)."""
    y = np.asarray(y, dtype=bool)
    rng = np.random.default_rng(seed)
    fold = np.empty(y.size, dtype=np.int64)
    for c in (False, True):
        idx = np.flatnonzero(y == c)
        rng.shuffle(idx)
        fold[idx] = (np.arange(idx.size) + (0 if c else int(np.sum(~y)))) % k
    return fold


def per_record_log_loss(p, y) -> np.ndarray:
    """-log of the probability given to what happened, per record [nats]."""
    p = np.clip(np.asarray(p, dtype=float), P_MIN, 1.0 - P_MIN)
    y = np.asarray(y, dtype=bool)
    return -np.where(y, np.log(p), np.log1p(-p))


def _auc(p: np.ndarray, y: np.ndarray) -> float:
    """ROC AUC: the probability that an overturned record gets the higher P (ties count half) [-]."""
    pos, neg = p[y], p[~y]
    if pos.size == 0 or neg.size == 0:
        return math.nan
    ranks = _midranks(np.concatenate((pos, neg)))
    return float((np.sum(ranks[: pos.size]) - pos.size * (pos.size + 1) / 2) / (pos.size * neg.size))


def _midranks(x: np.ndarray) -> np.ndarray:
    order = np.argsort(x, kind="mergesort")
    xs = x[order]
    ranks = np.empty(x.size)
    ranks[order] = np.arange(1, x.size + 1, dtype=float)
    _, first, counts = np.unique(xs, return_index=True, return_counts=True)
    for f, c in zip(first, counts, strict=True):
        if c > 1:
            ranks[order[f : f + c]] = f + (c + 1) / 2.0
    return ranks


def _point_scores(p: np.ndarray, y: np.ndarray) -> dict[str, float]:
    pred = p >= 0.5
    tp = float(np.sum(pred & y))
    n_pred, n_pos = float(np.sum(pred)), float(np.sum(y))
    return {
        "accuracy": float(np.mean(pred == y)),
        "f1": 2.0 * tp / (n_pred + n_pos) if n_pred + n_pos > 0 else math.nan,
        "log_loss": float(np.mean(per_record_log_loss(p, y))),
        "brier": float(np.mean((p - y) ** 2)),
        "precision": tp / n_pred if n_pred > 0 else math.nan,
        "recall": tp / n_pos if n_pos > 0 else math.nan,
        "roc_auc": _auc(p, y),
    }


def outcome_scores(p, y, *, seed=0, n_boot: int = N_BOOT, ci: float = 0.95) -> OutcomeScores:
    """Every score of :data:`SCORE_KEYS` with its bootstrap interval.

    Parameters
    ----------
    p : array_like
        Predicted P(overturn) per record [-].
    y : array_like of bool
        Observed outcomes.
    seed : int
        Seed of the bootstrap.

    Returns
    -------
    OutcomeScores
    """
    p = np.asarray(p, dtype=float)
    y = np.asarray(y, dtype=bool)
    out: dict = _point_scores(p, y)
    rng = np.random.default_rng(seed)
    boot = {k: np.empty(n_boot) for k in SCORE_KEYS}
    for b in range(n_boot):
        i = rng.integers(0, p.size, p.size)
        for k, v in _point_scores(p[i], y[i]).items():
            boot[k][b] = v
    lo, hi = 50.0 * (1.0 - ci), 50.0 * (1.0 + ci)
    for k in SCORE_KEYS:
        vals = boot[k][np.isfinite(boot[k])]
        out[f"{k}_ci"] = (float(np.percentile(vals, lo)), float(np.percentile(vals, hi))) if vals.size else None
    pred = p >= 0.5
    out.update(
        n=int(p.size),
        n_overturned=int(y.sum()),
        n_predicted=int(pred.sum()),
        tp=int(np.sum(pred & y)),
        fp=int(np.sum(pred & ~y)),
        fn=int(np.sum(~pred & y)),
        tn=int(np.sum(~pred & ~y)),
    )
    return OutcomeScores(**out)


def calibration_table(p, y, bins: int = 5) -> list[CalibrationBin]:
    """Reliability of the probabilities: records binned by P, mean P against the observed share.

    Returns
    -------
    list of CalibrationBin
        One per non-empty bin.
    """
    p = np.asarray(p, dtype=float)
    y = np.asarray(y, dtype=bool)
    edges = np.linspace(0.0, 1.0, bins + 1)
    which = np.clip(np.searchsorted(edges, p, side="right") - 1, 0, bins - 1)
    rows = []
    for b in range(bins):
        sel = which == b
        n = int(sel.sum())
        if n == 0:
            continue
        k = int(y[sel].sum())
        lo, hi = wilson_interval(k, n)
        rows.append(
            CalibrationBin(float(edges[b]), float(edges[b + 1]), n, float(p[sel].mean()), k / n, (float(lo), float(hi)))
        )
    return rows


def _logistic_fit(X: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Coefficients of a ridge-penalised logistic regression, and the standardisation it was fitted in."""
    mu, sd = X.mean(axis=0), X.std(axis=0)
    sd[sd == 0] = 1.0
    Z = np.column_stack((np.ones(len(X)), (X - mu) / sd))
    yf = y.astype(float)

    def f(b):
        z = Z @ b
        return float(np.sum(np.logaddexp(0.0, z)) - yf @ z + _RIDGE * b[1:] @ b[1:])

    def g(b):
        grad = Z.T @ (special.expit(Z @ b) - yf)
        grad[1:] += 2.0 * _RIDGE * b[1:]
        return grad

    b = optimize.minimize(f, np.zeros(Z.shape[1]), jac=g, method="BFGS").x
    return b, mu, sd


def logistic_oof(X, y, fold) -> np.ndarray:
    """Out-of-fold P(overturn) of a logistic regression on the features ``X`` [-], one fit per fold.

    Parameters
    ----------
    X : array_like, shape (n,) or (n, k)
        Features (the baselines use log PGA and log PGV).
    y : array_like of bool
    fold : array_like of int
        Fold of every record (:func:`stratified_folds`): each record is predicted by the fit without its fold.
    """
    X = np.asarray(X, dtype=float).reshape(len(y), -1)
    y = np.asarray(y, dtype=bool)
    fold = np.asarray(fold)
    p = np.empty(y.size)
    for f in np.unique(fold):
        te = fold == f
        b, mu, sd = _logistic_fit(X[~te], y[~te])
        p[te] = special.expit(b[0] + ((X[te] - mu) / sd) @ b[1:])
    return p


@dataclass(frozen=True)
class OutcomeFloor:
    """What a correct model's out-of-fold probabilities would score, simulated.

    Attributes
    ----------
    log_loss : float
        Mean log loss of the probabilities against outcomes drawn from them [nats].
    log_loss_ci : (float, float)
        Its central 95 % range over the simulated campaigns [nats].
    accuracy : float
        Mean accuracy against the drawn outcomes [-].
    accuracy_ci : (float, float)
    measured_log_loss : float
        The log loss against the measured outcomes [nats].
    z : float
        (measured - mean) / standard deviation of the simulated log loss [-].
    at_floor : bool
        The measured log loss lies within the upper end of the central 95 % range.
    """

    log_loss: float
    log_loss_ci: tuple[float, float]
    accuracy: float
    accuracy_ci: tuple[float, float]
    measured_log_loss: float
    z: float
    at_floor: bool

    def to_dict(self) -> dict:
        return {
            "log_loss": self.log_loss,
            "log_loss_ci": list(self.log_loss_ci),
            "accuracy": self.accuracy,
            "accuracy_ci": list(self.accuracy_ci),
            "measured_log_loss": self.measured_log_loss,
            "z": self.z,
            "at_floor": self.at_floor,
        }


def outcome_floor(p, y, *, seed=0, n_sim: int = 2000) -> OutcomeFloor:
    """The floor of the log loss and of the accuracy for the probabilities ``p``, simulated.

    Outcomes are drawn from ``p`` itself ``n_sim`` times (seeded): a model whose probabilities are right scores
    within that spread. The measured outcomes ``y`` are then placed in it.
    """
    p = np.clip(np.asarray(p, dtype=float), P_MIN, 1.0 - P_MIN)
    y = np.asarray(y, dtype=bool)
    rng = np.random.default_rng(seed)
    draws = rng.random((n_sim, p.size)) < p
    ll = -np.mean(np.where(draws, np.log(p), np.log1p(-p)), axis=1)
    acc = np.mean(draws == (p >= 0.5), axis=1)
    measured = float(np.mean(per_record_log_loss(p, y)))
    sd = float(np.std(ll))
    lo, hi = np.percentile(ll, [2.5, 97.5])
    return OutcomeFloor(
        log_loss=float(np.mean(ll)),
        log_loss_ci=(float(lo), float(hi)),
        accuracy=float(np.mean(acc)),
        accuracy_ci=tuple(float(v) for v in np.percentile(acc, [2.5, 97.5])),
        measured_log_loss=measured,
        z=(measured - float(np.mean(ll))) / sd if sd > 0 else math.nan,
        at_floor=bool(measured <= hi),
    )
