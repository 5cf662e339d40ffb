"""Physical effects: small pluggable additions to the analytic rocking model.

An *effect* is a frozen dataclass whose fields are its parameters. The class
says, once, what each parameter means (:class:`ParamSpec`: unit, bounds for
fitting, the neutral value at which the effect does nothing) and overrides
only the hooks it needs; the others are no-ops:

``modify_params(params, specimen)``
    returns a changed :class:`housner.model.RockingParams` (restitution,
    amplitude-dependent restitution, rotational damping, asymmetric pivots,
    frequency parameter);
``transform_input(motion)``
    returns the ground motion the block really feels;
``observe(response)``
    returns what a sensor would record (angle offset, channel time lag);
``solver()``
    returns a different equation of motion, a callable
    ``solve(specimen, motion, params, *, substeps=None, rest_tol=1e-6) -> Response``,
    for the effects that change the mechanics (flexible foundation, sliding);
    None keeps Housner's rigid block.

Effects live in the registry :data:`EFFECTS` (name -> class). Add your own
with the :func:`register_effect` decorator, or from an installed package
through the entry-point group ``housner.effects`` (each entry point names an
:class:`Effect` subclass, or a module that registers its effects on import)::

    @register_effect
    @dataclass(frozen=True)
    class TableFilter(Effect):
        name = "table_filter"
        params = {"gain": ParamSpec("-", (0.5, 1.5), 1.0, doc="table gain")}
        gain: float = 1.0

        def transform_input(self, motion):
            return motion.scaled(amplitude=self.gain)

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
3. the solver: Housner's (``housner.model.simulate``) or the one mechanics
   effect's; at most one mechanics-changing effect may be given (their
   kernels do not compose: a block that both slides and sits on springs
   would need a third kernel);
4. ``observe`` of every effect (``sensor_offset`` and ``time_lag`` commute).

References
----------
Housner, G. W. (1963). The behavior of inverted pendulum structures during
earthquakes. Bulletin of the Seismological Society of America 53(2), 403-417.
Bachmann, J. A., Strand, M., Vassiliou, M. F., Broccardo, M., Stojadinovic, B.
(2017). Probabilistic validation of the Housner rocking model. COMPDYN 2017.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import warnings
from collections.abc import Callable, Iterable, Mapping
from dataclasses import asdict, dataclass, replace
from importlib.metadata import entry_points
from typing import Any, ClassVar

import numpy as np

from housner.errors import EngineError, unknown_choice
from housner.motion import GroundMotion
from housner.response import Response
from housner.specimen import Specimen
from housner.units import G

__all__ = [
    "EFFECTS",
    "ENTRY_POINT_GROUP",
    "AmplitudeDependentRestitution",
    "AsymmetricPivots",
    "Effect",
    "EffectPlan",
    "FlexibleFoundation",
    "FrequencyParameter",
    "ParamSpec",
    "Restitution",
    "RotationalDamping",
    "SensorOffset",
    "Sliding",
    "TimeLag",
    "apply_effects",
    "asymmetric_impact_ratios",
    "available_effects",
    "discover_effects",
    "effect_class",
    "make_effect",
    "make_effects",
    "register_effect",
    "simulate_flexible",
    "simulate_sliding",
    "simulate_with_effects",
]

#: Entry-point group scanned for effects of other packages.
ENTRY_POINT_GROUP = "housner.effects"

#: Stages, in order of application (see the module docstring).
STAGE_GEOMETRY, STAGE_INERTIA, STAGE_DISSIPATION, STAGE_MECHANICS, STAGE_SENSOR = 10, 20, 30, 40, 50

#: Registry: effect name -> Effect subclass.
EFFECTS: dict[str, type[Effect]] = {}

_discovered = False


# ----------------------------------------------------------------------
# the parts of an effect
@dataclass(frozen=True)
class ParamSpec:
    """What one parameter of an effect means.

    Parameters
    ----------
    unit : str
        Unit of the value ("-" when dimensionless).
    bounds : (float, float) or callable
        Closed interval [lo, hi] of meaningful values, used to validate and as
        the search range of a fit; a callable ``bounds(specimen) -> (lo, hi)``
        when the range depends on the specimen.
    neutral : float or callable
        The value at which the effect does nothing (it may lie outside
        ``bounds``, e.g. ``inf`` for an infinitely stiff foundation), or a
        callable ``neutral(specimen) -> float``.
    default : float, optional
        The dataclass field's default, repeated here for tables and as the
        start value of a fit; None when the parameter is required.
    doc : str
        One line for tables and error messages.
    """

    unit: str
    bounds: tuple[float, float] | Callable[[Specimen], tuple[float, float]]
    neutral: float | Callable[[Specimen], float]
    default: float | None = None
    doc: str = ""

    def bounds_for(self, specimen: Specimen | None = None) -> tuple[float, float] | None:
        """The bounds [unit]; None when they depend on a specimen that is not given."""
        if callable(self.bounds):
            return None if specimen is None else tuple(float(b) for b in self.bounds(specimen))
        return float(self.bounds[0]), float(self.bounds[1])

    def neutral_for(self, specimen: Specimen | None = None) -> float | None:
        """The neutral value [unit]; None when it depends on a specimen that is not given."""
        if callable(self.neutral):
            return None if specimen is None else float(self.neutral(specimen))
        return float(self.neutral)


class Effect:
    """Base class of the physical effects (subclasses are frozen dataclasses).

    Attributes
    ----------
    name : str
        Registry key.
    params : mapping of str to ParamSpec
        One entry per dataclass field.
    stage : int
        Order of application (``STAGE_*``); ties keep the order given.
    changes_mechanics : bool
        True for effects that bring their own equation of motion (``solver``).
    conflicts : frozenset of str
        Names of effects that cannot be combined with this one while it is active.
    seen_in_free_vibration : bool
        False for an effect that a free-vibration record measured with the
        campaign's release alignment cannot show (its time axis starts at the
        release seen in its own theta channel); the campaign comparison leaves
        such an effect out of those records.

    The dataclass fields are validated on construction against the static
    bounds (a value outside them raises a ValueError naming the parameter,
    unless it is the neutral value); specimen-dependent bounds are checked by
    :meth:`check`, which :func:`apply_effects` calls.
    """

    name: ClassVar[str] = ""
    params: ClassVar[Mapping[str, ParamSpec]] = {}
    stage: ClassVar[int] = STAGE_DISSIPATION
    changes_mechanics: ClassVar[bool] = False
    conflicts: ClassVar[frozenset[str]] = frozenset()
    conflict_reason: ClassVar[str] = ""
    seen_in_free_vibration: ClassVar[bool] = True

    def __post_init__(self) -> None:
        for key, spec in self.params.items():
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
                raise ValueError(f"`{key}` of effect {self.name!r} must be a number [{spec.unit}], got {value!r}")
            x = float(value)
            if math.isnan(x):
                raise ValueError(f"`{key}` of effect {self.name!r} must not be NaN")
            neutral = spec.neutral_for(None)
            bounds = spec.bounds_for(None)
            if bounds is not None and x != neutral and not bounds[0] <= x <= bounds[1]:
                raise ValueError(
                    f"`{key}` of effect {self.name!r} must lie in [{bounds[0]:g}, {bounds[1]:g}] {spec.unit}"
                    + (
                        f" or be {neutral:g} (no effect)"
                        if neutral is not None and not bounds[0] <= neutral <= bounds[1]
                        else ""
                    )
                    + f", got {value!r}"
                )
            if bounds is None and not math.isfinite(x) and x != neutral:
                raise ValueError(f"`{key}` of effect {self.name!r} must be finite, got {value!r}")
            object.__setattr__(self, key, x)

    # -- validation and description ---------------------------------
    def check(self, specimen: Specimen) -> None:
        """Validate the specimen-dependent bounds (ValueError naming the parameter)."""
        for key, spec in self.params.items():
            if not callable(spec.bounds):
                continue
            lo, hi = spec.bounds_for(specimen)
            x = getattr(self, key)
            if x != spec.neutral_for(specimen) and not lo <= x <= hi:
                raise ValueError(
                    f"`{key}` of effect {self.name!r} must lie in [{lo:g}, {hi:g}] {spec.unit} "
                    f"for specimen {specimen.name!r}, got {x!r}"
                )

    @classmethod
    def neutral(cls, specimen: Specimen | None = None) -> Effect:
        """The effect with every parameter at its neutral value (it changes nothing).

        ``specimen`` is needed when a neutral value depends on it (``restitution``).
        """
        kwargs = {}
        for key, spec in cls.params.items():
            v = spec.neutral_for(specimen)
            if v is None and callable(spec.neutral):
                raise ValueError(f"the neutral `{key}` of effect {cls.name!r} depends on the specimen; pass it")
            kwargs[key] = v if v is not None else spec.default
        return cls(**kwargs)

    def describe(self) -> dict:
        """Plain data: ``{"name": ..., <param>: value, ...}`` (for results tables and the cache)."""
        return {"name": self.name, **{k: getattr(self, k) for k in self.params}}

    # -- hooks (no-op defaults) ---------------------------------------
    def modify_params(self, params, specimen: Specimen):
        """Return the rocking parameters with this effect applied (default: unchanged)."""
        return params

    def transform_input(self, motion: GroundMotion) -> GroundMotion:
        """Return the ground motion the block feels (default: unchanged)."""
        return motion

    def observe(self, response: Response) -> Response:
        """Return what the sensors record of ``response`` (default: unchanged)."""
        return response

    def solver(self) -> Callable[..., Response] | None:
        """Equation of motion replacing Housner's rigid block, or None (default)."""
        return None


