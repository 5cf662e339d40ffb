"""Kinematics shared by the adapters that model the block as a planar body with its own pivots."""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "IMPACT_LAW_DELAY",
    "IMPACT_LAW_RANGE",
    "IMPACT_LAW_TOL",
    "ImpactLaw",
    "ImpactLawEngine",
    "checked_settings",
    "com_state",
    "gravity_x",
    "law_factor",
    "release_state",
    "sampled_response",
    "substeps",
]

#: |theta| / alpha [-] a swing must exceed for the impact law to count its next sign change as an
#: impact. The tuner's free decay reaches 0.0011 alpha after 40 impacts, so the law must act down to
#: there (at 5e-3 alpha, the adapters' ROCKING_TOL, the 40th decay peak was 67 % high); a block that
#: has not lifted tilts far less: under a 5 Hz sine of 0.14 g, just below the seed specimen's uplift at
#: 0.15 g, at most 1.1e-4 alpha in OpenSees (its springs), 6e-6 alpha in Drake and DART, 4e-6 in MuJoCo
#: and 3e-6 in PyBullet (measured 2026-11-24), so its elastic tilt is not taken for rocking. For the
#: seed specimen 1e-3 alpha is 0.15 mrad, a fifth of what its markers resolve.
IMPACT_LAW_TOL = 1e-3

#: Time [s] from an impact's sign change to the impact law's scaling: the contacts the adapters
#: ship finish an impact well within it (MuJoCo's time constant is 0.4 ms, the OpenSees springs'
#: contact half-period about 1 ms, DART and PyBullet are rigid). The law's energy bookkeeping makes the
#: delay exact in free rocking; under a ground motion the ground's work in these 2 ms is scaled too.
IMPACT_LAW_DELAY = 2e-3

#: Accepted range of every planar adapter's ``impact_energy_factor`` setting (the low end excluded):
#: the adapter's impact law only ever takes energy away, so it cannot lift r above the contact's own.
IMPACT_LAW_RANGE = (0.0, 1.0)


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


def law_factor(setting: float, specimen, effects: tuple) -> float:
    """The impact law's factor for a record: the ``impact_energy_factor`` setting times r / Housner's r
    of a ``restitution`` effect (the contacts reproduce Housner's r, so the law takes the rest).

    Parameters
    ----------
    setting : float
        The adapter's ``impact_energy_factor`` [-].
    specimen : Specimen
        Provides Housner's r.
    effects : tuple
        The record's effects; a ``restitution`` one sets r [-].
    """
    f = float(setting)
    for e in effects:
        if getattr(e, "name", "") == "restitution":
            f *= float(e.r) / specimen.r_housner
    return f


def law_refusal(label: str, setting: float, specimen, effects: tuple) -> str | None:
    """Why an adapter cannot realise a ``restitution`` effect (an r above what its contact keeps), or None."""
    if law_factor(setting, specimen, effects) <= 1.0 + 1e-12:
        return None
    r = next(float(e.r) for e in effects if getattr(e, "name", "") == "restitution")
    return (
        f"engine {label!r} cannot realise restitution r = {r:g}: its contact keeps Housner's r = "
        f"{specimen.r_housner:.4f} of the energy at an impact (times impact_energy_factor = {float(setting):g}), "
        "and its impact law only takes energy away"
    )


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


