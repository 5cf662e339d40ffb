"""``housner diagnose CAMPAIGN``: the physical effects a measurement campaign needs, by the error ladder (its
parser and its run)."""

from __future__ import annotations

import argparse
import sys

from housner.cli.args import (
    UsageError,
    check_campaign,
    check_effects,
    folds_int,
    names_arg,
    nonneg_int,
    open_fraction,
    positive_int,
)
from housner.cli.command import add_command, plugin_option
from housner.scenarios.execution.outputs import check_output_file

SUMMARY = "find the physical effect a measurement campaign needs (error ladder)"


def add_parser(sub, names: dict) -> argparse.ArgumentParser:
    """The ``diagnose`` subcommand's arguments; ``names`` are the registries' names for the help texts."""
    d = add_command(sub, "diagnose", SUMMARY, run, epilog=f"effects: {names['effects']}")
    d.add_argument("campaign", help="campaign directory (campaign.toml + records/)")
    d.add_argument(
        "--effects",
        type=names_arg,
        help=f"candidate effects, comma-separated, or 'none' (default: all): {names['effects']}",
    )
    d.add_argument("--add", action="append", metavar="NAME", help="add this effect by hand first (repeatable)")
    d.add_argument("--json", help="write the diagnosis to this JSON file")
    d.add_argument("--report", help="write the HTML report to this file")
    d.add_argument(
        "--folds",
        type=folds_int,
        default=5,
        help="cross-validation folds: every record is held out once (5; at least 2)",
    )
    d.add_argument(
        "--train-fraction",
        type=open_fraction,
        default=None,
        help="older interface: share of records to fit on, sets folds = 1 / (1 - fraction)",
    )
    d.add_argument("--seed", type=nonneg_int, default=0, help="seed of the fold assignment (0)")
    d.add_argument(
        "--repeats",
        type=positive_int,
        default=5,
        help="outcome records: repeats of the cross-validation, each on its own folds from --seed on (5)",
    )
    d.add_argument(
        "--model",
        metavar="FITTED.json",
        help="outcome records: also score the model another campaign's diagnosis fitted (its --json), frozen, "
        "beside that campaign's baselines, frozen too",
    )
    d.add_argument(
        "--engine-model",
        metavar="ENGINE",
        help="outcome records of a scan-mesh campaign: also score this 3D engine (mujoco-3d, pybullet-3d) as a "
        "model, P(overturn) from its runs over the unrecorded azimuth and friction, on the same folds (cached runs)",
    )
    d.add_argument(
        "--engine-azimuths",
        type=positive_int,
        default=8,
        help="with --engine-model: azimuths evenly spaced from the campaign's own (8; 1: the campaign's alone)",
    )
    d.add_argument(
        "--engine-frictions",
        type=_numbers,
        default=(0.7,),
        help="with --engine-model: friction coefficients, comma-separated, each run at every azimuth (0.7)",
    )
    d.add_argument(
        "--engine-amplitudes",
        type=_numbers,
        default=(1.0,),
        help="with --engine-model: factors on the table acceleration, comma-separated, each run at every azimuth "
        "and friction (1)",
    )
    d.add_argument("--max-effects", type=nonneg_int, default=3, help="most effects the search adds (3)")
    d.add_argument(
        "--allow-outside",
        action="store_true",
        help="read record files and a mesh that resolve outside the campaign folder",
    )
    plugin_option(d)
    d.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    return d


def run(args: argparse.Namespace) -> int:
    """Diagnose the campaign (its motion records, its outcome records, or both); print the error ladder, write
    the JSON and the report asked for. Returns the exit status."""
    from housner.reports.diagnosis import write_diagnosis_report
    from housner.reports.diagnosis.verdict_text import diagnosis_summary
    from housner.scenarios.campaigns.campaign import load_campaign
    from housner.scenarios.diagnosis.diagnose import diagnose

    check_campaign(args.campaign)  # inputs and outputs checked before the work
    check_effects(args.effects, "--effects")
    check_effects(args.add, "--add")
    if args.json:
        check_output_file(args.json, "--json")
    if args.report is not None:
        check_output_file(args.report, "--report")
    frozen = _frozen_model(args.model)
    campaign = load_campaign(args.campaign, allow_outside=args.allow_outside)
    if frozen is not None and not campaign.outcomes:
        raise UsageError(f"--model: campaign {campaign.name!r} has no outcome records for a frozen outcome model")
    ensemble = _engine_ensemble(args, campaign)
    for rid, file, msg in campaign.skipped:
        print(f"skipped record {rid} ({file}): {msg}", file=sys.stderr)
    if not args.quiet:
        print(f"{campaign!r}", file=sys.stderr)
    outcomes = _diagnose_outcomes(args, campaign, frozen, ensemble) if campaign.outcomes else None
    if not campaign.records:  # outcome records only
        if args.json:
            from housner.reports.diagnosis.outcome_text import write_outcome_json

            write_outcome_json(outcomes, args.json)
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
        folds=_folds(args),
        seed=args.seed,
        max_effects=args.max_effects,
        compare_steps=want_report,
        progress=None if args.quiet else (lambda line: print(line, file=sys.stderr)),
    )
    print(f"verdict: {diag.status}")
    print(_without_status(diagnosis_summary(diag), diag.status))  # the status once: on the line above
    print()
    print(f"{'step':45s} {'held-out error [alpha]':>24s} {'improvement':>20s}")
    for s in diag.steps:
        imp = "" if s.added is None else f"{s.improvement:+.4f} +- {s.improvement_se:.2g}"
        print(f"{s.label()[:45]:45s} {s.heldout_error:>13.4f} +- {s.heldout_se:<8.2g} {imp:>20s}")
    res = diag.verdict.residual
    print(
        f"{'final model' if len(diag.steps) > 1 else 'plain model'}: held-out error {res.error:.4f} alpha, "
        f"correct-model floor {res.floor:.4f} alpha, residual ratio {res.ratio:.2f} (the worse group's error over "
        f"its floor); sensor noise sigma/alpha {diag.noise_floor:.4f}; {diag.elapsed:.1f} s"
    )
    if args.json:
        from housner.reports.diagnosis.document import write_diagnosis_json

        if outcomes is None:
            write_diagnosis_json(diag, args.json)
        else:  # a campaign of both kinds: the outcome diagnosis under its own key, its scores under `outcomes`
            from housner.reports.diagnosis.outcome_text import outcome_document
            from housner.scenarios.execution.rundir import jsonable

            both = jsonable(outcome_document(outcomes), nonfinite="null")
            write_diagnosis_json(diag, args.json, {"outcomes_diagnosis": both, "outcomes": both["outcomes"]})
        print(f"json:   {args.json}")
    if want_report:
        print(f"report: {write_diagnosis_report(diag, args.report)}")
    return 0


