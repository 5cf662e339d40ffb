"""Whether a 3D scan-mesh engine's outcomes converge in its time step (issue 48): every outcome record of a campaign
run at ``timestep`` and at half of it, and the share of records whose outcome (overturned or not) flips between the
two, with each step's accuracy against the measured outcomes.

Usage::

    housner campaign from-asu ../shared/data/asu-granite /tmp/asu-sp1
    python scripts/mesh_engine_step_convergence.py /tmp/asu-sp1 [ENGINE] [TIMESTEP] [N]
    # ENGINE mujoco-3d (default) or pybullet-3d; TIMESTEP the coarser step [s], 5e-4 by default; N records (all)
"""

from __future__ import annotations

import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from housner.engines import get_engine
from housner.scenarios.campaigns.campaign import load_campaign


def _outcomes(args) -> tuple[list[bool], float]:
    """The overturns of the records ``idx`` of the campaign at one step, and the CPU time they took [s]."""
    root, engine, settings, idx = args
    campaign = load_campaign(root, allow_outside=True)
    eng = get_engine(engine, **settings)
    cpu0 = time.process_time()
    out = [bool(eng.simulate(campaign.specimen, campaign.outcomes[i].motion).overturned) for i in idx]
    return out, time.process_time() - cpu0


def main(root: str, engine: str = "mujoco-3d", timestep: float = 5e-4, n: int | None = None) -> None:
    campaign = load_campaign(root, allow_outside=True)
    scan = campaign.scan
    base = {"mesh": str(scan.path), "azimuth": scan.azimuth, "density": scan.density}
    n = len(campaign.outcomes) if n is None else min(int(n), len(campaign.outcomes))
    y = np.array([r.overturned for r in campaign.outcomes[:n]])
    chunks = [list(range(k, n, 2)) for k in range(2)]
    got = {}
    with ProcessPoolExecutor(2) as pool:
        for dt in (timestep, timestep / 2):
            runs = list(pool.map(_outcomes, [(root, engine, {**base, "timestep": dt}, c) for c in chunks]))
            ov = np.empty(n, dtype=bool)
            for c, (o, _cpu) in zip(chunks, runs, strict=True):
                ov[c] = o
            got[dt] = ov
            cpu = sum(c for _o, c in runs)
            print(
                f"{engine} timestep {dt:g} s: {int(ov.sum())} of {n} overturn, accuracy {np.mean(ov == y):.3f}, "
                f"{cpu:.0f} CPU s"
            )
    a, b = got[timestep], got[timestep / 2]
    flips = int(np.sum(a != b))
    print(f"outcomes that flip between {timestep:g} s and {timestep / 2:g} s: {flips} of {n} ({100 * flips / n:.1f} %)")
    if flips:
        print("flipped records:", ", ".join(campaign.outcomes[i].id for i in np.flatnonzero(a != b)))


if __name__ == "__main__":
    argv = sys.argv[1:]
    if not argv or not Path(argv[0]).is_dir():
        sys.exit("usage: mesh_engine_step_convergence.py CAMPAIGN_DIR [ENGINE] [TIMESTEP] [N]")
    main(argv[0], *(argv[1:2]), *(float(x) for x in argv[2:3]), *(int(x) for x in argv[3:4]))
