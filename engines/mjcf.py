"""The rocking specimen as a MuJoCo model (MJCF), generated from a :class:`housner.Specimen`.

Every number in the generated XML is derived from the specimen and the contact settings, and the XML
carries the derivation in comments: a ``block`` body at the centre of mass on slide x, slide z and a hinge
about +y (the suite's theta), two 10 um sphere pivots at the outer bottom edges of the drawn contact
strips, a ground plane that carries the pivots' ``solref`` and ``solimp``, and the ``dalembert`` motor on
the x slide. ``engines/models/README.md`` ("MJCF (MuJoCo)") walks through it step by step. The seed
specimen's model is shipped as ``engines/models/eth_specimen.xml``; regenerate it with
:func:`write_eth_specimen` (a test checks the shipped file equals the generator's output) and open it with
``python -m mujoco.viewer --mjcf=engines/models/eth_specimen.xml``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

from housner.engines._planar import check_offset, pivot_x
from housner.engines._planar import model_number as _num
from housner.specimen import Specimen
from housner.units import G

__all__ = [
    "ETH_SPECIMEN_PATH",
    "MJCF_DEFAULTS",
    "initial_qpos",
    "mjcf_from_specimen",
    "write_eth_specimen",
    "write_mjcf",
]

#: Where the seed specimen's generated model is shipped.
ETH_SPECIMEN_PATH = Path(__file__).resolve().parent / "models" / "eth_specimen.xml"

#: Model settings used when a keyword is not given. The contact numbers are the
#: tuned defaults of :class:`housner.engines.mujoco_engine.MujocoEngine` (see there for
#: how they were found); ``strip_width``, ``strip_height`` (drawn strips) and
#: ``pivot_radius`` (contact spheres at their outer edges) are geometry [m].
MJCF_DEFAULTS: dict = {
    "timestep": 2e-4,
    "solref": (4e-4, 1.0),
    "solimp": (0.9, 0.95, 0.001, 0.5, 2.0),
    "friction": 1.5,
    "cone": "pyramidal",
    "impratio": 10.0,
    "noslip_iterations": 0,
    "integrator": "Euler",
    "iterations": 50,
    "tolerance": 1e-10,
    "strip_width": 0.002,
    "strip_height": 0.002,
    "pivot_radius": 1e-5,
}

_CONES = ("pyramidal", "elliptic")
_INTEGRATORS = ("Euler", "implicitfast", "implicit", "RK4")


def _vec(xs: Sequence[float]) -> str:
    return " ".join(_num(x) for x in xs)


def _check_settings(specimen: Specimen, s: dict) -> dict:
    """Validate and normalise model settings; messages name the argument."""
    if not isinstance(specimen, Specimen):
        raise TypeError(f"`specimen` must be a housner.Specimen, got {type(specimen).__name__}")
    out = dict(s)
    for key in ("timestep", "friction", "impratio", "strip_width", "strip_height", "pivot_radius", "tolerance"):
        v = out[key]
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ValueError(f"`{key}` must be a positive finite number, got {v!r}")
        out[key] = float(v)
    for key in ("noslip_iterations", "iterations"):
        v = out[key]
        if not (isinstance(v, int) and not isinstance(v, bool) and v >= 0):
            raise ValueError(f"`{key}` must be a non-negative integer, got {v!r}")
    if out["iterations"] < 1:
        raise ValueError(f"`iterations` must be at least 1, got {out['iterations']!r}")
    solref = tuple(float(v) for v in out["solref"])
    if len(solref) != 2 or not all(math.isfinite(v) for v in solref):
        raise ValueError(f"`solref` must be two finite numbers (timeconst [s], dampratio [-]), got {out['solref']!r}")
    if solref[0] > 0 and not solref[1] > 0:
        raise ValueError(f"`solref` dampratio must be positive, got {out['solref']!r}")
    if solref[0] <= 0 and solref[1] > 0:
        # MuJoCo would warn "mixed solref format" and silently use its default
        raise ValueError(f"`solref` must be (timeconst, dampratio) > 0 or (-stiffness, -damping) <= 0, got {solref!r}")
    out["solref"] = solref
    solimp = tuple(float(v) for v in out["solimp"])
    if len(solimp) != 5 or not all(math.isfinite(v) for v in solimp):
        raise ValueError(f"`solimp` must be five finite numbers (dmin, dmax, width, midpoint, power), got {solimp!r}")
    if not (0 < solimp[0] < 1 and 0 < solimp[1] < 1 and solimp[2] > 0):
        raise ValueError(f"`solimp` needs 0 < dmin, dmax < 1 and width > 0, got {solimp!r}")
    out["solimp"] = solimp
    if out["cone"] not in _CONES:
        raise ValueError(f"`cone` must be one of {_CONES}, got {out['cone']!r}")
    if out["integrator"] not in _INTEGRATORS:
        raise ValueError(f"`integrator` must be one of {_INTEGRATORS}, got {out['integrator']!r}")
    if out["strip_width"] >= specimen.B:
        raise ValueError(f"`strip_width` ({out['strip_width']} m) must be less than B = {specimen.B} m")
    if out["pivot_radius"] > 1e-3 * specimen.H:
        # the block rolls on the sphere: its pivot is the sphere's centre, rho above the corner; keep that
        # below 1e-3 of H so the geometry (alpha, R) stays the specimen's to 1e-3 or better
        raise ValueError(f"`pivot_radius` ({out['pivot_radius']} m) must be at most 1e-3 H = {1e-3 * specimen.H:.3g} m")
    return out


def block_inertia(specimen: Specimen) -> tuple[float, float, float]:
    """Principal moments of inertia about the centre of mass (Ixx, Iyy, Izz) [kg m^2].

    Iyy, the only one the planar model uses (its rotation is about y alone), is
    I0 - m R^2 (parallel-axis theorem), so that p = sqrt(m g R / I0) is the
    specimen's. Ixx is set equal to Iyy: the specimen's mass sits mostly in the
    wedges and plates at its top and bottom, at about the same lever arm from
    both horizontal axes. Izz is the solid-box value m (4B^2 + d^2) / 12,
    capped at 2 Iyy so the three moments satisfy the triangle inequality that
    MuJoCo checks.
    """
    iyy = specimen.centroidal_inertia
    if not iyy > 0:
        raise ValueError(
            f"`specimen` has no centroidal inertia (I0 - m R^2 = {iyy:.3g} kg m^2); MuJoCo needs a positive one"
        )
    izz = min(specimen.mass * (specimen.width**2 + specimen.depth**2) / 12.0, 2.0 * iyy)
    return iyy, iyy, izz


def initial_qpos(
    specimen: Specimen, theta0: float, pivot_radius: float = 0.0, offset: float = 0.0
) -> tuple[float, float, float]:
    """Joint positions (x [m], z [m], theta [rad]) of the block at rest, rotated by ``theta0`` about a pivot.

    The block is rotated about the +x pivot for ``theta0`` > 0 and about the -x
    pivot for ``theta0`` < 0, touching the ground at (s B, 0) with s = sgn(theta0).
    The pivot is a sphere of radius rho = ``pivot_radius`` [m] whose centre sits
    at (s B, -H + rho) in the body frame, and at (s B, rho) in the world; the
    block turns about that centre, so its centre of mass is at
    (s B (1 - cos theta0) + (H - rho) sin theta0, rho + B |sin theta0| + (H - rho) cos theta0);
    the slides hold its offset from the upright position (0, H). rho = 0 is
    rotation about the corner itself. With the centre of mass ``offset`` e [m] toward +x of the
    pivots' midpoint (``asymmetric_pivots``) s B is the pivot's x, B - e or -(B + e), and B its
    distance |s B| from the centre of mass.
    """
    th = float(theta0)
    s = math.copysign(1.0, th) if th != 0.0 else 0.0
    H, rho = specimen.H, float(pivot_radius)
    bx = 0.0 if s == 0.0 else pivot_x(specimen.B, offset)[0 if s > 0.0 else 1]  # s B at offset 0
    x = bx * (1.0 - math.cos(th)) + (H - rho) * math.sin(th)
    z = rho + abs(bx) * abs(math.sin(th)) + (H - rho) * math.cos(th) - H
    return x, z, th


def mjcf_from_specimen(
    specimen: Specimen,
    *,
    timestep: float = MJCF_DEFAULTS["timestep"],
    solref: Sequence[float] = MJCF_DEFAULTS["solref"],
    solimp: Sequence[float] = MJCF_DEFAULTS["solimp"],
    friction: float = MJCF_DEFAULTS["friction"],
    cone: str = MJCF_DEFAULTS["cone"],
    impratio: float = MJCF_DEFAULTS["impratio"],
    noslip_iterations: int = MJCF_DEFAULTS["noslip_iterations"],
    integrator: str = MJCF_DEFAULTS["integrator"],
    iterations: int = MJCF_DEFAULTS["iterations"],
    tolerance: float = MJCF_DEFAULTS["tolerance"],
    strip_width: float = MJCF_DEFAULTS["strip_width"],
    strip_height: float = MJCF_DEFAULTS["strip_height"],
    pivot_radius: float = MJCF_DEFAULTS["pivot_radius"],
    offset: float = 0.0,
) -> str:
    """The MJCF XML text of a planar rocking block, commented with each number's derivation.

    Parameters
    ----------
    specimen : Specimen
        Geometry (2H, 2B, depth [m]), mass [kg] and I0 [kg m^2].
    timestep : float
        Integration step [s]. The engine may shorten it so that it divides the
        motion's sample step.
    solref : (float, float)
        Contact reference (timeconst [s], dampratio [-]) of the strips.
    solimp : 5 floats
        Contact impedance (dmin [-], dmax [-], width [m], midpoint [-], power [-]).
    friction : float
        Sliding friction coefficient mu [-] of the strips on the ground.
    cone : {"pyramidal", "elliptic"}
        Friction cone.
    impratio : float
        Ratio of frictional to normal constraint impedance [-].
    noslip_iterations : int
        Iterations of MuJoCo's no-slip post-solver (0 = off).
    iterations, tolerance : int, float
        Main constraint-solver iterations and tolerance [-].
    strip_width, strip_height : float
        Size of each (drawn) contact strip in x and z [m]; its outer edge is at +-B.
    pivot_radius : float
        Radius [m] of the contact spheres at the strips' outer bottom edges, the
        pivots; at most 1e-3 H.
    offset : float
        e [m]: the centre of mass e toward +x of the pivots' midpoint (the effect
        ``asymmetric_pivots``), |e| < B: the pivots (and drawn strips) at x = B - e and
        -(B + e) of the body frame (the centre of mass), the drawn block centred on their
        midpoint; mass and inertia unchanged. 0 (default): the symmetric block, the same text
        as without the keyword.

    Returns
    -------
    str
        A standalone MJCF document (loads with ``mujoco.MjModel.from_xml_string``).

    References
    ----------
    Bachmann, J. A. et al. (2017). COMPDYN 2017, eqs. 3-4, section 3.1.
    """
    settings = dict(
        timestep=timestep,
        solref=solref,
        solimp=solimp,
        friction=friction,
        cone=cone,
        impratio=impratio,
        noslip_iterations=noslip_iterations,
        integrator=integrator,
        iterations=iterations,
        tolerance=tolerance,
        strip_width=strip_width,
        strip_height=strip_height,
        pivot_radius=pivot_radius,
    )
    s = _check_settings(specimen, settings)
    e = check_offset(specimen.B, offset)
    return _head_xml(specimen) + _scene_xml(s, specimen.H) + _block_xml(specimen, s, e) + _TAIL


def _head_xml(specimen: Specimen) -> str:
    """The comment that gives the specimen's numbers and how to open the file, and the model's opening."""
    name = specimen.name.replace("--", "- -")  # "--" may not appear inside an XML comment
    D, m = specimen.depth, specimen.mass
    return f"""<!--
  Rocking block "{name}", generated by engines/mjcf.py from a housner.Specimen.
  Do not edit by hand: regenerate it (see engines/models/README.md).
  Open it with:  python -m mujoco.viewer --mjcf=THIS_FILE

  Specimen: 2H = {_num(specimen.height)} m, 2B = {_num(specimen.width)} m, depth = {_num(D)} m, m = {_num(m)} kg,
            I0 = {_num(specimen.inertia)} kg m^2 (about a pivot), p = {_num(specimen.p)} 1/s,
            alpha = {_num(specimen.alpha)} rad, R = {_num(specimen.R)} m, r_housner = {_num(specimen.r_housner)}.
