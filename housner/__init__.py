"""Housner: the analytic rigid rocking block, and the vocabulary the whole suite shares.

Import what you need from here::

    from housner import Specimen, GroundMotion, simulate
"""

from housner.errors import DataFileError, EngineError
from housner.motion import GroundMotion
from housner.response import Response
from housner.specimen import Specimen
from housner.units import G

__version__ = "0.1.0"

__all__ = ["G", "DataFileError", "EngineError", "GroundMotion", "Response", "Specimen", "simulate", "__version__"]


def __getattr__(name):  # the solver compiles on first use; keep `import housner` light
    if name == "simulate":
        from housner.model import simulate

        return simulate
    raise AttributeError(f"module 'housner' has no attribute {name!r}")
