"""The diagnosis' results: candidates, the error ladder and the whole diagnosis, as text and JSON.

:class:`Diagnosis` is what :func:`housner.scenarios.diagnosis.diagnose.diagnose` returns; its
:meth:`Diagnosis.to_json` is strict JSON (NaN and infinities written as null).
Errors are time-history errors in units of alpha (see :mod:`housner.scenarios.diagnosis.comparison.record_comparison`).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from housner.effects import effect_class
from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.diagnosis.comparison.record_comparison import Comparison
from housner.scenarios.execution.typed_json import JsonValue, WrittenAsResult, floats, from_data, to_data

__all__ = [
    "Candidate",
    "Diagnosis",
    "DiagnosisResult",
    "DiagnosisSettings",
    "FloorSummary",
    "Step",
    "change_text",
    "fmt_pm",
    "names_label",
    "params_text",
    "signed_words",
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
    reason : str
        Why it is (not) significant, in words.
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
    reason: str
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
            "reason": self.reason,
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
            reason=data["reason"],
            fold_wins=None if folds is None else np.array([from_data(float, x) for x in folds]),
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
    economies : tuple of str
        What ran on fewer samples or stopped early, in words.
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
    economies: tuple[str, ...]


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


@dataclass(frozen=True)
class DiagnosisResult(JsonValue):
    """What a diagnosis JSON holds, as a value: :meth:`Diagnosis.result` makes it, :meth:`to_json` writes the file and
    :meth:`from_json` reads it back (:meth:`to_dict` adds the baseline's and the final model's error summaries, which
    follow from the ladder).

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
    summary : str
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
    summary: str
    elapsed_s: float

    def to_dict(self) -> dict:
        """The diagnosis JSON's keys, in its order."""
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
                "settings": to_data(self.settings),
                "folds": [list(f) for f in self.folds],
                "selection_frequency": dict(self.selection_frequency),
                "verdict": None if self.verdict is None else self.verdict.to_dict(),
                "sensor": self.sensor,
                "floor": None
                if self.floors is None
                else {"baseline": to_data(self.floors[0]), "final": to_data(self.floors[1])},
                "localisation": self.localisation,
                "summary": self.summary,
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
    def from_dict(cls, data: dict) -> DiagnosisResult:
        from housner.scenarios.diagnosis.verdict.decision import Verdict  # the verdict reads the results' classes

        floor = data.get("floor")
        return cls(
            campaign=data["campaign"],
            ladder=tuple(Step.from_dict(x) for x in data["ladder"]),
            candidates=tuple(Candidate.from_dict(c) for c in data["candidates"]),
            rounds=tuple(tuple(Candidate.from_dict(c) for c in r) for r in data["rounds"]),
            selected=tuple(data["selected"]),
            added=tuple(data["added"]),
            noise_floor=from_data(float, data["baseline"]["noise_floor"]),
            test_level=from_data(float, data["test_level"]),
            train_ids=tuple(data["train_ids"]),
            heldout_ids=tuple(data["heldout_ids"]),
            skipped=tuple(tuple(x) for x in data["skipped"]),
            settings=from_data(DiagnosisSettings, data["settings"]),
            folds=tuple(tuple(f) for f in data["folds"]),
            selection_frequency={k: from_data(float, v) for k, v in data["selection_frequency"].items()},
            verdict=None if data.get("verdict") is None else Verdict.from_dict(data["verdict"]),
            sensor=data.get("sensor"),
            floors=None
            if floor is None
            else (from_data(FloorSummary, floor["baseline"]), from_data(FloorSummary, floor["final"])),
            localisation=data["localisation"],
            summary=data["summary"],
            elapsed_s=from_data(float, data["elapsed_s"]),
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

    def summary(self) -> str:
        """One paragraph: the verdict in words, then the ladder with its figures.

        Every error is in units of alpha with its standard error (:func:`fmt_pm`); a change is said as
        "falls by" or "rises by" with a positive figure, and a parameter carries its unit.
        """
        parts = [self.verdict.text if self.verdict is not None else ""]
        chosen = self.steps[1:]
        if chosen:
            ladder = []
            final_params = dict(self.steps[-1].effects)
            for st in chosen:
                prm = "; ".join(_step_params(n, dict(st.effects)[n], final_params.get(n)) for n in st.added_effects)
                how = " (by hand)" if st.by_hand else ""
                ladder.append(
                    f"+ {st.added}{how} ({prm}): held-out error {fmt_pm(st.heldout_error, st.heldout_se)} alpha, "
                    f"which {change_text(st.improvement, st.improvement_se)} alpha"
                    f"{'' if st.significant else ', not significant'}"
                )
            parts.append("Ladder: " + "; ".join(ladder) + ".")
            b, f = self.baseline, self.final
            verb = "falls" if self.reduction >= 0 else "rises"
            parts.append(
                f"In all the held-out error {verb} by {abs(100 * self.reduction):.0f} %, from "
                f"{fmt_pm(b.heldout_error, b.heldout_se)} to {fmt_pm(f.heldout_error, f.heldout_se)} alpha."
            )
        elif self.candidates:
            best = self.candidates[0]
            if math.isfinite(best.improvement):
                verb = "lower" if best.improvement >= 0 else "raise"
                parts.append(
                    f"The best candidate, {best.effect}, would {verb} the held-out error by "
                    f"{fmt_pm(abs(best.improvement), best.improvement_se)} alpha ({signed_words(best.reason)})."
                )
        sensor = getattr(self.campaign, "sensor", None)
        if sensor is not None and sensor.noise.white and not sensor.faults:
            parts.append(f"Sensor noise: {sensor.noise.describe()}.")  # else the verdict's text says it
        k = self.settings.folds
        parts.append(
            f"({k}-fold cross-validation: every record held out once; sensor noise sigma/alpha {self.noise_floor:.2g}.)"
        )
        return " ".join(p for p in parts if p)

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
            summary=self.summary(),
            elapsed_s=self.elapsed,
        )


