"""The paired held-out test of the diagnosis: does a model's per-record error fall significantly from another's,
record by record, by more than a practical share of the sensor noise (:func:`judge`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.stats as sps

from housner.scenarios.diagnosis.selection.reasons import Reason

__all__ = ["PRACTICAL", "Judgement", "judge", "sem"]

#: An improvement must be at least this fraction of the sensor noise sigma/alpha per record [-]: the
#: smallest fall taken for physics rather than for the model's own conventions.
#: Why 0.1: docs/results.md#defaults-trial.
PRACTICAL = 0.1


@dataclass(frozen=True)
class Judgement:
    """Whether a held-out fall of the per-record errors is significant (:func:`judge`).

    Attributes
    ----------
    significant : bool
    improvement, improvement_se : float
        Mean paired fall of the errors [alpha] and its standard error.
    z : float
        improvement / improvement_se.
    pvalue : float
        One-sided Wilcoxon signed-rank p-value of the paired differences.
    reason : Reason
        The rule that decided it, with its figures.
    """

    significant: bool
    improvement: float
    improvement_se: float
    z: float
    pvalue: float
    reason: Reason


def _paired(base: np.ndarray, new: np.ndarray) -> tuple[float, float]:
    d = base - new
    if d.size < 2:
        return float(d.mean()) if d.size else math.nan, math.nan
    return float(d.mean()), float(d.std(ddof=1) / math.sqrt(d.size))


def judge(before: np.ndarray, after: np.ndarray, test_level: float, noise_floor: float) -> Judgement:
    """Is the held-out improvement from ``before`` to ``after`` (per-record errors [alpha]) significant?

    The p-value is the one-sided Wilcoxon signed-rank test of the paired differences (records the
    change leaves exactly as they were drop out): the differences are heavy-tailed (most records
    barely change, a few that diverge by chaos change a lot), where a rank test keeps its power
    and its level and a t-test on the mean does not. ``noise_floor`` is sigma/alpha [-]: the fall
    must also be :data:`PRACTICAL` of it.
    """
    diffs = before - after
    d, se = _paired(before, after)
    z = d / se if se > 0 else (math.inf if d > 0 else 0.0)
    nonzero = diffs[diffs != 0.0]
    if nonzero.size == 0:
        return Judgement(False, d, se, z, 1.0, Reason("changes_nothing"))
    pval = (
        float(sps.wilcoxon(nonzero, alternative="greater", zero_method="wilcox").pvalue) if nonzero.size >= 2 else 1.0
    )
    need = PRACTICAL * noise_floor
    if not d > 0:
        return Judgement(False, d, se, z, pval, Reason("no_improvement"))
    if pval > test_level:
        return Judgement(False, d, se, z, pval, Reason("within_uncertainty", {"p": pval, "level": test_level}))
    if d < need:
        return Judgement(False, d, se, z, pval, Reason("below_practical", {"fall": d, "need": need}))
    return Judgement(
        True, d, se, z, pval, Reason("significant", {"p": pval, "level": test_level, "fall": d, "need": need})
    )


def sem(v: np.ndarray) -> float:
    """The standard error of the mean of ``v`` (NaN for fewer than two values)."""
    return float(np.std(v, ddof=1) / math.sqrt(v.size)) if v.size > 1 else math.nan
