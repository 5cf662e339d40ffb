"""Fragility functions from multiple-stripe analysis: lognormal fits, bootstrap intervals, engine comparison.

One engine and one block size give a boolean matrix ``overturned[m, s]``:
motion m (0..M-1) scaled to the intensity ``im[s]`` of stripe s (0..S-1),
the same motions at every stripe. The fragility function is the lognormal
CDF P(overturn | IM = x) = Phi(ln(x / median) / beta), fitted by maximum
likelihood to the stripes' binomial counts (Baker 2015). The intensity is
whatever the campaign scales the motions to; here it is dimensionless (e.g.
PGA / (g tan alpha)), and the median carries the same unit as ``im``.

Functions: :func:`stripe_counts`, :func:`proportion_intervals` (Wilson),
:func:`fit_lognormal`, :func:`bootstrap_fit` (motions resampled),
:func:`compare_fits` (paired bootstrap of two engines on the same motions),
:func:`exceedance` (P[theta_max/alpha >= threshold] per stripe) and
:func:`fragility_curve`.

References
----------
Baker, J. W. (2015). Efficient analytical fragility function fitting using
dynamic structural analysis. Earthquake Spectra 31(1), 579-599 (multiple-stripe
likelihood, eq. 11).
Wilson, E. B. (1927). Probable inference, the law of succession, and
statistical inference. JASA 22, 209-212.
Albert, A., Anderson, J. A. (1984). On the existence of maximum likelihood
estimates in logistic regression models. Biometrika 71(1), 1-10 (separation).
Efron, B., Tibshirani, R. (1993). An Introduction to the Bootstrap, ch. 13
(percentile intervals).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import pandas as pd
from scipy import optimize, special

from housner.stats import _check_ci, wilson_interval

__all__ = [
    "BETA_BOUNDS",
    "BootstrapFit",
    "FitComparison",
    "LognormalFit",
    "bootstrap_fit",
    "compare_fits",
    "exceedance",
    "fit_lognormal",
    "fragility_curve",
    "proportion_intervals",
    "stripe_counts",
]

#: Search range of the logarithmic standard deviation beta [-]. Below 1e-3 the curve is a step at the
#: resolution of any stripe spacing in use; above 5 it rises from 5 % to 95 % over more than 7 decades of
#: IM, i.e. the data show no dependence on intensity that a lognormal can describe.
BETA_BOUNDS = (1e-3, 5.0)

#: Replicates whose counts are drawn in one matrix product, to bound memory (n_boot x M weights).
_BOOT_BLOCK = 1000
#: Newton iterations and step halvings per iteration, at most; from the point fit a bootstrap replicate
#: converges in 3 to 5 iterations (measured on 100 motions x 20 stripes), so these only stop a runaway.
_NEWTON_ITER = 50
_HALVINGS = 40
#: Search range of ln median beyond the stripes' ln IM: fitted probabilities down to about 1e-9 at the
#: stripes (one overturn in a billion records) keep |ln(x / median)| / beta below 6, i.e. ln median within
#: 6 x 5 = 30 of the stripes with beta <= 5; 50 leaves a margin.
_MU_MARGIN = 50.0
_LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)


# ----------------------------------------------------------------------------
# validation
def _check_im(im, n_stripes: int | None = None) -> np.ndarray:
    try:
        x = np.asarray(im, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError("`im` must be numeric: one intensity per stripe") from None
    if x.ndim != 1 or x.size == 0:
        raise ValueError(f"`im` must be a non-empty one-dimensional array (one value per stripe), got shape {x.shape}")
    if not np.all(np.isfinite(x) & (x > 0)):
        raise ValueError(f"`im` must hold finite positive intensities, got {x[~(np.isfinite(x) & (x > 0))][0]}")
    if n_stripes is not None and x.size != n_stripes:
        raise ValueError(f"`im` has {x.size} stripes but the outcome matrix has {n_stripes} columns")
    return x


def _check_matrix(values, name: str) -> np.ndarray:
    try:
        a = np.asarray(values)
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be an array of shape (motions, stripes)") from None
    if a.ndim != 2 or a.size == 0:
        raise ValueError(f"`{name}` must be a non-empty (motions, stripes) matrix, got shape {a.shape}")
    return a


def _outcomes(overturned, valid, name: str = "overturned", valid_name: str = "valid") -> tuple[np.ndarray, np.ndarray]:
    """(overturned & valid, valid) as float 0/1 matrices; NaN in ``overturned`` marks a failed record."""
    o = _check_matrix(overturned, name)
    if o.dtype == np.bool_:
        failed = np.zeros(o.shape, dtype=bool)
    else:
        try:
            o = o.astype(np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"`{name}` must hold booleans (or 0/1, NaN for a failed record)") from None
        failed = np.isnan(o)
        if not np.all(np.isin(o[~failed], (0.0, 1.0))):
            raise ValueError(f"`{name}` must hold booleans (or 0/1, NaN for a failed record)")
        o = np.where(failed, 0.0, o).astype(bool)
    v = _valid_mask(valid, o.shape, valid_name) & ~failed
    return (o & v).astype(np.float64), v.astype(np.float64)


def _valid_mask(valid, shape: tuple[int, ...], name: str = "valid") -> np.ndarray:
    if valid is None:
        return np.ones(shape, dtype=bool)
    v = np.asarray(valid)
    if v.shape != shape:
        raise ValueError(f"`{name}` must have the shape of the outcome matrix {shape}, got {v.shape}")
    if v.dtype != np.bool_:
        if not np.all(np.isin(v, (0, 1))):
            raise ValueError(f"`{name}` must hold booleans (True = the record ran)")
        v = v.astype(bool)
    return v


def _check_counts(n, k) -> tuple[np.ndarray, np.ndarray]:
    arrays = []
    for name, a in (("n", n), ("k", k)):
        try:
            x = np.atleast_1d(np.asarray(a, dtype=np.float64))
        except (TypeError, ValueError):
            raise ValueError(f"`{name}` must be counts (non-negative integers)") from None
        if x.ndim != 1 or not np.all(np.isfinite(x) & (x >= 0) & (x == np.round(x))):
            raise ValueError(f"`{name}` must be a one-dimensional array of non-negative integers, got {a!r}")
        arrays.append(x)
    n_, k_ = arrays
    if n_.shape != k_.shape:
        raise ValueError(f"`k` must have one count per stripe like `n`, got lengths {k_.size} and {n_.size}")
    if np.any(k_ > n_):
        j = int(np.flatnonzero(k_ > n_)[0])
        raise ValueError(f"`k` exceeds `n` at stripe {j}: {k_[j]:g} overturns out of {n_[j]:g} records")
    return n_, k_


def _check_n_boot(n_boot) -> int:
    if not (isinstance(n_boot, (int, np.integer)) and n_boot >= 1):
        raise ValueError(f"`n_boot` must be a positive integer, got {n_boot!r}")
    return int(n_boot)


# ----------------------------------------------------------------------------
# counts and binomial intervals
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
    o, v = _outcomes(overturned, valid)
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
    :func:`housner.stats.overturn_probability`, here vectorised over stripes.
    It stays in [0, 1] and is not empty at k = 0 or k = n, where the Wald
    interval collapses.

    References
    ----------
    Wilson (1927).
    """
    n_, k_ = _check_counts(n, k)
    with np.errstate(invalid="ignore", divide="ignore"):
        p = k_ / n_
    low, high = wilson_interval(k_, n_, _check_ci(ci))
    return p, low, high


