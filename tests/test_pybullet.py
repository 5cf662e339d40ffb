"""PyBullet engine: the URDF model, its p and r against Housner, forced response against the analytic model.

Every comparison is against a closed form (uplift threshold g tan alpha, exact
free-rocking quarter period, Housner's r, the parallel-axis inertia) or against
the independent analytic solver ``housner.model.simulate``.
"""

from __future__ import annotations

import math
import pickle
import re
import xml.etree.ElementTree as ET

import numpy as np
import pybullet as pb
import pytest

from housner import G, GroundMotion, Specimen
from housner.engines._planar import OVERTURN_ANGLE, ROCKING_TOL
from housner.engines.pybullet_engine import PybulletEngine
from housner.engines.urdf import ETH_SPECIMEN_PATH, JOINTS, urdf_from_specimen, write_urdf
from housner.errors import EngineError
from housner.free_vibration.calibration import free_vibration_peaks
from housner.free_vibration.closed_forms import energy_ratios, half_cycle_integral
from housner.model import simulate as housner_simulate
from housner.pulse_response.pulses import one_sine

SPEC = Specimen.bachmann2017()
AMPLITUDES = (0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9)

#: Accepted |r_engine / r_housner - 1| at each amplitude: the brief's 0.5 %,
#: half the 0.7 % gap between the seed's calibrated and Housner's r (Table 1).
R_RTOL = 0.005


@pytest.fixture(scope="module")
def engine():
    eng = PybulletEngine()
    yield eng
    eng.close()


def _release(a: float, dt: float = 0.001) -> GroundMotion:
    """Free vibration from a * alpha, long enough for the release peak, one impact and the next peak."""
    th0 = a * SPEC.alpha
    tq = half_cycle_integral(th0, SPEC.alpha) / SPEC.p
    return GroundMotion.free_vibration(th0, 2.3 * tq + 0.05, dt=dt)


@pytest.fixture(scope="module")
def free_vibrations(engine):
    """Responses to releases from each amplitude with the default settings."""
    return {a: engine.simulate(SPEC, _release(a)) for a in AMPLITUDES}


def _first_ratio(res) -> float:
    peaks = free_vibration_peaks(res.t, res.theta, SPEC.alpha, noise=0.0)
    return float(energy_ratios(peaks, SPEC.alpha)[0])


# ----------------------------------------------------------------------------
# the URDF
def test_shipped_urdf_matches_generator():
    assert ETH_SPECIMEN_PATH.read_text(encoding="utf-8") == urdf_from_specimen(SPEC), (
        "engines/models/eth_specimen.urdf is stale: run housner.engines.urdf.write_eth_specimen()"
    )


def test_urdf_numbers_follow_from_specimen():
    root = ET.fromstring(urdf_from_specimen(SPEC))
    block = root.find("link[@name='block']")
    assert float(block.find("inertial/mass").get("value")) == SPEC.mass
    iyy = float(block.find("inertial/inertia").get("iyy"))
    assert iyy == pytest.approx(SPEC.inertia - SPEC.mass * SPEC.R**2, rel=1e-15)
    assert iyy == SPEC.centroidal_inertia
    outer, inner = [], []
    for col in block.findall("collision"):
        x, _, z = map(float, col.find("origin").get("xyz").split())
        _, beta, _ = map(float, col.find("origin").get("rpy").split())
        wx, wy, wz = map(float, col.find("geometry/box").get("size").split())
        assert (wx, wy) == (0.002, SPEC.depth)
        # bottom corners of the strip's x-z section, rotated by beta about +y (x, z) -> (x c + z s, -x s + z c)
        c, s = math.cos(beta), math.sin(beta)
        corners = [(x + u * c - wz / 2 * s, z - u * s - wz / 2 * c) for u in (-wx / 2, wx / 2)]
        corners.sort(key=lambda p: abs(p[0]))
        inner.append(corners[0])
        outer.append(corners[1])
    # the outer bottom edges are the pivots (+-B, -H); the inner ones are raised by w sin(bevel), 10 um
    assert sorted(p[0] for p in outer) == pytest.approx([-SPEC.B, SPEC.B], abs=1e-15)
    assert [p[1] for p in outer] == pytest.approx([-SPEC.H] * 2, abs=1e-15)
    assert [p[1] + SPEC.H for p in inner] == pytest.approx([0.002 * math.sin(0.005)] * 2, rel=1e-9)
    assert [j.get("name") for j in root.findall("joint")] == list(JOINTS)
    assert root.find("joint[@name='x']/origin").get("xyz") == f"0 0 {SPEC.H!r}"