# ----------------------------------------------------------------------
# registry
def register_effect(arg: type | str | None = None) -> Any:
    """Class decorator adding an :class:`Effect` subclass to :data:`EFFECTS`.

    Use as ``@register_effect`` (the class's ``name``) or
    ``@register_effect("name")``. Registering a different class under a name
    already taken raises a ValueError; re-registering the same class (or a
    redefinition of it, same module and qualified name) replaces it.
    """
    if isinstance(arg, type):
        return _register(arg)

    def deco(cls: type) -> type:
        return _register(cls, arg)

    return deco


def _register(cls: type, name: str | None = None) -> type:
    if not (isinstance(cls, type) and issubclass(cls, Effect)):
        raise TypeError(f"only housner.effects.Effect subclasses can be registered, got {cls!r}")
    if not dataclasses.is_dataclass(cls):
        raise TypeError(f"effect class {cls.__qualname__} must be a dataclass (use @dataclass(frozen=True))")
    name = cls.name if name is None else name
    if not isinstance(name, str) or not name.isidentifier():
        raise ValueError(f"effect class {cls.__qualname__} needs a `name` that is an identifier, got {name!r}")
    fields = [f.name for f in dataclasses.fields(cls)]
    if sorted(fields) != sorted(cls.params):
        raise ValueError(
            f"effect {name!r}: the `params` specs ({', '.join(cls.params) or 'none'}) must match the dataclass "
            f"fields ({', '.join(fields) or 'none'})"
        )
    for key, spec in cls.params.items():
        if not isinstance(spec, ParamSpec):
            raise TypeError(f"effect {name!r}: params[{key!r}] must be a ParamSpec, got {spec!r}")
    old = EFFECTS.get(name)
    if old is not None and old is not cls and (old.__module__, old.__qualname__) != (cls.__module__, cls.__qualname__):
        raise ValueError(f"effect name {name!r} is already registered by {old.__module__}.{old.__qualname__}")
    cls.name = name
    EFFECTS[name] = cls
    return cls


def discover_effects(*, force: bool = False) -> tuple[str, ...]:
    """Load the effects that installed packages declare in the ``housner.effects`` entry-point group.

    Each entry point names an :class:`Effect` subclass (registered under its
    ``name``) or a module (imported, so that its ``@register_effect``
    decorators run). A broken entry point is reported with a warning and
    skipped. Runs once per process unless ``force``; returns the names known.
    """
    global _discovered
    if _discovered and not force:
        return tuple(EFFECTS)
    _discovered = True
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        try:
            obj = ep.load()
        except Exception as e:  # a plugin must not break the suite
            warnings.warn(f"cannot load effect entry point {ep.name!r} ({ep.value}): {e}", stacklevel=2)
            continue
        if isinstance(obj, type) and issubclass(obj, Effect):
            if EFFECTS.get(obj.name) is obj:
                continue
            try:
                _register(obj)
            except (TypeError, ValueError) as e:
                warnings.warn(f"effect entry point {ep.name!r} ({ep.value}) not registered: {e}", stacklevel=2)
        elif not hasattr(obj, "__path__") and not hasattr(obj, "__file__"):
            warnings.warn(
                f"effect entry point {ep.name!r} ({ep.value}) is neither an Effect subclass nor a module", stacklevel=2
            )
    return tuple(EFFECTS)


def available_effects() -> tuple[str, ...]:
    """Names of every registered effect (built-in, decorated and installed), sorted."""
    return tuple(sorted(discover_effects()))


def effect_class(name: str) -> type[Effect]:
    """The effect class registered as ``name``; unknown names list the choices and suggest the closest."""
    cls = EFFECTS.get(name)
    if cls is None:
        discover_effects()
        cls = EFFECTS.get(name)
    if cls is None:
        raise unknown_choice("effect", name, EFFECTS)
    return cls


def make_effect(name: str, specimen: Specimen | None = None, **params: float) -> Effect:
    """Build the effect registered as ``name`` with ``params``, validating every value.

    Parameters
    ----------
    name : str
        Registry key (see :func:`available_effects`).
    specimen : Specimen, optional
        Also check the bounds that depend on the specimen.
    **params : float
        Parameter values in the units of the effect's :class:`ParamSpec`.

    Raises
    ------
    ValueError
        Unknown name or parameter (listing the choices), a missing required
        parameter, or a value out of bounds (naming the parameter).
    """
    cls = effect_class(name)
    for key in params:
        if key not in cls.params:
            raise unknown_choice(f"parameter of effect {name!r}:", key, cls.params)
    missing = [k for k, s in cls.params.items() if k not in params and _field_default(cls, k) is None]
    if missing:
        spec = cls.params[missing[0]]
        raise ValueError(f"effect {name!r} needs `{missing[0]}` [{spec.unit}] ({spec.doc})")
    effect = cls(**params)
    if specimen is not None:
        effect.check(specimen)
    return effect


