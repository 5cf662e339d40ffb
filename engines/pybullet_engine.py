"""The rocking block in PyBullet (Bullet's Featherstone multibody with a sequential-impulse contact solver).

:class:`PybulletEngine` loads the URDF of :func:`housner.engines.urdf.urdf_from_specimen` (two carriages
and a hinge through the centre of mass, two bevelled contact strips whose outer edges are the pivots) on
PyBullet's fixed infinite plane, drives it by the d'Alembert force of the ground acceleration (gravity
tilted to (-ug'', 0, -g) before each step) and rebuilds the world for every record, so that the same
motion gives bit-identical results. How it holds the block, and where its impacts depart from Housner's,
are in ``docs/explanation/engines.md`` ("PyBullet"); the contact settings and why, in
:class:`PybulletEngine`; what they measure and cost, in ``docs/results.md#defaults-pybullet``.
"""

from __future__ import annotations

import ctypes
import math
import os
import shutil
import sys
import tempfile
import time
import weakref
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from housner.engines._planar import (
    IMPACT_LAW_RANGE,
    OVERTURN_ANGLE,
    RUNAWAY_M,
    PlanarEngine,
    gravity_x,
    pivot_offset,
    pivot_x,
    release_state,
    substeps,
)
from housner.engines.urdf import JOINTS, URDF_DEFAULTS, write_urdf
from housner.errors import EngineError, unknown_choice
from housner.motion import GroundMotion
from housner.response import Response
from housner.specimen import Specimen
from housner.units import G

__all__ = ["PybulletEngine"]

#: Sliding is measured while |theta| stays below this [rad]: past it a falling
#: block's normal force fades and it slides, as a real one does.
_SLIP_ANGLE = math.pi / 4

#: The seed specimen's p [1/s]: tuning candidates are scaled from it.
_P_SEED = 4.8883

_SETTING_DOCS = {
    "timestep": "largest engine step [s]",
    "solver_iterations": "sequential-impulse iterations per step [-]",
    "lateral_friction": "Coulomb friction coefficient strip/ground [-]",
    "restitution": "Newton restitution coefficient strip/ground [-]",
    "restitution_velocity_threshold": "normal speed below which restitution is ignored [m/s]",
    "contact_erp": "contact position-error reduction per step (rigid contact) [-]",
    "friction_erp": "friction drift correction per step [-]",
    "contact_slop": "penetration the solver leaves uncorrected [m]",
    "contact_breaking_threshold": "distance within which contact points are kept and made [m]",
    "cone_friction": "friction cone (True) or two-direction pyramid (False)",
    "contact_stiffness": "compliant contact stiffness [N/m] (None: rigid)",
    "contact_damping": "compliant contact damping [N s/m] (None: rigid)",
    "strip_width": "width of each contact strip [m]",
    "bevel": "bevel of the strips' bottom faces [rad]",
    "impact_energy_factor": "energy kept at each impact, as a fraction of what the contact leaves [-]",
}


