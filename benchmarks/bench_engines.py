"""Speed of each registered engine on the seed's ground motions, against the analytic model in the same run.

Run from the repository root::

    python benchmarks/bench_engines.py                         # every engine, 10 motions, 1 process
    python benchmarks/bench_engines.py --engines mujoco --n 100 --processes 2
    python benchmarks/bench_engines.py --engines mujoco --settings '{"timestep": 2.5e-4, "solref": [5e-4, 1]}'
    python benchmarks/bench_engines.py --scenario elcentro-strong --n 100 --processes 2   # the strong ensemble

Besides the speed, each engine's free-rocking r error is measured at release
amplitudes 0.005-0.9 alpha (1 ms samples, :data:`R_AMPLITUDES`), and the table
gives the largest amplitude at which it departs from Housner's r by more than
1 % (``r>1% below``: "-" when it never does): the small-amplitude limit of the
engine's contact, where its impacts count for less than the analytic model's.

Motions: the first ``--n`` of the ``elcentro`` scenario (Rezaeian & Der
Kiureghian motions fitted to El Centro 1940 NS, seed 2017, at model scale,
time compressed by sqrt(10)), built by ``housner.scenarios.catalogue.scenario``; the seed
specimen. Each engine runs once on a short record first (compilation, model
building), then on all motions, whole-run timed: wall time, process CPU time
(``--processes 1``) and simulated time. The baseline is the analytic Housner
engine on the same motions in the same run; the table gives each engine's
wall time as a multiple of it.

Targets (issue): the 100-motion ensemble in < 20 s for MuJoCo and < 90 s for
PyBullet on 2 cores, set on the published model's motions (``--model rdk2010``);
the scenario's matched motions are 21 % longer (18.1 s against 15.0 s at model
scale), at about the same cost per simulated second.
The last columns project the measured rates (wall, and process CPU) onto 100
such motions on ``--target-processes`` cores, assuming perfect scaling;
run with ``--n 100 --processes 2`` to measure it directly.
Timings on a shared machine are noisy; the CPU projection is less so, and
``--repeat K`` keeps each engine's fastest of K whole runs (wall, with that
run's CPU).

MuJoCo's figures (2026-11-21, a shared 2-core machine) are in
``engines/models/README.md``, contact tuning and CHANGELOG.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from housner import GroundMotion, Specimen  # noqa: E402
from housner.engines import ENGINES, get_engine  # noqa: E402
from housner.errors import EngineUnavailable  # noqa: E402
from housner.free_vibration.impacts import IMPACT_RESOLUTION, resolved_impact_count  # noqa: E402
from housner.scenarios.motions.build import build_motions
from housner.scenarios.runs.chaos import measure_engine_errors, rms  # noqa: E402

#: Release amplitudes theta0 / alpha [-] of the r-error scan, small to large.
R_AMPLITUDES = (0.005, 0.01, 0.02, 0.03, 0.05, 0.07, 0.1, 0.15, 0.2, 0.3, 0.5, 0.7, 0.9)
#: A finer resolution of the shared impact detector [-] (alpha), to separate the analytic model's rest-rule
#: tail (impacts after half-cycles below it) from the small rocking an engine's contact really loses.
FINE_RESOLUTION = 0.001
#: |r error| that counts as a departure [-].
R_DEPARTURE = 0.01


def r_departure(name: str, settings: dict, specimen: Specimen) -> dict:
    """The engine's r error at :data:`R_AMPLITUDES` and the largest amplitude where it exceeds 1 %."""
    err = measure_engine_errors(get_engine(name, **settings), specimen, dt=1e-3, amplitudes=R_AMPLITUDES)
    bad = [a for a, e in zip(R_AMPLITUDES, err.r_rel_errors, strict=True) if not abs(e) <= R_DEPARTURE]
    return {
        "r_rel_errors": dict(zip(R_AMPLITUDES, err.r_rel_errors, strict=True)),
        "r_departs_below": max(bad) if bad else 0.0,
        "eps_r": rms([e for a, e in zip(R_AMPLITUDES, err.r_rel_errors, strict=True) if a >= 0.2]),
    }


