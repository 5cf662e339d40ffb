"""The dimensional argument of seed eq. 6: a block S times larger under the same motion
slowed by sqrt(S) rocks identically in t / sqrt(S).

theta/alpha = phi(alpha, omega_p/p, a_p/(g tan alpha)): with alpha fixed, p ~ 1/sqrt(R), so
scaling R by S and the motion's time axis by sqrt(S) (accelerations unchanged) keeps every
dimensionless group, hence theta_model(t) = theta_prototype(t sqrt(S)).
"""

import math

import numpy as np

from housner import GroundMotion, Specimen, simulate
from housner.scenarios.motions.records import RECORDS


def test_prototype_and_model_rock_alike():
    S = 10.0
    model = Specimen.bachmann2017()
    proto = model.scaled(S)  # 2H = 5 m, same alpha, p / sqrt(10)
    assert math.isclose(proto.height, 5.0)
    # A 10 s window of the El Centro record at prototype scale, amplified so the 5 m block rocks.
    rec = next(iter(RECORDS.values()))()
    m_proto = GroundMotion(rec.acc[:1000] * 1.5, rec.dt, "elcentro x1.5")
    m_model = m_proto.to_model_scale(S)
    r_proto = simulate(proto, m_proto)
    r_model = simulate(model, m_model)
    assert r_proto.theta_max > 0.3 * proto.alpha  # it really rocks
    # Same grid in dimensionless time: sample k is t_model = t_proto / sqrt(S).
    np.testing.assert_allclose(r_model.t, r_proto.t / math.sqrt(S), rtol=1e-12, atol=1e-15)
    # The dimensionless arithmetic is identical up to rounding (p h is the same in both runs);
    # 1e-9 alpha leaves room for rounding growth over a few impacts.
    np.testing.assert_allclose(r_model.theta, r_proto.theta, atol=1e-9 * model.alpha, rtol=0)
    np.testing.assert_allclose(r_model.impact_times * math.sqrt(S), r_proto.impact_times, rtol=1e-9)
    assert r_model.overturned == r_proto.overturned
