"""Calibration of the diagnosis' correct-model floor on campaigns its code did not generate.

Plain-Housner campaigns (no hidden effect) from the two independent test
generators (``tests/campaign_generators.py``, ``a``, and
``tests/independent_campaigns.py``, ``b``, with its controls written with the
input held over each sample and with noise on the acceleration channel) are
written for several campaign seeds and judged by the verdict alone (no
effect searched): a correct model must give ``no_misfit``, a residual ratio
within [0.8, 1.25] and z < 3. The script prints each campaign's ratio, z and
the floor's family, and the distribution of the ratios.

Usage::

    python scripts/floor_calibration.py --campaigns 8 --json calibration.json
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

CONTROLS = {"a": ("none",), "b": ("none", "none_held", "none_acc_noise")}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--campaigns", type=int, default=8, help="campaign seeds per control (8)")
    ap.add_argument("--n-ground", type=int, default=60, help="ground-motion records per campaign (60)")
    ap.add_argument("--base", default="/tmp/housner-calibration")
    ap.add_argument("--json", help="write every campaign's figures to this file")
    args = ap.parse_args(argv)

    import campaign_generators
    import independent_campaigns

    from housner.scenarios.campaigns.campaign import load_campaign
    from housner.scenarios.diagnosis.diagnose import diagnose

    gens = {"a": campaign_generators, "b": independent_campaigns}
    rows = []
    print(
        f"{'gen':3s} {'case':16s} {'seed':>4s} {'status':12s} {'ratio':>6s} {'gm':>6s} {'z':>6s} {'family':7s} "
        f"{'time':>5s}"
    )
    for g, cases in CONTROLS.items():
        for case in cases:
            for seed in range(args.campaigns):
                info = gens[g].cached_campaign(Path(args.base) / g, case, n_ground=args.n_ground, seed=seed)
                t0 = time.perf_counter()
                d = diagnose(load_campaign(info["root"]), effects=[], compare_steps=False)
                v = d.verdict
                gm = v.residual.groups["ground_motion"].ratio if "ground_motion" in v.residual.groups else float("nan")
                row = {
                    "generator": g,
                    "case": case,
                    "seed": seed,
                    "status": v.status,
                    "ratio": v.residual.ratio,
                    "gm_ratio": gm,
                    "z": v.residual.z,
                    "family": d.settings.floor_family,
                }
                rows.append(row)
                print(
                    f"{g:3s} {case:16s} {seed:4d} {v.status:12s} {v.residual.ratio:6.2f} {gm:6.2f} "
                    f"{v.residual.z:6.1f} {row['family']:7s} {time.perf_counter() - t0:4.0f}s",
                    flush=True,
                )
    r = np.array([x["ratio"] for x in rows])
    inside = np.mean((r >= 0.8) & (r <= 1.25))
    ok = sum(x["status"] == "no_misfit" and x["z"] < 3 for x in rows)
    print(
        f"ratios: median {np.median(r):.2f}, 10-90 % {np.percentile(r, 10):.2f}-{np.percentile(r, 90):.2f}, "
        f"min {r.min():.2f}, max {r.max():.2f}; within [0.8, 1.25]: {inside:.0%}; no_misfit with z < 3: "
        f"{ok} of {len(rows)}"
    )
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
