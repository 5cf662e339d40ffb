"""MuJoCo engine: the generated model, its physics against closed forms and the analytic model, speed-neutral checks."""

from __future__ import annotations

import math
import pickle

import mujoco
import numpy as np
import pytest
from shared import SoftGroundMujoco

from housner import EngineError, GroundMotion, Specimen
from housner.effects import make_effect
from housner.engines import get_engine
from housner.engines.mjcf import (
    ETH_SPECIMEN_PATH,
    MJCF_DEFAULTS,
    block_inertia,
    initial_qpos,
    mjcf_from_specimen,
    write_mjcf,
)
from housner.engines.mujoco_engine import MujocoEngine, initial_qvel
from housner.engines.tuning import (
    DECAY_IMPACTS,
    DECAY_RTOL,
    DECAY_START,
    DEFAULT_AMPLITUDES,
    SMALL_AMPLITUDES,
    decay_motion,
    decay_peaks,
    first_impact_ratio,
    first_peak,
    free_rocking_quarter_period,
    free_vibration_motions,
    half_cycle_peaks,
)
from housner.model import simulate as housner_simulate
from housner.units import G

SEED = Specimen.bachmann2017()


@pytest.fixture(scope="module")
def engine() -> MujocoEngine:
    return MujocoEngine()


def _one_sine(specimen: Specimen, w_ratio: float, a_ratio: float, tail: float, dt: float = 0.001) -> GroundMotion:
    """ug'' = a_p sin(omega_p t) for one period, omega_p = w_ratio p, a_p = a_ratio g tan(alpha); then ``tail`` [s]."""
    omega = w_ratio * specimen.p
    tp = 2 * math.pi / omega
    t = np.arange(int(math.ceil((tp + tail) / dt)) + 1) * dt
    acc = np.where(t <= tp, a_ratio * specimen.uplift_acceleration * np.sin(omega * t), 0.0)
    return GroundMotion(acc, dt, name=f"one-sine {w_ratio}p {a_ratio}g tan(alpha)")


# --------------------------------------------------------------------------- the model file
def _warnings(data: mujoco.MjData) -> dict:
    return {mujoco.mjtWarning(i).name: int(data.warning[i].number) for i in range(len(data.warning))}


def test_model_compiles_and_steps_without_warnings():
    model = mujoco.MjModel.from_xml_string(mjcf_from_specimen(SEED))
    data = mujoco.MjData(model)
    # rock it: release at 0.6 alpha and shake with 2 g tan(alpha) at 3 Hz, so contacts open and close
    data.qpos[:] = initial_qpos(SEED, 0.6 * SEED.alpha)
    for k in range(1000):
        data.ctrl[0] = -SEED.mass * 2 * SEED.uplift_acceleration * math.sin(2 * math.pi * 3 * k * model.opt.timestep)
        mujoco.mj_step(model, data)
    assert all(n == 0 for n in _warnings(data).values()), _warnings(data)
    assert np.all(np.isfinite(data.qpos))
    assert data.ncon > 0


def test_shipped_model_is_the_generators_output_and_loads_standalone():
    assert ETH_SPECIMEN_PATH.read_text(encoding="utf-8") == mjcf_from_specimen(SEED), (
        "engines/models/eth_specimen.xml is stale: run `python -c "
        "'from housner.engines.mjcf import write_eth_specimen; "
        "write_eth_specimen()'`"
    )
    model = mujoco.MjModel.from_xml_path(str(ETH_SPECIMEN_PATH))  # what `python -m mujoco.viewer --mjcf=` loads
    data = mujoco.MjData(model)
    mujoco.mj_step(model, data, 1000)
    assert all(n == 0 for n in _warnings(data).values()), _warnings(data)


