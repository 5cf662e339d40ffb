"""What the 3D scan-mesh engines (``mujoco-3d``, ``pybullet-3d``) share.

A real rock's scan mesh is simulated as one free rigid body (six degrees of freedom) standing on a fixed,
flat table, instead of the equivalent planar block of :mod:`housner.scan`. Here are the rock
(:func:`load_rock`, :class:`MeshRock`: the mesh's mass, centre of mass, inertia and convex hull, placed in
the shaking frame), its start (settled for :data:`SETTLE_S` from :data:`DROP_GAP` above the table), theta
from the settled pose, the overturn criterion (:class:`OverturnCheck`, with :data:`PAST_PIVOT_S`) and the
base class :class:`MeshEngine`. The table acceleration enters as the exact d'Alembert force at the centre of
mass. Why each is so is in ``docs/explanation/engines.md`` ("The 3D scan-mesh engines").
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import time
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from housner.engines._planar import OVERTURN_ANGLE, RUNAWAY_M, sampled_response, step_info
from housner.engines.base import Engine, SpecAttribute
from housner.errors import DataFileError, EngineError, unknown_choice
from housner.response import Response

__all__ = [
    "DROP_GAP",
    "MESH_DEFAULTS",
    "PAST_PIVOT_S",
    "SETTLE_S",
    "MeshEngine",
    "MeshRock",
    "OverturnCheck",
    "load_rock",
    "tilt",
]

#: Settings every mesh engine takes, with their defaults: the mesh file (required), the shaking
#: azimuth [deg] from the mesh x axis, the density [kg/m^3] and the contact model (only "hull").
MESH_DEFAULTS: dict = {"mesh": None, "azimuth": 0.0, "density": 2700.0, "contact": "hull"}

#: Time [s] the rock settles on the table with no input before the record starts: several periods of
#: the contact's vertical vibration and long enough for the drop's bounce to die out.
SETTLE_S = 1.0

#: Height [m] of the rock's lowest hull point above the table at its release (just above contact).
DROP_GAP = 1e-4

#: Time [s] a rock may stay past its pivot before it counts as lying on another facet (overturned).
PAST_PIVOT_S = 1.0


@dataclass(frozen=True, eq=False)
class MeshRock:
    """A scan mesh as a rigid body in the shaking frame (x along the shaking direction, z up, origin at the COM).

    Attributes
    ----------
    path : pathlib.Path
    sha1 : str
        SHA-1 of the mesh file's content.
    scan : housner.scan.ScanSpecimen
        The equivalent planar block at this azimuth (pivot distances b, alpha, h).
    mass : float
        [kg].
    inertia : numpy.ndarray
        (3, 3) [kg m^2] about the COM, shaking-frame axes.
    hull : numpy.ndarray
        (k, 3) [m] vertices of the convex hull relative to the COM, shaking-frame axes.
    h : float
        [m] height of the COM above the rest facet (the lowest hull points are at z = -h).
    """

    path: Path
    sha1: str
    scan: Any
    mass: float
    inertia: np.ndarray
    hull: np.ndarray
    h: float

    def alpha(self, side: float) -> float:
        """alpha [rad] of the pivot on the side of sign ``side`` (+1: +x)."""
        return self.scan.pos.alpha if side > 0 else self.scan.neg.alpha

    def b(self, side: float) -> float:
        """Horizontal distance [m] from the COM to the pivot on the side of sign ``side``."""
        return self.scan.pos.b if side > 0 else self.scan.neg.b


def file_sha1(path: Path) -> str:
    """SHA-1 of the file's bytes; DataFileError for a file that cannot be read."""
    try:
        return hashlib.sha1(path.read_bytes()).hexdigest()
    except OSError as e:
        raise DataFileError(path, f"cannot be read: {e.strerror or e}") from None