def test_urdf_arguments_are_checked(tmp_path):
    with pytest.raises(ValueError, match="strip_width"):
        urdf_from_specimen(SPEC, strip_width=SPEC.B)
    with pytest.raises(ValueError, match="carriage_mass"):
        urdf_from_specimen(SPEC, carriage_mass=0.01)
    with pytest.raises(ValueError, match="strip_height"):
        urdf_from_specimen(SPEC, strip_height=-1.0)
    with pytest.raises(TypeError, match="specimen"):
        urdf_from_specimen("block")
    path = write_urdf(SPEC.scaled(2.0), tmp_path / "sub" / "big.urdf")
    assert path.read_text(encoding="utf-8") == urdf_from_specimen(SPEC.scaled(2.0))


def test_urdf_loads_without_warnings(capfd):
    cid = pb.connect(pb.DIRECT)
    try:
        capfd.readouterr()
        body = pb.loadURDF(
            str(ETH_SPECIMEN_PATH), useFixedBase=True, flags=pb.URDF_USE_INERTIA_FROM_FILE, physicsClientId=cid
        )
        out = capfd.readouterr()
        assert "warn" not in (out.out + out.err).lower()
        assert pb.getNumJoints(body, physicsClientId=cid) == 3
        info = pb.getDynamicsInfo(body, 2, physicsClientId=cid)
        assert info[0] == SPEC.mass
        assert info[2][1] == pytest.approx(SPEC.centroidal_inertia, rel=1e-12)  # not recomputed from the boxes
    finally:
        pb.disconnect(physicsClientId=cid)


@pytest.mark.parametrize("theta", [0.0, 0.5, -0.9])
def test_mass_matrix_gives_pivot_inertia(engine, theta):
    """PyBullet's own mass matrix, reduced to rotation about the pivot, is I0 (carriages included)."""
    cid, body = engine.build(SPEC, 2e-4)
    th = theta * SPEC.alpha
    s = 1.0 if th >= 0 else -1.0
    # centre of mass on a circle about the pivot (s B, 0): x = s B - s B cos + H sin, z = s B sin + H cos
    q = [s * SPEC.B * (1 - math.cos(th)) + SPEC.H * math.sin(th), s * SPEC.B * math.sin(th) + SPEC.H * math.cos(th)]
    M = np.array(pb.calculateMassMatrix(body, [q[0], q[1] - SPEC.H, th], physicsClientId=cid))
    J = np.array(
        [s * SPEC.B * math.sin(th) + SPEC.H * math.cos(th), s * SPEC.B * math.cos(th) - SPEC.H * math.sin(th), 1]
    )
    # The 2e-6 kg of carriages add at most 2e-6 * R^2 / I0 = 3e-7 relative.
    assert J @ M @ J == pytest.approx(SPEC.inertia, rel=1e-6)


# ----------------------------------------------------------------------------
# p, r and the static threshold against closed forms
@pytest.mark.parametrize("a", AMPLITUDES)
def test_quarter_period_gives_p(free_vibrations, a):
    """Release to first impact equals the exact quarter period F(theta0, alpha) / p of Housner's equation."""
    res = free_vibrations[a]
    exact = half_cycle_integral(a * SPEC.alpha, SPEC.alpha) / SPEC.p
    # The brief's 1 %; measured <= 0.07 %: the block sinks ~nm into the ground, and the impact time is read
    # off a 1 ms grid by linear interpolation (error << 1 ms^2 curvature terms).
    assert res.impact_times[0] == pytest.approx(exact, rel=0.01)
    p_engine = half_cycle_integral(a * SPEC.alpha, SPEC.alpha) / res.impact_times[0]
    assert p_engine == pytest.approx(SPEC.p, rel=0.01)


@pytest.mark.parametrize("a", AMPLITUDES)
def test_r_matches_housner(free_vibrations, a):
    """First-impact energy ratio (seed eq. 8) within 0.5 % of Housner's r at the default settings."""
    r = _first_ratio(free_vibrations[a])
    assert abs(r / SPEC.r_housner - 1.0) <= R_RTOL, f"r = {r:.5f} at {a} alpha, Housner {SPEC.r_housner:.5f}"


