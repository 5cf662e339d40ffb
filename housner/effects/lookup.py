"""Effects by name: the registry's lookups, which first load the installed packages' entry points.

The registry is :data:`housner.effects.registry.EFFECTS`; a name not in it yet is looked for among
the entry points (:func:`housner.effects.plugins.discover_effects`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping
from typing import Any

from housner.effects.plugins import discover_effects
from housner.effects.registry import EFFECTS, Effect
from housner.errors import unknown_choice
from housner.specimen import Specimen

__all__ = ["available_effects", "effect_class", "make_effect", "make_effects"]


def available_effects() -> tuple[str, ...]:
    """Names of every registered effect (built-in, decorated and installed), sorted; probes left out."""
    return tuple(sorted(n for n in discover_effects() if not EFFECTS[n].probe))


def effect_class(name: str) -> type[Effect]:
    """The effect class registered as ``name``; unknown names list the choices and suggest the closest."""
    cls = EFFECTS.get(name)
    if cls is None:
        discover_effects()
        cls = EFFECTS.get(name)
    if cls is None:
        raise unknown_choice("effect", name, EFFECTS)
    return cls


def make_effect(name: str, specimen: Specimen | None = None, **values: float) -> Effect:
    """Build the effect registered as ``name`` with the parameter ``values``, validating every value.

    Parameters
    ----------
    name : str
        Registry key (see :func:`available_effects`).
    specimen : Specimen, optional
        Also check the bounds that depend on the specimen.
    **values : float
        Parameter values in the units of the effect's :class:`~housner.effects.registry.ParamSpec`.

    Raises
    ------
    ValueError
        Unknown name or parameter (listing the choices), a missing required
        parameter, or a value out of bounds (naming the parameter).
    """
    cls = effect_class(name)
    specs = cls.param_specs
    for key in values:
        if key not in specs:
            raise unknown_choice(f"parameter of effect {name!r}:", key, specs)
    missing = [k for k, s in specs.items() if k not in values and _field_default(cls, k) is None]
    if missing:
        spec = specs[missing[0]]
        raise ValueError(f"effect {name!r} needs `{missing[0]}` [{spec.unit}] ({spec.doc})")
    effect = cls(**values)
    if specimen is not None:
        effect.check(specimen)
    return effect


def _field_default(cls: type, key: str) -> Any:
    """The default of the dataclass field ``key`` of ``cls``; None when it has none (a required parameter)."""
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
