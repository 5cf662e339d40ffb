"""Scores of outcome predictions: the proper scores (log loss, Brier), the counts a user reads (accuracy, precision,
recall, F1 at P >= 0.5) and the ROC AUC (scikit-learn's), each with a percentile interval from a bootstrap that
resamples whole ground motions; their mean and range over the repeats of the cross-validation; calibration; and
the floor, the log loss a correct model would reach (:func:`outcome_floor`, simulated). The counts and means are
written out rather than taken from scikit-learn because the bootstrap evaluates them a thousand times per model,
where its metrics' input checks would cost seconds; :func:`calibration_table` counts its bins itself because
each bin's Wilson interval needs its count, which ``sklearn.calibration.calibration_curve`` does not return. The
baselines and the folds are :mod:`housner.scenarios.diagnosis.outcomes.outcome_validation`'s.

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
from sklearn.metrics import roc_auc_score

from housner._values import read_fields, to_data
from housner.statistics.proportions import wilson_interval

__all__ = [
    "P_MIN",
    "SCORE_KEYS",
    "CalibrationBin",
    "OutcomeFloor",
    "OutcomeScores",
    "SeedSpread",
    "calibration_table",
    "outcome_floor",
    "outcome_scores",
    "per_record_log_loss",
    "point_scores",
    "seed_spread",
]

#: The score keys of every row (model, baselines), in the order tables print them.
SCORE_KEYS = ("accuracy", "f1", "log_loss", "brier", "precision", "recall", "roc_auc")
#: Probabilities are kept within [P_MIN, 1 - P_MIN] where a log loss is taken [-]: a probability of exactly
#: 0 or 1 would make one surprising outcome cost an infinite score.
P_MIN = 1e-6
#: Bootstrap resamples of the records for the intervals [-].
N_BOOT = 1000


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
class SeedSpread:
    """A score over the repeats of the cross-validation (one fold seed each): its mean and its range.

    Attributes
    ----------
    mean, low, high : float
        In the score's unit.
    """

    mean: float
    low: float
    high: float


def seed_spread(per_repeat: list[dict[str, float]]) -> dict[str, SeedSpread]:
    """Each score of :data:`SCORE_KEYS` over the repeats (each repeat's point scores, :func:`point_scores`)."""
    out = {}
    for k in SCORE_KEYS:
        v = np.array([r[k] for r in per_repeat], dtype=float)
        v = v[np.isfinite(v)]
        out[k] = SeedSpread(float(v.mean()), float(v.min()), float(v.max())) if v.size else SeedSpread(*[math.nan] * 3)
    return out


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


def per_record_log_loss(p, y) -> np.ndarray:
    """-log of the probability given to what happened, per record [nats]."""
    p = np.clip(np.asarray(p, dtype=float), P_MIN, 1.0 - P_MIN)
    y = np.asarray(y, dtype=bool)
    return -np.where(y, np.log(p), np.log1p(-p))


def point_scores(p: np.ndarray, y: np.ndarray) -> dict[str, float]:
    """Each score of :data:`SCORE_KEYS` of the probabilities ``p`` on the outcomes ``y``, without an interval."""
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
        "roc_auc": float(roc_auc_score(y, p)) if 0 < n_pos < y.size else math.nan,
    }


def outcome_scores(p, y, *, groups=None, seed=0, n_boot: int = N_BOOT, ci: float = 0.95) -> OutcomeScores:
    """Every score of :data:`SCORE_KEYS` with its bootstrap interval.

    Parameters
    ----------
    p : array_like
        Predicted P(overturn) per record [-].
    y : array_like of bool
        Observed outcomes.
    groups : array_like, optional
        The group of every record (the records of one ground motion): the bootstrap resamples whole groups, as
        their records are not independent evidence. Default: every record its own group.
    seed : int
        Seed of the bootstrap.

    Returns
    -------
    OutcomeScores
    """
    p = np.asarray(p, dtype=float)
    y = np.asarray(y, dtype=bool)
    out: dict = point_scores(p, y)
    _, g = np.unique(np.arange(p.size) if groups is None else np.asarray(groups), return_inverse=True)
    members = [np.flatnonzero(g == k) for k in range(int(g.max()) + 1)]
    rng = np.random.default_rng(seed)
    boot = {k: np.empty(n_boot) for k in SCORE_KEYS}
    for b in range(n_boot):
        i = np.concatenate([members[k] for k in rng.integers(0, len(members), len(members))])
        for k, v in point_scores(p[i], y[i]).items():
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
