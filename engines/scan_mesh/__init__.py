"""A real rock's scan mesh as a free rigid body on a shaken table, in 3D: what the mesh engines share
(:mod:`~housner.engines.scan_mesh.mesh3d`) and one adapter per engine (``mujoco-3d``, ``pybullet-3d``)."""
