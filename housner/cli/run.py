"""``housner run SCENARIO``: run a scenario on its engines, write the run directory and its report (its parser
and its run); ``housner run CAMPAIGN --engines ...``: the same on a measured campaign's records and specimen, each
engine's predicted outcomes scored against the measured ones."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from housner.cli.args import (
    EXIT_FAILURE,
    EXIT_OK,
    EXIT_VERDICT,
    UsageError,
    check_ensemble_option,
    engines_arg,
    nonneg_int,
    positive_int,
)
from housner.cli.command import EXIT_HELP, add_command, plugin_option
from housner.reports.run.page import write_report
from housner.reports.study.page import write_study_report
from housner.scenarios.catalogue.scenario import load_scenario
from housner.scenarios.execution.cluster import connect_scheduler
from housner.scenarios.execution.options import RunOptions
from housner.scenarios.execution.outputs import check_output_dir
from housner.scenarios.execution.rundir import RUN_FILES
from housner.scenarios.runs.campaign_run import is_campaign, run_campaign
from housner.scenarios.runs.run import run_scenario
from housner.scenarios.runs.view import Run
from housner.scenarios.studies.study import STUDY_FILES, run_study

SUMMARY = "run a scenario (or a measured campaign) on its engines and write results and an HTML report"


def add_parser(sub, names: dict) -> argparse.ArgumentParser:
    """The ``run`` subcommand's arguments; ``names`` are the registries' names for the help texts."""
    r = add_command(
        sub,
        "run",
        SUMMARY,
        run,
        description="Run a scenario on its engines, write the run directory and its HTML report.",
        epilog=f"engines: {names['engines']}\nscenarios: {names['scenarios']} (or a TOML file)\n\n"
        + EXIT_HELP.format(
            run_failure="a record failed in an engine (unless --allow-failures), ",
            ctrl_c="; finished records stay in the cache, re-run to resume",
        ),
    )
    r.add_argument(
        "scenario",
        help="catalogue name (see `housner scenarios`), path to a TOML file, or a campaign "
        "folder holding campaign.toml (then --engines is required)",
    )
    r.add_argument(
        "--engines", type=engines_arg, help=f"comma-separated engines (default: the scenario's): {names['engines']}"
    )
    r.add_argument("--n-motions", type=positive_int, help="number of motions of an RDK ensemble (positive)")
    r.add_argument("--seed", type=nonneg_int, help="override the RDK ensemble's seed (non-negative)")
    r.add_argument("--out", help="run directory (default runs/SCENARIO); checked writable before the run")
    r.add_argument("--jobs", type=positive_int, help="worker processes (default: all CPUs; 1 = this process)")
    r.add_argument("--scheduler", help="address of a Dask distributed scheduler to run on (5 s to connect)")
    r.add_argument("--no-cache", action="store_true", help="recompute instead of reusing cached results")
    r.add_argument(
        "--allow-outside",
        action="store_true",
        help="read record files outside the scenario file's folder (refused by default)",
    )
    r.add_argument("--no-report", action="store_true", help="skip the HTML report")
    r.add_argument(
        "--allow-failures",
        action="store_true",
        help="exit 0 even when records failed (they are listed, and kept out of the statistics)",
    )
    plugin_option(r)
    r.add_argument(
        "--check",
        action="store_true",
        help="exit 3 when an engine's verdict against the reference is FAIL (inconclusive does not fail)",
    )
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    return r


def run(args: argparse.Namespace) -> int:
    """Run the scenario (or its study), print the summary and the verdicts. Returns the exit status."""
    # Everything is checked before the first simulation: scenario, engines, arguments, outputs, scheduler.
    if is_campaign(args.scenario):
        return _run_campaign(args)
    scenario = load_scenario(args.scenario, allow_outside=args.allow_outside)
    engines = args.engines or scenario.engines
    scenario.check_engines(engines)
    check_ensemble_option(scenario, "--n-motions", args.n_motions)
    check_ensemble_option(scenario, "--seed", args.seed)
    out = Path(args.out) if args.out else Path("runs") / scenario.name
    if scenario.study is not None:
        check_output_dir(out, "--out" if args.out else "study directory (--out)", files=STUDY_FILES)
    else:
        check_output_dir(out, "--out" if args.out else "run directory (--out)", files=RUN_FILES)
    client = connect_scheduler(args.scheduler) if args.scheduler else None
    n = args.n_motions if args.n_motions is not None else scenario.n_motions
    if scenario.study is not None:
        return _run_study(args, scenario, engines, out, client, n)
    print(f"scenario {scenario.name}: {n} motions x engines {', '.join(engines)} -> {out}", file=sys.stderr)
    done = _call_runner(run_scenario, args, scenario, engines, out, client)
    _print_engines(done)
    return _finish(args, done, out)


def _print_engines(done) -> None:
    """One line per engine (or series): records ok, overturns, median theta_max/alpha, engine time."""
    res = done.results
    for name in dict.fromkeys(res.engine):  # the engines, then the series with the scenario's [[effects]]
        sub = res[res.engine == name]
        ok = sub[sub.status == "ok"]
        info = done.meta.engines[name]
        rejected = f", {info.cache_rejected} cache entries rejected" if info.cache_rejected else ""
        if info.kernel_cache_repairs:
            rejected += f", {info.kernel_cache_repairs} damaged kernel-cache entries rebuilt"
        median = ok.theta_max_over_alpha.median() if len(ok) else math.nan
        print(
            f"  {name:9s} {len(ok)}/{len(sub)} ok, {int(ok.overturned.sum())} overturned, "
            f"median theta_max/alpha {median:.3f}, "
            f"{info.wall_s:.1f} s engine time ({info.cached} cached{rejected})"
        )


def _finish(args: argparse.Namespace, done, out: Path) -> int:
    """The failures, the report and the verdicts of a written run; the exit status."""
    res = done.results
    if len(done.failures):
        print(f"{len(done.failures)} record(s) failed (kept out of the statistics):", file=sys.stderr)
        for r in done.failures.itertuples():
            print(f"  {r.engine} motion {r.motion_id} ({r.motion_name}): {r.error}", file=sys.stderr)
    print(f"results: {out / 'results.parquet'}")
    view = Run.load(out)  # once: the report and the verdicts read the same run (its chaos floors computed once)
    if view.meta.is_campaign:
        _print_outcomes(view)
    if not args.no_report:
        path = write_report(out, view=view)
        print(f"report:  {path}")
    failed_engines = _print_verdicts(view)
    if len(done.failures) and not args.allow_failures:
        print(
            f"housner: error: {len(done.failures)} of {len(res)} records failed (listed above); "
            "exit status 1 (--allow-failures: exit 0 when records fail)",
            file=sys.stderr,
        )
        return EXIT_FAILURE
    if failed_engines and args.check:
        print(
            f"housner: error: verdict FAIL for {', '.join(failed_engines)}; exit status {EXIT_VERDICT} (--check)",
            file=sys.stderr,
        )
        return EXIT_VERDICT
    return EXIT_OK


def _run_campaign(args: argparse.Namespace) -> int:
    """`housner run CAMPAIGN --engines ...`: the engines on the campaign's records, scored on its outcomes."""
    if not args.engines:
        raise UsageError(f"{args.scenario} is a campaign: name the engines to run on it, --engines NAME[,NAME...]")
    for opt in ("n_motions", "seed"):
        if getattr(args, opt) is not None:
            raise UsageError(f"--{opt.replace('_', '-')} is for a scenario's ensemble; a campaign runs its own records")
    folder = Path(args.scenario).resolve()
    out = Path(args.out) if args.out else Path("runs") / (folder.parent if folder.is_file() else folder).name
    check_output_dir(out, "--out" if args.out else "run directory (--out)", files=RUN_FILES)
    client = connect_scheduler(args.scheduler) if args.scheduler else None
    try:
        options = RunOptions(jobs=args.jobs, scheduler=client, use_cache=not args.no_cache, progress=not args.quiet)
        done = run_campaign(
            args.scenario,
            engines=args.engines,
            out=out,
            options=options,
            allow_outside=args.allow_outside,
            say=lambda s: print(s, file=sys.stderr),
        )
    finally:
        if client is not None:
            client.close(timeout=2)
    _print_engines(done)
    return _finish(args, done, out)


