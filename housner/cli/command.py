"""What the subcommands share: a subcommand's parser (its help line, its epilog), the exit-status text, ``--plugin``;
and what the commands that study one engine on a scenario's ground motions share (``explain``, ``frontier``): their
arguments open with ENGINE, ``--scenario`` and ``--n-motions`` (:func:`add_engine_command`) and close with
``--jobs`` and ``-q`` (:func:`add_engine_command_tail`); their run loads and checks the scenario
(:func:`engine_scenario`) and announces the work (:func:`engine_work`)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable

from housner.cli.args import UsageError, check_ensemble_option, engine_name, positive_int
from housner.scenarios.catalogue.scenario import load_scenario
from housner.scenarios.execution.options import RunOptions

#: The exit statuses, as the epilogs of ``housner --help`` and of the long-running commands list them;
#: ``run_failure`` and ``ctrl_c`` are the command's own words on status 1 and 130.
EXIT_HELP = """exit status:
  0    done
  1    runtime failure: {run_failure}an unreachable scheduler, an unexpected error
  2    bad input: arguments, scenario/campaign/record files, output paths (checked before any work)
  3    `run --check`: an engine's verdict against the reference is FAIL
  130  interrupted (Ctrl-C){ctrl_c}
  143  terminated (SIGTERM), handled as Ctrl-C"""


def add_command(
    sub, name: str, summary: str, func: Callable, epilog: str | None = None, **kw
) -> argparse.ArgumentParser:
    """Subcommand ``name`` of the subparsers ``sub``, run by ``func``, with ``summary`` as its line in the help.

    Its epilog (engines, effects, exit statuses) keeps its line breaks; ``kw`` go to ``add_parser``.
    """
    p = sub.add_parser(name, help=summary, epilog=epilog, formatter_class=argparse.RawDescriptionHelpFormatter, **kw)
    p.set_defaults(func=func)
    return p


def plugin_option(p: argparse.ArgumentParser) -> None:
    """``--plugin FILE.py`` (repeatable), as run, diagnose and explain take it."""
    p.add_argument(
        "--plugin",
        action="append",
        metavar="FILE.py",
        help="load the effects this Python file registers (@register_effect; repeatable)",
    )


def add_engine_command(
    sub, name: str, summary: str, func: Callable, names: dict, verb: str, description: str
) -> argparse.ArgumentParser:
    """Subcommand ``name`` with ENGINE ("engine to ``verb``"), --scenario and --n-motions;
    :func:`add_engine_command_tail` adds --jobs and -q after the command's own options."""
    c = add_command(
        sub,
        name,
        summary,
        func,
        description=description,
        epilog=f"engines: {names['engines']}\nscenarios: {names['scenarios']} (or a TOML file)\n\n"
        + EXIT_HELP.format(run_failure="", ctrl_c="; finished records stay in the cache, re-run to resume"),
    )
    c.add_argument("engine", type=engine_name, metavar="ENGINE", help=f"engine to {verb}: {names['engines']}")
    c.add_argument("--scenario", default="elcentro", help="scenario of ground motions (default elcentro)")
    c.add_argument("--n-motions", type=positive_int, help="number of motions of an RDK ensemble (positive)")
    return c


def add_engine_command_tail(c: argparse.ArgumentParser) -> None:
    """The last options of an engine command: --jobs and -q."""
    c.add_argument("--jobs", type=positive_int, help="worker processes (default: all CPUs; 1 = this process)")
    c.add_argument("-q", "--quiet", action="store_true", help="no progress bar or progress lines")


def engine_scenario(args: argparse.Namespace, purpose: str):
    """``--scenario`` loaded and checked for an engine's analysis: ground motions, ``--n-motions``, the engine."""
    scenario = load_scenario(args.scenario)
    if scenario.source == "free_vibration" or scenario.study is not None:
        raise UsageError(
            f"argument --scenario: scenario {scenario.name!r} has no ground motions to {purpose} "
            "(give one of ground motions, e.g. elcentro)"
        )
    check_ensemble_option(scenario, "--n-motions", args.n_motions)
    scenario.check_engines([args.engine, "housner"])
    return scenario


def engine_work(args: argparse.Namespace, scenario, what: str, records: str) -> dict:
    """Announce an engine command's work on stderr (unless -q) and give its keyword arguments: ``n_motions``,
    ``options`` (jobs, progress bar) and ``progress`` (lines on stderr)."""
    n = args.n_motions if args.n_motions is not None else scenario.n_motions
    if not args.quiet:
        print(f"{what} {args.engine} on {scenario.name}: {n} {records}", file=sys.stderr)
    return {
        "n_motions": args.n_motions,
        "options": RunOptions(jobs=args.jobs, progress=not args.quiet),
        "progress": None if args.quiet else (lambda line: print(line, file=sys.stderr)),
    }
