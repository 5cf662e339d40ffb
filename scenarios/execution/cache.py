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
from pathlib import Path

import numpy as np
from housner.scenarios.execution.rundir import effect_data, jsonable

import housner
from housner import engines
from housner.motion import GroundMotion
from housner.specimen import Specimen


def default_cache_dir() -> Path:
    """``$HOUSNER_CACHE_DIR`` or ``~/.cache/housner``."""
    env = os.environ.get("HOUSNER_CACHE_DIR")
    return Path(env) if env else Path.home() / ".cache" / "housner"


_CODE_VERSION: str | None = None
#: Sub-packages of ``housner`` that are not physics: installed, they sit inside housner/'s folder.
_ABOVE_PHYSICS = ("engines", "scenarios", "reports", "cli.py")


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
    content = {
        "specimen": specimen.describe(),
        "motion": motion.content_hash(),
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
    payload = json.dumps(jsonable(content), sort_keys=True)
    return hashlib.sha256(payload.encode()).hexdigest()


# --------------------------------------------------------------------------
# Result cache: one .npz per key, holding theta and the row, with the key and a checksum.
_log = logging.getLogger("housner.runner")


def _entry_checksum(key: str, meta: dict, theta: np.ndarray) -> str:
    """SHA-256 of an entry's payload: its key, its row fields (canonical JSON) and theta's bytes."""
    h = hashlib.sha256()
    h.update(key.encode())
    h.update(b"\0")
    h.update(json.dumps({k: v for k, v in meta.items() if k != "sha256"}, sort_keys=True).encode())
    h.update(b"\0")
    h.update(np.ascontiguousarray(theta, dtype="<f4").tobytes())
    return h.hexdigest()


def _load_cached(path: Path, key: str) -> tuple[dict | None, str | None]:
    """Read a cache entry.

    Returns
    -------
    row : dict or None
        The stored row with ``theta``, or None (absent or rejected).
    problem : str or None
        Why an existing entry was rejected (unreadable, another key, checksum mismatch).
    """
    if not path.exists():
        return None, None
    try:
        with np.load(path, allow_pickle=False) as z:
            meta = json.loads(str(z["row"]))
            theta = np.asarray(z["theta"])
    except Exception as e:
        return None, f"is unreadable ({type(e).__name__})"
    if not isinstance(meta, dict) or "sha256" not in meta or "key" not in meta:
        return None, "has no key or checksum (older or foreign format)"
    if meta["key"] != key:
        return None, f"holds the result of another key ({str(meta['key'])[:12]}...)"
    if meta["sha256"] != _entry_checksum(key, meta, theta):
        return None, "fails its checksum (edited or corrupted)"
    try:
        row = {k: v for k, v in meta.items() if k not in ("key", "sha256")}
        row["theta_max_over_alpha"] = float(row["theta_max_over_alpha"])
        row["theta"] = theta
        if row.get("status") != "ok":
            return None, f"has status {row.get('status')!r}"
    except (KeyError, TypeError, ValueError) as e:
        return None, f"has a malformed row ({type(e).__name__}: {e})"
    return row, None


def _store_cached(path: Path, key: str, row: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    meta = {k: v for k, v in row.items() if k not in ("theta", "motion_id")}
    meta["theta_max_over_alpha"] = str(meta["theta_max_over_alpha"])
    meta["key"] = key
    theta = np.ascontiguousarray(row["theta"], dtype=np.float32)
    meta["sha256"] = _entry_checksum(key, meta, theta)
    tmp = path.with_suffix(f".{os.getpid()}.tmp.npz")
    np.savez_compressed(tmp, theta=theta, row=np.array(json.dumps(meta)))
    os.replace(tmp, path)
