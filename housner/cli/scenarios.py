"""``housner scenarios``: the shipped scenarios, one line each (its parser and its run)."""

from __future__ import annotations

import argparse

from housner.cli.command import add_command
from housner.scenarios.catalogue.scenario import SCENARIOS, list_scenarios

SUMMARY = "list the shipped scenarios"


def add_parser(sub) -> argparse.ArgumentParser:
    """The ``scenarios`` subcommand's arguments."""
    s = add_command(sub, "scenarios", SUMMARY, run)
    s.add_argument("-v", "--verbose", action="store_true", help="also print each scenario's file")
    return s


def run(args: argparse.Namespace) -> int:
    """Print each scenario's name and description (with ``-v``, its file). Returns the exit status."""
    for name, desc in list_scenarios():
        print(f"{name:18s} {desc}")
        if args.verbose:
            print(f"{'':18s} {SCENARIOS[name]}")
    return 0
