"""The rocking specimen as a URDF robot (for PyBullet), generated from a :class:`housner.Specimen`.

URDF has no planar joint, so the block hangs from the world through two massless carriages (prismatic
``x`` anchored at z = H, prismatic ``z``, then the continuous ``theta`` about +y: the suite's theta) and
touches the ground only with two contact strips, bevelled so that their outer bottom edges are the
pivots; contact properties are not in the file (:class:`housner.engines.pybullet_engine.PybulletEngine`
sets them). Load it with ``useFixedBase=True`` and ``flags=pybullet.URDF_USE_INERTIA_FROM_FILE`` (without
it PyBullet recomputes the inertia from the collision boxes and ``p`` is wrong). How each number follows
from the specimen is in ``engines/models/README.md`` ("URDF (PyBullet)"). The seed specimen's model is
shipped as ``engines/models/eth_specimen.urdf``; regenerate it with :func:`write_eth_specimen` (a test
checks that the shipped file equals the generator's output).
"""

from __future__ import annotations

import math
from pathlib import Path

from housner.engines._planar import check_offset, pivot_x
from housner.engines._planar import model_number as _num
from housner.specimen import Specimen

__all__ = [
    "ETH_SPECIMEN_PATH",
    "JOINTS",
    "URDF_DEFAULTS",
    "urdf_from_specimen",
    "write_eth_specimen",
    "write_urdf",
]

#: Where the seed specimen's generated model is shipped.
ETH_SPECIMEN_PATH = Path(__file__).resolve().parent / "models" / "eth_specimen.urdf"

#: Joint names in the order PyBullet numbers them (joint index 0, 1, 2).
JOINTS = ("x", "z", "theta")

#: Geometry and dummy-link settings used when a keyword is not given.
URDF_DEFAULTS: dict = {
    "strip_width": 0.002,  # [m] the seed's wedges end in 2 mm strips
    "strip_height": 0.002,  # [m] collision only; any height gives the same contact
    "carriage_mass": 1e-6,  # [kg] relative 2.5e-7 of the seed's 3.94 kg
    "carriage_inertia": 1e-9,  # [kg m^2] the carriages never rotate
    "bevel": 0.005,  # [rad] inner edges 10 um above the ground: only the outer edges touch
}

#: Travel of the two slide joints [m]; wide enough never to be reached.
_SLIDE_LIMIT = 1.0e3


def _positive(name: str, value: float) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be a number, got {value!r}") from None
    if not (math.isfinite(x) and x > 0.0):
        raise ValueError(f"`{name}` must be positive and finite, got {value!r}")
    return x


def _inertial(mass: float, inertia: float, indent: str) -> str:
    i = _num(inertia)
    return (
        f"{indent}<inertial>\n"
        f'{indent}  <origin xyz="0 0 0" rpy="0 0 0"/>\n'
        f'{indent}  <mass value="{_num(mass)}"/>\n'
        f'{indent}  <inertia ixx="{i}" ixy="0" ixz="0" iyy="{i}" iyz="0" izz="{i}"/>\n'
        f"{indent}</inertial>\n"
    )


def urdf_from_specimen(
    specimen: Specimen,
    *,
    strip_width: float = URDF_DEFAULTS["strip_width"],
    strip_height: float = URDF_DEFAULTS["strip_height"],
    carriage_mass: float = URDF_DEFAULTS["carriage_mass"],
    carriage_inertia: float = URDF_DEFAULTS["carriage_inertia"],
    bevel: float = URDF_DEFAULTS["bevel"],
    name: str = "rocking_block",
    offset: float = 0.0,
) -> str:
    """The URDF text of the planar rocking block.

    Parameters
    ----------
    specimen : Specimen
        Geometry [m], mass [kg] and inertia [kg m^2] of the block.
    strip_width : float
        Width of each contact strip along x [m]; the strips' outer edges are
        at x = +-B whatever the width. Must be below B.
    strip_height : float
        Height of the strips [m] (collision geometry only).
    bevel : float
        Rotation of each strip about its outer bottom edge [rad], in
        [0, 0.1]: it lifts the inner bottom edge by ``strip_width *
        sin(bevel)`` so that only the outer edges touch flat ground.
    carriage_mass : float
        Mass of each of the two dummy carriage links [kg]; must be below 1e-3
        of the specimen's mass so that it cannot distort the dynamics.
    carriage_inertia : float
        Principal moments of inertia of each carriage [kg m^2].
    name : str
        The robot's name.
    offset : float
        e [m]: the centre of mass e toward +x of the pivots' midpoint (the effect
        ``asymmetric_pivots``), |e| < B: the pivots at x = B - e and -(B + e)
        of the block frame (the centre of mass), the visual box centred on their midpoint; the mass
        and the centroidal inertia unchanged. 0 (default): the symmetric block, the same text as
        without the keyword.

    Returns
    -------
    str
        URDF (XML) text; every number is written with enough digits to read
        back as the same float.

    Notes
    -----
    The layout and the derivation of each number: ``engines/models/README.md``, "URDF (PyBullet)".
    The joint anchor of ``x`` is at z = H, so with all joints at zero the block
    stands upright with its strips touching the plane z = 0.
    """
    if not isinstance(specimen, Specimen):
        raise TypeError(f"`specimen` must be a housner.Specimen, got {type(specimen).__name__}")
    strip, carriage = _checked_parts(specimen, (strip_width, strip_height, bevel), (carriage_mass, carriage_inertia))
    if not (isinstance(name, str) and name and all(ch.isalnum() or ch in "_-." for ch in name)):
        raise ValueError(f"`name` must be a non-empty identifier (letters, digits, _ - .), got {name!r}")
    e = check_offset(specimen.B, offset)
    return _urdf_header(specimen, e) + _urdf_robot(specimen, name, strip, carriage, e)


