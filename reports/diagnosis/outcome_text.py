"""An outcome diagnosis in words: its summary, what the plain model's misses point to, its parameters
(:func:`housner.scenarios.diagnosis.outcomes.outcome_diagnosis.diagnose_outcomes` gives the values), and its JSON as
the command line writes it."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from housner.scenarios.diagnosis.outcomes.outcome_effects import SOLVER_BUDGET_STEPS
from housner.scenarios.diagnosis.outcomes.outcome_validation import LEVEL

if TYPE_CHECKING:
    from housner.scenarios.diagnosis.outcomes.engine_ensemble import EngineModelScore
    from housner.scenarios.diagnosis.outcomes.outcome_results import OutcomeDiagnosis, OutcomeMisses
    from housner.scenarios.diagnosis.outcomes.outcome_transfer import OutcomeTransfer
    from housner.scenarios.diagnosis.outcomes.outcome_validation import OutcomeJudgement

__all__ = [
    "engine_model_text",
    "judgement_text",
    "outcome_document",
    "outcome_params_text",
    "outcome_pointer_text",
    "outcome_summary",
    "transfer_text",
    "write_outcome_json",
]

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
    text = (
        f"{misses.missed} overturns missed and {misses.false} predicted that did not happen ({where}): "
        f"{_LEANING[misses.leaning]}"
    )
    if misses.below_static:
        text += (
            f"; and {misses.below_static} records overturned under a peak table acceleration below the block's "
            f"static threshold g tan(alpha) = {misses.static_threshold_g:.3f} g (its smallest alpha), where a rigid "
            "block does not even lift off: the recorded table motion (or the geometry) is suspect for them, which "
            "no effect of the block explains"
        )
    return text


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


def _spread(step_or_spread, key: str, digits: int = 3) -> str:
    """A score's mean over the repeats with its range: ``0.899 (seeds 0.896-0.902)``."""
    v = step_or_spread[key]
    return f"{v.mean:.{digits}f} (seeds {v.low:.{digits}f}-{v.high:.{digits}f})"


def judgement_text(judged: OutcomeJudgement) -> str:
    """What the held-out log loss says of a model against the baselines and its floor, in words."""
    parts = []
    for name, c in judged.against.items():
        verb = "lower" if c.advantage >= 0 else "higher"
        parts.append(f"than {name} {verb} by {abs(c.advantage):.3f} +- {c.se:.3f}")
    said = "; ".join(parts)
    head = (
        "the model's held-out log loss against each baseline on the same folds (nats; standard errors clustered by "
        f"ground motion): {said}"
    )
    if judged.beaten_by:
        names = ", ".join(judged.beaten_by)
        return f"{head}. A baseline predicts significantly better ({names}): the model is beaten by a regression"
    if judged.powered and not judged.skill:
        return f"{head}. The model does not predict significantly better than the base rate: it shows no skill"
    if not judged.powered:
        return (
            f"{head}. Neither the model nor any baseline predicts significantly better than the base rate: these "
            "records cannot tell a model with skill from one without"
        )
    return f"{head}. No baseline predicts better"


def left_out_text(left_out) -> str:
    """The library effects an outcome diagnosis could not test, each with why; empty when none was left out."""
    why = {
        "sensor": lambda e: "changes only what a sensor reads, not whether the block falls",
        "channels": lambda e: f"reads the measured channel {', '.join(e.channels)}, which outcome records lack",
        "no_grid": lambda e: "has no parameter with a finite range to tabulate",
        "slow_solver": lambda e: (
            f"its own equation of motion, run record by record, would take over {e.steps:.2g} solver steps for its "
            f"table (the outcome tables take at most {SOLVER_BUDGET_STEPS:.0e})"
        ),
    }
    parts = [f"{e.name} ({why.get(e.why, lambda e: e.why)(e)})" for e in left_out]
    return f"not searched on outcome records: {'; '.join(parts)}." if parts else ""


def outcome_summary(diag: OutcomeDiagnosis) -> str:
    """The verdict in words: each score's mean and range over the repeats, the intervals, the baselines, the
    floor and the judgement the status rests on."""
    f, s = diag.final, diag.final.scores
    rep = diag.repeats
    best = min(diag.baselines, key=lambda k: diag.baselines[k].log_loss)
    eff = "no effect added" if f.name == "plain" else f"effect {f.name} ({outcome_params_text(f.params)})"
    shares = ", ".join(f"{e} {100 * v:.0f} %" for e, v in rep.selection_share.items())
    floor = diag.floor
    lines = [
        f"{len(diag.ids)} outcome records ({int(diag.observed.sum())} overturned) of "
        f"{np.unique(diag.groups).size} ground motions; {diag.folds}-fold cross-validation, stratified by outcome, "
        f"each ground motion's records in one fold, repeated over {len(rep.seeds)} fold seeds "
        f"({', '.join(str(x) for x in rep.seeds)}); {eff}: the final model of {rep.finals.count(rep.chosen)} of "
        f"{len(rep.seeds)} repeats (each effect's share of the repeats: {shares}).",
        f"held-out accuracy {_spread(f.over_seeds, 'accuracy')}, F1 {_spread(f.over_seeds, 'f1')}, log loss "
        f"{_spread(f.over_seeds, 'log_loss')}; on the repeats' mean probabilities, with intervals that resample "
        f"whole ground motions: accuracy {s.accuracy:.3f} [{s.accuracy_ci[0]:.3f}, {s.accuracy_ci[1]:.3f}], log "
        f"loss {s.log_loss:.3f} [{s.log_loss_ci[0]:.3f}, {s.log_loss_ci[1]:.3f}]; plain model: accuracy "
        f"{_spread(diag.steps[0].over_seeds, 'accuracy')}, log loss {_spread(diag.steps[0].over_seeds, 'log_loss')}.",
        *([left_out_text(diag.left_out)] if diag.left_out else []),
        f"best baseline ({best}): accuracy {_spread(diag.baseline_spread[best], 'accuracy')}, log loss "
        f"{_spread(diag.baseline_spread[best], 'log_loss')}; {judgement_text(diag.judgement)}.",
        f"floor (a correct model with these probabilities): log loss {floor.log_loss:.3f} "
        f"[{floor.log_loss_ci[0]:.3f}, {floor.log_loss_ci[1]:.3f}], measured {floor.measured_log_loss:.3f} "
        f"(z {floor.z:+.1f}): {'at the floor' if floor.at_floor else 'above the floor: a part is unexplained'}.",
    ]
    return "\n".join(lines)


