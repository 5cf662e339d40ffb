"""A specimen from a scan mesh: the equivalent planar rocking block of a real, irregular rock.

:func:`specimen_from_mesh` reads a watertight triangle mesh (metres), computes its mass properties for a
uniform density, finds the facet of its convex hull on which it stands (:func:`mesh_at_rest`, the rock in
its rest frame) and, for one shaking direction, the two pivots of the equivalent planar block: their
distances b from the centre of mass, alpha, R, the inertia about each pivot and p. The result, a
:class:`ScanSpecimen`, gives :class:`~housner.rocking_params.RockingParams` (both sides, with Housner's impact
law for an asymmetric block) and a :class:`~housner.specimen.Specimen`. The derivation step by step, and the
bracket of alpha the scan cannot fix, are in ``docs/reference/campaign-format.md`` ("A specimen from a scan
mesh").

References
----------
Housner, G. W. (1963). The behavior of inverted pendulum structures during earthquakes.
BSSA 53(2), 403-417 (the planar block, the impact law).
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial import ConvexHull, QhullError

from housner._validate import finite, positive
from housner.errors import DataFileError, one_line
from housner.rocking_params import RockingParams, pivot_impact_ratios
from housner.specimen import Specimen
from housner.units import G

__all__ = ["CONTACTS", "PlanarSide", "ScanSpecimen", "footprint_figure", "mesh_at_rest", "specimen_from_mesh"]

#: Contact models: ``"hull"`` or ``"flat:TOL"`` with TOL [m], e.g. ``"flat:0.006"``.
CONTACTS = ("hull", "flat")
#: The contact models whose spread is ``alpha_bracket``: the base is resolved to about 1 cm.
BRACKET_CONTACTS = ("hull", "flat:0.006", "flat:0.0125")
#: Azimuths [deg] of ``alpha_over_azimuth``: 0, 5, ..., 355.
AZIMUTHS = tuple(range(0, 360, 5))

#: Largest plausible extent of a rocking block [m]; above it the mesh is in mm or cm.
_MAX_EXTENT = 20.0
#: Smallest plausible extent [m].
_MIN_EXTENT = 1e-3
#: Largest flat-contact tolerance [m] accepted; more is a unit mistake, not a bedding-in.
_MAX_FLAT_TOL = 0.2
#: Hull vertices within this fraction of the largest extent of the rest plane belong to the rest facet
#: (coplanar faces of a CAD mesh; a scan's neighbouring hull faces differ by 0.1 mm or more).
_COPLANAR_REL = 1e-6
#: Height [m] above the rest plane of the outline that :func:`footprint_figure` draws.
_OUTLINE_HEIGHT = 0.01


@dataclass(frozen=True)
class PlanarSide:
    """One pivot of the equivalent planar block.

    Attributes
    ----------
    b : float
        [m] horizontal distance, along the shaking direction, from the COM to this pivot (> 0).
    h : float
        [m] height of the COM above the contact plane.
    alpha : float
        [rad] atan(b/h).
    R : float
        [m] hypot(b, h).
    I : float
        [kg m^2] inertia about the pivot's axis (horizontal, normal to the shaking direction),
        I_c + m R^2.
    p : float
        [1/s] frequency parameter sqrt(m g R / I).
    """

    b: float
    h: float
    alpha: float
    R: float
    I: float  # noqa: E741 - the physics' name
    p: float

    @classmethod
    def from_geometry(cls, b: float, h: float, centroidal_inertia: float, mass: float) -> PlanarSide:
        """The side of a pivot b [m] from the COM, h [m] below it, for I_c [kg m^2] and m [kg]."""
        R = math.hypot(b, h)
        inertia = centroidal_inertia + mass * R * R
        return cls(b=b, h=h, alpha=math.atan2(b, h), R=R, I=inertia, p=math.sqrt(mass * G * R / inertia))

    def to_dict(self) -> dict:
        """JSON-ready, SI with unit suffixes."""
        return {"b_m": self.b, "h_m": self.h, "alpha_rad": self.alpha, "R_m": self.R, "I_kgm2": self.I, "p_1_s": self.p}


@dataclass(frozen=True)
class ScanSpecimen:
    """The equivalent planar rocking block of a scan mesh for one shaking direction.

    Attributes
    ----------
    name : str
    path : pathlib.Path
        The mesh file.
    mass : float
        [kg] volume * density.
    density : float
        [kg/m^3].
    volume : float
        [m^3].
    com : tuple of float
        (x, y, z) [m] of the centre of mass in mesh coordinates.
    rest_tilt : float
        [rad] tilt of the rest facet's normal from the mesh z axis.
    azimuth : float
        [deg] shaking direction, from the mesh x axis toward +y (counter-clockwise seen from above).
    contact : str
        ``"hull"`` or ``"flat:TOL"`` (TOL [m]).
    centroidal_inertia : float
        I_c [kg m^2] about the horizontal axis through the COM normal to the shaking direction.
    pos, neg : PlanarSide
        The pivot on the +azimuth side (the block rocks on it when theta > 0, leaning toward
        +azimuth) and the one on the -azimuth side.
    footprint : numpy.ndarray
        (k, 2) [m] contact polygon (counter-clockwise) in the horizontal plane, relative to the COM's
        projection, turned so that +x' is the shaking direction.
    alpha_bracket : dict
        {"pos": (lo, hi), "neg": (lo, hi)} [rad]: alpha over the contact models
        :data:`BRACKET_CONTACTS` and this one, at this azimuth: the geometric uncertainty of a
        base resolved to about 1 cm.
    alpha_over_azimuth : tuple of float
        (min, max) [rad] of min(alpha+, alpha-) over :data:`AZIMUTHS` with this contact: the
        orientation on a shaking table is often undocumented.
    """

    name: str
    path: Path
    mass: float
    density: float
    volume: float
    com: tuple
    rest_tilt: float
    azimuth: float
    contact: str
    centroidal_inertia: float
    pos: PlanarSide
    neg: PlanarSide
    footprint: np.ndarray = field(repr=False, compare=False)
    alpha_bracket: dict
    alpha_over_azimuth: tuple
    # For footprint_figure: the contact polygons of BRACKET_CONTACTS, and the mesh's outline
    # _OUTLINE_HEIGHT above the rest plane as segments (n, 2, 2), both in the footprint's frame [m].
    _polygons: dict = field(default_factory=dict, repr=False, compare=False)
    _outline: np.ndarray = field(default_factory=lambda: np.empty((0, 2, 2)), repr=False, compare=False)
    # [m] the mesh's extent normal to the shaking direction (Specimen.depth).
    _depth: float = field(default=0.0, repr=False, compare=False)

    @property
    def h(self) -> float:
        """Height of the COM above the rest plane [m]."""
        return self.pos.h

    def impact_ratios(self) -> tuple[float, float]:
        """Angular-velocity ratios [-] of the two impacts under Housner's law (rho+-, rho-+).

        Angular momentum about the landing pivot is conserved, as in
        :func:`housner.effects.asymmetric_impact_ratios`: with
        I+- = I_c + m (h^2 + b+-^2), theta'_after / theta'_before =
        (I_c + m (h^2 - b+ b-)) / I_landing. rho+- ends rocking on the + pivot and lands on the
        - pivot; rho-+ the reverse.
        """
        return pivot_impact_ratios(self.pos.b, self.neg.b, self.h, self.centroidal_inertia, self.mass)

    def rocking_params(self, r: float | None = None) -> RockingParams:
        """The parameters of the rocking equation: alpha and p per side, and the impact law.

        Parameters
        ----------
        r : float, optional
            Kinetic-energy ratio at impact [-], in [0, 1]. None (default): Housner's law for this
            asymmetric block, r_neg = rho+-^2 (lands on the - pivot), r_pos = rho-+^2 and r their
            geometric mean (:meth:`impact_ratios`), as
            :class:`housner.effects.AsymmetricPivots` sets them. Given: those per-side ratios
            rescaled to the geometric mean r (:meth:`RockingParams.with_r`), keeping their split.

        Returns
        -------
        RockingParams
        """
        params = RockingParams.from_pivots(self.pos.b, self.neg.b, self.h, self.centroidal_inertia, self.mass)
        return params if r is None else params.with_r(r)

    def specimen(self) -> Specimen:
        """A :class:`~housner.specimen.Specimen` for code that needs one (symmetric: its B is the mean b).

        height = 2h, width = b+ + b-, depth = the mesh's extent normal to the shaking direction,
        I0 = I_c + m (h^2 + ((b+ + b-)/2)^2), so that its centroidal inertia is I_c. The
        asymmetry is lost: use :meth:`rocking_params` for both sides (or the effect
        ``asymmetric_pivots`` with e = (b- - b+)/2).
        """
        half = 0.5 * (self.pos.b + self.neg.b)
        return Specimen(
            height=2.0 * self.h,
            width=2.0 * half,
            depth=self._depth,
            mass=self.mass,
            I0=self.centroidal_inertia + self.mass * (self.h**2 + half**2),
            name=self.name,
        )

    def to_dict(self) -> dict:
        """JSON-ready description, SI with unit suffixes."""
        params = self.rocking_params()
        return {
            "name": self.name,
            "path": str(self.path),
            "mass_kg": self.mass,
            "density_kg_m3": self.density,
            "volume_m3": self.volume,
            "com_m": list(self.com),
            "com_height_m": self.h,
            "rest_tilt_rad": self.rest_tilt,
            "azimuth_deg": self.azimuth,
            "contact": self.contact,
            "centroidal_inertia_kgm2": self.centroidal_inertia,
            "depth_m": self._depth,
            "pos": self.pos.to_dict(),
            "neg": self.neg.to_dict(),
            "r_housner": {"r": params.r, "r_pos": params.r_pos, "r_neg": params.r_neg},
            "alpha_bracket_rad": {side: list(v) for side, v in self.alpha_bracket.items()},
            "alpha_bracket_contacts": sorted(set(BRACKET_CONTACTS) | {self.contact}),
            "alpha_over_azimuth_rad": list(self.alpha_over_azimuth),
            "azimuths_deg": [AZIMUTHS[0], AZIMUTHS[-1], AZIMUTHS[1] - AZIMUTHS[0]],
            "footprint_m": self.footprint.tolist(),
        }


def specimen_from_mesh(
    path: str | Path,
    *,
    azimuth: float = 0.0,
    contact: str = "hull",
    density: float = 2700.0,
    name: str | None = None,
) -> ScanSpecimen:
    """The equivalent planar rocking block of a watertight scan mesh (``docs/reference/campaign-format.md``).

    Parameters
    ----------
    path : str or pathlib.Path
        Triangle mesh in metres, mesh z up (any format trimesh reads: OBJ, STL, PLY, ...).
    azimuth : float
        Shaking direction [deg] in [0, 360), from the mesh x axis toward +y.
    contact : str
        ``"hull"`` (the rest facet of the convex hull) or ``"flat:TOL"``, TOL [m] in (0, 0.2].
    density : float
        Uniform density [kg/m^3].
    name : str, optional
        Free text for reports; default the file's stem.

    Returns
    -------
    ScanSpecimen

    Raises
    ------
    ValueError
        A bad argument (the message names it), or the COM outside the contact along ``azimuth``.
    housner.errors.DataFileError
        The file is missing, not a mesh, not watertight, or not in metres.
    """
    az = finite("azimuth", azimuth)
    if not 0.0 <= az < 360.0:
        raise ValueError(f"`azimuth` must lie in [0, 360) deg, got {azimuth!r}")
    contact = _normal_contact(contact)
    rho = positive("density", density)
    path = Path(path)
    return _specimen(mesh_at_rest(path, rho), path, az, contact, rho, path.stem if name is None else str(name))


def _normal_contact(contact) -> str:
    """``contact`` checked and written plainly ("hull" or "flat:TOL"), else ValueError naming it."""
    usage = "`contact` must be 'hull' or 'flat:TOL' with TOL > 0 in metres (e.g. 'flat:0.006')"
    if not isinstance(contact, str):
        raise ValueError(f"{usage}, got {contact!r}")
    kind, sep, tol = contact.strip().partition(":")
    if kind not in CONTACTS or (kind == "hull" and sep):
        close = difflib.get_close_matches(kind, CONTACTS, n=1)
        hint = f"; did you mean {close[0]!r}?" if close and close[0] != kind else ""
        raise ValueError(f"{usage}, got {contact!r}{hint}")
    if kind == "hull":
        return "hull"
    try:
        t = float(tol)
    except ValueError:
        t = math.nan
    if not (math.isfinite(t) and t > 0.0):
        raise ValueError(f"{usage}, got {contact!r}")
    if t > _MAX_FLAT_TOL:
        raise ValueError(
            f"`contact` tolerance {t:g} m is implausible (above {_MAX_FLAT_TOL:g} m): TOL is in metres, "
            f"e.g. 'flat:{t / 1000:g}' for {t:g} mm"
        )
    return f"flat:{t!r}"  # shortest exact form: _flat_tol reads it back


def _flat_tol(contact: str) -> float | None:
    """TOL [m] of a checked ``"flat:TOL"``, None for ``"hull"``."""
    return None if contact == "hull" else float(contact.partition(":")[2])


def _load(path: Path) -> trimesh.Trimesh:
    """The mesh at ``path``, watertight, in metres, with outward normals; else DataFileError."""
    if not path.exists():
        raise DataFileError(path, "no such file")
    if path.is_dir():
        raise DataFileError(path, "is a directory, not a mesh file")
    try:
        mesh = trimesh.load(path, force="mesh")
    except Exception as e:  # trimesh raises many types for unreadable input
        raise DataFileError(path, f"cannot be read as a mesh: {one_line(e)}") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise DataFileError(path, "holds no triangle faces: not a mesh")
    if not np.isfinite(mesh.vertices).all():
        raise DataFileError(path, "has vertices that are not finite")
    if not mesh.is_watertight:
        n_open = len(trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1))
        what = f"{n_open} open edges" if n_open else "edges shared by more than two faces"
        raise DataFileError(path, f"mesh is not watertight ({what}): a volume needs a closed surface")
    if not mesh.is_winding_consistent:
        raise DataFileError(path, "mesh faces are not wound consistently: its volume is undefined")
    ext = mesh.extents
    if ext.max() > _MAX_EXTENT:
        unit = "millimetres" if ext.max() > 10 * _MAX_EXTENT else "centimetres or millimetres"
        raise DataFileError(path, f"looks like {unit} (extent {ext.max():.4g} m): convert to metres")
    if ext.min() < _MIN_EXTENT:
        raise DataFileError(path, f"smallest extent {ext.min():.3g} m is below 1 mm: flat, or not in metres")
    if mesh.volume < 0.0:
        mesh.invert()  # inward normals (SP1.obj): the same surface, outward
    return mesh


@dataclass(frozen=True)
class MeshAtRest:
    """A mesh at rest: mass properties and geometry in the rest frame (origin at the COM, z up)."""

    volume: float
    mass: float
    com: np.ndarray  # [m] mesh coordinates
    inertia: np.ndarray  # (3, 3) [kg m^2] about the COM, rest-frame axes
    h: float  # [m]
    tilt: float  # [rad]
    vertices: np.ndarray  # (n, 3) [m] rest frame
    hull_vertices: np.ndarray  # (k, 3) [m] rest frame
    faces: np.ndarray


def mesh_at_rest(path: str | Path, density: float) -> MeshAtRest:
    """The scan mesh at ``path`` standing on its rest facet, of uniform ``density`` [kg/m^3]: its mass properties
    and geometry in the rest frame (steps 1-4 of docs/reference/campaign-format.md, "A specimen from a scan mesh"),
    the frame :func:`specimen_from_mesh` works in. A bad ``density`` is a ValueError naming it; a file that is
    missing, not a mesh, not watertight or not in metres a :class:`housner.errors.DataFileError`."""
    density = positive("density", density)
    path = Path(path)
    mesh = _load(path)
    # Scan coordinates carry arbitrary offsets (SP1: z near 312 m): work near the origin.
    shift = mesh.bounds.mean(axis=0)
    mesh = mesh.copy()
    mesh.apply_translation(-shift)
    mesh.density = density
    mass = float(mesh.mass)
    com = np.asarray(mesh.center_mass, dtype=float)
    inertia = np.asarray(mesh.moment_inertia, dtype=float)  # about the COM, mesh axes
    hull = mesh.convex_hull
    normal, point = _rest_facet(hull, com, path)
    rot = _rotation_onto(normal, np.array([0.0, 0.0, -1.0]))
    verts = (mesh.vertices - com) @ rot.T
    hull_verts = (hull.vertices - com) @ rot.T
    h = float(np.dot(com - point, -normal))  # the COM's distance above the facet plane
    return MeshAtRest(
        volume=float(mesh.volume),
        mass=mass,
        com=com + shift,
        inertia=rot @ inertia @ rot.T,
        h=h,
        tilt=float(math.atan2(math.hypot(normal[0], normal[1]), -normal[2])),  # acos is ill-conditioned near 0
        vertices=verts,
        hull_vertices=hull_verts,
        faces=np.asarray(mesh.faces),
    )


def _rest_facet(hull: trimesh.Trimesh, com: np.ndarray, path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(outward normal, a point) of the hull face under the COM whose normal is closest to -z."""
    tri = hull.triangles[:, :, :2] - com[:2]
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]

    def cross(u, v):
        return u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]

    # The origin (the COM's projection) is inside a triangle when it is on the same side of its three edges.
    area = cross(b - a, c - a)
    s = np.stack([cross(b - a, -a), cross(c - b, -b), cross(a - c, -c)], axis=1) * np.sign(area)[:, None]
    eps = 1e-12 * np.abs(area)[:, None]
    normals = hull.face_normals
    under = (s >= -eps).all(axis=1) & (normals[:, 2] < 0.0) & (area != 0.0)
    if not under.any():
        raise DataFileError(path, "no convex-hull facet lies under the centre of mass: is mesh z up?")
    i = np.flatnonzero(under)[np.argmin(normals[under, 2])]
    return normals[i], hull.triangles[i, 0]


