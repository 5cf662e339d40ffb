"""What a new user waits for, cold: the timings the README, the docs' home page and the tutorial quote.

Run from the repository root::

    python benchmarks/bench_first_run.py                 # both commands, once each
    python benchmarks/bench_first_run.py --only run      # `housner run elcentro` alone
    python benchmarks/bench_first_run.py --repeat 2

Each command runs in a fresh process with every cache empty, as on a fresh machine after
``pip install -e .``: the result cache (``HOUSNER_CACHE_DIR``), the generated kernels
(``HOUSNER_KERNEL_DIR``) and numba's compiled code (``NUMBA_CACHE_DIR``) each point at a new
temporary folder, so numba compiles the kernels again and every engine simulates every record.

* ``run``: ``housner run elcentro`` (the quick start's first command: the analytic model, MuJoCo and
  PyBullet on 100 motions, the report written), in a temporary output folder.
* ``diagnose``: ``housner diagnose examples/campaigns/pivot-friction`` with the library search (the
  tutorial's step 3, the longest step of the page).

The table gives each command's wall time and the machine (CPU model, cores). The docs quote these
figures; a quoted figure is within 25 % of this measurement on the machine it names.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

COMMANDS = {
    "run": ["run", "elcentro", "-q", "--out", "{tmp}/run"],
    "diagnose": [
        "diagnose",
        "examples/campaigns/pivot-friction",
        "-q",
        "--report",
        "{tmp}/diagnosis.html",
        "--json",
        "{tmp}/diagnosis.json",
    ],
}


def machine() -> str:
    """The CPU model and the cores this process may use."""
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return f"{model}, {cores} cores"


def cold(name: str) -> float:
    """Wall time [s] of one command with every cache empty."""
    with tempfile.TemporaryDirectory(prefix="housner-cold-") as tmp:
        env = dict(os.environ)
        for var in ("HOUSNER_CACHE_DIR", "HOUSNER_KERNEL_DIR", "NUMBA_CACHE_DIR"):
            env[var] = str(Path(tmp) / var.lower())
        cmd = [sys.executable, "-m", "housner.cli", *(a.format(tmp=tmp) for a in COMMANDS[name])]
        t0 = time.perf_counter()
        res = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        if res.returncode not in (0, 1):  # 1: a verdict or a diagnosis may say FAIL; the time still counts
            sys.exit(f"bench_first_run: {' '.join(cmd)} exited {res.returncode}:\n{res.stderr[-2000:]}")
    return wall


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", choices=sorted(COMMANDS), help="one command only")
    ap.add_argument("--repeat", type=int, default=1, help="runs of each command (the table gives each)")
    args = ap.parse_args(argv)
    if args.repeat < 1:
        ap.error(f"--repeat must be at least 1, got {args.repeat}")
    print(f"machine: {machine()}; every cache empty; {time.strftime('%Y-%m-%d')}")
    for name in [args.only] if args.only else list(COMMANDS):
        times = [cold(name) for _ in range(args.repeat)]
        shown = ", ".join(f"{t:.0f} s ({t / 60:.1f} min)" for t in times)
        print(f"{name:9s} housner {' '.join(COMMANDS[name][:2])}: {shown}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
