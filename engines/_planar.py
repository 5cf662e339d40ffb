"""Kinematics shared by the adapters that model the block as a planar body with its own pivots."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["com_state", "gravity_x", "release_state", "substeps"]


def com_state(H: float, pivot_x: float, theta: float, omega: float) -> tuple[float, float, float, float]:
    """Centre of mass (x, z) [m] and velocity (x', z') [m/s] of the block turned by ``theta`` about (pivot_x, 0).

    ``theta`` [rad] turns the block about +y and ``omega`` [rad/s] is its rate. With Rot(theta)
    (x, z) -> (x cos + z sin, -x sin + z cos), the centre of mass is pivot + Rot(theta) (-pivot_x, H).
    """
    c, s = math.cos(theta), math.sin(theta)
    rx, rz = -pivot_x, H
    return pivot_x + rx * c + rz * s, -rx * s + rz * c, (-rx * s + rz * c) * omega, (-rx * c - rz * s) * omega


def release_state(H: float, B: float, theta0: float, omega0: float) -> tuple[float, float, float, float]:
    """:func:`com_state` of a record's start: turned by ``theta0`` [rad] about the pivot on its side.

    The side is that of theta0, else of the initial rate ``omega0`` [rad/s]; a block at rest
    (both zero) stands on both pivots.
    """
    side = math.copysign(1.0, theta0) if theta0 != 0.0 else (math.copysign(1.0, omega0) if omega0 != 0.0 else 0.0)
    return com_state(H, side * B, theta0, omega0)


def substeps(dt: float, timestep: float) -> tuple[int, float]:
    """The fewest equal steps k per sample interval ``dt`` [s] no longer than ``timestep`` [s], and the step [s]."""
    k = max(1, math.ceil(dt / timestep * (1.0 - 1e-12)))
    return k, dt / k


def gravity_x(acc: np.ndarray, k: int) -> list[list[float]]:
    """Per sample interval, the x gravity [m/s^2] of each of its k steps: minus the exact mean of the linear ug''.

    ``acc`` is the ground acceleration at the samples [m/s^2]; the d'Alembert force of a rigid
    ground's motion on the block is that of a gravity component -ug'' along x.
    """
    frac = (np.arange(k) + 0.5) / k
    return (-(acc[:-1, None] + np.diff(acc)[:, None] * frac[None, :])).tolist()
