"""The validation of outcome models: grouped folds, clustered paired comparisons, and a judgement that can fail.

The outcomes here are drawn from known probabilities (a logistic law of log PGA), so what each predictor deserves
is known: the truth itself passes, while a base-rate predictor, a model that a regression beats and a campaign of
shuffled outcomes never pass.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import special

from housner.scenarios.diagnosis.outcomes.outcome_scores import outcome_floor
from housner.scenarios.diagnosis.outcomes.outcome_validation import (
    BASELINES,
    baseline_oof,
    compare_log_loss,
    grouped_folds,
    judge_outcome_model,
    repeat_seeds,
)

N_GROUPS, PER_GROUP = 60, 8  # like the ASU tests: 56 records at 2-14 scalings, 490 tests


def _campaign(seed: int):
    """Records of ``N_GROUPS`` ground motions at ``PER_GROUP`` scalings each: PGA [m/s^2], PGV [m/s], group, and
    the true P(overturn), a logistic law of log PGA (the PGV is the PGA times a per-motion period)."""
    rng = np.random.default_rng(seed)
    groups = np.repeat(np.arange(N_GROUPS), PER_GROUP)
    scale = np.tile(np.geomspace(0.3, 3.0, PER_GROUP), N_GROUPS)
    pga = 2.0 * scale * rng.lognormal(0.0, 0.3, N_GROUPS)[groups]
    pgv = pga * rng.lognormal(np.log(0.1), 0.4, N_GROUPS)[groups]
    p_true = special.expit(3.0 * np.log(pga / 3.0))
    return pga, pgv, groups, p_true


def _baselines(pga, pgv, y, groups, seed):
    fold = grouped_folds(y, groups, 5, seed)
    return {name: baseline_oof(name, pga, pgv, y, fold) for name in BASELINES}


def test_grouped_folds_keep_each_ground_motion_whole_and_balance_the_outcomes():
    pga, _pgv, groups, p = _campaign(0)
    y = np.random.default_rng(1).random(p.size) < p
    fold = grouped_folds(y, groups, 5, seed=3)
    for g in np.unique(groups):
        assert np.unique(fold[groups == g]).size == 1  # a ground motion is never split between folds
    shares = [y[fold == f].mean() for f in range(5)]
    # 12 groups of 8 per fold: the share of overturns of a fold can only move in steps of whole groups
    assert max(shares) - min(shares) < 0.15
    assert np.array_equal(fold, grouped_folds(y, groups, 5, seed=3))  # seeded
    assert not np.array_equal(fold, grouped_folds(y, groups, 5, seed=4))
    assert repeat_seeds(7, 3) == (7, 8, 9)
    with pytest.raises(ValueError, match="folds"):
        grouped_folds(y[:16], groups[:16], 5, seed=0)  # two groups cannot make five folds


def test_the_paired_comparison_is_clustered_by_ground_motion():
    rng = np.random.default_rng(2)
    y = rng.random(100) < 0.4
    a, b = rng.uniform(0.2, 0.8, 100), rng.uniform(0.2, 0.8, 100)
    alone = compare_log_loss(a, b, y, np.arange(100))
    # every record played 4 times: the same evidence, not four times as much
    four = compare_log_loss(np.repeat(a, 4), np.repeat(b, 4), np.repeat(y, 4), np.repeat(np.arange(100), 4))
    assert four.advantage == pytest.approx(alone.advantage)
    assert four.se == pytest.approx(alone.se, rel=1e-9)  # an unclustered error would be half as large
    same = compare_log_loss(a, a, y, np.arange(100))
    assert same.advantage == 0.0 and same.p_better == 1.0 and same.p_worse == 1.0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_true_probabilities_pass_and_a_base_rate_predictor_does_not(seed):
    pga, pgv, groups, p_true = _campaign(seed)
    y = np.random.default_rng(100 + seed).random(p_true.size) < p_true
    base = _baselines(pga, pgv, y, groups, seed)
    truth = judge_outcome_model(p_true, base, y, groups, outcome_floor(p_true, y, seed=seed))
    assert truth.skill and truth.powered and not truth.beaten_by and not truth.misfit
    # the base rate as the model: calibrated on average (its floor cannot fail it), but a regression beats it
    rate = base["base_rate"]
    flat = judge_outcome_model(rate, base, y, groups, outcome_floor(rate, y, seed=seed))
    assert flat.misfit and not flat.skill and "logistic_pga" in flat.beaten_by


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_model_that_a_regression_beats_is_a_misfit(seed):
    pga, pgv, groups, p_true = _campaign(seed)
    y = np.random.default_rng(200 + seed).random(p_true.size) < p_true
    base = _baselines(pga, pgv, y, groups, seed)
    # right on the whole, wrong for each ground motion: a shift of the threshold per motion the PGA does not see
    shift = np.random.default_rng(300 + seed).normal(0.0, 0.8, N_GROUPS)[groups]
    p_wrong = special.expit(3.0 * np.log(pga / 3.0) + 3.0 * shift)
    judged = judge_outcome_model(p_wrong, base, y, groups, outcome_floor(p_wrong, y, seed=seed))
    assert judged.misfit and "logistic_pga" in judged.beaten_by


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_shuffled_outcomes_cannot_be_explained(seed):
    pga, pgv, groups, p_true = _campaign(seed)
    y = np.random.default_rng(400 + seed).random(p_true.size) < p_true
    y = np.random.default_rng(500 + seed).permutation(y)  # the outcomes no longer belong to their motions
    base = _baselines(pga, pgv, y, groups, seed)
    judged = judge_outcome_model(p_true, base, y, groups, outcome_floor(p_true, y, seed=seed))
    # the truth of other outcomes: a regression on the shuffled outcomes predicts them better, or none can
    assert judged.misfit or not judged.powered
