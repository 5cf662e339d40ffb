"""Speed and memory of studies ([study] scenarios), against plain loops in the same run.

Run from the repository root::

    python benchmarks/bench_study.py                       # both parts
    python benchmarks/bench_study.py --part scale          # 10 000 analytic records
    python benchmarks/bench_study.py --part dask --engine mujoco --n 24

``scale``: a study of 20 stripes x 5 sizes x 100 motions = 10 000 records of
the analytic model (the El Centro matched ensemble of the seed), through the
study runner with 2 worker processes and an empty cache: motions, every record
(cached on disk as it finishes), the fragility fits with 1000 bootstrap
resamples, and the directory. Target (issue): < 60 s on 2 cores. Baseline: the
same 10 000 records simulated in one loop of ``simulate_many`` in this process,
nothing else; the second ratio adds to the loop the fit of the ensemble's model
(matched RDK), which the study pays once before its first record. Memory: the peak resident
size of the study's process for 2 000 records (one size) and for 10 000 (five): flat means the second is not five
times the first (histories are off, one size is in memory at a time). Disk: the CPU time to create an empty file
in the study's temporary folder just before the 10 000-record study, which writes one cache entry (one new file)
per record. It is a property of the disk at that moment, not of the runner: on an ext4 file system without a
journal, creating a file first scans the inodes deleted in the last few minutes in its block group
(``recently_deleted``), so that after a run (this benchmark's own previous one, a test suite) removed thousands of
files a creation costs 0.5-1 ms of CPU instead of 20-50 us, up to 10 s of the study's CPU that the loop never pays.

``dask``: an engine-bound study (``--engine``, default MuJoCo; 4 stripes x 1 size
x ``--n`` motions) on a local Dask cluster of one worker, then of two (one
thread each), cache off. Target (issue): two workers >= 1.8 x faster.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

ROOT = Path(__file__).resolve().parents[1]

SCENARIO = """name = "bench-study"
[specimen]
preset = "bachmann2017"
[motions]
source = "rdk"
record = "elcentro"
model = "matched"
n = {n}
seed = 2017
prototype_height = 5.0
[engines]
names = {engines}
[study]
levels = {levels}
prototype_heights = {heights}
"""


def _write(tmp: Path, n: int, engines: list[str], levels: list[float], heights: list[float]) -> Path:
    p = tmp / "bench-study.toml"
    p.write_text(SCENARIO.format(n=n, engines=json.dumps(engines), levels=levels, heights=heights))
    return p


def _child_study(toml: str, out: str, cache: str, jobs: int) -> None:
    """Run one study in this (fresh) process and print its wall time and peak RSS as JSON."""
    from housner.scenarios.execution import RunOptions
    from housner.scenarios.studies.study import run_study

    t0 = time.perf_counter()
    res = run_study(toml, out=out, options=RunOptions(jobs=jobs, cache_dir=cache, progress=False))
    wall = time.perf_counter() - t0
    rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        json.dumps(
            {
                "wall_s": wall,
                "records": len(res.results),
                "peak_rss_mb": rss_mb,
                "failed": int((res.results.status != "ok").sum()),
            }
        )
    )


def _run_child(toml: Path, out: Path, cache: Path, jobs: int) -> dict:
    code = (
        f"import sys; sys.path.insert(0, {str(ROOT)!r}); from benchmarks.bench_study import _child_study; "
        f"_child_study({str(toml)!r}, {str(out)!r}, {str(cache)!r}, {jobs})"
    )
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True)
    return json.loads(p.stdout.strip().splitlines()[-1])


def _file_creation_us(folder: Path, n: int = 200) -> float:
    """CPU time [us] to create one empty file in ``folder`` now (the files stay, for the folder's removal)."""
    folder.mkdir(parents=True)
    t0 = time.process_time()
    for i in range(n):
        os.close(os.open(folder / f"probe{i}", os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
    return (time.process_time() - t0) / n * 1e6


def part_scale(jobs: int) -> None:
    from housner.engines import get_engine
    from housner.scenarios.catalogue.scenario import load_scenario
    from housner.scenarios.motions.build import build_motions
    from housner.scenarios.studies.study import study_motions

    levels = [round(0.5 + 0.15 * i, 2) for i in range(20)]
    heights = [2.5, 4.0, 5.0, 7.5, 10.0]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        small = _write(tmp, 100, ["housner"], levels, heights[:1])
        r_small = _run_child(small, tmp / "small", tmp / "cache-small", jobs)
        big = _write(tmp, 100, ["housner"], levels, heights)
        create_us = _file_creation_us(tmp / "probe")
        r_big = _run_child(big, tmp / "big", tmp / "cache-big", jobs)
        # baseline: the same records in one plain loop in this process
        scen = load_scenario(big)
        t0 = time.perf_counter()
        base, _ = build_motions(scen)  # the ensemble's fit (matched RDK), once per process: the study pays it too
        fit = time.perf_counter() - t0
        eng = get_engine("housner")
        t0 = time.perf_counter()
        n = 0
        for k in range(len(heights)):
            motions, _ = study_motions(scen.study, base, scen.S, k, scen.specimen)
            n += len(eng.simulate_many(scen.specimen, motions))
        loop = time.perf_counter() - t0
    print(
        f"analytic study, {r_big['records']} records ({len(levels)} stripes x {len(heights)} sizes x 100 motions), "
        f"{jobs} workers, empty cache: {r_big['wall_s']:.1f} s (target < 60 s); failed {r_big['failed']}"
    )
    print(
        f"  baseline, the same {n} records in one simulate_many loop, 1 process: {loop:.1f} s "
        f"(study / loop = {r_big['wall_s'] / loop:.2f})"
    )
    print(
        f"  with the ensemble's fit on both sides ({fit:.1f} s, once per scenario and process, not per record): "
        f"study / (fit + loop) = {r_big['wall_s'] / (fit + loop):.2f}"
    )
    print(
        f"  creating a file in the study's folder just before it: {create_us:.0f} us of CPU (one per record: "
        f"{create_us * r_big['records'] / 1e6:.1f} s of the study's CPU; 20-50 us on a disk that no mass deletion "
        "of the last minutes slows, see the module notes)"
    )
    print(
        f"  peak RSS of the study process: {r_small['peak_rss_mb']:.0f} MB for {r_small['records']} records, "
        f"{r_big['peak_rss_mb']:.0f} MB for {r_big['records']} (x{r_big['peak_rss_mb'] / r_small['peak_rss_mb']:.2f}"
        f" for x{r_big['records'] / r_small['records']:.0f} the records)"
    )


def part_dask(engine: str, n: int) -> None:
    from distributed import Client, LocalCluster

    from housner.scenarios.execution import RunOptions
    from housner.scenarios.studies.study import run_study

    levels = [1.0, 1.5, 2.0, 2.5]
    walls = {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        toml = _write(tmp, n, [engine], levels, [5.0])
        (tmp / "warm").mkdir()
        warm = _write(tmp / "warm", 2, [engine], [1.0], [5.0])
        for workers in (1, 2):
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
            with cluster, Client(cluster) as client:
                # warm-up: the workers import the engine and build its model outside the timing
                opts = RunOptions(scheduler=client, use_cache=False, progress=False)
                run_study(warm, out=tmp / f"warm{workers}", options=opts)
                t0 = time.perf_counter()
                res = run_study(toml, out=tmp / f"d{workers}", options=opts)
                walls[workers] = time.perf_counter() - t0
            print(
                f"{engine} study on a local Dask cluster of {workers} worker(s): {len(res.results)} records "
                f"in {walls[workers]:.1f} s"
            )
    print(f"  speed-up 2 workers / 1 worker: {walls[1] / walls[2]:.2f} x (target >= 1.8 x)")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--part", choices=("scale", "dask", "all"), default="all")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes of the scale part")
    ap.add_argument("--engine", default="mujoco", help="engine of the Dask part")
    ap.add_argument("--n", type=int, default=24, help="motions of the Dask part")
    args = ap.parse_args(argv)
    if args.part in ("scale", "all"):
        part_scale(args.jobs)
    if args.part in ("dask", "all"):
        part_dask(args.engine, args.n)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
