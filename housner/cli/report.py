"""``housner report RUN_DIR``: rebuild the HTML report of a run or study directory (its parser and its run)."""

from __future__ import annotations

import argparse
from pathlib import Path

from housner.cli.args import EXIT_OK, UsageError
from housner.cli.command import add_command
from housner.reports.run.page import write_report
from housner.reports.study.page import write_study_report
from housner.scenarios.execution.outputs import check_output_dir, check_output_file
from housner.scenarios.execution.rundir import IncompleteRunError

SUMMARY = "rebuild the HTML report of a run directory"


def add_parser(sub) -> argparse.ArgumentParser:
    """The ``report`` subcommand's arguments."""
    rep = add_command(sub, "report", SUMMARY, run)
    rep.add_argument("run_dir")
    rep.add_argument("--out", help="report file (default RUN_DIR/report.html)")
    return rep


def run(args: argparse.Namespace) -> int:
    """Write the report of ``args.run_dir`` (a study's when it holds fragility.json). Returns the exit status."""
    run_dir = Path(args.run_dir)
    if not run_dir.exists():
        raise UsageError(f"run directory {run_dir} does not exist")
    if not run_dir.is_dir():
        raise UsageError(f"run directory {run_dir} is a file; give the directory a run wrote (--out of `housner run`)")
    if not (run_dir / "results.parquet").is_file():
        raise UsageError(f"{run_dir} holds no results.parquet; run `housner run SCENARIO --out {run_dir}` first")
    out = check_output_file(args.out, "--out") if args.out else None
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
