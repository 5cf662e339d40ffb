"""Argument checks shared by the public calls: messages name the argument."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["finite", "positive", "vector"]


def finite(name: str, value) -> float:
    """``value`` as a finite float, or ``ValueError`` naming ``name``."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"`{name}` must be finite, got {value!r}")
    return x


def positive(name: str, value) -> float:
    """``value`` as a positive finite float, or ``ValueError`` naming ``name``."""
    x = finite(name, value)
    if x <= 0.0:
        raise ValueError(f"`{name}` must be positive, got {value!r}")
    return x


def vector(name: str, value, *, expected: str, show: bool = False, shape_note: str = "") -> np.ndarray:
    """``value`` as a one-dimensional float64 array, or a one-line ``ValueError`` naming ``name``.

    Not numbers: "`name` must be EXPECTED" (then ", got VALUE" with ``show``); another shape: "`name` must be
    one-dimensional SHAPE_NOTE, got shape (...)". Units are the caller's.
    """
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be {expected}" + (f", got {value!r}" if show else "")) from None
    if a.ndim != 1:
        raise ValueError(f"`{name}` must be one-dimensional{shape_note}, got shape {a.shape}")
    return a
