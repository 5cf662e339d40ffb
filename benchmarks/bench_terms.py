"""Cost of the analytic kernel's terms (housner.effects.terms) against the plain kernel, and their compilation.

Run from the repository root::

    python benchmarks/bench_terms.py                 # 100 records of 16 s at 500 Hz, best of 3
    python benchmarks/bench_terms.py --records 20 --repeat 2 --no-compile

Records: those of ``benchmarks/bench_analytic.py`` (filtered noise, PGA 0.25-0.5 g, the Bachmann et al.
specimen). Every run is serial (``parallel=False``, one core) and whole (``simulate_many``: histories,
impacts, Responses); the figure is the best of ``--repeat`` runs after a warm-up call, so compilation is
excluded and reported apart. The ratio of each case is to a reference run in the same process:

* the same physics through the fast path (parameter vector) and through a term: ``rotational_damping``
  and ``restitution`` give the very same trajectories both ways, so their ratio is the terms machinery's
  own overhead;
* a user moment term (air drag -k w |w|, defined here), pivot friction (a Coulomb term with sticking) and
  a vertical table (a moment that acts at rest, read from a channel) against plain Housner: their physics
  differ (other impacts, other rocking), so the ratio also holds the cost of that physics.

Compilation (``--no-compile`` skips it): a fresh process with an empty kernel directory
(``HOUSNER_KERNEL_DIR``) compiles the serial term kernel of one structure; a second fresh process with the
same directory loads numba's cache instead. Both time the first ``simulate`` call with a term, and the same
for the plain kernel (already cached in the package).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from numba import njit

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmarks.bench_analytic import synthetic_records  # noqa: E402
from housner import G, GroundMotion, Specimen  # noqa: E402
from housner.effects import MomentTerm, TermSet, apply_effects, load_plugin, make_effect  # noqa: E402
from housner.model import simulate_many  # noqa: E402


@njit(cache=True)
def drag_moment(phi, w, t, a, v, s, alpha, p2, q):
    """A user's moment term: quadratic air drag per unit I0, -k w |w| [rad/s^2], q = (k,) [1/rad]."""
    return -q[0] * w * abs(w)


