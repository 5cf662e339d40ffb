"""The ``housner`` command line: the top layer, above scenarios, engines and reports.

Errors are one line on stderr, ``housner: error: ...``, naming the file, line,
key or argument at fault; ``--debug`` (or ``HOUSNER_DEBUG=1``) adds the
traceback. Inputs and output paths are checked before any simulation.

Exit status: 0 done; 1 a runtime failure (``run``: a record failed, unless
``--allow-failures``; ``tune``: target not met; an unreachable Dask
scheduler; an unexpected error); 2 bad input (arguments, scenario, campaign
or record files, output paths); 130 interrupted by Ctrl-C.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import sys
import threading
import traceback
from pathlib import Path

__all__ = ["main"]

#: Exit statuses of the command (see the module docstring).
EXIT_OK, EXIT_FAILURE, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130
#: Exit status after SIGTERM (128 + 15), which a batch scheduler or a container runtime sends.
EXIT_TERMINATED = 143
_TERMINATED = False


def _on_sigterm(signum, frame) -> None:
    """SIGTERM is handled like Ctrl-C (workers stopped, finished records cached), with its own status."""
    global _TERMINATED
    _TERMINATED = True
    raise KeyboardInterrupt

_EXIT_HELP = """exit status:
  0    done
  1    runtime failure: {run_failure}an unreachable scheduler, an unexpected error
  2    bad input: arguments, scenario/campaign/record files, output paths (checked before any work)
  130  interrupted (Ctrl-C){ctrl_c}
  143  terminated (SIGTERM), handled as Ctrl-C"""


class UsageError(ValueError):
    """Bad input found by the command itself (an argument, a path); exit status 2."""


class _Parser(argparse.ArgumentParser):
    """argparse, with one-line errors raised as :class:`UsageError` instead of usage text and exit."""

    def error(self, message: str):  # noqa: D102 - argparse API
        raise UsageError(f"{message} (see `{self.prog} --help`)")


def _int_at_least(minimum: int, what: str):
    """An argparse type: an integer of at least ``minimum``, else "must be <what>, got ..."."""

    def parse(value: str) -> int:
        try:
            n = int(value)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {what}, got {value!r}") from None
        if n < minimum:
            raise argparse.ArgumentTypeError(f"must be {what}, got {value!r}")
        return n

    return parse


_positive_int = _int_at_least(1, "a positive integer")
_nonneg_int = _int_at_least(0, "a non-negative integer")


def _folds_int(value: str) -> int:
    n = _nonneg_int(value)
    if n < 2:
        raise argparse.ArgumentTypeError(f"must be an integer of at least 2, got {value!r}")
    return n


def _as_float(text: str) -> float:
    """``float(text)``, NaN when it is not a number (so every range check fails on it)."""
    try:
        return float(text)
    except ValueError:
        return math.nan


def _float_within(inside, what: str):
    """An argparse type: a float for which ``inside(x)`` holds, else "must be WHAT, got 'TEXT'"."""

    def parse(value: str) -> float:
        x = _as_float(value)
        if not inside(x):
            raise argparse.ArgumentTypeError(f"must be {what}, got {value!r}")
        return x

    return parse


_open_fraction = _float_within(lambda x: 0.0 < x < 1.0, "a number between 0 and 1 (exclusive)")
_ratio = _float_within(lambda x: 0.0 < x <= 1.0, "a kinetic-energy ratio in (0, 1]")


def _amplitudes(value: str) -> tuple[float, ...]:
    out = []
    for part in value.split(","):
        a = _as_float(part)
        if not 0.0 < a < 1.0:
            raise argparse.ArgumentTypeError(
                f"must be comma-separated amplitudes theta0/alpha in (0, 1), got {part.strip()!r} in {value!r}"
            )
        out.append(a)
    return tuple(out)


def _engines_arg(value: str) -> list[str]:
    names = [v.strip() for v in value.split(",") if v.strip()]
    if not names:
        raise argparse.ArgumentTypeError("give at least one engine name, e.g. housner,mujoco")
    from housner.engines.base import ENGINES
    from housner.errors import unknown_choice

    for n in names:
        if n not in ENGINES:
            raise argparse.ArgumentTypeError(str(unknown_choice("engine", n, ENGINES)))
    return names


def _versions() -> str:
    """``housner X (python Y; engines: ...)``, from package metadata (imports no engine)."""
    import platform
    from importlib.metadata import PackageNotFoundError, version

    import housner
    from housner.engines.base import ENGINE_PACKAGES, ENGINES

    parts = []
    for name in ENGINES:
        pkg = ENGINE_PACKAGES.get(name, name)
        try:
            v = housner.__version__ if pkg == "housner" else version(pkg)
        except PackageNotFoundError:
            v = "not installed"
        parts.append(f"{name} {v}")
    return f"housner {housner.__version__} (python {platform.python_version()}; engines: {', '.join(parts)})"


class _VersionAction(argparse.Action):
    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings=option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(_versions())
        parser.exit(0)


def _check_output_file(path: str, option: str) -> Path:
    from housner.scenarios.execution.outputs import check_output_file

    return check_output_file(path, option)


def _cmd_scenarios(args: argparse.Namespace) -> int:
    from housner.scenarios.catalogue.scenario import SCENARIOS, list_scenarios

    for name, desc in list_scenarios():
        print(f"{name:18s} {desc}")
        if args.verbose:
            print(f"{'':18s} {SCENARIOS[name]}")
    return 0


def _cmd_run(args: argparse.Namespace) -> int:
    from housner.scenarios.catalogue.scenario import load_scenario
    from housner.scenarios.execution.outputs import check_output_dir
    from housner.scenarios.execution.rundir import RUN_FILES
    from housner.scenarios.execution.workers import connect_scheduler
    from housner.scenarios.runs.run import run_scenario

    # Everything is checked before the first simulation: scenario, engines, arguments, outputs, scheduler.
    scenario = load_scenario(args.scenario)
    engines = args.engines or scenario.engines
    scenario.check_engines(engines)
    for opt, value in (("--n-motions", args.n_motions), ("--seed", args.seed)):
        if value is not None and scenario.source != "rdk":
            raise UsageError(
                f"argument {opt}: scenario {scenario.name!r} has a fixed set of {scenario.n_motions} motions "
                f"(source {scenario.source!r}); {opt} applies to RDK ensembles"
            )
    out = Path(args.out) if args.out else Path("runs") / scenario.name
    if scenario.study is not None:
        from housner.scenarios.studies.study import STUDY_FILES

        check_output_dir(out, "--out" if args.out else "study directory (--out)", files=STUDY_FILES)
    else:
        check_output_dir(out, "--out" if args.out else "run directory (--out)", files=RUN_FILES)
    client = connect_scheduler(args.scheduler) if args.scheduler else None
    n = args.n_motions if args.n_motions is not None else scenario.n_motions
    if scenario.study is not None:
        return _run_study(args, scenario, engines, out, client, n)
    print(f"scenario {scenario.name}: {n} motions x engines {', '.join(engines)} -> {out}", file=sys.stderr)
    run = _call_runner(run_scenario, args, scenario, engines, out, client)
    res = run.results
    for name in dict.fromkeys(res.engine):  # the engines, then the series with the scenario's [[effects]]
        sub = res[res.engine == name]
        ok = sub[sub.status == "ok"]
        info = run.meta["engines"][name]
        rejected = f", {info['cache_rejected']} cache entries rejected" if info.get("cache_rejected") else ""
        median = ok.theta_max_over_alpha.median() if len(ok) else math.nan
        print(
            f"  {name:9s} {len(ok)}/{len(sub)} ok, {int(ok.overturned.sum())} overturned, "
            f"median theta_max/alpha {median:.3f}, "
            f"{info['wall_s']:.1f} s engine time ({info['cached']} cached{rejected})"
        )
    if len(run.failures):
        print(f"{len(run.failures)} record(s) failed (kept out of the statistics):", file=sys.stderr)
        for r in run.failures.itertuples():
            print(f"  {r.engine} motion {r.motion_id} ({r.motion_name}): {r.error}", file=sys.stderr)
    print(f"results: {out / 'results.parquet'}")
    if not args.no_report:
        from housner.reports.run.page import write_report

        path = write_report(out)
        print(f"report:  {path}")
    if len(run.failures) and not args.allow_failures:
        print(
            f"housner: error: {len(run.failures)} of {len(res)} records failed (listed above); "
            "exit status 1 (--allow-failures: exit 0 when records fail)",
            file=sys.stderr,
        )
        return EXIT_FAILURE
    return EXIT_OK


def _call_runner(runner, args: argparse.Namespace, scenario, engines: list[str], out: Path, client):
    """``runner`` (run_scenario or run_study) with the command's options; the scheduler's client closed after."""
    try:
        return runner(
            scenario,
            engines=engines,
            n_motions=args.n_motions,
            seed=args.seed,
            out=out,
            jobs=args.jobs,
            scheduler=client,
            use_cache=not args.no_cache,
            progress=not args.quiet,
        )
    finally:
        if client is not None:
            client.close(timeout=2)


def _run_study(args: argparse.Namespace, scenario, engines: list[str], out: Path, client, n: int) -> int:
    """`housner run` on a scenario with a [study]: every record, the fragility fits, the study report."""
    from housner.scenarios.studies.study import run_study

    st = scenario.study
    print(
        f"study {scenario.name}: {len(st.S)} sizes x {len(st.levels)} stripes x {n} motions x engines "
        f"{', '.join(engines)} = {len(st.S) * len(st.levels) * n * len(engines)} records -> {out}",
        file=sys.stderr,
    )
    res = _call_runner(run_study, args, scenario, engines, out, client)
    comps = {(c["engine"], c["size"]): c for c in res.comparisons}
    print(f"fragility ({st.label}; median and beta with {st.ci:.0%} bootstrap intervals):")
    for f in res.fits:
        head = f"  {f['engine']:9s} H = {f['size']:g} m: "
        if f["status"] != "ok":
            print(head + f"no fit ({f['message']})")
            continue
        line = (f"median {f['median']:.3g} [{f['median_low']:.3g}, {f['median_high']:.3g}], "
                f"beta {f['beta']:.2f} [{f['beta_low']:.2f}, {f['beta_high']:.2f}]")  # fmt: skip
        if f.get("caveat"):
            line += f" (caveat: {f['caveat']})"
        c = comps.get((f["engine"], f["size"]))
        if c is not None:
            word = "DISAGREES with" if c["disagree"] else "agrees with"
            line += (
                f"; {word} {c['reference']}: median x{c['median_ratio']:.3f} "
                f"[{c['ratio_low']:.3f}, {c['ratio_high']:.3f}], "
                f"beta {c['beta_diff']:+.2f} [{c['diff_low']:+.2f}, {c['diff_high']:+.2f}]"
            )
        print(head + line)
    failed = res.results[res.results["status"] != "ok"]
    if len(failed):
        print(f"{len(failed)} record(s) failed (kept out of the fits):", file=sys.stderr)
        for r in failed.head(20).itertuples():
            print(f"  {r.engine} H = {r.size:g} m stripe {r.stripe} motion {r.motion_id}: {r.error}", file=sys.stderr)
    print(f"results: {out / 'fragility.json'}")
    if not args.no_report:
        from housner.reports.study.page import write_study_report

        print(f"report:  {write_study_report(out)}")
    if len(failed) and not args.allow_failures:
        print(f"housner: error: {len(failed)} of {len(res.results)} records failed (listed above); exit status 1 "
              "(--allow-failures: exit 0 when records fail)", file=sys.stderr)  # fmt: skip
        return EXIT_FAILURE
    return EXIT_OK


def _cmd_report(args: argparse.Namespace) -> int:
    from housner.reports.run.page import write_report

    run_dir = Path(args.run_dir)
    if not run_dir.exists():
        raise UsageError(f"run directory {run_dir} does not exist")
    if not run_dir.is_dir():
        raise UsageError(f"run directory {run_dir} is a file; give the directory a run wrote (--out of `housner run`)")
    if not (run_dir / "results.parquet").is_file():
        raise UsageError(f"{run_dir} holds no results.parquet; run `housner run SCENARIO --out {run_dir}` first")
    out = _check_output_file(args.out, "--out") if args.out else None
    if (run_dir / "fragility.json").is_file():  # a study directory
        from housner.reports.study.page import write_study_report

        write_report = write_study_report  # noqa: F811
    if out is None:
        from housner.scenarios.execution.outputs import check_output_dir

        check_output_dir(run_dir, "run directory", files=("report.html",))
    try:
        path = write_report(run_dir, out)
    except (OSError, ValueError) as e:  # a damaged run directory: name it, no traceback
        detail = " ".join(str(e).split()) or type(e).__name__
        raise UsageError(f"run directory {run_dir}: cannot build the report ({type(e).__name__}: {detail})") from e
    print(f"report: {path}")
    return EXIT_OK


def _cmd_tune(args: argparse.Namespace) -> int:
    from housner.engines.tuning import tune
    from housner.specimen import Specimen

    specimen = Specimen.bachmann2017()
    if args.scenario:
        from housner.scenarios.catalogue.scenario import load_scenario

        specimen = load_scenario(args.scenario).specimen
    if args.json:
        _check_output_file(args.json, "--json")
    amps = args.amplitudes
    kwargs = {"target_r": args.target_r, "progress": not args.quiet}
    if amps:
        kwargs["amplitudes"] = amps
    if args.defaults_only:
        from housner.engines.base import get_engine

        kwargs["candidates"] = [get_engine(args.engine).settings()]
    if args.figure:
        _check_output_file(args.figure, "--figure")
    result = tune(args.engine, specimen, **kwargs)
    print(result.summary())
    _print_best_candidates(result)
    if args.json:
        Path(args.json).write_text(json.dumps(result.to_dict(), indent=2, default=str))
        print(f"written: {args.json}")
    if args.figure:
        from housner.reports.tuning_figure import tuning_report_figure

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


def _names_arg(value: str) -> list[str]:
    if value.strip().lower() == "none":
        return []
    return [v.strip() for v in value.split(",") if v.strip()]


def _check_campaign(path: str) -> None:
    """The campaign argument is a directory with campaign.toml, or a .toml file: checked before the work."""
    p = Path(path)
    if not p.exists():
        raise UsageError(f"campaign {p} does not exist (give a directory with campaign.toml, or the campaign.toml)")
    if p.is_dir() and not (p / "campaign.toml").exists():
        raise UsageError(f"campaign directory {p} holds no campaign.toml")
    if p.is_file() and p.suffix != ".toml":
        raise UsageError(f"campaign {p} is a file but not a .toml file (give the directory with campaign.toml)")
    toml = p / "campaign.toml" if p.is_dir() else p
    if toml.is_dir():
        raise UsageError(f"campaign {toml} is a directory, not a file")


def _check_effects(names: list[str] | None, option: str) -> None:
    from housner.effects import available_effects
    from housner.errors import unknown_choice

    known = available_effects()
    for n in names or ():
        if n not in known:
            raise UsageError(f"argument {option}: {unknown_choice('effect', n, known)}")


def _cmd_diagnose(args: argparse.Namespace) -> int:
    from housner.scenarios.campaigns.campaign import load_campaign
    from housner.scenarios.campaigns.diagnose import diagnose

    _check_campaign(args.campaign)  # inputs and outputs checked before the work
    _check_effects(args.effects, "--effects")
    _check_effects(args.add, "--add")
    if args.json:
        _check_output_file(args.json, "--json")
    if args.report is not None:
        _check_output_file(args.report, "--report")
    campaign = load_campaign(args.campaign)
    for rid, file, msg in campaign.skipped:
        print(f"skipped record {rid} ({file}): {msg}", file=sys.stderr)
    print(f"{campaign!r}", file=sys.stderr)
    want_report = args.report is not None
    diag = diagnose(
        campaign,
        effects=args.effects,
        add=tuple(args.add or ()),
        folds=args.folds,
        train_fraction=args.train_fraction,
        seed=args.seed,
        max_effects=args.max_effects,
        compare_steps=want_report,
        progress=None if args.quiet else (lambda line: print(line, file=sys.stderr)),
    )
    print(f"verdict: {diag.status}")
    print(diag.summary())
    print()
    print(f"{'step':45s} {'held-out error [alpha]':>24s} {'improvement':>20s}")
    for s in diag.steps:
        imp = "" if s.added is None else f"{s.improvement:+.4f} +- {s.improvement_se:.2g}"
        print(f"{s.label()[:45]:45s} {s.heldout_error:>13.4f} +- {s.heldout_se:<8.2g} {imp:>20s}")
    res = diag.verdict.residual
    print(f"correct-model floor {res.floor:.4f} (measured), error/floor {res.ratio:.2f}, z {res.z:+.1f}; "
          f"sensor noise sigma/alpha = {diag.noise_floor:.4f}; {diag.elapsed:.1f} s")
    if args.json:
        diag.to_json(args.json)
        print(f"json:   {args.json}")
    if want_report:
        from housner.reports.diagnosis import write_diagnosis_report

        print(f"report: {write_diagnosis_report(diag, args.report)}")
    return 0


def _listing(full: bool) -> dict[str, str]:
    """Names from the registries for the help texts (only built when help is asked for)."""
    if not full:
        return {"engines": "see `housner run --help`", "effects": "", "scenarios": ""}
    from housner.effects import available_effects
    from housner.engines.base import ENGINES
    from housner.scenarios.catalogue.scenario import SCENARIOS

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
    s = sub.add_parser("scenarios", help="list the shipped scenarios")
    s.add_argument("-v", "--verbose", action="store_true", help="also print each scenario's file")
    s.set_defaults(func=_cmd_scenarios)

    _add_run(sub, names)
    rep = sub.add_parser("report", help="rebuild the HTML report of a run directory")
    rep.add_argument("run_dir")
    rep.add_argument("--out", help="report file (default RUN_DIR/report.html)")
    rep.set_defaults(func=_cmd_report)

    _add_tune(sub, names)
    _add_diagnose(sub, names)
    return p


def _add_run(sub, names: dict) -> None:
    """The ``run`` command's arguments."""
    r = sub.add_parser(
        "run",
        help="run a scenario on its engines and write results and an HTML report",
        description="Run a scenario on its engines, write the run directory and its HTML report.",
        epilog=f"engines: {names['engines']}\nscenarios: {names['scenarios']} (or a TOML file)\n\n"
        + _EXIT_HELP.format(
            run_failure="a record failed in an engine (unless --allow-failures), ",
            ctrl_c="; finished records stay in the cache, re-run to resume",
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
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
    r.add_argument("--no-report", action="store_true", help="skip the HTML report")
    r.add_argument(
        "--allow-failures",
        action="store_true",
        help="exit 0 even when records failed (they are listed, and kept out of the statistics)",
    )
    r.add_argument("--plugin", action="append", metavar="FILE.py",
                   help="load the effects this Python file registers (@register_effect; repeatable)")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    r.set_defaults(func=_cmd_run)


def _add_tune(sub, names: dict) -> None:
    """The ``tune`` command's arguments."""
    t = sub.add_parser(
        "tune",
        help="search engine contact settings that reproduce a target r in free vibration",
        epilog=f"engines: {names['engines']}",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
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
    t.set_defaults(func=_cmd_tune)


def _add_diagnose(sub, names: dict) -> None:
    """The ``diagnose`` command's arguments."""
    d = sub.add_parser(
        "diagnose",
        help="find the physical effect a measurement campaign needs (error ladder)",
        epilog=f"effects: {names['effects']}",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
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
    d.add_argument("--plugin", action="append", metavar="FILE.py",
                   help="load the effects this Python file registers (@register_effect; repeatable)")
    d.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    d.set_defaults(func=_cmd_diagnose)


def _one_line(text: str) -> str:
    """Join a multi-line message into one line."""
    return "; ".join(line.strip() for line in str(text).splitlines() if line.strip())


def _error(message: str) -> None:
    print(f"housner: error: {_one_line(message)}", file=sys.stderr)


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
            from housner.effects import load_plugin

            try:
                load_plugin(path)
            except ValueError as e:
                _error(f"--plugin: {e}")
                return EXIT_USAGE
        try:
            parser = build_parser(full_help=any(a in ("-h", "--help") for a in argv))
            args = parser.parse_args(argv)
        except SystemExit as e:  # --help, --version
            return e.code if isinstance(e.code, int) else (EXIT_OK if e.code is None else EXIT_USAGE)
        return int(args.func(args) or 0)
    except KeyboardInterrupt as e:
        from housner.scenarios.execution.workers import RunInterrupted

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


def _classify(e: Exception) -> tuple[int, str]:
    """Exit status and message of an error that reached :func:`main`."""
    from housner.errors import DataFileError, EngineUnavailable
    from housner.scenarios.execution.workers import SchedulerError

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


if __name__ == "__main__":
    sys.exit(main())
