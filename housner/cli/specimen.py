"""``housner specimen MESH``: the equivalent planar rocking block of a scan mesh (its parser and its run)."""

from __future__ import annotations

import argparse
import json
import math
from dataclasses import dataclass

from housner._values import JsonValue
from housner.scenarios.execution.outputs import check_output_file

SUMMARY = "the equivalent planar rocking block of a scan mesh: alpha, R, I and p on each side, and its footprint"


@dataclass(frozen=True, eq=False)
class SideFacts(JsonValue):
    """One pivot of the planar block (:class:`housner.scan.PlanarSide`) as the specimen JSON holds it: its distance
    from the centre of mass [m], the centre of mass's height [m], alpha [rad], R [m], I [kg m^2] and p [1/s]."""

    b_m: float
    h_m: float
    alpha_rad: float
    R_m: float
    I_kgm2: float
    p_1_s: float


@dataclass(frozen=True, eq=False)
class HousnerRatios(JsonValue):
    """Housner's kinetic-energy ratios of the asymmetric block [-]: ``r_pos`` (lands on the + pivot), ``r_neg``
    (lands on the - pivot) and their geometric mean ``r``."""

    r: float
    r_pos: float
    r_neg: float


@dataclass(frozen=True, eq=False)
class SpecimenFacts(JsonValue):
    """The specimen JSON (``--json``): :meth:`housner.scan.ScanSpecimen.to_dict`, one field per key (SI units named
    in the keys): the mesh, its mass properties, the shaking direction and contact, the two pivots, Housner's
    ratios, alpha over the contacts and the azimuths, the footprint."""

    name: str
    path: str
    mass_kg: float
    density_kg_m3: float
    volume_m3: float
    com_m: tuple[float, ...]
    com_height_m: float
    rest_tilt_rad: float
    azimuth_deg: float
    contact: str
    centroidal_inertia_kgm2: float
    depth_m: float
    pos: SideFacts
    neg: SideFacts
    r_housner: HousnerRatios
    alpha_bracket_rad: dict[str, tuple[float, ...]]
    alpha_bracket_contacts: tuple[str, ...]
    alpha_over_azimuth_rad: tuple[float, ...]
    azimuths_deg: tuple[float, ...]
    footprint_m: tuple[tuple[float, ...], ...]


def add_parser(sub) -> argparse.ArgumentParser:
    """The ``specimen`` subcommand's arguments."""
    p = sub.add_parser(
        "specimen",
        help=SUMMARY,
        description=SUMMARY + ". The mesh is watertight, in metres, with z up; see housner.scan.",
    )
    p.add_argument("mesh", help="watertight triangle mesh in metres, z up (OBJ, STL, PLY, ...)")
    p.add_argument(
        "--azimuth",
        type=float,
        required=True,
        metavar="DEG",
        help="shaking direction [deg] in [0, 360), from the mesh x axis toward +y",
    )
    p.add_argument(
        "--contact",
        default="hull",
        metavar="hull|flat:TOL",
        help="contact polygon: the rest facet of the convex hull (hull, default) or the hull of the "
        "vertices within TOL metres of the rest plane (e.g. flat:0.006)",
    )
    p.add_argument("--density", type=float, default=2700.0, metavar="KG_M3", help="uniform density (default 2700)")
    p.add_argument("--json", metavar="FILE", help="write the specimen as JSON (SI, unit suffixes)")
    p.add_argument("--figure", metavar="FILE", help="draw the footprint, pivots and shaking direction to a PNG")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    """Print the planar block's table; write the JSON and the figure when asked. Returns the exit status."""
    # Output paths are checked before the mesh is read; bad arguments raise ValueError before it too.
    json_path = check_output_file(args.json, "--json") if args.json else None
    figure_path = check_output_file(args.figure, "--figure") if args.figure else None
    from housner.scan import footprint_figure, specimen_from_mesh  # lazy: trimesh loads only for this command

    scan = specimen_from_mesh(args.mesh, azimuth=args.azimuth, contact=args.contact, density=args.density)
    print(_table(scan))
    if json_path is not None:
        facts = SpecimenFacts.from_json(scan.to_dict())
        json_path.write_text(json.dumps(facts.to_json(), indent=1) + "\n")
        print(f"wrote {json_path}")
    if figure_path is not None:
        footprint_figure(scan, figure_path)
        print(f"wrote {figure_path}")
    return 0


def _table(scan) -> str:
    """The specimen's summary: mass, COM height, one row per pivot, the alpha ranges."""
    params = scan.rocking_params()
    lo, hi = scan.alpha_over_azimuth
    lines = [
        f"{scan.name}: mass {scan.mass:.2f} kg (density {scan.density:g} kg/m^3, volume {scan.volume:.5f} m^3), "
        f"COM {scan.h:.4f} m above the rest facet (tilted {math.degrees(scan.rest_tilt):.2f} deg from mesh z)",
        f"shaking azimuth {scan.azimuth:g} deg, contact {scan.contact}, "
        f"I_c {scan.centroidal_inertia:.3f} kg m^2 about the rocking axis",
        f"{'side':5s} {'b [m]':>7s} {'alpha [rad]':>11s} {'R [m]':>7s} {'I [kg m^2]':>10s} {'p [1/s]':>7s}  "
        "alpha over contacts hull, flat:0.006, flat:0.0125 [rad]",
    ]
    for side in ("pos", "neg"):
        s = getattr(scan, side)
        a, b = scan.alpha_bracket[side]
        lines.append(f"{side:5s} {s.b:7.4f} {s.alpha:11.4f} {s.R:7.4f} {s.I:10.3f} {s.p:7.4f}  {a:.4f} .. {b:.4f}")
    lines.append(f"min(alpha+, alpha-) over azimuths 0..355 deg: {lo:.4f} .. {hi:.4f} rad")
    lines.append(
        f"Housner impacts: r_pos {params.r_pos:.4f} (lands on +), r_neg {params.r_neg:.4f} (lands on -), "
        f"r {params.r:.4f}"
    )
    return "\n".join(lines)
