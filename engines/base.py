"""The engine protocol and its registry.

An engine turns (specimen, motion, effects) into a :class:`housner.Response`,
whole record in, whole response out. ``Engine.simulate`` validates its inputs
and calls ``_simulate``; subclasses implement only ``_simulate``.

The registry, :data:`ENGINES`, maps each engine's name to its :class:`EngineSpec`: the facts about
the engine that are not its physics (where its class lives, the distribution it drives, how to
install that, how messages name it), each declared once. An engine class reads them from its spec
(:class:`SpecAttribute`), so that ``housner --version`` and the help can list the engines without
importing any of them.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator, MutableMapping, Sequence
from dataclasses import dataclass
from importlib import metadata
from typing import Any, ClassVar

import numpy as np

from housner.errors import EngineError, unknown_choice
from housner.motion import GroundMotion
from housner.response import Response
from housner.specimen import Specimen

__all__ = [
    "ENGINES",
    "RECORD_ERRORS",
    "Engine",
    "EngineRegistry",
    "EngineSpec",
    "SpecAttribute",
    "check_response",
    "engine_class",
    "engine_spec",
    "get_engine",
    "register_engine",
]


@dataclass(frozen=True)
class EngineSpec:
    """One engine as the registry knows it, without importing it.

    Parameters
    ----------
    name : str
        The registry name (``housner run --engines NAME``); the engine class's ``name``.
    entry_point : str or type
        The engine class, or ``"module:Class"`` naming it, imported on first use (:meth:`load`).
    distribution : str
        The PyPI distribution the engine drives ("" for none): :meth:`Engine.version` reports its
        version, and ``housner --version`` reads it from the package metadata.
    install : str
        How to install that distribution, named when it is missing ("" when it ships with housner).
    label : str
        The engine as messages name it ("MuJoCo", "OpenSees"); its name when not given.
    """

    name: str
    entry_point: str | type
    distribution: str = ""
    install: str = ""
    label: str = ""

    def __post_init__(self) -> None:
        if not (isinstance(self.name, str) and self.name):
            raise ValueError(f"an engine's name must be a non-empty string, got {self.name!r}")
        if isinstance(self.entry_point, str):
            module, _, attr = self.entry_point.partition(":")
            if not (module and attr):
                raise ValueError(f"engine {self.name!r}: entry point {self.entry_point!r} is not 'module:Class'")
        elif not isinstance(self.entry_point, type):
            raise TypeError(
                f"engine {self.name!r}: the entry point must be a class or 'module:Class', "
                f"got {type(self.entry_point).__name__}"
            )
        if not self.label:
            object.__setattr__(self, "label", self.name)

    @property
    def module(self) -> str:
        """The module that defines the engine class (read from the entry point, nothing imported)."""
        if isinstance(self.entry_point, str):
            return self.entry_point.partition(":")[0]
        return self.entry_point.__module__

    @classmethod
    def from_class(
        cls,
        name: str,
        engine: type,
        distribution: str | None = None,
        install: str | None = None,
        label: str | None = None,
    ) -> EngineSpec:
        """The spec of an engine class registered as ``name``: the facts not given are the class's own or
        inherited ``package``, ``INSTALL`` and ``LABEL`` (so that a subclass of a registered engine keeps them)."""
        return cls(
            name,
            engine,
            distribution=getattr(engine, "package", "") if distribution is None else distribution,
            install=getattr(engine, "INSTALL", "") if install is None else install,
            label=getattr(engine, "LABEL", "") if label is None else label,
        )

    def load(self) -> type:
        """The engine class, its module imported on first use."""
        if not isinstance(self.entry_point, str):
            return self.entry_point
        module, _, attr = self.entry_point.partition(":")
        return getattr(importlib.import_module(module), attr)

    def make(self, **settings: Any) -> Engine:
        """An instance of the engine with ``settings``."""
        return self.load()(**settings)


class EngineRegistry(MutableMapping):
    """Engine name -> :class:`EngineSpec`, in the order of registration.

    An engine class or a ``"module:Class"`` string stored under a name (``ENGINES[name] = cls``, the
    registry's values before the specs) is registered as the spec of that entry point
    (:meth:`EngineSpec.from_class` for a class).
    """

    def __init__(self, specs: Sequence[EngineSpec] = ()):
        self._specs: dict[str, EngineSpec] = {}
        for spec in specs:
            self[spec.name] = spec

    def __getitem__(self, name: str) -> EngineSpec:
        return self._specs[name]

    def __setitem__(self, name: str, value: EngineSpec | str | type) -> None:
        if isinstance(value, type):
            value = EngineSpec.from_class(name, value)
        elif not isinstance(value, EngineSpec):
            value = EngineSpec(name, value)
        elif value.name != name:
            raise ValueError(f"the spec of engine {value.name!r} cannot be registered as {name!r}")
        self._specs[name] = value

    def __delitem__(self, name: str) -> None:
        del self._specs[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._specs)

    def __len__(self) -> int:
        return len(self._specs)

    def __repr__(self) -> str:
        return f"EngineRegistry({list(self._specs.values())!r})"


#: The registry: engine name -> :class:`EngineSpec`. The shipped engines are named by
#: ``"module:Class"``, so that ``import housner.engines`` imports neither MuJoCo nor PyBullet.
ENGINES = EngineRegistry(
    (
        EngineSpec("housner", "housner.engines.analytic:HousnerEngine", distribution="housner", label="Housner"),
        EngineSpec("mujoco", "housner.engines.mujoco_engine:MujocoEngine", distribution="mujoco", label="MuJoCo"),
        EngineSpec(
            "pybullet", "housner.engines.pybullet_engine:PybulletEngine", distribution="pybullet", label="PyBullet"
        ),
        EngineSpec(
            "dart",
            "housner.engines.dart_engine:DartEngine",
            distribution="dartpy",
            install="pip install -e '.[dart]'  (or: pip install dartpy)",
            label="DART",
        ),
        EngineSpec(
            "opensees",
            "housner.engines.opensees_engine:OpenSeesEngine",
            distribution="openseespy",
            install="pip install -e '.[opensees]'  (or: pip install 'openseespy>=3.7.1.2,<3.8')",
            label="OpenSees",
        ),
        EngineSpec(
            "drake",
            "housner.engines.drake_engine:DrakeEngine",
            distribution="drake",
            install="pip install -e '.[drake]'  (or: pip install drake)",
            label="Drake",
        ),
        # The 3D scan-mesh engines (a rock's mesh as a free rigid body), after the planar six whose order tests pin.
        EngineSpec(
            "mujoco-3d",
            "housner.engines.scan_mesh.mujoco_mesh_engine:MujocoMeshEngine",
            distribution="mujoco",
            label="MuJoCo 3D",
        ),
        EngineSpec(
            "pybullet-3d",
            "housner.engines.scan_mesh.pybullet_mesh_engine:PybulletMeshEngine",
            distribution="pybullet",
            label="PyBullet 3D",
        ),
    )
)


def register_engine(
    name: str,
    entry_point: str | type | None = None,
    *,
    distribution: str | None = None,
    install: str | None = None,
    label: str | None = None,
) -> Any:
    """Add an engine to :data:`ENGINES` under ``name``.

    Parameters
    ----------
    name : str
        The registry name.
    entry_point : str or type, optional
        The engine class or ``"module:Class"`` (imported on first use). Without it,
        ``register_engine(name)`` is a class decorator: it registers the class it decorates and
        sets its ``name``.
    distribution, install, label : str, optional
        As :class:`EngineSpec`'s. Not given: for a class, its own or inherited ``package``,
        ``INSTALL`` and ``LABEL`` (:meth:`EngineSpec.from_class`); for ``"module:Class"``, none.

    Returns
    -------
    EngineSpec or callable
        The registered spec; the class decorator when no ``entry_point`` is given.

    Examples
    --------
    A plugin package registers its engine without importing it (or decorates the class:
    ``@register_engine("mine")``):

    >>> from housner.engines import ENGINES, register_engine
    >>> spec = register_engine("mine", "mysolver.engine:MyEngine", distribution="mysolver")
    >>> ENGINES["mine"].module
    'mysolver.engine'
    >>> del ENGINES["mine"]
    """
    if entry_point is not None:
        if isinstance(entry_point, type):
            spec = EngineSpec.from_class(name, entry_point, distribution, install, label)
        else:
            spec = EngineSpec(name, entry_point, distribution or "", install or "", label or "")
        ENGINES[name] = spec
        return spec

    def deco(cls: type) -> type:
        spec = EngineSpec.from_class(name, cls, distribution, install, label)  # read before the class is renamed
        cls.name = name
        ENGINES[name] = spec
        return cls

    return deco


def engine_spec(name: str) -> EngineSpec:
    """The spec registered as ``name``; unknown names list the choices."""
    try:
        return ENGINES[name]
    except KeyError:
        raise unknown_choice("engine", name, ENGINES) from None


def engine_class(name: str) -> type:
    """The engine class registered as ``name``, imported on first use; unknown names list the choices."""
    return engine_spec(name).load()


def get_engine(name: str, **settings: Any) -> Engine:
    """Instantiate the engine registered as ``name`` with ``settings``."""
    return engine_spec(name).make(**settings)


class SpecAttribute:
    """A class attribute of an engine read from its registry entry (the spec under the class's ``name``).

    Parameters
    ----------
    field : str
        The :class:`EngineSpec` field it reads. An engine that is not registered reads "";
        a class that sets the attribute itself keeps its own value.
    """

    def __init__(self, field: str):
        self.field = field

    def __get__(self, obj: Any, owner: type) -> str:
        spec = ENGINES.get(getattr(owner, "name", ""))
        return getattr(spec, self.field) if spec is not None else ""


class Engine:
    """Base class of every engine.

    Attributes
    ----------
    name : str
        Registry name.
    effects_supported : frozenset of str
        Names of the physical effects this engine realises; others are refused by name.
    """

    name: ClassVar[str] = "engine"
    effects_supported: ClassVar[frozenset[str]] = frozenset()

    def simulate(self, specimen: Specimen, motion: GroundMotion, effects: Sequence[Any] = ()) -> Response:
        """Simulate one record.

        Parameters
        ----------
        specimen : Specimen
        motion : GroundMotion
            Ground acceleration [m/s^2] and the initial state (theta0 [rad], theta_dot0 [rad/s]).
        effects : sequence of effects
            Physical effects to add (each has a ``name``); an engine refuses those it cannot realise.
        """
        if not isinstance(specimen, Specimen):
            raise TypeError(f"`specimen` must be a housner.Specimen, got {type(specimen).__name__}")
        if not isinstance(motion, GroundMotion):
            raise TypeError(f"`motion` must be a housner.GroundMotion, got {type(motion).__name__}")
        effects = tuple(effects)
        self._refuse_unrealised(effects)
        why = self.effect_refusal(specimen, effects)
        if why:
            raise ValueError(why)
        return check_response(self._simulate(specimen, motion, effects), self.name, motion)

    def simulate_many(
        self, specimen: Specimen, motions: Sequence[GroundMotion], effects: Sequence[Any] = (), *, errors: str = "raise"
    ) -> list:
        """Simulate several records: one :meth:`simulate` each (an engine may batch them, with the same results).

        Parameters
        ----------
        specimen : Specimen
        motions : sequence of GroundMotion
        effects : sequence of effects
            The same effects for every record.
        errors : {"raise", "return"}
            What a record the engine fails on gives: its exception raised (the
            default), or returned in the record's place, the others kept.

        Returns
        -------
        list
            One :class:`housner.Response` per motion, in order, each passed by
            :func:`check_response` (or, with ``errors="return"``, the exception of a failed record).
        """
        check_errors(errors)
        out: list = []
        for m in motions:
            try:
                out.append(self.simulate(specimen, m, effects))
            except RECORD_ERRORS as e:
                if errors == "raise":
                    raise
                out.append(e)
        return out

    def effect_refusal(self, specimen: Specimen, effects: tuple) -> str | None:
        """Why this engine cannot realise these (supported) effects on this specimen, or None.

        For an effect whose value lies out of the engine's reach (a planar adapter realises the
        ``restitution`` effect only at or below its contact's r). Scenarios ask before any work.
        """
        return None

    def _refuse_unrealised(self, effects: tuple) -> None:
        """ValueError naming the first effect this engine does not realise, and those it does."""
        for e in effects:
            ename = getattr(e, "name", type(e).__name__)
            if ename not in self.effects_supported:
                supported = ", ".join(sorted(self.effects_supported)) or "none"
                raise ValueError(f"engine {self.name!r} cannot realise effect {ename!r} (it realises: {supported})")

    def _simulate(self, specimen: Specimen, motion: GroundMotion, effects: tuple) -> Response:
        raise NotImplementedError

    #: The PyPI distribution the engine drives ("" for none), from its spec: :meth:`version` reports its version.
    package = SpecAttribute("distribution")

    def settings(self) -> dict:
        """The engine's settings as plain data (for reports and the result cache): its ``_settings``, if any."""
        return dict(getattr(self, "_settings", {}))

    def version(self) -> str:
        """Version of the underlying package (for provenance and the result cache)."""
        if not self.package:
            return ""
        return metadata.version(self.package)

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.settings().items())
        return f"{type(self).__name__}({args})"


def check_response(resp: Response, engine: str, motion: GroundMotion) -> Response:
    """The output check every engine's response passes: a finite theta history, a peak that is a number.

    :meth:`Engine.simulate` and every ``simulate_many`` apply it; a caller
    that holds a response from elsewhere (a worker process, the cache) can
    apply the same check.

    Parameters
    ----------
    resp : Response
        The engine's answer: theta [rad] on the motion's grid, theta_max/alpha [-].
    engine : str
        The engine's registry name (for the message).
    motion : GroundMotion
        The motion it answered (for the message).

    Returns
    -------
    Response
        ``resp`` itself.

    Raises
    ------
    EngineError
        Naming the engine and the motion: the engine diverged or returned no usable history.
    """
    theta = np.asarray(resp.theta, dtype=float)
    if theta.size == 0 or not np.all(np.isfinite(theta)):
        raise EngineError(f"engine {engine!r} returned a non-finite theta history on motion {motion.name!r}")
    if np.isnan(resp.theta_max_over_alpha):
        raise EngineError(f"engine {engine!r} returned no theta_max on motion {motion.name!r}")
    return resp


#: Exceptions that fail one record (an engine diverging, a refused value), not the whole batch.
RECORD_ERRORS = (EngineError, ValueError, FloatingPointError, ArithmeticError)


def check_errors(errors: str) -> None:
    if errors not in ("raise", "return"):
        raise ValueError(f"`errors` must be 'raise' or 'return', got {errors!r}")