def test_model_mass_inertia_and_geometry_follow_the_specimen(tmp_path):
    path = write_mjcf(SEED, tmp_path / "block.xml")
    model = mujoco.MjModel.from_xml_path(str(path))
    body = model.body("block")
    assert body.mass[0] == pytest.approx(SEED.mass, rel=1e-12)
    # inertia about y through the centre of mass = I0 - m R^2, so p = sqrt(m g R / I0) is the specimen's
    assert body.inertia[1] == pytest.approx(SEED.I0 - SEED.mass * SEED.R**2, rel=1e-12)
    assert math.sqrt(SEED.mass * G * SEED.R / (body.inertia[1] + SEED.mass * SEED.R**2)) == pytest.approx(4.8883, 1e-9)
    assert body.pos[2] == pytest.approx(SEED.H)  # centre of mass H above the pivot line
    assert model.body_ipos[body.id] == pytest.approx([0, 0, 0])
    # drawn strips: outer edges at +-B (2B = 75 mm between them), bottom on the pivot line, 2 mm wide, no contact
    for name, sign in (("strip_pos", 1), ("strip_neg", -1)):
        g = model.geom(name)
        assert sign * (g.pos[0] + sign * g.size[0]) == pytest.approx(SEED.B, abs=1e-15)
        assert 2 * g.size[0] == pytest.approx(0.002)
        assert body.pos[2] + g.pos[2] - g.size[2] == pytest.approx(0.0, abs=1e-15)
        assert g.contype == 0 and g.conaffinity == 0
    # pivots: spheres whose lowest points are the strips' outer bottom edges (+-B, 0)
    for name, sign in (("pivot_pos", 1), ("pivot_neg", -1)):
        g = model.geom(name)
        assert g.type == mujoco.mjtGeom.mjGEOM_SPHERE and g.size[0] == MJCF_DEFAULTS["pivot_radius"]
        assert g.pos[0] == pytest.approx(sign * SEED.B, abs=1e-15)
        assert body.pos[2] + g.pos[2] - g.size[0] == pytest.approx(0.0, abs=1e-15)
    colliding = [model.geom(i).name for i in range(model.ngeom) if model.geom(i).contype or model.geom(i).conaffinity]
    assert sorted(colliding) == ["ground", "pivot_neg", "pivot_pos"]
    assert mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_QPOS) == 3  # planar: x, z, theta


def test_inertia_triangle_inequality_and_bad_settings():
    ixx, iyy, izz = block_inertia(SEED)
    assert ixx + iyy >= izz and iyy + izz >= ixx and ixx + izz >= iyy
    with pytest.raises(ValueError, match="`cone`"):
        mjcf_from_specimen(SEED, cone="round")
    with pytest.raises(ValueError, match="`strip_width`"):
        mjcf_from_specimen(SEED, strip_width=0.05)
    with pytest.raises(ValueError, match="`pivot_radius`"):
        mjcf_from_specimen(SEED, pivot_radius=0.001)  # 4e-3 H: would move the pivot by more than 1e-3 H
    with pytest.raises(ValueError, match="`solimp`"):
        mjcf_from_specimen(SEED, solimp=(0.9, 0.95))
    with pytest.raises(ValueError, match="`solref`"):
        mjcf_from_specimen(SEED, solref=(-1e6, 100.0))  # mixed formats: MuJoCo would silently use its default
    with pytest.raises(ValueError, match="did you mean 'timestep'"):
        MujocoEngine(timestp=1e-4)


def test_engine_defaults_are_the_model_defaults(engine):
    # the model's settings, and the impact law's factor at 1 (the contact alone), which is not the model's
    assert MujocoEngine.DEFAULTS == {**MJCF_DEFAULTS, "impact_energy_factor": 1.0}
    assert engine.settings()["timestep"] == MJCF_DEFAULTS["timestep"]
    assert engine.version() == mujoco.__version__


