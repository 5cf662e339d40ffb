"""Speed of the real-data loop: the ASU granite tests (SP1) from the shared files to the outcome verdict.

Run from the repository root (the data lie in ``../shared/data/asu-granite`` beside the checkout)::

    python benchmarks/bench_real_tests.py
    python benchmarks/bench_real_tests.py --data PATH --folds 5 --seed 0

Targets (issue 36), on 2 cores: the scan mesh to the equivalent planar block in < 5 s; the import and the
whole diagnosis in < 60 s together. Timed stages, each in this process:

1. ``specimen``: :func:`housner.scan.specimen_from_mesh` on SP1.obj (its bracket and azimuth sweep included);
2. ``import``: :func:`housner.scenarios.campaigns.asu.import_asu` into a temporary folder (490 record files);
3. ``load``: :func:`housner.scenarios.campaigns.campaign.load_campaign` of that campaign;
4. ``diagnose``: :func:`housner.scenarios.diagnosis.outcomes.outcome_diagnosis.diagnose_outcomes` (every ensemble, the
folds,
   the baselines, the floor).

Baseline in the same run: one pass of the plain analytic model over the 490 records
(:func:`housner.model.theta_max_many`, once compiled); the ratio says how many such passes the diagnosis
costs. The scores of the diagnosis are printed too, so the figures of docs/results.md come from here.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
DATA = HERE.parents[1] / "shared" / "data" / "asu-granite"
TARGET_SPECIMEN_S = 5.0
TARGET_LOOP_S = 60.0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(DATA), help=f"the ASU data folder ({DATA})")
    ap.add_argument("--folds", type=int, default=5)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    data = Path(args.data)
    if not (data / "index.csv").is_file():
        print(f"no ASU data at {data} (index.csv missing): see docs/how-to/real-shake-table-tests.md", file=sys.stderr)
        return 2
    from housner.model import theta_max_many
    from housner.scan import specimen_from_mesh
    from housner.scenarios.campaigns.asu import import_asu
    from housner.scenarios.campaigns.campaign import load_campaign
    from housner.scenarios.diagnosis.outcomes.outcome_diagnosis import diagnose_outcomes

    times = {}
    t = time.perf_counter()
    specimen_from_mesh(data / "SP1.obj", azimuth=0.0)
    times["specimen"] = time.perf_counter() - t
    with tempfile.TemporaryDirectory(prefix="housner-asu-") as tmp:
        t = time.perf_counter()
        import_asu(data, Path(tmp) / "sp1")
        times["import"] = time.perf_counter() - t
        t = time.perf_counter()
        campaign = load_campaign(Path(tmp) / "sp1")
        times["load"] = time.perf_counter() - t
    accs = [r.motion.acc for r in campaign.outcomes]
    dts = [r.dt for r in campaign.outcomes]
    params = campaign.scan.rocking_params()
    theta_max_many(campaign.specimen, accs[:2], dts[:2], params=params)  # compiled before the baseline is timed
    t = time.perf_counter()
    theta_max_many(campaign.specimen, accs, dts, params=params)
    times["one_pass"] = time.perf_counter() - t
    t = time.perf_counter()
    d = diagnose_outcomes(campaign, folds=args.folds, seed=args.seed)
    times["diagnose"] = time.perf_counter() - t
    loop = times["import"] + times["load"] + times["diagnose"]
    print(f"{len(campaign.outcomes)} records; specimen {times['specimen']:.2f} s (target < {TARGET_SPECIMEN_S:g} s)")
    print(
        f"import {times['import']:.1f} s, load {times['load']:.1f} s, diagnose {times['diagnose']:.1f} s: "
        f"{loop:.1f} s in all (target < {TARGET_LOOP_S:g} s)"
    )
    print(
        f"baseline: one pass of the plain model over every record {times['one_pass']:.3f} s; the diagnosis costs "
        f"{times['diagnose'] / times['one_pass']:.0f} passes"
    )
    print()
    from housner.reports.diagnosis.outcome_text import outcome_summary

    print(outcome_summary(d))
    rows = [(s.name, s.scores) for s in d.steps] + list(d.baselines.items())
    print(f"\n{'model':32s} {'accuracy':>22s} {'F1':>22s} {'log loss':>22s}")
    for name, sc in rows:
        cells = " ".join(
            f"{sc[k]:7.3f} [{sc[k + '_ci'][0]:.3f}, {sc[k + '_ci'][1]:.3f}]" for k in ("accuracy", "f1", "log_loss")
        )
        print(f"{name:32s} {cells}")
    return 0 if times["specimen"] < TARGET_SPECIMEN_S and loop < TARGET_LOOP_S else 1


if __name__ == "__main__":
    sys.exit(main())
