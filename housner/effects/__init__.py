"""Physical effects: small pluggable additions to the analytic rocking model.

An *effect* is a frozen dataclass whose fields are its parameters. Each field
says, once, what its parameter means (:func:`param`, a field carrying a
:class:`ParamSpec`: unit, bounds for fitting, the neutral value at which the
effect does nothing, its default) and the class overrides only the hooks it
needs; the others are no-ops:

``modify_params(params, specimen)``
    returns a changed :class:`housner.rocking_params.RockingParams` (restitution,
    amplitude-dependent restitution, rotational damping, asymmetric pivots,
    frequency parameter);
``transform_input(motion)``
    returns the ground motion the block really feels;
``observe(response)``
    returns what a sensor would record (angle offset, channel time lag);
``terms(params, specimen)``
    returns terms of the one compiled analytic kernel (:mod:`housner.effects.terms`):
    an extra moment (damping, drag, a vertical input), a dry (Coulomb) moment that
    makes the block stick and raises its uplift threshold, a change of the impact
    law. Terms of several effects compose in one kernel;
``solver()``
    returns a different equation of motion, a callable
    ``solve(specimen, motion, params, *, substeps=None, rest_tol=1e-6) -> Response``,
    for the effects that change the mechanics beyond terms (flexible foundation,
    sliding: other degrees of freedom); None keeps Housner's rigid block.

An effect that reads an extra measured channel of the motion (``GroundMotion.channels``,
e.g. ``"ground_acc_vertical"``) names it in its ``channels``; a motion without it is
refused by name before any simulation.

Effects live in the registry :data:`EFFECTS` (name -> class). Add your own
with the :func:`register_effect` decorator, from a file with
:func:`load_plugin` (``examples/effects/*.py``), or from an installed package
through the entry-point group ``housner.effects`` (each entry point names an
:class:`Effect` subclass, or a module that registers its effects on import)::

    @register_effect
    @dataclass(frozen=True)
    class TableFilter(Effect):
        name = "table_filter"
        gain: float = param("-", (0.5, 1.5), neutral=1.0, default=1.0, doc="table gain")

        def transform_input(self, motion):
            return motion.scaled(amplitude=self.gain)

An effect whose fields carry no :func:`param` may give its table instead, as a class
attribute ``params = {"gain": ParamSpec("-", (0.5, 1.5), 1.0, 1.0, "table gain")}``
(one :class:`ParamSpec` per field); :attr:`Effect.param_specs` reads either.

Composition (:func:`apply_effects`): effects are applied in the order of
their ``stage`` (geometry, inertia, dissipation, mechanics, sensor) and,
within a stage, in the order given, so that the built-in effects commute:

1. ``modify_params`` of every effect, starting from
   ``RockingParams.from_specimen(specimen)``: ``asymmetric_pivots`` sets the
   per-corner alpha, p and the impact loss from the geometry, then
   ``frequency_parameter`` scales p, then ``restitution`` replaces r,
   ``amplitude_dependent_restitution`` sets the exponent and
   ``rotational_damping`` adds its rate;
2. ``transform_input`` of every effect;
3. ``terms`` of every effect, from the final parameters, in that order; the
   solver: Housner's kernel with those terms (``housner.model.simulate``), or
   the one mechanics effect's; at most one mechanics-changing effect may be
   given, and it takes no terms (those kernels do not compose: a block that
   both slides and sits on springs would need a third kernel). The effects
   with a fast path (``restitution``, ``amplitude_dependent_restitution``,
   ``rotational_damping``) change the parameters instead of adding their
   terms, unless ``prefer_terms``;
4. ``observe`` of every effect (``sensor_offset`` and ``time_lag`` commute).

References
----------
Housner, G. W. (1963). The behavior of inverted pendulum structures during
earthquakes. Bulletin of the Seismological Society of America 53(2), 403-417.
Bachmann, J. A., Strand, M., Vassiliou, M. F., Broccardo, M., Stojadinovic, B.
(2017). Probabilistic validation of the Housner rocking model. COMPDYN 2017.
"""

from __future__ import annotations

from housner.effects.composition import EffectPlan, apply_effects, simulate_with_effects
from housner.effects.flexible import FlexibleFoundation, simulate_flexible
from housner.effects.lookup import available_effects, effect_class, make_effect, make_effects
from housner.effects.measured import MeasuredMaps  # noqa: F401 - registers the effect measured_maps
from housner.effects.parameters import (
    AmplitudeDependentRestitution,
    AsymmetricPivots,
    FrequencyParameter,
    Restitution,
    RotationalDamping,
    asymmetric_impact_ratios,
)
from housner.effects.plugins import ENTRY_POINT_GROUP, discover_effects, load_plugin
from housner.effects.registry import (
    EFFECTS,
    STAGE_DISSIPATION,  # noqa: F401 - the stages, for users' effects
    STAGE_GEOMETRY,  # noqa: F401
    STAGE_INERTIA,  # noqa: F401
    STAGE_MECHANICS,  # noqa: F401
    STAGE_SENSOR,  # noqa: F401
    Effect,
    ParamSpec,
    param,
    register_effect,
)
from housner.effects.sensor import SensorOffset, TimeLag
from housner.effects.sliding import Sliding, simulate_sliding
from housner.effects.terms import CoulombTerm, ImpactTerm, MomentTerm, TermSet

__all__ = [
    "EFFECTS",
    "ENTRY_POINT_GROUP",
    "AmplitudeDependentRestitution",
    "AsymmetricPivots",
    "CoulombTerm",
    "Effect",
    "EffectPlan",
    "FlexibleFoundation",
    "FrequencyParameter",
    "ImpactTerm",
    "MomentTerm",
    "ParamSpec",
    "Restitution",
    "RotationalDamping",
    "SensorOffset",
    "Sliding",
    "TermSet",
    "TimeLag",
    "apply_effects",
    "asymmetric_impact_ratios",
    "available_effects",
    "discover_effects",
    "effect_class",
    "load_plugin",
    "make_effect",
    "make_effects",
    "param",
    "register_effect",
    "simulate_flexible",
    "simulate_sliding",
    "simulate_with_effects",
]
