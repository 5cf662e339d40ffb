"""The ``housner`` command's parser: subcommands, their options, and the help that lists the registries."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable

from housner.cli import campaign as _campaign_cmd
from housner.cli import specimen as _specimen_cmd
from housner.cli.args import (
    _amplitudes,
    _engine_name,
    _engines_arg,
    _float_within,
    _folds_int,
    _names_arg,
    _nonneg_int,
    _open_fraction,
    _Parser,
    _positive_int,
    _ratio,
    _VersionAction,
)
from housner.cli.commands import (
    _cmd_diagnose,
    _cmd_explain,
    _cmd_frontier,
    _cmd_report,
    _cmd_run,
    _cmd_scenarios,
    _cmd_tune,
)
from housner.effects import available_effects
from housner.engines.base import ENGINES
from housner.scenarios.catalogue.scenario import SCENARIOS
from housner.scenarios.runs.explain import EXPLAIN_SIGMA

_EXIT_HELP = """exit status:
  0    done
  1    runtime failure: {run_failure}an unreachable scheduler, an unexpected error
  2    bad input: arguments, scenario/campaign/record files, output paths (checked before any work)
  3    `run --check`: an engine's verdict against the reference is FAIL
  130  interrupted (Ctrl-C){ctrl_c}
  143  terminated (SIGTERM), handled as Ctrl-C"""

#: Each subcommand's line in ``housner --help``, in the order listed there.
_SUMMARIES = {
    "scenarios": "list the shipped scenarios",
    "run": "run a scenario on its engines and write results and an HTML report",
    "report": "rebuild the HTML report of a run directory",
    "tune": "search engine contact settings that reproduce a target r in free vibration",
    "diagnose": "find the physical effect a measurement campaign needs (error ladder)",
    "explain": "diagnose an engine's own responses as a campaign: the effects that bring Housner to it, the floor",
    "frontier": "sweep an engine's time step and contact setting: accuracy against cost, and the knee",
}


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
    p = _Parser(
        prog="housner",
        description="Cross-validate physics engines against the analytic Housner rocking block.",
        epilog=_EXIT_HELP.format(run_failure="`run`: a record failed; `tune`: target not met; ", ctrl_c="")
        + "\n\nerrors are one line; --debug or HOUSNER_DEBUG=1 shows the traceback",
        formatter_class=raw,
    )
    p.add_argument("--version", action=_VersionAction, help="print the versions of housner and its engines, and exit")
    p.add_argument("--debug", action="store_true", help="show the traceback of an error (also HOUSNER_DEBUG=1)")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    s = _command(sub, "scenarios", _cmd_scenarios)
    s.add_argument("-v", "--verbose", action="store_true", help="also print each scenario's file")

    _add_run(sub, names)
    rep = _command(sub, "report", _cmd_report)
    rep.add_argument("run_dir")
    rep.add_argument("--out", help="report file (default RUN_DIR/report.html)")

    _add_tune(sub, names)
    _add_diagnose(sub, names)
    _add_explain(sub, names)
    _add_frontier(sub, names)
    _specimen_cmd.add_parser(sub)
    _campaign_cmd.add_parser(sub)
    return p


def _command(sub, name: str, func: Callable, epilog: str | None = None, **kw) -> argparse.ArgumentParser:
    """Subcommand ``name``, run by ``func``, with its line of :data:`_SUMMARIES` as help.

    Its epilog (engines, effects, exit statuses) keeps its line breaks; ``kw`` go to ``add_parser``.
    """
    p = sub.add_parser(
        name, help=_SUMMARIES[name], epilog=epilog, formatter_class=argparse.RawDescriptionHelpFormatter, **kw
    )
    p.set_defaults(func=func)
    return p


def _plugin_option(p: argparse.ArgumentParser) -> None:
    """``--plugin FILE.py`` (repeatable), as run, diagnose and explain take it."""
    p.add_argument("--plugin", action="append", metavar="FILE.py",
                   help="load the effects this Python file registers (@register_effect; repeatable)")  # fmt: skip


def _add_run(sub, names: dict) -> None:
    """The ``run`` command's arguments."""
    r = _command(
        sub,
        "run",
        _cmd_run,
        description="Run a scenario on its engines, write the run directory and its HTML report.",
        epilog=f"engines: {names['engines']}\nscenarios: {names['scenarios']} (or a TOML file)\n\n"
        + _EXIT_HELP.format(
            run_failure="a record failed in an engine (unless --allow-failures), ",
            ctrl_c="; finished records stay in the cache, re-run to resume",
        ),
    )
    r.add_argument("scenario", help="catalogue name (see `housner scenarios`) or path to a TOML file")
    r.add_argument(
        "--engines", type=_engines_arg, help=f"comma-separated engines (default: the scenario's): {names['engines']}"
    )
    r.add_argument("--n-motions", type=_positive_int, help="number of motions of an RDK ensemble (positive)")
    r.add_argument("--seed", type=_nonneg_int, help="override the RDK ensemble's seed (non-negative)")
    r.add_argument("--out", help="run directory (default runs/SCENARIO); checked writable before the run")
    r.add_argument("--jobs", type=_positive_int, help="worker processes (default: all CPUs; 1 = this process)")
    r.add_argument("--scheduler", help="address of a Dask distributed scheduler to run on (5 s to connect)")
    r.add_argument("--no-cache", action="store_true", help="recompute instead of reusing cached results")
    r.add_argument("--allow-outside", action="store_true",
                   help="read record files outside the scenario file's folder (refused by default)")  # fmt: skip
    r.add_argument("--no-report", action="store_true", help="skip the HTML report")
    r.add_argument(
        "--allow-failures",
        action="store_true",
        help="exit 0 even when records failed (they are listed, and kept out of the statistics)",
    )
    _plugin_option(r)
    r.add_argument("--check", action="store_true",
                   help="exit 3 when an engine's verdict against the reference is FAIL (inconclusive does not fail)")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar")


