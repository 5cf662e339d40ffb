"""The result of an outcome diagnosis
(:func:`housner.scenarios.diagnosis.outcomes.outcome_diagnosis.diagnose_outcomes`): its
ladder of models and the whole diagnosis, as values and their JSON form (their words are in
:mod:`housner.reports.diagnosis.outcome_text`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import numpy as np

from housner._values import JsonValue, WrittenAsResult, floats, read_as, to_data
from housner.scenarios.diagnosis.outcomes.engine_ensemble import EngineModelScore
from housner.scenarios.diagnosis.outcomes.outcome_effects import LeftOut, OutcomeEffect
from housner.scenarios.diagnosis.outcomes.outcome_scores import CalibrationBin, OutcomeFloor, OutcomeScores, SeedSpread
from housner.scenarios.diagnosis.outcomes.outcome_transfer import OutcomeTransfer
from housner.scenarios.diagnosis.outcomes.outcome_validation import BaselineFit, OutcomeJudgement

__all__ = [
    "Miss",
    "MissBand",
    "OutcomeCandidate",
    "OutcomeDiagnosis",
    "OutcomeDiagnosisResult",
    "OutcomeGeometry",
    "OutcomeMisses",
    "OutcomeRepeats",
    "OutcomeStep",
]


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
        Out-of-fold P(overturn) per record, the mean over the repeats of the cross-validation [-].
    scores : OutcomeScores
        :func:`outcome_scores` of ``p`` (the bootstrap resamples whole ground motions).
    improvement : float
        Mean per-record fall of the held-out log loss from the previous rung [nats] (0 for the plain model).
    improvement_se : float
    p_value : float
        One-sided p-value of that fall (Diebold-Mariano, clustered by ground motion; nan for the plain model).
    over_seeds : dict of str to SeedSpread
        Each score's mean and range over the repeats, each scored on its own folds.
    p_repeats : ndarray
        Out-of-fold P(overturn) of each repeat, (repeats, records) [-].
    """

    name: str
    params: dict
    fold_params: list = field(compare=False)
    p: np.ndarray = field(compare=False)
    scores: OutcomeScores
    improvement: float = 0.0
    improvement_se: float = 0.0
    p_value: float = math.nan
    over_seeds: dict[str, SeedSpread] = field(default_factory=dict)
    p_repeats: np.ndarray = field(compare=False, default=None)

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "params": self.params,
            "scores": self.scores.to_dict(),
            "over_seeds": to_data(self.over_seeds),
            "improvement": self.improvement,
            "improvement_se": self.improvement_se,
            "p_value": _nan_none(self.p_value),
        }

    @classmethod
    def from_dict(cls, data: dict) -> OutcomeStep:
        """The rung an outcome diagnosis JSON holds (its probabilities and fold fits are not written there)."""
        return cls(
            name=data["name"],
            params=dict(data["params"]),
            fold_params=[],
            p=None,
            scores=OutcomeScores.from_dict(data["scores"]),
            **floats(data, "improvement", "improvement_se", "p_value"),
            over_seeds=read_as(dict[str, SeedSpread], data.get("over_seeds", {})),
        )


@dataclass(frozen=True)
class OutcomeCandidate:
    """A candidate of the outcome diagnosis' forward selection, as tried.

    Attributes
    ----------
    name : str
    log_loss : float
        Its held-out log loss [nats].
    improvement, improvement_se : float
        The mean paired fall from the model it was tried on [nats], and its standard error.
    p_value : float
    added : bool
    params : dict
    """

    name: str
    log_loss: float
    improvement: float
    improvement_se: float
    p_value: float
    added: bool
    params: dict


@dataclass(frozen=True)
class Miss:
    """A record a model got wrong at P = 0.5.

    Attributes
    ----------
    model : str
    id : str
    observed : str
        ``"overturned"`` or ``"stood"``.
    predicted_p : float
        The model's held-out P(overturn) [-].
    pga_g : float
        The record's PGA [g].
    pgv_over_pga_s : float
        Its PGV/PGA [s].
    """

    model: str
    id: str
    observed: str
    predicted_p: float
    pga_g: float
    pgv_over_pga_s: float