def _field_default(cls: type, key: str) -> Any:
    for f in dataclasses.fields(cls):
        if f.name == key:
            if f.default is not dataclasses.MISSING:
                return f.default
            if f.default_factory is not dataclasses.MISSING:
                return f.default_factory()
    return None


def make_effects(specs: Iterable[Any]) -> tuple[Effect, ...]:
    """Effects from plain data: Effect instances, names, or ``{"name": ..., <param>: value}`` dicts."""
    out = []
    for i, spec in enumerate(specs):
        if isinstance(spec, Effect):
            out.append(spec)
        elif isinstance(spec, str):
            out.append(make_effect(spec))
        elif isinstance(spec, Mapping):
            spec = dict(spec)
            name = spec.pop("name", None)
            if name is None:
                raise ValueError(f"`effects[{i}]` needs a 'name' key, got {spec!r}")
            out.append(make_effect(name, **spec))
        else:
            raise TypeError(f"`effects[{i}]` must be an Effect, a name or a dict with 'name', got {spec!r}")
    return tuple(out)


# ----------------------------------------------------------------------
# composition
@dataclass(frozen=True, eq=False)
class EffectPlan:
    """Effects resolved for one (specimen, motion): what the solver is given and what it does afterwards.

    Attributes
    ----------
    specimen : Specimen
    effects : tuple of Effect
        In the order of application.
    params : RockingParams
        The rocking parameters after every ``modify_params``.
    motion : GroundMotion
        The ground motion after every ``transform_input``.
    solver : callable or None
        The mechanics effect's equation of motion; None for Housner's.
    mechanics : Effect or None
        The effect that supplied ``solver``.
    """

    specimen: Specimen
    effects: tuple
    params: Any
    motion: GroundMotion
    solver: Callable[..., Response] | None = None
    mechanics: Effect | None = None

    def observe(self, response: Response) -> Response:
        """Apply every ``observe`` hook and list the effects in ``response.info['effects']``."""
        for e in self.effects:
            out = e.observe(response)
            if not isinstance(out, Response):
                raise TypeError(f"effect {e.name!r}: observe() must return a Response, got {type(out).__name__}")
            response = out
        return replace(response, info={**response.info, "effects": [e.describe() for e in self.effects]})

    def run(self, *, substeps: int | None = None, rest_tol: float = 1e-6) -> Response:
        """Simulate: the solver on (specimen, motion, params), then the observers.

        Parameters
        ----------
        substeps : int, optional
            RK4 substeps per sample; default: the solver's.
        rest_tol : float
            Rest rule of :func:`housner.model.simulate` [-].
        """
        if self.solver is None:
            from housner.model import simulate

            res = simulate(self.specimen, self.motion, params=self.params, substeps=substeps, rest_tol=rest_tol)
        else:
            res = self.solver(self.specimen, self.motion, self.params, substeps=substeps, rest_tol=rest_tol)
        return self.observe(res)


def apply_effects(
    specimen: Specimen, motion: GroundMotion, effects: Iterable[Effect] = (), *, params=None
) -> EffectPlan:
    """Resolve ``effects`` for one simulation (see the module docstring for the order).

    Parameters
    ----------
    specimen : Specimen
    motion : GroundMotion
    effects : iterable of Effect
        At most one of each name, and at most one that changes the mechanics.
    params : RockingParams, optional
        Starting parameters; default ``RockingParams.from_specimen(specimen)``.

    Returns
    -------
    EffectPlan
        Call its ``run()`` to simulate.
    """
    from housner.model import RockingParams

    if not isinstance(specimen, Specimen):
        raise TypeError(f"`specimen` must be a housner.Specimen, got {type(specimen).__name__}")
    if not isinstance(motion, GroundMotion):
        raise TypeError(f"`motion` must be a housner.GroundMotion, got {type(motion).__name__}")
    effects = tuple(effects)
    seen: dict[str, int] = {}
    for i, e in enumerate(effects):
        if not isinstance(e, Effect):
            raise TypeError(
                f"`effects[{i}]` must be a housner.effects.Effect (build one with make_effect(name, ...)), "
                f"got {type(e).__name__}"
            )
        if e.name in seen:
            raise ValueError(f"effect {e.name!r} given twice (effects[{seen[e.name]}] and effects[{i}]); give it once")
        seen[e.name] = i
        e.check(specimen)
    mech = [e.name for e in effects if e.changes_mechanics]
    if len(mech) > 1:
        raise ValueError(
            f"effects {' and '.join(repr(m) for m in mech)} each replace the equation of motion and cannot be "
            "combined: give at most one mechanics-changing effect per simulation"
        )
    ordered = tuple(sorted(effects, key=lambda e: e.stage))
    prm = RockingParams.from_specimen(specimen) if params is None else params
    for e in ordered:
        prm = e.modify_params(prm, specimen)
        if not isinstance(prm, RockingParams):
            raise TypeError(f"effect {e.name!r}: modify_params() must return a RockingParams, got {type(prm).__name__}")
    mo = motion
    for e in ordered:
        mo = e.transform_input(mo)
        if not isinstance(mo, GroundMotion):
            raise TypeError(f"effect {e.name!r}: transform_input() must return a GroundMotion, got {type(mo).__name__}")
    solver = None
    mechanics = None
    for e in ordered:
        s = e.solver()
        if s is not None:
            solver, mechanics = s, e
    if mechanics is not None:
        clash = [e.name for e in ordered if e.name in mechanics.conflicts]
        if clash:
            raise ValueError(
                f"effect {mechanics.name!r} cannot be combined with {', '.join(repr(c) for c in clash)}: "
                f"{mechanics.conflict_reason}"
            )
    return EffectPlan(specimen, ordered, prm, mo, solver, mechanics)


def simulate_with_effects(
    specimen: Specimen,
    motion: GroundMotion,
    effects: Iterable[Effect] = (),
    *,
    params=None,
    substeps: int | None = None,
    rest_tol: float = 1e-6,
) -> Response:
    """Simulate ``motion`` on ``specimen`` with ``effects`` (``apply_effects(...).run(...)``).

    Parameters
    ----------
    specimen : Specimen
    motion : GroundMotion
    effects : iterable of Effect
    params : RockingParams, optional
        Starting parameters (default: the specimen's Housner parameters).
    substeps : int, optional
        RK4 substeps per sample [-].
    rest_tol : float
        Rest rule of :func:`housner.model.simulate` [-].
    """
    return apply_effects(specimen, motion, effects, params=params).run(substeps=substeps, rest_tol=rest_tol)


