"""The diagnosis' results: candidates, the error ladder and the whole diagnosis, as values and JSON (their words are in
:mod:`housner.reports.diagnosis.words`).

:class:`Diagnosis` is what :func:`housner.scenarios.diagnosis.diagnose.diagnose` returns; its
:meth:`Diagnosis.to_json` is strict JSON data (NaN and infinities written as null).
Errors are time-history errors in units of alpha (see :mod:`housner.scenarios.diagnosis.comparison.record_comparison`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np

from housner._values import JsonValue, WrittenAsResult, floats, read_as, read_fields, to_data
from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.diagnosis.comparison.record_comparison import Comparison
from housner.scenarios.diagnosis.economies import Economy, economy_data, economy_from_data
from housner.scenarios.diagnosis.selection.reasons import Reason

__all__ = [
    "Candidate",
    "Diagnosis",
    "DiagnosisResult",
    "DiagnosisSettings",
    "FloorSummary",
    "Step",
    "names_label",
]


#: The error figures of a candidate and of a rung of the ladder [alpha].
_ERRORS = ("train_error", "heldout_error", "heldout_se", "improvement", "improvement_se")


def names_label(names) -> str:
    """Effects' registered names as one label, ``"a + b"`` (the form the results, the JSON and the text use)."""
    return " + ".join(names)


@dataclass(frozen=True)
class Candidate:
    """One candidate effect, fitted on the training records and scored on the held-out ones.

    Attributes
    ----------
    effects : tuple of str
        Registered name(s): one effect, or two that are tried together (a pair).
    params : dict
        Fitted parameters (units of the effect's ParamSpec).
    base : tuple of str
        Effects already in the model it was added to.
    round : int
        Greedy round (1 = against the starting model).
    train_error : float
        Mean training error [alpha].
    heldout_error, heldout_se : float
        Mean held-out error [alpha] and its standard error.
    improvement, improvement_se : float
        Mean paired held-out improvement over the model it was added to [alpha], and its standard error.
    z : float
        improvement / improvement_se.
    pvalue : float
        One-sided Wilcoxon signed-rank p-value of the paired held-out differences.
    significant : bool
        Step 4 of ``docs/explanation/diagnosis.md``, "The search, step by step" (p-value below the Bonferroni
        level and improvement above the noise floor).
    reason : Reason or None
        The rule that decided whether it is significant, with its figures (in words:
        :mod:`housner.reports.diagnosis.reason_text`).
    heldout_errors : ndarray
        Per record, out of fold [alpha] (None when not held out).
    fold_wins : ndarray
        Per fold: mean improvement on that fold's records [alpha] (None when not held out).
    """

    effects: tuple
    params: dict
    base: tuple
    round: int
    train_error: float
    heldout_error: float
    heldout_se: float
    improvement: float
    improvement_se: float
    z: float
    pvalue: float
    significant: bool
    reason: Reason | None
    heldout_errors: np.ndarray = field(repr=False, compare=False, default=None)
    fold_wins: np.ndarray = field(repr=False, compare=False, default=None)

    @property
    def effect(self) -> str:
        """The candidate's name in the results and the text: its effect's, or a pair's ``"a + b"``."""
        return names_label(self.effects)

    def to_dict(self) -> dict:
        return {
            "effect": self.effect,
            "params": _clean(self.params),
            "base": list(self.base),
            "round": self.round,
            "train_error": self.train_error,
            "heldout_error": self.heldout_error,
            "heldout_se": self.heldout_se,
            "improvement": self.improvement,
            "improvement_se": self.improvement_se,
            "z": self.z,
            "pvalue": self.pvalue,
            "significant": self.significant,
            "reason_facts": None if self.reason is None else self.reason.to_dict(),
            "fold_improvements": None if self.fold_wins is None else [float(x) for x in self.fold_wins],
        }

    @classmethod
    def from_dict(cls, data: dict) -> Candidate:
        """The candidate a diagnosis JSON holds (its per-record held-out errors are not written there)."""
        folds = data.get("fold_improvements")
        return cls(
            effects=tuple(data["effect"].split(" + ")),
            params=_params_from(data["params"]),
            base=tuple(data["base"]),
            round=int(data["round"]),
            **floats(data, *_ERRORS, "z", "pvalue"),
            significant=bool(data["significant"]),
            reason=None if data.get("reason_facts") is None else Reason.from_dict(data["reason_facts"]),
            fold_wins=None if folds is None else np.array([read_as(float, x) for x in folds]),
        )