def chaos_impacts(specimen: Specimen, motions: list[GroundMotion], eps_r: float) -> tuple[int, int]:
    """Impacts >= IMPACT_RESOLUTION of the analytic model with r x (1 -+ eps_r): what chaos alone moves the count by."""
    out = []
    for sign in (-1.0, 1.0):
        eng = get_engine("housner", r=specimen.r_housner * (1.0 + sign * eps_r))
        out.append(sum(resolved_impact_count(r) for r in eng.simulate_many(specimen, motions)))
    return min(out), max(out)


def seed_motions(n: int, model: str | None = None, scenario: str = "elcentro") -> list[GroundMotion]:
    """The first ``n`` motions of the seed study (scenario ``elcentro``, or ``scenario``), at model scale.

    ``model`` overrides the scenario's RDK model ("matched", or "rdk2010": the published
    model, whose weaker motions the first speed targets were set on).
    """
    from housner.scenarios.catalogue.scenario import load_scenario

    scen = load_scenario(scenario)
    if model is not None:
        scen.motions = {**scen.motions, "model": model}
    motions, _ = build_motions(scen, n)
    return motions


def _run(name: str, settings: dict, specimen: Specimen, motions: list[GroundMotion]) -> tuple[float, int, int, int]:
    """Simulate all motions with one engine; CPU seconds, overturns, impacts as the engine counts them, and
    impacts after a half-cycle peak of at least IMPACT_RESOLUTION alpha (the same detector for every engine)."""
    eng = get_engine(name, **settings)
    c0 = time.process_time()
    resps = eng.simulate_many(specimen, motions)
    cpu = time.process_time() - c0
    resolved = sum(resolved_impact_count(r) for r in resps)
    fine = sum(resolved_impact_count(r, FINE_RESOLUTION) for r in resps)
    return cpu, sum(r.overturned for r in resps), sum(r.n_impacts for r in resps), resolved, fine


def time_engine(
    name: str, settings: dict, specimen: Specimen, motions: list[GroundMotion], processes: int, repeat: int = 1
) -> dict:
    """Whole-run timing of one engine on ``motions`` (after a warm-up run); the fastest of ``repeat`` runs."""
    runs = [_time_once(name, settings, specimen, motions, processes) for _ in range(max(1, repeat))]
    best = min(runs, key=lambda r: r["wall_s"])
    best["repeats"] = len(runs)
    best["all_wall_s"] = [r["wall_s"] for r in runs]
    return best