# ----------------------------------------------------------------------
# effects that change the rocking parameters
@register_effect
@dataclass(frozen=True)
class Restitution(Effect):
    """Kinetic-energy ratio at impact r, free instead of Housner's value.

    At every impact theta'_after = sqrt(r) theta'_before, so the energy ratio
    of two successive free-rocking half-cycles is r (seed eq. 8 measures it
    as c_i = (cos(alpha - |theta_{i+1}|) - cos alpha) / (cos(alpha - |theta_i|)
    - cos alpha)). Neutral: the specimen's Housner value (seed eq. 4).

    Parameters
    ----------
    r : float
        Kinetic-energy ratio at impact [-], in [0, 1].

    References
    ----------
    Housner (1963); Bachmann et al. (2017), eqs. 4 and 8 and Table 1
    (r = 0.9532 measured, 0.9465 from eq. 4).
    """

    name = "restitution"
    params = {"r": ParamSpec("-", (0.0, 1.0), lambda s: s.r_housner, doc="kinetic-energy ratio at impact")}
    stage = STAGE_DISSIPATION
    r: float

    def modify_params(self, params, specimen):
        # with_r keeps the split of an asymmetric block's two impacts (r_pos / r_neg)
        return params.with_r(self.r)


@register_effect
@dataclass(frozen=True)
class AmplitudeDependentRestitution(Effect):
    """Impact loss that depends on the impact speed.

    The energy ratio of an impact with pre-impact speed |theta'| is
    r_eff = clip(r (|theta'| / (p_s alpha_s))^n, 0, 1) with the r in force
    (Housner's or the ``restitution`` effect's), p_s and alpha_s of the
    corner the block rocked on before the impact. p alpha is the impact speed
    of a block released from theta = alpha in the linearised model, so a
    block released near overturning loses what r says; n > 0 makes small
    impacts lose more (tests on stone and concrete blocks find the measured
    ratio falling with amplitude), n < 0 less. Realised by
    ``RockingParams.r_amp_exponent``.

    Parameters
    ----------
    exponent : float
        Exponent n [-], in [-2, 2]; neutral 0 (constant r).

    References
    ----------
    Kalliontzis, D., Sritharan, S., Schultz, A. (2016). Improved coefficient
    of restitution estimation for free rocking members. Journal of Structural
    Engineering 142(12), 06016002.
    """

    name = "amplitude_dependent_restitution"
    params = {"exponent": ParamSpec("-", (-2.0, 2.0), 0.0, 0.0, "exponent n of r (|theta'|/(p alpha))^n")}
    stage = STAGE_DISSIPATION
    exponent: float = 0.0

    def modify_params(self, params, specimen):
        if self.exponent == 0.0:
            return params
        return replace(params, r_amp_exponent=self.exponent)


@register_effect
@dataclass(frozen=True)
class RotationalDamping(Effect):
    """Viscous moment between impacts, -c I0 theta'.

    The equation of motion gains -c theta', so between impacts the rocking
    energy per unit I0, E = theta'^2/2 + p^2 (cos(alpha - |theta|) - cos alpha)
    [1/s^2], decays at exactly dE/dt = -c theta'^2. A phenomenological stand-in
    for losses that Housner's instantaneous impact misses (air, interface
    micro-slip, a soft base). Adds to any damping already in force.

    Parameters
    ----------
    c : float
        Damping rate [1/s] per unit rotational inertia about the pivot, in
        [0, 5]; neutral 0.

    References
    ----------
    Housner (1963) for the energy integral.
    """

    name = "rotational_damping"
    params = {"c": ParamSpec("1/s", (0.0, 5.0), 0.0, 0.0, "viscous damping rate of the rotation")}
    stage = STAGE_DISSIPATION
    c: float = 0.0

    def modify_params(self, params, specimen):
        if self.c == 0.0:
            return params
        return replace(params, damping=params.damping + self.c)


def asymmetric_impact_ratios(specimen: Specimen, e: float) -> tuple[float, float]:
    """Angular-velocity ratios of the two impacts of a block whose centre of mass is off-centre.

    The centre of mass sits at height H and horizontally e [m] toward +x from
    the midpoint of the pivots, so the +x corner is b+ = B - e and the -x
    corner b- = B + e away from it horizontally. Conservation of angular
    momentum about the corner that lands (Housner's assumptions: impulse at
    the corner, no bounce, no slip) gives, with I_c the centroidal inertia and
    I+- = I_c + m (H^2 + b+-^2) the inertia about each corner::

        theta'_after / theta'_before = (I_c + m (H^2 - b+ b-)) / I_landing

    Returns
    -------
    (rho_pos_to_neg, rho_neg_to_pos) : tuple of float
        Ratio [-] for an impact that ends rocking on the +x corner and lands
        on the -x corner, and for the reverse. For e = 0 both are
        1 - 2 m B^2 / I0 = sqrt(r_housner).
    """
    m = specimen.mass
    hh = specimen.H
    bp = specimen.B - e
    bn = specimen.B + e
    ic = specimen.centroidal_inertia
    common = ic + m * (hh * hh - bp * bn)
    return common / (ic + m * (hh * hh + bn * bn)), common / (ic + m * (hh * hh + bp * bp))