# ----------------------------------------------------------------------------
# maximum-likelihood lognormal fit
class LognormalFit(NamedTuple):
    """A lognormal fragility function P(overturn | IM = x) = Phi(ln(x / median) / beta).

    Attributes
    ----------
    median : float
        IM at which half the records overturn [unit of ``im``]; NaN when no
        estimate exists (``status`` "no_overturn" or "all_overturn").
    beta : float
        Logarithmic standard deviation [-]; 0 for separated data, NaN when no estimate exists.
    status : str
        "ok"; "no_overturn" or "all_overturn" (no maximum-likelihood estimate);
        "separated" (a step: beta -> 0); "beta_at_bound" (beta stopped at a
        bound of :data:`BETA_BOUNDS`); "not_converged" (the optimiser stopped
        without meeting its tolerance).
    message : str
        The status in words.
    """

    median: float
    beta: float
    status: str
    message: str


def _aggregate(lx: np.ndarray, n: np.ndarray, k: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stripes sorted by IM, those with equal IM pooled, those without records dropped."""
    ux, inv = np.unique(lx, return_inverse=True)
    nu = np.bincount(inv, weights=n, minlength=ux.size)
    ku = np.bincount(inv, weights=k, minlength=ux.size)
    keep = nu > 0
    return ux[keep], nu[keep], ku[keep]


def _neg_loglik(theta: np.ndarray, lx: np.ndarray, n: np.ndarray, k: np.ndarray, scale: float):
    """Negative binomial log-likelihood per record (constant C(n, k) left out) and its gradient in (mu, ln beta)."""
    mu, s = theta
    inv_beta = math.exp(-s)
    z = (lx - mu) * inv_beta
    # log_ndtr of both tails keeps p and 1 - p accurate far out where 1 - Phi(z) rounds to 0.
    lp, lq = special.log_ndtr(z), special.log_ndtr(-z)
    f = -(k @ lp + (n - k) @ lq) * scale
    lpdf = -0.5 * z * z - _LOG_SQRT_2PI
    dz = -(k * np.exp(lpdf - lp) - (n - k) * np.exp(lpdf - lq)) * scale
    return f, np.array([-inv_beta * dz.sum(), -(dz @ z)])


def _degenerate(lx: np.ndarray, n: np.ndarray, k: np.ndarray) -> LognormalFit | None:
    """The fit when no maximum-likelihood estimate exists (Albert and Anderson 1984), else None."""
    N, K = n.sum(), k.sum()
    x = np.exp(lx)
    if K == 0:
        return LognormalFit(
            math.nan,
            math.nan,
            "no_overturn",
            f"no record overturned at any stripe (0 of {N:.0f}): the likelihood keeps rising as the median goes to "
            f"infinity, so there is no maximum-likelihood fit; the median lies above the largest stripe, {x[-1]:.4g}",
        )
    if K == N:
        return LognormalFit(
            math.nan,
            math.nan,
            "all_overturn",
            f"every record overturned at every stripe ({N:.0f} of {N:.0f}): the likelihood keeps rising as the median "
            f"goes to zero, so there is no maximum-likelihood fit; the median lies below the smallest stripe, "
            f"{x[0]:.4g}",
        )
    first_over = int(np.flatnonzero(k > 0)[0])
    last_standing = int(np.flatnonzero(k < n)[-1])
    if last_standing < first_over:
        a, b = x[last_standing], x[first_over]
        return LognormalFit(
            math.sqrt(a * b),
            0.0,
            "separated",
            f"the data are perfectly separated: no overturn up to IM = {a:.4g}, every record overturned from "
            f"IM = {b:.4g}; the likelihood keeps rising as beta -> 0, so there is no maximum-likelihood fit. "
            f"Reported the step: median = {math.sqrt(a * b):.4g} (geometric mean of the two stripes), beta = 0; "
            "stripes between the two would resolve the curve",
        )
    if last_standing == first_over:
        c = x[first_over]
        return LognormalFit(
            float(c),
            0.0,
            "separated",
            f"the data are separated but for one stripe, IM = {c:.4g} ({k[first_over]:.0f} of {n[first_over]:.0f} "
            "overturned): no overturn below it, every record overturned above it; the likelihood keeps rising as "
            f"beta -> 0 with the median at that stripe, so there is no maximum-likelihood fit. Reported median = "
            f"{c:.4g}, beta = 0",
        )
    return None


def _start(lx: np.ndarray, n: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Starting (mu, ln beta): probit regression on the mixed stripes, else the 0.5 crossing with beta = 0.5."""
    f = k / n
    mixed = (k > 0) & (k < n)
    if np.count_nonzero(mixed) >= 2:
        # Weighting by n alone (not the binomial variance) is enough for a start.
        slope, intercept = np.polyfit(lx[mixed], special.ndtri(f[mixed]), 1, w=np.sqrt(n[mixed]))
        # A slope near 0 (equal fractions) would put the median decades away; then the crossing is better.
        if 1.0 / BETA_BOUNDS[1] <= slope <= 1.0 / BETA_BOUNDS[0]:
            mu = float(np.clip(-intercept / slope, lx[0] - _MU_MARGIN, lx[-1] + _MU_MARGIN))
            return np.array([mu, -math.log(slope)])
    mu = float(np.interp(0.5, np.maximum.accumulate(f), lx))
    return np.array([mu, math.log(0.5)])


def _probit_terms(a: np.ndarray, b: np.ndarray, lx: np.ndarray, n: np.ndarray, k: np.ndarray):
    """Log-likelihood of rows of counts at eta = a + b ln x, and its first and second derivatives in eta."""
    z = a[:, None] + b[:, None] * lx
    lp, lq = special.log_ndtr(z), special.log_ndtr(-z)
    lpdf = -0.5 * z * z - _LOG_SQRT_2PI
    rp, rq = np.exp(lpdf - lp), np.exp(lpdf - lq)
    ll = (k * lp + (n - k) * lq).sum(axis=1)
    g = k * rp - (n - k) * rq
    h = -k * rp * (z + rp) - (n - k) * rq * (rq - z)
    return ll, g, h


def _loglik_rows(a: np.ndarray, b: np.ndarray, lx: np.ndarray, n: np.ndarray, k: np.ndarray) -> np.ndarray:
    z = a[:, None] + b[:, None] * lx
    return (k * special.log_ndtr(z) + (n - k) * special.log_ndtr(-z)).sum(axis=1)


def _newton_direction(g: np.ndarray, h: np.ndarray, lx: np.ndarray, fixed_b: bool):
    """Newton step (da, db) from per-stripe derivatives in eta, its decrement g^T (-H)^-1 g, and where it is valid."""
    ga, haa = g.sum(axis=1), h.sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        if fixed_b:
            da, db, det = -ga / haa, np.zeros_like(ga), -haa
        else:
            gb, hab, hbb = g @ lx, h @ lx, h @ (lx * lx)
            det = haa * hbb - hab * hab
            da, db = (hab * gb - hbb * ga) / det, (hab * ga - haa * gb) / det
    decrement = ga * da + (0.0 if fixed_b else gb * db)
    ok = np.isfinite(decrement) & (det > 0) & (haa < 0)
    return np.where(ok, da, 0.0), np.where(ok, db, 0.0), decrement, ok


def _newton_rows(lx: np.ndarray, n: np.ndarray, k: np.ndarray, a: np.ndarray, b: np.ndarray, fixed_b: bool = False):
    """Damped Newton on the probit form p = Phi(a + b ln x), all rows at once; returns (a, b, converged).

    In (a, b) the log-likelihood is concave (the normal CDF is log-concave), so Newton with step halving
    climbs to the unique maximum of any non-separated row; the bounds on beta are left to the caller, who
    may hold b fixed (``fixed_b``) and maximise over a alone.
    """
    a, b = a.copy(), b.copy()
    converged = np.zeros(a.size, dtype=bool)
    active = np.ones(a.size, dtype=bool)
    # Rounding of a sum over N records; a decrement below it means the next step is the last useful one.
    slack = 1e-13 * n.sum(axis=1)
    for _ in range(_NEWTON_ITER):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        ni, ki = n[idx], k[idx]
        ll, g, h = _probit_terms(a[idx], b[idx], lx, ni, ki)
        da, db, decrement, ok = _newton_direction(g, h, lx, fixed_b)
        step = np.where(ok, 1.0, 0.0)
        for _ in range(_HALVINGS):
            worse = (step > 0) & ~(_loglik_rows(a[idx] + step * da, b[idx] + step * db, lx, ni, ki) >= ll - slack[idx])
            if not worse.any():
                break
            step = np.where(worse, 0.5 * step, step)
        a[idx] += step * da
        b[idx] += step * db
        last = ok & (decrement < slack[idx])
        converged[idx[last]] = True
        active[idx[last | ~ok]] = False
    return a, b, converged


def _polish(lx: np.ndarray, n: np.ndarray, k: np.ndarray, mu: float, beta: float) -> tuple[float, float] | None:
    """The maximum of the likelihood from (mu, beta) by Newton's method in the concave probit form.

    Unconstrained first; if that maximum lies beyond a bound of beta (b = 1/beta past 1/5 or 1/1e-3, or running
    off to -inf for data that fall with IM), concavity puts the constrained one on that bound, found over a alone.
    Returns (median, beta), or None where Newton fails.
    """
    b_lo, b_hi = 1.0 / BETA_BOUNDS[1], 1.0 / BETA_BOUNDS[0]
    a, b, converged = _newton_rows(lx, n[None], k[None], np.array([-mu / beta]), np.array([1.0 / beta]))
    if converged[0] and b_lo <= b[0] <= b_hi:
        return math.exp(-a[0] / b[0]), 1.0 / b[0]
    if np.isnan(b[0]) or b_lo <= b[0] <= b_hi:
        return None  # stalled inside the bounds: no reason to look on them
    b_fix = b_lo if b[0] < b_lo else b_hi
    a, b, converged = _newton_rows(lx, n[None], k[None], np.array([-mu * b_fix]), np.array([b_fix]), fixed_b=True)
    return (math.exp(-a[0] / b_fix), 1.0 / b_fix) if converged[0] else None


def _at_bound(median: float, beta: float) -> LognormalFit | None:
    """The fit flagged "beta_at_bound" when beta stopped at a bound of :data:`BETA_BOUNDS`, else None."""
    for bound, side in zip(BETA_BOUNDS, ("lower", "upper"), strict=True):
        if abs(math.log(beta / bound)) < 1e-6:
            why = (
                "the overturn fraction barely rises with IM (or falls), which a lognormal cannot describe"
                if side == "upper"
                else "the data are nearly a step between two stripes"
            )
            return LognormalFit(median, beta, "beta_at_bound", f"beta stopped at its {side} bound {bound:g}: {why}")
    return None


def _fit_counts(lx: np.ndarray, n: np.ndarray, k: np.ndarray, start: np.ndarray | None = None) -> LognormalFit:
    """The fit on aggregated stripes (ln IM ascending, n > 0)."""
    if lx.size == 0:
        return LognormalFit(math.nan, math.nan, "no_data", "no valid record at any stripe")
    degenerate = _degenerate(lx, n, k)
    if degenerate is not None:
        return degenerate
    x0 = _start(lx, n, k) if start is None else start
    # Per-record scaling keeps the gradient O(1) whatever the number of records, so one tolerance fits all;
    # ln median is bounded (see _MU_MARGIN) only to keep a wild line search finite. TNC rather than L-BFGS-B:
    # the latter's per-iteration LAPACK calls cost milliseconds when OpenBLAS threads compete with other jobs
    # (measured 35x slower on a loaded 2-core machine).
    res = optimize.minimize(
        _neg_loglik,
        x0,
        args=(lx, n, k, 1.0 / n.sum()),
        jac=True,
        method="TNC",
        bounds=[(lx[0] - _MU_MARGIN, lx[-1] + _MU_MARGIN), (math.log(BETA_BOUNDS[0]), math.log(BETA_BOUNDS[1]))],
        options={"ftol": 0.0, "xtol": 1e-12, "gtol": 1e-12, "maxfun": 500},
    )
    # Where the median lies far beyond the stripes the likelihood is a flat ridge and TNC stops up to 1e-2
    # short of it, or runs out of evaluations on the way to a bound (measured); Newton in the concave form
    # finishes to rounding, as the bootstrap replicates do.
    polished = _polish(lx, n, k, float(res.x[0]), math.exp(res.x[1]))
    if polished is None:
        return LognormalFit(
            math.exp(res.x[0]), math.exp(res.x[1]), "not_converged", f"the optimiser stopped short: {res.message}"
        )
    return _at_bound(*polished) or LognormalFit(*polished, "ok", f"maximum-likelihood fit ({res.nit} iterations)")


def fit_lognormal(im, n, k) -> LognormalFit:
    """Maximum-likelihood lognormal fragility function from multiple-stripe counts.

    Parameters
    ----------
    im : array_like of float, shape (S,)
        Intensity of each stripe, positive (dimensionless, or any unit: the
        median comes out in it). Stripes of equal intensity are pooled.
    n : array_like of int, shape (S,)
        Valid records per stripe; stripes with n = 0 are left out.
    k : array_like of int, shape (S,)
        Overturns among them.

    Returns
    -------
    LognormalFit
        ``median`` [unit of ``im``], ``beta`` [-], ``status`` and ``message``.

    Notes
    -----
    Maximises prod_j C(n_j, k_j) p_j^k_j (1 - p_j)^(n_j - k_j) with
    p_j = Phi(ln(im_j / median) / beta) (Baker 2015, eq. 11) over
    (ln median, ln beta), beta within :data:`BETA_BOUNDS`, by a bounded
    truncated Newton method (scipy's TNC) from a probit regression on the
    stripes with 0 < k < n, then finished by Newton's method on the probit
    form p = Phi(a + b ln x), b = 1/beta, a = -ln(median)/beta, where the
    log-likelihood is concave: its maximum is unique, and on a bound of beta
    when the unconstrained one lies beyond it.

    The estimate does not exist when no record overturns ("no_overturn") or
    all do ("all_overturn"): NaN is returned. Nor does it when the stripes
    are separated, none overturning below some intensity and all above it,
    with at most one mixed stripe in between: the likelihood then rises as
    beta -> 0, and the step is returned ("separated", beta = 0, the median at
    the geometric mean of the two stripes around the step, or at the mixed
    stripe). A beta stopped at a bound gives "beta_at_bound".

    References
    ----------
    Baker (2015); Albert and Anderson (1984).
    """
    x = _check_im(im)
    n_, k_ = _check_counts(n, k)
    if n_.size != x.size:
        raise ValueError(f"`n` must have one count per stripe of `im` ({x.size}), got {n_.size}")
    if n_.sum() == 0:
        raise ValueError("`n` is zero at every stripe: no valid record to fit")
    return _fit_counts(*_aggregate(np.log(x), n_, k_))


# ----------------------------------------------------------------------------
# bootstrap over motions
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
    whose beta leaves :data:`BETA_BOUNDS` is refitted alone by :func:`_fit_counts`.
    """
    out = np.full((n.shape[0], 2), np.nan)
    if not start.beta > 0:
        # No estimate or a step: resampling cannot mix a stripe that is all 0 or all 1, so every replicate
        # is degenerate too.
        return out
    rows = np.flatnonzero(~_separable(n, k))
    a0 = np.full(rows.size, -math.log(start.median) / start.beta)
    b0 = np.full(rows.size, 1.0 / start.beta)
    a, b, converged = _newton_rows(st.lx, n[rows], k[rows], a0, b0)
    inside = converged & (b >= 1.0 / BETA_BOUNDS[1]) & (b <= 1.0 / BETA_BOUNDS[0])
    out[rows[inside], 0] = np.exp(-a[inside] / b[inside])
    out[rows[inside], 1] = 1.0 / b[inside]
    x0 = np.array([math.log(start.median), math.log(start.beta)])
    for i in rows[~inside]:
        keep = n[i] > 0
        fit = _fit_counts(st.lx[keep], n[i, keep], k[i, keep], x0)
        if fit.status in _USABLE:
            out[i] = fit.median, fit.beta
    return out


def _percentile_interval(values: np.ndarray, ci: float) -> tuple[float, float]:
    v = values[np.isfinite(values)]
    if v.size == 0:
        return math.nan, math.nan
    low, high = np.percentile(v, [50.0 * (1.0 - ci), 50.0 * (1.0 + ci)])
    return float(low), float(high)


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
    o, v = _outcomes(overturned, valid)
    x = _check_im(im, o.shape[1])
    n_boot, ci = _check_n_boot(n_boot), _check_ci(ci)
    st = _stripes(x)
    fit = fit_lognormal(x, v.sum(axis=0), o.sum(axis=0))
    est = np.full((n_boot, 2), np.nan)
    rng = np.random.default_rng(seed)
    row = 0
    for w in _motion_weights(rng, o.shape[0], n_boot):
        est[row : row + w.shape[0]] = _replicate_fits(st, w @ v @ st.pool, w @ o @ st.pool, fit)
        row += w.shape[0]
    medians, betas = est[:, 0], est[:, 1]
    return BootstrapFit(
        fit,
        *_percentile_interval(medians, ci),
        *_percentile_interval(betas, ci),
        n_boot,
        int(np.count_nonzero(np.isnan(medians))),
        medians,
        betas,
    )


# ----------------------------------------------------------------------------
# two engines on the same motions
class FitComparison(NamedTuple):
    """Fragility of an engine against a reference, with paired-bootstrap intervals.

    Attributes
    ----------
    median_ratio : float
        Median of the engine over that of the reference [-].
    ratio_low, ratio_high : float
        Percentile interval of the ratio [-].
    beta_diff : float
        Beta of the engine minus that of the reference [-].
    diff_low, diff_high : float
        Percentile interval of the difference [-].
    disagree : bool
        The ratio interval excludes 1 or the difference interval excludes 0.
        Two intervals are checked, so for engines that agree it comes out
        True with probability up to about 2 (1 - ci), more where percentile
        intervals run short (those of beta do with about 100 motions).
        False when the intervals are NaN: check both fits' ``status``.
    fit_engine, fit_reference : LognormalFit
        The two point fits.
    n_boot : int
        Replicates drawn.
    n_failed : int
        Replicates left out because either fit was degenerate.
    """

    median_ratio: float
    ratio_low: float
    ratio_high: float
    beta_diff: float
    diff_low: float
    diff_high: float
    disagree: bool
    fit_engine: LognormalFit
    fit_reference: LognormalFit
    n_boot: int
    n_failed: int


def compare_fits(
    im,
    overturned_engine,
    overturned_reference,
    valid_engine=None,
    valid_reference=None,
    n_boot: int = 1000,
    seed=0,
    ci: float = 0.95,
) -> FitComparison:
    """Compare the fragility functions of two engines run on the same motions, by a paired bootstrap.

    Parameters
    ----------
    im : array_like of float, shape (S,)
        Intensity of each stripe, positive [dimensionless, or any unit].
    overturned_engine, overturned_reference : array_like of bool, shape (M, S)
        Outcomes of the two engines, row m from the same motion in both.
    valid_engine, valid_reference : array_like of bool, shape (M, S), optional
        False for a failed record of that engine; default all True.
    n_boot : int
        Number of bootstrap replicates.
    seed : int, numpy.random.SeedSequence or numpy.random.Generator
        Seed of :func:`numpy.random.default_rng`.
    ci : float
        Confidence level of the intervals [-].

    Returns
    -------
    FitComparison
        Ratio of medians and difference of betas with their intervals, the
        verdict ``disagree`` and both point fits. Identical data give a ratio
        of exactly 1 and a difference of exactly 0, intervals included.

    Notes
    -----
    Each replicate resamples the motions once and refits both engines on that
    same resample: both ran the same motions, so the motion-to-motion
    variability common to both cancels in the ratio, and the interval measures
    only how differently the engines respond. Replicates where either fit is
    degenerate are left out (``n_failed``), as in :func:`bootstrap_fit`.

    References
    ----------
    Efron and Tibshirani (1993), ch. 13; Baker (2015).
    """
    oe, ve = _outcomes(overturned_engine, valid_engine, "overturned_engine", "valid_engine")
    orf, vr = _outcomes(overturned_reference, valid_reference, "overturned_reference", "valid_reference")
    if oe.shape != orf.shape:
        raise ValueError(
            f"`overturned_engine` {oe.shape} and `overturned_reference` {orf.shape} must pair the same motions "
            "and stripes"
        )
    x = _check_im(im, oe.shape[1])
    n_boot, ci = _check_n_boot(n_boot), _check_ci(ci)
    st = _stripes(x)
    fe = fit_lognormal(x, ve.sum(axis=0), oe.sum(axis=0))
    fr = fit_lognormal(x, vr.sum(axis=0), orf.sum(axis=0))
    eng, ref = np.full((n_boot, 2), np.nan), np.full((n_boot, 2), np.nan)
    rng = np.random.default_rng(seed)
    row = 0
    for w in _motion_weights(rng, oe.shape[0], n_boot):
        rows = slice(row, row + w.shape[0])
        eng[rows] = _replicate_fits(st, w @ ve @ st.pool, w @ oe @ st.pool, fe)
        ref[rows] = _replicate_fits(st, w @ vr @ st.pool, w @ orf @ st.pool, fr)
        row += w.shape[0]
    ratio_low, ratio_high = _percentile_interval(eng[:, 0] / ref[:, 0], ci)
    diff_low, diff_high = _percentile_interval(eng[:, 1] - ref[:, 1], ci)
    # NaN comparisons are False, so missing intervals never claim a disagreement.
    disagree = bool(ratio_low > 1.0 or ratio_high < 1.0 or diff_low > 0.0 or diff_high < 0.0)
    return FitComparison(
        fe.median / fr.median,
        ratio_low,
        ratio_high,
        fe.beta - fr.beta,
        diff_low,
        diff_high,
        disagree,
        fe,
        fr,
        n_boot,
        int(np.count_nonzero(np.isnan(eng[:, 0]) | np.isnan(ref[:, 0]))),
    )


# ----------------------------------------------------------------------------
# exceedance of response thresholds, and the curve
def _check_ratios(values) -> np.ndarray:
    r = _check_matrix(values, "theta_max_over_alpha")
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
    v = _valid_mask(valid, r.shape) & ~np.isnan(r)
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


def fragility_curve(x, median: float, beta: float) -> np.ndarray:
    """The lognormal fragility function Phi(ln(x / median) / beta).

    Parameters
    ----------
    x : array_like of float
        Intensities [unit of ``median``]; 0 is returned for x <= 0.
    median : float
        IM of 50 % probability, positive; NaN gives NaN everywhere (a fit that does not exist).
    beta : float
        Logarithmic standard deviation [-], >= 0; 0 gives the step (1/2 at the median).

    Returns
    -------
    ndarray
        Probability of overturning [-], the shape of ``x``.
    """
    xa = np.asarray(x, dtype=np.float64)
    median, beta = float(median), float(beta)
    if math.isnan(median) or math.isnan(beta):
        return np.full(xa.shape, np.nan)
    if not (median > 0 and math.isfinite(median)):
        raise ValueError(f"`median` must be a finite positive intensity, got {median!r}")
    if not (beta >= 0 and math.isfinite(beta)):
        raise ValueError(f"`beta` must be finite and >= 0, got {beta!r}")
    pos = xa > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        lr = np.log(np.where(pos, xa, 1.0) / median)
        p = special.ndtr(lr / beta) if beta > 0 else np.where(lr > 0, 1.0, np.where(lr < 0, 0.0, 0.5))
    return np.where(pos, p, 0.0)