class PybulletEngine(PlanarEngine):
    """PyBullet's rigid block on a rigid plane, driven by the d'Alembert force.

    Parameters
    ----------
    timestep : float
        Largest engine step [s]; the step used is ``motion.dt / k`` with the
        smallest integer k that makes it at most ``timestep``.
    solver_iterations : int
        Sequential-impulse iterations per step [-] (``numSolverIterations``).
    lateral_friction : float
        Friction coefficient between the strips and the ground [-]. It must
        exceed max |ug''| / g with a margin for the impacts, which need about
        0.1 for the seed specimen; sliding is reported in
        ``Response.info["max_pivot_slip_m"]``.
    restitution : float
        Newton coefficient of restitution at the strips [-]; 0 is Housner's
        plastic impact.
    restitution_velocity_threshold : float
        Normal approach speed below which restitution is ignored [m/s].
    contact_erp : float
        Fraction of the contact penetration corrected per step (rigid
        contact) [-] (``contactERP``).
    friction_erp : float
        Fraction of the friction drift corrected per step [-] (``frictionERP``).
    contact_slop : float
        Penetration the solver leaves uncorrected [m] (``contactSlop``).
    contact_breaking_threshold : float
        Distance within which contact points are made and kept [m]
        (``contactBreakingThreshold``; Bullet keeps it in a process-wide
        global, so the engine sets it before every run).
    cone_friction : bool
        Coulomb friction cone (True) or a pyramid of two independent
        directions (False) (``enableConeFriction``).
    contact_stiffness, contact_damping : float or None
        A compliant contact, stiffness [N/m] and damping [N s/m]; give both or
        neither. None: rigid contact.
    strip_width : float
        Width of each contact strip [m] (their outer edges stay at +-B).
    bevel : float
        Rotation of each strip about its outer bottom edge [rad]: the inner
        edge stands ``strip_width * sin(bevel)`` above the ground, so only the
        outer edges touch (see :func:`housner.engines.urdf.urdf_from_specimen`).
    impact_energy_factor : float
        The impact law's factor (:class:`housner.engines._planar.PlanarEngine`); 1 (default): the contact alone.

    Notes
    -----
    The defaults come from the contact tuner (:mod:`housner.engines.tuning`) run
    for the seed specimen and Housner's r; their measured errors:
    docs/results.md#defaults-pybullet. Each instance owns one PyBullet ``DIRECT`` client
    (opened on first use and reused by every :meth:`simulate` call, which
    resets the world in it); a pickled engine carries only its settings.

    By default the contact is rigid: Bullet's velocity-level contact
    constraint (restitution 0, friction 1.5, no allowed penetration), solved
    by sequential impulses. Contact points are made only within 1 um of the
    ground (``contact_breaking_threshold``): with Bullet's default 2 cm the
    landing pivot is caught by a "speculative" contact a step early and the
    impact loses about 0.5 % too much energy. The impact is then the solver's
    plastic impulse at the landing pivot, and its energy ratio scatters about
    Housner's r by an amount that shrinks with the step: at the default
    1e-4 s it is within 0.18 % of it at every release amplitude from 0.2 to
    0.9 alpha (0.01 alpha grid; mean -0.02 %; 0.31 % at 2e-4 s). A compliant
    contact (``contact_stiffness`` and ``contact_damping``, both set) can
    reach other r values in free rocking but distorts the forced response,
    see :meth:`tuning_candidates`.

    Examples
    --------
    >>> from housner import GroundMotion, Specimen
    >>> from housner.engines.pybullet_engine import PybulletEngine
    >>> spec = Specimen.bachmann2017()
    >>> res = PybulletEngine().simulate(spec, GroundMotion.free_vibration(0.5 * spec.alpha, 1.0))
    >>> res.n_impacts >= 2
    True
    """

    name = "pybullet"

    #: Default settings: the choice of ``housner tune pybullet`` (housner.engines.tuning.tune) for
    #: Specimen.bachmann2017() and Housner's r (what they measure: docs/results.md#defaults-pybullet), with the
    #: step halved to 0.1 ms on 2026-11-27: PyBullet's impacts below x = |w-|/(p alpha) ~ 0.2 keep too little
    #: energy, in proportion to the step (its impact map: 7.1 % at x = 0.05 at 0.2 ms, 4.7 % at 0.1 ms, 0.4 % at
    #: 0.01 ms); at 0.1 ms the KS distance on three El Centro ensembles of 100 motions fell from 0.18, 0.09, 0.12
    #: to 0.09, 0.07, 0.09, for 1.8 times the CPU (docs/results.md#pybullet-verdict).
    DEFAULTS: dict = {
        "timestep": 1.0e-4,
        "solver_iterations": 10,
        "lateral_friction": 1.5,
        "restitution": 0.0,
        "restitution_velocity_threshold": 0.0,
        "contact_erp": 0.2,
        "friction_erp": 0.2,
        "contact_slop": 0.0,
        "contact_breaking_threshold": 1e-6,
        "cone_friction": True,
        "contact_stiffness": None,
        "contact_damping": None,
        "strip_width": URDF_DEFAULTS["strip_width"],
        "bevel": URDF_DEFAULTS["bevel"],
        "impact_energy_factor": 1.0,
    }
    #: The accuracy-cost frontier's axes (``housner frontier pybullet``): the step [s] and the contact's
    #: error reduction parameter [-] (how fast penetration is pushed out).
    FRONTIER: ClassVar[dict] = {"timestep": (1e-4, 2e-4, 5e-4, 1e-3), "contact_erp": (0.1, 0.2, 0.5, 0.8)}

    def __init__(self, **settings: Any):
        unknown = sorted(set(settings) - set(self.DEFAULTS))
        if unknown:
            raise unknown_choice("PyBullet setting", unknown[0], self.DEFAULTS)
        s = dict(self.DEFAULTS)
        s.update(settings)
        self._settings = _validated(s)
        self._client: int | None = None
        self._finalizer: weakref.finalize | None = None
        self._urdf: dict[tuple, Path] = {}

    # ------------------------------------------------------------------
    def close(self) -> None:
        """Disconnect the PyBullet client and delete the temporary URDF files (reopened on next use)."""
        if self._finalizer is not None:
            self._finalizer()
        self._client = None
        self._finalizer = None
        self._urdf = {}

    # ------------------------------------------------------------------
    @classmethod
    def tuning_candidates(cls, specimen: Specimen, target_r: float) -> list[dict]:
        """Settings to try when tuning the contact to reach ``target_r``, cheap to expensive.

        Parameters
        ----------
        specimen : Specimen
        target_r : float
            Kinetic-energy ratio at impact to reach [-].

        Returns
        -------
        list of dict
            Keyword settings for :class:`PybulletEngine`.

        Notes
        -----
        Steps are given for the seed specimen (p = 4.8883 1/s) and scaled by
        p_seed / p, so a geometrically similar block S times larger gets
        sqrt(S) times longer steps (the same steps per rocking time).

        1. Rigid contact with shrinking steps from 2e-4 s (the step decides
           how close the impact's energy loss comes to Housner's, from below
           or above depending on where in a step the impact falls). Longer
           steps (5e-4 s, 3.4e-4 s, 2.5e-4 s) also keep r within 0.5 % of
           Housner's at the tuner's amplitudes, but the free flight between
           impacts (Bullet integrates with semi-implicit Euler, first order)
           then costs accuracy under shaking: the median theta_max error on
           one-sine pulses is 0.69 %, 0.47 % and 0.35 % against 0.26 % at
           2e-4 s, so they are not offered.
        2. When ``target_r`` is more than 0.25 % away from Housner's r, a
           compliant contact: stiffness k = m omega_c^2 (per strip edge)
           with omega_c = 461 p and 798 p (2e7 and 6e7 N/m for the seed
           specimen), damping d = 2 zeta sqrt(k m) for a range of zeta, and a
           step of 0.08 / omega_c; softer contacts (146 p, 2e6 N/m) for
           targets below Housner's. A stiff, lightly damped contact keeps
           more energy than Housner's plastic impact, a softer or more damped
           one less. But a compliant contact also lets the block tilt on it
           before uplift, which the tuner's pulse check catches: for the seed
           specimen the contacts that reach the calibrated r = 0.9532 in free
           rocking overshoot the analytic first peak under a one-sine pulse
           by about 2 %. The rigid contact has no knob for r: a restitution
           above 0 makes the landing pivot bounce and chatter, which leaves r
           nearly unchanged for small values and erratic for large ones.
        """
        try:
            target = float(target_r)
        except (TypeError, ValueError):
            raise ValueError(f"`target_r` must be a number, got {target_r!r}") from None
        if not (math.isfinite(target) and 0.0 < target <= 1.0):
            raise ValueError(f"`target_r` must lie in (0, 1], got {target_r!r}")
        scale = _P_SEED / specimen.p
        out: list[dict] = [{"timestep": _sig(h * scale)} for h in (2e-4, 1.5e-4, 1e-4, 7e-5, 5e-5)]
        if abs(target / specimen.r_housner - 1.0) > 0.0025:
            m = specimen.mass
            zetas = (0.005, 0.01, 0.02, 0.05) if target > specimen.r_housner else (0.3, 0.5, 1.0)
            ratios = (461.0, 798.0) if target > specimen.r_housner else (146.0, 461.0)
            for ratio in ratios:
                omega_c = ratio * specimen.p
                k = m * omega_c**2
                for zeta in zetas:
                    out.append(
                        {
                            "timestep": _sig(0.08 / omega_c),
                            "contact_stiffness": _sig(k),
                            "contact_damping": _sig(2.0 * zeta * math.sqrt(k * m)),
                        }
                    )
        return out

    # ------------------------------------------------------------------
    def _connect(self) -> int:
        if self._client is None:
            pb = _pybullet()

            cid = pb.connect(pb.DIRECT)
            if cid < 0:
                raise EngineError("cannot open a PyBullet DIRECT client")
            tmp = Path(tempfile.mkdtemp(prefix="housner-urdf-"))
            self._client = cid
            self._tmp = tmp
            self._finalizer = weakref.finalize(self, _close_client, cid, str(tmp))
            self._urdf = {}
        return self._client

    def _urdf_path(self, specimen: Specimen, offset: float = 0.0) -> Path:
        key = (specimen.height, specimen.width, specimen.depth, specimen.mass, specimen.inertia)
        if offset != 0.0:
            key += (offset,)
        path = self._urdf.get(key)
        if path is None:
            path = write_urdf(
                specimen,
                self._tmp / f"block{len(self._urdf)}.urdf",
                strip_width=self.strip_width,
                bevel=self._settings["bevel"],
                **({"offset": offset} if offset != 0.0 else {}),
            )
            self._urdf[key] = path
        return path

    @property
    def strip_width(self) -> float:
        """Width of each contact strip [m]."""
        return self._settings["strip_width"]

    def build(self, specimen: Specimen, step: float, offset: float = 0.0) -> tuple[int, int]:
        """Reset the client's world to the specimen standing on the plane.

        Parameters
        ----------
        specimen : Specimen
        step : float
            Engine step [s].
        offset : float
            e [m] of the effect ``asymmetric_pivots``: the strips' outer edges at x = B - e and
            -(B + e) of the centre of mass (:func:`housner.engines.urdf.urdf_from_specimen`); 0: +-B.

        Returns
        -------
        (client, body) : tuple of int
            PyBullet client id and the block's body id (joints 0, 1, 2 are x,
            z, theta).
        """
        pb = _pybullet()

        cid = self._connect()
        s = self._settings
        pb.resetSimulation(physicsClientId=cid)
        params = {
            "fixedTimeStep": step,
            "numSubSteps": 0,
            "numSolverIterations": s["solver_iterations"],
            "contactERP": s["contact_erp"],
            "frictionERP": s["friction_erp"],
            "restitutionVelocityThreshold": s["restitution_velocity_threshold"],
            "contactSlop": s["contact_slop"],
            "enableConeFriction": int(s["cone_friction"]),
            # A process-wide global in Bullet (gContactBreakingThreshold): set it on every build.
            "contactBreakingThreshold": s["contact_breaking_threshold"],
            "deterministicOverlappingPairs": 1,
        }
        pb.setPhysicsEngineParameter(physicsClientId=cid, **params)
        pb.setGravity(0.0, 0.0, -G, physicsClientId=cid)
        plane = pb.createMultiBody(
            0.0, pb.createCollisionShape(pb.GEOM_PLANE, physicsClientId=cid), physicsClientId=cid
        )
        body = pb.loadURDF(
            str(self._urdf_path(specimen, offset)),
            useFixedBase=True,
            flags=pb.URDF_USE_INERTIA_FROM_FILE,
            physicsClientId=cid,
        )
        if [pb.getJointInfo(body, j, physicsClientId=cid)[1].decode() for j in range(3)] != list(JOINTS):
            raise EngineError("the generated URDF's joints are not (x, z, theta)")
        # PyBullet motorises every joint by default; a zero-force motor frees it.
        pb.setJointMotorControlArray(body, [0, 1, 2], pb.VELOCITY_CONTROL, forces=[0.0] * 3, physicsClientId=cid)
        # Combined coefficients are products (Bullet): the plane carries 1 so the block's values are the contact's.
        pb.changeDynamics(plane, -1, lateralFriction=1.0, restitution=1.0, physicsClientId=cid)
        for link in (-1, 0, 1, 2):
            pb.changeDynamics(body, link, linearDamping=0.0, angularDamping=0.0, jointDamping=0.0, physicsClientId=cid)
        contact = {
            "lateralFriction": s["lateral_friction"],
            "restitution": s["restitution"],
            "rollingFriction": 0.0,
            "spinningFriction": 0.0,
        }
        if s["contact_stiffness"] is not None:
            contact["contactStiffness"] = s["contact_stiffness"]
            contact["contactDamping"] = s["contact_damping"]
        pb.changeDynamics(body, 2, physicsClientId=cid, **contact)
        # Bullet puts resting bodies to sleep, and a gravity change does not wake them.
        pb.changeDynamics(body, -1, activationState=pb.ACTIVATION_STATE_DISABLE_SLEEPING, physicsClientId=cid)
        return cid, body

    # ------------------------------------------------------------------
    def _simulate(self, specimen: Specimen, motion: GroundMotion, effects: tuple) -> Response:
        pb = _pybullet()

        wall0 = time.perf_counter()
        H, B = specimen.H, specimen.B
        e = pivot_offset(effects)
        k, h = substeps(motion.dt, self._settings["timestep"])
        cid, body = self.build(specimen, h, e)

        # Release state: rotated by theta0 about the pivot on its side, touching the ground.
        th0, om0 = motion.theta0, motion.theta_dot0
        xc, zc, dxc, dzc = release_state(H, B, th0, om0, e)
        pb.resetJointState(body, 0, xc, dxc, physicsClientId=cid)
        pb.resetJointState(body, 1, zc - H, dzc, physicsClientId=cid)
        pb.resetJointState(body, 2, th0, om0, physicsClientId=cid)

        # Gravity x component before each step: minus the exact mean of the linear ug'' over the step.
        gx_rows = gravity_x(motion.acc, k)

        n = motion.n
        states = np.empty((n, 6))
        states[0] = (xc, zc - H, th0, dxc, dzc, om0)
        # The client id is passed by position in the step loop: as a keyword it costs each call a dict (3 % of a step).
        set_gravity, step, get_states = pb.setGravity, pb.stepSimulation, pb.getJointStates
        joints = (0, 1, 2)
        g = -G
        last = n - 1
        overturned = False
        after = self.impact_law(specimen, effects, h, th0).step_hook
        for i in range(1, n):
            for gxi in gx_rows[i - 1]:
                set_gravity(gxi, 0.0, g, cid)
                step(cid)
                if after is not None and (c := after(*pb.getJointState(body, 2, physicsClientId=cid)[:2])) is not None:
                    for j, (q, v, *_) in zip(joints, get_states(body, joints, physicsClientId=cid), strict=True):
                        pb.resetJointState(body, j, q, c * v, physicsClientId=cid)
            (q0, v0, *_), (q1, v1, *_), (q2, v2, *_) = get_states(body, joints, cid)
            states[i] = (q0, q1, q2, v0, v1, v2)
            if not (abs(q0) < RUNAWAY_M and abs(q1) < RUNAWAY_M and math.isfinite(q2) and math.isfinite(v2)):
                state = f"x = {q0:.6g} m, z = {q1:.6g} m, theta = {q2:.6g} rad; limit {RUNAWAY_M:g} m"
                raise self.diverged(motion, i, state, friction="lateral_friction")
            if abs(q2) >= OVERTURN_ANGLE:
                overturned = True
                last = i
                break

        # Sliding: the x drift of the pivot carrying the block, while |theta| < pi/4 (a falling block slides).
        upright = np.abs(states[: last + 1, 2]) < _SLIP_ANGLE
        x_com, th = states[: last + 1, 0][upright], states[: last + 1, 2][upright]
        sgn = np.sign(th)
        sb = sgn * B if e == 0.0 else np.where(th > 0.0, pivot_x(B, e)[0], np.where(th < 0.0, pivot_x(B, e)[1], 0.0))
        slip = x_com + sb * np.cos(th) - H * np.sin(th) - sb
        return self._response(
            specimen,
            motion,
            states[:, 2].copy(),
            states[:, 5].copy(),
            last,
            overturned,
            h,
            k,
            time.perf_counter() - wall0,
            max_pivot_slip_m=float(np.max(np.abs(slip), initial=0.0)),
            max_penetration_m=float(max(0.0, -np.min(_pivot_z(states[: last + 1], H, B, e)))),
        )


