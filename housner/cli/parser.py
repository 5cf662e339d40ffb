"""The ``housner`` command's parser: its own options, and each subcommand's module's parser, in the help's order.

A subcommand is one module of this package holding its ``SUMMARY``, its ``add_parser`` and its ``run``.
"""

from __future__ import annotations

import argparse

from housner.cli import campaign, diagnose, explain, frontier, impact_map, report, run, scenarios, specimen, tune
from housner.cli.args import Parser, VersionAction
from housner.cli.command import EXIT_HELP
from housner.effects import available_effects
from housner.engines.base import ENGINES
from housner.scenarios.catalogue.scenario import SCENARIOS


def _listing(full: bool) -> dict[str, str]:
    """Names from the registries for the help texts (only built when help is asked for)."""
    if not full:
        return {"engines": "see `housner run --help`", "effects": "", "scenarios": ""}
    return {
        "engines": ", ".join(ENGINES),
        "effects": ", ".join(available_effects()),
        "scenarios": ", ".join(SCENARIOS),
    }


def build_parser(full_help: bool = True) -> argparse.ArgumentParser:
    """The command's parser; ``full_help`` lists the registered engines, effects and scenarios in the help."""
    names = _listing(full_help)
    raw = argparse.RawDescriptionHelpFormatter
    p = Parser(
        prog="housner",
        description="Cross-validate physics engines against the analytic Housner rocking block.",
        epilog=EXIT_HELP.format(run_failure="`run`: a record failed; `tune`: target not met; ", ctrl_c="")
        + "\n\nerrors are one line; --debug or HOUSNER_DEBUG=1 shows the traceback",
        formatter_class=raw,
    )
    p.add_argument("--version", action=VersionAction, help="print the versions of housner and its engines, and exit")
    p.add_argument("--debug", action="store_true", help="show the traceback of an error (also HOUSNER_DEBUG=1)")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    scenarios.add_parser(sub)
    run.add_parser(sub, names)
    report.add_parser(sub)
    tune.add_parser(sub, names)
    diagnose.add_parser(sub, names)
    explain.add_parser(sub, names)
    frontier.add_parser(sub, names)
    impact_map.add_parser(sub, names)
    specimen.add_parser(sub)
    campaign.add_parser(sub)
    return p
