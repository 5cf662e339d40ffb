"""DART (dartpy): the rocking block as a planar rigid body on a rigid ground, boxed-LCP contact.

:class:`DartEngine` builds the world for every run: the block on a ``PlanarJoint`` in the ZX plane, two
10 um sphere pivots on a fixed box ground, DART's rigid contact (a boxed LCP solved every step, with DART's
own collision detector), and the ground acceleration as a gravity component set before every step. The
model step by step is in ``engines/models/README.md`` ("DART (dartpy)", whose numbers the code cites) and
``docs/explanation/engines.md`` ("DART"); the settings and why, in :class:`DartEngine`; what they measure
and cost, in ``docs/results.md#defaults-dart``.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from housner.engines._planar import PIVOT_RANGES, PlanarEngine, gravity_x, pivot_offset, pivot_x
from housner.motion import GroundMotion
from housner.specimen import Specimen
from housner.units import G

__all__ = ["DartEngine"]


class DartEngine(PlanarEngine):
    """DART's rigid block on a rigid ground with boxed-LCP contact, driven by the d'Alembert force.

    Parameters
    ----------
    restitution : float
        Newton restitution coefficient at the pivots [-]; 0 is Housner's plastic impact.
    collision_detector : {"dart", "fcl", "bullet", "ode"}
        The collision detector (Notes): DART's own (default) or the one of FCL (DART's default), Bullet
        or ODE.
    timestep, friction, pivot_radius, impact_energy_factor
        As :class:`housner.engines._planar.PlanarEngine`'s, which also shows how an adapter is driven.

    Notes
    -----
    The pivots have restitution 0 (Housner's plastic impact) and Coulomb friction mu = 1.5. The contact
    is DART's default rigid contact, a boxed LCP (Dantzig) solved every step; impacts are velocity-level
    impulses, so no contact stiffness or damping needs tuning. Collisions are found by DART's own detector
    (``collision_detector`` "dart": ``DARTCollisionDetector``, which handles sphere-box pairs), not DART's
    default FCL: the same first-impact r and impact counts at less CPU time (docs/results.md#defaults-dart).
    With these settings and a 0.1 ms step the first impact's energy ratio after releases at 0.2, 0.5 and
    0.8 alpha is within 0.1 % of Housner's r for the seed specimen (``tests/test_dart.py``), without any
    tuning.
    """

    name = "dart"

    #: Default settings, with no tuning (why a 0.1 ms step: docs/results.md#defaults-dart).
    DEFAULTS: ClassVar[dict] = {
        "timestep": 1.0e-4,
        "friction": 1.5,
        "restitution": 0.0,
        "pivot_radius": 1.0e-5,
        "impact_energy_factor": 1.0,
        "collision_detector": "dart",
    }
    #: The collision detectors offered (``collision_detector``): dartpy's class of each.
    DETECTORS: ClassVar[dict] = {
        "dart": "DARTCollisionDetector",
        "fcl": "FCLCollisionDetector",
        "bullet": "BulletCollisionDetector",
        "ode": "OdeCollisionDetector",
    }
    #: The accuracy-cost frontier's axes (``housner frontier dart``): the step [s], the radius of
    #: the pivot spheres [m] (the contact's geometry: DART's contact is rigid, an LCP) and the detector.
    FRONTIER: ClassVar[dict] = {
        "timestep": (5e-5, 1e-4, 1.25e-4, 2e-4, 4e-4),
        "pivot_radius": (1e-6, 1e-5, 1e-4),
        "collision_detector": ("dart", "fcl"),
    }

    MODULE = "dartpy"
    RANGES: ClassVar[dict] = {
        **PIVOT_RANGES,
        "restitution": (0.0, 1.0),
        "pivot_radius": (1e-7, 1e-2),
    }
    CHOICES: ClassVar[dict] = {"collision_detector": DETECTORS}

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
    def build(self, specimen: Specimen, step: float, offset: float = 0.0):
        """The DART world of ``specimen`` (steps 1-5 of engines/models/README.md, "DART") and the block's skeleton;
        the pivots at x = B - e and -(B + e) of the centre of mass for ``offset`` e [m] (``asymmetric_pivots``)."""
        dart = self.require()
        H, B, m = specimen.H, specimen.B, specimen.mass
        rho = self._pivot_radius(specimen)
        world = dart.simulation.World()
        world.setGravity([0.0, 0.0, -G])
        world.setTimeStep(step)
        detector = getattr(dart.collision, self.DETECTORS[self._settings["collision_detector"]])
        world.getConstraintSolver().setCollisionDetector(detector())  # step 5
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
        for x in pivot_x(B, offset):  # (B, -B) at offset 0
            _collider(dart, body, dart.dynamics.SphereShape(rho), (x, 0.0, -H + rho), self._settings)
        world.addSkeleton(block)
        return world, block

    def _stepper(self, specimen: Specimen, motion: GroundMotion, effects: tuple, states, k: int, h: float):
        world, block = self.build(specimen, h, pivot_offset(effects))
        block.setPositions(states[0, :3].tolist())
        block.setVelocities(states[0, 3:].tolist())
        gx_rows = gravity_x(motion.acc, k)  # step 1 of engines/models/README.md, "DART"
        # Gravity set before each step from its three components: dartpy's (x, y, z) overload takes 0.3 us where
        # an ndarray converted to its Eigen vector takes 1.0 us (a list 1.6 us), the same numbers.
        set_gravity, step, gz = world.setGravity, world.step, -G
        after = self.impact_law(specimen, effects, h, motion.theta0).step_hook

        def advance(i: int) -> np.ndarray:
            for gxi in gx_rows[i - 1]:
                set_gravity(gxi, 0.0, gz)
                step()
                if after is not None and (c := after(block.getPosition(2), block.getVelocity(2))) is not None:
                    block.setVelocities(c * block.getVelocities())
            q = states[i, :3] = block.getPositions()
            states[i, 3:] = block.getVelocities()
            return q

        return advance


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
