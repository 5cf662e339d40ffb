"""Benchmark: a 100 x 100 rocking spectrum (seed Figure 2) against a naive loop.

Target: the 100 x 100 grid in under 10 s on 2 cores.

The naive baseline is what one would write without this module: a Python loop
over :func:`housner.simulate`, one call per grid point, each pulse padded with
30/p of free rocking so that theta_max has been reached (the default of
:func:`housner.pulse_response.pulses.ricker` when p is given). It is timed on a random
subset of the grid and extrapolated; its results are also compared with the
spectrum's on that subset.

Usage::

    python benchmarks/bench_spectra.py --out spectrum.png
    python benchmarks/bench_spectra.py --pulse one_sine --n 50 --baseline 50 --threads 2
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100, help="grid points per axis (default 100)")
    ap.add_argument("--pulse", default="symmetric_ricker", help="symmetric_ricker, antisymmetric_ricker or one_sine")
    ap.add_argument("--baseline", type=int, default=100, help="grid points timed with the naive loop (default 100)")
    ap.add_argument("--threads", type=int, default=None, help="numba threads (default: all)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the baseline subset")
    ap.add_argument("--out", default=None, help="save the spectrum figure here (PNG, PDF, ...)")
    args = ap.parse_args(argv)

    import matplotlib

    matplotlib.use("Agg")
    import numba

    from housner import G, Specimen
    from housner.model import simulate
    from housner.pulse_response import pulses
    from housner.pulse_response.spectra import PULSES, pulse_motion, rocking_spectrum

    spec = Specimen.bachmann2017()
    W = np.linspace(1.0, 12.0, args.n)
    A = np.linspace(0.5, 12.0, args.n)
    threads = args.threads or numba.get_num_threads()

    t0 = time.perf_counter()
    rocking_spectrum(spec, args.pulse, W[:2], A[:2], n_jobs=args.threads)  # compile / load the kernel
    t_warm = time.perf_counter() - t0

    t0 = time.perf_counter()
    s = rocking_spectrum(spec, args.pulse, W, A, n_jobs=args.threads)
    t_spec = time.perf_counter() - t0

    # naive baseline on a random subset
    rng = np.random.default_rng(args.seed)
    idx = rng.choice(W.size * A.size, size=min(args.baseline, W.size * A.size), replace=False)
    p = spec.p
    t_base = 0.0
    diffs, flag_mismatch = [], 0
    for k in idx:
        i, j = divmod(int(k), W.size)
        w, a = W[j], A[i]
        dt = pulse_motion(args.pulse, 1.0, w * p, p).dt
        a_p = a * G * spec.tan_alpha
        t1 = time.perf_counter()
        if args.pulse == "one_sine":
            g = pulses.one_sine(a_p, w * p, dt=dt, p=p)
        else:
            g = pulses.ricker(a_p, w * p, kind=PULSES[args.pulse], dt=dt, p=p)
        res = simulate(spec, g)
        t_base += time.perf_counter() - t1
        mine = s.theta_max_over_alpha[i, j]
        if res.overturned != bool(s.overturned[i, j]):
            flag_mismatch += 1
        elif np.isfinite(mine):
            diffs.append(abs(res.theta_max_over_alpha - mine))
    t_base_full = t_base / idx.size * W.size * A.size

    print(f"rocking spectrum {args.pulse}, {args.n} x {args.n} grid, {threads} numba threads")
    print(f"  compile/load (first call): {t_warm:8.2f} s")
    print(f"  spectrum {args.n}x{args.n}:          {t_spec:8.2f} s   (target < 10 s)")
    print(
        f"  naive loop over simulate: {t_base:8.2f} s for {idx.size} points -> "
        f"{t_base_full:8.1f} s extrapolated to {W.size * A.size}"
    )
    print(f"  speed-up: {t_base_full / t_spec:8.1f} x")
    print(
        f"  agreement on the subset: max |d theta_max/alpha| = {max(diffs, default=0.0):.2e} "
        f"over {len(diffs)} finite points, {flag_mismatch} overturn-flag mismatches"
    )
    print(f"  overturned: {int(s.overturned.sum())} of {s.overturned.size} grid points")
    if args.out:
        ax = s.plot()
        ax.figure.savefig(args.out, dpi=120)
        print(f"  figure: {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
