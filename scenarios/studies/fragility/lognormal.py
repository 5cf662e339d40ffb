"""The lognormal fragility function and its maximum-likelihood fit to multiple-stripe counts.

References
----------
Baker, J. W. (2015). Efficient analytical fragility function fitting using
dynamic structural analysis. Earthquake Spectra 31(1), 579-599 (multiple-stripe
likelihood, eq. 11).
Albert, A., Anderson, J. A. (1984). On the existence of maximum likelihood
estimates in logistic regression models. Biometrika 71(1), 1-10 (separation).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy import optimize, special

from housner.scenarios.studies.fragility.input_checks import check_counts, check_im
from housner.scenarios.studies.fragility.newton import LOG_SQRT_2PI, newton_rows

__all__ = ["BETA_BOUNDS", "LognormalFit", "fit_lognormal", "fragility_curve"]

#: Search range of the logarithmic standard deviation beta [-]. Below 1e-3 the curve is a step at the
#: resolution of any stripe spacing in use; above 5 it rises from 5 % to 95 % over more than 7 decades of
#: IM, i.e. the data show no dependence on intensity that a lognormal can describe.
BETA_BOUNDS = (1e-3, 5.0)
#: Search range of ln median beyond the stripes' ln IM: fitted probabilities down to about 1e-9 at the
#: stripes (one overturn in a billion records) keep |ln(x / median)| / beta below 6, i.e. ln median within
#: 6 x 5 = 30 of the stripes with beta <= 5; 50 leaves a margin.
_MU_MARGIN = 50.0


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
    lpdf = -0.5 * z * z - LOG_SQRT_2PI
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


def _polish(lx: np.ndarray, n: np.ndarray, k: np.ndarray, mu: float, beta: float) -> tuple[float, float] | None:
    """The maximum of the likelihood from (mu, beta) by Newton's method in the concave probit form.

    Unconstrained first; if that maximum lies beyond a bound of beta (b = 1/beta past 1/5 or 1/1e-3, or running
    off to -inf for data that fall with IM), concavity puts the constrained one on that bound, found over a alone.
    Returns (median, beta), or None where Newton fails.
    """
    b_lo, b_hi = 1.0 / BETA_BOUNDS[1], 1.0 / BETA_BOUNDS[0]
    a, b, converged = newton_rows(lx, n[None], k[None], np.array([-mu / beta]), np.array([1.0 / beta]))
    if converged[0] and b_lo <= b[0] <= b_hi:
        return math.exp(-a[0] / b[0]), 1.0 / b[0]
    if np.isnan(b[0]) or b_lo <= b[0] <= b_hi:
        return None  # stalled inside the bounds: no reason to look on them
    b_fix = b_lo if b[0] < b_lo else b_hi
    a, b, converged = newton_rows(lx, n[None], k[None], np.array([-mu * b_fix]), np.array([b_fix]), fixed_b=True)
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


def fit_counts(lx: np.ndarray, n: np.ndarray, k: np.ndarray, start: np.ndarray | None = None) -> LognormalFit:
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
    x = check_im(im)
    n_, k_ = check_counts(n, k)
    if n_.size != x.size:
        raise ValueError(f"`n` must have one count per stripe of `im` ({x.size}), got {n_.size}")
    if n_.sum() == 0:
        raise ValueError("`n` is zero at every stripe: no valid record to fit")
    return fit_counts(*_aggregate(np.log(x), n_, k_))


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
