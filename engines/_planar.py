"""What the adapters that model the block as a planar body with its own pivots share.

:class:`PlanarEngine`, the base of the five planar adapters (MuJoCo, PyBullet, DART, OpenSees, Drake):
settings checked against their ranges, pickling by settings, the sample loop of a rigid-body state
with its runaway and overturn checks, and the :class:`housner.Response` from the sampled theta. The
kinematics of a release (:func:`release_state`), the ground motion as a gravity component
(:func:`gravity_steps`, :func:`gravity_x`), and the factor of a record's impact law (:func:`law_factor`; the
law itself, through which every planar adapter realises an energy ratio below its contact's own, is
:class:`housner.engines._impact_law.ImpactLaw`). Every planar adapter realises the effect
``asymmetric_pivots`` in its geometry: its pivots at x = B - e and -(B + e) of the centre of mass
(:func:`pivot_x`, :func:`pivot_offset`), the release turned about the pivot on its side.
"""

from __future__ import annotations

import importlib
import math
import time
from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np

from housner.engines._impact_law import ImpactLaw
from housner.engines.base import Engine, SpecAttribute
from housner.errors import EngineError, EngineUnavailable, unknown_choice
from housner.free_vibration.impacts import impact_times, uplift_time
from housner.response import Response
from housner.rocking_params import RockingParams, pivot_impact_ratios

__all__ = [
    "IMPACT_LAW_RANGE",
    "PIVOT_RANGES",
    "OVERTURN_ANGLE",
    "QUIET",
    "ROCKING_TOL",
    "RUNAWAY_M",
    "PlanarEngine",
    "checked_settings",
    "com_state",
    "contact_r",
    "gravity_steps",
    "gravity_x",
    "law_factor",
    "model_number",
    "optional_package",
    "pivot_offset",
    "pivot_x",
    "check_offset",
    "release_state",
    "sampled_response",
    "start_states",
    "step_info",
    "substeps",
]

#: |theta| above ROCKING_TOL * alpha counts as rocking [-] for the shared impact and uplift detector
#: (:mod:`housner.free_vibration.impacts`), the same for every adapter so that counts mean the same; below it the
#: block is at rest. The contacts tilt a block at rest by far less: DART's rigid contact by less than
#: 1e-6 alpha; Drake's default contact by 6e-6 alpha and OpenSees' penalty contact by about 2e-4 alpha
#: under 0.9 g tan(alpha); PyBullet's rigid contact lets each pivot sink about 10 um into the ground,
#: and when the load shifts to one pivot (ground acceleration near g tan alpha) the block tilts by up
#: to about 2e-3 alpha without any uplift. 5e-3 alpha is 0.74 mrad for the seed specimen, just below
#: the 0.8 mrad accuracy of the seed's camera (0.0053 alpha).
ROCKING_TOL = 5e-3

#: |theta| at which the block has fallen [rad]: it lies on its side; the adapter stops and holds theta there.
OVERTURN_ANGLE = math.pi / 2

#: A centre of mass farther than this from its start [m] has run away (slid off or diverged).
RUNAWAY_M = 10.0

#: Fraction of the rocking threshold taken as "still at rest" when dating the uplift: 2e-3 * 5e-3
#: alpha = 1e-5 alpha, four times the largest tilt of PyBullet's block at rest under load (the two
#: pivots sink by different nanometres).
QUIET = 2e-3

#: Accepted range of every planar adapter's ``impact_energy_factor`` setting (the low end excluded):
#: the adapter's impact law only ever takes energy away, so it cannot lift r above the contact's own.
IMPACT_LAW_RANGE = (0.0, 1.0)

#: Ranges of the settings every rigid-pivot adapter (DART, Drake, OpenSees) takes: the step [s], the pivot's
#: Coulomb friction coefficient [-] and the impact law's factor [-]; an adapter adds its own contact's.
PIVOT_RANGES: dict = {"timestep": (1e-6, 1e-2), "friction": (0.0, 100.0), "impact_energy_factor": IMPACT_LAW_RANGE}


def model_number(x: float) -> str:
    """Shortest decimal text that reads back as the same float ("0" for zero): the numbers of the generated
    model files (:mod:`housner.engines.mjcf`, :mod:`housner.engines.urdf`)."""
    x = float(x)
    if x == 0.0:
        return "0"
    return repr(x)


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


#: The registered name of the effect that moves the pivots relative to the centre of mass
#: (:class:`housner.effects.AsymmetricPivots`), which every planar adapter realises in its geometry.
ASYMMETRIC = "asymmetric_pivots"