@register_effect
@dataclass(frozen=True)
class AsymmetricPivots(Effect):
    """Centre of mass off-centre by e: the two corners have their own alpha, R and p.

    With the centre of mass e [m] toward +x of the midpoint of the pivots
    (height H, centroidal inertia I_c unchanged), the block rocking on the +x
    corner (theta > 0) has b+ = B - e, alpha+ = atan(b+/H), R+ = hypot(b+, H),
    p+ = sqrt(m g R+ / (I_c + m R+^2)); on the -x corner the same with
    b- = B + e. The uplift thresholds differ: it lifts onto the +x corner when
    ug'' < -g tan(alpha+) and onto the -x corner when ug'' > g tan(alpha-).

    Impacts: angular momentum about the landing corner is conserved
    (:func:`asymmetric_impact_ratios`): just before an impact that ends
    rocking on the +x corner, the block turns at theta' about that corner;
    the impulse acts at the landing (-x) corner, so the angular momentum
    about it, (I_c + m (H^2 - b+ b-)) theta', is kept, and just after the
    block turns about the -x corner with inertia I- = I_c + m (H^2 + b-^2).
    This scales theta' by rho+- at that impact and by rho-+ (the same with
    the sides swapped) at the converse; rho+- / rho-+ = I+ / I-. The effect
    sets the restitution of each impact exactly (``RockingParams.r_pos`` and
    ``r_neg``, ratios of the squared angular velocities; the kinetic energy
    itself changes by rho+-^2 I- / I+ and rho-+^2 I+ / I-)::

        r_neg = rho+-^2 * r_in_force(-) / r_housner   (lands on the -x corner)
        r_pos = rho-+^2 * r_in_force(+) / r_housner   (lands on the +x corner)
        r     = rho+- rho-+ * r_in_force / r_housner  (their geometric mean)

    each clipped to 1, where r_in_force is the ratio in force before this
    effect (per side where set). With Housner's r in force this is
    r_neg = rho+-^2 and r_pos = rho-+^2; a later ``restitution`` effect
    rescales both (:meth:`housner.model.RockingParams.with_r`), keeping
    r_neg / r_pos = (I+ / I-)^2.

    Parameters
    ----------
    e : float
        Horizontal offset of the centre of mass toward +x [m], within
        +-B/2 (B the half width); neutral 0.

    References
    ----------
    Housner (1963) for the impact law (angular momentum about the new pivot);
    the asymmetric generalisation is derived in this docstring.
    """

    name = "asymmetric_pivots"
    params = {
        "e": ParamSpec("m", lambda s: (-0.5 * s.B, 0.5 * s.B), 0.0, 0.0, "offset of the centre of mass toward +x")
    }
    stage = STAGE_GEOMETRY
    e: float = 0.0

    def modify_params(self, params, specimen):
        if self.e == 0.0:
            return params
        m, hh, ic = specimen.mass, specimen.H, specimen.centroidal_inertia
        out = {}
        for side, b in (("pos", specimen.B - self.e), ("neg", specimen.B + self.e)):
            rr = math.hypot(b, hh)
            out[f"alpha_{side}"] = math.atan2(b, hh)
            out[f"p_{side}"] = math.sqrt(m * G * rr / (ic + m * rr * rr))
        rho_pn, rho_np = asymmetric_impact_ratios(specimen, self.e)
        r_h = specimen.r_housner
        out["r"] = min(1.0, params.r * rho_pn * rho_np / r_h)
        out["r_neg"] = min(1.0, params.r_impact_neg * rho_pn * rho_pn / r_h)  # lands on the -x corner
        out["r_pos"] = min(1.0, params.r_impact_pos * rho_np * rho_np / r_h)  # lands on the +x corner
        return replace(params, **out)


@register_effect
@dataclass(frozen=True)
class FrequencyParameter(Effect):
    """The frequency parameter p scaled by a factor (a mis-stated or mis-measured p).

    Both corners' p are multiplied by ``factor``: half-cycle durations scale
    as 1/factor (Housner: cosh(p T / 4) = 1 / (1 - theta0/alpha), seed eq. 7).
    alpha and r are unchanged (change r with ``restitution``). To state p
    directly use :meth:`from_p`.

    Parameters
    ----------
    factor : float
        Ratio of the p used to the specimen's p [-], in [0.5, 2]; neutral 1.

    References
    ----------
    Housner (1963); Bachmann et al. (2017), eqs. 3 and 7 (p calibrated from
    free vibration, 4.8883 1/s).
    """

    name = "frequency_parameter"
    params = {"factor": ParamSpec("-", (0.5, 2.0), 1.0, 1.0, "ratio of the p used to the specimen's p")}
    stage = STAGE_INERTIA
    factor: float = 1.0

    @classmethod
    def from_p(cls, specimen: Specimen, p: float) -> FrequencyParameter:
        """The effect that makes the specimen rock with frequency parameter ``p`` [1/s]."""
        if not (isinstance(p, (int, float)) and math.isfinite(p) and p > 0):
            raise ValueError(f"`p` must be a positive number [1/s], got {p!r}")
        return cls(factor=p / specimen.frequency_parameter)

    def modify_params(self, params, specimen):
        if self.factor == 1.0:
            return params
        return replace(params, p_pos=params.p_pos * self.factor, p_neg=params.p_neg * self.factor)


# ----------------------------------------------------------------------
# effects that change the mechanics
def _pos_int_or_none(name: str, v) -> int | None:
    if v is None:
        return None
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
        raise ValueError(f"`{name}` must be a positive integer, got {v!r}")
    return int(v)


def _corner_geometry(specimen: Specimen, params) -> dict:
    """Per-unit-mass geometry of the two corners from the rocking parameters.

    Returns b (horizontal distance centre of mass -> corner [m]), R [m],
    i0 = I_corner / m [m^2] and i_c = I_c / m [m^2] per side; raises a
    ValueError when p implies an impossible inertia (I0 < m R^2).
    """
    hh = specimen.H
    out = {}
    for side in ("pos", "neg"):
        alpha = getattr(params, f"alpha_{side}")
        p = getattr(params, f"p_{side}")
        b = hh * math.tan(alpha)
        rr = math.hypot(b, hh)
        i0 = G * rr / (p * p)
        if i0 <= rr * rr:
            raise ValueError(
                f"`p_{side}` = {p:.6g} 1/s is impossible for a block with R = {rr:.6g} m (it must stay below "
                f"sqrt(g/R) = {math.sqrt(G / rr):.6g} 1/s): flexible_foundation and sliding need a positive centroidal "
                "inertia I0 - m R^2 (is the frequency_parameter `factor` too large?)"
            )
        out[side] = (b, rr, i0, i0 - rr * rr)
    return out


