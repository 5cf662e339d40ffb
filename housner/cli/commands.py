"""The ``housner`` subcommands: scenarios, run, report, tune, diagnose, explain, frontier (each returns the exit
status)."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from housner.cli.args import (
    EXIT_FAILURE,
    EXIT_OK,
    EXIT_VERDICT,
    UsageError,
    _check_campaign,
    _check_effects,
    _check_output_file,
)
from housner.engines.base import get_engine
from housner.reports.run.page import write_report
from housner.reports.run.view import Run, engine_verdict
from housner.reports.study.page import write_study_report
from housner.scenarios.catalogue.scenario import SCENARIOS, list_scenarios, load_scenario
from housner.scenarios.execution.options import RunOptions
from housner.scenarios.execution.outputs import check_output_dir
from housner.scenarios.execution.rundir import RUN_FILES, IncompleteRunError
from housner.scenarios.execution.workers import connect_scheduler
from housner.scenarios.runs.run import run_scenario
from housner.scenarios.studies.study import STUDY_FILES, run_study
from housner.specimen import Specimen


def _cmd_scenarios(args: argparse.Namespace) -> int:
    for name, desc in list_scenarios():
        print(f"{name:18s} {desc}")
        if args.verbose:
            print(f"{'':18s} {SCENARIOS[name]}")
    return 0


def _cmd_run(args: argparse.Namespace) -> int:
    # Everything is checked before the first simulation: scenario, engines, arguments, outputs, scheduler.
    scenario = load_scenario(args.scenario, allow_outside=args.allow_outside)
    engines = args.engines or scenario.engines
    scenario.check_engines(engines)
    _check_ensemble_option(scenario, "--n-motions", args.n_motions)
    _check_ensemble_option(scenario, "--seed", args.seed)
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
    run = _call_runner(run_scenario, args, scenario, engines, out, client)
    res = run.results
    for name in dict.fromkeys(res.engine):  # the engines, then the series with the scenario's [[effects]]
        sub = res[res.engine == name]
        ok = sub[sub.status == "ok"]
        info = run.meta["engines"][name]
        rejected = f", {info['cache_rejected']} cache entries rejected" if info.get("cache_rejected") else ""
        if info.get("kernel_cache_repairs"):
            rejected += f", {info['kernel_cache_repairs']} damaged kernel-cache entries rebuilt"
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
    view = Run.load(out)  # once: the report and the verdicts read the same run (its chaos floors computed once)
    if not args.no_report:
        path = write_report(out, view=view)
        print(f"report:  {path}")
    failed_engines = _print_verdicts(view)
    if len(run.failures) and not args.allow_failures:
        print(
            f"housner: error: {len(run.failures)} of {len(res)} records failed (listed above); "
            "exit status 1 (--allow-failures: exit 0 when records fail)",
            file=sys.stderr,
        )
        return EXIT_FAILURE
    if failed_engines and args.check:
        print(f"housner: error: verdict FAIL for {', '.join(failed_engines)}; exit status {EXIT_VERDICT} (--check)",
              file=sys.stderr)  # fmt: skip
        return EXIT_VERDICT
    return EXIT_OK


def _check_ensemble_option(scenario, opt: str, value) -> None:
    """``--n-motions`` and ``--seed`` apply to RDK ensembles: refused for a scenario with a fixed set of motions."""
    if value is not None and scenario.source != "rdk":
        raise UsageError(
            f"argument {opt}: scenario {scenario.name!r} has a fixed set of {scenario.n_motions} motions "
            f"(source {scenario.source!r}); {opt} applies to RDK ensembles"
        )


def _print_verdicts(view: Run) -> list[str]:
    """Print each engine's verdict against the reference (as the report's headline gives it); the failed ones."""
    if not view.others:
        return []
    floors = view.chaos_floors
    effects = {n for n, v in (view.meta.get("engines") or {}).items() if isinstance(v, dict) and v.get("effects")}
    print(f"verdict against {view.reference} (the report's headline):")
    failed = []
    for name in view.others:
        if name in effects:
            continue  # an engine with the scenario's effects is meant to differ: no verdict
        v = engine_verdict(view.comparison.loc[name], floors.get(name))
        print(f"  {name:9s} {v.line()}")
        if v.status == "FAIL":
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
        print(f"report:  {write_study_report(out)}")
    if len(failed) and not args.allow_failures:
        print(f"housner: error: {len(failed)} of {len(res.results)} records failed (listed above); exit status 1 "
              "(--allow-failures: exit 0 when records fail)", file=sys.stderr)  # fmt: skip
        return EXIT_FAILURE
    return EXIT_OK


def _cmd_report(args: argparse.Namespace) -> int:
    run_dir = Path(args.run_dir)
    if not run_dir.exists():
        raise UsageError(f"run directory {run_dir} does not exist")
    if not run_dir.is_dir():
        raise UsageError(f"run directory {run_dir} is a file; give the directory a run wrote (--out of `housner run`)")
    if not (run_dir / "results.parquet").is_file():
        raise UsageError(f"{run_dir} holds no results.parquet; run `housner run SCENARIO --out {run_dir}` first")
    out = _check_output_file(args.out, "--out") if args.out else None
    write = write_study_report if (run_dir / "fragility.json").is_file() else write_report  # a study's or a run's
    if out is None:
        check_output_dir(run_dir, "run directory", files=("report.html",))
    try:
        path = write(run_dir, out)
    except IncompleteRunError:  # its own line names the directory and what does not match
        raise
    except (OSError, ValueError) as e:  # a damaged run directory: name it, no traceback
        detail = " ".join(str(e).split()) or type(e).__name__
        raise UsageError(f"run directory {run_dir}: cannot build the report ({type(e).__name__}: {detail})") from e
    print(f"report: {path}")
    return EXIT_OK


def _cmd_tune(args: argparse.Namespace) -> int:
    from housner.engines.tuning import tune  # each command imports its own layers: `housner run` starts faster
    from housner.reports.tuning_figure import tuning_report_figure

    specimen = Specimen.bachmann2017()
    if args.scenario:
        specimen = load_scenario(args.scenario).specimen
    if args.json:
        _check_output_file(args.json, "--json")
    amps = args.amplitudes
    kwargs = {"target_r": args.target_r, "progress": not args.quiet}
    if amps:
        kwargs["amplitudes"] = amps
    if args.defaults_only:
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


def _cmd_diagnose(args: argparse.Namespace) -> int:
    from housner.reports.diagnosis import write_diagnosis_report
    from housner.scenarios.campaigns.campaign import load_campaign
    from housner.scenarios.campaigns.diagnose import diagnose

    _check_campaign(args.campaign)  # inputs and outputs checked before the work
    _check_effects(args.effects, "--effects")
    _check_effects(args.add, "--add")
    if args.json:
        _check_output_file(args.json, "--json")
    if args.report is not None:
        _check_output_file(args.report, "--report")
    campaign = load_campaign(args.campaign, allow_outside=args.allow_outside)
    for rid, file, msg in campaign.skipped:
        print(f"skipped record {rid} ({file}): {msg}", file=sys.stderr)
    if not args.quiet:
        print(f"{campaign!r}", file=sys.stderr)
    outcomes = _diagnose_outcomes(args, campaign) if campaign.outcomes else None
    if not campaign.records:  # outcome records only
        if args.json:
            Path(args.json).write_text(json.dumps(outcomes.to_dict(), indent=1, default=_json_default) + "\n")
            print(f"json:   {args.json}")
        if args.report is not None:
            from housner.reports.diagnosis import write_outcome_report

            print(f"report: {write_outcome_report(outcomes, args.report)}")
        return 0
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
        if outcomes is not None:  # a campaign of both kinds: the outcome diagnosis under its own key
            data = json.loads(Path(args.json).read_text())
            data["outcomes_diagnosis"] = outcomes.to_dict()
            data["outcomes"] = data["outcomes_diagnosis"]["outcomes"]
            Path(args.json).write_text(json.dumps(data, indent=1, default=_json_default) + "\n")
        print(f"json:   {args.json}")
    if want_report:
        print(f"report: {write_diagnosis_report(diag, args.report)}")
    return 0


def _json_default(o):
    """numpy scalars and arrays in the diagnosis' JSON."""
    import numpy as np

    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"{type(o).__name__} is not JSON serialisable")


