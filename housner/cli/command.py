"""What the subcommands share: a subcommand's parser (its help line, its epilog), the exit-status text, ``--plugin``."""

from __future__ import annotations

import argparse
from collections.abc import Callable

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