@dataclass(frozen=True)
class MissBand:
    """A model's misses among the records of one third of PGV/PGA.

    Attributes
    ----------
    name : str
        ``"short"``, ``"middle"`` or ``"long"`` PGV/PGA.
    missed : int
        Overturns the model did not predict.
    false : int
        Overturns it predicted that did not happen.
    """

    name: str
    missed: int
    false: int


@dataclass(frozen=True)
class OutcomeMisses:
    """What a model's misses at P = 0.5 point to: their counts, in all and over thirds of PGV/PGA.

    Attributes
    ----------
    missed, false : int
        Overturns missed, and overturns predicted that did not happen.
    bands : tuple of MissBand
        The same over the short, middle and long PGV/PGA thirds of the records.
    below_static : int
        Records that overturned under a peak table acceleration below the block's static threshold, g tan(alpha)
        of its smallest alpha over the specimen's bracket: a rigid block on a rigid base does not even lift off
        there, so the recorded motion (or the geometry) contradicts the outcome.
    static_threshold_g : float
        That threshold [g].
    """

    missed: int
    false: int
    bands: tuple[MissBand, ...]
    below_static: int = 0
    static_threshold_g: float = math.nan

    @property
    def leaning(self) -> str:
        """``"missed"`` when the misses are mostly missed overturns (more than twice the false ones), ``"false"``
        when mostly false ones, ``"both"`` otherwise."""
        if self.missed > 2 * max(self.false, 1):
            return "missed"
        if self.false > 2 * max(self.missed, 1):
            return "false"
        return "both"


@dataclass(frozen=True)
class OutcomeRepeats:
    """The repeats of an outcome diagnosis' cross-validation, each on its own folds.

    Attributes
    ----------
    seeds : tuple of int
        Their fold seeds.
    finals : tuple of str
        The final model each repeat's forward selection ended in (``"plain"``, or effects joined by "+").
    selection_share : dict of str to float
        Each candidate effect -> the share of repeats whose final model holds it [-].
    chosen : str
        The final model the diagnosis reports: the one most repeats ended in (the one with fewer effects on a
        tie).
    """

    seeds: tuple[int, ...]
    finals: tuple[str, ...]
    selection_share: dict[str, float]
    chosen: str


@dataclass(frozen=True)
class OutcomeGeometry:
    """The block behind an outcome model, in SI: centre-of-mass height, pivots, alphas, inertia, mass, and each
    pivot's bracket of b [m] (``pos``, ``neg``)."""

    h_m: float
    b_pos_m: float
    b_neg_m: float
    alpha_pos_rad: float
    alpha_neg_rad: float
    centroidal_inertia_kgm2: float
    mass_kg: float
    b_bracket_m: dict[str, tuple[float, float]]