def transfer_text(t: OutcomeTransfer) -> str:
    """A model fitted on another campaign, scored here frozen beside that campaign's baselines, in words."""
    s = t.scores
    rows = "; ".join(
        f"than {name} (log loss {t.baselines[name].log_loss:.3f}) {'lower' if c.advantage >= 0 else 'higher'} by "
        f"{abs(c.advantage):.3f} +- {c.se:.3f}"
        for name, c in t.against.items()
    )
    beaten = [n for n, c in t.against.items() if c.p_worse < LEVEL]
    ahead = [n for n, c in t.against.items() if c.p_better < LEVEL]
    if beaten:
        end = f"a frozen baseline predicts these records better ({', '.join(beaten)}): the model does not transfer"
    elif len(ahead) == len(t.against):
        end = "the frozen model predicts these records significantly better than every frozen baseline"
    else:
        end = "the frozen model is not significantly better than every frozen baseline"
    return (
        f"transfer: {t.model} ({outcome_params_text(t.params)}) fitted on {t.source}, frozen, scores here accuracy "
        f"{s.accuracy:.3f} [{s.accuracy_ci[0]:.3f}, {s.accuracy_ci[1]:.3f}], F1 {s.f1:.3f}, log loss "
        f"{s.log_loss:.3f} [{s.log_loss_ci[0]:.3f}, {s.log_loss_ci[1]:.3f}]; its log loss against the baselines "
        f"fitted on {t.source}, frozen (nats; clustered by ground motion): {rows}; {end}."
    )


def _engine_against(c, what: str) -> str:
    """The engine's model against the planar final model (a PairedComparison), in words."""
    if c.p_better < LEVEL:
        return (
            f"{what} predicts these records better than the planar final model by {c.advantage:.3f} +- {c.se:.3f} "
            f"nats (p {c.p_better:.2g}): the planar model misses the third dimension"
        )
    if c.p_worse < LEVEL:
        return (
            f"the planar final model predicts these records better than {what}, by {-c.advantage:.3f} +- "
            f"{c.se:.3f} nats (p {c.p_worse:.2g})"
        )
    return f"{what} and the planar final model differ by {c.advantage:+.3f} +- {c.se:.3f} nats (not significant)"


def engine_model_text(e: EngineModelScore) -> str:
    """A 3D engine's ensemble scored as an outcome model, against the planar final model, in words."""
    ens = e.ensemble
    frictions = ", ".join(f"{f:g}" for f in ens.frictions)
    step = "its default step" if ens.timestep is None else f"step {ens.timestep:g} s"
    if ens.amplitudes != (1.0,):
        step += ", table acceleration x " + ", ".join(f"{k:g}" for k in ens.amplitudes)
    az = ", ".join(f"{a:g}" for a in e.azimuths)
    u = e.uniform_over_seeds
    return (
        f"3D engine {ens.engine}: {ens.size} runs per record ({len(ens.azimuths)} azimuths from "
        f"{ens.azimuths[0]:g} deg, friction {frictions}, {step}), P(overturn) the share that overturn; its runs "
        f"disagree on {100 * e.flip_share:.1f} % of records"
        + (f", {e.failed_runs} runs failed" if e.failed_runs else "")
        + f". With the rock's orientation fitted on the training folds (azimuth {az} deg on every record, chosen "
        f"by {100 * e.fold_agreement:.0f} % of the fold fits; lapse {e.lapse:g}), held out: accuracy "
        f"{_spread(e.over_seeds, 'accuracy')}, F1 {_spread(e.over_seeds, 'f1')}, log loss "
        f"{_spread(e.over_seeds, 'log_loss')}; {judgement_text(e.judgement)}; "
        f"{_engine_against(e.against_final, 'the engine')}. With every azimuth alike (the orientation unknown): "
        f"accuracy {_spread(u, 'accuracy')}, log loss {_spread(u, 'log_loss')}; "
        f"{_engine_against(e.uniform_against_final, 'the engine so')}."
    )


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
