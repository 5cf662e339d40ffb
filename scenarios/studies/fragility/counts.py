"""Overturns per stripe and their binomial (Wilson) intervals.

References
----------
Wilson, E. B. (1927). Probable inference, the law of succession, and
statistical inference. JASA 22, 209-212.
"""

from __future__ import annotations

import numpy as np

from housner.scenarios.studies.fragility.input_checks import check_counts, outcomes
from housner.statistics.ensemble_stats import check_ci
from housner.statistics.proportions import wilson_interval

__all__ = ["proportion_intervals", "stripe_counts"]


def stripe_counts(overturned, valid=None) -> tuple[np.ndarray, np.ndarray]:
    """Number of valid records and of overturns at each stripe.

    Parameters
    ----------
    overturned : array_like of bool, shape (M, S)
        ``overturned[m, s]``: motion m at the intensity of stripe s overturned
        the block. A float matrix may hold NaN for a failed record.
    valid : array_like of bool, shape (M, S), optional
        False for a record that failed (or is to be left out); default all True.

    Returns
    -------
    n, k : ndarray of int, shape (S,)
        Valid records and overturns among them, per stripe.
    """
    o, v = outcomes(overturned, valid)
    return v.sum(axis=0).astype(np.int64), o.sum(axis=0).astype(np.int64)


def proportion_intervals(k, n, ci: float = 0.95) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Overturn fractions with Wilson score intervals, stripe by stripe.

    Parameters
    ----------
    k : array_like of int
        Overturns per stripe.
    n : array_like of int
        Valid records per stripe (same length as ``k``).
    ci : float
        Confidence level [-], e.g. 0.95.

    Returns
    -------
    p, low, high : ndarray
        k/n and the interval ends [-]; NaN where n = 0.

    Notes
    -----
    With z = Phi^-1((1 + ci)/2) the interval is (k + z^2/2)/(n + z^2) -+
    z/(n + z^2) sqrt(k (n - k)/n + z^2/4), the same as
    :func:`housner.statistics.proportions.overturn_probability`, here vectorised over stripes.
    It stays in [0, 1] and is not empty at k = 0 or k = n, where the Wald
    interval collapses.

    References
    ----------
    Wilson (1927).
    """
    n_, k_ = check_counts(n, k)
    with np.errstate(invalid="ignore", divide="ignore"):
        p = k_ / n_
    low, high = wilson_interval(k_, n_, check_ci(ci))
    return p, low, high