@dataclass
class OutcomeDiagnosis(WrittenAsResult):
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
    candidates : list of OutcomeCandidate
        Every candidate tried.
    baselines : dict of str to OutcomeScores
        Name -> :func:`outcome_scores` of the logistic regressions on the same folds.
    baseline_p : dict
        Name -> out-of-fold probabilities of each baseline.
    floor : OutcomeFloor
        The final model against what a correct model would score.
    pointer : OutcomeMisses
        What the plain model's misses point to.
    misses : list of Miss
        The plain and the final model's misses, record by record.
    status : str
        ``no_misfit``, ``explained``, ``partly_explained`` or ``unexplained`` (the one vocabulary:
        :data:`housner.scenarios.diagnosis.verdict.status.STATUSES`).
    geometry : OutcomeGeometry
    folds : int
    seed : int
        The first repeat's fold seed (the others follow it: :func:`repeat_seeds`).
    elapsed : float
        [s]
    calibration : list of CalibrationBin
    groups : ndarray
        The group (ground motion) of every record.
    repeats : OutcomeRepeats
        The repeats of the cross-validation: their seeds, each one's final model, each effect's share.
    baseline_spread : dict
        Baseline name -> each score's mean and range over the repeats.
    judgement, judgement_plain : OutcomeJudgement
        The final and the plain model against the baselines and their floors: what the status rests on.
    baseline_fits : dict of str to BaselineFit
        The baselines fitted on every record, for another campaign to score (``--model``).
    transfer : OutcomeTransfer or None
        A model fitted on another campaign, scored here frozen (``--model``).
    engine_model : EngineModelScore or None
        A 3D engine's ensemble scored as an outcome model on the same folds (``--engine-model``).
    searched : tuple of OutcomeEffect
        The library effects searched, each with the grid it was tabulated on.
    left_out : tuple of LeftOut
        The library effects the records cannot test, each with why.
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
    pointer: OutcomeMisses
    misses: list
    status: str
    geometry: OutcomeGeometry
    folds: int
    seed: int
    elapsed: float = 0.0
    calibration: list = field(default_factory=list)
    groups: np.ndarray = None
    repeats: OutcomeRepeats | None = None
    baseline_spread: dict = field(default_factory=dict)
    judgement: OutcomeJudgement | None = None
    judgement_plain: OutcomeJudgement | None = None
    baseline_fits: dict = field(default_factory=dict)
    transfer: OutcomeTransfer | None = None
    engine_model: EngineModelScore | None = None
    searched: tuple = ()
    left_out: tuple = ()

    @property
    def final(self) -> OutcomeStep:
        return self.steps[-1]

    @property
    def effects(self) -> list[str]:
        return [] if self.final.name == "plain" else self.final.name.split("+")

    def result(self) -> OutcomeDiagnosisResult:
        """The outcome diagnosis as the value its JSON holds."""
        return OutcomeDiagnosisResult(
            campaign=self.campaign,
            status=self.status,
            n_records=len(self.ids),
            n_overturned=int(self.observed.sum()),
            folds=self.folds,
            seed=self.seed,
            ladder=tuple(self.steps),
            baselines=dict(self.baselines),
            floor=self.floor,
            calibration=tuple(self.calibration),
            candidates=tuple(self.candidates),
            pointer=self.pointer,
            misses=tuple(self.misses),
            geometry=self.geometry,
            repeats=self.repeats,
            baseline_spread=dict(self.baseline_spread),
            judgement=self.judgement,
            judgement_plain=self.judgement_plain,
            baseline_fits=dict(self.baseline_fits),
            transfer=self.transfer,
            engine_model=self.engine_model,
            searched=tuple(self.searched),
            left_out=tuple(self.left_out),
            elapsed_s=self.elapsed,
        )


