"""The effects' vocabulary: ParamSpec and :func:`param`, Effect, the stages, and the registry EFFECTS.

An effect's parameter is declared once, on its dataclass field (:func:`param`); the table of its
parameters (:attr:`Effect.param_specs`) is read off the fields. Where effects come from (installed
packages' entry points, plugin files) is :mod:`housner.effects.plugins`; an effect by name is
:mod:`housner.effects.lookup`; their composition for one simulation is
:mod:`housner.effects.composition` (``apply_effects``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, ClassVar
from weakref import WeakKeyDictionary

import numpy as np

from housner.motion import GroundMotion
from housner.readers.measured_data import CHANNEL_PREFIX
from housner.response import Response
from housner.specimen import Specimen

__all__ = [
    "EFFECTS",
    "STAGE_DISSIPATION",
    "STAGE_GEOMETRY",
    "STAGE_INERTIA",
    "STAGE_MECHANICS",
    "STAGE_SENSOR",
    "Effect",
    "ParamSpec",
    "param",
    "register_effect",
]

#: Stages, in order of application (see :mod:`housner.effects`).
STAGE_GEOMETRY, STAGE_INERTIA, STAGE_DISSIPATION, STAGE_MECHANICS, STAGE_SENSOR = 10, 20, 30, 40, 50

#: Registry: effect name -> Effect subclass.
EFFECTS: dict[str, type[Effect]] = {}

#: The key of a dataclass field's metadata that holds its :class:`ParamSpec` (:func:`param`).
_SPEC_KEY = "housner.effects.param"


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
        The dataclass field's default (the start value of a fit); None when
        the parameter is required. :func:`param` sets it from the field.
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


def param(
    unit: str,
    bounds: tuple[float, float] | Callable[[Specimen], tuple[float, float]],
    *,
    neutral: float | Callable[[Specimen], float],
    default: float = dataclasses.MISSING,
    doc: str = "",
) -> Any:
    """A parameter of an effect: its dataclass field, carrying its :class:`ParamSpec`.

    Use as the field's value in the effect's dataclass::

        gain: float = param("-", (0.5, 1.5), neutral=1.0, default=1.0, doc="table gain")

    Parameters
    ----------
    unit, bounds, neutral, doc
        Those of :class:`ParamSpec`.
    default : float, optional
        The field's default; without one the parameter is required.

    Returns
    -------
    dataclasses.Field
        The field, with the spec in its metadata (read back by :attr:`Effect.param_specs`).
    """
    spec = ParamSpec(unit, bounds, neutral, None if default is dataclasses.MISSING else default, doc)
    return dataclasses.field(default=default, metadata={_SPEC_KEY: spec})


class _ParamSpecTable:
    """The class attribute :attr:`Effect.param_specs`: parameter name -> :class:`ParamSpec`, in field order.

    Read off the dataclass fields declared with :func:`param`; an effect whose fields carry no spec may
    give the table itself as a class attribute ``params`` (one :class:`ParamSpec` per field).
    """

    def __init__(self) -> None:
        self._tables: WeakKeyDictionary = WeakKeyDictionary()

    def __get__(self, obj: Any, owner: type) -> Mapping[str, ParamSpec]:
        table = self._tables.get(owner)
        if table is None:
            if not dataclasses.is_dataclass(owner):
                return MappingProxyType(dict(getattr(owner, "params", {})))
            fields = dataclasses.fields(owner)
            declared = {f.name: f.metadata[_SPEC_KEY] for f in fields if _SPEC_KEY in f.metadata}
            table = MappingProxyType(declared or dict(getattr(owner, "params", {})))
            self._tables[owner] = table
        return table


class Effect:
    """Base class of the physical effects (subclasses are frozen dataclasses).

    Attributes
    ----------
    name : str
        Registry key.
    param_specs : mapping of str to ParamSpec
        One entry per dataclass field, in field order: read off the fields declared with
        :func:`param` (or, for an effect whose fields carry no spec, the class attribute
        ``params``, a table of one :class:`ParamSpec` per field).
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
    makes_channels : tuple of str
        Channels this effect's ``transform_input`` adds to the motion (they then satisfy the
        ``channels`` of the effects given with it, and ``"ground_acc_vertical"`` drives the terms' v).
    probe : bool
        A localisation probe (a physical class tried to say where a misfit lies, never offered as an
        explanation): left out of :func:`available_effects`, so never a candidate of a search.
    channels : tuple of str
        The extra channels of the motion this effect reads (``GroundMotion.channels``,
        e.g. ``"ground_acc_vertical"``); a motion without one of them is refused by name
        before any simulation. ``"ground_acc_vertical"`` drives the terms' v.
    probe_summary : str
        A probe's physics in a few words (the verdict names the probe with them).
    fast_path : bool
        True for an effect whose ``modify_params`` realises the same physics as its
        ``terms`` (faster, batched with the plain kernel): it is the default route, and
        ``apply_effects(..., prefer_terms=True)`` takes the terms instead.
    solver_step_cost : float
        For an effect with its own solver: the cost of one of its steps relative to a step of the sliding
        kernel's (about 20 ns on 2 cores), measured once; what the outcome tables count their work in
        (:data:`housner.scenarios.diagnosis.outcomes.outcome_effects.SOLVER_BUDGET_STEPS`). 1 by default.

    Notes
    -----
    The dataclass fields are validated on construction against the static
    bounds (a value outside them raises a ValueError naming the parameter,
    unless it is the neutral value); specimen-dependent bounds are checked by
    :meth:`check`, which :func:`apply_effects` calls.
    """

    name: ClassVar[str] = ""
    param_specs: ClassVar[Mapping[str, ParamSpec]] = _ParamSpecTable()
    stage: ClassVar[int] = STAGE_DISSIPATION
    changes_mechanics: ClassVar[bool] = False
    conflicts: ClassVar[frozenset[str]] = frozenset()
    conflict_reason: ClassVar[str] = ""
    seen_in_free_vibration: ClassVar[bool] = True
    channels: ClassVar[tuple[str, ...]] = ()
    makes_channels: ClassVar[tuple[str, ...]] = ()
    probe: ClassVar[bool] = False
    probe_summary: ClassVar[str] = ""
    fast_path: ClassVar[bool] = False
    solver_step_cost: ClassVar[float] = 1.0

    def __post_init__(self) -> None:
        for key, spec in self.param_specs.items():
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
        for key, spec in self.param_specs.items():
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
        for key, spec in cls.param_specs.items():
            v = spec.neutral_for(specimen)
            if v is None and callable(spec.neutral):
                raise ValueError(f"the neutral `{key}` of effect {cls.name!r} depends on the specimen; pass it")
            kwargs[key] = v if v is not None else spec.default
        return cls(**kwargs)

    @classmethod
    def measured_params(cls, metrics: dict, specimen: Specimen) -> dict | None:
        """Parameters a campaign's localisation measures directly, better than a fit to the histories can.

        ``metrics`` maps the localisation quantities of
        :data:`housner.scenarios.diagnosis.comparison.localise.METRICS` (for example ``"tilt_offset"``, the rotation
        read at rest [alpha]) to objects with ``value`` and ``se``.
        The diagnosis takes the parameters returned as measured and fits only the others. Default:
        None (every parameter is fitted within its bounds).
        """
        return None

    def describe(self) -> dict:
        """Plain data: ``{"name": ..., <param>: value, ...}`` (for results tables and the cache)."""
        return {"name": self.name, **{k: getattr(self, k) for k in self.param_specs}}

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

    def terms(self, params, specimen: Specimen) -> tuple:
        """Terms this effect adds to the analytic kernel (default: none).

        ``params`` are the rocking parameters after every ``modify_params`` (so a term can use the
        final p and alpha of each pivot). Returns :class:`housner.effects.terms.MomentTerm`,
        :class:`~housner.effects.terms.CoulombTerm` and :class:`~housner.effects.terms.ImpactTerm`
        instances (see :mod:`housner.effects.terms`).
        """
        return ()


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
    """Add ``cls`` to :data:`EFFECTS` as ``name`` (default its ``name``), once its declaration is checked."""
    if not (isinstance(cls, type) and issubclass(cls, Effect)):
        raise TypeError(f"only housner.effects.Effect subclasses can be registered, got {cls!r}")
    if not dataclasses.is_dataclass(cls):
        raise TypeError(f"effect class {cls.__qualname__} must be a dataclass (use @dataclass(frozen=True))")
    name = cls.name if name is None else name
    if not isinstance(name, str) or not name.isidentifier():
        raise ValueError(f"effect class {cls.__qualname__} needs a `name` that is an identifier, got {name!r}")
    _check_param_specs(cls, name)
    chans = cls.channels
    if not isinstance(chans, tuple) or not all(isinstance(c, str) and c.startswith(CHANNEL_PREFIX) for c in chans):
        raise ValueError(
            f"effect {name!r}: `channels` must be a tuple of channel names '{CHANNEL_PREFIX}<what>', got {chans!r}"
        )
    old = EFFECTS.get(name)
    if old is not None and old is not cls and (old.__module__, old.__qualname__) != (cls.__module__, cls.__qualname__):
        raise ValueError(f"effect name {name!r} is already registered by {old.__module__}.{old.__qualname__}")
    cls.name = name
    EFFECTS[name] = cls
    return cls


def _check_param_specs(cls: type[Effect], name: str) -> None:
    """ValueError or TypeError unless every dataclass field of ``cls`` has one :class:`ParamSpec`, declared once."""
    fields = dataclasses.fields(cls)
    declared = [f.name for f in fields if _SPEC_KEY in f.metadata]
    if declared and "params" in vars(cls):
        raise ValueError(
            f"effect {name!r}: its parameters are declared twice, with param() on the fields and in a `params` "
            "table; keep the fields' param()"
        )
    specs = cls.param_specs
    if sorted(f.name for f in fields) != sorted(specs):
        raise ValueError(
            f"effect {name!r}: the parameter specs ({', '.join(specs) or 'none'}) must match the dataclass "
            f"fields ({', '.join(f.name for f in fields) or 'none'}); declare each field with param(...)"
        )
    for key, spec in specs.items():
        if not isinstance(spec, ParamSpec):
            raise TypeError(f"effect {name!r}: params[{key!r}] must be a ParamSpec, got {spec!r}")
