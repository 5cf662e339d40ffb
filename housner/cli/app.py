"""The ``housner`` command: its parser (its own options, and each subcommand's module's parser, in the help's order;
a subcommand is one module of this package holding its ``SUMMARY``, its ``add_parser`` and its ``run``) and ``main``,
its entry point (plugins first, then the parser; signals; one-line errors)."""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
import traceback

from housner.cli import campaign, diagnose, explain, frontier, impact_map, report, run, scenarios, specimen, tune
from housner.cli.args import (
    EXIT_FAILURE,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_TERMINATED,
    EXIT_USAGE,
    Parser,
    UsageError,
    VersionAction,
)
from housner.cli.command import EXIT_HELP
from housner.effects import available_effects, load_plugin
from housner.engines.base import ENGINES
from housner.errors import DataFileError, EngineUnavailable, one_line
from housner.scenarios.catalogue.scenario import SCENARIOS
from housner.scenarios.execution.cluster import SchedulerError
from housner.scenarios.execution.workers import RunInterrupted

__all__ = ["build_parser", "main"]


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


_TERMINATED = False


def _on_sigterm(signum, frame) -> None:
    """SIGTERM is handled like Ctrl-C (workers stopped, finished records cached), with its own status."""
    global _TERMINATED
    _TERMINATED = True
    raise KeyboardInterrupt


def _error(message: str) -> None:
    print(f"housner: error: {one_line(message)}", file=sys.stderr)


def _plugin_args(argv: list[str]) -> list[str]:
    """The files named by ``--plugin FILE`` / ``--plugin=FILE`` on the command line, in order."""
    out = []
    for i, a in enumerate(argv):
        if a == "--plugin" and i + 1 < len(argv):
            out.append(argv[i + 1])
        elif a.startswith("--plugin="):
            out.append(a.split("=", 1)[1])
    return out


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``housner`` command; returns the exit status (see the module docstring)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = os.environ.get("HOUSNER_DEBUG", "").strip().lower() not in ("", "0", "false", "no") or "--debug" in argv
    argv = [a for a in argv if a != "--debug"]  # accepted anywhere on the line
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        # effect plugins load first, so that their effects are known to the parser's help and checks
        for path in _plugin_args(argv):
            try:
                load_plugin(path)
            except Exception as e:  # a bad plugin is bad input, whatever it raised: exit 2, naming the file
                if debug:
                    traceback.print_exc()
                _error(f"--plugin: {_plugin_message(path, e)}")
                return EXIT_USAGE
        try:
            parser = build_parser(full_help=any(a in ("-h", "--help") for a in argv))
            args = parser.parse_args(argv)
        except SystemExit as e:  # --help, --version
            return e.code if isinstance(e.code, int) else (EXIT_OK if e.code is None else EXIT_USAGE)
        return int(args.func(args) or 0)
    except KeyboardInterrupt as e:
        if debug:
            traceback.print_exc()
        if isinstance(e, RunInterrupted) and e.cached:
            print(
                f"housner: interrupted: {e.done} of {e.total} records finished and are cached; "
                "run the same command again to resume",
                file=sys.stderr,
            )
        elif isinstance(e, RunInterrupted):
            print(
                f"housner: interrupted: {e.done} of {e.total} records finished (not cached: --no-cache)",
                file=sys.stderr,
            )
        else:
            print("housner: interrupted", file=sys.stderr)
        return EXIT_TERMINATED if _TERMINATED else EXIT_INTERRUPTED
    except Exception as e:
        if debug:
            traceback.print_exc()
        status, message = _classify(e)
        if status == EXIT_FAILURE and not debug and type(e).__name__ not in ("SchedulerError",):
            message += " (run with --debug or HOUSNER_DEBUG=1 for the traceback)"
        _error(message)
        return status


def _plugin_message(path: str, e: Exception) -> str:
    """The error of a plugin file that cannot be loaded, naming the file (load_plugin's errors already do)."""
    if isinstance(e, OSError):
        return f"effect plugin {path!r}: cannot read ({e.strerror or type(e).__name__})"
    text = one_line(e)
    return text if isinstance(e, ValueError) else f"effect plugin {path!r}: {type(e).__name__}: {text}"


def _classify(e: Exception) -> tuple[int, str]:
    """Exit status and message of an error that reached :func:`main`."""
    if isinstance(e, SchedulerError):
        return EXIT_FAILURE, str(e)
    if isinstance(e, (UsageError, DataFileError, ValueError, FileNotFoundError, EngineUnavailable)):  # bad input
        msg = str(e)
        if isinstance(e, OSError) and e.filename is not None and str(e.filename) not in msg:
            msg = f"{e.filename}: {e.strerror or msg}"
        return EXIT_USAGE, msg or type(e).__name__
    if isinstance(e, OSError):
        where = f"{e.filename}: " if e.filename is not None else ""
        return EXIT_FAILURE, f"{where}{e.strerror or e}"
    return EXIT_FAILURE, f"unexpected {type(e).__name__}: {e}"
