"""Where effects come from besides the library: installed packages' entry points and plugin files.

:func:`discover_effects` loads the ``housner.effects`` entry-point group of the installed packages;
:func:`load_plugin` imports a Python file whose ``@register_effect`` classes join
:data:`housner.effects.registry.EFFECTS`. A plugin's effect travels to a worker process (spawned,
or on a Dask cluster) by its file, which the worker loads first (its classes' reduction is
registered with :mod:`copyreg`); every other effect pickles as any dataclass, by its class's
module and name and its fields.
"""

from __future__ import annotations

import copyreg
import dataclasses
import hashlib
import importlib
import sys
import traceback
import warnings
from importlib.metadata import entry_points
from pathlib import Path
from typing import Any

from housner.effects.codegen import import_file
from housner.effects.registry import EFFECTS, Effect, register_effect

__all__ = ["ENTRY_POINT_GROUP", "PLUGIN_FILES", "discover_effects", "load_plugin"]

ENTRY_POINT_GROUP = "housner.effects"

#: Module name -> the file of every effect plugin loaded (:func:`load_plugin`).
PLUGIN_FILES: dict[str, str] = {}
#: Plugin module -> SHA-256 (16 hex digits) of the file it was loaded from.
_PLUGIN_CODE: dict[str, str] = {}

_discovered = False


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
                register_effect(obj)
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
    for obj in list(vars(sys.modules[modname]).values()):
        if isinstance(obj, type) and issubclass(obj, Effect) and obj.__module__ == modname:
            copyreg.pickle(obj, _reduce_plugin_effect)
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


def _reduce_plugin_effect(effect: Effect) -> tuple:
    """How an effect of a plugin's class pickles: its class's module and name, the plugin's file and its fields."""
    cls = type(effect)
    values = {f.name: getattr(effect, f.name) for f in dataclasses.fields(effect) if f.init}
    return _rebuild_effect, (cls.__module__, cls.__qualname__, PLUGIN_FILES.get(cls.__module__), values)


def _rebuild_effect(module: str, qualname: str, plugin: str | None, values: dict) -> Effect:
    """The effect of :func:`_reduce_plugin_effect`: its class imported (a plugin loaded from its file), then built."""
    if module not in sys.modules:
        if plugin is not None:
            load_plugin(plugin)
        else:
            importlib.import_module(module)
    obj: Any = sys.modules[module]
    for part in qualname.split("."):
        obj = getattr(obj, part)
    return obj(**values)
