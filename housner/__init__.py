"""Housner: the analytic rigid rocking block, and the vocabulary the whole suite shares.

Import what you need from here::

    from housner import Specimen, GroundMotion, simulate

The layers above the physics install under this one name: :mod:`housner.engines`,
:mod:`housner.scenarios`, :mod:`housner.reports` and the command line, :mod:`housner.cli`.
``import housner`` itself imports nothing heavy (no numpy): the pytest plugin that every user's
pytest session loads lives under it; the names below load on first use.
"""

import importlib

__version__ = "0.1.0"

#: The public names and the modules that hold them (loaded on first use).
_PUBLIC = {
    "G": "housner.units",
    "DataFileError": "housner.errors",
    "EngineError": "housner.errors",
    "GroundMotion": "housner.motion",
    "Response": "housner.response",
    "Specimen": "housner.specimen",
    "simulate": "housner.model",
}

__all__ = [*_PUBLIC, "__version__"]


def __getattr__(name):
    if name in _PUBLIC:
        value = getattr(importlib.import_module(_PUBLIC[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'housner' has no attribute {name!r}")


def __dir__():
    return sorted({*globals(), *_PUBLIC})