@pytest.mark.parametrize("rho", [0.0, MJCF_DEFAULTS["pivot_radius"], 2e-4])
def test_initial_state_puts_the_pivot_on_the_ground(rho):
    for th0 in (0.3, -0.3, 0.0):
        x, z, th = initial_qpos(SEED, th0, rho)
        s = math.copysign(1.0, th0)
        # centre of the pivot sphere, body point (s B, -H + rho), rotated by th about y and shifted by the slides:
        # (x + s B cos th + (-H + rho) sin th, H + z - s B sin th + (-H + rho) cos th), back at (s B, rho)
        assert x + s * SEED.B * math.cos(th) + (rho - SEED.H) * math.sin(th) == pytest.approx(s * SEED.B, abs=1e-15)
        assert SEED.H + z - s * SEED.B * math.sin(th) + (rho - SEED.H) * math.cos(th) == pytest.approx(rho, abs=1e-15)
    # rolling about the contact point (B, 0) of the +x pivot at rate w: the centre of mass moves perpendicular to
    # the arm from that point, at w times its length
    vx, vz, w = initial_qvel(SEED, 0.1, 2.0, rho)
    x, z, _ = initial_qpos(SEED, 0.1, rho)
    rx, rz = x - SEED.B, SEED.H + z
    assert vx * rx + vz * rz == pytest.approx(0.0, abs=1e-15)
    assert math.hypot(vx, vz) == pytest.approx(2.0 * math.hypot(rx, rz), rel=1e-12)
    assert math.hypot(rx, rz) == pytest.approx(SEED.R, rel=1e-4 if rho else 1e-12)  # rho shortens the arm


def _contact_rows(xml: str) -> tuple[mujoco.MjModel, mujoco.MjData]:
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_step(model, data, 10)
    assert data.ncon == 2  # one contact per pivot
    return model, data


def test_ground_carries_the_pivots_contact_settings():
    """The contact's stiffness and damping are those of the pivots' solref, not an average with the ground's.

    MuJoCo builds each contact row's reference acceleration -B v - K d with K = 1 / (dmax tc dr)^2 and
    B = 2 / (dmax tc), from the solref (tc, dr) and solimp dmax of the contact, where the two geoms' solref and
    solimp are averaged (solmix 1 each). A ground left at MuJoCo's default solref (0.02, 1) averages the time
    constant to (0.02 + tc) / 2: the cause of the too soft contact of the first tuned model (docs/results.md).
    """
    tc, dr = MJCF_DEFAULTS["solref"]
    dmax = MJCF_DEFAULTS["solimp"][1]
    xml = mjcf_from_specimen(SEED)
    model, data = _contact_rows(xml)
    kbip = data.efc_KBIP[: data.nefc]
    assert np.allclose(kbip[:, 0], 1.0 / (dmax * tc * dr) ** 2, rtol=1e-9)
    assert np.allclose(kbip[:, 1], 2.0 / (dmax * tc), rtol=1e-9)
    # the same model with the ground's solref and solimp removed: the time constant is averaged with 0.02 s
    start = xml.index('<geom name="ground"')
    end = xml.index("/>", start)
    bare = xml[:start] + xml[start:end].split(" solref=")[0] + xml[end:]
    model, data = _contact_rows(bare)
    tc_mix = (0.02 + tc) / 2
    assert np.allclose(data.efc_KBIP[: data.nefc, 0], 1.0 / (dmax * tc_mix * dr) ** 2, rtol=1e-9)


# --------------------------------------------------------------------------- physics
def test_sign_convention_ground_acceleration_below_minus_g_tan_alpha_lifts_to_positive_theta(engine):
    n = 301
    acc = np.full(n, -1.3 * SEED.uplift_acceleration)
    resp = engine.simulate(SEED, GroundMotion(acc, 0.001, name="push"))
    moved = np.flatnonzero(np.abs(resp.theta) > 1e-3 * SEED.alpha)
    assert moved.size and resp.theta[moved[0]] > 0
    assert resp.uplift_time >= 0.0


