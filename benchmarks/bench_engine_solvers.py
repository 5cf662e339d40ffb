"""CPU time of the engines' solver defaults of 2026-11-26/27 against the settings they replaced, in the same run.

Run from the repository root::

    python benchmarks/bench_engine_solvers.py                    # 6 motions, 3 rounds
    python benchmarks/bench_engine_solvers.py --n 10 --rounds 5 --engines drake

Three engines changed solver at the accuracy-cost frontier (``housner frontier ENGINE``; the tuner's
checks and the per-record agreement decided, this measures only the cost):

* Drake: TAMSI at 1/8 ms on 2.5e9 N/m, was SAP at 1/4 ms on 5e8 N/m (``contact_approximation``,
  ``timestep``, ``stiffness``);
* OpenSees: Krylov-Newton, was Newton (``algorithm``, 2026-11-26); a node-to-node contact element,
  was a friction bearing (``contact_element``, 2026-11-27): both changes together, and the contact
  element alone;
* DART: its own collision detector, was FCL (``collision_detector``).

Motions: the first ``--n`` of ``elcentro-strong`` (the six-engine run's, 42 % of which overturn
the block in the analytic model, so records stop at different times). In each round the old and the
new settings run the same motions one after the other in this process (the order alternating from
round to round), timed by process CPU time; the ratio new / old is taken round by round, so a
machine whose speed drifts moves both. Printed: each engine's CPU s per simulated s, old and new,
and the median ratio with its range over the rounds.

Measured 2026-11-26 (6 motions, 3 rounds, a 2-core machine otherwise idle): Drake 0.387 (0.365-0.399),
OpenSees 0.696 (0.617-0.699), DART 0.931 (0.906-0.952). Measured 2026-11-27 (the same way), OpenSees against
Newton and the bearing 0.530 (0.523-0.533), against the bearing alone 0.762 (0.757-0.768).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from housner.engines import get_engine  # noqa: E402
from housner.scenarios.catalogue.scenario import load_scenario  # noqa: E402
from housner.scenarios.motions.build import build_motions  # noqa: E402

#: (engine, the settings its new defaults replaced), in the order measured.
REPLACED = (
    ("drake", {"contact_approximation": "sap", "timestep": 2.5e-4, "stiffness": 5e8}),
    ("opensees", {"algorithm": "Newton", "contact_element": "flatSliderBearing"}),
    ("opensees", {"contact_element": "flatSliderBearing"}),
    ("dart", {"collision_detector": "fcl"}),
)


def cpu_per_sim_second(engine, specimen, motions) -> float:
    """Process CPU seconds per simulated second of ``engine`` over ``motions`` (up to each overturn)."""
    t0, simulated = time.process_time(), 0.0
    for m in motions:
        res = engine.simulate(specimen, m)
        simulated += res.overturn_time if res.overturned else (m.n - 1) * m.dt
    return (time.process_time() - t0) / simulated


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    names = list(dict.fromkeys(name for name, _ in REPLACED))
    ap.add_argument("--engines", nargs="*", default=names, help="engines (default: all three)")
    ap.add_argument("--n", type=int, default=6, help="motions of elcentro-strong (default 6)")
    ap.add_argument("--rounds", type=int, default=3, help="rounds of old and new (default 3)")
    args = ap.parse_args(argv)
    sc = load_scenario("elcentro-strong")
    motions, _ = build_motions(sc, args.n)
    print(f"{'engine':10s} {'old CPU s/s':>12s} {'new CPU s/s':>12s} {'new/old':>8s} {'range':>14s}  old settings")
    for name, replaced in REPLACED:
        if name not in args.engines:
            continue
        old, new = get_engine(name, **replaced), get_engine(name)
        for e in (old, new):
            e.simulate(sc.specimen, motions[0])  # model building, first-call costs
        olds, news = [], []
        for k in range(args.rounds):
            pair = (old, new) if k % 2 == 0 else (new, old)
            cost = {id(e): cpu_per_sim_second(e, sc.specimen, motions) for e in pair}
            olds.append(cost[id(old)])
            news.append(cost[id(new)])
        ratios = [b / a for a, b in zip(olds, news, strict=True)]
        print(
            f"{name:10s} {statistics.median(olds):12.4f} {statistics.median(news):12.4f} "
            f"{statistics.median(ratios):8.3f} {min(ratios):6.3f}-{max(ratios):.3f}  {replaced}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
