"""The diagnosis' verdict matrix on synthetic campaigns from the project's two independent test generators.

Each case is a campaign with a known hidden effect (or none), written by
``tests/campaign_generators.py`` (generator ``a``) or
``tests/independent_campaigns.py`` (generator ``b``, written apart from the
first, with other numerical conventions). Every campaign is diagnosed at each
split seed and judged against what it should give:

* no hidden effect: ``no_misfit`` with a residual ratio of at most 1.25;
* library effects: ``explained``, naming all of them (and no other);
* effects outside the library: ``partly_explained`` or ``unexplained``, with
  the right physical class first.

Usage::

    python scripts/diagnosis_matrix.py --generator b --seeds 0 1 --json matrix-b.json
    python scripts/diagnosis_matrix.py --generator a --cases none restitution

The campaigns are written once under ``--base`` (default ``/tmp/housner-matrix``).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


def _generator(name: str):
    if name == "a":
        import campaign_generators as gen

        cases = {**{k: v[1] for k, v in gen.HIDDEN.items()}, **{k: v[1] for k, v in gen.OUTSIDE.items()}}
        return gen, cases
    import independent_campaigns as gen

    return gen, {k: v[1] for k, v in gen.CASES.items()}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--generator", choices=("a", "b"), default="b")
    ap.add_argument("--cases", nargs="*", help="cases to run (default: all of the generator's)")
    ap.add_argument("--seeds", nargs="*", type=int, default=[0, 1], help="split seeds of the diagnosis (0 1)")
    ap.add_argument("--n-ground", type=int, default=60, help="ground-motion records per campaign (60)")
    ap.add_argument("--base", default="/tmp/housner-matrix", help="where the campaigns are written")
    ap.add_argument("--json", help="write the matrix to this file")
    args = ap.parse_args(argv)

    from matrix import judge

    from housner.scenarios.campaigns.campaign import load_campaign
    from housner.scenarios.diagnosis.diagnose import diagnose

    gen, cases = _generator(args.generator)
    names = args.cases or list(cases)
    rows, right = [], 0
    print(f"{'case':34s} {'seed':>4s} {'status':17s} {'effects':44s} {'ratio':>6s} {'z':>6s} {'ok':>3s} {'time':>6s}")
    for name in names:
        info = gen.cached_campaign(Path(args.base) / args.generator, name, n_ground=args.n_ground)
        camp = load_campaign(info["root"])
        for seed in args.seeds:
            t0 = time.perf_counter()
            diag = diagnose(camp, seed=seed, compare_steps=False)
            el = time.perf_counter() - t0
            ok, why = judge(cases[name], diag)
            right += ok
            v = diag.verdict
            eff = ", ".join(f"{n}({', '.join(f'{k}={x:.4g}' for k, x in p.items())})" for n, p in diag.final.effects)
            print(
                f"{name:34s} {seed:4d} {v.status:17s} {eff or '-':44s} {v.residual.ratio:6.2f} {v.residual.z:6.1f} "
                f"{'yes' if ok else 'NO':>3s} {el:5.0f}s" + (f"  {why}" if why else ""),
                flush=True,
            )
            rows.append(
                {
                    "case": name,
                    "seed": seed,
                    "expected": cases[name],
                    "status": v.status,
                    "effects": [[n, p] for n, p in diag.final.effects],
                    "ratio": v.residual.ratio,
                    "z": v.residual.z,
                    "baseline_ratio": v.baseline.ratio,
                    "next": [c.name for c in v.next],
                    "right": ok,
                    "why": why,
                    "family": diag.settings.floor_family,
                    "seconds": el,
                }
            )
    print(f"right {right} of {len(rows)}")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1, default=str))
    return 0 if right == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
