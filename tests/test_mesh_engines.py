"""The 3D scan-mesh engines (mujoco-3d, pybullet-3d): a rock's mesh as a free rigid body on a shaken table."""

from __future__ import annotations

import importlib.util
import math
import pickle
from pathlib import Path

import numpy as np
import pytest

from housner import GroundMotion
from housner.engines import ENGINES, engine_class, get_engine
from housner.engines.measures import free_rocking_quarter_period
from housner.scan import specimen_from_mesh

trimesh = pytest.importorskip("trimesh")

SP1 = Path("/work/shared/data/asu-granite/SP1.obj")
PACKAGES = {"mujoco-3d": "mujoco", "pybullet-3d": "pybullet"}
ENGINE_NAMES = [
    pytest.param(n, marks=pytest.mark.skipif(importlib.util.find_spec(p) is None, reason=f"{p} is not installed"))
    for n, p in PACKAGES.items()
]
G = 9.80665


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    """A 2B x depth x 2H = 0.2 x 0.4 x 1.0 m box standing on z = 0: the seed's proportions, slender enough to rock."""
    path = tmp_path_factory.mktemp("box") / "box.obj"
    mesh = trimesh.creation.box(extents=(0.2, 0.4, 1.0))
    mesh.apply_translation((0.0, 0.0, 0.5))
    mesh.export(path)
    return path


@pytest.mark.parametrize("name", ENGINE_NAMES)
def test_registered_as_mesh_engines(name):
    cls = engine_class(name)
    assert cls.mesh_engine is True and cls.name == name
    assert ENGINES[name].label == {"mujoco-3d": "MuJoCo 3D", "pybullet-3d": "PyBullet 3D"}[name]


@pytest.mark.parametrize("name", ENGINE_NAMES)
def test_box_first_impact_is_housners_quarter_period(name, box):
    """Released from rest at 0.5 alpha, the box falls back onto its base after Housner's quarter period."""
    spec = specimen_from_mesh(box).specimen()  # the rectangular block of the box: B = 0.1, H = 0.5
    theta0 = 0.5 * spec.alpha
    motion = GroundMotion.free_vibration(theta0, 0.6, dt=0.001)
    res = get_engine(name, mesh=str(box)).simulate(spec, motion)
    assert res.theta[0] == pytest.approx(theta0, rel=1e-9) and not res.overturned
    expected = free_rocking_quarter_period(spec, theta0)  # 0.347 s
    # 1 %: 3.5 ms, three samples; the sampled sign change is interpolated linearly (< 1 ms), the contacts
    # are stiff (MuJoCo's time constant is 2 ms, Bullet's rigid), and the measured error is 0.05-0.1 %.
    assert res.impact_times[0] == pytest.approx(expected, rel=0.01)


@pytest.mark.parametrize("name", ENGINE_NAMES)
def test_box_at_rest_stays_at_rest(name, box):
    spec = specimen_from_mesh(box).specimen()
    res = get_engine(name, mesh=str(box)).simulate(spec, GroundMotion(np.zeros(1001), 0.005))
    # 1e-3 alpha (0.2 mrad): a fifth of the suite's rocking threshold (ROCKING_TOL = 5e-3 alpha); measured
    # 0 (MuJoCo) and 5e-10 rad (PyBullet). 1 mm of creep of the COM in 5 s: Bullet's position correction.
    assert np.max(np.abs(res.theta)) < 1e-3 * spec.alpha
    assert res.uplift_time != res.uplift_time and not res.overturned  # NaN: it never rocked
    assert np.linalg.norm(res.info["com_shift_m"]) < 1e-3


@pytest.mark.parametrize("name", ENGINE_NAMES)
def test_a_shaken_box_rocks_the_same_every_run(name, box):
    """The world is rebuilt for every record, so the same record gives the same response, bit for bit."""
    spec = specimen_from_mesh(box).specimen()
    t = np.arange(0.0, 1.5, 0.005)
    motion = GroundMotion(-3.0 * G * math.tan(spec.alpha) * np.sin(2 * np.pi * 2.0 * t) * (t < 0.5), 0.005)
    eng = get_engine(name, mesh=str(box))
    first, second = eng.simulate(spec, motion), eng.simulate(spec, motion)
    assert first.theta_max > 0.05 * spec.alpha  # it rocked
    assert np.array_equal(first.theta, second.theta)