def _time_once(name: str, settings: dict, specimen: Specimen, motions: list[GroundMotion], processes: int) -> dict:
    """One whole-run timing of one engine on ``motions`` (after a warm-up run)."""
    warm = GroundMotion.free_vibration(0.5 * specimen.alpha, 0.5, dt=motions[0].dt)
    get_engine(name, **settings).simulate(specimen, warm)
    w0 = time.perf_counter()
    if processes == 1:
        cpu, n_over, n_imp, n_res, n_fine = _run(name, settings, specimen, motions)
    else:
        chunks = [motions[i::processes] for i in range(processes)]
        with ProcessPoolExecutor(processes) as pool:
            # warm each worker, then time the whole ensemble
            list(
                pool.map(_run, [name] * processes, [settings] * processes, [specimen] * processes, [[warm]] * processes)
            )
            w0 = time.perf_counter()
            parts = list(pool.map(_run, [name] * processes, [settings] * processes, [specimen] * processes, chunks))
        cpu = sum(p[0] for p in parts)
        n_over = sum(p[1] for p in parts)
        n_imp = sum(p[2] for p in parts)
        n_res = sum(p[3] for p in parts)
        n_fine = sum(p[4] for p in parts)
    wall = time.perf_counter() - w0
    sim = sum(m.duration for m in motions)
    return {
        "engine": name,
        "settings": settings,
        "motions": len(motions),
        "processes": processes,
        "wall_s": wall,
        "cpu_s": cpu,
        "simulated_s": sim,
        "wall_per_sim_s": wall / sim,
        "overturned": n_over,
        "impacts": n_imp,
        "impacts_resolved": n_res,
        "impacts_resolved_fine": n_fine,
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--engines", nargs="*", default=None, help="engine names (default: all registered)")
    ap.add_argument("--n", type=int, default=10, help="number of motions (default 10)")
    ap.add_argument("--processes", type=int, default=1, help="worker processes (default 1)")
    ap.add_argument("--target-processes", type=int, default=2, help="cores of the projection (default 2)")
    ap.add_argument("--settings", default="{}", help="JSON settings for the engines named (not the baseline)")
    ap.add_argument("--repeat", type=int, default=1, help="whole runs per engine; the fastest counts (default 1)")
    ap.add_argument("--json", default=None, help="write the rows as JSON here")
    ap.add_argument("--model", default=None, help="RDK model of the motions: matched (the scenario's) or rdk2010")
    ap.add_argument("--scenario", default="elcentro", help="scenario whose motions to run (default elcentro)")
    args = ap.parse_args(argv)
    names = args.engines or sorted(ENGINES)
    settings = json.loads(args.settings)
    specimen = Specimen.bachmann2017()
    motions = seed_motions(args.n, args.model, args.scenario)
    print(
        f"{len(motions)} motions of {motions[0].duration:.2f} s at dt = {motions[0].dt:.5g} s; "
        f"{args.processes} process(es); specimen {specimen.name}"
    )
    rows = [time_engine("housner", {}, specimen, motions, args.processes, args.repeat)]
    for name in names:
        if name != "housner":
            try:
                rows.append(time_engine(name, settings, specimen, motions, args.processes, args.repeat))
                rows[-1].update(r_departure(name, settings, specimen))
                rows[-1]["chaos_impacts"] = chaos_impacts(specimen, motions, rows[-1]["eps_r"])
            except (ImportError, EngineUnavailable) as e:
                print(f"skipping {name}: {e}")
    base = rows[0]["wall_s"]
    target = args.target_processes
    mean_dur = sum(m.duration for m in motions) / len(motions)
    print(
        f"{'engine':10s} {'wall s':>8s} {'CPU s':>8s} {'x housner':>10s} {'wall/sim s':>11s} {'CPU/sim s':>10s} "
        f"{'overturned':>10s} {'impacts':>8s} {'>=' + format(FINE_RESOLUTION, 'g') + ' a':>9s} "
        f"{'>=' + format(IMPACT_RESOLUTION, 'g') + ' a':>9s} {'r>1% below':>10s}   "
        f"100 motions on {target} cores (from wall / from CPU)"
    )
    for r in rows:
        # ideal scaling: one process's rate is processes x the measured wall rate
        r["projected_100_motions_wall_s"] = r["wall_per_sim_s"] * r["processes"] * 100 * mean_dur / target
        r["projected_100_motions_cpu_s"] = r["cpu_s"] / r["simulated_s"] * 100 * mean_dur / target
        r["ratio_to_housner"] = r["wall_s"] / base if base > 0 else math.inf
        print(
            f"{r['engine']:10s} {r['wall_s']:8.2f} {r['cpu_s']:8.2f} {r['ratio_to_housner']:10.1f} "
            f"{r['wall_per_sim_s']:11.4f} {r['cpu_s'] / r['simulated_s']:10.4f} {r['overturned']:10d} "
            f"{r['impacts']:8d} {r['impacts_resolved_fine']:9d} {r['impacts_resolved']:9d} {_departs(r):>10s}   "
            f"{r['projected_100_motions_wall_s']:8.1f} s / "
            f"{r['projected_100_motions_cpu_s']:6.1f} s"
        )
    print(
        f"impacts after half-cycles >= {IMPACT_RESOLUTION:g} alpha, and what the analytic model counts with its r "
        "perturbed by each engine's RMS r error at 0.2-0.9 alpha (chaos alone):"
    )
    for r in rows[1:]:
        lo, hi = r["chaos_impacts"]
        print(f"  {r['engine']:10s} {r['impacts_resolved']:7d}   analytic with r x (1 -+ {r['eps_r']:.3%}): {lo}-{hi}")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(rows, fh, indent=1)
    return 0


def _departs(row: dict) -> str:
    a = row.get("r_departs_below")
    if a is None:
        return ""
    return f"{a:g} a" if a > 0 else "-"


if __name__ == "__main__":
    raise SystemExit(main())
