"""An outcome diagnosis in words: its summary, what the plain model's misses point to, its parameters
(:func:`housner.scenarios.diagnosis.outcomes.outcome_diagnosis.diagnose_outcomes` gives the values), and its JSON as
the command line writes it."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from housner.scenarios.diagnosis.outcomes.outcome_results import OutcomeDiagnosis, OutcomeMisses

__all__ = ["outcome_document", "outcome_params_text", "outcome_pointer_text", "outcome_summary", "write_outcome_json"]

#: What each leaning of the misses (:attr:`OutcomeMisses.leaning`) points to.
_LEANING = {
    "missed": (
        "the rock overturns under motions that the model's footprint survives: its contact sits inside the "
        "footprint (a convex or uneven base, a smaller effective alpha), or its impacts dissipate less"
    ),
    "false": (
        "the model overturns where the rock stood: a wider effective contact or more dissipation at impact "
        "(a smaller r)"
    ),
    "both": "misses in both directions: the effective geometry is uncertain rather than biased",
}


def outcome_pointer_text(misses: OutcomeMisses) -> str:
    """What the plain model's misses point to, in words, with the counts over PGV/PGA."""
    where = ", ".join(f"{b.name} PGV/PGA: {b.missed} missed overturns, {b.false} false" for b in misses.bands)
    return (
        f"{misses.missed} overturns missed and {misses.false} predicted that did not happen ({where}): "
        f"{_LEANING[misses.leaning]}"
    )


def outcome_params_text(params: dict) -> str:
    """An outcome model's fitted parameters: alpha_eff in rad, the spread in log units, None as Housner's."""
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


def outcome_summary(diag: OutcomeDiagnosis) -> str:
    """The verdict in words: the figures, their intervals, the floor, the baselines, what remains."""
    f, s = diag.final, diag.final.scores
    best = min(diag.baselines, key=lambda k: diag.baselines[k].log_loss)
    b = diag.baselines[best]
    eff = "no effect added" if f.name == "plain" else f"effect {f.name} ({outcome_params_text(f.params)})"
    floor = diag.floor
    lines = [
        f"{len(diag.ids)} outcome records ({int(diag.observed.sum())} overturned); {diag.folds}-fold "
        f"cross-validation (seed {diag.seed}); {eff}.",
        f"held-out accuracy {s.accuracy:.3f} [{s.accuracy_ci[0]:.3f}, {s.accuracy_ci[1]:.3f}], "
        f"F1 {s.f1:.3f} [{s.f1_ci[0]:.3f}, {s.f1_ci[1]:.3f}], log loss {s.log_loss:.3f} "
        f"[{s.log_loss_ci[0]:.3f}, {s.log_loss_ci[1]:.3f}]; plain model: accuracy "
        f"{diag.steps[0].scores.accuracy:.3f}, F1 {diag.steps[0].scores.f1:.3f}, log loss "
        f"{diag.steps[0].scores.log_loss:.3f}.",
        f"best baseline ({best}): accuracy {b.accuracy:.3f}, F1 {b.f1:.3f}, log loss {b.log_loss:.3f} "
        f"on the same folds: the model is {'ahead' if s.log_loss < b.log_loss else 'NOT ahead'} "
        "in log loss.",
        f"floor (a correct model with these probabilities): log loss {floor.log_loss:.3f} "
        f"[{floor.log_loss_ci[0]:.3f}, {floor.log_loss_ci[1]:.3f}], measured {floor.measured_log_loss:.3f} "
        f"(z {floor.z:+.1f}): {'at the floor' if floor.at_floor else 'above the floor: a part is unexplained'}.",
    ]
    return "\n".join(lines)


def outcome_document(diag: OutcomeDiagnosis) -> dict:
    """The outcome diagnosis JSON's content: the data of :meth:`OutcomeDiagnosis.result` with its words, the
    ``pointer`` (beside its counts) and the ``summary`` (before ``elapsed_s``)."""
    data = diag.result().to_json()
    elapsed = data.pop("elapsed_s")
    words = {"pointer": outcome_pointer_text(diag.pointer), "summary": outcome_summary(diag)}
    return {**data, **words, "elapsed_s": elapsed}


def write_outcome_json(diag: OutcomeDiagnosis, path: str | Path) -> None:
    """Write :func:`outcome_document` to ``path``, strict JSON."""
    Path(path).write_text(json.dumps(outcome_document(diag), indent=1, allow_nan=False) + "\n")
