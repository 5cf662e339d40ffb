"""Fragility functions from multiple-stripe analysis: lognormal fits, bootstrap intervals, engine comparison.

One engine and one block size give a boolean matrix ``overturned[m, s]``:
motion m (0..M-1) scaled to the intensity ``im[s]`` of stripe s (0..S-1),
the same motions at every stripe. The fragility function is the lognormal
CDF P(overturn | IM = x) = Phi(ln(x / median) / beta), fitted by maximum
likelihood to the stripes' binomial counts (Baker 2015). The intensity is
whatever the campaign scales the motions to; here it is dimensionless (e.g.
PGA / (g tan alpha)), and the median carries the same unit as ``im``.

Modules, one concept each (this package's names are their public ones):

- :mod:`.counts`: :func:`stripe_counts`, :func:`proportion_intervals` (Wilson);
- :mod:`.lognormal`: :func:`fit_lognormal` (maximum likelihood) and :func:`fragility_curve`;
- :mod:`.newton`: Newton's method on the concave probit form, many rows at once (the fit's finish, the bootstrap);
- :mod:`.bootstrap`: :func:`bootstrap_fit` (motions resampled);
- :mod:`.compare`: :func:`compare_fits` (paired bootstrap of two engines on the same motions) and
  :func:`interval_disagreement`, the rule that calls two engines' fragility different;
- :mod:`.thresholds`: :func:`exceedance` (P[theta_max/alpha >= threshold] per stripe);
- :mod:`.checks`: the checks of every function's inputs.

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

from housner.scenarios.studies.fragility.bootstrap import BootstrapFit, bootstrap_fit
from housner.scenarios.studies.fragility.compare import FitComparison, compare_fits, interval_disagreement
from housner.scenarios.studies.fragility.counts import proportion_intervals, stripe_counts
from housner.scenarios.studies.fragility.lognormal import BETA_BOUNDS, LognormalFit, fit_lognormal, fragility_curve
from housner.scenarios.studies.fragility.thresholds import exceedance

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
    "interval_disagreement",
    "proportion_intervals",
    "stripe_counts",
]