@pytest.mark.parametrize("amplitude", [0.1, 0.3, 0.6, 0.9])
def test_free_vibration_quarter_period_gives_the_specimens_p(engine, amplitude):
    # The time from release to the first impact is exact for Housner's equation (quadrature); the compliant
    # contact shifts it by the micrometre sinking of the pivot. 0.2 % of the quarter period is 0.1 % of p
    # (T ~ 1/p), ten times finer than the 1 % the conformance check asks; measured: -0.06 % at 0.1 alpha,
    # -0.01 % at 0.9 alpha.
    th0 = amplitude * SEED.alpha
    tq = free_rocking_quarter_period(SEED, th0)
    resp = engine.simulate(SEED, GroundMotion.free_vibration(th0, 1.3 * tq, dt=0.001))
    assert resp.impact_times.size >= 1
    assert resp.impact_times[0] == pytest.approx(tq, rel=2e-3)


def test_energy_ratio_at_impact_is_housners_at_every_amplitude(engine):
    # Check 1 of the tuner (engines/tuning/checks.py) at its first sample step: 0.5 % at 71 amplitudes 0.2-0.9
    # alpha, half the 0.7 % gap between the seed's calibrated and Housner's r. Measured at the defaults: worst
    # -0.285 % (0.25 alpha), mean -0.012 %.
    r = np.array(
        [first_impact_ratio(engine.simulate(SEED, m)) for m in free_vibration_motions(SEED, DEFAULT_AMPLITUDES)]
    )
    rel = r / SEED.r_housner - 1
    assert np.all(np.abs(rel) <= 5e-3), dict(zip(DEFAULT_AMPLITUDES, np.round(rel * 100, 3), strict=True))
    assert abs(rel.mean()) <= 1e-3  # no bias beyond the per-impact scatter (std 0.135 %)


def test_energy_ratio_of_small_impacts(engine):
    # Check 2 of the tuner: releases at 0.02-0.19 alpha, where the first tuned contact lost 3-15 % of the energy
    # per impact below 0.03 alpha. Each slow impact's r scatters more with its phase in the step, so the worst may
    # reach 3 x 0.5 %; the mean (a bias would add up over a record's many small impacts) stays within 0.5 %.
    # Measured at the defaults: worst +0.66 % (0.02 alpha), mean +0.04 %, std 0.26 %.
    r = np.array([first_impact_ratio(engine.simulate(SEED, m)) for m in free_vibration_motions(SEED, SMALL_AMPLITUDES)])
    rel = r / SEED.r_housner - 1
    assert np.all(np.abs(rel) <= 1.5e-2), dict(zip(SMALL_AMPLITUDES, np.round(rel * 100, 3), strict=True))
    assert abs(rel.mean()) <= 5e-3


def test_free_decay_follows_housner_for_40_impacts(engine):
    # Check 3 of the tuner: released at 0.1 alpha, the peaks after 10-40 impacts (0.056 to 0.011 alpha) against the
    # exact sequence cos(alpha - theta_k) - cos(alpha) = r^k (cos(alpha - theta_0) - cos(alpha)). 5 %: scatter of
    # ~0.3 % per impact adds up to ~2 % (one standard deviation) over 40; 5 % of the 40th peak is 0.08 mrad.
    # Measured at the defaults: +0.87, +0.68, +1.26, +1.61 %.
    m = decay_motion(SEED)
    exact = decay_peaks(SEED, DECAY_START * SEED.alpha, max(DECAY_IMPACTS))[list(DECAY_IMPACTS)]
    peaks = half_cycle_peaks(engine.simulate(SEED, m))[list(DECAY_IMPACTS)]
    assert np.all(np.abs(peaks / exact - 1) <= DECAY_RTOL), np.round((peaks / exact - 1) * 100, 2)
    # The same model with a soft ground (the contact's time constant averaged with MuJoCo's default 20 ms) loses the
    # small rocking: at rest before the 40th impact (the first tuned model: 40th peak 91 % low, check 1 passed).
    soft = half_cycle_peaks(SoftGroundMujoco(**engine.settings()).simulate(SEED, m))
    assert soft.size <= max(DECAY_IMPACTS) or soft[max(DECAY_IMPACTS)] < 0.5 * exact[-1]