def _fmt_num(v: float) -> str:
    return f"{v:.4g}"


# ----------------------------------------------------------------------------
# numbers in words (the summary here, the page in housner.reports.diagnosis)
def fmt_pm(value, se, *, sep: str = " +- ", inf: str = "overturned", nan: str = "n/a") -> str:
    """A value with its standard error: the error to 2 significant digits, the value to the same decimal place.

    ``fmt_pm(0.0031234, 0.000423)`` is ``"0.00312 +- 0.00042"``, ``fmt_pm(123.4, 15.6)`` is ``"123 +- 16"``.
    An infinite value (a theta_max/alpha of an overturned block) is written ``inf`` (``"overturned"``, or
    ``"-inf"`` when negative) without an uncertainty; a missing value is ``nan``; a value whose
    standard error is missing or infinite is written to 4 significant digits alone, and one with a
    zero standard error to 4 significant digits ``+- 0``.

    Parameters
    ----------
    value, se : float
    sep : str
        Between the two (``" &plusmn; "`` on an HTML page).
    inf, nan : str
        What an infinite and a missing value read as.
    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        return nan
    if math.isnan(v):
        return nan
    if math.isinf(v):
        return inf if v > 0 else "-inf"
    try:
        e = abs(float(se))
    except (TypeError, ValueError):
        e = math.nan
    if not math.isfinite(e):
        return _sig(v, 4)
    if e == 0.0:
        return f"{_sig(v, 4)}{sep}0"
    decimals = 1 - math.floor(math.log10(e))  # 2 significant digits of the error
    if math.floor(math.log10(round(e, decimals))) > math.floor(math.log10(e)):  # 0.000996 -> 0.0010
        decimals -= 1
    if decimals > 12:  # too small for fixed notation to stay readable
        return f"{v:.3e}{sep}{e:.1e}"
    return f"{_fixed(v, decimals)}{sep}{_fixed(e, decimals)}"


def _fixed(v: float, decimals: int) -> str:
    r = round(v, decimals)
    if r == 0:
        r = 0.0  # no "-0.000"
    return f"{r:.{max(decimals, 0)}f}"


def _sig(v: float, digits: int) -> str:
    """``v`` to ``digits`` significant digits in fixed notation where that stays short."""
    if v == 0:
        return "0"
    if not 1e-4 <= abs(v) < 1e6:
        return f"{v:.{digits - 1}e}"
    return _fixed(v, max(digits - 1 - math.floor(math.log10(abs(v))), 0))


def change_text(improvement: float, se: float, *, sep: str = " +- ") -> str:
    """A paired improvement (previous error minus this one) in words: ``"falls by X +- s"`` or ``"rises by X +- s"``.

    The figure is always positive: an error that grows "rises by 0.05", never "falls by -0.05".
    """
    try:
        d = float(improvement)
    except (TypeError, ValueError):
        d = math.nan
    if not math.isfinite(d):
        return "does not change measurably"
    return f"{'falls' if d >= 0 else 'rises'} by {fmt_pm(abs(d), se, sep=sep)}"


_NUM = r"(\d+(?:\.\d*)?(?:[eE][-+]?\d+)?)"
_FALLS = re.compile(r"\bfalls by ([-+])" + _NUM)
_LOWERS = re.compile(r"\blowers (the [\w ]+?) by ([-+])" + _NUM)


def signed_words(text: str) -> str:
    """Rewrite signed changes in words: "falls by -0.05" -> "rises by 0.05", "falls by +0.05" -> "falls by 0.05".

    For the reasons the search gives (:mod:`housner.scenarios.diagnosis.diagnose`), written with a sign.
    """
    text = _FALLS.sub(lambda m: f"{'rises' if m.group(1) == '-' else 'falls'} by {m.group(2)}", text)
    return _LOWERS.sub(lambda m: f"{'raises' if m.group(2) == '-' else 'lowers'} {m.group(1)} by {m.group(3)}", text)


def param_unit(name: str, key: str) -> str:
    """The unit of parameter ``key`` of effect ``name`` (its ParamSpec's), "" when unknown."""
    try:
        return effect_class(name).param_specs[key].unit
    except (KeyError, ValueError, AttributeError):
        return ""


def _step_params(name: str, params: dict, final: dict | None) -> str:
    """An effect's parameters as fitted at its step of the ladder; where the final model's joint refit moved
    them, both, each labelled (the verdict's text gives the final model's)."""
    text = params_text(name, params)
    if final is None or params_text(name, final) == text:
        return text
    return (
        f"{text} as fitted at this step; {params_text(name, final)} in the final model, refitted with the "
        "effects after it"
    )


def params_text(name: str, params: dict, *, digits: int = 4) -> str:
    """``"c = 0.5999 1/s"``: an effect's fitted parameters with their units ([-] when dimensionless), and where
    one stopped at an end of its search range that is not its neutral value, that it did (:func:`at_bound`)."""
    out = []
    for k, v in params.items():
        unit = param_unit(name, k)
        unit = "[-]" if unit in ("-", "") else unit
        out.append(f"{k} = {_sig(float(v), digits) if math.isfinite(float(v)) else v} {unit}{at_bound(name, k, v)}")
    return ", ".join(out)


def at_bound(name: str, key: str, value) -> str:
    """``" (at the top of its search range 0-0.5: the fit may want a larger value ...)"``, or ``""``.

    A parameter fitted to within 1e-6 of the range's span from an end that is not its neutral value (0 damping
    at the bottom is a fit that found no effect, not a range too narrow) may be held back by the range: an
    effect that fails so is not shown to be wrong. Ranges that depend on the specimen are not checked here.
    """
    from housner.scenarios.diagnosis.selection.fitting import search_bounds

    try:
        bounds = search_bounds(name, key)
        neutral = effect_class(name).param_specs[key].neutral_for(None)
        v = float(value)
    except (KeyError, ValueError, TypeError, AttributeError):
        return ""
    if bounds is None or not math.isfinite(v):
        return ""
    lo, hi = float(bounds[0]), float(bounds[1])
    near = 1e-6 * (hi - lo)
    for end, word, more in ((hi, "top", "larger"), (lo, "bottom", "smaller")):
        if math.isfinite(end) and abs(v - end) <= near and end != neutral:
            return (
                f" (at the {word} of its search range {lo:g} to {hi:g}: the fit may want a {more} value, so this "
                "fit does not rule the effect out; widen its bounds to test it)"
            )
    return ""


def _nan_none(v: float):
    return None if v is None or (isinstance(v, float) and not math.isfinite(v)) else v


def _clean(params: dict) -> dict:
    return {k: _nan_none(float(v)) for k, v in params.items()}


def _params_from(data: dict) -> dict:
    """Fitted parameters as a diagnosis JSON holds them (null: no finite value)."""
    return {k: from_data(float, v) for k, v in data.items()}
