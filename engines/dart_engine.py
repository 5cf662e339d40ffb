"""DART (dartpy): the rocking block as a planar rigid body on a rigid ground, boxed-LCP contact.

The model, built from a :class:`housner.Specimen` for every run (numbered as in
``engines/models/README.md``, section DART):

1. World: gravity -g along z (g = 9.80665 m/s^2); the ground acceleration
   enters as the d'Alembert body force -m ug''(t), i.e. a gravity component
   g_x = -ug''(t) along x, set before every step to the exact mean of the
   linearly interpolated ug'' over that step. The ground itself does not move.
2. Ground: a fixed box, its top face the pivot line z = 0.
3. Block: one body, centre of mass at its frame origin, on a ``PlanarJoint``
   in the ZX plane (dofs z, x and the rotation about +y, which is the suite's
   theta: theta > 0 turns the top toward +x, rocking on the +x pivot).
   Mass m, inertia about the centre of mass I_c = I0 - m R^2 on all three axes
   (only the one about y enters the planar motion), so p = sqrt(m g R / I0).
4. Pivots: the only collision shapes, two spheres of radius rho = 10 um at
   (+-B, -H + rho) in the body frame, touching the ground at (+-B, 0) when the
   block stands upright: one contact point per pivot, as in Housner's model.
   Restitution 0 (Housner's plastic impact), Coulomb friction mu = 1.5.
5. Contact: DART's default rigid contact, a boxed LCP (Dantzig) solved every
   step with the FCL collision detector; impacts are velocity-level impulses,
   so no contact stiffness or damping needs tuning.

With these settings and a 0.1 ms step the first impact's energy ratio after
releases at 0.2, 0.5 and 0.8 alpha is within 0.1 % of Housner's r for the
seed specimen (``tests/test_dart.py``), without any tuning.

References
----------
DART: Dynamic Animation and Robotics Toolkit, https://dartsim.github.io
(PlanarJoint, BoxedLcpConstraintSolver).
Housner, G. W. (1963). BSSA 53(2), 403-417.
Bachmann, J. A. et al. (2017). COMPDYN 2017, section 3.1 and eq. 8.
"""

from __future__ import annotations

import math
import time
from typing import Any, ClassVar

import numpy as np
from housner.engines._planar import (
    IMPACT_LAW_RANGE,
    ImpactLawEngine,
    checked_settings,
    gravity_x,
    release_state,
    sampled_response,
    substeps,
)
from housner.engines.base import Engine

from housner.errors import EngineError, EngineUnavailable
from housner.motion import GroundMotion
from housner.response import Response
from housner.specimen import Specimen
from housner.units import G

__all__ = ["DartEngine", "OVERTURN_ANGLE", "ROCKING_TOL", "INSTALL"]

#: How to install the package this engine needs (named in the error when it is missing).
INSTALL = "pip install -e '.[dart]'  (or: pip install dartpy)"

#: |theta| above ROCKING_TOL * alpha counts as rocking [-] (impact and uplift detection); below it
#: the block is at rest. The rigid contact tilts the block at rest by less than 1e-6 alpha.
ROCKING_TOL = 5e-3

#: |theta| at which the block has fallen [rad]; the engine stops and holds theta there.
OVERTURN_ANGLE = math.pi / 2

#: A centre of mass farther than this from its start [m] has run away (slid off or diverged).
_RUNAWAY_M = 10.0

#: Fraction of the rocking threshold taken as "still at rest" when dating the uplift.
_QUIET = 2e-3

#: Accepted range of each setting (low, high); the timestep's low end excluded.
_RANGES = {
    "timestep": (1e-6, 1e-2),
    "friction": (0.0, 100.0),
    "restitution": (0.0, 1.0),
    "pivot_radius": (1e-7, 1e-2),
    "impact_energy_factor": IMPACT_LAW_RANGE,
}


def _dart():
    """The dartpy module, or an EngineError naming the install command."""
    try:
        import dartpy
    except ImportError as e:
        raise EngineUnavailable(f"engine 'dart' needs the dartpy package ({e}); install it with: {INSTALL}") from None
    return dartpy


