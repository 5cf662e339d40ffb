"""The result of an outcome diagnosis
(:func:`housner.scenarios.diagnosis.outcomes.outcome_diagnosis.diagnose_outcomes`): its
ladder of models and the whole diagnosis, as values with their summary in words and their JSON form."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from housner.scenarios.diagnosis.outcomes.outcome_scores import OutcomeFloor
from housner.scenarios.execution.rundir import jsonable

__all__ = ["OutcomeDiagnosis", "OutcomeStep", "params_text"]


@dataclass(frozen=True)
class OutcomeStep:
    """One rung of the ladder: a model, its out-of-fold probabilities and scores.

    Attributes
    ----------
    name : str
        ``"plain"`` or the effects in, joined by "+".
    params : dict
        Fitted on all records (what the model is), by effect.
    fold_params : list of dict
        Fitted without each fold (what scored it).
    p : ndarray
        Out-of-fold P(overturn) per record [-].
    scores : dict
        :func:`outcome_scores` of ``p``.
    improvement : float
        Mean per-record fall of the held-out log loss from the previous rung [nats] (0 for the plain model).
    improvement_se : float
    p_value : float
        One-sided p-value of that fall (Diebold-Mariano; nan for the plain model).
    """

    name: str
    params: dict
    fold_params: list
    p: np.ndarray
    scores: dict
    improvement: float = 0.0
    improvement_se: float = 0.0
    p_value: float = math.nan

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "params": self.params,
            "scores": self.scores,
            "improvement": self.improvement,
            "improvement_se": self.improvement_se,
            "p_value": _nan_none(self.p_value),
        }


@dataclass
class OutcomeDiagnosis:
    """The mission loop on a campaign's outcome records (:func:`diagnose_outcomes`).

    Attributes
    ----------
    campaign : str
    ids : list of str
    observed : ndarray of bool
    pga, pgv : ndarray
        Measured peak table acceleration [m/s^2] and velocity [m/s] per record.
    steps : list of OutcomeStep
        The plain model, then each effect added.
    candidates : list of dict
        Every candidate tried: name, held-out log loss, fall, p-value, added or not.
    baselines : dict
        Name -> :func:`outcome_scores` of the logistic regressions on the same folds.
    baseline_p : dict
        Name -> out-of-fold probabilities of each baseline.
    floor : OutcomeFloor
        The final model against what a correct model would score.
    pointer : str
        What the plain model's misses point to.
    misses : list of dict
        The plain and the final model's misses, record by record.
    status : str
        ``no_misfit``, ``explained``, ``partly_explained`` or ``unexplained`` (the one vocabulary:
        :data:`housner.scenarios.diagnosis.verdict.status.STATUSES`).
    geometry : dict
    folds : int
    seed : int
    elapsed : float
        [s]
    """

    campaign: str
    ids: list
    observed: np.ndarray
    pga: np.ndarray
    pgv: np.ndarray
    steps: list
    candidates: list
    baselines: dict
    baseline_p: dict
    floor: OutcomeFloor
    pointer: str
    misses: list
    status: str
    geometry: dict
    folds: int
    seed: int
    elapsed: float = 0.0
    calibration: list = field(default_factory=list)

    @property
    def final(self) -> OutcomeStep:
        return self.steps[-1]

    @property
    def effects(self) -> list[str]:
        return [] if self.final.name == "plain" else self.final.name.split("+")

    def summary(self) -> str:
        """The verdict in words: the figures, their intervals, the floor, the baselines, what remains."""
        f, s = self.final, self.final.scores
        best = min(self.baselines, key=lambda k: self.baselines[k]["log_loss"])
        b = self.baselines[best]
        eff = "no effect added" if f.name == "plain" else f"effect {f.name} ({params_text(f.params)})"
        floor = self.floor
        lines = [
            f"{len(self.ids)} outcome records ({int(self.observed.sum())} overturned); {self.folds}-fold "
            f"cross-validation (seed {self.seed}); {eff}.",
            f"held-out accuracy {s['accuracy']:.3f} [{s['accuracy_ci'][0]:.3f}, {s['accuracy_ci'][1]:.3f}], "
            f"F1 {s['f1']:.3f} [{s['f1_ci'][0]:.3f}, {s['f1_ci'][1]:.3f}], log loss {s['log_loss']:.3f} "
            f"[{s['log_loss_ci'][0]:.3f}, {s['log_loss_ci'][1]:.3f}]; plain model: accuracy "
            f"{self.steps[0].scores['accuracy']:.3f}, F1 {self.steps[0].scores['f1']:.3f}, log loss "
            f"{self.steps[0].scores['log_loss']:.3f}.",
            f"best baseline ({best}): accuracy {b['accuracy']:.3f}, F1 {b['f1']:.3f}, log loss {b['log_loss']:.3f} "
            f"on the same folds: the model is {'ahead' if s['log_loss'] < b['log_loss'] else 'NOT ahead'} "
            "in log loss.",
            f"floor (a correct model with these probabilities): log loss {floor.log_loss:.3f} "
            f"[{floor.log_loss_ci[0]:.3f}, {floor.log_loss_ci[1]:.3f}], measured {floor.measured_log_loss:.3f} "
            f"(z {floor.z:+.1f}): {'at the floor' if floor.at_floor else 'above the floor: a part is unexplained'}.",
        ]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        f = self.final
        outcomes = {k: f.scores[k] for k in f.scores}
        outcomes.update(
            model=f.name,
            effect=self._effect(),
            baselines=self.baselines,
            floor=self.floor.to_dict(),
            at_floor=self.floor.at_floor,
            calibration=self.calibration,
        )
        return {
            "kind": "outcomes",
            "campaign": self.campaign,
            "status": self.status,
            "n_records": len(self.ids),
            "n_overturned": int(self.observed.sum()),
            "folds": self.folds,
            "seed": self.seed,
            "outcomes": outcomes,
            "baselines": self.baselines,
            "effect": self._effect(),
            "ladder": [s.to_dict() for s in self.steps],
            "candidates": self.candidates,
            "pointer": self.pointer,
            "misses": self.misses,
            "geometry": self.geometry,
            "summary": self.summary(),
            "elapsed_s": self.elapsed,
        }

    def to_json(self, path: str | Path | None = None) -> str:
        """The JSON text of :meth:`to_dict` (non-finite numbers as null); also written to ``path`` when given."""
        text = json.dumps(jsonable(self.to_dict(), nonfinite="null"), indent=1, allow_nan=False)
        if path is not None:
            Path(path).write_text(text + "\n")
        return text

    def _effect(self) -> dict | None:
        f = self.final
        return None if f.name == "plain" else {"name": f.name, "params": f.params}


def params_text(params: dict) -> str:
    parts = []
    for k, v in params.items():
        if v is None:
            parts.append(f"{k} Housner")
        elif k == "alpha_eff":
            parts.append(f"alpha_eff {v:.4f} rad")
        elif k == "spread":
            parts.append(f"spread {v:.2f} (log)")
        else:
            parts.append(f"{k} {v:.3g}")
    return ", ".join(parts)


def _nan_none(v: float):
    return None if v is None or (isinstance(v, float) and not math.isfinite(v)) else v
