"""runs.spread.equivalent_amplitude: the factor on an ensemble that reaches another study's percentiles.

Checked against its definition by direct simulation, and by undoing a known
scaling of the ensemble (the analytic model is deterministic, so multiplying
the motions by 1/c and then by c gives back the same responses).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from shared import windowed_sines

from housner import Specimen
from housner.engines.analytic import HousnerEngine
from housner.scenarios.motions.build import build_motions
from housner.scenarios.runs.spread import equivalent_amplitude

SPEC = Specimen.bachmann2017()


def motions(n=16, seed=5):
    """Windowed sines at model scale, 1.5-4 g tan(alpha): most rock, a few overturn."""
    return windowed_sines(n, seed, freq=(1.5, 4.0), amp=(1.5, 4.0), scale=SPEC.uplift_acceleration, width=0.6)


def pct(ms, q, a=1.0):
    v = np.array(
        [r.theta_max_over_alpha for r in HousnerEngine().simulate_many(SPEC, [m.scaled(amplitude=a) for m in ms])]
    )
    return float(np.percentile(v, q, method="inverted_cdf"))


def test_the_factor_undoes_a_known_weakening_of_the_ensemble():
    """Weakening the motions by c = 1.02**13 (a whole number of grid steps) multiplies every factor by c.

    The weakened ensemble at a*c is the original at a (to rounding), so the grids line
    up and each percentile crosses its target at the matching point.
    """
    ms = motions()
    c = 1.02**13
    targets = {25: 0.4, 50: 0.7, 75: math.inf}
    orig = equivalent_amplitude(SPEC, ms, targets, n_boot=200).factors
    weak = equivalent_amplitude(SPEC, [m.scaled(amplitude=1.0 / c) for m in ms], targets, n_boot=200).factors
    for q in orig:
        assert math.isfinite(orig[q].factor)
        # 1e-9: the grid points are powers of 1.02 computed separately; the factors are equal to rounding
        assert weak[q].factor == pytest.approx(c * orig[q].factor, rel=1e-9), q
        # (the bootstrap intervals line up too where neither grid cuts them off at its lower end)
        for f in (orig[q], weak[q]):
            assert f.low <= f.factor <= f.high


def test_the_factor_is_the_first_grid_point_where_the_percentile_reaches_the_target():
    ms = motions()
    for q, target in ((25, 0.3), (75, math.inf)):
        r = equivalent_amplitude(SPEC, ms, {q: target}, n_boot=100)
        a = r.factors[float(q)].factor
        assert math.isfinite(a)
        # independently: the percentile at the factor reaches the target, one grid step below it does not
        assert pct(ms, q, a) >= target
        assert pct(ms, q, a / (1.0 + r.step)) < target
        assert a in r.grid


def test_a_target_out_of_reach_is_nan_not_an_error():
    weak = [m.scaled(amplitude=1e-3) for m in motions(4)]
    r = equivalent_amplitude(SPEC, weak, {50: 0.5}, max_factor=2.0, n_boot=50)
    assert math.isnan(r.factors[50.0].factor)


@pytest.mark.parametrize(
    "motions_, targets, says",
    [
        ([], {50: 0.5}, "`motions` is empty"),
        (None, {}, "`targets` is empty"),
        (None, {0: 0.5}, "percentile must lie in (0, 100)"),
        (None, {50: -1.0}, "must be positive or inf"),
        (None, {50: float("nan")}, "must be positive or inf"),
    ],
)
def test_bad_arguments_are_named(motions_, targets, says):
    with pytest.raises(ValueError, match=None) as e:
        equivalent_amplitude(SPEC, motions(2) if motions_ is None else motions_, targets)
    assert says in str(e.value)


def test_seed_spread_runs_through_the_runner_and_its_cache(tmp_path):
    """k ensembles of n motions: percentiles as computed directly with the analytic model, cached on the way."""
    from housner.scenarios.catalogue.scenario import load_scenario
    from housner.scenarios.runs.spread import ensemble_seeds, seed_spread

    scen = load_scenario("elcentro")
    got = seed_spread(scen, 2, n=6, cache_dir=tmp_path)
    assert list(got.seeds) == ensemble_seeds(2017, 2) and got.n_failed == 0
    for j, s in enumerate(got.seeds):
        ms, _ = build_motions(scen, 6, seed=s)
        v = np.array([r.theta_max_over_alpha for r in HousnerEngine().simulate_many(SPEC, ms)])
        for q in (25, 50, 75):
            assert got.percentiles[q][j] == float(np.percentile(v, q, method="inverted_cdf"))
    assert len(list(tmp_path.rglob("*.npz"))) == 12  # every record in the run cache
    assert seed_spread(scen, 2, n=6, cache_dir=tmp_path).percentiles == got.percentiles
