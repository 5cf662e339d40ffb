"""The engine protocol and its registry.

An engine turns (specimen, motion, effects) into a :class:`housner.Response`,
whole record in, whole response out. ``Engine.simulate`` validates its inputs
and calls ``_simulate``; subclasses implement only ``_simulate``.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Sequence
from importlib import metadata
from typing import Any, ClassVar

import numpy as np

from housner.errors import EngineError, unknown_choice
from housner.motion import GroundMotion
from housner.response import Response
from housner.specimen import Specimen

__all__ = ["ENGINES", "RECORD_ERRORS", "Engine", "check_response", "get_engine", "register_engine"]

#: Registry: engine name -> class, or "module:Class" imported on first use
#: (so that `import housner.engines` does not import MuJoCo or PyBullet).
ENGINES: dict[str, Any] = {
    "housner": "housner.engines.analytic:HousnerEngine",
    "mujoco": "housner.engines.mujoco_engine:MujocoEngine",
    "pybullet": "housner.engines.pybullet_engine:PybulletEngine",
    "dart": "housner.engines.dart_engine:DartEngine",
    "opensees": "housner.engines.opensees_engine:OpenSeesEngine",
    "drake": "housner.engines.drake_engine:DrakeEngine",
}

#: The PyPI distribution each registered engine drives (read without importing the engine, for
#: ``housner --version``); an engine absent here is taken to be its own distribution.
ENGINE_PACKAGES: dict[str, str] = {
    "housner": "housner",
    "mujoco": "mujoco",
    "pybullet": "pybullet",
    "dart": "dartpy",
    "opensees": "openseespy",
    "drake": "drake",
}


def register_engine(name: str) -> Callable[[type], type]:
    """Class decorator that adds an engine to :data:`ENGINES` under ``name``."""

    def deco(cls: type) -> type:
        cls.name = name
        ENGINES[name] = cls
        return cls

    return deco


def engine_class(name: str) -> type:
    """The engine class registered as ``name``; unknown names list the choices."""
    try:
        entry = ENGINES[name]
    except KeyError:
        raise unknown_choice("engine", name, ENGINES) from None
    if isinstance(entry, str):
        module, _, attr = entry.partition(":")
        entry = getattr(importlib.import_module(module), attr)
        ENGINES[name] = entry
    return entry


def get_engine(name: str, **settings: Any) -> Engine:
    """Instantiate the engine registered as ``name`` with ``settings``."""
    return engine_class(name)(**settings)


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

    #: The PyPI distribution the engine drives ("" for none): :meth:`version` reports its version.
    package: ClassVar[str] = ""

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