@pytest.mark.parametrize(
    ("w_ratio", "a_ratio", "rtol_max"),
    [(8.0, 5.0, 5e-3), (6.0, 3.0, 5e-3), (12.0, 5.0, 5e-3), (6.0, 1.5, 1.5e-2), (3.0, 1.2, 1.5e-2)],
    ids=["8p-5gtan", "6p-3gtan", "12p-5gtan", "6p-1.5gtan", "3p-1.2gtan"],
)
def test_dalembert_force_reproduces_the_analytic_pulse_response(engine, w_ratio, a_ratio, rtol_max):
    # Check 4 of the tuner. The first three pulses rock the block to 0.2-0.65 alpha: theta_max (after one impact)
    # within 0.5 % of the analytic model, the tuning tolerance on r. The last two lift it just above the uplift
    # threshold to 0.02 alpha, where the first tuned contact rocked 4 % and 10 % too far; their theta_max follows an
    # impact at 0.02 alpha and gets the small-impact tolerance, 1.5 %. The first peak (before any impact) tests the
    # ground forcing and the uplift alone: 0.5 %. Measured at the defaults: theta_max -0.16, +0.18, -0.01, +0.14,
    # +0.24 %; first peaks +0.05, +0.04, +0.09, +0.04, +0.13 %.
    m = _one_sine(SEED, w_ratio, a_ratio, tail=4.0 / SEED.p)
    ref = housner_simulate(SEED, m)
    resp = engine.simulate(SEED, m)
    assert not ref.overturned and not resp.overturned
    assert resp.theta_max == pytest.approx(ref.theta_max, rel=rtol_max)
    assert first_peak(resp) == pytest.approx(first_peak(ref), rel=5e-3)
    assert resp.n_impacts == ref.n_impacts


def test_no_sliding_while_rocking(engine):
    # Pivot slip while |theta| <= alpha stays below 0.1 mm, the accuracy of the seed's Optotrak markers
    # (section 3.4): it is the soft friction constraint's creep, micrometres. mu = 1.5 exceeds max|ug''|/g here
    # (0.75) by 2x.
    m = _one_sine(SEED, 8.0, 5.0, tail=2.0 / SEED.p)
    demand = 5.0 * SEED.uplift_acceleration / G  # max |ug''| / g of the pulse
    assert MujocoEngine.DEFAULTS["friction"] >= 1.99 * demand
    resp = engine.simulate(SEED, m)
    assert resp.info["max_pivot_slip_m"] < 1e-4
    assert resp.info["max_pivot_slip_m"] < 1e-5  # measured 0.9 um


def test_overturn_is_detected_held_and_the_run_stops(engine):
    acc = np.full(3001, -3.0 * SEED.uplift_acceleration)
    m = GroundMotion(acc, 0.001, name="topple")
    resp = engine.simulate(SEED, m)
    ref = housner_simulate(SEED, m)
    assert resp.overturned and ref.overturned
    # the rigid block and MuJoCo's fall the same way; past alpha the falling block's pivot starts to slip,
    # so the times agree to a few percent only (measured +1.8 % for the ramp of the conformance check)
    assert resp.overturn_time == pytest.approx(ref.overturn_time, rel=0.05)
    after = resp.t >= resp.overturn_time
    assert np.all(resp.theta[after] == math.pi / 2) and np.all(resp.theta_dot[after] == 0.0)
    assert resp.theta_max == math.pi / 2
    assert resp.info["n_steps"] * resp.info["timestep_used_s"] < resp.overturn_time + 0.6  # stopped early


