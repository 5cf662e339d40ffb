"""Percentile-bootstrap intervals of a lognormal fragility fit, resampling the motions.

References
----------
Efron, B., Tibshirani, R. (1993). An Introduction to the Bootstrap, ch. 13
(percentile intervals).
Baker, J. W. (2015). Efficient analytical fragility function fitting using
dynamic structural analysis. Earthquake Spectra 31(1), 579-599.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from housner.scenarios.studies.fragility.input_checks import check_im, check_n_boot, outcomes
from housner.scenarios.studies.fragility.lognormal import BETA_BOUNDS, LognormalFit, fit_counts, fit_lognormal
from housner.scenarios.studies.fragility.newton import newton_rows
from housner.statistics.ensemble_stats import check_ci

__all__ = ["BootstrapFit", "bootstrap_fit"]

#: Replicates whose counts are drawn in one matrix product, to bound memory (n_boot x M weights).
_BOOT_BLOCK = 1000


class BootstrapFit(NamedTuple):
    """A lognormal fit with percentile-bootstrap intervals from resampled motions.

    Attributes
    ----------
    fit : LognormalFit
        The fit on the data as given.
    median_low, median_high : float
        Interval of the median [unit of ``im``]; NaN when no replicate could be fitted.
    beta_low, beta_high : float
        Interval of beta [-].
    n_boot : int
        Replicates drawn.
    n_failed : int
        Replicates left out of the intervals because their fit was not "ok"
        or "beta_at_bound" (no estimate, a step, or no convergence).
    medians, betas : ndarray, shape (n_boot,)
        The replicates' estimates, NaN for the failed ones.
    """

    fit: LognormalFit
    median_low: float
    median_high: float
    beta_low: float
    beta_high: float
    n_boot: int
    n_failed: int
    medians: np.ndarray
    betas: np.ndarray


#: Replicate statuses whose estimates enter the intervals: a beta at its bound is still the constrained
#: maximum of the likelihood, and dropping those would bias the interval away from the bound.
_USABLE = ("ok", "beta_at_bound")


class _Stripes(NamedTuple):
    """Stripes of an outcome matrix pooled by intensity: ln IM ascending and the pooling matrix (S x U)."""

    lx: np.ndarray
    pool: np.ndarray


def _stripes(x: np.ndarray) -> _Stripes:
    ux, inv = np.unique(np.log(x), return_inverse=True)
    pool = np.zeros((x.size, ux.size))
    pool[np.arange(x.size), inv] = 1.0
    return _Stripes(ux, pool)


def _motion_weights(rng: np.random.Generator, n_motions: int, n_boot: int):
    """Blocks of multinomial motion counts, one row per replicate: resampling motions with replacement."""
    for start in range(0, n_boot, _BOOT_BLOCK):
        size = min(_BOOT_BLOCK, n_boot - start)
        yield rng.multinomial(n_motions, np.full(n_motions, 1.0 / n_motions), size=size).astype(np.float64)


def _separable(n: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Rows of counts (R x U, ln IM ascending) without a maximum-likelihood estimate; see :func:`_degenerate`."""
    over, standing = k > 0, k < n
    first_over = np.argmax(over, axis=1)
    last_standing = n.shape[1] - 1 - np.argmax(standing[:, ::-1], axis=1)
    # No overturn (or no record) leaves `over` all False; all overturned leaves `standing` all False.
    return ~over.any(axis=1) | ~standing.any(axis=1) | (last_standing <= first_over)


def _replicate_fits(st: _Stripes, n: np.ndarray, k: np.ndarray, start: LognormalFit) -> np.ndarray:
    """(median, beta) per replicate row of the counts (R x U), NaN where the fit is not usable.

    Rows are solved together by Newton's method from the point fit; a row that does not converge or
    whose beta leaves :data:`BETA_BOUNDS` is refitted alone by :func:`fit_counts`.
    """
    out = np.full((n.shape[0], 2), np.nan)
    if not start.beta > 0:
        # No estimate or a step: resampling cannot mix a stripe that is all 0 or all 1, so every replicate
        # is degenerate too.
        return out
    rows = np.flatnonzero(~_separable(n, k))
    a0 = np.full(rows.size, -math.log(start.median) / start.beta)
    b0 = np.full(rows.size, 1.0 / start.beta)
    a, b, converged = newton_rows(st.lx, n[rows], k[rows], a0, b0)
    inside = converged & (b >= 1.0 / BETA_BOUNDS[1]) & (b <= 1.0 / BETA_BOUNDS[0])
    out[rows[inside], 0] = np.exp(-a[inside] / b[inside])
    out[rows[inside], 1] = 1.0 / b[inside]
    x0 = np.array([math.log(start.median), math.log(start.beta)])
    for i in rows[~inside]:
        keep = n[i] > 0
        fit = fit_counts(st.lx[keep], n[i, keep], k[i, keep], x0)
        if fit.status in _USABLE:
            out[i] = fit.median, fit.beta
    return out