-->
<mujoco model="{_xml_attr(specimen.name)}">
  <compiler angle="radian" autolimits="true"/>
"""


def _scene_xml(s: dict, H: float) -> str:
    """Options (steps 1-3), visual settings, the ground (step 4) and the camera."""
    return f"""  <!-- (1) g = housner.units.G = 9.80665 m/s^2 downward. (2) timestep: engine setting [s].
       (3) cone, impratio, noslip_iterations, iterations, tolerance: contact solver settings
       (housner.engines.mujoco_engine.MujocoEngine documents the tuned values). -->
  <option timestep="{_num(s["timestep"])}" gravity="0 0 {_num(-G)}" integrator="{s["integrator"]}" cone="{s["cone"]}"
          impratio="{_num(s["impratio"])}" noslip_iterations="{s["noslip_iterations"]}"
          iterations="{s["iterations"]}" tolerance="{_num(s["tolerance"])}">
    <!-- (3a) Speed, same results: no constraint islands (one body), no mid-phase collision (two pairs),
         no implicit joint damping (none to integrate); together about 15 % faster per step. -->
    <flag island="disable" midphase="disable" eulerdamp="disable"/>
  </option>
  <visual>
    <global offwidth="1280" offheight="720"/>
  </visual>
  <statistic center="0 0 {_num(H)}" extent="{_num(2.5 * H)}"/>
  <asset>
    <texture name="grid" type="2d" builtin="checker" rgb1=".85 .85 .85" rgb2=".7 .7 .7" width="256" height="256"/>
    <material name="grid" texture="grid" texrepeat="20 20" texuniform="true"/>
  </asset>
  <worldbody>
    <light pos="0 -2 3" dir="0 0.6 -0.8" directional="true"/>
    <!-- (4) Pivot line z = 0 on an infinite ground plane (size 0 = infinite) with the pivots' friction (MuJoCo
         takes the larger of the two geoms' coefficients) and the pivots' solref and solimp (MuJoCo averages the
         two geoms' values: a ground left at the default solref (0.02, 1) would give the contact a time constant
         of (0.02 s + timeconst) / 2, tens of times softer than asked). -->
    <geom name="ground" type="plane" size="0 0 1" material="grid" friction="{_num(s["friction"])} 0 0"
          solref="{_vec(s["solref"])}" solimp="{_vec(s["solimp"])}"/>
    <camera name="side" pos="0 {_num(-6 * H)} {_num(H)}" xyaxes="1 0 0 0 0 1"/>
