"""Statistics on ensembles of rocking responses, with overturning as an outcome of its own.

The quantity is the peak rotation of each record normalised by the slenderness,
theta_max / alpha [-]. An overturned block has no finite peak: it is written as
``+inf``, so that it sorts above every rocking response and the empirical CDF
of the finite values tops out at 1 - P[overturn] (as in Fig. 10 of the seed
paper, where the curves stop below 1). A failed simulation (``NaN``) is not an
outcome: the array functions refuse it, and the table helpers drop failed rows
and count them.

Array functions: :func:`ecdf` (+ :func:`dkw_band`), :func:`percentiles` (with
percentile-bootstrap intervals), :func:`ks_2samp`, :func:`wasserstein`,
:func:`per_record_agreement`; the probability of overturning, with Wilson or
Clopper-Pearson intervals, is :func:`housner.statistics.proportions.overturn_probability`.
Their use on the runner's results table (one row per engine and motion) is
:mod:`housner.scenarios.execution.tables`'.

References
----------
Bachmann, J. A., Strand, M., Vassiliou, M. F., Broccardo, M., Stojadinovic, B.
(2017). Probabilistic validation of the Housner rocking model. COMPDYN 2017,
Sec. 6, Fig. 10 and Table 2.
Yim, C.-S., Chopra, A. K., Penzien, J. (1980). Rocking response of rigid blocks
to earthquakes. Earthquake Eng. Struct. Dyn. 8(6), 565-587.
Dvoretzky, A., Kiefer, J., Wolfowitz, J. (1956), with Massart's constant
(1990): P(sup |F_n - F| > eps) <= 2 exp(-2 n eps^2).
Efron, B., Tibshirani, R. (1993). An Introduction to the Bootstrap, ch. 13
(percentile intervals).
Hyndman, R. J., Fan, Y. (1996). Sample quantiles in statistical packages.
Am. Stat. 50(4), 361-365.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from housner._validate import vector

__all__ = [
    "ECDF",
    "KSResult",
    "KS_MAX",
    "OVERTURN_TOL",
    "PercentileEstimate",
    "RecordAgreement",
    "dkw_band",
    "ecdf",
    "ks_2samp",
    "per_record_agreement",
    "percentile_label",
    "percentiles",
    "wasserstein",
]

#: The distribution criterion of a run's headline verdict and of users' CI
#: (:func:`housner.reports.assertions.runs.assert_cdf_agreement`): a two-sample KS distance of theta_max/alpha
#: at most KS_MAX [-] and P[overturn] within OVERTURN_TOL [-] of the reference's.
KS_MAX = 0.15
OVERTURN_TOL = 0.08

#: Bootstrap resamples are drawn in blocks of at most this many values, to bound memory.
_BOOT_BLOCK_VALUES = 4_000_000


# ----------------------------------------------------------------------------
# validation
def _theta_over_alpha(values, name: str = "values", *, allow_empty: bool = False) -> np.ndarray:
    """theta_max/alpha as a 1-D float array: finite and >= 0, or +inf for an overturn."""
    v = vector(
        name, values, expected="numeric (theta_max/alpha, +inf for an overturn)", shape_note=" (one value per record)"
    )
    if v.size == 0 and not allow_empty:
        raise ValueError(f"`{name}` is empty")
    nan = np.flatnonzero(np.isnan(v))
    if nan.size:
        raise ValueError(
            f"`{name}` holds NaN at index {nan[0]} ({nan.size} in all): a failed run is not an outcome; "
            "drop failed runs first (see `split_failed`)"
        )
    bad = np.flatnonzero((v < 0) | (v == -np.inf))
    if bad.size:
        raise ValueError(f"`{name}` must be >= 0 (theta_max/alpha), got {v[bad[0]]} at index {bad[0]}")
    return v


def check_ci(ci: float, name: str = "ci") -> float:
    """A confidence level as a float in (0, 1) [-]; ValueError naming ``name`` otherwise."""
    try:
        c = float(ci)
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be a number in (0, 1), got {ci!r}") from None
    if not 0.0 < c < 1.0:
        raise ValueError(f"`{name}` must lie in (0, 1) (e.g. 0.95), got {ci!r}")
    return c


def _finite_stand_in(*arrays: np.ndarray) -> float:
    """A finite number above every finite value of the arrays, to stand in for +inf.

    Replacing +inf by it is a monotone map, so order statistics, ranks and the
    KS distance are unchanged; a result above the largest finite value maps back to +inf.
    """
    top = 0.0
    for a in arrays:
        f = a[np.isfinite(a)]
        if f.size:
            top = max(top, float(f.max()))
    return 2.0 * top + 1.0


# ----------------------------------------------------------------------------
# empirical CDF
@dataclass(frozen=True, eq=False)
class ECDF:
    """Empirical CDF of theta_max/alpha with overturning as a separate atom at +inf.

    Attributes
    ----------
    x : ndarray
        Distinct finite values, ascending [-] (theta_max/alpha).
    F : ndarray
        F(x) = #(values <= x) / n [-], a right-continuous step function; its
        last value is 1 - ``p_overturn``, not 1.
    p_overturn : float
        Share of the records that overturned [-]: the jump of the CDF at +inf.
    n : int
        Number of records, overturned ones included.
    """

    x: np.ndarray
    F: np.ndarray
    p_overturn: float
    n: int

    def __call__(self, t) -> np.ndarray:
        """F(t) = #(values <= t) / n at theta_max/alpha ``t`` [-]; F(+inf) = 1."""
        t = np.asarray(t, dtype=np.float64)
        k = np.searchsorted(self.x, t, side="right")
        F = np.concatenate(([0.0], self.F))[k]
        return np.where(np.isposinf(t), 1.0, F)

    def band(self, ci: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
        """DKW confidence band (lower, upper) on F at ``x``; see :func:`dkw_band`."""
        return dkw_band(self.F, self.n, ci)


def ecdf(values) -> ECDF:
    """Empirical CDF of theta_max/alpha, overturns (+inf) kept as their own outcome.

    Parameters
    ----------
    values : array_like
        theta_max/alpha per record [-]; ``+inf`` for an overturned block. NaN
        (a failed run) is refused.

    Returns
    -------
    ECDF
        ``x`` (distinct finite values, ascending), ``F`` = #(values <= x)/n
        at each, ``p_overturn`` and ``n``. The convention: the CDF is over all
        n records, so it rises to 1 - P[overturn] at the largest finite value
        and jumps to 1 only "at infinity", and curves of two engines are
        comparable even when they overturn differently often.

    References
    ----------
    Bachmann et al. (2017), Fig. 10; Yim, Chopra and Penzien (1980).
    """
    v = _theta_over_alpha(values)
    n = v.size
    finite = np.sort(v[np.isfinite(v)])
    x, counts = np.unique(finite, return_counts=True)
    F = np.cumsum(counts) / n
    return ECDF(x=x, F=F, p_overturn=float((n - finite.size) / n), n=int(n))


def dkw_band(F, n: int, ci: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Simultaneous confidence band on a CDF from the Dvoretzky-Kiefer-Wolfowitz inequality.

    Parameters
    ----------
    F : array_like
        Empirical CDF values [-].
    n : int
        Number of records the CDF was built from.
    ci : float
        Confidence level [-], e.g. 0.95.

    Returns
    -------
    lower, upper : ndarray
        F -+ eps clipped to [0, 1], with eps = sqrt(ln(2 / (1 - ci)) / (2 n)).
        With probability at least ``ci`` the true CDF lies inside the band at
        every x at once (the overturn atom included: the inequality holds for
        any distribution on the extended real line).

    References
    ----------
    Dvoretzky, Kiefer and Wolfowitz (1956); Massart (1990), tight constant 2.
    """
    ci = check_ci(ci)
    if not (isinstance(n, (int, np.integer)) and n > 0):
        raise ValueError(f"`n` must be a positive integer, got {n!r}")
    F = np.asarray(F, dtype=np.float64)
    eps = math.sqrt(math.log(2.0 / (1.0 - ci)) / (2.0 * n))
    return np.clip(F - eps, 0.0, 1.0), np.clip(F + eps, 0.0, 1.0)


# ----------------------------------------------------------------------------
# percentiles with bootstrap intervals
class PercentileEstimate(NamedTuple):
    """Percentiles of theta_max/alpha with confidence intervals (+inf = "overturn").

    Attributes
    ----------
    q : ndarray
        Percentile levels [%].
    value : ndarray
        Sample percentiles [-].
    low, high : ndarray
        Ends of the percentile-bootstrap interval [-]; NaN when no bootstrap was run.
    """

    q: np.ndarray
    value: np.ndarray
    low: np.ndarray
    high: np.ndarray


def _percentile_inf(v: np.ndarray, q: np.ndarray, method: str, axis: int | None = None) -> np.ndarray:
    """np.percentile that treats +inf as the largest outcome and answers +inf where it reaches it."""
    w = np.where(np.isposinf(v), _finite_stand_in(v), v)
    out = np.percentile(w, q, axis=axis, method=method)
    # Interpolating between the largest finite value and an overturn lands
    # strictly above that value: the percentile falls in the overturn mass.
    return np.where(out > _top_finite(v), np.inf, out)


def percentiles(
    values,
    q: Sequence[float] = (25, 50, 75),
    *,
    ci: float = 0.90,
    n_boot: int = 2000,
    seed=0,
    method: str = "linear",
) -> PercentileEstimate:
    """Percentiles of theta_max/alpha with percentile-bootstrap confidence intervals.

    Parameters
    ----------
    values : array_like
        theta_max/alpha per record [-], ``+inf`` for an overturn; NaN is refused.
    q : sequence of float
        Percentile levels [%], in [0, 100].
    ci : float
        Confidence level of the intervals [-].
    n_boot : int
        Number of bootstrap resamples; 0 skips the bootstrap (``low``/``high`` NaN).
    seed : int, numpy.random.SeedSequence or numpy.random.Generator
        Seed of the resampling; the same seed gives the same intervals.
    method : str
        Sample-quantile definition passed to :func:`numpy.percentile`; the
        default ``"linear"`` is Hyndman and Fan's type 7.

    Returns
    -------
    PercentileEstimate
        ``q``, ``value``, ``low``, ``high`` [-]. A percentile that reaches the
        overturn mass is ``+inf`` (Table 2 of the seed paper writes
        "overturn"); an interval end may be ``+inf`` too.

    Notes
    -----
    Overturns sort above every finite response. With interpolating methods a
    percentile between the largest finite value and an overturn is an
    overturn: with 30 % of records overturned, the 75th percentile is +inf.
    The interval is the (1 - ci)/2 and (1 + ci)/2 quantiles of the percentile
    over ``n_boot`` resamples of the records with replacement.

    References
    ----------
    Efron and Tibshirani (1993), ch. 13; Hyndman and Fan (1996);
    Bachmann et al. (2017), Table 2.
    """
    v = _theta_over_alpha(values)
    try:
        qa = np.atleast_1d(np.asarray(q, dtype=np.float64))
    except (TypeError, ValueError):
        raise ValueError(f"`q` must be percentile levels in [0, 100], got {q!r}") from None
    if qa.ndim != 1 or qa.size == 0 or not np.all((qa >= 0) & (qa <= 100)):
        raise ValueError(f"`q` must be percentile levels in [0, 100], got {q!r}")
    ci = check_ci(ci)
    if not (isinstance(n_boot, (int, np.integer)) and n_boot >= 0):
        raise ValueError(f"`n_boot` must be a non-negative integer, got {n_boot!r}")
    value = _percentile_inf(v, qa, method)
    if n_boot == 0:
        nan = np.full(qa.shape, np.nan)
        return PercentileEstimate(qa, value, nan, nan.copy())
    rng = np.random.default_rng(seed)
    n = v.size
    # Resample with +inf replaced by a stand-in (monotone; mapped back below).
    stand_in = _finite_stand_in(v)
    w = np.where(np.isposinf(v), stand_in, v)
    block = max(1, _BOOT_BLOCK_VALUES // n)
    boot = np.empty((n_boot, qa.size))
    for start in range(0, n_boot, block):
        stop = min(n_boot, start + block)
        idx = rng.integers(0, n, size=(stop - start, n))
        boot[start:stop] = np.percentile(w[idx], qa, axis=1, method=method).T
    boot = np.where(boot > _top_finite(v), np.inf, boot)
    lo_hi = _percentile_inf_columns(boot, [50.0 * (1.0 - ci), 50.0 * (1.0 + ci)], method)
    return PercentileEstimate(qa, value, lo_hi[0], lo_hi[1])


def _top_finite(v: np.ndarray) -> float:
    f = v[np.isfinite(v)]
    return float(f.max()) if f.size else -np.inf


def _percentile_inf_columns(boot: np.ndarray, levels: list[float], method: str) -> np.ndarray:
    """Percentiles ``levels`` of each column of ``boot`` (which may hold +inf), shape (len(levels), ncol)."""
    out = np.empty((len(levels), boot.shape[1]))
    for j in range(boot.shape[1]):
        out[:, j] = _percentile_inf(boot[:, j], np.asarray(levels), method)
    return out


# ----------------------------------------------------------------------------
# distances between two ensembles
class KSResult(NamedTuple):
    """Two-sample Kolmogorov-Smirnov distance and p-value [-]."""

    distance: float
    pvalue: float


def ks_2samp(a, b) -> KSResult:
    """Kolmogorov-Smirnov distance between two ensembles, overturns counted as +inf.

    Parameters
    ----------
    a, b : array_like
        theta_max/alpha per record [-] of two engines (or engine and
        experiment), ``+inf`` for an overturn; NaN is refused.

    Returns
    -------
    KSResult
        ``distance`` = sup_x |F_a(x) - F_b(x)| over the CDFs of :func:`ecdf`,
        which end at 1 - P[overturn]: a difference in the overturn fractions
        alone gives a distance of at least |P_a - P_b|. ``pvalue`` of the
        two-sided test of equal distributions (scipy's exact or asymptotic
        null distribution).

    Notes
    -----
    The null distribution assumes continuous data; the overturn atom (and
    any other ties) makes the test conservative, i.e. the p-value is larger
    than it would be for tie-free data.

    References
    ----------
    Yim, Chopra and Penzien (1980); Bachmann et al. (2017), Sec. 6.
    """
    x = _theta_over_alpha(a, "a")
    y = _theta_over_alpha(b, "b")
    fa, fb = ecdf(x), ecdf(y)
    grid = np.union1d(fa.x, fb.x)
    distance = float(np.max(np.abs(fa(grid) - fb(grid)))) if grid.size else 0.0
    from scipy import stats

    # The p-value is scipy's; it sees +inf through a monotone finite stand-in. For two nearly equal ensembles
    # (D of a few 1/n, p near 1) its exact method does not converge and it takes the asymptotic one, as
    # documented above, with a RuntimeWarning that would reach the user's terminal: that one is not shown.
    stand_in = _finite_stand_in(x, y)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="ks_2samp: Exact calculation unsuccessful", category=RuntimeWarning)
        res = stats.ks_2samp(np.where(np.isposinf(x), stand_in, x), np.where(np.isposinf(y), stand_in, y))
    return KSResult(distance, float(res.pvalue))


def wasserstein(a, b) -> float:
    """First Wasserstein (earth mover's) distance between the non-overturned parts [-].

    Parameters
    ----------
    a, b : array_like
        theta_max/alpha per record [-], ``+inf`` for an overturn; NaN is refused.

    Returns
    -------
    float
        W1 = integral |G_a(x) - G_b(x)| dx in units of alpha, where G is the
        CDF of the finite values of each sample renormalised to 1 (the records
        that rocked without overturning). It measures how far the rocking
        amplitudes differ, independently of how often each overturns; compare
        overturn fractions separately. NaN when either side has no finite value.

    Notes
    -----
    Overturns cannot enter W1 (moving mass to +inf costs an infinite distance),
    so they are left out rather than capped at an arbitrary value.
    """
    x = _theta_over_alpha(a, "a")
    y = _theta_over_alpha(b, "b")
    x = np.sort(x[np.isfinite(x)])
    y = np.sort(y[np.isfinite(y)])
    if x.size == 0 or y.size == 0:
        return math.nan
    grid = np.union1d(x, y)
    Gx = np.searchsorted(x, grid[:-1], side="right") / x.size
    Gy = np.searchsorted(y, grid[:-1], side="right") / y.size
    return float(np.sum(np.abs(Gx - Gy) * np.diff(grid)))


# ----------------------------------------------------------------------------
# record-by-record agreement
class RecordAgreement(NamedTuple):
    """Record-by-record agreement of two engines on the same motions.

    Attributes
    ----------
    n : int
        Number of paired records.
    n_same_verdict : int
        Records where both overturned or both did not.
    n_agree : int
        Records that agree: both overturned, or both rocked with theta_max/alpha
        within tolerance.
    same_verdict, agree : ndarray of bool
        The per-record flags, in the order given.
    """

    n: int
    n_same_verdict: int
    n_agree: int
    same_verdict: np.ndarray
    agree: np.ndarray

    @property
    def share(self) -> float:
        """Share of records in agreement, n_agree / n [-]."""
        return self.n_agree / self.n if self.n else math.nan

    @property
    def verdict_share(self) -> float:
        """Share of records with the same overturn verdict [-]."""
        return self.n_same_verdict / self.n if self.n else math.nan


def per_record_agreement(a, b, *, rtol: float = 0.1, atol: float = 0.05) -> RecordAgreement:
    """Compare two engines record by record on the same motions.

    Parameters
    ----------
    a : array_like
        theta_max/alpha per record [-] of the engine under test (+inf = overturned).
    b : array_like
        The same for the reference, record i of ``b`` from the same motion as
        record i of ``a``.
    rtol : float
        Relative tolerance on theta_max/alpha [-], relative to the reference.
    atol : float
        Absolute tolerance on theta_max/alpha [-] (in units of alpha).

    Returns
    -------
    RecordAgreement
        A record agrees when both overturned, or neither did and
        |a - b| <= atol + rtol |b| (the rule of :func:`numpy.isclose`).

    Notes
    -----
    Rocking is sensitive to small perturbations (Bachmann et al. 2017, Fig. 9),
    so low record-by-record agreement alone does not condemn an engine; the
    distributional measures carry the verdict.
    """
    x = _theta_over_alpha(a, "a", allow_empty=True)
    y = _theta_over_alpha(b, "b", allow_empty=True)
    if x.shape != y.shape:
        raise ValueError(f"`a` and `b` must pair the same records, got lengths {x.size} and {y.size}")
    for name, tol in (("rtol", rtol), ("atol", atol)):
        if not (isinstance(tol, (int, float, np.floating)) and math.isfinite(tol) and tol >= 0):
            raise ValueError(f"`{name}` must be a finite number >= 0, got {tol!r}")
    ox, oy = np.isposinf(x), np.isposinf(y)
    same = ox == oy
    both_rock = ~ox & ~oy
    close = np.zeros_like(same)
    close[both_rock] = np.abs(x[both_rock] - y[both_rock]) <= atol + rtol * np.abs(y[both_rock])
    agree = (ox & oy) | close
    return RecordAgreement(int(x.size), int(same.sum()), int(agree.sum()), same, agree)


def percentile_label(q: float) -> str:
    """The label of percentile level ``q`` [%]: "25th", "1st", "99.5th"."""
    s = f"{q:g}"
    if s.endswith(("11", "12", "13")) or "." in s:
        suffix = "th"
    else:
        suffix = {"1": "st", "2": "nd", "3": "rd"}.get(s[-1], "th")
    return s + suffix