@pytest.mark.slow
def test_r_matches_housner_fine_sweep():
    """On a 0.01 alpha grid the error scatters with where in a step the impact falls: worst 0.31 %, mean -0.05 %."""
    eng = PybulletEngine()
    amps = np.round(np.arange(0.2, 0.9001, 0.01), 2)
    err = np.array([_first_ratio(eng.simulate(SPEC, _release(a))) / SPEC.r_housner - 1.0 for a in amps])
    assert np.max(np.abs(err)) <= R_RTOL
    assert abs(np.mean(err)) <= 0.2 * R_RTOL  # no bias to speak of: the errors scatter about zero


@pytest.mark.parametrize(("factor", "rocks"), [(-0.98, False), (-1.02, True), (0.98, False), (1.02, True)])
def test_uplift_threshold_and_sign(engine, factor, rocks):
    """A constant ground acceleration rocks the block only beyond g tan(alpha); below -g tan(alpha) theta > 0.

    +-2 % brackets the threshold g B / H: it checks that the pivots are the strips' outer edges at +-B
    (a pivot 1.5 mm inside, at the strip centre, would move the threshold by 2.7 %).
    """
    acc = np.full(151, factor * G * SPEC.tan_alpha)
    acc[0] = 0.0
    res = engine.simulate(SPEC, GroundMotion(acc, 0.002))
    if rocks:
        # Just past the threshold theta grows slowly (~ cosh(p t) - 1): 0.026 alpha after 0.3 s, in proportion
        # to the 2 % excess over g tan alpha, so 3 % here is a 0.06 % shift of the threshold (measured ~1.5 %).
        ref = housner_simulate(SPEC, GroundMotion(acc, 0.002))
        assert res.theta_max == pytest.approx(ref.theta_max, rel=0.03)
        assert np.sign(res.theta[-1]) == -np.sign(factor) == np.sign(ref.theta[-1])
        assert 0.0 <= res.uplift_time <= 0.01
    else:
        assert res.theta_max < ROCKING_TOL * SPEC.alpha
        assert math.isnan(res.uplift_time) and res.n_impacts == 0


def test_block_does_not_fall_asleep(engine):
    """Bullet deactivates bodies at rest after 2 s; a later shaking must still rock the block."""
    acc = np.zeros(1601)
    acc[1500:] = -1.5 * G * SPEC.tan_alpha
    res = engine.simulate(SPEC, GroundMotion(acc, 0.002))
    assert res.theta[-1] > 0.05 * SPEC.alpha
    assert 2.99 <= res.uplift_time <= 3.01


# ----------------------------------------------------------------------------
# forced response against the analytic model
PULSES = [(8.0, 1.5), (8.0, 3.0), (4.0, 1.5)]  # (omega_p / p, a_p / (g tan alpha))


@pytest.mark.parametrize("sign", [1.0, -1.0], ids=["theta+", "theta-"])
@pytest.mark.parametrize(("w_ratio", "a_ratio"), PULSES)
def test_one_sine_pulse_matches_analytic(engine, w_ratio, a_ratio, sign):
    """The d'Alembert force reproduces the analytic model's one-sine response: theta_max within 0.5 %.

    Measured 0.1-0.35 %, on either pivot. The pulses rock the block to 0.1-0.5 alpha with 3-10 impacts;
    near-overturning pulses are left out on purpose: there a 0.2 % change of r alone moves theta_max by 1.6 %.
    """
    omega = w_ratio * SPEC.p
    tp = 2 * math.pi / omega
    motion = one_sine(-sign * a_ratio * G * SPEC.tan_alpha, omega, dt=tp / 100, duration=tp + 1.0)
    ref = housner_simulate(SPEC, motion)
    res = engine.simulate(SPEC, motion)
    assert not ref.overturned and not res.overturned
    assert res.theta_max == pytest.approx(ref.theta_max, rel=0.005)
    assert res.n_impacts == ref.n_impacts
    # Same first impact: the step (2e-4 s) and the sampling (tp / 100) bound the timing error.
    assert res.impact_times[0] == pytest.approx(ref.impact_times[0], abs=2 * motion.dt)
    # Uplift is dated from theta's growth (extrapolated back from 1e-5 and 8e-5 alpha): measured 0.3-0.6 ms early.
    assert res.uplift_time == pytest.approx(ref.uplift_time, abs=motion.dt)
    assert res.info["steps_per_sample"] * res.info["step"] == pytest.approx(motion.dt, rel=1e-12)


