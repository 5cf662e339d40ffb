"""Specimen: derived Housner parameters and input validation."""

import math
import warnings

import pytest

from housner import G, Specimen


def test_seed_specimen_matches_table_1():
    s = Specimen.bachmann2017()
    # Table 1 of the seed paper gives r_Housner = 0.9465 from p = 4.8883 1/s (4 digits).
    assert round(s.r_housner, 4) == 0.9465
    assert s.tan_alpha == pytest.approx(0.15, rel=1e-12)
    assert s.R == pytest.approx(math.hypot(0.25, 0.0375), rel=1e-12)
    assert s.p == pytest.approx(4.8883, rel=1e-12)
    # I0 = m g R / p^2 (definition of p, seed eq. 3)
    assert s.I0 == pytest.approx(3.94 * G * s.R / 4.8883**2, rel=1e-12)
    assert s.uplift_acceleration == pytest.approx(0.15 * G, rel=1e-12)


def test_solid_block_default_inertia():
    s = Specimen(height=0.5, width=0.075, depth=0.4, mass=3.94)
    # Solid rectangle: I0 = 4/3 m R^2, so p = sqrt(3 g / (4 R)) (seed, after eq. 3): 5.39 1/s.
    assert s.I0 == pytest.approx(4 / 3 * 3.94 * s.R**2, rel=1e-12)
    assert s.p == pytest.approx(math.sqrt(3 * G / (4 * s.R)), rel=1e-12)
    assert round(s.p, 2) == 5.39
    # Closed form for a solid block: r = (1 - 3/2 sin^2 alpha)^2
    assert s.r_housner == pytest.approx((1 - 1.5 * math.sin(s.alpha) ** 2) ** 2, rel=1e-12)


def test_p_and_I0_consistent_and_inconsistent():
    s = Specimen.bachmann2017()
    ok = Specimen(height=0.5, width=0.075, depth=0.4, mass=3.94, p=4.8883, I0=s.I0)
    assert ok.p == pytest.approx(4.8883)
    with pytest.raises(ValueError, match=r"`p`.*`I0`.*disagree"):
        Specimen(height=0.5, width=0.075, depth=0.4, mass=3.94, p=4.8883, I0=1.1 * s.I0)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"height": 0.0}, "height"),
        ({"height": -1.0}, "height"),
        ({"width": float("nan")}, "width"),
        ({"mass": -3.0}, "mass"),
        ({"depth": 0}, "depth"),
        ({"p": float("inf")}, "p"),
        ({"p": 100.0}, "p"),  # p > sqrt(g/R) means I0 < m R^2: impossible
        ({"I0": -1.0}, "I0"),
        ({"height": "tall"}, "height"),
    ],
)
def test_invalid_input_names_the_argument(kwargs, name):
    base = dict(height=0.5, width=0.075, depth=0.4, mass=3.94)
    base.update(kwargs)
    with pytest.raises(ValueError, match=f"`{name}`"):
        Specimen(**base)


def test_squat_block_warns_with_alpha():
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        s = Specimen(height=0.1, width=0.2, depth=0.1, mass=1.0)
    assert s.alpha == pytest.approx(math.atan(2.0))
    assert any("alpha = 1.1071 rad" in str(x.message) for x in w)


def test_scaled_keeps_alpha_and_r_and_scales_p():
    s = Specimen.bachmann2017()
    big = s.scaled(10.0)
    assert big.alpha == pytest.approx(s.alpha, rel=1e-12)
    assert big.r_housner == pytest.approx(s.r_housner, rel=1e-12)
    assert big.p == pytest.approx(s.p / math.sqrt(10.0), rel=1e-12)
    assert s.with_p(5.0).p == pytest.approx(5.0)