def simulate_flexible(
    specimen: Specimen,
    motion: GroundMotion,
    params=None,
    *,
    frequency: float,
    damping_ratio: float = 0.5,
    substeps: int | None = None,
    rest_tol: float = 1e-6,
) -> Response:
    """Rocking on a flexible foundation (see :class:`FlexibleFoundation` for the model).

    Parameters
    ----------
    specimen : Specimen
    motion : GroundMotion
        Ground acceleration [m/s^2] and initial rotation theta0 [rad],
        theta_dot0 [rad/s]; the block starts with its weight on the springs.
    params : RockingParams, optional
        alpha and p per corner (asymmetric pivots, frequency parameter) and
        ``damping`` [1/s] are used; r and r_amp_exponent are not (the springs
        replace the impact law). Default: the specimen's. The centroidal
        inertia is I_c = m (g R_s / p_s^2 - R_s^2); where the two corners imply
        different values (p scaled on an asymmetric block) their mean is used
        and ``info['inertia_mismatch']`` gives their relative difference.
    frequency : float
        Vertical natural frequency of the block on its foundation [Hz].
    damping_ratio : float
        Damping ratio of that vertical mode [-].
    substeps : int, optional
        RK4 substeps per sample; default: enough for 0.05 rad of the fastest
        contact mode per step and p h <= 0.01.
    rest_tol : float
        Unused (no rest rule is needed: the springs bring the block to rest).

    Returns
    -------
    Response
        ``info`` adds ``w`` and ``w_dot`` (vertical displacement [m] and
        velocity [m/s] of the base point below the centre of mass, 0 when the
        springs are unloaded, histories on the sample grid), ``w_min`` [m],
        ``impact_durations`` [s] (time both corners push around each impact;
        NaN where the block crossed theta = 0 with at most one corner
        pushing), ``substeps``, ``inertia_mismatch`` and the foundation
        constants ``k`` [N/m] and ``c`` [N s/m] per corner. An impact is a
        crossing of theta = 0 after a corner lost contact (not the small
        rocking of a block that sits on both springs).
    """
    from housner import _effects_kernels as K
    from housner.model import PH_MAX, RockingParams

    prm = RockingParams.from_specimen(specimen) if params is None else params
    f = float(frequency)
    zeta = float(damping_ratio)
    if not (math.isfinite(f) and f > 0):
        raise ValueError(f"`frequency` must be positive and finite [Hz], got {frequency!r}")
    if not (math.isfinite(zeta) and zeta >= 0):
        raise ValueError(f"`damping_ratio` must be >= 0, got {damping_ratio!r}")
    geo = _corner_geometry(specimen, prm)
    bp, _rp, i0p, icp = geo["pos"]
    bn, _rn, i0n, icn = geo["neg"]
    # a rigid block has one centroidal inertia; p scaled on an asymmetric block implies two: take their mean
    ic = 0.5 * (icp + icn)
    omega_v = 2.0 * math.pi * f
    kappa = 0.5 * omega_v**2  # k/m per corner: 2 k / m = omega_v^2
    eta = zeta * omega_v  # c/m per corner: 2 c / m = 2 zeta omega_v
    q = np.zeros(K.N_FLEX)
    q[K.F_G], q[K.F_H], q[K.F_BP], q[K.F_BN] = G, specimen.H, bp, bn
    q[K.F_IC], q[K.F_I0P], q[K.F_I0N] = ic, i0p, i0n
    q[K.F_C], q[K.F_KAPPA], q[K.F_ETA] = prm.damping, kappa, eta
    # fastest mode: vertical (2 kappa) or one corner against the rotational inertia
    bmax = max(bp, bn)
    lam = math.sqrt(kappa * max(2.0, 1.0 + bmax * bmax / ic)) * (zeta + math.sqrt(1.0 + zeta * zeta))
    dt = motion.dt
    m = _pos_int_or_none("substeps", substeps)
    if m is None:
        m = max(math.ceil(dt * lam / _FLEX_STEP - 1e-9), math.ceil(prm.p_max * dt / PH_MAX - 1e-9), 1)
    th0, thd0 = motion.theta0, motion.theta_dot0
    # vertical equilibrium at theta0: both corners pushing, or the lower one alone
    sn = math.sin(th0)
    w0 = 0.5 * ((bp - bn) * sn - G / kappa)
    if bp * sn - w0 <= 0.0 or -w0 - bn * sn <= 0.0:
        w0 = (bp * sn if th0 > 0 else -bn * sn) - G / kappa
    n = motion.n
    th, thd, w, wd = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    cap = max(64, n)
    imp, dur = np.empty(cap), np.empty(cap)
    acc = np.ascontiguousarray(motion.acc, dtype=np.float64)
    out = K.run_flexible(acc, dt, m, q, th0, thd0, w0, 0.0, True, th, thd, w, wd, imp, dur)
    theta_max, over, t_over, t_up, n_imp, guard, w_min = out
    if guard:
        raise EngineError(
            f"flexible_foundation: contact chattering on motion {motion.name!r} (more than "
            f"{K.MAX_EVENTS_PER_SAMPLE} contact changes in one sample); raise the damping ratio"
        )
    if n_imp > cap:
        imp, dur = np.empty(n_imp), np.empty(n_imp)
        K.run_flexible(acc, dt, m, q, th0, thd0, w0, 0.0, False, th[:0], thd[:0], w[:0], wd[:0], imp, dur)
    info = {
        "kernel": "flexible_foundation",
        "substeps": m,
        "params": asdict(prm),
        "frequency_hz": f,
        "damping_ratio": zeta,
        "k": kappa * specimen.mass,
        "c": eta * specimen.mass,
        "w": w,
        "w_dot": wd,
        "w_min": float(w_min),
        "impact_durations": dur[:n_imp].copy(),
        "inertia_mismatch": abs(icp - icn) / ic,
    }
    return Response(
        t=motion.t,
        theta=th,
        theta_dot=thd,
        impact_times=imp[:n_imp].copy(),
        theta_max=math.pi / 2 if over else float(theta_max),
        alpha=specimen.alpha,
        overturned=bool(over),
        overturn_time=float(t_over),
        uplift_time=float(t_up),
        engine="housner",
        info=info,
    )


#: Flexible foundation: RK4 step as a fraction of the fastest contact period / (2 pi) [rad].
_FLEX_STEP = 0.05


@register_effect
@dataclass(frozen=True)
class FlexibleFoundation(Effect):
    """The block on two compression-only spring-dashpots at its corners (a two-spring foundation).

    Degrees of freedom: the rotation theta and the vertical displacement w of
    the base point below the centre of mass (2 DOF). Each corner pushes with
    F = max(0, k d + c d') while its penetration d = -z_corner > 0 and never
    pulls; z_+- = w -+ b+- sin(theta) with b+- the horizontal distances of the
    corners from the centre of mass. Horizontally the corner on the side of
    sgn(theta) is held to the ground (no sliding): it is the pivot of Housner's
    model, and the switch at theta = 0 is continuous in position and velocity
    (at theta = 0 both corners move vertically only). The constraint holds
    also while that corner is off its spring (the model has no sliding and no
    horizontal flight; a stiff, damped foundation barely lets the block hop). Lagrange's equations
    with u_g(t) the ground motion, a = d x_G / d theta = s b_s sin(theta) +
    H cos(theta)::

        (I_c + m a^2) theta'' = -m a (ug'' + a' theta'^2) + H sin(theta) (F+ + F-)
                                - cos(theta) (b+ F+ - b- F-) - c_rot I0 theta'
        m w'' = -m g + F+ + F- + m H (sin(theta) theta'' + cos(theta) theta'^2)

    Consequences: the block tilts before it lifts off (small-angle static tilt
    under a constant lateral acceleration a below uplift,
    theta = m a H / (2 k B^2 - m g H)); an impact takes time (both corners
    push for a while as the block rolls from one corner onto the other); with
    c = 0 the total energy (kinetic + gravity + springs) is conserved, with
    c > 0 it only decreases; there is no coefficient of restitution (the
    springs and dashpots replace the impact law, so ``restitution`` and
    ``amplitude_dependent_restitution`` cannot be combined with it). As k
    grows, the block approaches Housner's rigid block (energy loss per impact
    set by the damping: with ``damping_ratio`` 0.5, the default, a 1000 Hz
    foundation under the seed specimen loses Housner's r = 0.9465 per impact
    to 4 digits). The seed reports 25 Hz as the measured eigenfrequency of
    its specimen, an order of magnitude to start a fit from.

    Parameters
    ----------
    frequency : float
        Vertical natural frequency of the block on the two springs,
        sqrt(2 k / m) / (2 pi) [Hz], in [2, 2000]; neutral inf (rigid ground,
        Housner's model). k = m (2 pi f)^2 / 2 per corner.
    damping_ratio : float
        Damping ratio of that vertical mode [-], in [0, 2]; c = zeta m 2 pi f
        per corner. Default 0.5.

    References
    ----------
    Psycharis, I. N., Jennings, P. C. (1983). Rocking of slender rigid bodies
    allowed to uplift. Earthquake Engineering & Structural Dynamics 11(1), 57-76.
    Chopra, A. K., Yim, S. C.-S. (1985). Simplified earthquake analysis of
    structures with foundation uplift. Journal of Structural Engineering
    111(4), 906-930.
    """

    name = "flexible_foundation"
    params = {
        "frequency": ParamSpec("Hz", (2.0, 2000.0), math.inf, None, "vertical natural frequency on the foundation"),
        "damping_ratio": ParamSpec("-", (0.0, 2.0), 0.0, 0.5, "damping ratio of the vertical mode"),
    }
    stage = STAGE_MECHANICS
    changes_mechanics = True
    conflicts = frozenset({"restitution", "amplitude_dependent_restitution"})
    conflict_reason = "its springs and dashpots replace the instantaneous impact law (there is no r to set)"
    frequency: float
    damping_ratio: float = 0.5

    @classmethod
    def from_stiffness(cls, specimen: Specimen, k: float, c: float = 0.0) -> FlexibleFoundation:
        """The foundation with stiffness ``k`` [N/m] and dashpot ``c`` [N s/m] per corner."""
        if not (math.isfinite(k) and k > 0):
            raise ValueError(f"`k` must be positive [N/m], got {k!r}")
        if not (math.isfinite(c) and c >= 0):
            raise ValueError(f"`c` must be >= 0 [N s/m], got {c!r}")
        omega = math.sqrt(2.0 * k / specimen.mass)
        return cls(frequency=omega / (2.0 * math.pi), damping_ratio=c / (specimen.mass * omega))

    def solver(self):
        if math.isinf(self.frequency):
            return None
        return functools.partial(simulate_flexible, frequency=self.frequency, damping_ratio=self.damping_ratio)


