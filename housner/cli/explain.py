"""``housner explain ENGINE``: an engine's own responses diagnosed as a measurement campaign (its parser and its
run)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from housner.cli.args import EXIT_OK, UsageError, check_effects, float_within, names_arg, nonneg_int
from housner.cli.command import add_engine_command, add_engine_command_tail, engine_scenario, engine_work, plugin_option
from housner.scenarios.execution.outputs import check_output_dir, check_output_file
from housner.scenarios.runs.explain import EXPLAIN_SIGMA

SUMMARY = "diagnose an engine's own responses as a campaign: the effects that bring Housner to it, the floor"
DESCRIPTION = (
    "Run an engine on a scenario's ground motions and on free vibrations, diagnose its responses like a "
    "measurement campaign, and compare the analytic model with the effects found against the engine, record "
    "by record, beside the floor a correct model could reach."
)

_noise_rad = float_within(lambda x: math.isfinite(x) and x >= 0.0, "a noise level >= 0 [rad]")


def add_parser(sub, names: dict) -> argparse.ArgumentParser:
    """The ``explain`` subcommand's arguments; ``names`` are the registries' names for the help texts."""
    e = add_engine_command(sub, "explain", SUMMARY, run, names, "explain", DESCRIPTION)
    e.add_argument(
        "--sigma",
        type=_noise_rad,
        default=EXPLAIN_SIGMA,
        help=f"noise added to the engine's theta before the diagnosis [rad] (default {EXPLAIN_SIGMA:g})",
    )
    e.add_argument("--seed", type=nonneg_int, default=0, help="seed of the noise and of the diagnosis' folds (0)")
    e.add_argument(
        "--effects",
        type=names_arg,
        help=f"candidate effects, comma-separated, or 'none' (default: all): {names['effects']}",
    )
    e.add_argument("--json", help="write the explanation to this JSON file")
    e.add_argument("--workdir", help="keep the engine's campaign in WORKDIR/ENGINE-SCENARIO (default: a temporary one)")
    e.add_argument(
        "--no-maps",
        action="store_true",
        help="skip measuring the engine's impact and flight maps and running Housner + those maps",
    )
    e.add_argument("--figure", help="write the figure of the engine's impact and flight maps to this file (PNG, SVG)")
    plugin_option(e)
    add_engine_command_tail(e)
    return e


def run(args: argparse.Namespace) -> int:
    """Explain the engine on the scenario; print the explanation, write the JSON asked for. Returns the exit
    status."""
    from housner.scenarios.runs.explain import explain_engine

    # inputs and outputs checked before the work: scenario, engine, options, files
    scenario = engine_scenario(args, "explain an engine on")
    check_effects(args.effects, "--effects")
    if args.json:
        check_output_file(args.json, "--json")
    if args.workdir:
        check_output_dir(Path(args.workdir), "--workdir")
    if args.figure:
        if args.no_maps:
            raise UsageError("--figure draws the maps, which --no-maps skips: give one of them")
        if Path(args.figure).suffix.lower() not in (".png", ".svg"):
            raise UsageError(f"--figure {args.figure}: the figure is written as PNG or SVG (.png, .svg)")
        check_output_file(args.figure, "--figure")
    common = engine_work(args, scenario, "explain", "ground motions and free vibrations")
    expl = explain_engine(
        args.engine,
        scenario,
        sigma=args.sigma,
        seed=args.seed,
        effects=args.effects,
        workdir=args.workdir,
        maps=not args.no_maps,
        **common,
    )
    from housner.reports.explain_text import explanation_summary, write_explain_json

    print(explanation_summary(expl))
    print(f"wall time {expl.wall_s['total']:.1f} s")
    if args.workdir:
        print(f"campaign: {expl.details.campaign}")
    if args.json:
        write_explain_json(expl, args.json)
        print(f"json:   {args.json}")
    if args.figure and expl.maps is not None:
        from housner.reports.impact_map_figure import maps_figure, save_figure

        print(f"figure: {save_figure(maps_figure([expl.maps.maps]), args.figure)}")
    return EXIT_OK
