"""A real rock's scan mesh as a free rigid body on a shaken table, in MuJoCo (engine ``mujoco-3d``).

:class:`MujocoMeshEngine` puts the rock of :mod:`housner.engines.scan_mesh.mesh3d` on a body with a free joint at its
centre of mass (the mesh's mass and full inertia tensor, its convex hull as collision geometry) on MuJoCo's
fixed infinite plane, and drives it by the d'Alembert force of the table acceleration at the centre of mass
(``xfrc_applied``, at the middle of each step). How it holds the rock is in ``docs/explanation/engines.md``
("The 3D scan-mesh engines"); the settings, their defaults and why, in :class:`MujocoMeshEngine`.
"""

from __future__ import annotations

from typing import Any, ClassVar

import mujoco
import numpy as np

from housner.engines.scan_mesh.mesh3d import MeshEngine, hull_drop_height
from housner.units import G

__all__ = ["MujocoMeshEngine"]


class MujocoMeshEngine(MeshEngine):
    """A scan mesh as a free rigid body on a fixed table, driven by -m ug''(t) at its COM, in MuJoCo.

    Parameters
    ----------
    solref : (float, float)
        Contact (time constant [s], damping ratio [-]) of the rock and the table.
    solimp : 5 floats
        Contact impedance (dmin, dmax, width [m], midpoint, power).
    cone : {"elliptic", "pyramidal"}
    impratio : float
    integrator : {"Euler", "implicitfast", "implicit", "RK4"}
    iterations : int
    tolerance : float
    mesh, azimuth, density, contact, timestep, friction
        As :class:`housner.engines.scan_mesh.mesh3d.MeshEngine`'s.

    Notes
    -----
    The defaults (``DEFAULTS``) and why:

    * ``timestep`` 0.5 ms (10 steps per 5 ms sample of the ASU records). Measured: a 0.2 x 0.4 x 1 m box
      released at 0.5 alpha gives the first impact within 0.1 % of Housner's quarter period and the next
      three rocking peaks within 1 % of Housner's at 1, 0.5 and 0.25 ms; on 16 random ASU records
      (SP1, azimuth 0) the predicted overturns differ in 1-2 records near the threshold between those
      steps (the rocking of a rock whose alpha is 0.09 rad is that sensitive), with no trend; 0.5 ms
      costs about 0.013 CPU s per simulated second, a tenth of the campaign's budget.
    * ``solref`` (2 ms, 1): four steps, critically damped (MuJoCo needs at least two steps): a stiff
      contact (the rock sinks by a few um at rest) whose impacts are plastic, as Housner's.
    * ``friction`` 0.7: granite on the steel shake table, in the 0.6-0.8 the Virtual Shake Robot study of
      the same rocks used (Chen et al. 2024). It is a physical value, not a numerical one: table
      accelerations above mu g make the rock slide, as it can on the real table.
    * ``cone`` "elliptic", ``impratio`` 1: MuJoCo's physically plain Coulomb cone.
    * ``integrator`` "implicitfast", ``iterations`` 50, ``tolerance`` 1e-10.

    References
    ----------
    MuJoCo documentation, "Computation" (soft contacts, solref/solimp) and "Modeling" (mesh geoms are
    convex hulls for collisions), https://mujoco.readthedocs.io
    Chen, Z. et al. (2024). Virtual Shake Robot. Seismica 3(1), doi:10.26443/seismica.v3i1.692.
    """

    name: ClassVar[str] = "mujoco-3d"
    DEFAULTS: ClassVar[dict] = {
        **MeshEngine.DEFAULTS,
        "solref": (2e-3, 1.0),
        "solimp": (0.9, 0.95, 0.001, 0.5, 2.0),
        "cone": "elliptic",
        "impratio": 1.0,
        "integrator": "implicitfast",
        "iterations": 50,
        "tolerance": 1e-10,
    }
    RANGES: ClassVar[dict] = {
        **MeshEngine.RANGES,
        "impratio": (0.0, 1e3),
        "iterations": (1, 1000),
        "tolerance": (0.0, 1e-2),
    }
    STRICT: ClassVar[tuple[str, ...]] = ("timestep", "density", "impratio")
    CHOICES: ClassVar[dict] = {
        "cone": ("elliptic", "pyramidal"),
        "integrator": ("Euler", "implicitfast", "implicit", "RK4"),
    }

    def __init__(self, **settings: Any):
        super().__init__(**settings)
        s = self._settings
        for key, n in (("solref", 2), ("solimp", 5)):
            try:
                v = tuple(float(x) for x in s[key])
            except (TypeError, ValueError):
                v = ()
            if len(v) != n or not np.all(np.isfinite(v)):
                raise ValueError(f"{self.LABEL} setting `{key}` must be {n} numbers, got {s[key]!r}")
            s[key] = v
        s["iterations"] = int(s["iterations"])
        self._model = self._data = None
        self._built_h = None

    def settings(self) -> dict:
        """The settings as plain data (tuples as lists), with the mesh's ``mesh_sha1``."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in super().settings().items()}

    def version(self) -> str:
        """The MuJoCo package version."""
        return mujoco.__version__

    def mjcf(self, h: float) -> str:
        """The MJCF text of the rock on the table with engine step ``h`` [s]."""
        s, rock = self._settings, self.rock
        num = " ".join
        contact = (
            f'friction="{s["friction"]!r} 0 0" condim="3" solref="{num(repr(v) for v in s["solref"])}" '
            f'solimp="{num(repr(v) for v in s["solimp"])}"'
        )
        i = rock.inertia
        full = num(repr(float(v)) for v in (i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2]))
        verts = num(repr(float(v)) for v in rock.hull.ravel())
        return f"""<mujoco model="rock">
  <option timestep="{h!r}" gravity="0 0 {-G!r}" integrator="{s["integrator"]}" cone="{s["cone"]}"
          impratio="{s["impratio"]!r}" iterations="{s["iterations"]}" tolerance="{s["tolerance"]!r}"/>
  <asset><mesh name="hull" vertex="{verts}"/></asset>
  <worldbody>
    <geom name="table" type="plane" size="0 0 1" {contact}/>
    <body name="rock" pos="0 0 {hull_drop_height(rock)!r}">
      <freejoint name="free"/>
      <inertial pos="0 0 0" mass="{rock.mass!r}" fullinertia="{full}"/>
      <geom name="hull" type="mesh" mesh="hull" {contact}/>
    </body>
  </worldbody>