def simulate_sliding(
    specimen: Specimen,
    motion: GroundMotion,
    params=None,
    *,
    mu: float,
    substeps: int | None = None,
    rest_tol: float = 1e-6,
) -> Response:
    """Rocking with Coulomb friction at the base (see :class:`Sliding` for the model).

    Parameters
    ----------
    specimen : Specimen
    motion : GroundMotion
        Ground acceleration [m/s^2] and initial state theta0 [rad],
        theta_dot0 [rad/s] (the base is not slipping at t = 0).
    params : RockingParams, optional
        Every field is used except the per-side ratios ``r_pos`` and
        ``r_neg`` (the sliding kernel's impacts use ``r``, the geometric mean
        of the two for :class:`AsymmetricPivots`); default: the specimen's.
    mu : float
        Friction coefficient [-].
    substeps : int, optional
        RK4 substeps per sample; default as :func:`housner.model.simulate` (p h <= 0.01).
    rest_tol : float
        Rest rule of :func:`housner.model.simulate` [-].

    Returns
    -------
    Response
        ``info`` adds ``slip`` (horizontal displacement of the base corner in
        contact relative to the ground [m], history), ``regime`` (int8
        history: 0 rest, 1 slide, 2 rock, 3 slide-rock, 4 overturned),
        ``slip_max`` [m], ``slide_time`` (first slip [s], NaN if none),
        ``painleve_jams`` and ``lift_off_time`` [s] (see :class:`Sliding`).
    """
    from housner import _effects_kernels as K
    from housner.model import RockingParams, default_substeps

    prm = RockingParams.from_specimen(specimen) if params is None else params
    mu = float(mu)
    if not (math.isfinite(mu) and mu > 0):
        raise ValueError(f"`mu` must be positive and finite, got {mu!r}")
    if not (isinstance(rest_tol, (int, float)) and 0.0 < rest_tol < 1.0):
        raise ValueError(f"`rest_tol` must lie in (0, 1), got {rest_tol!r}")
    geo = _corner_geometry(specimen, prm)
    q = np.zeros(K.N_SLIDE)
    q[K.S_G], q[K.S_MU], q[K.S_C], q[K.S_R], q[K.S_REXP] = G, mu, prm.damping, prm.r, prm.r_amp_exponent
    for side, (ia, ir, ii, ip) in (
        ("pos", (K.S_ALPHA_P, K.S_R_P, K.S_I0_P, K.S_P2_P)),
        ("neg", (K.S_ALPHA_N, K.S_R_N, K.S_I0_N, K.S_P2_N)),
    ):
        _b, rr, i0, _ic = geo[side]
        q[ia] = getattr(prm, f"alpha_{side}")
        q[ir] = rr
        q[ii] = i0
        q[ip] = getattr(prm, f"p_{side}") ** 2
    m = _pos_int_or_none("substeps", substeps)
    if m is None:
        m = default_substeps(prm.p_max, motion.dt)
    n = motion.n
    th, thd, x = np.empty(n), np.empty(n), np.empty(n)
    reg = np.empty(n, dtype=np.int8)
    cap = max(64, n)
    imp = np.empty(cap)
    acc_g = np.ascontiguousarray(motion.acc, dtype=np.float64) / G
    args = (acc_g, motion.dt, m, q, motion.theta0, motion.theta_dot0, float(rest_tol))
    out = K.run_sliding(*args, True, th, thd, x, reg, imp)
    theta_max, over, t_over, t_up, n_imp, guard, x_max, t_slide, n_jam, t_lift = out
    if guard:
        raise EngineError(
            f"sliding: more than {K.MAX_EVENTS_PER_SAMPLE} regime changes in one sample on motion {motion.name!r}"
        )
    if n_imp > cap:
        imp = np.empty(n_imp)
        K.run_sliding(*args, False, th[:0], thd[:0], x[:0], reg[:0], imp)
    info = {
        "kernel": "sliding",
        "substeps": m,
        "rest_tol": rest_tol,
        "params": asdict(prm),
        "mu": mu,
        "slip": x,
        "regime": reg,
        "slip_max": float(x_max),
        "slide_time": float(t_slide),
        "painleve_jams": int(n_jam),
        "lift_off_time": float(t_lift),
    }
    return Response(
        t=motion.t,
        theta=th,
        theta_dot=thd,
        impact_times=imp[:n_imp].copy(),
        theta_max=math.pi / 2 if over else float(theta_max),
        alpha=specimen.alpha,
        overturned=bool(over),
        overturn_time=float(t_over),
        uplift_time=float(t_up),
        engine="housner",
        info=info,
    )


