"""How often the outcome judgement (``outcome_validation.judge_outcome_model``) calls each kind of predictor a misfit,
over campaigns whose outcomes are drawn from known probabilities (issue 48): the truth, the base rate, a model a
regression beats, and the truth on shuffled outcomes. The campaigns are those of ``tests/test_outcome_validation.py``
(ground motions at several scalings, a logistic law of log PGA), other seeds.

Usage::

    python scripts/outcome_verdict_calibration.py [N]      # N campaigns, 60 by default (about a minute)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy import special

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from test_outcome_validation import N_GROUPS, _baselines, _campaign  # noqa: E402

from housner.scenarios.diagnosis.outcomes.outcome_scores import outcome_floor  # noqa: E402
from housner.scenarios.diagnosis.outcomes.outcome_validation import judge_outcome_model  # noqa: E402


def main(n: int) -> None:
    counts = {"the truth called a misfit": 0, "the base rate passes": 0, "a beaten model passes": 0}
    counts["shuffled outcomes pass"] = 0
    for s in range(n):
        pga, pgv, groups, p = _campaign(1000 + s)
        y = np.random.default_rng(2000 + s).random(p.size) < p
        base = _baselines(pga, pgv, y, groups, s)

        def judged(q, outcomes=y, baselines=base, groups=groups, seed=s):
            return judge_outcome_model(q, baselines, outcomes, groups, outcome_floor(q, outcomes, seed=seed))

        counts["the truth called a misfit"] += judged(p).misfit
        rate = judged(base["base_rate"])
        counts["the base rate passes"] += not rate.misfit and rate.powered
        shift = np.random.default_rng(4000 + s).normal(0.0, 0.8, N_GROUPS)[groups]
        beaten = judged(special.expit(3.0 * np.log(pga / 3.0) + 3.0 * shift))
        counts["a beaten model passes"] += not beaten.misfit and beaten.powered
        ys = np.random.default_rng(3000 + s).permutation(y)
        shuffled = judged(p, ys, _baselines(pga, pgv, ys, groups, s))
        counts["shuffled outcomes pass"] += not shuffled.misfit and shuffled.powered
    for k, v in counts.items():
        print(f"{k:28s} {v} of {n}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 60)