@dataclass(frozen=True)
class Step:
    """One rung of the error ladder: the model with the effects so far.

    Attributes
    ----------
    effects : tuple of (str, dict)
        (name, fitted parameters) of each effect in the model, in the order added.
    added_effects : tuple of str
        The registered name(s) of the effect(s) this step added (empty for the baseline); two
        effects that only help together enter in one step.
    by_hand : bool
        Added with ``add`` rather than by the greedy search.
    train_error, heldout_error, heldout_se : float
        [alpha].
    improvement, improvement_se : float
        Mean paired held-out improvement over the previous step [alpha] (NaN for the baseline).
    significant : bool
    heldout_errors : ndarray
        Per held-out record [alpha].
    comparison : Comparison or None
        The full comparison of this model with the campaign (localisation included).
    """

    effects: tuple
    added_effects: tuple
    by_hand: bool
    train_error: float
    heldout_error: float
    heldout_se: float
    improvement: float
    improvement_se: float
    significant: bool
    heldout_errors: np.ndarray = field(repr=False, compare=False, default=None)
    comparison: Comparison | None = field(repr=False, compare=False, default=None)

    @property
    def names(self) -> list[str]:
        return [n for n, _p in self.effects]

    @property
    def added(self) -> str | None:
        """What this step added, as the results and the text name it (``"a + b"`` for a pair); None: the baseline."""
        return names_label(self.added_effects) if self.added_effects else None

    def label(self) -> str:
        return "Housner (baseline)" if not self.effects else " + ".join(self.names)

    def to_dict(self) -> dict:
        return {
            "effects": [{"name": n, "params": _clean(p)} for n, p in self.effects],
            "added": self.added,
            "by_hand": self.by_hand,
            "train_error": self.train_error,
            "heldout_error": self.heldout_error,
            "heldout_se": self.heldout_se,
            "improvement": _nan_none(self.improvement),
            "improvement_se": _nan_none(self.improvement_se),
            "significant": self.significant,
        }

    @classmethod
    def from_dict(cls, data: dict) -> Step:
        """The rung a diagnosis JSON's ladder holds (its per-record errors and comparison are not written there)."""
        return cls(
            effects=tuple((e["name"], _params_from(e["params"])) for e in data["effects"]),
            added_effects=tuple(data["added"].split(" + ")) if data["added"] else (),
            by_hand=bool(data["by_hand"]),
            **floats(data, *_ERRORS),
            significant=bool(data["significant"]),
        )


@dataclass(frozen=True)
class DiagnosisSettings:
    """What a diagnosis ran with, and how it was computed.

    Attributes
    ----------
    effects, add : tuple of str
        The candidate effects and those added by hand.
    folds : int
        Cross-validation folds K [-].
    seed : Any
        The seed as given (an int, None or its text).
    max_effects : int
    level, practical : float
        The family-wise level of a round [-] and the practical share of the sensor noise a fall must reach [-].
    pairs : bool
    replicas : int
        Replicas of the floor's parametric bootstrap.
    engine_settings : dict
        The analytic engine's settings.
    floor_family, floor_family_plain : str
        The families of correct integrators of the final and of the plain model's floor.
    search : str
        What the search did (``ran``, ``off``, ``none_left``, ``skipped``).
    decimation : int
        The search ran on every ``decimation``-th sample [-].
    economies : tuple of Economy
        What ran on fewer samples or stopped early (:mod:`housner.scenarios.diagnosis.economies`).
    """

    effects: tuple[str, ...]
    add: tuple[str, ...]
    folds: int
    seed: Any
    max_effects: int
    level: float
    practical: float
    pairs: bool
    replicas: int
    engine_settings: dict
    floor_family: str
    floor_family_plain: str
    search: str
    decimation: int
    economies: tuple[Economy, ...]

    def to_dict(self) -> dict:
        """The settings as plain data, the economies as theirs (``economy_facts``: the JSON's ``economies`` are their
        words, :func:`housner.reports.diagnosis.document.diagnosis_document`'s)."""
        out = to_data({f.name: getattr(self, f.name) for f in fields(self) if f.name != "economies"})
        return {**out, "economy_facts": [to_data(economy_data(e)) for e in self.economies]}

    @classmethod
    def from_dict(cls, data: dict) -> DiagnosisSettings:
        """The settings :meth:`to_dict` wrote."""
        plain = {k: v for k, v in data.items() if k not in ("economies", "economy_facts")}
        economies = tuple(economy_from_data(e) for e in data["economy_facts"])
        return replace(read_fields(cls, {**plain, "economies": []}), economies=economies)


@dataclass(frozen=True)
class FloorSummary:
    """A correct-model floor as a diagnosis JSON holds it.

    Attributes
    ----------
    per_record : tuple of float
        The floor of each record, campaign order [alpha].
    perturbation : dict
        What the bootstrap perturbed, and by how much.
    replicas : int
    """

    per_record: tuple[float, ...]
    perturbation: dict
    replicas: int

    @classmethod
    def of(cls, floor) -> FloorSummary:
        """The summary of a measured :class:`housner.scenarios.diagnosis.verdict.correct_model_floor.Floor`."""
        return cls(tuple(float(x) for x in floor.mean), dict(floor.perturbation), int(floor.n_replicas))


