"""``housner tune ENGINE``: search an engine's contact settings for a target kinetic-energy ratio r in free
vibration (its parser and its run)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from housner.cli.args import amplitudes, ratio
from housner.cli.command import add_command
from housner.engines.base import get_engine
from housner.scenarios.catalogue.scenario import load_scenario
from housner.scenarios.execution.outputs import check_output_file
from housner.specimen import Specimen

SUMMARY = "search engine contact settings that reproduce a target r in free vibration"


def add_parser(sub, names: dict) -> argparse.ArgumentParser:
    """The ``tune`` subcommand's arguments; ``names`` are the registries' names for the help texts."""
    t = add_command(sub, "tune", SUMMARY, run, epilog=f"engines: {names['engines']}")
    t.add_argument("engine", help=f"engine name ({names['engines']})")
    t.add_argument(
        "--r",
        "--target-r",
        dest="target_r",
        type=ratio,
        help="kinetic-energy ratio to reach, e.g. a measured one (default: the specimen's Housner r)",
    )
    t.add_argument(
        "--amplitudes", type=amplitudes, help="release amplitudes theta0/alpha, comma-separated (default 0.2..0.9)"
    )
    t.add_argument("--scenario", help="take the specimen from this scenario (default: the seed specimen)")
    t.add_argument(
        "--json", help="write the tuning result to this JSON file (the report reads engines/models/tuning-ENGINE.json)"
    )
    t.add_argument("--figure", help="write the figure of r against release amplitude to this file (PNG, SVG, PDF)")
    t.add_argument(
        "--defaults-only",
        action="store_true",
        help="only measure the engine's current default settings (r against amplitude, cost)",
    )
    t.add_argument("-q", "--quiet", action="store_true")
    return t


def run(args: argparse.Namespace) -> int:
    """Tune the engine (or measure its defaults), print the result, write the files asked for.

    Returns the exit status: 0 when the target is met, else 1.
    """
    from housner.engines.tuning import tune  # each command imports its own layers: `housner run` starts faster
    from housner.reports.tuning_figure import tuning_report_figure

    specimen = Specimen.bachmann2017()
    if args.scenario:
        specimen = load_scenario(args.scenario).specimen
    if args.json:
        check_output_file(args.json, "--json")
    amps = args.amplitudes
    kwargs = {"target_r": args.target_r, "progress": not args.quiet}
    if amps:
        kwargs["amplitudes"] = amps
    if args.defaults_only:
        kwargs["candidates"] = [get_engine(args.engine).settings()]
    if args.figure:
        check_output_file(args.figure, "--figure")
    result = tune(args.engine, specimen, **kwargs)
    print(result.summary())
    _print_best_candidates(result)
    if args.json:
        Path(args.json).write_text(json.dumps(result.to_json(), indent=2, default=str))
        print(f"written: {args.json}")
    if args.figure:
        tuning_report_figure(result).savefig(args.figure)
        print(f"written: {args.figure}")
    return 0 if result.met else 1


def _print_best_candidates(result, n: int = 10) -> None:
    """The n best candidates of a tuning by score (largest error over its tolerance; <= 1 passes)."""
    import pandas as pd

    if len(result.candidates) < 2:
        return
    cols = [
        "settings",
        "score",
        "worst_rel_error",
        "small_worst_rel_error",
        "small_mean_rel_error",
        "decay_rel_error",
        "pulse_rel_error",
        "cost_per_sim_second",
        "met",
    ]
    best = result.candidates.sort_values(["score", "cost_per_sim_second"]).head(n)
    print(f"\nbest {len(best)} candidates by score (largest error over its tolerance; <= 1 passes):")
    with pd.option_context("display.width", 250, "display.max_colwidth", 120):
        print(best[[c for c in cols if c in best.columns]].to_string())
