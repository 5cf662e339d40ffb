"""The ``housner`` command line: the top layer, above scenarios, engines and reports."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

__all__ = ["main"]


def _engines_arg(value: str) -> list[str]:
    names = [v.strip() for v in value.split(",") if v.strip()]
    if not names:
        raise argparse.ArgumentTypeError("give at least one engine name, e.g. housner,mujoco")
    return names


def _cmd_scenarios(args: argparse.Namespace) -> int:
    from scenarios.catalogue import SCENARIOS, list_scenarios

    for name, desc in list_scenarios():
        print(f"{name:18s} {desc}")
        if args.verbose:
            print(f"{'':18s} {SCENARIOS[name]}")
    return 0


def _cmd_run(args: argparse.Namespace) -> int:
    from scenarios.catalogue import load_scenario
    from scenarios.runner import run_scenario

    scenario = load_scenario(args.scenario)
    engines = args.engines or scenario.engines
    out = Path(args.out) if args.out else Path("runs") / scenario.name
    n = args.n_motions if args.n_motions is not None else scenario.n_motions
    print(f"scenario {scenario.name}: {n} motions x engines {', '.join(engines)} -> {out}", file=sys.stderr)
    run = run_scenario(
        scenario,
        engines=engines,
        n_motions=args.n_motions,
        seed=args.seed,
        out=out,
        jobs=args.jobs,
        scheduler=args.scheduler,
        use_cache=not args.no_cache,
        progress=not args.quiet,
    )
    res = run.results
    for name in engines:
        sub = res[res.engine == name]
        ok = sub[sub.status == "ok"]
        info = run.meta["engines"][name]
        print(
            f"  {name:9s} {len(ok)}/{len(sub)} ok, {int(ok.overturned.sum())} overturned, "
            f"median theta_max/alpha {ok.theta_max_over_alpha.median():.3f}, "
            f"{info['wall_s']:.1f} s engine time ({info['cached']} cached)"
        )
    if len(run.failures):
        print(f"{len(run.failures)} record(s) failed (kept out of the statistics):", file=sys.stderr)
        for r in run.failures.itertuples():
            print(f"  {r.engine} motion {r.motion_id} ({r.motion_name}): {r.error}", file=sys.stderr)
    print(f"results: {out / 'results.parquet'}")
    if not args.no_report:
        from reports.html import write_report

        path = write_report(out)
        print(f"report:  {path}")
    return 0


def _cmd_report(args: argparse.Namespace) -> int:
    from reports.html import write_report

    run_dir = Path(args.run_dir)
    if not (run_dir / "results.parquet").exists():
        print(
            f"error: {run_dir} holds no results.parquet; run `housner run SCENARIO --out {run_dir}` first",
            file=sys.stderr,
        )
        return 2
    print(f"report: {write_report(run_dir, args.out)}")
    return 0


def _cmd_tune(args: argparse.Namespace) -> int:
    from engines.tuning import tune
    from housner.specimen import Specimen

    specimen = Specimen.bachmann2017()
    if args.scenario:
        from scenarios.catalogue import load_scenario

        specimen = load_scenario(args.scenario).specimen
    amps = tuple(float(a) for a in args.amplitudes.split(",")) if args.amplitudes else None
    kwargs = {"target_r": args.target_r, "progress": not args.quiet}
    if amps:
        kwargs["amplitudes"] = amps
    if args.defaults_only:
        from engines.base import get_engine

        kwargs["candidates"] = [get_engine(args.engine).settings()]
    result = tune(args.engine, specimen, **kwargs)
    print(result.summary())
    if args.json:
        Path(args.json).write_text(json.dumps(result.to_dict(), indent=2, default=str))
        print(f"written: {args.json}")
    return 0 if result.met else 1


def _names_arg(value: str) -> list[str]:
    if value.strip().lower() == "none":
        return []
    return [v.strip() for v in value.split(",") if v.strip()]


def _cmd_diagnose(args: argparse.Namespace) -> int:
    from scenarios.campaign import load_campaign
    from scenarios.diagnose import diagnose

    campaign = load_campaign(args.campaign)
    for rid, file, msg in campaign.skipped:
        print(f"skipped record {rid} ({file}): {msg}", file=sys.stderr)
    print(f"{campaign!r}", file=sys.stderr)
    want_report = args.report is not None
    diag = diagnose(
        campaign,
        effects=args.effects,
        add=tuple(args.add or ()),
        train_fraction=args.train_fraction,
        seed=args.seed,
        max_effects=args.max_effects,
        compare_steps=want_report,
        progress=None if args.quiet else (lambda line: print(line, file=sys.stderr)),
    )
    print(diag.summary())
    print()
    print(f"{'step':45s} {'held-out error [alpha]':>24s} {'improvement':>20s}")
    for s in diag.steps:
        imp = "" if s.added is None else f"{s.improvement:+.4f} +- {s.improvement_se:.2g}"
        print(f"{s.label()[:45]:45s} {s.heldout_error:>13.4f} +- {s.heldout_se:<8.2g} {imp:>20s}")
    print(f"noise floor sigma/alpha = {diag.noise_floor:.4f}; {diag.elapsed:.1f} s")
    if args.json:
        diag.to_json(args.json)
        print(f"json:   {args.json}")
    if want_report:
        from reports.diagnosis import write_diagnosis_report

        print(f"report: {write_diagnosis_report(diag, args.report)}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="housner",
        description="Cross-validate physics engines against the analytic Housner rocking block.",
    )
    sub = p.add_subparsers(dest="command", required=True)

    s = sub.add_parser("scenarios", help="list the shipped scenarios")
    s.add_argument("-v", "--verbose", action="store_true", help="also print each scenario's file")
    s.set_defaults(func=_cmd_scenarios)

    r = sub.add_parser("run", help="run a scenario on its engines and write results and an HTML report")
    r.add_argument("scenario", help="catalogue name (see `housner scenarios`) or path to a TOML file")
    r.add_argument("--engines", type=_engines_arg, help="comma-separated engines (default: the scenario's)")
    r.add_argument("--n-motions", type=int, help="number of motions of a stochastic ensemble")
    r.add_argument("--seed", type=int, help="override the ensemble's seed")
    r.add_argument("--out", help="run directory (default runs/SCENARIO)")
    r.add_argument("--jobs", type=int, help="worker processes (default: all CPUs; 1 = this process)")
    r.add_argument("--scheduler", help="address of a Dask distributed scheduler to run on")
    r.add_argument("--no-cache", action="store_true", help="recompute instead of reusing cached results")
    r.add_argument("--no-report", action="store_true", help="skip the HTML report")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    r.set_defaults(func=_cmd_run)

    rep = sub.add_parser("report", help="rebuild the HTML report of a run directory")
    rep.add_argument("run_dir")
    rep.add_argument("--out", help="report file (default RUN_DIR/report.html)")
    rep.set_defaults(func=_cmd_report)

    t = sub.add_parser("tune", help="search engine contact settings that reproduce a target r in free vibration")
    t.add_argument("engine", help="engine name (mujoco, pybullet)")
    t.add_argument("--target-r", type=float, help="kinetic-energy ratio to reach (default: the specimen's Housner r)")
    t.add_argument("--amplitudes", help="release amplitudes theta0/alpha, comma-separated (default 0.2..0.9)")
    t.add_argument("--scenario", help="take the specimen from this scenario (default: the seed specimen)")
    t.add_argument(
        "--json", help="write the tuning result to this JSON file (the report reads engines/models/tuning-ENGINE.json)"
    )
    t.add_argument(
        "--defaults-only",
        action="store_true",
        help="only measure the engine's current default settings (r against amplitude, cost)",
    )
    t.add_argument("-q", "--quiet", action="store_true")
    t.set_defaults(func=_cmd_tune)

    d = sub.add_parser("diagnose", help="find the physical effect a measurement campaign needs (error ladder)")
    d.add_argument("campaign", help="campaign directory (campaign.toml + records/)")
    d.add_argument("--effects", type=_names_arg, help="candidate effects, comma-separated, or 'none' (default: all)")
    d.add_argument("--add", action="append", metavar="NAME", help="add this effect by hand first (repeatable)")
    d.add_argument("--json", help="write the diagnosis to this JSON file")
    d.add_argument("--report", help="write the HTML report to this file")
    d.add_argument("--train-fraction", type=float, default=0.5, help="share of ground motions to fit on (0.5)")
    d.add_argument("--seed", type=int, default=0, help="seed of the train / held-out split (0)")
    d.add_argument("--max-effects", type=int, default=3, help="most effects the search adds (3)")
    d.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    d.set_defaults(func=_cmd_diagnose)
    return p


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``housner`` command."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (ValueError, FileNotFoundError) as e:  # bad input: one clear line, no traceback
        print(f"error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