# ----------------------------------------------------------------------
def _validated(s: dict) -> dict:
    """Check and normalise the settings (messages name the setting)."""
    out = dict(s)

    def number(key: str, lo: float, hi: float, lo_open: bool = False) -> float:
        v = out[key]
        try:
            x = float(v)
        except (TypeError, ValueError):
            raise ValueError(f"`{key}` ({_SETTING_DOCS[key]}) must be a number, got {v!r}") from None
        if not math.isfinite(x) or x < lo or x > hi or (lo_open and x == lo):
            rng = f"{'(' if lo_open else '['}{lo:g}, {hi:g}]"
            raise ValueError(f"`{key}` ({_SETTING_DOCS[key]}) must lie in {rng}, got {v!r}")
        return x

    out["timestep"] = number("timestep", 0.0, 0.01, lo_open=True)
    it = out["solver_iterations"]
    if isinstance(it, bool) or not isinstance(it, (int, np.integer)) or it < 1:
        raise ValueError(f"`solver_iterations` must be a positive integer, got {it!r}")
    out["solver_iterations"] = int(it)
    out["lateral_friction"] = number("lateral_friction", 0.0, 10.0)
    out["restitution"] = number("restitution", 0.0, 1.0)
    out["restitution_velocity_threshold"] = number("restitution_velocity_threshold", 0.0, 10.0)
    out["contact_erp"] = number("contact_erp", 0.0, 1.0)
    out["friction_erp"] = number("friction_erp", 0.0, 1.0)
    out["contact_slop"] = number("contact_slop", 0.0, 0.01)
    out["contact_breaking_threshold"] = number("contact_breaking_threshold", 0.0, 0.1, lo_open=True)
    if not isinstance(out["cone_friction"], (bool, np.bool_)):
        raise ValueError(f"`cone_friction` must be True or False, got {out['cone_friction']!r}")
    out["cone_friction"] = bool(out["cone_friction"])
    out["bevel"] = number("bevel", 0.0, 0.1)
    out["strip_width"] = number("strip_width", 0.0, 1.0, lo_open=True)
    out["impact_energy_factor"] = number("impact_energy_factor", *IMPACT_LAW_RANGE, lo_open=True)
    ks, kd = out["contact_stiffness"], out["contact_damping"]
    if (ks is None) != (kd is None):
        raise ValueError("`contact_stiffness` and `contact_damping` must be given together (or both None: rigid)")
    if ks is not None:
        out["contact_stiffness"] = number("contact_stiffness", 0.0, 1e12, lo_open=True)
        out["contact_damping"] = number("contact_damping", 0.0, 1e9)
    return out


