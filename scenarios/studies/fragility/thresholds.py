"""Exceedance of response thresholds: P[theta_max/alpha >= threshold] per stripe, with Wilson intervals.

References
----------
Wilson, E. B. (1927). Probable inference, the law of succession, and
statistical inference. JASA 22, 209-212.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from housner.scenarios.studies.fragility.counts import proportion_intervals
from housner.scenarios.studies.fragility.input_checks import check_matrix, valid_mask

__all__ = ["exceedance"]


def _check_ratios(values) -> np.ndarray:
    r = check_matrix(values, "theta_max_over_alpha")
    try:
        r = r.astype(np.float64)
    except (TypeError, ValueError):
        raise ValueError(
            "`theta_max_over_alpha` must be numeric (+inf for an overturn, NaN for a failed record)"
        ) from None
    if np.any(r[~np.isnan(r)] < 0):
        raise ValueError("`theta_max_over_alpha` must be >= 0 (or +inf / NaN)")
    return r


def _check_thresholds(thresholds) -> np.ndarray:
    try:
        t = np.atleast_1d(np.asarray(thresholds, dtype=np.float64))
    except (TypeError, ValueError):
        raise ValueError(f"`thresholds` must be positive numbers, got {thresholds!r}") from None
    if t.ndim != 1 or t.size == 0 or not np.all(np.isfinite(t) & (t > 0)):
        raise ValueError(f"`thresholds` must be a non-empty sequence of finite positive numbers, got {thresholds!r}")
    return t


def exceedance(theta_max_over_alpha, thresholds=(0.5, 0.8, 1.0), valid=None, ci: float = 0.95) -> pd.DataFrame:
    """Probability that the peak rotation reaches each threshold, stripe by stripe, with Wilson intervals.

    Parameters
    ----------
    theta_max_over_alpha : array_like of float, shape (M, S)
        Peak rotation over slenderness per motion and stripe [-]; ``+inf``
        (or any value >= 1) for an overturned block, NaN for a failed record.
    thresholds : sequence of float
        Levels of theta_max/alpha [-], positive.
    valid : array_like of bool, shape (M, S), optional
        False for a record to leave out; NaN records are left out regardless.
    ci : float
        Confidence level of the intervals [-].

    Returns
    -------
    pandas.DataFrame
        One row per (stripe, threshold), stripes outer: ``stripe`` (column
        index s), ``threshold``, ``n`` (valid records), ``k`` (records with
        theta_max/alpha >= threshold), ``p`` = k/n, ``p_low``, ``p_high``
        (Wilson; NaN where n = 0).

    Notes
    -----
    A block whose rotation reached alpha has passed its point of no return
    and overturns: it counts as exceeding every threshold, those above 1
    included.

    References
    ----------
    Wilson (1927).
    """
    r, t = _check_ratios(theta_max_over_alpha), _check_thresholds(thresholds)
    v = valid_mask(valid, r.shape) & ~np.isnan(r)
    # Overturned (>= 1) becomes +inf so that it lies above every threshold, also those above 1.
    r = np.where(r >= 1.0, np.inf, r)
    n = np.broadcast_to(v.sum(axis=0)[:, None], (r.shape[1], t.size))
    k = ((r[:, :, None] >= t) & v[:, :, None]).sum(axis=0)
    p, low, high = proportion_intervals(k.ravel(), n.ravel(), ci)
    return pd.DataFrame(
        {
            "stripe": np.repeat(np.arange(r.shape[1]), t.size),
            "threshold": np.tile(t, r.shape[1]),
            "n": n.ravel().astype(np.int64),
            "k": k.ravel().astype(np.int64),
            "p": p,
            "p_low": low,
            "p_high": high,
        }
    )