def test_initial_angular_velocity_reaches_the_energy_peak(engine):
    # Released at theta0 = 0.1 alpha with theta_dot0 > 0 (toward +x): the energy integral of Housner's equation,
    # theta_dot^2 / 2 + p^2 cos(alpha - theta) = const, gives the peak
    # cos(alpha - theta_pk) = cos(alpha - theta0) + theta_dot0^2 / (2 p^2); theta_dot0 is chosen for 0.6 alpha.
    # 0.5 %: the contact compliance, as for the pulses (measured below 0.1 %).
    a, p = SEED.alpha, SEED.p
    th0 = 0.1 * a
    thd0 = p * math.sqrt(2 * (math.cos(a - 0.6 * a) - math.cos(a - th0)))
    th_pk = a - math.acos(math.cos(a - th0) + thd0**2 / (2 * p * p))
    assert th_pk == pytest.approx(0.6 * a, rel=1e-12)
    m = GroundMotion(np.zeros(601), 0.001, name="kick", theta0=th0, theta_dot0=thd0)
    resp = engine.simulate(SEED, m)
    assert first_peak(resp) == pytest.approx(th_pk, rel=5e-3)
    assert resp.uplift_time == 0.0


def test_at_rest_the_block_stays_put_and_has_no_impacts(engine):
    resp = engine.simulate(SEED, GroundMotion(np.zeros(1001), 0.001, name="rest"))
    assert np.max(np.abs(resp.theta)) < 1e-6 * SEED.alpha
    assert resp.n_impacts == 0 and math.isnan(resp.uplift_time) and not resp.overturned


def test_deterministic_and_picklable(engine):
    m = _one_sine(SEED, 8.0, 5.0, tail=1.0)
    a = engine.simulate(SEED, m)
    clone = pickle.loads(pickle.dumps(engine))
    b = clone.simulate(SEED, m)
    assert np.array_equal(a.theta, b.theta) and np.array_equal(a.impact_times, b.impact_times)
    assert clone.settings() == engine.settings()


def test_sample_grid_need_not_be_a_multiple_of_the_step(engine):
    # El Centro at model scale is sampled at 0.02 / sqrt(10) s: the step is shortened to divide it
    dt = 0.02 / math.sqrt(10)
    th0 = 0.5 * SEED.alpha
    m = GroundMotion.free_vibration(th0, 1.2 * free_rocking_quarter_period(SEED, th0), dt=dt)
    resp = engine.simulate(SEED, m)
    n_sub = resp.info["substeps_per_sample"]
    assert n_sub * resp.info["timestep_used_s"] == pytest.approx(dt, rel=1e-12)
    assert resp.info["timestep_used_s"] <= engine.settings()["timestep"]
    assert resp.t.shape == m.t.shape and resp.theta[0] == th0
    assert resp.impact_times[0] == pytest.approx(free_rocking_quarter_period(SEED, th0), rel=2e-3)


def test_divergence_raises_engine_error_naming_the_motion(tmp_path, monkeypatch):
    # An absurd record (1e12 m/s^2) makes MuJoCo flag the simulation as unstable (bad control / acceleration);
    # the engine turns that into an EngineError that names the motion instead of returning garbage.
    monkeypatch.chdir(tmp_path)  # MuJoCo writes its warnings to MUJOCO_LOG.TXT in the working directory
    m = GroundMotion(np.full(200, 1e12), 0.01, name="absurd shaking")
    with pytest.raises(EngineError, match="absurd shaking"):
        MujocoEngine().simulate(SEED, m)


def test_scaled_specimen_keeps_its_p():
    big = SEED.scaled(10.0)  # the 5 m prototype: p / sqrt(10)
    eng = MujocoEngine()
    th0 = 0.5 * big.alpha
    tq = free_rocking_quarter_period(big, th0)
    resp = eng.simulate(big, GroundMotion.free_vibration(th0, 1.2 * tq, dt=0.002))
    assert resp.impact_times[0] == pytest.approx(tq, rel=2e-3)