@dataclass(frozen=True, eq=False)
class DiagnosisResult(JsonValue):
    """What a diagnosis JSON holds, as a value: :meth:`Diagnosis.result` makes it, :meth:`to_json` writes its data and
    :meth:`from_json` reads it back (:meth:`to_json` adds the baseline's and the final model's error summaries, which
    follow from the ladder). The words the file holds besides (the verdict's text, its summary) are
    :func:`housner.reports.diagnosis.document.diagnosis_document`'s.

    Attributes
    ----------
    campaign : str
    ladder : tuple of Step
    candidates : tuple of Candidate
        The first round.
    rounds : tuple of tuple of Candidate
    selected, added : tuple of str
    noise_floor, test_level : float
    train_ids, heldout_ids : tuple of str
    skipped : tuple of tuple of str
        The campaign's records left out, each (record, file, why).
    settings : DiagnosisSettings
    folds : tuple of tuple of str
    selection_frequency : dict of str to float
    verdict : Verdict or None
    sensor : dict or None
        The sensor's assessment as plain data.
    floors : (FloorSummary, FloorSummary) or None
        The plain and the final model's floors.
    localisation : dict
        ``baseline`` and ``final``: each model's comparison summary as plain data (None where not run).
    elapsed_s : float
    """

    campaign: str
    ladder: tuple[Step, ...]
    candidates: tuple[Candidate, ...]
    rounds: tuple[tuple[Candidate, ...], ...]
    selected: tuple[str, ...]
    added: tuple[str, ...]
    noise_floor: float
    test_level: float
    train_ids: tuple[str, ...]
    heldout_ids: tuple[str, ...]
    skipped: tuple[tuple[str, ...], ...]
    settings: DiagnosisSettings
    folds: tuple[tuple[str, ...], ...]
    selection_frequency: dict
    verdict: Any
    sensor: dict | None
    floors: tuple[FloorSummary, FloorSummary] | None
    localisation: dict
    elapsed_s: float

    def to_json(self) -> dict:
        """The diagnosis JSON's keys, in its order (strict JSON data: NaN and infinities written as null)."""
        base, final = self.ladder[0], self.ladder[-1]
        b = base.heldout_error
        reduction = (b - final.heldout_error) / b if b > 0 else 0.0
        return to_data(
            {
                "campaign": self.campaign,
                "baseline": self._errors(base),
                "candidates": [c.to_dict() for c in self.candidates],
                "selected": list(self.selected),
                "added": list(self.added),
                "final": {**self._errors(final), "reduction": reduction},
                "ladder": [st.to_dict() for st in self.ladder],
                "rounds": [[c.to_dict() for c in r] for r in self.rounds],
                "test_level": self.test_level,
                "train_ids": list(self.train_ids),
                "heldout_ids": list(self.heldout_ids),
                "skipped": [list(x) for x in self.skipped],
                "settings": self.settings.to_dict(),
                "folds": [list(f) for f in self.folds],
                "selection_frequency": dict(self.selection_frequency),
                "verdict": None if self.verdict is None else self.verdict.to_dict(),
                "sensor": self.sensor,
                "floor": None
                if self.floors is None
                else {"baseline": to_data(self.floors[0]), "final": to_data(self.floors[1])},
                "localisation": self.localisation,
                "elapsed_s": self.elapsed_s,
            }
        )

    def _errors(self, step: Step) -> dict:
        return {
            "heldout_error": step.heldout_error,
            "heldout_se": step.heldout_se,
            "train_error": step.train_error,
            "noise_floor": self.noise_floor,
            "effects": [{"name": n, "params": _clean(p)} for n, p in step.effects],
        }

    @classmethod
    def from_json(cls, data: dict) -> DiagnosisResult:
        from housner.scenarios.diagnosis.verdict.decision import Verdict  # the verdict reads the results' classes

        floor = data.get("floor")
        return cls(
            campaign=data["campaign"],
            ladder=tuple(Step.from_dict(x) for x in data["ladder"]),
            candidates=tuple(Candidate.from_dict(c) for c in data["candidates"]),
            rounds=tuple(tuple(Candidate.from_dict(c) for c in r) for r in data["rounds"]),
            selected=tuple(data["selected"]),
            added=tuple(data["added"]),
            noise_floor=read_as(float, data["baseline"]["noise_floor"]),
            test_level=read_as(float, data["test_level"]),
            train_ids=tuple(data["train_ids"]),
            heldout_ids=tuple(data["heldout_ids"]),
            skipped=tuple(tuple(x) for x in data["skipped"]),
            settings=DiagnosisSettings.from_dict(data["settings"]),
            folds=tuple(tuple(f) for f in data["folds"]),
            selection_frequency={k: read_as(float, v) for k, v in data["selection_frequency"].items()},
            verdict=None if data.get("verdict") is None else Verdict.from_dict(data["verdict"]),
            sensor=data.get("sensor"),
            floors=None
            if floor is None
            else (read_as(FloorSummary, floor["baseline"]), read_as(FloorSummary, floor["final"])),
            localisation=data["localisation"],
            elapsed_s=read_as(float, data["elapsed_s"]),
        )


