"""The result cache: one entry per (specimen, motion, engine, settings, version, effects, code), by content.

Each entry stores its key and a SHA-256 of its payload (key, row fields,
theta bytes); an entry under the wrong key or failing its checksum is
reported (a warning on the ``housner.runner`` logger) and recomputed by the
runner. Location: ``$HOUSNER_CACHE_DIR`` or ``~/.cache/housner``.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import logging
import os
import threading
from contextlib import suppress
from pathlib import Path

import housner
from housner import engines
from housner.motion import GroundMotion
from housner.scenarios.execution.rundir import effect_data, jsonable
from housner.specimen import Specimen


def default_cache_dir() -> Path:
    """``$HOUSNER_CACHE_DIR`` or ``~/.cache/housner``."""
    env = os.environ.get("HOUSNER_CACHE_DIR")
    return Path(env) if env else Path.home() / ".cache" / "housner"


_CODE_VERSION: str | None = None
#: Sub-packages of ``housner`` that are not physics: installed, they sit inside housner/'s folder.
_ABOVE_PHYSICS = ("engines", "scenarios", "reports", "cli")


def code_version() -> str:
    """Hash of the suite's physics and engine sources (part of every cache key)."""
    global _CODE_VERSION
    if _CODE_VERSION is None:
        h = hashlib.sha256(housner.__version__.encode())
        # The physics (housner/ less the layers above it, which share its name once installed) and the engines.
        for pkg, above in ((housner, _ABOVE_PHYSICS), (engines, ())):
            root = Path(pkg.__file__).parent
            for f in sorted(root.rglob("*")):
                rel = f.relative_to(root)
                if f.suffix in (".py", ".xml", ".urdf") and "__pycache__" not in f.parts and rel.parts[0] not in above:
                    h.update(rel.as_posix().encode())
                    h.update(f.read_bytes())
        _CODE_VERSION = h.hexdigest()[:16]
    return _CODE_VERSION


def effect_code_hash(effect) -> str | None:
    """SHA-256 (16 hex digits) of the source file of a user's effect; None for the library's own.

    The library's effects are covered by :func:`code_version`; an effect defined elsewhere (a
    ``--plugin`` file, an installed package's entry point) is keyed by its module's file, so that a
    changed effect is recomputed, not read back from the cache.
    """
    cls = type(effect)
    loaded = cls.__dict__.get("_housner_code_hash")  # a plugin's class: the code it was loaded from
    if loaded is not None:
        return loaded
    try:
        path = Path(inspect.getsourcefile(cls) or "")
    except (TypeError, OSError):
        path = Path()
    lib = Path(housner.__file__).resolve().parent
    if path.is_file():
        rp = path.resolve()
        if lib in rp.parents:
            return None
        return hashlib.sha256(rp.read_bytes()).hexdigest()[:16]
    # defined where no file says what it does (an interactive session): its source, if it can be read
    try:
        return hashlib.sha256(inspect.getsource(cls).encode()).hexdigest()[:16]
    except (TypeError, OSError):
        return f"unreadable:{cls.__module__}.{cls.__qualname__}"


def cache_key(
    specimen: Specimen, motion: GroundMotion, engine: str, settings: dict, version: str, effects: tuple = ()
) -> str:
    """Content hash of everything that determines one (engine, effects, motion) result."""
    return _key(_shared_content(specimen, engine, settings, version, effects), motion)


def cache_keys(
    specimen: Specimen, motions: list[GroundMotion], engine: str, settings: dict, version: str, effects: tuple = ()
) -> list[str]:
    """:func:`cache_key` of each motion (the very same strings), the parts the motions share made once."""
    shared = _shared_content(specimen, engine, settings, version, effects)
    return [_key(shared, m) for m in motions]


def _shared_content(specimen: Specimen, engine: str, settings: dict, version: str, effects: tuple) -> dict:
    """Everything in a key but the motion, as plain JSON data."""
    content = {
        "specimen": specimen.describe(),
        "engine": engine,
        "settings": settings,
        "engine_version": version,
        "code": code_version(),
    }
    if effects:  # no key for none: results without effects keep their cache entries
        content["effects"] = [effect_data(e) for e in effects]
        user = {type(e).name: h for e in effects if (h := effect_code_hash(e))}
        if user:  # a user's effect (plugin, entry point): its code is part of the result
            content["effect_code"] = user
    return jsonable(content)


def _key(shared: dict, motion: GroundMotion) -> str:
    """SHA-256 of the canonical JSON of the shared content and the motion's content hash."""
    return content_key({**shared, "motion": motion.content_hash()})


def content_key(content) -> str:
    """SHA-256 (hex) of the canonical JSON of ``content``: keys sorted, a value JSON cannot hold as its ``str``.

    The key of every cache file: a record's entry (:func:`cache_key`), an engine's free-rocking errors, a
    stored figure.
    """
    return hashlib.sha256(json.dumps(content, sort_keys=True, default=str).encode()).hexdigest()


def store_text(path: str | Path, text: str) -> None:
    """Write a cache file whole: a temporary file of this process and thread, renamed into place, so that a
    reader never sees half of it. A cache that cannot be written is skipped, not an error."""
    path = Path(path)
    tmp = path.with_name(f"{path.name}.{os.getpid()}.{threading.get_ident()}.tmp")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, path)
    except OSError:
        with suppress(OSError):
            tmp.unlink()


# --------------------------------------------------------------------------
# Result cache: one .npz per key, holding theta and the row, with the key and a checksum. The format is
# written and read in housner.scenarios.execution.chunks (which the worker processes load by its path).
runner_logger = logging.getLogger("housner.runner")

__all__ = [
    "cache_key",
    "cache_keys",
    "code_version",
    "content_key",
    "default_cache_dir",
    "effect_code_hash",
    "store_text",
]