@pytest.mark.skipif(not SP1.exists(), reason="the ASU granite data folder is not here")
@pytest.mark.parametrize("name", ENGINE_NAMES)
def test_sp1_strong_long_pulse_overturns_and_a_weak_one_does_not(name):
    eng = get_engine(name, mesh=str(SP1))
    spec = specimen_from_mesh(SP1).specimen()
    # SP1's hull facet puts its +x pivot at alpha+ = 0.094 rad (uplift at g tan(alpha+) = 0.094 g).
    assert eng.rock.alpha(1.0) == pytest.approx(0.0939, abs=1e-3)

    def pulse(a_g: float) -> GroundMotion:  # a_g [g] held for 2 s after 0.1 s, then 1 s of quiet
        return GroundMotion(np.r_[np.zeros(20), np.full(400, a_g * G), np.zeros(200)], 0.005, name=f"{a_g} g")

    strong = eng.simulate(spec, pulse(-0.4))  # the table pushes -x: the rock leans onto its +x pivot
    assert strong.overturned and strong.theta[-1] == math.pi / 2 and strong.theta_max == math.pi / 2
    assert 0.1 < strong.overturn_time < 2.1 and strong.info["n_steps"] < 420 * strong.info["steps_per_sample"]
    weak = eng.simulate(spec, pulse(-0.05))  # half the uplift acceleration: the rock does not lift
    assert not weak.overturned and weak.theta_max < 0.01 * eng.rock.alpha(1.0)


@pytest.mark.parametrize("name", ENGINE_NAMES)
def test_settings_carry_the_mesh_content_and_pickle(name, box):
    eng = get_engine(name, mesh=str(box), azimuth=90.0, friction=0.6)
    s = eng.settings()
    assert s["mesh_sha1"] == __import__("hashlib").sha1(box.read_bytes()).hexdigest()
    assert s["azimuth"] == 90.0 and s["friction"] == 0.6 and s["contact"] == "hull" and s["density"] == 2700.0
    assert pickle.loads(pickle.dumps(eng)).settings() == s
    # azimuth 90: the box's 0.4 m depth is now along the shaking direction
    assert eng.rock.b(1.0) == pytest.approx(0.2) and eng.rock.mass == pytest.approx(0.08 * 2700.0)


@pytest.mark.parametrize(
    ("settings", "match"),
    [
        ({}, "setting `mesh` is required"),
        ({"mesh": "/nonexistent/rock.obj"}, "rock.obj.*no such file"),
        ({"mesh": "NOTAMESH"}, "cannot be read as a mesh|holds no triangle faces|not a mesh"),
        ({"mesh": "BOX", "frction": 0.7}, "frction.*friction"),
        ({"mesh": "BOX", "friction": -1.0}, "`friction` must lie in"),
        ({"mesh": "BOX", "azimuth": 400.0}, "`azimuth` must lie in"),
        ({"mesh": "BOX", "density": "heavy"}, "`density` must be a number"),
        ({"mesh": "BOX", "contact": "flat:0.006"}, "`contact` must be 'hull'"),
        ({"mesh": "BOX", "timestep": 0.0}, "`timestep` must lie in"),
    ],
)
@pytest.mark.parametrize("name", ENGINE_NAMES)
def test_bad_settings_are_one_line_errors(name, settings, match, box, tmp_path):
    junk = tmp_path / "junk.obj"
    junk.write_text("this is not a mesh\n")
    settings = {k: {"BOX": str(box), "NOTAMESH": str(junk)}.get(v, v) for k, v in settings.items()}
    with pytest.raises(ValueError, match=match) as err:
        get_engine(name, **settings)
    assert "\n" not in str(err.value)


@pytest.mark.skipif(importlib.util.find_spec("mujoco") is None, reason="mujoco is not installed")
def test_mujoco_contact_settings_are_checked(box):
    with pytest.raises(ValueError, match="`solref` must be 2 numbers"):
        get_engine("mujoco-3d", mesh=str(box), solref=(0.002,))
    with pytest.raises(ValueError, match="cone"):
        get_engine("mujoco-3d", mesh=str(box), cone="round")