def load_rock(mesh: str | Path, azimuth: float = 0.0, density: float = 2700.0, contact: str = "hull") -> MeshRock:
    """The rock of scan mesh ``mesh`` for shaking along ``azimuth`` [deg] at ``density`` [kg/m^3] (cached by content).

    Raises
    ------
    housner.errors.DataFileError
        The file is missing, unreadable or not a usable mesh (one line, naming it).
    ValueError
        A bad azimuth, density or contact (naming it).
    """
    if mesh is None or (isinstance(mesh, str) and not mesh.strip()):
        raise ValueError("setting `mesh` is required: the path of the rock's scan mesh (.obj, metres)")
    path = Path(mesh).expanduser()
    if not path.is_file():
        raise DataFileError(path, "no such file" if not path.exists() else "is not a file")
    if contact != "hull":
        raise ValueError(
            f"setting `contact` must be 'hull' (the convex hull is the collision geometry), got {contact!r}"
        )
    return _load_rock(str(path.resolve()), file_sha1(path), float(azimuth), float(density))


@lru_cache(maxsize=8)
def _load_rock(path: str, sha1: str, azimuth: float, density: float) -> MeshRock:
    from housner import scan

    p = Path(path)
    spec = scan.specimen_from_mesh(p, azimuth=azimuth, contact="hull", density=density)
    rest = scan.mesh_at_rest(p, density)  # the same rest frame as spec's (origin at the COM, z up)
    c, s = math.cos(math.radians(azimuth)), math.sin(math.radians(azimuth))
    turn = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])  # rest frame -> shaking frame (+x along azimuth)
    hull = rest.hull_vertices @ turn.T
    inertia = turn @ rest.inertia @ turn.T
    return MeshRock(
        path=p, sha1=sha1, scan=spec, mass=rest.mass, inertia=0.5 * (inertia + inertia.T), hull=hull, h=rest.h
    )


def tilt(rot: np.ndarray, rot0: np.ndarray, omega: np.ndarray) -> tuple[float, float]:
    """theta [rad] and theta' [rad/s] of a body at rotation ``rot`` (body -> world) turning at ``omega`` (world).

    theta = atan2(n_x, n_z) with n = rot rot0^T e_z, the settled vertical body axis now (``rot0``:
    the settled rotation); theta' its exact rate with n' = omega x n.
    """
    n = rot @ (rot0.T[:, 2])
    dn = np.cross(omega, n)
    r2 = n[0] * n[0] + n[2] * n[2]
    return math.atan2(n[0], n[2]), float((n[2] * dn[0] - n[0] * dn[2]) / r2) if r2 > 0 else 0.0


