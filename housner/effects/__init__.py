"""Physical effects: small pluggable additions to the analytic rocking model.

An *effect* is a frozen dataclass whose fields are its parameters (:func:`param`, a field carrying a
:class:`ParamSpec`: unit, bounds for fitting, the neutral value at which the effect does nothing, its
default; or a class attribute ``params``, read alike by :attr:`Effect.param_specs`), and which overrides
only the hooks it needs: ``modify_params`` (the rocking parameters), ``transform_input`` (the ground motion
the block feels), ``observe`` (what a sensor records), ``terms`` (terms of the one compiled analytic kernel,
:mod:`housner.effects.terms`) and ``solver`` (another equation of motion); the others are no-ops. An effect
that reads an extra measured channel of the motion names it in its ``channels``. Effects live in the registry
:data:`EFFECTS` (name -> class): add your own with :func:`register_effect`, from a file with
:func:`load_plugin`, or from an installed package through the entry-point group ``housner.effects``;
:func:`apply_effects` composes them by ``stage``. Each hook's arguments, units and signs, the order in which
effects compose, and an effect in full are in ``docs/reference/effects-api.md``; how to write one, in
``docs/how-to/add-effect.md``.
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