def percentile_interval(values: np.ndarray, ci: float) -> tuple[float, float]:
    v = values[np.isfinite(values)]
    if v.size == 0:
        return math.nan, math.nan
    low, high = np.percentile(v, [50.0 * (1.0 - ci), 50.0 * (1.0 + ci)])
    return float(low), float(high)


def resampled_fits(x: np.ndarray, samples, n_boot: int, seed) -> tuple[list[LognormalFit], list[np.ndarray]]:
    """Point fits of (overturned, valid) samples of the same motions, and their replicates on the same resamples.

    Returns the fits and, per sample, the (n_boot, 2) replicate estimates (median, beta), NaN where not usable;
    every sample is refitted on each resample of the motions (a paired bootstrap when there are several).
    """
    st = _stripes(x)
    fits = [fit_lognormal(x, v.sum(axis=0), o.sum(axis=0)) for o, v in samples]
    est = [np.full((n_boot, 2), np.nan) for _ in samples]
    rng = np.random.default_rng(seed)
    row = 0
    for w in _motion_weights(rng, samples[0][0].shape[0], n_boot):
        rows = slice(row, row + w.shape[0])
        for e, (o, v), fit in zip(est, samples, fits, strict=True):
            e[rows] = _replicate_fits(st, w @ v @ st.pool, w @ o @ st.pool, fit)
        row += w.shape[0]
    return fits, est


def bootstrap_fit(im, overturned, valid=None, n_boot: int = 1000, seed=0, ci: float = 0.95) -> BootstrapFit:
    """Lognormal fragility fit with percentile-bootstrap intervals, resampling motions.

    Parameters
    ----------
    im : array_like of float, shape (S,)
        Intensity of each stripe, positive [dimensionless, or any unit].
    overturned : array_like of bool, shape (M, S)
        Outcome of motion m scaled to stripe s; a float matrix may hold NaN for a failed record.
    valid : array_like of bool, shape (M, S), optional
        False for a record left out of the counts (failed run); default all True.
    n_boot : int
        Number of bootstrap replicates.
    seed : int, numpy.random.SeedSequence or numpy.random.Generator
        Seed of :func:`numpy.random.default_rng`; the same seed gives the same numbers.
    ci : float
        Confidence level of the intervals [-].

    Returns
    -------
    BootstrapFit
        The point fit (:func:`fit_lognormal` on the stripe counts), the
        percentile intervals of median and beta, and the replicates.

    Notes
    -----
    A replicate draws M motions with replacement and keeps each drawn motion
    at every stripe: the stripes share their motions, so their outcomes are
    correlated, and resampling stripes independently would understate the
    spread. Its counts are ``w @ overturned`` with w the multinomial number
    of draws of each motion. The replicates are fitted together by Newton's
    method on the concave probit form, from the point fit; one whose beta
    reaches a bound is refitted alone as in :func:`fit_lognormal`.

    Replicates whose fit is degenerate (no overturn, all overturned,
    separated, not converged) are counted in ``n_failed`` and left out of the
    percentiles, which are then conditional on a fit existing: with many
    failures the intervals are too narrow. Replicates whose beta stops at a
    bound of :data:`BETA_BOUNDS` are kept (the bound is then an interval
    end): they are the constrained maximum of the likelihood. A degenerate
    point fit makes every replicate degenerate (resampling cannot mix a
    stripe that is all 0 or all 1), and the intervals are NaN.

    References
    ----------
    Efron and Tibshirani (1993), ch. 13; Baker (2015).
    """
    o, v = outcomes(overturned, valid)
    x = check_im(im, o.shape[1])
    n_boot, ci = check_n_boot(n_boot), check_ci(ci)
    (fit,), (est,) = resampled_fits(x, [(o, v)], n_boot, seed)
    medians, betas = est[:, 0], est[:, 1]
    return BootstrapFit(
        fit,
        *percentile_interval(medians, ci),
        *percentile_interval(betas, ci),
        n_boot,
        int(np.count_nonzero(np.isnan(medians))),
        medians,
        betas,
    )
