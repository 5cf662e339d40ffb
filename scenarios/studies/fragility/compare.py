"""Two engines' fragility on the same motions: ratio of medians and difference of betas, paired bootstrap.

References
----------
Efron, B., Tibshirani, R. (1993). An Introduction to the Bootstrap, ch. 13.
Baker, J. W. (2015). Efficient analytical fragility function fitting using
dynamic structural analysis. Earthquake Spectra 31(1), 579-599.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from housner.scenarios.studies.fragility.bootstrap import percentile_interval, resampled_fits
from housner.scenarios.studies.fragility.input_checks import check_im, check_n_boot, outcomes
from housner.scenarios.studies.fragility.lognormal import LognormalFit
from housner.statistics.ensemble_stats import check_ci

__all__ = ["FitComparison", "compare_fits", "interval_disagreement"]


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
        The ratio interval excludes 1 or the difference interval excludes 0
        (:func:`interval_disagreement`, the studies' one verdict rule).
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


def interval_disagreement(ratio_low: float, ratio_high: float, diff_low: float, diff_high: float) -> tuple[bool, bool]:
    """The studies' verdict rule: whether the median-ratio interval excludes 1 and the beta-difference one 0.

    An engine disagrees with the reference (:attr:`FitComparison.disagree`) when either holds. NaN interval
    ends exclude nothing (comparisons with NaN are False), so missing intervals never claim a disagreement.

    Returns
    -------
    median_differs, beta_differs : bool
    """
    return bool(ratio_low > 1.0 or ratio_high < 1.0), bool(diff_low > 0.0 or diff_high < 0.0)


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
    oe, ve = outcomes(overturned_engine, valid_engine, "overturned_engine", "valid_engine")
    orf, vr = outcomes(overturned_reference, valid_reference, "overturned_reference", "valid_reference")
    if oe.shape != orf.shape:
        raise ValueError(
            f"`overturned_engine` {oe.shape} and `overturned_reference` {orf.shape} must pair the same motions "
            "and stripes"
        )
    x = check_im(im, oe.shape[1])
    n_boot, ci = check_n_boot(n_boot), check_ci(ci)
    (fe, fr), (eng, ref) = resampled_fits(x, [(oe, ve), (orf, vr)], n_boot, seed)
    ratio_low, ratio_high = percentile_interval(eng[:, 0] / ref[:, 0], ci)
    diff_low, diff_high = percentile_interval(eng[:, 1] - ref[:, 1], ci)
    disagree = any(interval_disagreement(ratio_low, ratio_high, diff_low, diff_high))
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
