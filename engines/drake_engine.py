"""Drake (pydrake): the rocking block as a planar body on a stiff point contact, TAMSI discrete solver.

:class:`DrakeEngine` builds a discrete ``MultibodyPlant`` once per specimen and step and reuses it for every
record: the block on a ``PlanarJoint`` whose coordinates are (z, x, theta), two 10 um sphere pivots on a
fixed box ground, point contact solved by TAMSI (or SAP), the d'Alembert force of the ground acceleration
on the x coordinate, the plant's discrete update stepped directly so that the state lands on the sample
times. The model step by step is in ``engines/models/drake.md`` ("Derivation, step by step", whose numbers
the code cites) and ``docs/explanation/engines.md`` ("Drake"); the contact settings and why, in
:class:`DrakeEngine`; what they measure and cost, in ``docs/results.md#defaults-drake``.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from housner.engines._planar import PIVOT_RANGES, PlanarEngine, gravity_steps, pivot_offset, pivot_x
from housner.errors import EngineError
from housner.motion import GroundMotion
from housner.specimen import Specimen
from housner.units import G

__all__ = ["DrakeEngine"]


def _drake() -> Any:
    """pydrake's multibody plant module (the first the engine needs), or an EngineUnavailable naming the install."""
    return DrakeEngine.require()


