"""OpenSees (openseespy): the rocking block as a rigid frame on penalty contacts with Coulomb friction.

:class:`OpenSeesEngine` builds the model for every run: a 2D domain whose centre-of-mass node carries the
block's mass and inertia, two massless corner nodes joined to it by corotational elastic beams, at each
corner a node-to-node contact (a hinge with friction, released in tension) beside a damped no-tension
spring (the loss at impact), the ground acceleration as a ``UniformExcitation``, and Newmark's average
acceleration with Krylov-Newton iterations at a fixed step. The model step by step is in
``engines/models/opensees.md`` ("Derivation, step by step", whose numbers the code cites) and
``docs/explanation/engines.md`` ("OpenSees"); the contact settings, the solver and why, in
:class:`OpenSeesEngine`; what they measure and cost, in ``docs/results.md#defaults-opensees``.
"""

from __future__ import annotations

import atexit
import math
import os
import sys
import time
from typing import ClassVar

import numpy as np

from housner.engines._impact_law import ImpactLaw
from housner.engines._planar import (
    OVERTURN_ANGLE,
    PIVOT_RANGES,
    RUNAWAY_M,
    PlanarEngine,
    pivot_offset,
    pivot_x,
    release_state,
    substeps,
)
from housner.errors import EngineError, EngineUnavailable
from housner.motion import GroundMotion
from housner.response import Response
from housner.specimen import Specimen
from housner.units import G

__all__ = ["OpenSeesEngine", "SYSTEM_LIBRARIES"]

#: The system libraries openseespy's Linux build loads (named when it fails to load them).
SYSTEM_LIBRARIES = "apt-get install libblas3 liblapack3"

#: Axial and bending stiffness of the beams from the centre of mass to the corners [N], [N m^2].
_BEAM_EA, _BEAM_EI = 1.0e10, 1.0e8

#: Stick (elastic) stiffness of the Coulomb friction at a corner [N/m].
_STICK_K = 1.0e9

#: Most Newton iterations per step, and the retries of a failed sample interval (step divisor, algorithm,
#: factor on ``tolerance``). The last, a tolerance 100 times looser (0.1 N at the default: 0.26 % of the seed's
#: weight) for the rest of that one interval, is for a corner that touches down again after a lift of a few
#: nanometres: the node-to-node contact's stick force then switches on at its stiffness times the drift
#: since the last stick (1e9 N/m x ~1e-10 m), the unbalance jumps between 0.01 and 0.1 N and no shorter step
#: converges (measured: ``elcentro`` motion 39 at 0.023 s, the one of 200 records of ``elcentro`` and
#: ``elcentro-strong`` that needed it). Each interval that needed it is counted in ``info["loose_samples"]``.
_MAX_ITER = 25
_LOOSE = 100.0
_RETRIES = ((10, "Newton", 1.0), (100, "KrylovNewton", 1.0), (10, "KrylovNewton", _LOOSE))

#: The solution algorithms offered (``algorithm``), the default first.
_ALGORITHMS = ("KrylovNewton", "Newton")

#: The frictional contact elements offered (``contact_element``), the default first.
_CONTACT_ELEMENTS = ("zeroLengthContact2D", "flatSliderBearing")


def _quiet_exit() -> None:
    """Send the process's standard streams to /dev/null at exit: openseespy's library prints
    "Process 0 Terminating" from its teardown, after Python has written everything it had to
    (an uncaught exception's traceback is printed before the atexit handlers run)."""
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)
        os.dup2(null, 2)
    except (OSError, ValueError):
        pass


def _opensees():
    """The openseespy.opensees module, or an EngineUnavailable naming what to install."""
    if "openseespy.opensees" not in sys.modules:
        atexit.register(_quiet_exit)
    try:
        import openseespy.opensees as ops  # optional engine
    except ImportError as e:
        raise EngineUnavailable(
            f"engine {OpenSeesEngine.name!r} needs the {OpenSeesEngine.package} package ({e}); "
            f"install it with: {OpenSeesEngine.INSTALL}"
        ) from None
    except RuntimeError as e:  # the package is there but its library is not loadable (libblas/liblapack)
        raise EngineUnavailable(
            f"engine {OpenSeesEngine.name!r} could not load {OpenSeesEngine.package} ({e}); install the system "
            f"libraries with: {SYSTEM_LIBRARIES} (and the package with: {OpenSeesEngine.INSTALL})"
        ) from None
    return ops