def rot_y(angle: float) -> np.ndarray:
    """Rotation [-] by ``angle`` [rad] about world +y (z toward +x)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


class OverturnCheck:
    """The overturn criterion (docs/explanation/engines.md, "The 3D scan-mesh engines"), fed one sample at a time."""

    def __init__(self, rock: MeshRock, dt: float):
        self.limit = {s: min(2.0 * rock.alpha(s), OVERTURN_ANGLE) for s in (1.0, -1.0)}
        self.alpha = {s: rock.alpha(s) for s in (1.0, -1.0)}
        self.n_past = max(1, round(PAST_PIVOT_S / dt))
        self.dt = dt
        self.since: int | None = None  # first sample of the current excursion past the pivot
        self.time = math.nan

    def __call__(self, i: int, theta: float) -> bool:
        """Whether the rock has overturned at sample ``i`` with tilt ``theta`` [rad] (sets :attr:`time`)."""
        s = 1.0 if theta >= 0.0 else -1.0
        if abs(theta) >= self.limit[s]:
            self.time = i * self.dt
            return True
        if abs(theta) > self.alpha[s]:
            self.since = i if self.since is None else self.since
            if i - self.since >= self.n_past:
                self.time = self.since * self.dt
                return True
        else:
            self.since = None
        return False


class MeshEngine(Engine):
    """Base of the 3D scan-mesh engines: settings, the rock, the settling, the sample loop and the response.

    A subclass sets :attr:`DEFAULTS` (its own settings added to these), :attr:`RANGES`,
    :attr:`STRICT` and :attr:`CHOICES`, and implements :meth:`_build` (the world), :meth:`_step`,
    :meth:`_state` and :meth:`_set_state`. The rock is the mesh of the ``mesh`` setting: the
    ``specimen`` passed to :meth:`simulate` only gives the alpha that normalises the response
    (theta_max / alpha and the rocking threshold of the impact and uplift detector), as for the
    planar engines; the campaign passes the scan's equivalent block (``ScanSpecimen.specimen()``).
    An instance pickles as its settings (the rock is reloaded, from a cache, in the receiving process).

    Parameters
    ----------
    mesh : str or pathlib.Path
        The rock's scan mesh (watertight, metres, mesh z up); required.
    azimuth : float
        Shaking direction [deg] in [0, 360), from the mesh x axis toward +y.
    density : float
        Uniform density [kg/m^3].
    contact : {"hull"}
        The collision geometry: the mesh's convex hull.
    timestep : float
        Largest engine step [s]; the step used is motion.dt / ceil(motion.dt / timestep). Default 0.5 ms
        (10 steps per 5 ms sample of the ASU records; each engine's module says what it measured).
    friction : float
        Coulomb friction coefficient rock/table [-]. Default 0.7: granite on the steel shake table, in the
        0.6-0.8 the Virtual Shake Robot study of the same rocks used (Chen et al. 2024).
    """

    #: The campaign runner passes the campaign's mesh, azimuth and density as settings to such an engine.
    mesh_engine: ClassVar[bool] = True
    DEFAULTS: ClassVar[dict] = {**MESH_DEFAULTS, "timestep": 5e-4, "friction": 0.7}
    RANGES: ClassVar[dict] = {"timestep": (0.0, 1e-2), "friction": (0.0, 100.0)}
    STRICT: ClassVar[tuple[str, ...]] = ("timestep", "density")
    CHOICES: ClassVar[dict] = {}
    LABEL = SpecAttribute("label")

    def __init__(self, **settings: Any):
        unknown = sorted(set(settings) - set(self.DEFAULTS))
        if unknown:
            raise unknown_choice(f"{self.LABEL} setting", unknown[0], self.DEFAULTS)
        s = {**self.DEFAULTS, **settings}
        ranges = {"azimuth": (0.0, 360.0), "density": (0.0, 1e5), **self.RANGES}
        for key, (lo, hi) in ranges.items():
            try:
                v = float(s[key])
            except (TypeError, ValueError):
                raise ValueError(f"{self.LABEL} setting `{key}` must be a number, got {s[key]!r}") from None
            if not (lo <= v <= hi) or (key in self.STRICT and v == lo) or (key == "azimuth" and v == hi):
                raise ValueError(f"{self.LABEL} setting `{key}` must lie in [{lo:g}, {hi:g}], got {s[key]!r}")
            s[key] = v
        for key, accepted in self.CHOICES.items():
            if s[key] not in accepted:
                raise unknown_choice(f"{self.LABEL} setting `{key}`", s[key], accepted)
        self.rock = load_rock(s["mesh"], s["azimuth"], s["density"], s["contact"])
        s["mesh"] = str(s["mesh"])
        self._settings = s

    def settings(self) -> dict:
        """The settings as plain data, with ``mesh_sha1``: the mesh file's content enters the result cache key."""
        return {**self._settings, "mesh_sha1": self.rock.sha1}

    def __getstate__(self) -> dict:
        return {"settings": dict(self._settings)}

    def __setstate__(self, state: dict) -> None:
        self.__init__(**state["settings"])

    # --- the engine's hooks ---------------------------------------------------------------------------
    def _build(self, h: float) -> None:
        """Build the world (table, rock at rest :data:`DROP_GAP` above it) with engine step ``h`` [s]."""
        raise NotImplementedError

    def _step(self, force_x: np.ndarray) -> None:
        """Take one engine step per entry of ``force_x``, with that force [N] along +x at the COM."""
        raise NotImplementedError

    def _state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """COM position [m], rotation (body -> world), COM velocity [m/s], angular velocity [rad/s] (world)."""
        raise NotImplementedError

    def _set_state(self, pos: np.ndarray, rot: np.ndarray, vel: np.ndarray, omega: np.ndarray) -> None:
        """Put the rock in that state (as :meth:`_state` returns it)."""
        raise NotImplementedError

    # --- the run --------------------------------------------------------------------------------------
    def _simulate(self, specimen, motion, effects: tuple) -> Response:
        cpu0, wall0 = time.process_time(), time.perf_counter()
        k = max(1, math.ceil(motion.dt / self._settings["timestep"] * (1.0 - 1e-12)))
        h = motion.dt / k
        self._build(h)
        n_settle = max(1, round(SETTLE_S / h))
        self._step(np.zeros(n_settle))
        pos, rot0, vel, omega = self._state()
        x0 = pos.copy()  # the settled COM
        if motion.theta0 != 0.0 or motion.theta_dot0 != 0.0:
            pos, rot, vel, omega = self._release(pos, rot0, motion.theta0, motion.theta_dot0)
            self._set_state(pos, rot, vel, omega)
        check = OverturnCheck(self.rock, motion.dt)
        theta = np.zeros(motion.n)
        theta_dot = np.zeros(motion.n)
        theta[0], theta_dot[0] = tilt(self._state()[1], rot0, self._state()[3])
        frac = (np.arange(k) + 0.5) / k
        acc = np.asarray(motion.acc, dtype=float)
        force = -self.rock.mass * (acc[:-1, None] + np.diff(acc)[:, None] * frac[None, :])
        last, overturned = motion.n - 1, False
        for i in range(1, motion.n):
            self._step(force[i - 1])
            p, r, _, w = self._state()
            if not (np.isfinite(p).all() and np.isfinite(r).all() and np.linalg.norm(p - x0) < RUNAWAY_M):
                raise EngineError(
                    f"{self.LABEL} failed on motion {motion.name!r} at t = {i * motion.dt:.6g} s: the state is not "
                    f"finite or ran away (COM at {np.round(p, 4).tolist()} m); a diverging run needs a smaller "
                    "`timestep`"
                )
            theta[i], theta_dot[i] = tilt(r, rot0, w)
            if check(i, theta[i]):
                last, overturned = i, True
                break
        pos_end = self._state()[0]
        info = {
            **step_info(self, h, k, last),
            "settle_steps": n_settle,
            "mesh_mass_kg": self.rock.mass,
            "mesh_com_height_m": self.rock.h,
            "alpha_pos": self.rock.alpha(1.0),
            "alpha_neg": self.rock.alpha(-1.0),
            "com_shift_m": (pos_end - x0).tolist(),  # from the settled COM
            "cpu_time_s": time.process_time() - cpu0,
            "wall_time_s": time.perf_counter() - wall0,
        }
        res = sampled_response(self, specimen, motion, theta, theta_dot, last, overturned, info)
        if overturned:
            res = dataclasses.replace(res, overturn_time=check.time)
        return res

    def _release(self, pos, rot0, theta0: float, theta_dot0: float):
        """The settled rock turned by theta0 [rad] about its pivot edge, turning at theta_dot0 [rad/s] about it."""
        th, w = float(theta0), float(theta_dot0)
        side = math.copysign(1.0, th) if th != 0.0 else math.copysign(1.0, w)
        pivot = np.array([pos[0] + side * self.rock.b(side), pos[1], pos[2] - self.rock.h])
        turn = rot_y(th)
        new_pos = pivot + turn @ (pos - pivot)
        omega = np.array([0.0, w, 0.0])
        return new_pos, turn @ rot0, np.cross(omega, new_pos - pivot), omega


def hull_drop_height(rock: MeshRock) -> float:
    """COM height [m] at the release: the lowest hull point :data:`DROP_GAP` above the table (z = 0)."""
    return float(-rock.hull[:, 2].min()) + DROP_GAP
