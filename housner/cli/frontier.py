"""``housner frontier ENGINE``: an engine's accuracy against its cost over its time step and contact setting,
and the knee (its parser and its run)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from housner.cli.args import EXIT_OK, UsageError
from housner.cli.command import add_engine_command, add_engine_command_tail, engine_scenario, engine_work
from housner.scenarios.execution.outputs import check_output_file

SUMMARY = "sweep an engine's time step and contact setting: accuracy against cost, and the knee"
DESCRIPTION = (
    "Sweep an engine's time step and its main contact setting (the axes its class declares), and measure at "
    "each point the tuner's checks, per-record agreement and KS against the analytic model on a scenario's "
    "ground motions, the extended floor and the CPU time; mark the knee, where accuracy stops improving."
)


def add_parser(sub, names: dict) -> argparse.ArgumentParser:
    """The ``frontier`` subcommand's arguments; ``names`` are the registries' names for the help texts."""
    f = add_engine_command(sub, "frontier", SUMMARY, run, names, "sweep", DESCRIPTION)
    f.add_argument(
        "--json", help="write the frontier to this JSON file (the run report reads engines/models/frontier-ENGINE.json)"
    )
    f.add_argument("--figure", help="write the frontier's figure to this image file")
    add_engine_command_tail(f)
    return f


def run(args: argparse.Namespace) -> int:
    """Sweep the engine on the scenario; print the frontier, write the JSON and the figure asked for. Returns
    the exit status."""
    from housner.reports.frontier_figure import frontier_figure
    from housner.scenarios.runs.frontier import engine_frontier, frontier_axes

    # inputs and outputs checked before the work: engine, scenario, options, files
    if args.engine == "housner":
        raise UsageError(
            "argument ENGINE: 'housner' is the reference the frontier is measured against; name another engine"
        )
    try:
        frontier_axes(args.engine)
    except ValueError as e:
        raise UsageError(f"argument ENGINE: {e}") from None
    scenario = engine_scenario(args, "measure a frontier on")
    for opt, path in (("--json", args.json), ("--figure", args.figure)):
        if path:
            check_output_file(path, opt)
    fr = engine_frontier(args.engine, scenario, **engine_work(args, scenario, "frontier of", "ground motions"))
    print(fr.summary())
    print(f"wall time {fr.wall_s:.1f} s")
    if args.json:
        Path(args.json).write_text(json.dumps(fr.to_dict(), indent=2))
        print(f"json:   {args.json}")
    if args.figure:
        frontier_figure(fr).savefig(args.figure)
        print(f"figure: {args.figure}")
    return EXIT_OK
