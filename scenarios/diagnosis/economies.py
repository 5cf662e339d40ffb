"""What a diagnosis computed on fewer samples or stopped early, as values: each is said once, where the verdict
is read (:mod:`housner.reports.diagnosis.verdict_text` says them in words; ``docs/explanation/diagnosis.md`` says
why each is safe)."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import ClassVar

__all__ = [
    "ECONOMIES",
    "Economy",
    "FloorLoopStopped",
    "MechanicsSubset",
    "StepNotSignificant",
    "ThinnedSearch",
    "economy_data",
    "economy_from_data",
]


@dataclass(frozen=True)
class FloorLoopStopped:
    """The loop over families of correct integrators stopped early: the narrowest family's floor was far below the
    model's error (more than ``jump`` x ``band``) and the widest's too, so the families between were not measured
    (nested, their floors lie below the widest's).

    Attributes
    ----------
    model : str
        ``"final"`` or ``"plain"``: whose floor.
    said_before : bool
        The other model's loop stopped early too, and was said first.
    ratio, widest_ratio : float
        The ground motions' error over their floor under the narrowest and the widest family [-].
    families : tuple of str
        The families in order, narrowest first.
    jump, band : float
        The factor over the band that stops the loop, and the band of a correct model (its residual ratio) [-].
    """

    kind: ClassVar[str] = "floor_loop_stopped"
    model: str
    said_before: bool
    ratio: float
    widest_ratio: float
    families: tuple[str, ...]
    jump: float
    band: float


@dataclass(frozen=True)
class MechanicsSubset:
    """Models with an effect that replaces the equation of motion were fitted on the free vibrations and a spread
    subset of the ground motions; their errors and tests are on every record.

    Attributes
    ----------
    fitted, ground_motions : int
        The ground motions fitted on, of all of them.
    fitted_s, total_s : float
        Their error windows [s], of all the ground motions'.
    grid_records : int
        The records their grids ran on.
    """

    kind: ClassVar[str] = "mechanics_subset"
    fitted: int
    ground_motions: int
    fitted_s: float
    total_s: float
    grid_records: int


@dataclass(frozen=True)
class ThinnedSearch:
    """The search ran on every ``decimation``-th sample; the ladder's errors, the floors and the verdict on every
    sample.

    Attributes
    ----------
    decimation : int
    rates : tuple of float
        The campaign's sampling rates, lowest first [Hz].
    search_rate : float
        The rate the physics needs [Hz].
    """

    kind: ClassVar[str] = "thinned_search"
    decimation: int
    rates: tuple[float, ...]
    search_rate: float


@dataclass(frozen=True)
class StepNotSignificant:
    """A step the thinned search took whose fall is not significant on every sample (it stays in the ladder).

    Attributes
    ----------
    step : int
        Its place in the ladder (1: the first effect).
    added : str
        The effects it added.
    improvement, improvement_se : float
        Its paired fall on every sample, and the standard error [alpha].
    pvalue, level : float
        The fall's p-value and its round's level [-].
    decimation : int
        The search's decimation.
    """

    kind: ClassVar[str] = "step_not_significant"
    step: int
    added: str
    improvement: float
    improvement_se: float
    pvalue: float
    level: float
    decimation: int


Economy = FloorLoopStopped | MechanicsSubset | ThinnedSearch | StepNotSignificant
#: Each economy's class by its ``kind``.
ECONOMIES: dict[str, type] = {c.kind: c for c in (FloorLoopStopped, MechanicsSubset, ThinnedSearch, StepNotSignificant)}


def economy_data(e: Economy) -> dict:
    """An economy as plain data, its ``kind`` first."""
    return {"kind": e.kind, **asdict(e)}


def economy_from_data(data: dict) -> Economy:
    """The economy :func:`economy_data` wrote."""
    cls = ECONOMIES[data["kind"]]
    values = {k: v for k, v in data.items() if k != "kind"}
    for k in ("families", "rates"):
        if k in values:
            values[k] = tuple(values[k])
    return cls(**values)
