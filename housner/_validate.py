"""Argument checks shared by the public calls: messages name the argument."""

from __future__ import annotations

import math

__all__ = ["finite", "positive"]


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