def _checked_parts(specimen: Specimen, strip: tuple, carriage: tuple) -> tuple[tuple, tuple[float, float]]:
    """The contact strip's (width [m], height [m], bevel [rad]) and each dummy carriage's (mass [kg], moment of
    inertia [kg m^2]), checked as :func:`urdf_from_specimen` documents."""
    (strip_width, strip_height, bevel), (carriage_mass, carriage_inertia) = strip, carriage
    strip_width = _positive("strip_width", strip_width)
    strip_height = _positive("strip_height", strip_height)
    carriage_mass = _positive("carriage_mass", carriage_mass)
    carriage_inertia = _positive("carriage_inertia", carriage_inertia)
    try:
        bevel = float(bevel)
    except (TypeError, ValueError):
        raise ValueError(f"`bevel` must be a number, got {bevel!r}") from None
    if not (0.0 <= bevel <= 0.1):
        raise ValueError(f"`bevel` must lie in [0, 0.1] rad, got {bevel!r}")
    B, m = specimen.B, specimen.mass
    if strip_width >= B:
        raise ValueError(f"`strip_width` ({strip_width} m) must be below B = {B} m (half the pivot distance)")
    if carriage_mass > 1e-3 * m:
        raise ValueError(f"`carriage_mass` ({carriage_mass} kg) must be below 1e-3 of the specimen's mass ({m} kg)")
    return (strip_width, strip_height, bevel), (carriage_mass, carriage_inertia)


def _urdf_header(specimen: Specimen, e: float = 0.0) -> str:
    """The XML declaration and the comment that gives the specimen's numbers (and the pivots' offset ``e`` [m],
    when not 0) and how to load the file."""
    D, m = specimen.depth, specimen.mass
    pivots = ""
    if e != 0.0:
        bp, bn = pivot_x(specimen.B, e)
        pivots = (
            f"\n     Asymmetric pivots: centre of mass e = {_num(e)} m toward +x of their midpoint, pivots at "
            f"x = {_num(bp)} m and {_num(bn)} m"
        )
    return f"""<?xml version="1.0"?>
<!-- Generated by housner.engines.urdf.urdf_from_specimen; do not edit by hand.
     Specimen: {_xml_comment(specimen.name)}
     2H = {_num(specimen.height)} m, 2B = {_num(specimen.width)} m, depth = {_num(D)} m, m = {_num(m)} kg
     I0 = {_num(specimen.inertia)} kg m^2 (pivot), p = {_num(specimen.p)} 1/s, alpha = {_num(specimen.alpha)} rad
     I_c = I0 - m R^2 = {_num(specimen.centroidal_inertia)} kg m^2 (centre of mass), R = {_num(specimen.R)} m{pivots}
     Load with useFixedBase=True and flags=URDF_USE_INERTIA_FROM_FILE. -->
"""


