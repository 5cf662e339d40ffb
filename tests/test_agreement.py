"""Cross-engine agreement with the analytic model (issue: engines, item 7).

On pulses (not chaotic) every engine must follow the analytic model record by
record: theta_max within 3 % where neither overturns, and the same overturn
verdict. Under long random records rocking is chaotic, so the verdict rests on
distributions on the 100-motion El Centro ensemble (slow): a KS distance below
the two-sample 1 % critical value, overturn fractions within 0.08, and no
record-by-record bias (sign test).
"""

import math

import numpy as np
import pytest
from shared import OTHER_ENGINES, installed_engines

from housner import Specimen, simulate
from housner.engines.base import get_engine
from housner.pulse_response import pulses
from housner.reports.assertions.runs import assert_cdf_agreement

SPEC = Specimen.bachmann2017()
ENGINES = OTHER_ENGINES

# Symmetric Ricker pulses on both sides of the block, spanning small rocking,
# large rocking and overturn: (omega_p / p, a_p / (g tan alpha)).
PULSES = [(2.0, 1.3), (2.0, -1.3), (4.0, 2.5), (4.0, -3.0), (6.0, 5.0), (2.0, 2.5)]


def pulse_motions():
    out = []
    for w, a in PULSES:
        m = pulses.ricker(a * SPEC.uplift_acceleration, w * SPEC.p, dt=0.002, p=SPEC.p)
        out.append(m.with_duration(min(m.duration, 4.0)))
    return out


@pytest.fixture(scope="module")
def reference():
    return [simulate(SPEC, m) for m in pulse_motions()]


@pytest.mark.parametrize("engine", ENGINES)
def test_pulse_responses_agree(engine, reference):
    eng = get_engine(engine)
    rows = []
    for m, ref in zip(pulse_motions(), reference, strict=True):
        got = eng.simulate(SPEC, m)
        rows.append((m.name, ref.theta_max_over_alpha, got.theta_max_over_alpha))
        assert got.overturned == ref.overturned, f"{engine} {m.name}: overturn verdict differs"
        if not ref.overturned:
            # 3 % is the issue's record-by-record tolerance on non-chaotic input; the engines'
            # own tests show ~0.5 % on single pulses, the rest is margin for contact compliance.
            assert math.isclose(got.theta_max, ref.theta_max, rel_tol=0.03), rows[-1]
    # The set really exercises rocking without overturn and overturn.
    assert any(math.isinf(r[1]) for r in rows) and any(0.1 < r[1] < 1 for r in rows)


@pytest.mark.slow
@pytest.mark.parametrize("engine", ENGINES)
def test_elcentro_distributions_agree(engine, tmp_path_factory):
    from scipy.stats import binomtest

    from housner.scenarios.runs.run import run_scenario

    out = tmp_path_factory.mktemp("elcentro")
    run = run_scenario("elcentro", engines=["housner", engine], out=out, progress=False)
    a = run.results
    n = int((a.engine == engine).sum())
    # Chaos decorrelates the engines record by record (see docs/results.md), so their samples behave
    # as independent draws of one distribution: the two-sample KS distance of such draws exceeds
    # 1.63 sqrt(2/n) (0.23 at n = 100) 1 % of the time. The old fixed 0.15 is exceeded 21 % of the
    # time by identical distributions (PyBullet on the matched ensemble: 0.18, p = 0.08).
    ks_max = 1.628 * math.sqrt(2.0 / n)
    report = assert_cdf_agreement(run.results, engine=engine, reference="housner", ks_max=ks_max, overturn_tol=0.08)
    print(report)
    assert np.isfinite(a[a.engine == engine].wall_s).all()
    # No bias record by record: the engine lies below the reference about as often as above
    # (sign test over the records where neither overturns). Both checks guard against gross
    # errors only: the analytic model with r 2 % low gives KS 0.15 and a sign-test p of 0.010,
    # 2 % high 0.25; r itself is held to 0.3 % by the free-rocking tests of each engine.
    h = a[a.engine == "housner"].set_index("motion_id").theta_max_over_alpha
    x = a[a.engine == engine].set_index("motion_id").theta_max_over_alpha
    both = np.isfinite(h) & np.isfinite(x) & (x != h)
    below = int((x[both] < h[both]).sum())
    p = binomtest(below, int(both.sum())).pvalue
    assert p >= 0.01, f"{engine} below the analytic model on {below} of {int(both.sum())} records (p = {p:.2g})"


@pytest.fixture(scope="module")
def strong_run(tmp_path_factory):
    """elcentro-strong (100 matched motions x 1.6, 42 overturn in the analytic model) on every installed engine."""
    from housner.scenarios.runs.run import run_scenario

    names = ["housner", *installed_engines()]
    return run_scenario("elcentro-strong", engines=names, out=tmp_path_factory.mktemp("strong"), progress=False)


@pytest.mark.slow
@pytest.mark.parametrize("engine", ENGINES)
def test_strong_ensemble_distributions_agree(engine, strong_run):
    """Where overturning matters (a third or more overturn): KS <= 0.15 and |dP[overturn]| <= 0.08 (the issue's).

    On this ensemble the engines stay correlated with the analytic model (the same overturn verdict
    on 85-97 % of the records), so the fixed 0.15 is not the coin toss it is on elcentro.
    """
    run = strong_run
    p_ref = float(run.results[run.results.engine == "housner"].overturned.mean())
    assert p_ref >= 1 / 3, f"the strong ensemble overturns only {p_ref:.0%} in the analytic model"
    report = assert_cdf_agreement(run.results, engine=engine, reference="housner", ks_max=0.15, overturn_tol=0.08)
    print(report)
    assert run.failures.empty, run.failures.to_string()