@dataclass(frozen=True, eq=False)
class OutcomeDiagnosisResult(JsonValue):
    """What an outcome diagnosis JSON holds, as a value: :meth:`OutcomeDiagnosis.result` makes it, :meth:`to_json`
    writes the file (its ``outcomes`` table repeats the final model's scores beside the floor and the baselines) and
    :meth:`from_json` reads it back."""

    campaign: str
    status: str
    n_records: int
    n_overturned: int
    folds: int
    seed: int
    ladder: tuple[OutcomeStep, ...]
    baselines: dict[str, OutcomeScores]
    floor: OutcomeFloor
    calibration: tuple[CalibrationBin, ...]
    candidates: tuple[OutcomeCandidate, ...]
    pointer: OutcomeMisses
    misses: tuple[Miss, ...]
    geometry: OutcomeGeometry
    repeats: OutcomeRepeats | None
    baseline_spread: dict[str, dict[str, SeedSpread]]
    judgement: OutcomeJudgement | None
    judgement_plain: OutcomeJudgement | None
    baseline_fits: dict[str, BaselineFit]
    transfer: OutcomeTransfer | None
    elapsed_s: float
    searched: tuple[OutcomeEffect, ...] = ()
    left_out: tuple[LeftOut, ...] = ()
    engine_model: EngineModelScore | None = None

    @property
    def final(self) -> OutcomeStep:
        return self.ladder[-1]

    def _effect(self) -> dict | None:
        f = self.final
        return None if f.name == "plain" else {"name": f.name, "params": f.params}

    def to_json(self) -> dict:
        """The outcome diagnosis JSON's keys, in its order (strict JSON data: NaN and infinities written as null)."""
        f = self.final
        baselines = {k: v.to_dict() for k, v in self.baselines.items()}
        outcomes = {
            **f.scores.to_dict(),
            "model": f.name,
            "effect": self._effect(),
            "baselines": baselines,
            "floor": self.floor.to_dict(),
            "at_floor": self.floor.at_floor,
            "calibration": [to_data(c) for c in self.calibration],
        }
        return to_data(
            {
                "kind": "outcomes",
                "campaign": self.campaign,
                "status": self.status,
                "n_records": self.n_records,
                "n_overturned": self.n_overturned,
                "folds": self.folds,
                "seed": self.seed,
                "outcomes": outcomes,
                "baselines": baselines,
                "effect": self._effect(),
                "ladder": [st.to_dict() for st in self.ladder],
                "candidates": [to_data(c) for c in self.candidates],
                "pointer_counts": to_data(self.pointer),
                "misses": [to_data(m) for m in self.misses],
                "geometry": to_data(self.geometry),
                "repeats": to_data(self.repeats),
                "baselines_over_seeds": to_data(self.baseline_spread),
                "judgement": to_data(self.judgement),
                "judgement_plain": to_data(self.judgement_plain),
                "baseline_fits": to_data(self.baseline_fits),
                "transfer": None if self.transfer is None else to_data(_without_p(self.transfer)),
                "effects_searched": [to_data(e) for e in self.searched],
                "effects_left_out": [to_data(e) for e in self.left_out],
                **({} if self.engine_model is None else {"engine_model": to_data(self.engine_model)}),
                "elapsed_s": self.elapsed_s,
            }
        )

    @classmethod
    def from_json(cls, data: dict) -> OutcomeDiagnosisResult:
        out = data["outcomes"]
        return cls(
            campaign=data["campaign"],
            status=data["status"],
            n_records=int(data["n_records"]),
            n_overturned=int(data["n_overturned"]),
            folds=int(data["folds"]),
            seed=data["seed"],
            ladder=tuple(OutcomeStep.from_dict(x) for x in data["ladder"]),
            baselines={k: OutcomeScores.from_dict(v) for k, v in data["baselines"].items()},
            floor=read_as(OutcomeFloor, out["floor"]),
            calibration=read_as(tuple[CalibrationBin, ...], out["calibration"]),
            candidates=read_as(tuple[OutcomeCandidate, ...], data["candidates"]),
            pointer=read_as(OutcomeMisses, data["pointer_counts"]),
            misses=read_as(tuple[Miss, ...], data["misses"]),
            geometry=read_as(OutcomeGeometry, data["geometry"]),
            repeats=read_as(OutcomeRepeats | None, data.get("repeats")),
            baseline_spread=read_as(dict[str, dict[str, SeedSpread]], data.get("baselines_over_seeds", {})),
            judgement=read_as(OutcomeJudgement | None, data.get("judgement")),
            judgement_plain=read_as(OutcomeJudgement | None, data.get("judgement_plain")),
            baseline_fits=read_as(dict[str, BaselineFit], data.get("baseline_fits", {})),
            transfer=read_as(OutcomeTransfer | None, data.get("transfer")),
            elapsed_s=read_as(float, data["elapsed_s"]),
            searched=read_as(tuple[OutcomeEffect, ...], data.get("effects_searched", [])),
            left_out=read_as(tuple[LeftOut, ...], data.get("effects_left_out", [])),
            engine_model=read_as(EngineModelScore | None, data.get("engine_model")),
        )


def _without_p(t: OutcomeTransfer) -> dict:
    """A transfer's fields as its JSON holds them: its per-record probabilities are not written."""
    return {f.name: getattr(t, f.name) for f in fields(t) if f.name != "p"}


def _nan_none(v: float):
    return None if v is None or (isinstance(v, float) and not math.isfinite(v)) else v
