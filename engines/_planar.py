"""Kinematics shared by the adapters that model the block as a planar body with its own pivots."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["checked_settings", "com_state", "gravity_x", "release_state", "sampled_response", "substeps"]


def checked_settings(
    label: str, defaults: dict, ranges: dict, settings: dict, strict: tuple[str, ...] = ("timestep",)
) -> dict:
    """An adapter's settings: ``defaults`` updated by ``settings``, each numeric one checked against its range.

    Parameters
    ----------
    label : str
        The engine as messages name it ("DART", "OpenSees", "Drake").
    defaults : dict
        Every setting the engine takes, with its default.
    ranges : dict
        Setting -> (low, high): the accepted closed range (a setting absent here is taken as given).
    settings : dict
        The caller's settings.
    strict : tuple of str
        Settings whose low end is excluded (a step or a stiffness of exactly zero).

    Raises
    ------
    ValueError
        Naming the setting: unknown (with the closest known one), not a number, or out of range.
    """
    from housner.errors import unknown_choice

    unknown = sorted(set(settings) - set(defaults))
    if unknown:
        raise unknown_choice(f"{label} setting", unknown[0], defaults)
    s = {**defaults, **settings}
    for key, (lo, hi) in ranges.items():
        try:
            v = float(s[key])
        except (TypeError, ValueError):
            raise ValueError(f"{label} setting `{key}` must be a number, got {s[key]!r}") from None
        if not (lo <= v <= hi) or (key in strict and v == lo):
            raise ValueError(f"{label} setting `{key}` must lie in [{lo:g}, {hi:g}], got {s[key]!r}")
        s[key] = v
    return s


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


def sampled_response(
    engine,
    specimen,
    motion,
    theta: np.ndarray,
    theta_dot: np.ndarray,
    last: int,
    overturned: bool,
    info: dict,
    *,
    rocking_tol: float = 5e-3,
    quiet: float = 2e-3,
    overturn_angle: float = math.pi / 2,
):
    """The :class:`housner.Response` of a planar adapter from theta, theta' read at the motion's samples.

    Parameters
    ----------
    engine : Engine
        The adapter (its name goes into the response).
    specimen, motion
        The block (alpha [rad]) and the record (its sample times).
    theta, theta_dot : ndarray
        theta [rad] and theta' [rad/s] at every sample up to ``last``; changed in place: after an
        overturn both are held (at +-``overturn_angle`` and 0) to the end of the record.
    last : int
        Index of the last simulated sample (the record's last, or the one where the block fell).
    overturned : bool
        Whether |theta| reached ``overturn_angle`` [rad] at sample ``last``.
    info : dict
        The engine's own information (settings, steps, wall time).
    rocking_tol : float
        |theta| / alpha [-] above which the block rocks, for the shared impact and uplift detector
        (:mod:`housner.impacts`); the same for every adapter, so that counts mean the same.
    quiet : float
        Fraction of the rocking threshold taken as "still at rest" when dating the uplift [-].
    """
    from housner.impacts import impact_times, uplift_time
    from housner.response import Response

    alpha, t = specimen.alpha, motion.t
    overturn_time = math.nan
    if overturned:
        a, b = abs(theta[last - 1]), abs(theta[last])
        f = (overturn_angle - a) / (b - a) if b > a else 1.0
        overturn_time = float(t[last - 1] + min(max(f, 0.0), 1.0) * motion.dt)
        theta[last:] = math.copysign(overturn_angle, theta[last])
        theta_dot[last:] = 0.0
    tol = rocking_tol * alpha
    released = motion.theta0 != 0.0 or motion.theta_dot0 != 0.0
    return Response(
        t=t,
        theta=theta,
        theta_dot=theta_dot,
        impact_times=impact_times(t[: last + 1], theta[: last + 1], tol),
        theta_max=overturn_angle if overturned else float(np.max(np.abs(theta))),
        alpha=alpha,
        overturned=overturned,
        overturn_time=overturn_time,
        uplift_time=uplift_time(t[: last + 1], theta[: last + 1], tol, released, quiet),
        engine=engine.name,
        info=info,
    )
