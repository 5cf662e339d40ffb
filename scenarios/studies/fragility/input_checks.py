"""Checks of the fragility functions' inputs: stripe intensities, outcome matrices, counts, replicates.

Each names the argument at fault and what it must be; the public functions of
:mod:`housner.scenarios.studies.fragility` call them before any arithmetic.
"""

from __future__ import annotations

import numpy as np

__all__: list[str] = []


def check_im(im, n_stripes: int | None = None) -> np.ndarray:
    try:
        x = np.asarray(im, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError("`im` must be numeric: one intensity per stripe") from None
    if x.ndim != 1 or x.size == 0:
        raise ValueError(f"`im` must be a non-empty one-dimensional array (one value per stripe), got shape {x.shape}")
    if not np.all(np.isfinite(x) & (x > 0)):
        raise ValueError(f"`im` must hold finite positive intensities, got {x[~(np.isfinite(x) & (x > 0))][0]}")
    if n_stripes is not None and x.size != n_stripes:
        raise ValueError(f"`im` has {x.size} stripes but the outcome matrix has {n_stripes} columns")
    return x


def check_matrix(values, name: str) -> np.ndarray:
    try:
        a = np.asarray(values)
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be an array of shape (motions, stripes)") from None
    if a.ndim != 2 or a.size == 0:
        raise ValueError(f"`{name}` must be a non-empty (motions, stripes) matrix, got shape {a.shape}")
    return a


def outcomes(overturned, valid, name: str = "overturned", valid_name: str = "valid") -> tuple[np.ndarray, np.ndarray]:
    """(overturned & valid, valid) as float 0/1 matrices; NaN in ``overturned`` marks a failed record."""
    o = check_matrix(overturned, name)
    if o.dtype == np.bool_:
        failed = np.zeros(o.shape, dtype=bool)
    else:
        try:
            o = o.astype(np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"`{name}` must hold booleans (or 0/1, NaN for a failed record)") from None
        failed = np.isnan(o)
        if not np.all(np.isin(o[~failed], (0.0, 1.0))):
            raise ValueError(f"`{name}` must hold booleans (or 0/1, NaN for a failed record)")
        o = np.where(failed, 0.0, o).astype(bool)
    v = valid_mask(valid, o.shape, valid_name) & ~failed
    return (o & v).astype(np.float64), v.astype(np.float64)


def valid_mask(valid, shape: tuple[int, ...], name: str = "valid") -> np.ndarray:
    if valid is None:
        return np.ones(shape, dtype=bool)
    v = np.asarray(valid)
    if v.shape != shape:
        raise ValueError(f"`{name}` must have the shape of the outcome matrix {shape}, got {v.shape}")
    if v.dtype != np.bool_:
        if not np.all(np.isin(v, (0, 1))):
            raise ValueError(f"`{name}` must hold booleans (True = the record ran)")
        v = v.astype(bool)
    return v


def check_counts(n, k) -> tuple[np.ndarray, np.ndarray]:
    arrays = []
    for name, a in (("n", n), ("k", k)):
        try:
            x = np.atleast_1d(np.asarray(a, dtype=np.float64))
        except (TypeError, ValueError):
            raise ValueError(f"`{name}` must be counts (non-negative integers)") from None
        if x.ndim != 1 or not np.all(np.isfinite(x) & (x >= 0) & (x == np.round(x))):
            raise ValueError(f"`{name}` must be a one-dimensional array of non-negative integers, got {a!r}")
        arrays.append(x)
    n_, k_ = arrays
    if n_.shape != k_.shape:
        raise ValueError(f"`k` must have one count per stripe like `n`, got lengths {k_.size} and {n_.size}")
    if np.any(k_ > n_):
        j = int(np.flatnonzero(k_ > n_)[0])
        raise ValueError(f"`k` exceeds `n` at stripe {j}: {k_[j]:g} overturns out of {n_[j]:g} records")
    return n_, k_


def check_n_boot(n_boot) -> int:
    if not (isinstance(n_boot, (int, np.integer)) and n_boot >= 1):
        raise ValueError(f"`n_boot` must be a positive integer, got {n_boot!r}")
    return int(n_boot)