def _add_tune(sub, names: dict) -> None:
    """The ``tune`` command's arguments."""
    t = _command(sub, "tune", _cmd_tune, epilog=f"engines: {names['engines']}")
    t.add_argument("engine", help=f"engine name ({names['engines']})")
    t.add_argument(
        "--r",
        "--target-r",
        dest="target_r",
        type=_ratio,
        help="kinetic-energy ratio to reach, e.g. a measured one (default: the specimen's Housner r)",
    )
    t.add_argument(
        "--amplitudes", type=_amplitudes, help="release amplitudes theta0/alpha, comma-separated (default 0.2..0.9)"
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


def _add_diagnose(sub, names: dict) -> None:
    """The ``diagnose`` command's arguments."""
    d = _command(sub, "diagnose", _cmd_diagnose, epilog=f"effects: {names['effects']}")
    d.add_argument("campaign", help="campaign directory (campaign.toml + records/)")
    d.add_argument(
        "--effects",
        type=_names_arg,
        help=f"candidate effects, comma-separated, or 'none' (default: all): {names['effects']}",
    )
    d.add_argument("--add", action="append", metavar="NAME", help="add this effect by hand first (repeatable)")
    d.add_argument("--json", help="write the diagnosis to this JSON file")
    d.add_argument("--report", help="write the HTML report to this file")
    d.add_argument("--folds", type=_folds_int, default=5,
                   help="cross-validation folds: every record is held out once (5; at least 2)")
    d.add_argument("--train-fraction", type=_open_fraction, default=None,
                   help="older interface: share of records to fit on, sets folds = 1 / (1 - fraction)")
    d.add_argument("--seed", type=_nonneg_int, default=0, help="seed of the fold assignment (0)")
    d.add_argument("--max-effects", type=_nonneg_int, default=3, help="most effects the search adds (3)")
    d.add_argument("--allow-outside", action="store_true",
                   help="read record files and a mesh that resolve outside the campaign folder")  # fmt: skip
    _plugin_option(d)
    d.add_argument("-q", "--quiet", action="store_true", help="no progress lines")


_noise_rad = _float_within(lambda x: math.isfinite(x) and x >= 0.0, "a noise level >= 0 [rad]")


#: What the commands that run one engine on a scenario's ground motions do, for their ``--help``.
_ENGINE_COMMANDS = {
    "explain": (
        "explain",
        "Run an engine on a scenario's ground motions and on free vibrations, diagnose its responses like a "
        "measurement campaign, and compare the analytic model with the effects found against the engine, record "
        "by record, beside the floor a correct model could reach.",
    ),
    "frontier": (
        "sweep",
        "Sweep an engine's time step and its main contact setting (the axes its class declares), and measure at "
        "each point the tuner's checks, per-record agreement and KS against the analytic model on a scenario's "
        "ground motions, the extended floor and the CPU time; mark the knee, where accuracy stops improving.",
    ),
}


def _engine_command(sub, name: str, func: Callable, names: dict) -> argparse.ArgumentParser:
    """A command of :data:`_ENGINE_COMMANDS`: ENGINE, --scenario, --n-motions; :func:`_engine_command_tail`
    adds --jobs and -q after the command's own options."""
    verb, description = _ENGINE_COMMANDS[name]
    c = _command(
        sub,
        name,
        func,
        description=description,
        epilog=f"engines: {names['engines']}\nscenarios: {names['scenarios']} (or a TOML file)\n\n"
        + _EXIT_HELP.format(run_failure="", ctrl_c="; finished records stay in the cache, re-run to resume"),
    )
    c.add_argument("engine", type=_engine_name, metavar="ENGINE", help=f"engine to {verb}: {names['engines']}")
    c.add_argument("--scenario", default="elcentro", help="scenario of ground motions (default elcentro)")
    c.add_argument("--n-motions", type=_positive_int, help="number of motions of an RDK ensemble (positive)")
    return c


def _engine_command_tail(c: argparse.ArgumentParser) -> None:
    c.add_argument("--jobs", type=_positive_int, help="worker processes (default: all CPUs; 1 = this process)")
    c.add_argument("-q", "--quiet", action="store_true", help="no progress bar or progress lines")


def _add_explain(sub, names: dict) -> None:
    """The ``explain`` command's arguments."""
    e = _engine_command(sub, "explain", _cmd_explain, names)
    e.add_argument("--sigma", type=_noise_rad, default=EXPLAIN_SIGMA,
                   help=f"noise added to the engine's theta before the diagnosis [rad] (default {EXPLAIN_SIGMA:g})")
    e.add_argument("--seed", type=_nonneg_int, default=0, help="seed of the noise and of the diagnosis' folds (0)")
    e.add_argument("--effects", type=_names_arg,
                   help=f"candidate effects, comma-separated, or 'none' (default: all): {names['effects']}")
    e.add_argument("--json", help="write the explanation to this JSON file")
    e.add_argument("--workdir", help="keep the engine's campaign in WORKDIR/ENGINE-SCENARIO (default: a temporary one)")
    _plugin_option(e)
    _engine_command_tail(e)


def _add_frontier(sub, names: dict) -> None:
    """The ``frontier`` command's arguments."""
    f = _engine_command(sub, "frontier", _cmd_frontier, names)
    f.add_argument("--json", help="write the frontier to this JSON file (the run report reads "
                   "engines/models/frontier-ENGINE.json)")  # fmt: skip
    f.add_argument("--figure", help="write the frontier's figure to this image file")
    _engine_command_tail(f)
