"""Whether a 3D scan-mesh engine's outcomes converge in its time step (issue 48): every outcome record of a campaign
run at ``timestep`` and at half of it, and the share of records whose outcome (overturned or not) flips between the
two, with each step's accuracy against the measured outcomes. Beside it, the outcomes' own sensitivity: the share
that flips at ``timestep`` when the table acceleration is scaled by 1 + :data:`NUDGE` (a change far below any
accelerometer's calibration), the floor under which no step can bring the flips.

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

#: Relative change of the table acceleration [-] whose flips measure the outcomes' own sensitivity.
NUDGE = 1e-3


def _outcomes(args) -> tuple[list[bool], float]:
    """The overturns of the records ``idx`` of the campaign at one step, with the table acceleration scaled by
    ``scale``, and the CPU time they took [s]."""
    root, engine, settings, idx, scale = args
    campaign = load_campaign(root, allow_outside=True)
    eng = get_engine(engine, **settings)
    cpu0 = time.process_time()
    out = []
    for i in idx:
        mo = campaign.outcomes[i].motion
        mo = mo if scale == 1.0 else mo.scaled(scale)
        out.append(bool(eng.simulate(campaign.specimen, mo).overturned))
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
        for dt, scale in ((timestep, 1.0), (timestep / 2, 1.0), (timestep, 1.0 + NUDGE)):
            runs = list(pool.map(_outcomes, [(root, engine, {**base, "timestep": dt}, c, scale) for c in chunks]))
            ov = np.empty(n, dtype=bool)
            for c, (o, _cpu) in zip(chunks, runs, strict=True):
                ov[c] = o
            got[dt, scale] = ov
            cpu = sum(c for _o, c in runs)
            print(
                f"{engine} timestep {dt:g} s, table acceleration x {scale:g}: {int(ov.sum())} of {n} overturn, "
                f"accuracy {np.mean(ov == y):.3f}, {cpu:.0f} CPU s"
            )
    a = got[timestep, 1.0]
    for key, what in (
        ((timestep / 2, 1.0), f"between {timestep:g} s and {timestep / 2:g} s"),
        ((timestep, 1.0 + NUDGE), f"at {timestep:g} s when the table acceleration changes by {NUDGE:g}"),
    ):
        b = got[key]
        flips = int(np.sum(a != b))
        print(f"outcomes that flip {what}: {flips} of {n} ({100 * flips / n:.1f} %)")
        if flips:
            print("  flipped records:", ", ".join(campaign.outcomes[i].id for i in np.flatnonzero(a != b)))


if __name__ == "__main__":
    argv = sys.argv[1:]
    if not argv or not Path(argv[0]).is_dir():
        sys.exit("usage: mesh_engine_step_convergence.py CAMPAIGN_DIR [ENGINE] [TIMESTEP] [N]")
    main(argv[0], *(argv[1:2]), *(float(x) for x in argv[2:3]), *(int(x) for x in argv[3:4]))