def _first_call(kernel_dir: str) -> dict:
    """In a fresh process: seconds of the first plain call and of the first call with a drag term."""
    code = f"""
import json, sys, time
sys.path.insert(0, {str(ROOT)!r})
t0 = time.perf_counter()
import numpy as np
from housner import GroundMotion, Specimen
from housner.model import simulate, simulate_many
from housner.effects import MomentTerm, TermSet
from benchmarks.bench_terms import drag_moment
t_import = time.perf_counter() - t0
spec = Specimen.bachmann2017()
mo = GroundMotion.free_vibration(0.5 * spec.alpha, 1.0)
t0 = time.perf_counter(); simulate(spec, mo); t_plain = time.perf_counter() - t0
ts = TermSet((MomentTerm(drag_moment, (0.5,), at_rest=False),))
t0 = time.perf_counter(); simulate(spec, mo, terms=ts); t_terms = time.perf_counter() - t0
t0 = time.perf_counter(); simulate_many(spec, [mo, mo]); t_plain_par = time.perf_counter() - t0
t0 = time.perf_counter(); simulate_many(spec, [mo, mo], terms=ts); t_terms_par = time.perf_counter() - t0
print(json.dumps({{"import": t_import, "plain": t_plain, "terms": t_terms, "plain_par": t_plain_par,
                  "terms_par": t_terms_par}}))
"""
    env = {**os.environ, "HOUSNER_KERNEL_DIR": kernel_dir}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--records", type=int, default=100, help="number of synthetic records (default 100)")
    ap.add_argument("--duration", type=float, default=16.0, help="record length [s] (default 16)")
    ap.add_argument("--repeat", type=int, default=3, help="timed runs per case (the best is reported)")
    ap.add_argument("--no-compile", action="store_true", help="skip the compile-time measurement (two processes)")
    args = ap.parse_args(argv)

    if not args.no_compile:
        with tempfile.TemporaryDirectory(prefix="housner-bench-kernels-") as d:
            cold, warm = _first_call(d), _first_call(d)
        print("first call in a fresh process [s]     plain kernel   kernel with a moment term  (parallel batch)")
        for label, r in (("empty kernel directory (compiles)", cold), ("same directory again (numba cache)", warm)):
            par = f"({r['plain_par']:.2f}, {r['terms_par']:.2f})"
            print(f"  {label:34s}  {r['plain']:12.2f}   {r['terms']:12.2f}   {par}")
        print(f"  (importing housner and numpy: {warm['import']:.2f} s; the plain kernel is always in numba's cache)")

    spec = Specimen.bachmann2017()
    acc, dt = synthetic_records(args.records, 2017, duration=args.duration)
    rng = np.random.default_rng(5)
    motions = []
    for i, a in enumerate(acc):
        # a vertical channel for the vertical table: 0.3 x the horizontal input, smoothed over 40 ms, lagged
        av = 0.3 * np.convolve(a, np.ones(20) / 20, mode="same") * rng.uniform(0.5, 1.0)
        motions.append(GroundMotion(a, dt, name=f"synthetic-{i:03d}", channels={"ground_acc_vertical": av}))
    for f in ("pivot_friction", "vertical_table"):
        load_plugin(ROOT / "examples" / "effects" / f"{f}.py")
    print(f"\n{len(motions)} records of {motions[0].duration:g} s at {1 / dt:g} Hz, one core, best of {args.repeat}")

    def plan(effects, prefer_terms=True):
        pl = apply_effects(spec, motions[0], effects, prefer_terms=prefer_terms)
        return pl.params, pl.terms

    def run(prm, terms):
        simulate_many(spec, motions[:2], params=prm, terms=terms, parallel=False)  # warm-up (compile)
        best, out = np.inf, None
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            out = simulate_many(spec, motions, params=prm, terms=terms, parallel=False)
            best = min(best, time.perf_counter() - t0)
        return best, out

    housner = plan([], False)
    drag = (housner[0], TermSet((MomentTerm(drag_moment, (0.5,), at_rest=False),)))
    cases = [
        ("plain Housner", housner, None),
        ("damping c=0.3, fast path", plan([make_effect("rotational_damping", c=0.3)], False), None),
        ("damping c=0.3 as a moment term", plan([make_effect("rotational_damping", c=0.3)]), 1),
        ("restitution r=0.9, fast path", plan([make_effect("restitution", r=0.9)], False), None),
        ("restitution r=0.9 as an impact term", plan([make_effect("restitution", r=0.9)]), 3),
        ("user moment term: drag k=0.5", drag, 0),
        ("pivot friction M_f=0.05 N m", plan([make_effect("pivot_friction", moment=0.05)]), 0),
        ("vertical table (channel)", plan([make_effect("vertical_table")]), 0),
    ]
    times, outs = [], []
    print(f"{'case':38s} {'time [s]':>9s} {'ratio':>7s}  vs                              impacts  overturned")
    for label, (prm, terms), ref in cases:
        t, out = run(prm, terms)
        times.append(t)
        outs.append(out)
        ratio = "" if ref is None else f"{t / times[ref]:7.2f}"
        against = "" if ref is None else cases[ref][0]
        n_imp = sum(r.n_impacts for r in out)
        n_over = sum(r.overturned for r in out)
        print(f"{label:38s} {t:9.3f} {ratio:>7s}  {against:30s} {n_imp:8d} {n_over:10d}")
        if ref in (1, 3):
            same = all(np.array_equal(a.theta, b.theta) for a, b in zip(outs[ref], out, strict=True))
            print(f"{'':38s} same histories as the fast path, bit for bit: {same}")
    print(f"(peak accelerations {np.min(np.abs(acc).max(axis=1)) / G:.2f}-{np.max(np.abs(acc).max(axis=1)) / G:.2f} g)")


if __name__ == "__main__":
    main()
