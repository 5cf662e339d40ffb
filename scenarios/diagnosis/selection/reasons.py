"""Why a candidate effect is, or is not, significant: the rule that decided it and its figures, as a value (its
words are :mod:`housner.reports.diagnosis.reason_text`'s; the rules are ``docs/explanation/diagnosis.md``, "The
search, step by step")."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from housner._values import to_data

__all__ = ["KINDS", "Reason"]

#: The rules, and the figures each reason carries (errors in alpha [-], p-values [-]):
#:
#: - ``changes_nothing``, ``no_improvement``: none; ``within_uncertainty``: p, level; ``below_practical``: fall,
#:   need; ``significant``: p, level, fall, need (the paired held-out test, ``paired_test.judge``);
#: - ``rejected_not_finite``: record (a history with NaN);
#: - ``training_fall_small``: fall, margin; ``fitted_fall_small``: fall, margin; ``fitted_within_uncertainty``:
#:   p, level (the screen before the fold refits);
#: - ``grid_fall_small``: records, fall, margin; ``subset_fall_small``: records (0: all), fall, margin (a
#:   mechanics effect's start);
#: - ``free_vibrations``: quantity, z, measured, se (a model that contradicts the free vibrations);
#: - ``at_neutral``: params (rows of name.key, value, neutral, se), fall;
#: - ``kernel_numerics``: effect, faded (its parameters faded out), p;
#: - ``at_noise``: train, margin, noise (the round not searched).
KINDS = (
    "changes_nothing",
    "no_improvement",
    "within_uncertainty",
    "below_practical",
    "significant",
    "rejected_not_finite",
    "training_fall_small",
    "fitted_fall_small",
    "fitted_within_uncertainty",
    "grid_fall_small",
    "subset_fall_small",
    "free_vibrations",
    "at_neutral",
    "kernel_numerics",
    "at_noise",
)


@dataclass(frozen=True)
class Reason:
    """The rule (``kind``, one of :data:`KINDS`) that decided a candidate, and the figures it decided on."""

    kind: str
    figures: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"unknown reason kind {self.kind!r}; known: {', '.join(KINDS)}")

    def to_dict(self) -> dict:
        return {"kind": self.kind, **to_data(self.figures)}

    @classmethod
    def from_dict(cls, data: dict) -> Reason:
        figures = {k: math.nan if v is None else v for k, v in data.items() if k != "kind"}
        if "params" in figures:
            figures["params"] = [tuple(row) for row in figures["params"]]
        if "faded" in figures:
            figures["faded"] = dict(figures["faded"])
        return cls(data["kind"], figures)

    def line(self) -> str:
        """The rule and its figures in a line of progress (``kind: key=value, ...``)."""
        bits = [f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in self.figures.items()]
        return f"{self.kind}: {', '.join(bits)}" if bits else self.kind