def _print_outcomes(view: Run) -> None:
    """Each engine's outcome scores against the campaign's measured outcomes (as the report's table gives them)."""
    rows = view.outcome_scores
    if not rows:
        return
    clip = rows[0].p_clip
    print(
        f"outcomes against the campaign's measured ones (95 % bootstrap intervals over the records; log loss "
        f"of 0/1 predictions with P clipped to [{clip:g}, {1 - clip:g}]):"
    )
    for r in rows:
        failed = f", {r.n_failed} failed records left out" if r.n_failed else ""
        if not r.n:
            print(f"  {r.engine:9s} no record with an outcome ran{failed}")
            continue
        acc, f1, loss = (ci or (math.nan, math.nan) for ci in (r.accuracy_ci, r.f1_ci, r.log_loss_ci))
        print(
            f"  {r.engine:9s} accuracy {r.accuracy:.3f} [{acc[0]:.3f}, {acc[1]:.3f}], "
            f"F1 {r.f1:.3f} [{f1[0]:.3f}, {f1[1]:.3f}], log loss {r.log_loss:.3f} "
            f"[{loss[0]:.3f}, {loss[1]:.3f}], {r.n_predicted} predicted / "
            f"{r.n_overturned} measured overturns of {r.n} records{failed}"
        )
    for p in view.published_outcomes:
        print(
            f"  ({p.note}: {p.model}: accuracy {p.accuracy:.3f}, F1 {p.f1:.3f}, "
            f"{p.n_predicted} predicted / {p.n_overturned} measured overturns)"
        )


