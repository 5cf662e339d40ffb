"""Cross-engine agreement with the analytic model (issue: engines, item 7).

On pulses (not chaotic) every engine must follow the analytic model record by
record: theta_max within 3 % where neither overturns, and the same overturn
verdict. Under long random records rocking is chaotic, so the verdict rests on
distributions: KS distance <= 0.15 and overturn fractions within 0.08 on the
100-motion El Centro ensemble (slow).
"""

import math

import numpy as np
import pytest

from engines.base import get_engine
from housner import Specimen, simulate
from reports.assertions import assert_cdf_agreement
from scenarios import pulses

SPEC = Specimen.bachmann2017()
ENGINES = ["mujoco", "pybullet"]

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
    from scenarios.runner import run_scenario

    out = tmp_path_factory.mktemp("elcentro")
    run = run_scenario("elcentro", engines=["housner", engine], out=out, progress=False)
    report = assert_cdf_agreement(run.results, engine=engine, reference="housner", ks_max=0.15, overturn_tol=0.08)
    print(report)
    a = run.results
    assert np.isfinite(a[a.engine == engine].wall_s).all()