def _rotation_onto(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation taking unit vector ``a`` onto unit vector ``b`` (Rodrigues)."""
    v = np.cross(a, b)
    s = float(np.linalg.norm(v))
    c = float(np.dot(a, b))
    if s < 1e-15:
        return np.eye(3)  # a == b: facets under the COM point down, never up
    k = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + k + k @ k * ((1.0 - c) / (s * s))


def _contact_points(rest: MeshAtRest, contact: str) -> np.ndarray:
    """(k, 2) [m] rest-frame vertices of the contact polygon (counter-clockwise), relative to the COM."""
    tol = _flat_tol(contact)
    if tol is None:
        scale = float(np.ptp(rest.vertices, axis=0).max())
        pts = rest.hull_vertices[rest.hull_vertices[:, 2] + rest.h <= _COPLANAR_REL * scale]
    else:
        pts = rest.vertices[rest.vertices[:, 2] + rest.h <= tol]
    pts = pts[:, :2]
    try:
        return pts[ConvexHull(pts).vertices]
    except (QhullError, ValueError):  # fewer than 3 points, or all on a line
        raise ValueError(f"the contact {contact!r} touches the rest plane along a line or a point") from None


def _turn(points: np.ndarray, azimuth: float) -> np.ndarray:
    """Rest-frame (.., 2) points in the shaking frame: +x' along the azimuth [deg]."""
    c, s = math.cos(math.radians(azimuth)), math.sin(math.radians(azimuth))
    return points @ np.array([[c, -s], [s, c]])


def _alphas(poly: np.ndarray, h: float, azimuths) -> tuple[np.ndarray, np.ndarray]:
    """alpha+ and alpha- [rad] of contact polygon ``poly`` (rest frame) at ``azimuths`` [deg]."""
    az = np.radians(np.asarray(azimuths, dtype=float))
    proj = poly @ np.stack([np.cos(az), np.sin(az)])
    return np.arctan2(proj.max(axis=0), h), np.arctan2(-proj.min(axis=0), h)


def _outline(rest: MeshAtRest, azimuth: float) -> np.ndarray:
    """Segments (n, 2, 2) [m] of the mesh's section _OUTLINE_HEIGHT above the rest plane, shaking frame."""
    cut = trimesh.intersections.mesh_plane(
        trimesh.Trimesh(rest.vertices, rest.faces, process=False),
        plane_normal=[0.0, 0.0, 1.0],
        plane_origin=[0.0, 0.0, _OUTLINE_HEIGHT - rest.h],
    )
    return _turn(np.asarray(cut)[:, :, :2], azimuth) if len(cut) else np.empty((0, 2, 2))


def _specimen(rest: MeshAtRest, path: Path, az: float, contact: str, density: float, name: str) -> ScanSpecimen:
    contacts = dict.fromkeys((*BRACKET_CONTACTS, contact))
    polys = {c: _contact_points(rest, c) for c in contacts}
    poly = polys[contact]
    proj = poly @ np.array([math.cos(math.radians(az)), math.sin(math.radians(az))])
    b_pos, b_neg = float(proj.max()), float(-proj.min())
    if b_pos <= 0.0 or b_neg <= 0.0:
        raise ValueError(
            f"the centre of mass lies outside the contact {contact!r} along azimuth {az:g} deg "
            f"(b+ = {b_pos:.4g} m, b- = {b_neg:.4g} m): the block cannot stand so"
        )
    az_r = math.radians(az)
    axis = np.array([-math.sin(az_r), math.cos(az_r), 0.0])  # the rocking axis
    ic = float(axis @ rest.inertia @ axis)
    across = rest.vertices[:, :2] @ axis[:2]
    bracket = np.array([_alphas(p, rest.h, [az]) for p in polys.values()])[:, :, 0]  # (contact, side)
    a_pos, a_neg = _alphas(poly, rest.h, AZIMUTHS)
    return ScanSpecimen(
        name=name,
        path=path,
        mass=rest.mass,
        density=density,
        volume=rest.volume,
        com=tuple(float(x) for x in rest.com),
        rest_tilt=rest.tilt,
        azimuth=az,
        contact=contact,
        centroidal_inertia=ic,
        pos=PlanarSide.from_geometry(b_pos, rest.h, ic, rest.mass),
        neg=PlanarSide.from_geometry(b_neg, rest.h, ic, rest.mass),
        footprint=_turn(poly, az),
        alpha_bracket={
            "pos": (float(bracket[:, 0].min()), float(bracket[:, 0].max())),
            "neg": (float(bracket[:, 1].min()), float(bracket[:, 1].max())),
        },
        alpha_over_azimuth=(float(np.minimum(a_pos, a_neg).min()), float(np.minimum(a_pos, a_neg).max())),
        _polygons={c: _turn(p, az) for c, p in polys.items()},
        _outline=_outline(rest, az),
        _depth=float(np.ptp(across)),
    )


def footprint_figure(scan: ScanSpecimen, path: str | Path) -> Path:
    """Draw the footprint of ``scan`` to a PNG file.

    The contact polygons flat:0.006 and hull (and the scan's own, when another), the mesh's
    outline 1 cm above the rest plane, the COM's projection, the two pivots (alpha+- in the
    legend) and the shaking direction, in the shaking frame (+x' along the azimuth) [m].

    Parameters
    ----------
    scan : ScanSpecimen
    path : str or pathlib.Path
        The PNG file to write.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure

    if not isinstance(scan, ScanSpecimen):
        raise TypeError(f"`scan` must be a ScanSpecimen, got {type(scan).__name__}")
    path = Path(path)
    fig = Figure(figsize=(6.5, 5.5), layout="constrained")
    ax = fig.add_subplot()
    if len(scan._outline):
        ax.add_collection(
            LineCollection(scan._outline, colors="0.6", lw=0.7, label=f"mesh {_OUTLINE_HEIGHT * 100:g} cm above rest")
        )
    styles = {"flat:0.006": ("tab:blue", "-"), "hull": ("tab:red", "--")}
    for contact in dict.fromkeys(("flat:0.006", "hull", scan.contact)):
        poly = scan._polygons.get(contact, scan.footprint if contact == scan.contact else None)
        if poly is None:
            continue
        color, ls = styles.get(contact, ("tab:green", "-"))
        closed = np.vstack([poly, poly[:1]])
        own = " (this specimen)" if contact == scan.contact else ""
        ax.plot(closed[:, 0], closed[:, 1], color=color, ls=ls, lw=2.0 if own else 1.2, label=f"contact {contact}{own}")
    ax.plot([0.0], [0.0], "k+", ms=12, mew=2, label="centre of mass")
    ax.plot(
        [scan.pos.b],
        [0.0],
        "o",
        color="tab:orange",
        label=f"pivot +: b = {scan.pos.b:.4f} m, alpha+ = {scan.pos.alpha:.4f} rad",
    )
    ax.plot(
        [-scan.neg.b],
        [0.0],
        "s",
        color="tab:purple",
        label=f"pivot -: b = {scan.neg.b:.4f} m, alpha- = {scan.neg.alpha:.4f} rad",
    )
    # The shaking direction: an arrow under the drawing, along +x'.
    drawn = [scan.footprint, *scan._polygons.values(), scan._outline.reshape(-1, 2)]
    ys = np.concatenate([d[:, 1] for d in drawn if len(d)])
    xs = np.concatenate([d[:, 0] for d in drawn if len(d)])
    y = ys.min() - 0.14 * np.ptp(ys)
    half = 0.25 * np.ptp(xs)
    ax.annotate("", xy=(half, y), xytext=(-half, y), arrowprops={"arrowstyle": "->", "lw": 1.5})
    ax.text(0.0, y, f"shaking direction: azimuth {scan.azimuth:g} deg\n", ha="center", va="bottom", fontsize="small")
    ax.update_datalim([(-half, y - 0.03 * np.ptp(ys)), (half, y)])  # annotations do not widen the axes
    ax.set_aspect("equal", adjustable="datalim")
    ax.autoscale_view()
    ax.set_xlabel("x' along the shaking direction [m]")
    ax.set_ylabel("y' [m]")
    ax.set_title(f"{scan.name}: footprint, COM {scan.h:.4f} m above the rest plane")
    ax.grid(True, lw=0.3)
    ax.legend(loc="upper left", fontsize="x-small")
    fig.savefig(path, dpi=120)
    return path