def _without_status(text: str, status: str) -> str:
    """The verdict's paragraph without its leading status word ("Explained: ..."), which the ``verdict:`` line
    before it gives."""
    head = status.replace("_", " ") + ":"
    if text[: len(head)].lower() == head:
        text = text[len(head) :].lstrip()
        text = text[:1].upper() + text[1:]
    return text


def _folds(args: argparse.Namespace) -> int:
    """The cross-validation folds asked for: ``--folds``, or K = round(1 / (1 - f)) (at least 2) from the older
    ``--train-fraction f``, the share of records each fold's model is fitted on."""
    if args.train_fraction is None:
        return args.folds
    return max(2, int(round(1.0 / (1.0 - args.train_fraction))))


def _frozen_model(path: str | None):
    """``--model``'s fitted model, read before the work; a UsageError naming the option and the file."""
    if path is None:
        return None
    from housner.scenarios.diagnosis.outcomes.outcome_transfer import read_frozen_model

    try:
        return read_frozen_model(path)
    except ValueError as e:
        raise UsageError(f"--model: {e}") from None


def _numbers(text: str) -> tuple[float, ...]:
    """Comma-separated numbers (``--engine-frictions``, ``--engine-amplitudes``)."""
    try:
        return tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected numbers separated by commas, got {text!r}") from None


def _engine_ensemble(args: argparse.Namespace, campaign):
    """``--engine-model``'s ensemble, checked before the work; a UsageError naming the option."""
    if args.engine_model is None:
        return None
    if not campaign.outcomes:
        raise UsageError(f"--engine-model: campaign {campaign.name!r} has no outcome records to score a 3D engine on")
    from housner.scenarios.diagnosis.outcomes.engine_ensemble import engine_ensemble

    try:
        return engine_ensemble(
            campaign,
            args.engine_model,
            azimuths=args.engine_azimuths,
            frictions=args.engine_frictions,
            amplitudes=args.engine_amplitudes,
        )
    except ValueError as e:
        raise UsageError(str(e)) from None


def _diagnose_outcomes(args: argparse.Namespace, campaign, frozen=None, ensemble=None):
    """The outcome records' diagnosis
    (:func:`housner.scenarios.diagnosis.outcomes.outcome_diagnosis.diagnose_outcomes`), printed."""
    from housner.reports.diagnosis.outcome_text import engine_model_text, outcome_summary, transfer_text
    from housner.scenarios.diagnosis.outcomes.outcome_diagnosis import diagnose_outcomes
    from housner.scenarios.diagnosis.outcomes.outcome_scores import SCORE_KEYS
    from housner.scenarios.execution.options import RunOptions

    d = diagnose_outcomes(
        campaign,
        folds=args.folds,
        seed=args.seed,
        repeats=args.repeats,
        model=frozen,
        effects=args.effects,
        engine_model=ensemble,
        run_options=RunOptions(progress=not args.quiet),
        progress=None if args.quiet else (lambda line: print(line, file=sys.stderr)),
    )
    # a campaign of both kinds prints two verdicts: each line says which records it judges
    print(f"verdict{' (outcome records)' if campaign.records else ''}: {d.status}")
    print(_without_status(outcome_summary(d), d.status))
    print()
    keys = SCORE_KEYS[:4]
    print(f"{'held out, same folds':34s}" + "".join(f"{k:>22s}" for k in keys))
    rows = [(s.name if i == 0 else f"+ {s.name}", s.scores) for i, s in enumerate(d.steps)]
    rows += [(name, sc) for name, sc in d.baselines.items()]
    for name, sc in rows:
        cells = "".join(f"{sc.score(k):>9.3f} [{sc.interval(k)[0]:.3f},{sc.interval(k)[1]:.3f}]" for k in keys)
        print(f"{name[:34]:34s}{cells}")
    if d.transfer is not None:
        print()
        print(transfer_text(d.transfer))
    if d.engine_model is not None:
        print()
        print(engine_model_text(d.engine_model))
    print(f"{d.elapsed:.1f} s")
    return d