def pivot_offset(effects: tuple) -> float:
    """The offset e [m] of the centre of mass toward +x of the pivots' midpoint: that of an ``asymmetric_pivots``
    effect among ``effects``, else 0 (the symmetric block)."""
    return sum(float(e.e) for e in effects if getattr(e, "name", "") == ASYMMETRIC)


def pivot_x(B: float, e: float = 0.0) -> tuple[float, float]:
    """The pivots' x [m] in the body frame at the centre of mass: (B - e, -(B + e)) for half width B [m] and the
    centre of mass e [m] toward +x of their midpoint; (B, -B) exactly at e = 0."""
    return B - e, -(B + e)


def check_offset(B: float, offset) -> float:
    """The pivots' offset e [m] (a model builder's ``offset``) as a float in (-B, B), so that the pivots stand on
    either side of the centre of mass; else ValueError naming ``offset``."""
    try:
        e = float(offset)
    except (TypeError, ValueError):
        raise ValueError(f"`offset` must be a number [m], got {offset!r}") from None
    if not abs(e) < B:
        raise ValueError(
            f"`offset` ({offset!r} m) must lie in (-B, B) = +-{B:g} m, so that the pivots stand on "
            "either side of the centre of mass"
        )
    return e


def com_state(H: float, pivot_x: float, theta: float, omega: float) -> tuple[float, float, float, float]:
    """Centre of mass (x, z) [m] and velocity (x', z') [m/s] of the block turned by ``theta`` about (pivot_x, 0).

    ``theta`` [rad] turns the block about +y and ``omega`` [rad/s] is its rate. With Rot(theta)
    (x, z) -> (x cos + z sin, -x sin + z cos), the centre of mass is pivot + Rot(theta) (-pivot_x, H).
    """
    c, s = math.cos(theta), math.sin(theta)
    rx, rz = -pivot_x, H
    return pivot_x + rx * c + rz * s, -rx * s + rz * c, (-rx * s + rz * c) * omega, (-rx * c - rz * s) * omega


def release_state(
    H: float, B: float, theta0: float, omega0: float, e: float = 0.0
) -> tuple[float, float, float, float]:
    """:func:`com_state` of a record's start: turned by ``theta0`` [rad] about the pivot on its side.

    The side is that of theta0, else of the initial rate ``omega0`` [rad/s]; a block at rest
    (both zero) stands on both pivots. The pivots are at x = B - e and -(B + e) [m] of the centre of
    mass (:func:`pivot_x`; e = 0: +-B).
    """
    side = math.copysign(1.0, theta0) if theta0 != 0.0 else (math.copysign(1.0, omega0) if omega0 != 0.0 else 0.0)
    if side == 0.0:
        return com_state(H, 0.0 * B, theta0, omega0)
    return com_state(H, pivot_x(B, e)[0 if side > 0.0 else 1], theta0, omega0)


def contact_r(specimen, e: float = 0.0) -> float:
    """The r [-] a rigid plastic contact realises on its own: Housner's r of the specimen, or with the centre of
    mass ``e`` [m] off-centre the product rho+- rho-+ of the two impacts' angular-velocity ratios (the geometric
    mean of r_pos and r_neg that :class:`housner.effects.AsymmetricPivots` sets, each impact keeping the angular
    momentum about its landing pivot)."""
    if e == 0.0:
        return specimen.r_housner
    rho_pn, rho_np = pivot_impact_ratios(
        specimen.B - e, specimen.B + e, specimen.H, specimen.centroidal_inertia, specimen.mass
    )
    return rho_pn * rho_np


def law_factor(setting: float, specimen, effects: tuple) -> float:
    """The impact law's factor for a record: the ``impact_energy_factor`` setting times r / the contact's r
    of a ``restitution`` effect (the contacts reproduce Housner's r, so the law takes the rest).

    With an ``asymmetric_pivots`` effect the contact's r is the geometric mean rho+- rho-+ of the two
    impacts' (:func:`contact_r`): the analytic engine rescales both per-side ratios r_pos, r_neg by
    r / that mean (:meth:`housner.rocking_params.RockingParams.with_r`), one factor for both sides, which
    is what the law applies to each impact.

    Parameters
    ----------
    setting : float
        The adapter's ``impact_energy_factor`` [-].
    specimen : Specimen
        Provides Housner's r.
    effects : tuple
        The record's effects; a ``restitution`` one sets r [-], an ``asymmetric_pivots`` one the pivots.
    """
    f = float(setting)
    for e in effects:
        if getattr(e, "name", "") == "restitution":
            f *= float(e.r) / contact_r(specimen, pivot_offset(effects))
    return f