@dataclass(eq=False)
class Diagnosis(WrittenAsResult):
    """The result of :func:`diagnose`.

    Attributes
    ----------
    campaign : Campaign
    baseline : Step
        The plain Housner model.
    steps : list of Step
        The error ladder: baseline, then each added effect.
    candidates : list of Candidate
        The first round: every candidate against the starting model, best first.
    rounds : list of list of Candidate
        Every greedy round, each best first.
    selected : list of str
        Effects the greedy search added (after the hand-added ones).
    added : list of str
        Effects added by hand.
    noise_floor : float
        Mean sigma/alpha of the records [-]: the sensor noise alone (the verdict uses the measured
        correct-model floor, ``floors``).
    test_level : float
        The per-test significance level of the first round, ``level`` / candidates [-].
    train_ids, heldout_ids : list of str
        Every record (cross-validation: each trains in K - 1 folds and is held out in one).
    settings : dict
    folds : list of list of str
        Record ids of each fold.
    verdict : housner.scenarios.diagnosis.verdict.decision.Verdict
    floors : (Floor, Floor)
        The measured correct-model floor of the plain and of the final model.
    selection_frequency : dict
        Effect -> share of the folds in which it was the best candidate of its round [-].
    elapsed : float
        Wall time [s].
    """

    campaign: Campaign
    baseline: Step
    steps: list[Step]
    candidates: list[Candidate]
    rounds: list[list[Candidate]]
    selected: list[str]
    added: list[str]
    noise_floor: float
    test_level: float
    train_ids: list[str]
    heldout_ids: list[str]
    settings: DiagnosisSettings
    folds: list = field(default_factory=list)
    verdict: Any = None
    floors: tuple = ()
    selection_frequency: dict = field(default_factory=dict)
    elapsed: float = math.nan

    @property
    def status(self) -> str:
        """The verdict's status (see :data:`housner.scenarios.diagnosis.verdict.status.STATUSES`)."""
        return self.verdict.status if self.verdict is not None else "inconclusive"

    @property
    def final(self) -> Step:
        return self.steps[-1]

    @property
    def reduction(self) -> float:
        """Fraction of the baseline held-out error removed by the final model [-]."""
        b = self.baseline.heldout_error
        return (b - self.final.heldout_error) / b if b > 0 else 0.0

    def result(self) -> DiagnosisResult:
        """The diagnosis as the value its JSON holds."""
        cmp0, cmp1 = self.baseline.comparison, self.final.comparison
        sensor = getattr(self.campaign, "sensor", None)
        return DiagnosisResult(
            campaign=self.campaign.name,
            ladder=tuple(self.steps),
            candidates=tuple(self.candidates),
            rounds=tuple(tuple(r) for r in self.rounds),
            selected=tuple(self.selected),
            added=tuple(self.added),
            noise_floor=self.noise_floor,
            test_level=self.test_level,
            train_ids=tuple(self.train_ids),
            heldout_ids=tuple(self.heldout_ids),
            skipped=tuple(tuple(x) for x in self.campaign.skipped),
            settings=self.settings,
            folds=tuple(tuple(f) for f in self.folds),
            selection_frequency=dict(self.selection_frequency),
            verdict=self.verdict,
            sensor=None if sensor is None else to_data(sensor.to_dict()),
            floors=None if not self.floors else (FloorSummary.of(self.floors[0]), FloorSummary.of(self.floors[1])),
            localisation={
                "baseline": None if cmp0 is None else to_data(cmp0.summary()),
                "final": None if cmp1 is None else to_data(cmp1.summary()),
            },
            elapsed_s=self.elapsed,
        )


def _nan_none(v: float):
    return None if v is None or (isinstance(v, float) and not math.isfinite(v)) else v


def _clean(params: dict) -> dict:
    return {k: _nan_none(float(v)) for k, v in params.items()}


def _params_from(data: dict) -> dict:
    """Fitted parameters as a diagnosis JSON holds them (null: no finite value)."""
    return {k: read_as(float, v) for k, v in data.items()}