def test_no_sliding_under_strong_pulse(engine):
    """0.74 g pulse (5 g tan alpha), friction 1.5: the pivots stay put while the block rocks to 0.5 alpha.

    10 um is a tenth of the seed camera's 0.1 mm accuracy; measured ~1e-7 m.
    """
    omega = 8.0 * SPEC.p
    tp = 2 * math.pi / omega
    motion = one_sine(-5.0 * G * SPEC.tan_alpha, omega, dt=tp / 100, duration=tp + 1.0)
    res = engine.simulate(SPEC, motion)
    assert res.theta_max > 0.4 * SPEC.alpha and not res.overturned
    assert res.info["max_pivot_slip_m"] < 1e-5


def test_overturn(engine):
    """A long strong push topples the block: theta held at +pi/2 afterwards, theta_max = pi/2."""
    acc = np.zeros(801)
    acc[1:200] = -3.0 * G * SPEC.tan_alpha
    res = engine.simulate(SPEC, GroundMotion(acc, 0.002, name="push"))
    assert res.overturned and res.theta_max == OVERTURN_ANGLE
    k = int(np.searchsorted(res.t, res.overturn_time))
    assert np.all(res.theta[k:] == OVERTURN_ANGLE) and np.all(res.theta_dot[k:] == 0.0)
    assert np.all(np.abs(res.theta[: k - 1]) < OVERTURN_ANGLE)
    assert res.theta_max_over_alpha == math.inf


def test_mirror_symmetry(engine):
    """Mirroring the ground motion mirrors the response (the model is symmetric about x = 0)."""
    omega = 8.0 * SPEC.p
    tp = 2 * math.pi / omega
    motion = one_sine(-3.0 * G * SPEC.tan_alpha, omega, dt=tp / 100, duration=tp + 0.6)
    mirrored = GroundMotion(-motion.acc, motion.dt)
    a, b = engine.simulate(SPEC, motion), engine.simulate(SPEC, mirrored)
    # The sequential-impulse solver meets the two strips in a fixed order; with only the strips' outer edges
    # touching (the 5 mrad bevel) the contact forces are determinate and the mirror images differ by ~1e-3 alpha
    # (up to 6e-2 alpha with flat strips, whose two contact lines per strip the solver converges on slowly).
    np.testing.assert_allclose(a.theta, -b.theta, rtol=0, atol=5e-3 * SPEC.alpha)
    assert a.theta_max == pytest.approx(b.theta_max, rel=1e-3)


# ----------------------------------------------------------------------------
# engine contract
def test_determinism_and_client_reuse(engine):
    """Repeated runs in one client, a run of something else in between, a new instance, a pickled copy: same bits."""
    motion = _release(0.6, dt=0.002)
    first = engine.simulate(SPEC, motion)
    engine.simulate(SPEC.scaled(2.0), _release(0.3))
    again = engine.simulate(SPEC, motion)
    fresh = PybulletEngine().simulate(SPEC, motion)
    copied = pickle.loads(pickle.dumps(engine)).simulate(SPEC, motion)
    for other in (again, fresh, copied):
        np.testing.assert_array_equal(first.theta, other.theta)
        np.testing.assert_array_equal(first.impact_times, other.impact_times)


def test_response_contract(free_vibrations):
    res = free_vibrations[0.5]
    assert res.engine == "pybullet"
    assert res.t.shape == res.theta.shape == res.theta_dot.shape
    assert res.theta[0] == 0.5 * SPEC.alpha and res.uplift_time == 0.0
    assert res.alpha == SPEC.alpha and not res.overturned and math.isnan(res.overturn_time)
    assert res.theta_max == pytest.approx(0.5 * SPEC.alpha, rel=1e-9)
    assert res.info["settings"] == PybulletEngine.DEFAULTS
    assert res.info["n_steps"] == (res.t.size - 1) * res.info["steps_per_sample"]
    # impacts alternate pivots: theta changes sign across each impact
    for ti in res.impact_times:
        k = int(np.searchsorted(res.t, ti))
        assert np.sign(res.theta[k - 1]) == -np.sign(res.theta[k])