def _diagnose_outcomes(args: argparse.Namespace, campaign):
    """The outcome records' diagnosis (:func:`housner.scenarios.campaigns.outcomes.diagnose_outcomes`), printed."""
    from housner.scenarios.campaigns.outcome_scores import SCORE_KEYS
    from housner.scenarios.campaigns.outcomes import diagnose_outcomes

    d = diagnose_outcomes(campaign, folds=args.folds, seed=args.seed,
                          progress=None if args.quiet else (lambda line: print(line, file=sys.stderr)))  # fmt: skip
    print(f"verdict: {d.status}")
    print(d.summary())
    print()
    keys = SCORE_KEYS[:4]
    print(f"{'held out, same folds':34s}" + "".join(f"{k:>22s}" for k in keys))
    rows = [(s.name if i == 0 else f"+ {s.name}", s.scores) for i, s in enumerate(d.steps)]
    rows += [(name, sc) for name, sc in d.baselines.items()]
    for name, sc in rows:
        cells = "".join(f"{sc[k]:>9.3f} [{sc[k + '_ci'][0]:.3f},{sc[k + '_ci'][1]:.3f}]" for k in keys)
        print(f"{name[:34]:34s}{cells}")
    print(f"{d.elapsed:.1f} s")
    return d


def _engine_scenario(args: argparse.Namespace, purpose: str):
    """``--scenario`` loaded and checked for an engine's analysis: ground motions, ``--n-motions``, the engine."""
    scenario = load_scenario(args.scenario)
    if scenario.source == "free_vibration" or scenario.study is not None:
        raise UsageError(f"argument --scenario: scenario {scenario.name!r} has no ground motions to {purpose} "
                         "(give one of ground motions, e.g. elcentro)")  # fmt: skip
    _check_ensemble_option(scenario, "--n-motions", args.n_motions)
    scenario.check_engines([args.engine, "housner"])
    return scenario