def _sig(x: float, digits: int = 3) -> float:
    """``x`` rounded to ``digits`` significant digits (tidy settings in tables)."""
    return float(f"{x:.{digits - 1}e}")


def _pybullet():
    """The ``pybullet`` module, imported without its "pybullet build time: ..." banner.

    The C extension prints the banner when it is imported (to fd 2 with the
    wheels of PyBullet 3.2.7, to fd 1 with other builds); it would land in the
    middle of the progress bar or of a command's output. The import runs with
    file descriptors 1 and 2 pointed at the null device, C's stdio flushed before
    they are restored. Where that cannot be done, the module is imported plainly.
    """
    pb = sys.modules.get("pybullet")
    if pb is not None:
        return pb
    saved: list[tuple[int, int]] = []
    try:
        for stream in (sys.stdout, sys.stderr):
            if stream is not None:
                stream.flush()
        for fd in (1, 2):
            saved.append((fd, os.dup(fd)))
    except (OSError, ValueError, AttributeError):
        for _fd, copy in saved:
            os.close(copy)
        import pybullet as pb  # lazy: imported with its build banner silenced

        return pb
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        try:
            for fd, _copy in saved:
                os.dup2(devnull, fd)
        finally:
            os.close(devnull)
        import pybullet as pb  # lazy: imported with its build banner silenced

        _flush_c_stdio()
    finally:
        for fd, copy in saved:
            os.dup2(copy, fd)
            os.close(copy)
    return pb


def _flush_c_stdio() -> None:
    """fflush(NULL): push C stdio buffers (the banner) out while fds 1 and 2 are still the null device."""
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError, TypeError):
        pass


def _close_client(cid: int, tmp: str) -> None:
    try:
        pb = _pybullet()

        if pb.isConnected(physicsClientId=cid):
            pb.disconnect(physicsClientId=cid)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _pivot_z(states: np.ndarray, H: float, B: float, e: float = 0.0) -> np.ndarray:
    """Height of the lower pivot edge [m] from the states (x, z - H, theta, ...); negative = penetration.

    The pivots are at x = B - e and -(B + e) of the centre of mass (``e`` [m], 0: +-B); the lower one is
    that of theta's side.
    """
    z = states[:, 1] + H
    th = states[:, 2]
    if e != 0.0:
        B = np.where(th >= 0.0, B - e, B + e)  # distance of the pivot of theta's side from the centre of mass
    return z - H * np.cos(th) - B * np.abs(np.sin(th))