class DrakeEngine(PlanarEngine):
    """Drake's block on a stiff point contact (TAMSI solver by default), driven by the d'Alembert force.

    Parameters
    ----------
    stiffness : float
        Point-contact stiffness of each pivot on the ground [N/m] (the pair's
        combined value; each side of the pair is given twice it).
    relaxation_time : float
        SAP's linear dissipation time of the pivot contact [s] (the pair's
        combined value; each side carries half of it). 0 is no dissipation
        beyond the implicit step's. Only ``"sap"`` uses it: the other solvers
        refuse a non-zero one.
    dissipation : float
        Hunt-Crossley dissipation of the pivot contact [s/m] (each side
        carries it), which ``"tamsi"``, ``"lagged"`` and ``"similar"`` use.
    contact_approximation : {"tamsi", "sap", "lagged", "similar"}
        Drake's discrete contact solver (Notes).
    stiction_tolerance : float
        Sliding speed below which TAMSI's regularised friction sticks [m/s].
    timestep, friction, pivot_radius, impact_energy_factor
        As :class:`housner.engines._planar.PlanarEngine`'s, which also shows how an adapter is driven.

    Notes
    -----
    The step h is ``timestep``, 1/8 ms: each sample interval cut into the fewest
    equal steps no longer than it. The pivots carry Coulomb friction mu = 1.5
    (Drake combines the pair's coefficients as 2 mu1 mu2 / (mu1 + mu2), so both
    carry mu). The contact is point contact (``ContactModel.kPoint``) with the
    pair's stiffness k (``stiffness``, 2.5e9 N/m per pivot), solved by the
    discrete solver ``contact_approximation`` names:

    * ``"tamsi"`` (default, ``DiscreteContactApproximation.kTamsi``): TAMSI,
      Hunt-Crossley dissipation d (``dissipation``, 50 s/m: Drake's own value
      when none is given, drake 1.51.1) and regularised Coulomb friction that
      lets a pivot creep below ``stiction_tolerance`` (1e-4 m/s, Drake's default);
    * ``"sap"`` (``kSap``): SAP, a convex implicit contact solver, with linear
      (Kelvin-Voigt) dissipation time tau (``relaxation_time``, 0 s) in place of d;
    * ``"lagged"``, ``"similar"``: SAP's convex solver on the Hunt-Crossley d.

    Drake combines a pair's stiffnesses in series, k1 k2 / (k1 + k2), and
    adds their relaxation times (and gives each geometry tau = 0.1 s when
    unset), so the ground and the pivots each carry 2 k, d and tau / 2. With
    k = 2.5e9 N/m, sqrt(k / m) h = 3.1 at h = 1/8 ms: the contact is far too
    stiff for the step to resolve, the solver treats it as near-rigid and ends
    each impact within a step or two without a rebound, Housner's plastic
    impact. The stiffness still matters before uplift: the block's elastic
    tilt on softer pivots starts the rocking early (5e7 N/m: first pulse
    peaks 1-2 % high; 5e8 and 2.5e9 N/m: within 0.3 %). Under TAMSI the
    softer 5e8 N/m also overturned the block less often than the analytic
    model on ``elcentro-strong`` (34 of 100 motions against 42; 2.5e9 N/m: 38;
    SAP at 5e8 N/m: 41), and checked worse on the free decay (3.5 % against 1.5 %).
    Why TAMSI at 1/8 ms on 2.5e9 N/m is the default: docs/results.md#defaults-drake.

    With these settings the first impact's energy ratio after releases at 0.2,
    0.5 and 0.8 alpha is within 0.2 % of Housner's r for the seed specimen
    (``tests/test_drake.py``; ``engines/models/drake.md`` has the measurements).

    References
    ----------
    Drake: https://drake.mit.edu (MultibodyPlant, PlanarJoint, SAP: Castro, A. et
    al. (2022). An unconstrained convex formulation of compliant contact. IEEE
    Transactions on Robotics 39(2), 1301-1320).
    """

    name = "drake"

    #: Default settings, with no tuning (what they measure: docs/results.md#defaults-drake).
    DEFAULTS: ClassVar[dict] = {
        "timestep": 1.25e-4,
        "stiffness": 2.5e9,
        "relaxation_time": 0.0,
        "friction": 1.5,
        "pivot_radius": 1.0e-5,
        "impact_energy_factor": 1.0,
        "dissipation": 50.0,
        "contact_approximation": "tamsi",
        "stiction_tolerance": 1.0e-4,
    }
    #: The accuracy-cost frontier's axes (``housner frontier drake``): the step [s], the point
    #: contact's stiffness [N/m] and the contact solver.
    FRONTIER: ClassVar[dict] = {
        "timestep": (6.25e-5, 1.25e-4, 2.5e-4, 5e-4),
        "stiffness": (5e8, 2.5e9, 1e10),
        "contact_approximation": ("tamsi", "sap"),
    }

    MODULE = "pydrake.multibody.plant"
    RANGES: ClassVar[dict] = {
        **PIVOT_RANGES,
        "stiffness": (1e3, 1e12),
        "relaxation_time": (0.0, 1.0),
        "pivot_radius": (1e-7, 1e-2),
        "dissipation": (0.0, 1e4),
        "stiction_tolerance": (1e-9, 1.0),
    }
    #: Drake's discrete contact solvers this adapter offers (``contact_approximation``).
    APPROXIMATIONS: ClassVar[dict] = {"sap": "kSap", "tamsi": "kTamsi", "lagged": "kLagged", "similar": "kSimilar"}
    CHOICES: ClassVar[dict] = {"contact_approximation": APPROXIMATIONS}

    def __init__(self, **settings: Any):
        super().__init__(**settings)
        a = self._settings["contact_approximation"]
        if a != "sap" and self._settings["relaxation_time"] > 0.0:
            raise ValueError(
                f"Drake setting `relaxation_time` is SAP's dissipation; {a!r} ignores it: give "
                "`contact_approximation='sap'` with it, or `dissipation` (Hunt-Crossley) instead"
            )
        self._model = None  # (key, plant, diagram context, plant context, input vector), built on first use

    @classmethod
    def tuning_candidates(cls, specimen: Specimen, target_r: float) -> list[dict]:
        """Settings to try when tuning the contact to an energy ratio, cheap to expensive.

        Within 0.2 % of Housner's r: the stiff default contact on TAMSI at 1/8 and
        1/10 ms, then SAP at 1/4 ms on 5e8 N/m (the earlier defaults). TAMSI's
        free decay moves with the step by more than its r does, so the coarser steps are not
        offered. Away from Housner's r the contact is SAP's at 1/4 ms, whose
        stiffness and dissipation time were measured there. Above it: softer
        undamped pivots, which give part of the impact's energy back. Below it: softer
        pivots with SAP's linear dissipation, the only knob that takes more
        energy at an impact; none keeps r flat below about 0.94, and soft pivots tilt before
        uplift, which puts the pulses' first peaks 14-170 % off; the tuner then reports the
        closest it found. The figures: docs/results.md#defaults-drake.
        Returns keyword settings of :class:`DrakeEngine` (at most 8) for ``target_r``,
        the target kinetic-energy ratio at impact [-].
        """
        r_h = specimen.r_housner
        sap = dict(contact_approximation="sap", timestep=2.5e-4, stiffness=5e8)
        if target_r > r_h * 1.002:
            out = [dict(sap, stiffness=k) for k in (1e7, 7e6, 5e6, 3.5e6, 2.5e6)]
            return out + [dict(sap, stiffness=k, relaxation_time=1e-4) for k in (5e6, 3.5e6)]
        if target_r < r_h * 0.998:
            pairs = (
                (5e6, 5e-4),
                (5e6, 2e-3),
                (2e6, 1e-3),
                (2e6, 3e-3),
                (1e6, 2e-3),
                (1e6, 6e-3),
                (5e5, 6e-3),
                (5e5, 2e-2),
            )
            return [dict(sap, stiffness=k, relaxation_time=tau) for k, tau in pairs]
        return [dict(), dict(timestep=1e-4), sap]

    # ------------------------------------------------------------------
    def build(self, specimen: Specimen, step: float, offset: float = 0.0):
        """Drake's diagram of ``specimen`` (steps 1-5 of ``engines/models/drake.md``) and the block's plant; the pivots
        at x = B - e and -(B + e) of the centre of mass for ``offset`` e [m] (``asymmetric_pivots``).

        Returns
        -------
        tuple
            (diagram, plant): a ``MultibodyPlant`` with step ``step`` [s] inside a
            diagram with its ``SceneGraph``.
        """
        _drake()
        from pydrake.geometry import AddContactMaterial, Box, ProximityProperties, Sphere  # optional engine
        from pydrake.math import RigidTransform, RotationMatrix  # optional engine
        from pydrake.multibody.plant import (  # optional engine
            AddMultibodyPlantSceneGraph,
            ContactModel,
            CoulombFriction,
            DiscreteContactApproximation,
        )
        from pydrake.multibody.tree import FixedOffsetFrame, PlanarJoint, SpatialInertia, UnitInertia  # optional engine
        from pydrake.systems.framework import DiagramBuilder  # optional engine

        s = self._settings
        H, B, m = specimen.H, specimen.B, specimen.mass
        rho = self._pivot_radius(specimen)
        builder = DiagramBuilder()
        plant, _ = AddMultibodyPlantSceneGraph(builder, time_step=step)
        plant.set_discrete_contact_approximation(
            getattr(DiscreteContactApproximation, self.APPROXIMATIONS[s["contact_approximation"]])
        )
        plant.set_stiction_tolerance(s["stiction_tolerance"])
        plant.set_contact_model(ContactModel.kPoint)
        plant.SetUseSampledOutputPorts(False)
        plant.mutable_gravity_field().set_gravity_vector([0.0, 0.0, -G])  # Drake's default is 9.81
        ic = specimen.centroidal_inertia / m
        body = plant.AddRigidBody("block", SpatialInertia(m, np.zeros(3), UnitInertia(ic, ic, ic)))
        # Joint frames: x = world z, y = world x, z = world y (step 2 of engines/models/drake.md).
        axes = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])  # columns: world z, x, y
        turn = RigidTransform(RotationMatrix(axes), np.zeros(3))
        frame_f = plant.AddFrame(FixedOffsetFrame("plane_on_world", plant.world_frame(), turn))
        frame_m = plant.AddFrame(FixedOffsetFrame("plane_on_block", body.body_frame(), turn))
        plant.AddJoint(PlanarJoint("planar", frame_f, frame_m))

        def material() -> ProximityProperties:
            # Drake combines a pair's stiffnesses in series and adds its relaxation times (step 5).
            props = ProximityProperties()
            mu = s["friction"]
            AddContactMaterial(s["dissipation"], 2.0 * s["stiffness"], CoulombFriction(mu, mu), props)
            props.AddProperty("material", "relaxation_time", 0.5 * s["relaxation_time"])
            return props

        ground = Box(100.0 * H, 100.0 * H, 1.0)
        register = plant.RegisterCollisionGeometry
        register(plant.world_body(), RigidTransform([0.0, 0.0, -0.5]), ground, "ground", material())
        for x, label in zip(pivot_x(B, offset), ("pivot+x", "pivot-x"), strict=True):  # (B, -B) at offset 0
            register(body, RigidTransform([x, 0.0, -H + rho]), Sphere(rho), label, material())
        plant.Finalize()
        return builder.Build(), plant

    def _model_for(self, specimen: Specimen, step: float, offset: float = 0.0):
        """The cached (plant, plant context, applied-force vector) of ``specimen`` at ``step`` with the pivots'
        ``offset`` [m], built if new."""
        key = (specimen.H, specimen.B, specimen.mass, specimen.centroidal_inertia, step, offset)
        if self._model is None or self._model[0] != key:
            diagram, plant = self.build(specimen, step, offset)
            root = diagram.CreateDefaultContext()
            ctx = plant.GetMyMutableContextFromRoot(root)
            fixed = plant.get_applied_generalized_force_input_port().FixValue(ctx, np.zeros(3))
            # diagram and root context are kept: the plant context lives inside them
            self._model = (key, plant, ctx, fixed.GetMutableData().get_mutable_value(), diagram, root)
        return self._model[1:4]

    def _stepper(self, specimen: Specimen, motion: GroundMotion, effects: tuple, states, k: int, h: float):
        plant, ctx, force = self._model_for(specimen, h, pivot_offset(effects))
        plant.SetPositionsAndVelocities(ctx, states[0].tolist())
        force.SetFromVector(np.zeros(3))
        fx_rows = (specimen.mass * gravity_steps(motion.acc, k)).tolist()  # step 6: m times the mean of -ug''
        # One step is the plant's forced discrete update, computed into values allocated once and stored in the
        # context: what ExecuteForcedEvents does, less the state and values it allocates at every call (10 % of a
        # step), the same numbers. The force is written into the fixed input's vector, which SetAtIndex also does.
        update = plant.AllocateDiscreteVariables()
        calc, store, state = plant.CalcForcedDiscreteVariableUpdate, ctx.SetDiscreteState, ctx.get_discrete_state_vector
        force_xyz = force.get_mutable_value()  # a view of the input's vector: [1] is the x coordinate's force
        after = self.impact_law(specimen, effects, h, motion.theta0).step_hook

        def advance(i: int) -> np.ndarray:
            try:
                for fx in fx_rows[i - 1]:
                    force_xyz[1] = fx
                    calc(ctx, update)
                    store(update)
                    if after is not None and (c := after(state().GetAtIndex(2), state().GetAtIndex(5))) is not None:
                        plant.SetVelocities(ctx, c * plant.GetVelocities(ctx))
            except RuntimeError as e:  # the contact solver did not converge
                raise EngineError(
                    f"Drake failed on motion {motion.name!r} at t = {i * motion.dt:.6g} s: {e}; "
                    "try a smaller `timestep` or a softer `stiffness`"
                ) from None
            q = states[i] = state().value()
            return q

        return advance
