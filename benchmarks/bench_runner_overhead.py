"""The runner's own cost per record: a 10 000-record analytic study against a plain loop over the same records.

Two whole processes, for ``farm-bench --vs`` (it runs them in turn and takes the ratio pair by pair)::

    farm-bench -n 5 --timeout 600 -- python benchmarks/bench_runner_overhead.py study \\
        --vs 'python benchmarks/bench_runner_overhead.py loop'

``study``: ``run_study`` of 20 stripes x 5 sizes x 100 motions of the analytic model (the scenario of
``bench_study.py --part scale``), 2 worker processes, an empty result cache (a fresh folder), every record
cached as it finishes, fragility fits with 1000 bootstrap resamples and the study directory written.
``loop``: the same scenario loaded, its motions built (the matched ensemble's fit included, as the study
pays it) and the same 10 000 records simulated by ``simulate_many`` in one process (numba's threads on every
core), nothing stored. Both processes import the package and start numba the same way.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.bench_study import _write  # noqa: E402

LEVELS = [round(0.5 + 0.15 * i, 2) for i in range(20)]
HEIGHTS = [2.5, 4.0, 5.0, 7.5, 10.0]


def study(tmp: Path) -> int:
    from housner.scenarios.execution import RunOptions
    from housner.scenarios.studies.study import run_study

    toml = _write(tmp, 100, ["housner"], LEVELS, HEIGHTS)
    res = run_study(toml, out=tmp / "out", options=RunOptions(jobs=2, cache_dir=tmp / "cache", progress=False))
    return len(res.results)


def loop(tmp: Path) -> int:
    from housner.engines import get_engine
    from housner.scenarios.catalogue.scenario import load_scenario
    from housner.scenarios.motions.build import build_motions
    from housner.scenarios.studies.study import study_motions

    scen = load_scenario(_write(tmp, 100, ["housner"], LEVELS, HEIGHTS))
    base, _ = build_motions(scen)
    eng = get_engine("housner")
    n = 0
    for k in range(len(HEIGHTS)):
        motions, _ = study_motions(scen.study, base, scen.S, k, scen.specimen)
        n += len(eng.simulate_many(scen.specimen, motions))
    return n


if __name__ == "__main__":
    part = sys.argv[1] if len(sys.argv) > 1 else ""
    if part not in ("study", "loop"):
        raise SystemExit("usage: python benchmarks/bench_runner_overhead.py study|loop")
    with tempfile.TemporaryDirectory() as tmp:
        n = (study if part == "study" else loop)(Path(tmp))
    assert n == len(LEVELS) * len(HEIGHTS) * 100, n