def test_kinematic_ground_does_not_drive_the_block():
    """Why the ground motion is a d'Alembert force: a mocap (kinematic) ground does not carry the block along.

    The table accelerates at 0.5 g tan(alpha), well below uplift; a block with mu = 1.5 should ride on it.
    In MuJoCo the mocap table has no velocity in the contact solver, so the block stays where it was.
    """
    xml = mjcf_from_specimen(SEED)
    table = (
        '<body name="table" mocap="true" pos="0 0 0"><geom name="ground" type="box" size="2 1 0.05" pos="0 0 -0.05" '
        'friction="1.5 0 0"/></body>'
    )
    start = xml.index('<geom name="ground"')
    xml = xml[:start] + table + xml[xml.index("/>", start) + 2 :]
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    a = 0.5 * SEED.uplift_acceleration
    n = int(round(1.0 / model.opt.timestep))
    for k in range(n):
        data.mocap_pos[0, 0] = 0.5 * a * ((k + 1) * model.opt.timestep) ** 2
        mujoco.mj_step(model, data)
    ground_x = data.mocap_pos[0, 0]
    assert ground_x == pytest.approx(0.5 * a, rel=1e-9)  # 0.37 m in 1 s
    assert abs(data.qpos[0]) < 0.01 * ground_x  # the block did not follow: it slid 100 % relative to the table
    # whereas the d'Alembert model keeps the block at rest on the ground (relative motion zero, no rocking)
    resp = MujocoEngine().simulate(SEED, GroundMotion(np.full(1001, a), 0.001, name="table"))
    assert np.max(np.abs(resp.theta)) < 1e-3 * SEED.alpha and resp.info["max_pivot_slip_m"] < 1e-5


def test_registry_builds_the_engine():
    eng = get_engine("mujoco", timestep=2.5e-4)
    assert isinstance(eng, MujocoEngine) and eng.settings()["timestep"] == 2.5e-4


def test_rotational_damping_is_realised_as_hinge_damping():
    """MuJoCo's rotational_damping (hinge damping c I0) against the analytic engine's, on free rocking.

    Free rocking from 0.6 alpha with c = 1 1/s: the half-cycle peaks of both engines with the
    effect agree within 1 % over the first five half-cycles (MuJoCo's tuned r is within 0.3 % of
    Housner's per impact, so four impacts stay within ~1.2 %; 1 % holds on this record), while
    the effect itself lowers the fifth peak by far more (> 5 %), so the test can fail.
    """
    spec = Specimen.bachmann2017()
    motion = GroundMotion.free_vibration(0.6 * spec.alpha, 4.0, dt=1e-3)
    eff = [make_effect("rotational_damping", c=1.0)]
    mj = MujocoEngine()
    model, _ = mj._model(spec)
    assert model.jnt_dofadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "theta")] == 2
    peaks = {
        "mujoco": half_cycle_peaks(mj.simulate(spec, motion, eff))[:5],
        "mujoco_plain": half_cycle_peaks(mj.simulate(spec, motion))[:5],  # the damping is reset between calls
        "housner": half_cycle_peaks(get_engine("housner").simulate(spec, motion, eff))[:5],
    }
    assert all(v.size == 5 for v in peaks.values())
    np.testing.assert_allclose(peaks["mujoco"], peaks["housner"], rtol=0.01)
    assert peaks["mujoco"][4] < 0.95 * peaks["mujoco_plain"][4]
    assert mj.simulate(spec, motion).theta_max == pytest.approx(peaks["mujoco_plain"][0], rel=1e-3)
    with pytest.raises(ValueError, match="cannot realise effect 'sliding'.*restitution, rotational_damping"):
        mj.simulate(spec, motion, [make_effect("sliding", mu=0.3)])