class OpenSeesEngine(PlanarEngine):
    """OpenSees' rigid frame on damped no-tension contact springs with Coulomb friction, uniform excitation.

    Parameters
    ----------
    contact_stiffness : float
        k_n [N/m]: stiffness of each of the two normal springs per corner (the
        contact element's and the damped one's), so 2 k_n per corner in contact.
    contact_damping : float
        beta_K [s]: stiffness-proportional damping of the no-tension spring
        (on its current stiffness: none once the corner lifts). More damping,
        more energy lost at an impact.
    friction : float
        Coulomb friction coefficient corner/ground [-]; it must exceed
        max |ug''| / g with a margin for the impacts.
    tolerance : float
        The iterations stop when the norm of the unbalanced forces is below
        this [N, N m].
    algorithm : {"KrylovNewton", "Newton"}
        OpenSees' solution algorithm of each step (Notes).
    contact_element : {"zeroLengthContact2D", "flatSliderBearing"}
        The frictional contact element at each corner (Notes).
    timestep, impact_energy_factor
        As :class:`housner.engines._planar.PlanarEngine`'s, which also shows how an adapter is driven.

    Notes
    -----
    OpenSees is one interpreter per process: the engine wipes and rebuilds the
    model for every record, so records run one after the other in a process
    (use processes, not threads, to run them in parallel).

    The contact, per corner (step 4 of ``engines/models/opensees.md``), is two
    elements between the ground node and the corner node, in parallel:

    * a ``zeroLengthContact2D`` node-to-node contact (the corner constrained,
      the ground retained, normal +y): penalty k_n in the normal direction,
      released in tension (uplift), Coulomb friction mu = 1.5 on that normal
      force with a stick (tangential penalty) stiffness of 1e9 N/m. It carries
      no moment, so the corner is a hinge. ``contact_element =
      "flatSliderBearing"`` puts OpenSees' friction bearing there instead
      (the same normal spring, friction and stick stiffness, and a
      zero-stiffness ``-Mz`` material for the hinge): the earlier model,
      which rocks alike at more CPU time. Why the node-to-node contact and not
      the bearing: docs/results.md#defaults-opensees;
    * a ``zeroLength`` spring, vertical, elastic-no-tension (``ENT``) k_n, with
      stiffness-proportional Rayleigh damping beta_K on its current stiffness
      (``-doRayleigh``), so that it damps only while the corner presses on the
      ground: the loss at impact that Housner's plastic impact stands for.

    The static compression under the block's weight, m g / (4 k_n) =
    0.64 um per corner for the seed specimen, is the initial state.

    Each step (step 5) iterates ``algorithm`` (Krylov-Newton, which forms the
    tangent once per step and accelerates the iterations on it; or full
    Newton) until the unbalanced force is below ``tolerance`` (1 mN, 2.6e-5 of
    the seed's weight), at the fixed step ``timestep``. A sample interval
    whose step fails is redone in steps ten times shorter with Newton, then a
    hundred times shorter with Krylov-Newton, then ten times shorter at a
    tolerance a hundred times looser (``_RETRIES``: a corner touching down
    after a lift of nanometres; counted in ``info["loose_samples"]``); if that
    fails too the engine raises an ``EngineError`` naming the motion and the
    time. Why Krylov-Newton is the default: docs/results.md#defaults-opensees.

    The beta_K and k_n were tuned (``engines/models/opensees.md``): first-impact
    r within 0.07 % of Housner's at 0.2-0.9 alpha (within 0.7 % at 0.01-0.19
    alpha) with k_n = 1.5e7 N/m, beta_K = 3.5e-4 s and 0.2 ms steps.
    """

    name = "opensees"

    #: Default settings, seed specimen (what they measure: docs/results.md#defaults-opensees).
    DEFAULTS: ClassVar[dict] = {
        "timestep": 2.0e-4,
        "contact_stiffness": 1.5e7,
        "contact_damping": 3.5e-4,
        "friction": 1.5,
        "tolerance": 1.0e-3,
        "impact_energy_factor": 1.0,
        "algorithm": "KrylovNewton",
        "contact_element": "zeroLengthContact2D",
    }
    #: The accuracy-cost frontier's axes (``housner frontier opensees``): the step [s], the contact
    #: springs' stiffness [N/m], the solution algorithm and the contact element.
    FRONTIER: ClassVar[dict] = {
        "timestep": (1e-4, 2e-4, 5e-4, 1e-3),
        "contact_stiffness": (5e6, 1.5e7, 5e7),
        "algorithm": _ALGORITHMS,
        "contact_element": _CONTACT_ELEMENTS,
    }
    CHOICES: ClassVar[dict] = {"algorithm": _ALGORITHMS, "contact_element": _CONTACT_ELEMENTS}

    RANGES: ClassVar[dict] = {
        **PIVOT_RANGES,
        "contact_stiffness": (1e4, 1e10),
        "contact_damping": (0.0, 1e-1),
        "tolerance": (1e-9, 1.0),
    }
    STRICT = ("timestep", "contact_stiffness", "impact_energy_factor")

    @classmethod
    def require(cls):
        return _opensees()

    @classmethod
    def tuning_candidates(cls, specimen: Specimen, target_r: float) -> list[dict]:
        """Contact damping beta_K for targets at or below Housner's r, a softer contact for targets above it.

        Measured on the seed specimen (``engines/models/opensees.md``): beta_K = 3.5e-4 s
        at k_n = 1.5e7 N/m gives Housner's r within 0.07 % at 0.2-0.9 alpha; 5e-4 s gives
        r = 0.944 (-0.25 %) at every amplitude; from 7e-4 s on r depends on the amplitude
        (0.940-0.951 at 1e-3 s) and no damping brings it to 0.90. A softer contact keeps
        more energy (k_n = 3e6 N/m: r = 0.954-0.957). Cheap (0.2 ms step) candidates first.
        """
        r_h, target = specimen.r_housner, float(target_r)
        if target > r_h * 1.002:
            return [dict(contact_stiffness=k) for k in (1.0e7, 6.0e6, 4.0e6, 3.0e6, 2.0e6)]
        if target >= r_h * 0.998:
            return [dict(), dict(contact_damping=4.0e-4), dict(contact_damping=3.0e-4), dict(timestep=1e-3 / 6)]
        return [dict(contact_damping=b) for b in (4.5e-4, 5.0e-4, 6.0e-4, 7.0e-4, 1.0e-3, 2.0e-3)]

    # ------------------------------------------------------------------
    def build(self, specimen: Specimen, motion: GroundMotion, step: float, offset: float = 0.0):
        """The OpenSees model of ``specimen`` under ``motion`` (steps 1-5 of ``engines/models/opensees.md``), at rest.

        Node tags: 1 centre of mass, 2 and 3 the corners at +B and -B (at B - e and -(B + e) for the
        ``offset`` e [m] of ``asymmetric_pivots``), 4 and 5 the ground under them. Returns the module.
        """
        ops = _opensees()
        s = self._settings
        H, B, m = specimen.H, specimen.B, specimen.mass
        bp, bn = pivot_x(B, offset)  # (B, -B) at offset 0
        k, beta = s["contact_stiffness"], s["contact_damping"]
        ops.wipe()
        ops.logFile(os.devnull, "-noEcho")  # OpenSees writes warnings to stderr: keep records quiet
        ops.model("basic", "-ndm", 2, "-ndf", 3)
        ops.node(1, 0.0, H)
        ops.node(2, bp, 0.0)
        ops.node(3, bn, 0.0)
        ops.node(4, bp, 0.0)
        ops.node(5, bn, 0.0)
        ops.fix(4, 1, 1, 1)
        ops.fix(5, 1, 1, 1)
        ops.mass(1, m, m, specimen.centroidal_inertia)
        ops.geomTransf("Corotational", 1)
        for tag, corner in ((1, 2), (2, 3)):
            ops.element("elasticBeamColumn", tag, 1, corner, 1.0, _BEAM_EA, _BEAM_EI / _BEAM_EA, 1)  # A = 1 m^2
        ops.uniaxialMaterial("Elastic", 1, k)  # flatSliderBearing's normal spring (it handles the uplift)
        ops.uniaxialMaterial("Elastic", 2, 0.0)  # no moment at the corner: a hinge
        ops.uniaxialMaterial("ENT", 3, k)  # the damped spring
        ops.frictionModel("Coulomb", 1, s["friction"])
        bearing = s["contact_element"] == "flatSliderBearing"
        for i, (ground, corner) in enumerate(((4, 2), (5, 3))):
            if bearing:
                ops.element(
                    "flatSliderBearing",
                    10 + i,
                    ground,
                    corner,
                    1,
                    _STICK_K,
                    "-P",
                    1,
                    "-Mz",
                    2,
                    "-orient",
                    0.0,
                    1.0,
                    0.0,
                    -1.0,
                    0.0,
                    0.0,
                )
            else:  # the corner is the constrained node, the ground's upward normal the retained side's
                ops.element(
                    "zeroLengthContact2D", 10 + i, corner, ground, k, _STICK_K, s["friction"], "-normal", 0.0, 1.0
                )
            ops.element("zeroLength", 20 + i, ground, corner, "-mat", 3, "-dir", 2, "-doRayleigh", 1)
        ops.rayleigh(0.0, beta, 0.0, 0.0)  # current stiffness: only the contact springs opt in
        ops.timeSeries("Path", 1, "-dt", motion.dt, "-values", *motion.acc.tolist())
        ops.pattern("UniformExcitation", 1, 1, "-accel", 1)
        ops.timeSeries("Constant", 2)
        ops.pattern("Plain", 2, 2)
        ops.load(1, 0.0, -m * G, 0.0)
        ops.constraints("Plain")
        ops.numberer("Plain")
        ops.system("BandGeneral")
        ops.test("NormUnbalance", s["tolerance"], _MAX_ITER)
        ops.algorithm(s["algorithm"])
        ops.integrator("Newmark", 0.5, 0.25)
        ops.analysis("Transient")
        return ops

    def _set_initial_state(self, ops, specimen: Specimen, motion: GroundMotion, offset: float = 0.0) -> None:
        """Nodes at the release: turned by theta0 about the pivot on its side, sunk by the static compression.

        With the pivots' ``offset`` e [m] (``asymmetric_pivots``) a block at rest on both carries
        m g b-/(2B) on the + corner and m g b+/(2B) on the - one: each corner sinks by its own
        load / (2 k_n), the block tilted rigidly between them.
        """
        H, B, m, k = specimen.H, specimen.B, specimen.mass, self._settings["contact_stiffness"]
        th0, om0 = motion.theta0, motion.theta_dot0
        x0, z0, dx0, dz0 = release_state(H, B, th0, om0, offset)
        on_one = th0 != 0.0 or om0 != 0.0
        sink = m * G / ((2.0 if on_one else 4.0) * k)  # weight on one pivot (two springs) or on both
        if offset != 0.0 and not on_one:
            self._set_asymmetric_rest(ops, specimen, offset)
            return
        c, sn = math.cos(th0), math.sin(th0)
        bp, bn = pivot_x(B, offset)  # (B, -B) at offset 0
        for node, bx in ((1, 0.0), (2, bp), (3, bn)):
            bz = -H if node != 1 else 0.0  # body frame, from the centre of mass
            rx, rz = bx * c + bz * sn, -bx * sn + bz * c  # Rot(theta) of the suite
            ux, uz = x0 + rx - bx, z0 + rz - H - bz - sink
            ops.setNodeDisp(node, 1, ux, "-commit")
            ops.setNodeDisp(node, 2, uz, "-commit")
            ops.setNodeDisp(node, 3, -th0, "-commit")
            if om0 != 0.0:  # rigid-body velocity; the rotation rate about +y is -omega_z of OpenSees
                ops.setNodeVel(node, 1, dx0 + om0 * rz, "-commit")
                ops.setNodeVel(node, 2, dz0 - om0 * rx, "-commit")
                ops.setNodeVel(node, 3, -om0, "-commit")

    def _set_asymmetric_rest(self, ops, specimen: Specimen, offset: float) -> None:
        """Nodes of a block at rest on both corners with the pivots' ``offset`` e [m]: the + corner sunk by
        d+ = m g b- / (2B) / (2 k_n), the - one by d- = m g b+ / (2B) / (2 k_n), the block turned rigidly
        about the + corner by theta = asin((d+ - d-) / (2B)) (theta > 0 lowers the + corner)."""
        H, B, m, k = specimen.H, specimen.B, specimen.mass, self._settings["contact_stiffness"]
        bp, bn = pivot_x(B, offset)
        d_pos, d_neg = (m * G * b / (2.0 * B) / (2.0 * k) for b in (-bn, bp))
        th = math.asin((d_pos - d_neg) / (2.0 * B))
        c, sn = math.cos(th), math.sin(th)
        for node, bx, bz in ((1, 0.0, 0.0), (2, bp, -H), (3, bn, -H)):
            rx, rz = bx - bp, bz + H  # from the + corner, body frame
            x, z = bp + rx * c + rz * sn, -d_pos - rx * sn + rz * c  # turned by th about the sunk + corner
            ops.setNodeDisp(node, 1, x - bx, "-commit")
            ops.setNodeDisp(node, 2, z - (bz + H), "-commit")
            ops.setNodeDisp(node, 3, -th, "-commit")

    def _simulate(self, specimen: Specimen, motion: GroundMotion, effects: tuple) -> Response:
        wall0 = time.perf_counter()
        k, h = substeps(motion.dt, self._settings["timestep"])
        e = pivot_offset(effects)
        ops = self.build(specimen, motion, h, e)
        self._set_initial_state(ops, specimen, motion, e)
        n = motion.n
        theta = np.empty(n)
        theta_dot = np.empty(n)
        theta[0], theta_dot[0] = motion.theta0, motion.theta_dot0
        last, overturned, retried, loose = n - 1, False, 0, 0
        analyze, disp, vel = ops.analyze, ops.nodeDisp, ops.nodeVel
        law = self.impact_law(specimen, effects, h, motion.theta0)
        with_law = law.active
        try:
            for i in range(1, n):
                if with_law:
                    stage = self._steps_with_law(ops, motion, i, k, h, law)
                elif analyze(k, h) == 0:
                    stage = 0
                else:
                    stage = self._retry(ops, motion, i, h)
                retried += stage > 0
                loose += stage == len(_RETRIES)
                x, th = disp(1, 1), -disp(1, 3)
                theta[i], theta_dot[i] = th, -vel(1, 3)
                if not (abs(x) < RUNAWAY_M and math.isfinite(th) and math.isfinite(x)):
                    raise self.diverged(motion, i, f"x = {x:.6g} m, theta = {th:.6g} rad")
                if abs(th) >= OVERTURN_ANGLE:
                    overturned, last = True, i
                    break
        finally:
            ops.wipe()
        wall = time.perf_counter() - wall0
        return self._response(
            specimen,
            motion,
            theta,
            theta_dot,
            last,
            overturned,
            h,
            k,
            wall,
            retried_samples=retried,
            loose_samples=loose,
        )

    def _steps_with_law(self, ops, motion: GroundMotion, i: int, k: int, h: float, law: ImpactLaw) -> int:
        """Sample interval i step by step, scaling every node's velocity at an impact; the retry stage that
        finished it (0: none was needed, see :meth:`_retry`)."""
        for _ in range(k):
            if ops.analyze(1, h) != 0:
                return self._retry(ops, motion, i, h)
            if (c := law.after_step(-ops.nodeDisp(1, 3), -ops.nodeVel(1, 3))) is not None:
                for node in (1, 2, 3):
                    for dof in (1, 2, 3):
                        ops.setNodeVel(node, dof, c * ops.nodeVel(node, dof), "-commit")
                ops.domainChange()  # the integrator reads the new velocities back from the nodes
        return 0

    def _retry(self, ops, motion: GroundMotion, i: int, h: float) -> int:
        """Redo the rest of sample interval i in shorter steps (Newton, then Krylov-Newton, then Krylov-Newton at a
        looser tolerance: :data:`_RETRIES`); returns the stage that finished it (1, 2, ...), or raises EngineError."""
        target, tol = i * motion.dt, self._settings["tolerance"]
        try:
            for stage, (divisor, algorithm, factor) in enumerate(_RETRIES, start=1):
                rest = target - ops.getTime()
                if rest <= 1e-12 * motion.dt:
                    return stage - 1
                steps = max(1, round(rest / (h / divisor)))
                ops.algorithm(algorithm)
                ops.test("NormUnbalance", tol * factor, _MAX_ITER)
                if ops.analyze(steps, rest / steps) == 0:
                    return stage
        finally:
            ops.algorithm(self._settings["algorithm"])
            ops.test("NormUnbalance", tol, _MAX_ITER)
        raise EngineError(
            f"OpenSees failed on motion {motion.name!r} at t = {ops.getTime():.6g} s: the iterations did not converge "
            f"even in steps of {h / max(d for d, _, _ in _RETRIES):.3g} s or at {_LOOSE:g} times the tolerance; try a "
            "smaller `timestep`"
        )