def law_refusal(label: str, setting: float, specimen, effects: tuple) -> str | None:
    """Why an adapter cannot realise a ``restitution`` effect (an r above what its contact keeps), or None."""
    if law_factor(setting, specimen, effects) <= 1.0 + 1e-12:
        return None
    r = next(float(e.r) for e in effects if getattr(e, "name", "") == "restitution")
    e = pivot_offset(effects)
    whose = "Housner's r" if e == 0.0 else f"the asymmetric pivots' (e = {e:g} m) r = rho+- rho-+"
    return (
        f"engine {label!r} cannot realise restitution r = {r:g}: its contact keeps {whose} = "
        f"{contact_r(specimen, e):.4f} of the energy at an impact (times impact_energy_factor = {float(setting):g}), "
        "and its impact law only takes energy away"
    )


def substeps(dt: float, timestep: float) -> tuple[int, float]:
    """The fewest equal steps k per sample interval ``dt`` [s] no longer than ``timestep`` [s], and the step [s]."""
    k = max(1, math.ceil(dt / timestep * (1.0 - 1e-12)))
    return k, dt / k


def gravity_steps(acc: np.ndarray, k: int) -> np.ndarray:
    """Per sample interval (row), the x gravity [m/s^2] of each of its k steps (column): minus the exact mean of
    the linear ug'' over the step.

    ``acc`` is the ground acceleration at the samples [m/s^2]; the d'Alembert force of a rigid
    ground's motion on the block is that of a gravity component -ug'' along x.
    """
    frac = (np.arange(k) + 0.5) / k
    return -(acc[:-1, None] + np.diff(acc)[:, None] * frac[None, :])


