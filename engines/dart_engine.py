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
   Restitution 0 (Housner's plastic impact), Coulomb friction mu = 1.5. With the
   effect ``asymmetric_pivots`` (centre of mass e toward +x of the pivots'
   midpoint) the spheres sit at x = B - e and -(B + e), mass and I_c unchanged.
5. Contact: DART's default rigid contact, a boxed LCP (Dantzig) solved every
   step; impacts are velocity-level impulses, so no contact stiffness or
   damping needs tuning. Collisions are found by DART's own detector
   (``collision_detector`` "dart": ``DARTCollisionDetector``, which handles
   sphere-box pairs), not DART's default FCL: the same first-impact r and
   impact counts at less CPU time (docs/results.md#defaults-dart).

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
        The collision detector (step 5 of the module docstring): DART's own (default) or the one of
        FCL (DART's default), Bullet or ODE.
    timestep, friction, pivot_radius, impact_energy_factor
        As :class:`housner.engines._planar.PlanarEngine`'s, which also shows how an adapter is driven.
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
        """The DART world of ``specimen`` (steps 1-5 of the module docstring) and the block's skeleton; the
        pivots at x = B - e and -(B + e) of the centre of mass for ``offset`` e [m] (``asymmetric_pivots``)."""
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
        gx_rows = gravity_x(motion.acc, k)  # step 1 of the module docstring
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