class DartEngine(ImpactLawEngine, Engine):
    """DART's rigid block on a rigid ground with boxed-LCP contact, driven by the d'Alembert force.

    Parameters
    ----------
    timestep : float
        Longest step [s]: each sample interval of a motion is cut into the
        fewest equal steps no longer than this.
    friction : float
        Coulomb friction coefficient pivot/ground [-]; it must exceed
        max |ug''| / g with a margin for the impacts.
    restitution : float
        Newton restitution coefficient at the pivots [-]; 0 is Housner's plastic impact.
    pivot_radius : float
        Radius of the pivot spheres [m], at most 1e-3 H.
    impact_energy_factor : float
        Energy the block keeps at each impact as a fraction of what the
        contact leaves it [-], in (0, 1]: the adapters' impact law
        (:class:`housner.engines._planar.ImpactLaw`) for an r below the contact's own.
        1 (default): the contact alone.

    Examples
    --------
    >>> from housner.engines import get_engine
    >>> from housner import GroundMotion, Specimen
    >>> spec = Specimen.bachmann2017()
    >>> released = GroundMotion.free_vibration(0.3 * spec.alpha, 2.0)  # from rest at 0.3 alpha, 2 s
    >>> get_engine("dart").simulate(spec, released).n_impacts > 3
    True
    """

    name = "dart"
    package = "dartpy"
    effects_supported: ClassVar[frozenset[str]] = frozenset({"restitution"})

    #: Default settings (2026-11-24, dartpy 6.20, seed specimen): first-impact r within 0.1 % of
    #: Housner's at 0.2, 0.5 and 0.8 alpha with no tuning (step 0.1 ms; 0.2 ms is 0.11 % off at 0.8 alpha).
    DEFAULTS: ClassVar[dict] = {
        "timestep": 1.0e-4,
        "friction": 1.5,
        "restitution": 0.0,
        "pivot_radius": 1.0e-5,
        "impact_energy_factor": 1.0,
    }

    def __init__(self, **settings: Any):
        _dart()  # a missing package is said before any long work
        self._settings = checked_settings(
            "DART", self.DEFAULTS, _RANGES, settings, strict=("timestep", "impact_energy_factor")
        )

    def __getstate__(self) -> dict:
        return {"settings": dict(self._settings)}

    def __setstate__(self, state: dict) -> None:
        self.__init__(**state["settings"])

    @classmethod
    def tuning_candidates(cls, specimen: Specimen, target_r: float) -> list[dict]:
        """Steps of 1/10 to 1/2 ms (they divide the tuner's 1 ms samples), the rest at the defaults.

        The rigid contact has no stiffness or damping to tune: the step is the only knob,
        and a restitution above 0 the only way to give energy back at an impact (tried
        when the target lies above Housner's r).
        """
        steps = [1e-3 / n for n in (2, 3, 4, 5, 6, 8, 10)]
        out = [dict(timestep=h) for h in steps]
        if target_r > specimen.r_housner * 1.001:
            out += [dict(timestep=h, restitution=e) for h in steps[-3:] for e in (0.05, 0.1, 0.2)]
        return out

    # ------------------------------------------------------------------
    def build(self, specimen: Specimen, step: float):
        """The DART world of ``specimen`` (steps 1-5 of the module docstring) and the block's skeleton."""
        dart = _dart()
        H, B, m = specimen.H, specimen.B, specimen.mass
        rho = self._settings["pivot_radius"]
        if rho > 1e-3 * H:
            raise ValueError(f"DART setting `pivot_radius` ({rho:g} m) must be at most 1e-3 H = {1e-3 * H:g} m")
        world = dart.simulation.World()
        world.setGravity([0.0, 0.0, -G])
        world.setTimeStep(step)
        ground = dart.dynamics.Skeleton("ground")
        _, gbody = ground.createWeldJointAndBodyNodePair()
        _collider(dart, gbody, dart.dynamics.BoxShape([100.0 * H, 100.0 * H, 1.0]), (0.0, 0.0, -0.5), self._settings)
        world.addSkeleton(ground)
        block = dart.dynamics.Skeleton("block")
        props = dart.dynamics.PlanarJointProperties()
        props.mName = "planar"
        joint, body = block.createPlanarJointAndBodyNodePair(None, props)
        joint.setZXPlane()  # dofs: z, x, rotation about +y
        ic = specimen.centroidal_inertia
        body.setInertia(dart.dynamics.Inertia(m, [0.0, 0.0, 0.0], np.diag([ic, ic, ic])))
        for side in (1.0, -1.0):
            _collider(dart, body, dart.dynamics.SphereShape(rho), (side * B, 0.0, -H + rho), self._settings)
        world.addSkeleton(block)
        return world, block

    def _simulate(self, specimen: Specimen, motion: GroundMotion, effects: tuple) -> Response:
        wall0 = time.perf_counter()
        k, h = substeps(motion.dt, self._settings["timestep"])
        world, block = self.build(specimen, h)
        th0, om0 = motion.theta0, motion.theta_dot0
        x0, z0, dx0, dz0 = release_state(specimen.H, specimen.B, th0, om0)
        block.setPositions([z0, x0, th0])
        block.setVelocities([dz0, dx0, om0])
        gx_rows = gravity_x(motion.acc, k)  # step 1 of the module docstring
        n = motion.n
        states = np.empty((n, 6))
        states[0] = (z0, x0, th0, dz0, dx0, om0)
        last, overturned = n - 1, False
        set_gravity, step = world.setGravity, world.step
        law = self.impact_law(specimen, effects, h, th0)
        for i in range(1, n):
            for gxi in gx_rows[i - 1]:
                set_gravity([gxi, 0.0, -G])
                step()
                if law.active and (c := law.after_step(block.getPosition(2), block.getVelocity(2))) is not None:
                    block.setVelocities(c * block.getVelocities())
            q, v = block.getPositions(), block.getVelocities()
            states[i, :3], states[i, 3:] = q, v
            if not (abs(q[1] - x0) < _RUNAWAY_M and abs(q[0]) < _RUNAWAY_M and np.isfinite(q).all()):
                raise EngineError(
                    f"DART failed on motion {motion.name!r} at t = {i * motion.dt:.6g} s: the state is not finite "
                    f"or ran away (x = {q[1]:.6g} m, z = {q[0]:.6g} m, theta = {q[2]:.6g} rad); a block that "
                    "slides needs more `friction`, one that diverges a smaller `timestep`"
                )
            if abs(q[2]) >= OVERTURN_ANGLE:
                overturned, last = True, i
                break
        return self._response(specimen, motion, states, last, overturned, h, k, time.perf_counter() - wall0)

    def _response(self, specimen, motion, states, last, overturned, h, k, wall) -> Response:
        """The Response from the sampled states (z, x, theta, z', x', theta'), held at +-pi/2 after an overturn."""
        info = {
            "settings": self.settings(),
            "version": self.version(),
            "step": h,
            "steps_per_sample": k,
            "n_steps": last * k,
            "wall_time_s": wall,
        }
        return sampled_response(self, specimen, motion, states[:, 2].copy(), states[:, 5].copy(), last, overturned,
                                info, rocking_tol=ROCKING_TOL, quiet=_QUIET, overturn_angle=OVERTURN_ANGLE)  # fmt: skip


def _collider(dart, body, shape, pos, settings: dict) -> None:
    """A collision shape on ``body`` at ``pos`` [m] in its frame, with the pivots' restitution and friction."""
    node = body.createShapeNode(shape)
    node.createCollisionAspect()
    dyn = node.createDynamicsAspect()
    dyn.setRestitutionCoeff(settings["restitution"])
    dyn.setFrictionCoeff(settings["friction"])
    tf = dart.math.Isometry3()
    tf.set_translation(list(pos))
    node.setRelativeTransform(tf)
