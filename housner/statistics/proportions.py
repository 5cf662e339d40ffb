"""The probability of overturning: a binomial proportion over the records, with a confidence interval.

Overturning is an outcome of its own (:mod:`housner.statistics.ensemble_stats`): each record either overturned or not,
and
the share that did is a binomial proportion k/n. :func:`overturn_probability` gives it with a Wilson
score or a Clopper-Pearson interval; :func:`wilson_interval` is the score interval elementwise, for
tables of counts.

References
----------
Wilson, E. B. (1927). Probable inference, the law of succession, and
statistical inference. JASA 22, 209-212.
Clopper, C. J., Pearson, E. S. (1934). The use of confidence or fiducial
limits illustrated in the case of the binomial. Biometrika 26, 404-413.
"""

from __future__ import annotations

from statistics import NormalDist
from typing import NamedTuple

import numpy as np

from housner.errors import unknown_choice
from housner.statistics.ensemble_stats import check_ci

__all__ = ["ProportionCI", "overturn_probability", "wilson_interval"]


class ProportionCI(NamedTuple):
    """A proportion with a two-sided confidence interval [-]."""

    estimate: float
    low: float
    high: float


_PROPORTION_METHODS = ("wilson", "clopper-pearson")


def wilson_interval(k, n, ci: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Wilson score interval of k successes in n trials, elementwise [-]; NaN where n = 0.

    (k + z^2/2)/(n + z^2) -+ z/(n + z^2) sqrt(k (n - k)/n + z^2/4) with z = Phi^-1((1 + ci)/2),
    exactly 0 at k = 0 and 1 at k = n (rounding would leave 3e-17 there, outside [k/n, ...]).
    ``ci`` is taken as checked.
    """
    k = np.asarray(k, dtype=float)
    n = np.asarray(n, dtype=float)
    z = NormalDist().inv_cdf(0.5 * (1.0 + ci))
    z2 = z * z
    with np.errstate(invalid="ignore", divide="ignore"):
        centre = (k + 0.5 * z2) / (n + z2)
        half = z / (n + z2) * np.sqrt(k * (n - k) / n + 0.25 * z2)
    empty = n == 0
    low = np.where(empty, np.nan, np.where(k == 0, 0.0, np.clip(centre - half, 0.0, 1.0)))
    high = np.where(empty, np.nan, np.where(k == n, 1.0, np.clip(centre + half, 0.0, 1.0)))
    return low, high


def overturn_probability(overturned, *, ci: float = 0.95, method: str = "wilson") -> ProportionCI:
    """Probability of overturning with a binomial confidence interval.

    Parameters
    ----------
    overturned : array_like of bool
        One verdict per record (True = overturned). Failed runs must be left out.
    ci : float
        Confidence level [-].
    method : {"wilson", "clopper-pearson"}
        ``"wilson"``: the score interval (no continuity correction), close to
        nominal coverage and never outside [0, 1]. ``"clopper-pearson"``: the
        exact interval from beta quantiles, conservative (coverage >= ci).

    Returns
    -------
    ProportionCI
        ``estimate`` = k/n, ``low``, ``high`` [-].

    Notes
    -----
    With k overturns out of n and z = Phi^-1((1 + ci)/2), Wilson's interval is
    (k + z^2/2)/(n + z^2) -+ z/(n + z^2) sqrt(k (n - k)/n + z^2/4). The
    Clopper-Pearson ends are Beta((1 - ci)/2; k, n - k + 1) and
    Beta((1 + ci)/2; k + 1, n - k), with 0 for k = 0 and 1 for k = n.

    References
    ----------
    Wilson (1927); Clopper and Pearson (1934).
    """
    try:
        o = np.asarray(overturned)
    except (TypeError, ValueError):
        raise ValueError("`overturned` must be an array of booleans") from None
    o = o.reshape(-1)
    if o.size == 0:
        raise ValueError("`overturned` is empty: no records to estimate an overturning probability from")
    if o.dtype != np.bool_:
        if not np.all(np.isin(o, (0, 1))):
            raise ValueError("`overturned` must hold booleans (or 0/1), one verdict per record")
        o = o.astype(bool)
    ci = check_ci(ci)
    if method not in _PROPORTION_METHODS:
        raise unknown_choice("`method`", method, _PROPORTION_METHODS)
    n = int(o.size)
    k = int(np.count_nonzero(o))
    est = k / n
    if method == "wilson":
        low, high = wilson_interval(k, n, ci)
        return ProportionCI(est, float(low), float(high))
    from scipy.special import betaincinv

    a = 1.0 - ci
    low = 0.0 if k == 0 else float(betaincinv(k, n - k + 1, 0.5 * a))
    high = 1.0 if k == n else float(betaincinv(k + 1, n - k, 1.0 - 0.5 * a))
    return ProportionCI(est, low, high)
