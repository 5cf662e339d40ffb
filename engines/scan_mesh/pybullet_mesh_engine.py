"""A real rock's scan mesh as a free rigid body on a shaken table, in PyBullet (engine ``pybullet-3d``).

:class:`PybulletMeshEngine` puts the rock of :mod:`housner.engines.scan_mesh.mesh3d` on one floating-base body (its
convex hull as ``GEOM_MESH``, the mesh's mass and diagonalised inertia, no damping) on PyBullet's fixed
infinite plane, and drives it by the d'Alembert force of the table acceleration (gravity tilted to
(-ug'', 0, -g) before each step). How it holds the rock is in ``docs/explanation/engines.md`` ("The 3D
scan-mesh engines"); the settings, their defaults and why, in :class:`PybulletMeshEngine`.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from housner.engines._planar import optional_package
from housner.engines.scan_mesh.mesh3d import DROP_GAP, MeshEngine
from housner.units import G

__all__ = ["PybulletMeshEngine"]


class PybulletMeshEngine(MeshEngine):
    """A scan mesh as a free rigid body on a fixed table, driven by -m ug''(t) at its COM, in PyBullet.

    Parameters
    ----------
    solver_iterations : int
        Sequential-impulse iterations per step.
    erp, contact_erp : float
        Share of a joint / contact position error corrected per step [-].
    collision_margin : float
        Bullet's collision margin around the convex hull [m].
    mesh, azimuth, density, contact, timestep, friction
        As :class:`housner.engines.scan_mesh.mesh3d.MeshEngine`'s.

    Notes
    -----
    The defaults (``DEFAULTS``) and why:

    * ``timestep`` 0.5 ms (10 steps per 5 ms sample of the ASU records): Bullet's contact is rigid
      (velocity-level, restitution 0), so the step sets how exactly an impact lands. Measured: a
      0.2 x 0.4 x 1 m box released at 0.5 alpha gives the first impact within 0.1 % of Housner's
      quarter period and the next three rocking peaks within 1 % of Housner's at 1, 0.5 and 0.25 ms;
      on 16 random ASU records (SP1, azimuth 0) the predicted overturns differ in 1-3 records near the
      threshold between those steps, with no trend; 0.5 ms costs about 0.016 CPU s per simulated second.
    * ``friction`` 0.7: granite on the steel shake table, in the 0.6-0.8 the Virtual Shake Robot
      study of the same rocks used in PyBullet (Chen et al. 2024); table accelerations above mu g
      make the rock slide, as on the real table.
    * ``solver_iterations`` 50, ``erp`` 0.2 and ``contact_erp`` 0.2
      (Bullet's defaults: the share of a penetration corrected per step), ``collision_margin`` 1 mm:
      the shell Bullet keeps around a convex hull; the rock stands and rocks on its hull grown by
      that much (a pivot radius of 1 mm).

    References
    ----------
    Coumans, E. and Bai, Y. (2016-2021). PyBullet. https://pybullet.org (Quickstart Guide:
    createCollisionShape, createMultiBody, changeDynamics, setPhysicsEngineParameter).
    Chen, Z. et al. (2024). Virtual Shake Robot. Seismica 3(1), doi:10.26443/seismica.v3i1.692.
    """

    name: ClassVar[str] = "pybullet-3d"
    DEFAULTS: ClassVar[dict] = {
        **MeshEngine.DEFAULTS,
        "solver_iterations": 50,
        "erp": 0.2,
        "contact_erp": 0.2,
        "collision_margin": 1e-3,
    }
    RANGES: ClassVar[dict] = {
        **MeshEngine.RANGES,
        "solver_iterations": (1, 10000),
        "erp": (0.0, 1.0),
        "contact_erp": (0.0, 1.0),
        "collision_margin": (0.0, 0.05),
    }
    MODULE: ClassVar[str] = "pybullet"

    def __init__(self, **settings: Any):
        self._pb = optional_package(self.name, "pybullet", "pybullet", "pip install pybullet")
        super().__init__(**settings)
        self._settings["solver_iterations"] = int(self._settings["solver_iterations"])
        self._cid: int | None = None

    def close(self) -> None:
        """Disconnect the PyBullet client (reopened on next use)."""
        if self._cid is not None:
            try:
                self._pb.disconnect(physicsClientId=self._cid)
            except Exception:  # already gone
                pass
            self._cid = None

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:
            pass

    def _build(self, h: float) -> None:
        pb, s, rock = self._pb, self._settings, self.rock
        if self._cid is None:
            self._cid = pb.connect(pb.DIRECT)
        cid = self._cid
        pb.resetSimulation(physicsClientId=cid)
        pb.setPhysicsEngineParameter(
            fixedTimeStep=h,
            numSubSteps=0,
            numSolverIterations=s["solver_iterations"],
            erp=s["erp"],
            contactERP=s["contact_erp"],
            frictionERP=s["erp"],
            restitutionVelocityThreshold=0.0,
            physicsClientId=cid,
        )
        pb.setGravity(0.0, 0.0, -G, physicsClientId=cid)
        plane = pb.createMultiBody(
            0.0, pb.createCollisionShape(pb.GEOM_PLANE, physicsClientId=cid), physicsClientId=cid
        )
        moments, axes = np.linalg.eigh(rock.inertia)
        if np.linalg.det(axes) < 0:
            axes[:, 2] *= -1.0
        quat = _quat_of(axes)
        shape = pb.createCollisionShape(pb.GEOM_MESH, vertices=rock.hull.tolist(), physicsClientId=cid)
        z0 = float(-rock.hull[:, 2].min()) + DROP_GAP + s["collision_margin"]
        self._body = pb.createMultiBody(
            baseMass=rock.mass,
            baseCollisionShapeIndex=shape,
            basePosition=(0.0, 0.0, z0),
            baseInertialFramePosition=(0.0, 0.0, 0.0),
            baseInertialFrameOrientation=quat,
            physicsClientId=cid,
        )
        for body in (plane, self._body):
            pb.changeDynamics(
                body,
                -1,
                lateralFriction=s["friction"],
                restitution=0.0,
                rollingFriction=0.0,
                spinningFriction=0.0,
                linearDamping=0.0,
                angularDamping=0.0,
                physicsClientId=cid,
            )
        pb.changeDynamics(
            self._body,
            -1,
            localInertiaDiagonal=moments.tolist(),
            collisionMargin=s["collision_margin"],
            activationState=pb.ACTIVATION_STATE_DISABLE_SLEEPING,
            physicsClientId=cid,
        )
        self._axes = axes  # inertial frame -> rock frame: the body's rotation is R_inertial axes^T

    def _step(self, force_x: np.ndarray) -> None:
        pb, cid, m = self._pb, self._cid, self.rock.mass
        gz = -G
        for f in force_x:
            pb.setGravity(f / m, 0.0, gz, physicsClientId=cid)
            pb.stepSimulation(physicsClientId=cid)

    def _state(self):
        pb, cid = self._pb, self._cid
        pos, quat = pb.getBasePositionAndOrientation(self._body, physicsClientId=cid)
        vel, omega = pb.getBaseVelocity(self._body, physicsClientId=cid)
        rot = np.array(pb.getMatrixFromQuaternion(quat)).reshape(3, 3) @ self._axes.T
        return np.array(pos), rot, np.array(vel), np.array(omega)

    def _set_state(self, pos, rot, vel, omega) -> None:
        pb, cid = self._pb, self._cid
        quat = _quat_of(rot @ self._axes)
        pb.resetBasePositionAndOrientation(self._body, pos.tolist(), quat, physicsClientId=cid)
        pb.resetBaseVelocity(self._body, vel.tolist(), omega.tolist(), physicsClientId=cid)


def _quat_of(rot: np.ndarray) -> tuple[float, float, float, float]:
    """(x, y, z, w) quaternion of a rotation matrix (Shepperd's method)."""
    m = np.asarray(rot, dtype=float)
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    if tr > 0.0:
        s = 2.0 * math.sqrt(tr + 1.0)
        w, x, y, z = 0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        w, x, y, z = (m[2, 1] - m[1, 2]) / s, 0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        w, x, y, z = (m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s
    else:
        s = 2.0 * math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        w, x, y, z = (m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s
    return (x, y, z, w)