def _print_verdicts(view: Run) -> list[str]:
    """Print each engine's one verdict against the reference (as the report's headline gives it), with the figures
    behind it; the engines that fail."""
    verdicts = view.verdicts()  # an engine with the scenario's effects is meant to differ: it has none
    if not verdicts:
        return []
    print(f"verdict against {view.reference} (as the report's first screen; the rule: docs/explanation/verdict.md):")
    failed = []
    for name, v in verdicts.items():
        print(f"  {name:9s} {v.line()}")
        print(f"  {'':9s} {v.figures()}")
        if v.kind == "fails":
            failed.append(name)
    return failed


def _call_runner(runner, args: argparse.Namespace, scenario, engines: list[str], out: Path, client):
    """``runner`` (run_scenario or run_study) with the command's options; the scheduler's client closed after."""
    try:
        options = RunOptions(jobs=args.jobs, scheduler=client, use_cache=not args.no_cache, progress=not args.quiet)
        return runner(scenario, engines=engines, n_motions=args.n_motions, seed=args.seed, out=out, options=options)
    finally:
        if client is not None:
            client.close(timeout=2)


def _run_study(args: argparse.Namespace, scenario, engines: list[str], out: Path, client, n: int) -> int:
    """`housner run` on a scenario with a [study]: every record, the fragility fits, the study report."""
    st = scenario.study
    print(
        f"study {scenario.name}: {len(st.S)} sizes x {len(st.levels)} stripes x {n} motions x engines "
        f"{', '.join(engines)} = {len(st.S) * len(st.levels) * n * len(engines)} records -> {out}",
        file=sys.stderr,
    )
    res = _call_runner(run_study, args, scenario, engines, out, client)
    comps = {(c.engine, c.size): c for c in res.comparisons}
    print(f"fragility ({st.label}; median and beta with {st.ci:.0%} bootstrap intervals):")
    for f in res.fits:
        head = f"  {f.engine:9s} H = {f.size:g} m: "
        if not f.ok:
            print(head + f"no fit ({f.message})")
            continue
        line = (
            f"median {f.median:.3g} [{f.median_low:.3g}, {f.median_high:.3g}], "
            f"beta {f.beta:.2f} [{f.beta_low:.2f}, {f.beta_high:.2f}]"
        )
        if f.caveat:
            line += f" (caveat: {f.caveat})"
        c = comps.get((f.engine, f.size))
        if c is not None:
            word = "DISAGREES with" if c.disagree else "agrees with"
            line += (
                f"; {word} {c.reference}: median x{c.median_ratio:.3f} "
                f"[{c.ratio_low:.3f}, {c.ratio_high:.3f}], "
                f"beta {c.beta_diff:+.2f} [{c.diff_low:+.2f}, {c.diff_high:+.2f}]"
            )
        print(head + line)
    failed = res.results[res.results["status"] != "ok"]
    if len(failed):
        print(f"{len(failed)} record(s) failed (kept out of the fits):", file=sys.stderr)
        for r in failed.head(20).itertuples():
            print(f"  {r.engine} H = {r.size:g} m stripe {r.stripe} motion {r.motion_id}: {r.error}", file=sys.stderr)
    print(f"results: {out / 'fragility.json'}")
    if not args.no_report:
        print(f"report:  {write_study_report(out)}")
    if len(failed) and not args.allow_failures:
        print(
            f"housner: error: {len(failed)} of {len(res.results)} records failed (listed above); exit status 1 "
            "(--allow-failures: exit 0 when records fail)",
            file=sys.stderr,
        )
        return EXIT_FAILURE
    return EXIT_OK