def gravity_x(acc: np.ndarray, k: int) -> list[list[float]]:
    """:func:`gravity_steps` as lists of floats, one per sample interval: what an adapter's step loop passes to
    its engine one value at a time (a float from a list costs less to pass than one from an array)."""
    return gravity_steps(acc, k).tolist()


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
    rocking_tol: float = ROCKING_TOL,
    quiet: float = QUIET,
    overturn_angle: float = OVERTURN_ANGLE,
) -> Response:
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
        (:mod:`housner.free_vibration.impacts`); the same for every adapter, so that counts mean the same.
    quiet : float
        Fraction of the rocking threshold taken as "still at rest" when dating the uplift [-].
    """
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


def step_info(engine, h: float, k: int, last: int) -> dict:
    """What a run's ``info`` opens with, for every adapter: the engine's settings and version, its step h [s], the
    k steps per sample and the steps run to sample ``last``."""
    return {
        "settings": engine.settings(),
        "version": engine.version(),
        "step": h,
        "steps_per_sample": k,
        "n_steps": last * k,
    }


def optional_package(engine: str, package: str, module: str, install: str) -> Any:
    """The module ``module`` of an optional engine's ``package``, imported on first use, or EngineUnavailable.

    The message names the ``engine``, the import error and the ``install`` command.
    """
    try:
        importlib.import_module(module.partition(".")[0])  # the package first, as an import statement does
        return importlib.import_module(module)
    except ImportError as e:
        raise EngineUnavailable(
            f"engine {engine!r} needs the {package} package ({e}); install it with: {install}"
        ) from None


def start_states(specimen, motion, e: float = 0.0) -> np.ndarray:
    """Room for the sampled rigid-body states (z, x, theta [m, m, rad], z', x', theta' [m/s, m/s, rad/s]) of a
    record, one row per sample, the first that of its release (:func:`release_state`, the centre of mass
    ``e`` [m] toward +x of the pivots' midpoint)."""
    th0, om0 = motion.theta0, motion.theta_dot0
    x0, z0, dx0, dz0 = release_state(specimen.H, specimen.B, th0, om0, e)
    states = np.empty((motion.n, 6))
    states[0] = (z0, x0, th0, dz0, dx0, om0)
    return states


class PlanarEngine(Engine):
    """The base of the planar adapters: settings and pickling, the impact law's hooks, the sample loop, the response.

    A subclass sets :attr:`DEFAULTS` (every setting, ``impact_energy_factor`` among them),
    :attr:`RANGES` and :attr:`STRICT` for :func:`checked_settings` (and :attr:`CHOICES`), and an optional
    engine its :attr:`MODULE` (:meth:`require`); or its own ``__init__``. Its :attr:`LABEL` and
    :attr:`INSTALL` are its registry spec's (:class:`housner.engines.EngineSpec`). An
    instance pickles as its settings: models, contexts and clients are rebuilt in the receiving
    process. The ``restitution`` effect is realised through the impact law (:class:`ImpactLaw`), the
    ``asymmetric_pivots`` effect by the pivots' places: at x = B - e and -(B + e) of the centre of mass
    (:func:`pivot_x`), the mass and the centroidal inertia unchanged, so the uplift thresholds
    g tan(alpha+-), each pivot's p and each impact's ratio are the contact's own. A
    subclass that keeps the rigid-body state (z, x, theta, z', x', theta') implements
    :meth:`_stepper`; the others their own ``_simulate``.

    Parameters
    ----------
    timestep : float
        Longest step [s]: each sample interval of a motion is cut into the
        fewest equal steps no longer than this (:func:`substeps`).
    impact_energy_factor : float
        Energy the block keeps at each impact as a fraction of what the
        contact leaves it [-], in (0, 1]: the adapters' impact law
        (:class:`ImpactLaw`) for an r below the contact's own.
        1 (default): the contact alone.
    friction : float
        Coulomb friction coefficient pivot/ground [-]; it must exceed
        max |ug''| / g with a margin for the impacts.
    pivot_radius : float
        Radius of the pivot spheres [m], at most 1e-3 H (the adapters whose pivots are spheres: DART, Drake).
    **settings
        The adapter's others (its ``DEFAULTS``).

    Examples
    --------
    Every adapter is driven alike; released from rest at 0.3 alpha, the block rocks and impacts:

    >>> from housner.engines import get_engine
    >>> from housner import GroundMotion, Specimen
    >>> spec = Specimen.bachmann2017()
    >>> released = GroundMotion.free_vibration(0.3 * spec.alpha, 2.0)  # from rest at 0.3 alpha, 2 s
    >>> [get_engine(name).simulate(spec, released).n_impacts > 3 for name in ("dart", "drake", "opensees")]
    [True, True, True]
    """

    #: The ``restitution`` effect, through the impact law; ``asymmetric_pivots``, through the pivots' places.
    effects_supported: ClassVar[frozenset[str]] = frozenset({"restitution", ASYMMETRIC})
    #: Every setting and its default.
    DEFAULTS: ClassVar[dict] = {}
    #: The engine as messages name it ("DART", "OpenSees", "Drake"), from its spec.
    LABEL = SpecAttribute("label")
    #: Accepted closed range (low, high) of each numeric setting.
    RANGES: ClassVar[dict] = {}
    #: Settings whose low end is excluded.
    STRICT: ClassVar[tuple[str, ...]] = ("timestep", "impact_energy_factor")
    #: The accepted values of each setting that is a choice (a solver, a detector), as a collection.
    CHOICES: ClassVar[dict] = {}
    #: The optional engine's module, imported on first use (:meth:`require`); "" for none.
    MODULE: ClassVar[str] = ""
    #: How to install the engine's package (named when it is missing), from its spec.
    INSTALL = SpecAttribute("install")

    def __init__(self, **settings: Any):
        self.require()  # a missing package is said before any long work
        self._settings = checked_settings(self.LABEL, self.DEFAULTS, self.RANGES, settings, strict=self.STRICT)
        for key, accepted in self.CHOICES.items():
            if self._settings[key] not in accepted:
                raise unknown_choice(f"{self.LABEL} setting `{key}`", self._settings[key], accepted)

    @classmethod
    def require(cls) -> Any:
        """The engine's :attr:`MODULE`, imported on first use, or :class:`housner.errors.EngineUnavailable`
        naming :attr:`INSTALL`; None for an engine without one."""
        return optional_package(cls.name, cls.package, cls.MODULE, cls.INSTALL) if cls.MODULE else None

    def __getstate__(self) -> dict:
        return {"settings": dict(self._settings)}

    def __setstate__(self, state: dict) -> None:
        self.__init__(**state["settings"])

    def effect_refusal(self, specimen, effects: tuple) -> str | None:
        """An ``asymmetric_pivots`` offset out of its range for ``specimen`` (both pivots must stay on their side
        of the centre of mass), or a ``restitution`` effect above the contact's r (the impact law only takes
        energy away), else None."""
        for e in effects:
            if getattr(e, "name", "") == ASYMMETRIC:
                try:
                    e.check(specimen)
                except ValueError as err:
                    return f"engine {self.name!r}: {err}"
        return law_refusal(self.name, self._settings["impact_energy_factor"], specimen, effects)

    def impact_law(self, specimen, effects: tuple, step: float, theta0: float) -> ImpactLaw:
        """The law of one record: the setting times a ``restitution`` effect's share, at engine step ``step`` [s];
        with an ``asymmetric_pivots`` effect each pivot's alpha and p (:meth:`pivot_params`)."""
        factor = law_factor(self._settings["impact_energy_factor"], specimen, effects)
        return ImpactLaw(factor, specimen, step, theta0, self.pivot_params(specimen, effects))

    @staticmethod
    def pivot_params(specimen, effects: tuple) -> RockingParams | None:
        """The rocking parameters (alpha and p per pivot) of the block with the record's ``asymmetric_pivots``
        effect, as the analytic engine forms them; None without one (or at e = 0)."""
        asym = [e for e in effects if getattr(e, "name", "") == ASYMMETRIC and float(e.e) != 0.0]
        if not asym:
            return None
        return asym[0].modify_params(RockingParams.from_specimen(specimen), specimen)

    def _pivot_radius(self, specimen) -> float:
        """The ``pivot_radius`` setting [m] of an adapter with pivot spheres; ValueError above 1e-3 H."""
        rho = self._settings["pivot_radius"]
        if rho > 1e-3 * specimen.H:
            raise ValueError(
                f"{self.LABEL} setting `pivot_radius` ({rho:g} m) must be at most 1e-3 H = {1e-3 * specimen.H:g} m"
            )
        return rho

    def diverged(self, motion, i: int, state: str, friction: str = "friction") -> EngineError:
        """The error of a record whose state, read at sample ``i``, is not finite or ran away (``state`` says it)."""
        return EngineError(
            f"{self.LABEL} failed on motion {motion.name!r} at t = {i * motion.dt:.6g} s: the state is not finite "
            f"or ran away ({state}); a block that slides needs more `{friction}`, one that diverges a smaller "
            "`timestep`"
        )

    def _simulate(self, specimen, motion, effects: tuple) -> Response:
        """The record sample by sample (:meth:`_run_samples`) with the steps of :meth:`_stepper`, and its response."""
        wall0 = time.perf_counter()
        k, h = substeps(motion.dt, self._settings["timestep"])
        states = start_states(specimen, motion, pivot_offset(effects))
        advance = self._stepper(specimen, motion, effects, states, k, h)
        last, overturned = self._run_samples(motion, states, advance)
        wall = time.perf_counter() - wall0
        return self._response(specimen, motion, states[:, 2].copy(), states[:, 5].copy(), last, overturned, h, k, wall)

    def _stepper(self, specimen, motion, effects: tuple, states: np.ndarray, k: int, h: float) -> Callable:
        """The engine's model of ``specimen`` at the release ``states[0]``, and its ``advance(i)`` (see
        :meth:`_run_samples`) through k steps of h [s] per sample interval with the impact law of ``effects``.
        An adapter that keeps the rigid-body state (z, x, theta, z', x', theta') implements it; the others
        their own ``_simulate``."""
        raise NotImplementedError

    def _run_samples(self, motion, states: np.ndarray, advance: Callable[[int], np.ndarray]) -> tuple[int, bool]:
        """Sample intervals 1, 2, ... of ``motion`` until its end or the overturn: (last sample, overturned).

        ``advance(i)`` steps through interval i, writes the state at sample i into ``states[i]``
        (the rows of :func:`start_states`) and returns what is checked: (z, x, theta, ...) all
        finite, the centre of mass within :data:`RUNAWAY_M` of its start; an overturn at
        |theta| >= :data:`OVERTURN_ANGLE`.
        """
        # The checks read the state as Python floats: per sample, 0.7 us against 2.8 us on the array (the same tests).
        x0, isfinite = float(states[0, 1]), math.isfinite
        for i in range(1, motion.n):
            q = advance(i).tolist()
            if not (abs(q[1] - x0) < RUNAWAY_M and abs(q[0]) < RUNAWAY_M and all(map(isfinite, q))):
                raise self.diverged(motion, i, f"x = {q[1]:.6g} m, z = {q[0]:.6g} m, theta = {q[2]:.6g} rad")
            if abs(q[2]) >= OVERTURN_ANGLE:
                return i, True
        return motion.n - 1, False

    def _response(self, specimen, motion, theta, theta_dot, last, overturned, h, k, wall, **extra: Any) -> Response:
        """The Response from theta, theta' [rad, rad/s] at the samples (:func:`sampled_response`).

        ``info`` holds the settings, the version, the step h [s], the k steps per sample, the steps
        run, ``extra`` and the wall time ``wall`` [s].
        """
        info = {**step_info(self, h, k, last), **extra, "wall_time_s": wall}
        return sampled_response(self, specimen, motion, theta, theta_dot, last, overturned, info)