def _urdf_robot(specimen: Specimen, name: str, strip: tuple, carriage: tuple[float, float], e: float = 0.0) -> str:
    """The robot: the world, the x and z slides with their carriages, the theta hinge and the block with its strips.

    ``strip`` is (width [m], height [m], bevel [rad]), ``carriage`` (mass [kg], inertia [kg m^2]) and ``e`` [m]
    the centre of mass's offset toward +x of the pivots' midpoint (pivots at x = B - e and -(B + e)).
    """
    strip_width, strip_height, bevel = strip
    H, B, D = specimen.H, specimen.B, specimen.depth
    bp, bn = pivot_x(B, e)
    # Strip centre = outer bottom edge (B, -H) + Rot(bevel) (-w/2, h/2), with Rot(b) (x, z) = (x c + z s, -x s + z c)
    cb, sb = math.cos(bevel), math.sin(bevel)
    inward = strip_width / 2.0 * cb - strip_height / 2.0 * sb
    sx, sx_neg = bp - inward, bn + inward  # -(B - inward) at e = 0, the same float as -sx
    sz = -H + (strip_width / 2.0 * sb + strip_height / 2.0 * cb)
    if e == 0.0:
        visual, edge_pos, edge_neg = "0 0 0", "+B", "-B"
    else:
        visual, edge_pos, edge_neg = f"{_num(-e)} 0 0", f"+(B - e) = {_num(bp)}", f"-(B + e) = {_num(bn)}"
    box = f'<box size="{_num(strip_width)} {_num(D)} {_num(strip_height)}"/>'
    lim = _num(_SLIDE_LIMIT)
    slide_limit = f'<limit lower="-{lim}" upper="{lim}" effort="0" velocity="1000"/>'
    return f"""<robot name="{name}">
  <link name="world"/>
{_joint("x", "prismatic", "world", "carriage_x", f"0 0 {_num(H)}", "1 0 0", slide_limit)}
{_carriage("carriage_x", *carriage)}
{_joint("z", "prismatic", "carriage_x", "carriage_z", "0 0 0", "0 0 1", slide_limit)}
{_carriage("carriage_z", *carriage)}
{_joint("theta", "continuous", "carriage_z", "block", "0 0 0", "0 1 0")}
  <link name="block">
    <!-- centre of mass at the link origin; iyy = I0 - m R^2 -->
{_inertial(specimen.mass, specimen.centroidal_inertia, "    ")}    <visual>
      <origin xyz="{visual}" rpy="0 0 0"/>
      <geometry><box size="{_num(specimen.width)} {_num(D)} {_num(specimen.height)}"/></geometry>
    </visual>
    <!-- contact strip at the +x pivot: outer bottom edge at ({edge_pos}, -H), turned by the bevel about it -->
    <collision name="pivot_pos">
      <origin xyz="{_num(sx)} 0 {_num(sz)}" rpy="0 {_num(bevel)} 0"/>
      <geometry>{box}</geometry>
    </collision>
    <!-- contact strip at the -x pivot: outer bottom edge at ({edge_neg}, -H) -->
    <collision name="pivot_neg">
      <origin xyz="{_num(sx_neg)} 0 {_num(sz)}" rpy="0 {_num(-bevel)} 0"/>
      <geometry>{box}</geometry>
    </collision>
  </link>
</robot>
"""


def _joint(name: str, kind: str, parent: str, child: str, xyz: str, axis: str, extra: str = "") -> str:
    """A URDF joint from ``parent`` to ``child`` anchored at ``xyz`` [m] in the parent, moving along/about ``axis``."""
    lines = [
        f'  <joint name="{name}" type="{kind}">',
        f'    <parent link="{parent}"/>',
        f'    <child link="{child}"/>',
        f'    <origin xyz="{xyz}" rpy="0 0 0"/>',
        f'    <axis xyz="{axis}"/>',
        *([f"    {extra}"] if extra else []),
        "  </joint>",
    ]
    return "\n".join(lines)


def _carriage(name: str, mass: float, inertia: float) -> str:
    """A massless-in-effect carriage link between two prismatic joints."""
    return f'  <link name="{name}">\n{_inertial(mass, inertia, "    ")}  </link>'


def _xml_comment(s: str) -> str:
    """Text safe inside an XML comment (no ``--``)."""
    return str(s).replace("--", "- -")


def write_urdf(specimen: Specimen, path: str | Path, **kwargs) -> Path:
    """Write :func:`urdf_from_specimen` ``(specimen, **kwargs)`` to ``path``.

    Parameters
    ----------
    specimen : Specimen
    path : str or pathlib.Path
        Output file (parent folders are created).
    **kwargs
        Passed to :func:`urdf_from_specimen`.

    Returns
    -------
    pathlib.Path
        The written file.
    """
    path = Path(path)
    text = urdf_from_specimen(specimen, **kwargs)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def write_eth_specimen(path: str | Path = ETH_SPECIMEN_PATH) -> Path:
    """Regenerate the shipped model of the seed specimen (:meth:`Specimen.bachmann2017`) [file]."""
    return write_urdf(Specimen.bachmann2017(), path)