@register_effect
@dataclass(frozen=True)
class Sliding(Effect):
    """Rocking with Coulomb friction mu at the base: rest, slide, rock and slide-rock.

    Rigid block, rigid ground; degrees of freedom theta and the horizontal
    slip x of the base corner in contact (the pivot stays on the ground, as in
    Housner's model). Friction F <= mu N, N the normal force. Regimes:

    * rest: the block moves with the ground while |ug''| <= mu g and it does
      not uplift (ug'' within [-g tan(alpha+), g tan(alpha-)]);
    * slide (theta = 0): m x'' = -m ug'' - mu m g sgn(x'); it stops when x'
      returns to zero and |ug''| <= mu g;
    * rock (x' = 0): Housner's equation; the pivot holds while the friction
      demand F = m (ug'' + zeta theta'' - xi theta'^2) stays within mu N,
      N = m (g - xi theta'' - zeta theta'^2), where (xi, zeta) = position of the
      centre of mass relative to the pivot;
    * slide-rock: both; with F = -mu N sgn(x') the moment balance about the
      pivot gives (I_c + m xi^2 + mu sgn(x') m zeta xi) theta'' =
      m (mu sgn(x') zeta + xi)(g - zeta theta'^2) - c I0 theta'. When this
      coefficient is not positive the Coulomb problem has no consistent slip
      (Painleve's paradox): the slip is stopped (a tangential jam, counted in
      ``info['painleve_jams']``). When the normal-force demand turns negative
      (the block would jump) friction vanishes and the pivot is kept on the
      ground (time counted in ``info['lift_off_time']``).

    Impacts follow Housner's law (theta' times sqrt(r), with every
    restitution effect) and keep the slip velocity: with x' unchanged,
    angular momentum about the landing corner is conserved exactly as on a
    fixed base, and the impulse lies inside the friction cone whenever
    mu >= tan(alpha) (it needs (1 - sqrt r) / ((1 + sqrt r) tan(alpha)) < tan(alpha)).

    Start of motion from rest under horizontal ground acceleration (Shenton
    1996): the block slides if mu < tan(alpha) and |ug''| > mu g, and then
    never rocks (friction caps the inertia force the base can transmit at
    mu m g < m g tan(alpha)); it rocks if mu > tan(alpha) and |ug''| > g tan(alpha),
    and slides while rocking when the friction demand exceeds mu N.

    Parameters
    ----------
    mu : float
        Coulomb friction coefficient at the base [-], in [0.01, 2]; neutral inf
        (no sliding: Housner's model).

    References
    ----------
    Shenton, H. W., Jones, N. P. (1991). Base excitation of rigid bodies. I:
    Formulation. Journal of Engineering Mechanics 117(10), 2286-2306.
    Shenton, H. W. (1996). Criteria for initiation of slide, rock, and
    slide-rock rigid-body modes. Journal of Engineering Mechanics 122(7), 690-693.
    Zhang, J., Makris, N. (2001). Rocking response of free-standing blocks
    under cycloidal pulses. Journal of Engineering Mechanics 127(5), 473-483.
    Genot, F., Brogliato, B. (1999). New results on Painleve paradoxes.
    European Journal of Mechanics A/Solids 18(4), 653-677.
    """

    name = "sliding"
    params = {"mu": ParamSpec("-", (0.01, 2.0), math.inf, None, "Coulomb friction coefficient at the base")}
    stage = STAGE_MECHANICS
    changes_mechanics = True
    mu: float

    def solver(self):
        if math.isinf(self.mu):
            return None
        return functools.partial(simulate_sliding, mu=self.mu)


# ----------------------------------------------------------------------
# sensor effects
@register_effect
@dataclass(frozen=True)
class SensorOffset(Effect):
    """A constant offset added to the measured rotation.

    The observed theta is theta + offset [rad] at every sample (the seed's
    optical system had an offset between its marker lines that was measured
    at rest and subtracted; a residual remains). ``theta_max`` becomes the
    largest |theta + offset|: exact at the response's own (between-sample)
    peak on its side, sampled on the other side. Impact, uplift and overturn
    times are those of the block. A record released from a measured tilt
    (free vibration) starts from the measured angle less the offset.

    Parameters
    ----------
    offset : float
        Offset [rad], in [-0.05, 0.05]; neutral 0.

    References
    ----------
    Bachmann et al. (2017), section 3.4 (angle accuracy 0.8 mrad; the initial
    offset is subtracted in post-processing).
    """

    name = "sensor_offset"
    params = {"offset": ParamSpec("rad", (-0.05, 0.05), 0.0, 0.0, "constant offset of the measured angle")}
    stage = STAGE_SENSOR
    offset: float = 0.0

    def transform_input(self, motion):
        # a block released from a measured tilt was released from the measured angle less the offset
        if self.offset == 0.0 or motion.theta0 == 0.0:
            return motion
        return replace(motion, theta0=motion.theta0 - self.offset)

    def observe(self, response):
        if self.offset == 0.0:
            return response
        th = response.theta
        hi, lo = float(np.max(th)), float(-np.min(th))
        if hi >= lo:
            hi = max(hi, response.theta_max)
        else:
            lo = max(lo, response.theta_max)
        theta_max = max(hi + self.offset, lo - self.offset, 0.0)
        if response.overturned:
            theta_max = math.pi / 2
        return replace(
            response,
            theta=th + self.offset,
            theta_max=theta_max,
            info={**response.info, "sensor_offset": self.offset},
        )


@register_effect
@dataclass(frozen=True)
class TimeLag(Effect):
    """The rotation channel lags the ground-acceleration channel by tau.

    The observed theta(t) is the block's theta(t - tau), linearly interpolated
    between samples (exact sample values when tau is a multiple of dt); before
    the record starts (t < tau) the initial state is held, beyond its end the
    last value. theta' is shifted the same way; impact, uplift and overturn
    times are moved by +tau. ``theta_max`` stays the block's own (between
    samples) if its sampled peak is inside the observed window, else it is the
    largest observed |theta|. Positive tau delays theta.

    Parameters
    ----------
    tau : float
        Lag of theta behind ground_acc [s], in [-0.1, 0.1]; neutral 0.

    References
    ----------
    Bachmann et al. (2017), section 3.4 (table and block measured by separate
    channels at 500 Hz).
    """

    name = "time_lag"
    params = {"tau": ParamSpec("s", (-0.1, 0.1), 0.0, 0.0, "lag of the theta channel behind ground_acc")}
    stage = STAGE_SENSOR
    # a free vibration has no ground channel to lag behind, and a measured one starts at the release
    # its theta channel shows (scenarios.campaign.estimate_release), which already carries the lag
    seen_in_free_vibration = False
    tau: float = 0.0

    def observe(self, response):
        if self.tau == 0.0:
            return response
        t = response.t
        n = t.size
        dt = float(t[1] - t[0]) if n > 1 else 1.0
        idx = np.arange(n, dtype=np.float64)
        src = idx - self.tau / dt
        theta = np.interp(src, idx, response.theta)
        theta_dot = np.interp(src, idx, response.theta_dot)
        k = int(np.argmax(np.abs(response.theta)))  # sample k is observed at index k + tau/dt
        if response.overturned or 0.0 <= k + self.tau / dt <= n - 1:
            theta_max = response.theta_max
        else:
            theta_max = float(np.max(np.abs(theta)))
        return replace(
            response,
            theta=theta,
            theta_dot=theta_dot,
            theta_max=theta_max,
            impact_times=response.impact_times + self.tau,
            uplift_time=response.uplift_time + self.tau,
            overturn_time=response.overturn_time + self.tau,
            info={**response.info, "time_lag": self.tau},
        )
