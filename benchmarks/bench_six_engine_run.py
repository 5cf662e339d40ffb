"""The six-engine ``housner run elcentro-strong`` of this checkout against the same command at another commit.

Issue 25's target: the run took 7.2 min on 2 cores when the issue was filed (main at 6230d22, 2026-11-26),
and should take under 4 min, a ratio of 0.556. The machines this is measured on change speed by 10-20 %
from hour to hour, so the figure is a ratio of two whole processes run in turn, for ``farm-bench --vs``::

    python benchmarks/bench_six_engine_run.py setup --dir /tmp/housner-6230d22            # once: 2-3 min
    farm-bench -n 2 --warmup 0 --timeout 3500 -- python benchmarks/bench_six_engine_run.py run \\
        --vs 'python benchmarks/bench_six_engine_run.py run --baseline /tmp/housner-6230d22'

``setup`` checks the commit (``--ref``, default 6230d22) out into a git worktree at ``--dir`` with its own
virtual environment (the package and every engine's extra, the same engine versions as pip resolves for
this checkout) and runs it once on 2 motions, so that numba's compiled kernels are cached before timing.
``run`` is one user's first run of the scenario: ``housner run elcentro-strong --engines
housner,mujoco,pybullet,dart,opensees,drake`` with an empty result cache (a fresh ``HOUSNER_CACHE_DIR``,
so the engines' free-rocking errors and the report's stored figures are computed too), the report
written, on all CPUs. It prints the command's own summary (each engine's time) and its wall time.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ENGINES = "housner,mujoco,pybullet,dart,opensees,drake"
FILED_AT = "6230d22"  # main when issue 25 was filed (7.2 min)


def _housner(checkout: Path) -> Path:
    """The ``housner`` command of ``checkout``'s environment (this checkout: the running interpreter's)."""
    if checkout == ROOT:
        return Path(sys.executable).with_name("housner")
    return checkout / ".venv" / "bin" / "housner"


def _six_engine_run(cmd: Path, tmp: str, *extra: str, **kwargs) -> subprocess.CompletedProcess:
    """``cmd run elcentro-strong`` on the six engines, its run folder and an empty result cache under ``tmp``."""
    argv = [str(cmd), "run", "elcentro-strong", "--engines", ENGINES, "-q", "--out", f"{tmp}/run", *extra]
    return subprocess.run(argv, env={**os.environ, "HOUSNER_CACHE_DIR": f"{tmp}/cache"}, **kwargs)


def setup(ref: str, where: Path) -> int:
    if not (where / ".git").exists():
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(where), ref], check=True)
    cmd = _housner(where)
    if not cmd.exists():
        subprocess.run([sys.executable, "-m", "venv", str(where / ".venv")], check=True)
        pip = [str(where / ".venv" / "bin" / "python"), "-m", "pip", "install", "-q"]
        subprocess.run([*pip, "-e", f"{where}[all]"], check=True)
    with tempfile.TemporaryDirectory() as tmp:  # numba compiles the analytic kernels on their first run
        _six_engine_run(cmd, tmp, "--n-motions", "2", check=True, stdout=subprocess.DEVNULL)
    print(f"baseline {ref} ready: {cmd}")
    return 0


def run(checkout: Path) -> int:
    cmd = _housner(checkout)
    if not cmd.exists():
        print(f"bench_six_engine_run: error: no housner command at {cmd}; run `setup` first", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        done = _six_engine_run(cmd, tmp)
        wall = time.perf_counter() - t0
    print(f"{checkout}: {wall:.1f} s wall, exit status {done.returncode}")
    return done.returncode


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="what", required=True)
    s = sub.add_parser("setup", help="a worktree and virtual environment of the baseline commit")
    s.add_argument("--ref", default=FILED_AT, help=f"the baseline commit (default {FILED_AT})")
    s.add_argument("--dir", required=True, type=Path, help="where to check it out")
    r = sub.add_parser("run", help="one six-engine run, empty cache")
    r.add_argument("--baseline", type=Path, help="a checkout made by `setup` (default: this one)")
    args = ap.parse_args(argv)
    if args.what == "setup":
        return setup(args.ref, args.dir.resolve())
    return run(args.baseline.resolve() if args.baseline else ROOT)


if __name__ == "__main__":
    sys.exit(main())
