"""``housner impact-map ENGINE [ENGINE ...]``: each engine's impact and flight maps against Housner's model (its
parser and its run)."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from housner.cli.args import EXIT_OK, UsageError, amplitudes, float_within, positive_int
from housner.cli.command import EXIT_HELP, add_command

SUMMARY = "measure each engine's departure from Housner at the impact and in flight (its maps), with a figure"
DESCRIPTION = (
    "Release the block from rest at amplitudes from 0.0012 to 0.9 alpha, run each engine, and measure at every "
    "impact the energy it keeps over Housner's r against the impact speed x = |w-|/(p alpha), and in every "
    "flight the equivalent viscous coefficient c (dE/dt = -c w^2). Writes maps-ENGINE.json per engine and "
    "impact-maps.png into --out."
)
#: Where the maps go by default.
DEFAULT_OUT = "runs/impact-maps"
#: The figure's name in the output directory.
FIGURE = "impact-maps.png"

_dt = float_within(lambda x: math.isfinite(x) and 0.0 < x <= 0.01, "a sample interval in (0, 0.01] s")


def _map_engine(value: str) -> str:
    """A registered engine name, or ``analytic`` (an argument's type)."""
    from housner.scenarios.runs.impact_map import engine_registry_name

    try:
        engine_registry_name(value)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None
    return value


def _setting(value: str) -> tuple[str, str, object]:
    """``[ENGINE.]KEY=VALUE``: (engine or "", key, value read as JSON, else as text) (an argument's type)."""
    key, sep, text = value.partition("=")
    key = key.strip()
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"must be KEY=VALUE or ENGINE.KEY=VALUE, got {value!r}")
    engine, _, key = key.rpartition(".")
    try:
        parsed = json.loads(text)
    except json.JSONDecodeError:
        parsed = text
    return engine, key, parsed


def add_parser(sub, names: dict) -> argparse.ArgumentParser:
    """The ``impact-map`` subcommand's arguments; ``names`` are the registries' names for the help texts."""
    from housner.scenarios.runs.impact_map import AMPLITUDES, DT, N_IMPACTS

    c = add_command(
        sub,
        "impact-map",
        SUMMARY,
        run,
        description=DESCRIPTION,
        epilog=f"engines: {names['engines']} (analytic: housner)\n\n" + EXIT_HELP.format(run_failure="", ctrl_c=""),
    )
    c.add_argument("engines", nargs="+", type=_map_engine, metavar="ENGINE", help="engines to measure")
    c.add_argument("--out", default=DEFAULT_OUT, help=f"directory of the maps and the figure (default {DEFAULT_OUT})")
    c.add_argument(
        "--settings",
        action="append",
        type=_setting,
        default=[],
        metavar="[ENGINE.]KEY=VALUE",
        help="an engine setting (repeatable; without ENGINE. for every engine named); default: the engines' defaults",
    )
    c.add_argument(
        "--amplitudes",
        type=amplitudes,
        default=AMPLITUDES,
        help="release amplitudes theta0/alpha, comma-separated (default: 11 from 0.0012 to 0.9)",
    )
    c.add_argument(
        "--n-impacts", type=positive_int, default=N_IMPACTS, help=f"impacts measured per release (default {N_IMPACTS})"
    )
    c.add_argument("--dt", type=_dt, default=DT, help=f"sample interval [s] (default {DT:g})")
    c.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    return c


def run(args: argparse.Namespace) -> int:
    """Measure each engine's maps; print a table per engine, write the JSONs and the figure. Returns the exit status."""
    from housner.engines.base import get_engine
    from housner.reports.impact_map_figure import maps_figure, save_figure
    from housner.scenarios.execution.outputs import check_output_dir
    from housner.scenarios.runs.impact_map import engine_registry_name, measure_maps

    if args.n_impacts < 2:
        raise UsageError(f"argument --n-impacts: must be at least 2, got {args.n_impacts}")
    names = list(dict.fromkeys(args.engines))
    registry = {n: engine_registry_name(n) for n in names}
    for engine, key, _ in args.settings:
        if engine and engine not in names and engine not in registry.values():
            raise UsageError(f"argument --settings: {engine}.{key}: engine {engine!r} is not among those named")
    settings = {n: {k: v for e, k, v in args.settings if not e or e in (n, registry[n])} for n in names}
    # inputs checked before the work: every engine installed and its settings accepted, the directory writable
    for n in names:
        try:
            get_engine(registry[n], **settings[n])
        except (ValueError, TypeError) as e:  # TypeError: a keyword the analytic engine does not take
            raise UsageError(f"argument --settings: engine {n!r}: {e}") from None
    files = [f"maps-{n}.json" for n in names] + [FIGURE]
    out = check_output_dir(Path(args.out), "--out", files=files)
    progress = None if args.quiet else (lambda line: print(line, file=sys.stderr))
    maps = []
    for n in names:
        m = measure_maps(
            n, amplitudes=args.amplitudes, dt=args.dt, n_impacts=args.n_impacts, settings=settings[n], progress=progress
        )
        (out / f"maps-{n}.json").write_text(m.to_json())
        print(m.summary())
        maps.append(m)
    fig_path = save_figure(maps_figure(maps), out / FIGURE)
    print(f"maps:   {', '.join(str(out / f'maps-{n}.json') for n in names)}")
    print(f"figure: {fig_path}")
    return EXIT_OK