</mujoco>"""

    def _build(self, h: float) -> None:
        if self._model is None or self._built_h != h:
            self._model = mujoco.MjModel.from_xml_string(self.mjcf(h))
            self._data = mujoco.MjData(self._model)
            self._built_h = h
            self._body = self._model.body("rock").id
        mujoco.mj_resetData(self._model, self._data)
        self._quat = np.empty(4)
        self._mat = np.empty(9)

    def _step(self, force_x: np.ndarray) -> None:
        m, d, frc = self._model, self._data, self._data.xfrc_applied[self._body]
        if not force_x.any():
            frc[0] = 0.0
            mujoco.mj_step(m, d, nstep=len(force_x))
            return
        for f in force_x:
            frc[0] = f
            mujoco.mj_step(m, d)

    def _state(self):
        d = self._data
        mujoco.mju_quat2Mat(self._mat, d.qpos[3:7])
        rot = self._mat.reshape(3, 3).copy()
        return d.qpos[0:3].copy(), rot, d.qvel[0:3].copy(), rot @ d.qvel[3:6]

    def _set_state(self, pos, rot, vel, omega) -> None:
        d = self._data
        d.qpos[0:3] = pos
        mujoco.mju_mat2Quat(self._quat, np.ascontiguousarray(rot).ravel())
        d.qpos[3:7] = self._quat
        d.qvel[0:3] = vel
        d.qvel[3:6] = rot.T @ omega
        d.qacc_warmstart[:] = 0.0
        mujoco.mj_forward(self._model, d)