def test_negative_release_and_initial_velocity(engine):
    """theta0 < 0 rocks on the -x pivot (mirror of theta0 > 0); a pure velocity kick from rest rocks too."""
    a = engine.simulate(SPEC, _release(0.4, dt=0.002))
    m = _release(0.4, dt=0.002)
    b = engine.simulate(SPEC, GroundMotion(m.acc, m.dt, theta0=-m.theta0))
    np.testing.assert_allclose(a.theta, -b.theta, rtol=0, atol=1e-4 * SPEC.alpha)
    # From rest with theta_dot0: energy integral theta_dot0^2 / (2 p^2) = cos(alpha - th_pk) - cos(alpha).
    th_pk = 0.5 * SPEC.alpha
    om = SPEC.p * math.sqrt(2 * (math.cos(SPEC.alpha - th_pk) - math.cos(SPEC.alpha)))
    kick = engine.simulate(SPEC, GroundMotion(np.zeros(301), 0.001, theta_dot0=om))
    # Measured -0.17 %: Bullet's semi-implicit Euler is first order (-0.28, -0.17, -0.08 % at 0.4, 0.2, 0.1 ms
    # steps); the peak falling between 1 ms samples adds ~1e-6. 0.3 % leaves room for the step's phase.
    assert kick.theta_max == pytest.approx(th_pk, rel=0.003)


def test_settings_are_validated():
    with pytest.raises(ValueError, match="timestep"):
        PybulletEngine(timestep=0.0)
    with pytest.raises(ValueError, match="did you mean 'timestep'"):
        PybulletEngine(time_step=1e-4)
    with pytest.raises(ValueError, match="contact_damping"):
        PybulletEngine(contact_stiffness=1e7)
    with pytest.raises(ValueError, match="solver_iterations"):
        PybulletEngine(solver_iterations=2.5)
    with pytest.raises(ValueError, match="restitution"):
        PybulletEngine(restitution=1.5)
    eng = PybulletEngine(timestep=1e-4)
    assert eng.settings()["timestep"] == 1e-4 and "timestep=0.0001" in repr(eng)
    assert re.fullmatch(r"\d+\.\d+\.\d+.*", eng.version())


def test_runaway_raises_engine_error():
    """Without friction a sustained push slides the block away: the engine stops with a named error."""
    eng = PybulletEngine(lateral_friction=0.0)
    acc = np.full(2501, -0.9 * G * SPEC.tan_alpha)
    with pytest.raises(EngineError, match="'slide'"):
        eng.simulate(SPEC, GroundMotion(acc, 0.002, name="slide"))


def test_tuning_candidates():
    near = PybulletEngine.tuning_candidates(SPEC, SPEC.r_housner)
    far = PybulletEngine.tuning_candidates(SPEC, 0.9532)
    assert near == far[: len(near)] and len(far) > len(near)
    steps = [c["timestep"] for c in near]
    assert steps == sorted(steps, reverse=True)  # cheap to expensive
    assert any("contact_stiffness" in c for c in far)
    for c in far:
        PybulletEngine(**c)  # every candidate is a valid setting
    big = PybulletEngine.tuning_candidates(SPEC.scaled(4.0), SPEC.r_housner)
    assert big[0]["timestep"] == pytest.approx(2 * near[0]["timestep"], rel=0.01)  # steps scale with 1/p
    with pytest.raises(ValueError, match="target_r"):
        PybulletEngine.tuning_candidates(SPEC, 1.5)


def test_kinematic_ground_does_not_transmit_shaking(engine):
    """Moving the plane kinematically (teleporting it each step) barely moves the block; the d'Alembert force does.

    The contact solver sees the plane's positions but no velocity, so friction never drags the block along.
    """
    acc = -2.0 * G * SPEC.tan_alpha  # twice the uplift threshold, held 0.3 s
    h, n = 2e-4, 1500
    dalembert = engine.simulate(SPEC, GroundMotion(np.r_[0.0, np.full(n // 10, acc)], 10 * h))
    cid, body = engine.build(SPEC, h)
    plane = 0  # the first body created by build()
    theta = []
    for i in range(1, n + 1):
        x = 0.5 * acc * (i * h) ** 2
        pb.resetBasePositionAndOrientation(plane, [x, 0, 0], [0, 0, 0, 1], physicsClientId=cid)
        pb.stepSimulation(physicsClientId=cid)
        theta.append(pb.getJointState(body, 2, physicsClientId=cid)[0])
    assert dalembert.theta_max > 0.5 * SPEC.alpha
    assert max(abs(t) for t in theta) < 0.05 * dalembert.theta_max