def _engine_work(args: argparse.Namespace, scenario, what: str, records: str) -> dict:
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


def _cmd_explain(args: argparse.Namespace) -> int:
    from housner.scenarios.runs.explain import explain_engine

    # inputs and outputs checked before the work: scenario, engine, options, files
    scenario = _engine_scenario(args, "explain an engine on")
    _check_effects(args.effects, "--effects")
    if args.json:
        _check_output_file(args.json, "--json")
    if args.workdir:
        check_output_dir(Path(args.workdir), "--workdir")
    common = _engine_work(args, scenario, "explain", "ground motions and free vibrations")
    expl = explain_engine(args.engine, scenario, sigma=args.sigma, seed=args.seed, effects=args.effects,
                          workdir=args.workdir, **common)  # fmt: skip
    print(expl.summary())
    print(f"wall time {expl.wall_s['total']:.1f} s")
    if args.workdir:
        print(f"campaign: {expl.details['campaign']}")
    if args.json:
        Path(args.json).write_text(json.dumps(expl.to_dict(), indent=2))
        print(f"json:   {args.json}")
    return EXIT_OK


def _cmd_frontier(args: argparse.Namespace) -> int:
    from housner.reports.frontier_figure import frontier_figure
    from housner.scenarios.runs.frontier import engine_frontier, frontier_axes

    # inputs and outputs checked before the work: engine, scenario, options, files
    if args.engine == "housner":
        raise UsageError("argument ENGINE: 'housner' is the reference the frontier is measured against; "
                         "name another engine")  # fmt: skip
    try:
        frontier_axes(args.engine)
    except ValueError as e:
        raise UsageError(f"argument ENGINE: {e}") from None
    scenario = _engine_scenario(args, "measure a frontier on")
    for opt, path in (("--json", args.json), ("--figure", args.figure)):
        if path:
            _check_output_file(path, opt)
    fr = engine_frontier(args.engine, scenario, **_engine_work(args, scenario, "frontier of", "ground motions"))
    print(fr.summary())
    print(f"wall time {fr.wall_s:.1f} s")
    if args.json:
        Path(args.json).write_text(json.dumps(fr.to_dict(), indent=2))
        print(f"json:   {args.json}")
    if args.figure:
        frontier_figure(fr).savefig(args.figure)
        print(f"figure: {args.figure}")
    return EXIT_OK