class ImpactLaw:
    """The adapters' impact law: the block keeps ``factor`` of the energy its contact leaves it at each impact.

    Housner's r follows from a plastic impact at the new pivot, and a rigid or
    stiff contact reproduces exactly that loss; no engine's contact has a knob
    that takes uniformly more (measured 2026-11-24: damping knobs saturate near
    r = 0.94 or make r depend on the amplitude, ``engines/models/README.md``).
    A specimen that loses more at impact (a measured r below Housner's) is
    modelled by this law, the same in every adapter. The engine still does
    everything else: the flight, the uplift, the impact itself and the overturn.

    1. An impact is detected as :func:`housner.impacts.impact_times` counts
       one: theta changes sign after |theta| exceeded :data:`IMPACT_LAW_TOL`
       alpha since the previous sign change.
    2. :data:`IMPACT_LAW_DELAY` later, when the contact has finished the
       impact, every velocity of the block (relative to the ground) is
       multiplied by one factor c, chosen so that the block's energy above the
       upright position, per unit of I0,

           e = theta'^2 / 2 + p^2 (cos(alpha - |theta|) - cos alpha),

       becomes ``factor`` times what it was. In free rocking e is constant
       between impacts, so the energy ratio of the impact (the seed's eq. 8,
       which compares exactly these energies at the peaks) is ``factor``
       times the contact's, whatever the delay. Scaling at the sign change
       itself, in the middle of a compliant contact's impact, was measured to
       scatter each impact's ratio by about 0.3 % at 0.004 alpha (MuJoCo), 17 %
       on the tuner's 40th decay peak.

    Parameters
    ----------
    factor : float
        Energy kept at each impact, as a fraction of what the contact leaves [-], in (0, 1];
        1 leaves the contact alone.
    specimen : Specimen
        The block: alpha [rad] and p [1/s].
    step : float
        The engine step [s] at which :meth:`after_step` is called.
    theta0 : float
        The record's initial rotation [rad].
    """

    __slots__ = ("factor", "tol", "_alpha", "_cos_a", "_p2", "_wait", "_side", "_peak", "_countdown")

    def __init__(self, factor: float, specimen, step: float, theta0: float = 0.0):
        self.factor = float(factor)
        self._alpha = specimen.alpha
        self._cos_a = math.cos(self._alpha)
        self._p2 = specimen.frequency_parameter**2
        self.tol = IMPACT_LAW_TOL * self._alpha
        self._wait = max(1, math.ceil(IMPACT_LAW_DELAY / step * (1.0 - 1e-9)))
        self._side = 0.0 if theta0 == 0.0 else math.copysign(1.0, theta0)
        self._peak = abs(theta0)
        self._countdown = 0  # steps until the pending impact's energy is scaled; 0: none pending

    @property
    def active(self) -> bool:
        """Whether the law changes anything (``factor`` below 1)."""
        return self.factor != 1.0

    def after_step(self, theta: float, omega: float) -> float | None:
        """The factor to multiply every velocity of the block by after a step that reached (theta, omega), or None.

        ``theta`` [rad] and ``omega`` [rad/s] are the block's rotation and rate after the step.
        """
        scale = None
        if theta != 0.0:
            side = 1.0 if theta > 0.0 else -1.0
            if self._side != 0.0 and side != self._side:
                impact = self._peak > self.tol
                self._side, self._peak = side, abs(theta)
                if impact:
                    if self._countdown:  # the previous impact is still pending: it is scaled now
                        scale = self._scale(theta, omega)
                    self._countdown = self._wait
                return scale
            self._side = side
            self._peak = max(self._peak, abs(theta))
        if self._countdown:
            self._countdown -= 1
            if not self._countdown:
                scale = self._scale(theta, omega)
        return scale

    def _scale(self, theta: float, omega: float) -> float:
        """c with c^2 theta'^2 / 2 + u = factor (theta'^2 / 2 + u), u the potential energy per I0 (0 if unreachable)."""
        k = 0.5 * omega * omega
        if k <= 0.0:
            return 1.0
        u = self._p2 * (math.cos(self._alpha - abs(theta)) - self._cos_a)
        return math.sqrt(max(self.factor * (k + u) - u, 0.0) / k)

    def first_scale(self, theta: np.ndarray, omega: np.ndarray) -> tuple[int, float] | None:
        """The first step of consecutive steps (``theta`` [rad], ``omega`` [rad/s]) after which to scale, else None.

        Returns (index, factor); the law's state advances up to and including that step, so the next
        call continues after it.
        """
        pairs = zip(np.asarray(theta, float).tolist(), np.asarray(omega, float).tolist(), strict=True)
        for i, (th, w) in enumerate(pairs):
            c = self.after_step(th, w)
            if c is not None:
                return i, c
        return None


class ImpactLawEngine:
    """The impact law's two hooks, for an adapter whose ``_settings`` hold ``impact_energy_factor``.

    Mixed in before :class:`housner.engines.base.Engine` by the five planar adapters, which realise the
    ``restitution`` effect through the law.
    """

    def effect_refusal(self, specimen, effects: tuple) -> str | None:
        """A ``restitution`` effect above the contact's r (the impact law only takes energy away), else None."""
        return law_refusal(self.name, self._settings["impact_energy_factor"], specimen, effects)

    def impact_law(self, specimen, effects: tuple, step: float, theta0: float) -> ImpactLaw:
        """The law of one record: the setting times a ``restitution`` effect's share, at engine step ``step`` [s]."""
        return ImpactLaw(law_factor(self._settings["impact_energy_factor"], specimen, effects), specimen, step, theta0)
