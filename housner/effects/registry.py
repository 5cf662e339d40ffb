"""The effects' vocabulary and registry: ParamSpec, Effect, register / discover / make.

Their composition for one simulation is :mod:`housner.effects.composition` (``apply_effects``).
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib
import math
import sys
import traceback
import warnings
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from importlib.metadata import entry_points
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from housner.effects.terms import import_file
from housner.errors import unknown_choice
from housner.motion import GroundMotion
from housner.readers import CHANNEL_PREFIX
from housner.response import Response
from housner.specimen import Specimen

ENTRY_POINT_GROUP = "housner.effects"

#: Stages, in order of application (see the module docstring).
STAGE_GEOMETRY, STAGE_INERTIA, STAGE_DISSIPATION, STAGE_MECHANICS, STAGE_SENSOR = 10, 20, 30, 40, 50

#: Registry: effect name -> Effect subclass.
EFFECTS: dict[str, type[Effect]] = {}
#: Module name -> the file of every effect plugin loaded (:func:`load_plugin`).
PLUGIN_FILES: dict[str, str] = {}
#: Plugin module -> SHA-256 (16 hex digits) of the file it was loaded from.
_PLUGIN_CODE: dict[str, str] = {}

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
    fast_path : bool
        True for an effect whose ``modify_params`` realises the same physics as its
        ``terms`` (faster, batched with the plain kernel): it is the default route, and
        ``apply_effects(..., prefer_terms=True)`` takes the terms instead.

    Notes
    -----
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
    channels: ClassVar[tuple[str, ...]] = ()
    makes_channels: ClassVar[tuple[str, ...]] = ()
    probe: ClassVar[bool] = False
    fast_path: ClassVar[bool] = False

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

    @classmethod
    def measured_params(cls, metrics: dict, specimen: Specimen) -> dict | None:
        """Parameters a campaign's localisation measures directly, better than a fit to the histories can.

        ``metrics`` maps the localisation quantities of
        :data:`housner.scenarios.campaigns.localise.METRICS` (for example ``"tilt_offset"``, the rotation
        read at rest [alpha]) to objects with ``value`` and ``se``.
        The diagnosis takes the parameters returned as measured and fits only the others. Default:
        None (every parameter is fitted within its bounds).
        """
        return None

    def __reduce__(self):
        # An effect travels to worker processes (spawned, or on a Dask cluster) by its class's module and
        # name and its fields; a plugin's class by its file, which the worker loads first.
        cls = type(self)
        values = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.init}
        return _rebuild_effect, (cls.__module__, cls.__qualname__, PLUGIN_FILES.get(cls.__module__), values)

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


def load_plugin(path) -> tuple[str, ...]:
    """Import a Python file as a module so that its ``@register_effect`` classes join :data:`EFFECTS`.

    The module is named ``housner_plugin_<stem>_<hash of the resolved path>`` and kept in
    ``sys.modules`` (so that its ``@njit`` term functions can be found by the generated kernels
    and numba can cache them); loading the same file again re-executes it.

    Parameters
    ----------
    path : str or path
        A ``.py`` file.

    Returns
    -------
    tuple of str
        The names of the effects it registers.

    Raises
    ------
    ValueError
        One line naming the file: it does not exist, is not a ``.py`` file, registers no effect, has a
        syntax error (with its line), or raises while it is imported (the exception's type, text and the
        file's line; the exception is the error's ``__cause__``). A bad plugin is bad input, as a bad
        record is: ``housner`` exits 2 on it.
    """
    p = Path(path).expanduser()
    if not p.is_file():
        raise ValueError(f"effect plugin {str(p)!r}: no such file")
    if p.suffix != ".py":
        raise ValueError(f"effect plugin {str(p)!r}: not a Python file (.py)")
    p = p.resolve()
    digest = hashlib.sha256(str(p).encode()).hexdigest()[:12]
    stem = "".join(ch if ch.isalnum() else "_" for ch in p.stem)
    modname = f"housner_plugin_{stem}_{digest}"
    code_hash = hashlib.sha256(p.read_bytes()).hexdigest()[:16]
    # The same file again, or a byte-identical copy of it elsewhere (a scenario's folder, a notebook's),
    # replaces the effects it registered before; another file may not take a registered name.
    same = {m for m, f in PLUGIN_FILES.items() if f == str(p) or _PLUGIN_CODE.get(m) == code_hash}
    before = dict(EFFECTS)
    for n in [n for n, cls in EFFECTS.items() if cls.__module__ in same]:
        del EFFECTS[n]
    try:
        _import_plugin(modname, p)
        names = tuple(n for n, cls in EFFECTS.items() if cls.__module__ == modname)
        if not names:
            sys.modules.pop(modname, None)
            raise ValueError(
                f"effect plugin {str(p)!r} registers no effect (decorate an Effect subclass with @register_effect)"
            )
    except BaseException:  # the registry is left as it was
        EFFECTS.clear()
        EFFECTS.update(before)
        raise
    PLUGIN_FILES[modname] = str(p)
    _PLUGIN_CODE[modname] = code_hash
    for n in names:
        # the code each class was loaded from, kept even once the file is reloaded: a result cache keys
        # on it (housner.scenarios.execution.cache.effect_code_hash)
        EFFECTS[n]._housner_code_hash = code_hash
    return names


def _import_plugin(modname: str, p: Path) -> None:
    """Import the plugin file; its syntax error, or an exception it raises, becomes one ValueError naming it."""
    try:
        import_file(modname, p)
    except SyntaxError as e:  # IndentationError too
        where = f" line {e.lineno}" if e.filename == str(p) and e.lineno else ""
        elsewhere = f" in {e.filename} line {e.lineno}" if e.filename != str(p) else ""
        raise ValueError(f"effect plugin {str(p)!r}{where}: syntax error{elsewhere} ({e.msg})") from e
    except (Exception, SystemExit) as e:  # the file's own code failed; Ctrl-C still propagates
        lines = [f.lineno for f in traceback.extract_tb(e.__traceback__) if f.filename == str(p)]
        where = f" line {lines[-1]}" if lines else ""
        text = " ".join(str(e).split())
        raise ValueError(
            f"effect plugin {str(p)!r}{where}: raises {type(e).__name__} when imported" + (f": {text}" if text else "")
        ) from e


def _rebuild_effect(module: str, qualname: str, plugin: str | None, values: dict) -> Effect:
    """The effect of :meth:`Effect.__reduce__`: its class imported (a plugin loaded from its file), then built."""
    if module not in sys.modules:
        if plugin is not None:
            load_plugin(plugin)
        else:
            importlib.import_module(module)
    obj: Any = sys.modules[module]
    for part in qualname.split("."):
        obj = getattr(obj, part)
    return obj(**values)


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
