"""``housner campaign from-asu DATA OUT``: measured campaigns from other projects' files (its parser and its run)."""

from __future__ import annotations

import argparse
import math
import sys

from housner.cli.args import UsageError, float_within

SUMMARY = "write a campaign from another project's measured data (from-asu: the ASU granite shake-table tests)"

_FROM_ASU = "write the ASU granite shake-table tests (2021) of one specimen as a campaign directory"
_FROM_ASU_EPILOG = """\
DATA holds index.csv and either asu_granite_200hz.npz (the compact data set) or the original
Test###.txt files (800 Hz; here or in data/Shake_Table_Response/), which are processed as the data
set's README says. OUT gets campaign.toml, a copy of the mesh and records/Test###.csv (200 Hz,
m/s^2). OUT must be new, empty, or a previous import (then replaced whole). A test without an
outcome, without its file or with a malformed file is left out, with one line saying why.

example:
  housner campaign from-asu /data/asu-granite asu-sp1
  housner campaign from-asu /data/asu-granite asu-sp1-y --azimuth 90 --contact flat:0.006"""


def add_parser(sub) -> argparse.ArgumentParser:
    """The ``campaign`` subcommand and its own subcommands."""
    p = sub.add_parser("campaign", help=SUMMARY, description=SUMMARY)
    p.set_defaults(func=run)
    inner = p.add_subparsers(dest="campaign_cmd", metavar="{from-asu}")
    a = inner.add_parser(
        "from-asu",
        help=_FROM_ASU,
        description=_FROM_ASU,
        epilog=_FROM_ASU_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    a.add_argument("data", metavar="DATA", help="the data folder (index.csv with the npz or the Test###.txt files)")
    a.add_argument("out", metavar="OUT", help="the campaign directory to write")
    a.add_argument("--specimen", default="SP1", metavar="NAME", help="the specimen, SP1 or SP2 (default SP1)")
    a.add_argument("--flags", metavar="COLUMN", help="index.csv's outcome column (default overturn_<specimen>)")
    a.add_argument("--mesh", metavar="FILE", help="the specimen's scan mesh [m] (default DATA/<specimen>.obj)")
    # the range, [0, 360), is checked by housner.scan.specimen_from_mesh, with the mesh
    a.add_argument(
        "--azimuth",
        type=float_within(math.isfinite, "a number of degrees"),
        default=0.0,
        metavar="DEG",
        help="shaking direction from the mesh x axis [deg], in [0, 360) (default 0)",
    )
    a.add_argument(
        "--contact",
        default="hull",
        metavar="hull|flat:TOL",
        help="the contact polygon: the hull's rest facet, or the vertices within TOL [m] of it",
    )
    return p


def run(args: argparse.Namespace) -> int:
    """Run ``housner campaign <subcommand>``; exit status 0, or an error raised as one line."""
    if getattr(args, "campaign_cmd", None) != "from-asu":
        raise UsageError("`housner campaign` needs a subcommand: from-asu (see `housner campaign --help`)")
    from housner.scenarios.campaigns.asu import import_asu

    result = import_asu(
        args.data,
        args.out,
        specimen=args.specimen,
        flags=args.flags,
        mesh=args.mesh,
        azimuth=args.azimuth,
        contact=args.contact,
        progress=lambda line: print(f"housner: {line}", file=sys.stderr),
    )
    print(result.summary)
    return 0