"""


def _block_xml(specimen: Specimen, s: dict, e: float = 0.0) -> str:
    """The block: frame, joints, inertia, drawn body and strips, and the two pivot spheres (steps 5-11);
    the pivots at x = B - e and -(B + e) of the centre of mass (``e`` [m], 0: +-B)."""
    H, B, D, m = specimen.H, specimen.B, specimen.depth, specimen.mass
    ixx, iyy, izz = block_inertia(specimen)
    w, hs = s["strip_width"], s["strip_height"]
    bp, bn = pivot_x(B, e)
    strip_x, strip_x_neg = bp - w / 2.0, bn + w / 2.0  # -(B - w/2) at e = 0, the same float
    strip_z = -H + hs / 2.0
    rho = s["pivot_radius"]
    pivot_z = -H + rho
    if e == 0.0:
        body_pos = ""
        strips = f"x = +-B = +-{_num(B)} m, so centres at x = +-(B - w/2) = +-{_num(strip_x)} m"
        pivots = f"x = +-B = +-{_num(B)} m"
        touch = "(+-B, 0)"
    else:
        body_pos = f' pos="{_vec((-e, 0, 0))}"'
        strips = (
            f"x = B - e = {_num(bp)} m and -(B + e) = {_num(bn)} m (centre of mass e = {_num(e)} m toward +x of\n"
            f"           their midpoint), so centres at x = {_num(strip_x)} m and {_num(strip_x_neg)} m"
        )
        pivots = f"x = B - e = {_num(bp)} m and -(B + e) = {_num(bn)} m"
        touch = "(B - e, 0) and (-(B + e), 0)"
    return f"""\
    <!-- (5) The body frame is the centre of mass, at height H = 2H / 2 = {_num(H)} m above the pivot line. -->
    <body name="block" pos="0 0 {_num(H)}">
      <!-- (6) Planar motion: slide x, slide z, hinge about +y through the centre of mass.
           Hinge angle = theta of the suite (theta > 0: top toward +x, rocking on the +x pivot). -->
      <joint name="x" type="slide" axis="1 0 0"/>
      <joint name="z" type="slide" axis="0 0 1"/>
      <joint name="theta" type="hinge" axis="0 1 0"/>
      <!-- (7) Mass m = {_num(m)} kg at the centre of mass. Iyy = I0 - m R^2
           = {_num(specimen.inertia)} - {_num(m)} * {_num(specimen.R)}^2 = {_num(iyy)} kg m^2
           (parallel axes), so p = sqrt(m g R / I0) = {_num(specimen.p)} 1/s.
           Ixx = Iyy (mass mostly at top and bottom); Izz = min(m (4B^2 + d^2) / 12, 2 Iyy)
           = {_num(izz)} kg m^2. Only Iyy enters the planar motion. -->
      <inertial pos="0 0 0" mass="{_num(m)}" diaginertia="{_vec((ixx, iyy, izz))}"/>
      <!-- (8) Visual block: half-sizes (B, depth/2, H) = ({_vec((B, D / 2, H))}) m; no contact, no mass. -->
      <geom name="body" type="box" size="{_vec((B, D / 2, H))}"{body_pos} contype="0" conaffinity="0" mass="0"
            rgba=".75 .78 .82 .6"/>
      <!-- (9) Contact strips (drawn only: no contact, no mass), {_num(w)} m wide and {_num(hs)} m tall, full depth;
           outer edges at {strips} and
           z = -H + h/2 = {_num(strip_z)} m (bottom on the pivot line). -->
      <geom name="strip_pos" type="box" size="{_vec((w / 2, D / 2, hs / 2))}" pos="{_vec((strip_x, 0, strip_z))}"
            contype="0" conaffinity="0" mass="0" rgba=".2 .3 .8 1"/>
      <geom name="strip_neg" type="box" size="{_vec((w / 2, D / 2, hs / 2))}" pos="{_vec((strip_x_neg, 0, strip_z))}"
            contype="0" conaffinity="0" mass="0" rgba=".8 .3 .2 1"/>
      <!-- (10) Pivots, the only contact geoms: spheres of radius rho = {_num(rho)} m at the strips' outer bottom
           edges, centres at {pivots}, z = -H + rho = {_num(pivot_z)} m, so each touches the ground
           at {touch} when upright: one contact point per pivot, as in Housner's model.
           (11) friction mu = {_num(s["friction"])}; solref = (timeconst [s], dampratio [-]);
           solimp = (dmin, dmax, width [m], midpoint, power): contact settings, the ground's too. -->
      <geom name="pivot_pos" type="sphere" size="{_num(rho)}" pos="{_vec((bp, 0, pivot_z))}"
            condim="3" friction="{_num(s["friction"])} 0 0" solref="{_vec(s["solref"])}" solimp="{_vec(s["solimp"])}"
            mass="0" rgba=".1 .1 .1 1"/>
      <geom name="pivot_neg" type="sphere" size="{_num(rho)}" pos="{_vec((bn, 0, pivot_z))}"
            condim="3" friction="{_num(s["friction"])} 0 0" solref="{_vec(s["solref"])}" solimp="{_vec(s["solimp"])}"
            mass="0" rgba=".1 .1 .1 1"/>
    </body>
"""


#: The actuator (step 12) and the end of the document.
_TAIL = """  </worldbody>
  <actuator>
    <!-- (12) d'Alembert force of the ground acceleration, ctrl = -m ug''(t) [N], along x through the
         centre of mass (the slide joint's anchor); unlimited. -->
    <motor name="dalembert" joint="x" gear="1"/>
  </actuator>
</mujoco>
"""


def _xml_attr(text: str) -> str:
    return text.replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;").replace(">", "&gt;")


def write_mjcf(specimen: Specimen, path: str | Path, **settings) -> Path:
    """Write :func:`mjcf_from_specimen` (``settings`` as its keywords) to ``path`` and return the path."""
    path = Path(path)
    path.write_text(mjcf_from_specimen(specimen, **settings), encoding="utf-8")
    return path


def write_eth_specimen(path: str | Path = ETH_SPECIMEN_PATH) -> Path:
    """Regenerate the shipped model of the seed specimen (``Specimen.bachmann2017()``, default settings)."""
    return write_mjcf(Specimen.bachmann2017(), path)
