"""Running an engine through the tuner's check records: the raw measurements and the cost per simulated second."""

from __future__ import annotations

import math
import time

import numpy as np

from housner.engines.measures import first_impact_ratio, first_peak, half_cycle_peaks
from housner.engines.tuning.checks import CheckSuite
from housner.specimen import Specimen


def measure(engine, specimen: Specimen, suites: list[CheckSuite]) -> list[dict]:
    """Every check's raw measurement per suite, and CPU and wall seconds per simulated second (over all).

    Per suite: ``r`` and ``small`` (the first impact's energy ratio of each release [-]), ``decay``
    (the peaks / alpha after the compared impacts; NaN for a peak the record did not reach),
    ``pulse`` ((first peak, theta_max) [rad] per pulse), ``cpu`` and ``wall`` [s/s].
    """
    engine.simulate(specimen, suites[0].releases[0])  # warm-up: model compile / JIT outside the timing
    cpu = wall = sim = 0.0
    found = []
    for suite in suites:
        out = {"r": [], "small": [], "decay": [], "pulse": []}
        jobs = [("r", m) for m in suite.releases] + [("small", m) for m in suite.small]
        jobs += [("decay", m) for m in suite.decay] + [("pulse", m) for m in suite.pulses]
        for kind, m in jobs:
            c0, w0 = time.process_time(), time.perf_counter()
            resp = engine.simulate(specimen, m)
            cpu += time.process_time() - c0
            wall += time.perf_counter() - w0
            sim += m.duration
            if kind in ("r", "small"):
                out[kind].append(first_impact_ratio(resp))
            elif kind == "decay":
                pk = half_cycle_peaks(resp) / specimen.alpha
                out[kind].extend(pk[k] if k < pk.size else math.nan for k in suite.decay_impacts)
            else:
                out[kind].append((first_peak(resp), resp.theta_max))
        res = {k: np.asarray(v, dtype=float) for k, v in out.items()}
        res["pulse"] = res["pulse"].reshape(-1, 2)
        found.append(res)
    for res in found:
        res["cpu"], res["wall"] = cpu / sim, wall / sim
    return found


def failed_measurement(suite: CheckSuite) -> dict:
    """The measurements of a candidate whose engine failed: all NaN, infinite cost."""
    return {
        "r": np.full(len(suite.releases), np.nan),
        "small": np.full(len(suite.small), np.nan),
        "decay": np.full(len(suite.decay_impacts) * len(suite.decay), np.nan),
        "pulse": np.full((len(suite.pulses), 2), np.nan),
        "cpu": math.inf,
        "wall": math.inf,
    }
