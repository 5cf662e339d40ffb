"""A study's fragility.json as values: each engine's lognormal fit at each size, and its comparison with the reference.

:func:`housner.scenarios.studies.study.analyse` makes them, :func:`~housner.scenarios.studies.study.write_study`
writes :class:`StudyFits` (NaN as null) and :func:`~housner.scenarios.studies.study.load_study` reads it back
(null as NaN); the study's report, its assertion and ``housner run`` read the fits through their fields.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

from housner._values import JsonValue

if TYPE_CHECKING:
    from housner.scenarios.studies.fragility import FitComparison

__all__ = ["StudyComparison", "StudyFit", "StudyFits"]


@dataclass(frozen=True, eq=False)
class StudyFit(JsonValue):
    """The lognormal fragility fit of one engine at one size (a row of fragility.json's ``fits``).

    Attributes
    ----------
    engine : str
    size : float
        Prototype height [m].
    S : float
        Its scale factor [-].
    median, median_low, median_high : float
        The fitted median [intensity] and its bootstrap interval (NaN where there is none).
    beta, beta_low, beta_high : float
        The fitted lognormal standard deviation [-] and its interval (NaN where there is none).
    status : str
        ``ok`` for a maximum-likelihood fit; else why there is none (``no_data``, a step, ...).
    message : str
        The fit's message.
    n_boot, n_failed : int or None
        Bootstrap replicates, and those whose own fit was degenerate.
    caveat : str or None
        What a reader must know of an ok fit ("" when nothing; None when the file does not say).
    """

    engine: str
    size: float
    S: float = math.nan
    median: float = math.nan
    median_low: float = math.nan
    median_high: float = math.nan
    beta: float = math.nan
    beta_low: float = math.nan
    beta_high: float = math.nan
    status: str = ""
    message: str = ""
    n_boot: int | None = None
    n_failed: int | None = None
    caveat: str | None = None

    @property
    def ok(self) -> bool:
        """A maximum-likelihood fit (status "ok"): the only kind whose median and beta are reported."""
        return self.status == "ok"


@dataclass(frozen=True, eq=False)
class StudyComparison(JsonValue):
    """An engine's fit against the reference's at one size (a row of fragility.json's ``comparisons``).

    Attributes
    ----------
    engine, reference : str
    size : float
        Prototype height [m].
    S : float
        Its scale factor [-].
    median_ratio, ratio_low, ratio_high : float
        The ratio of the medians [-] and its paired bootstrap interval.
    beta_diff, diff_low, diff_high : float
        The difference of the betas [-] and its interval.
    disagree : bool or None
        Whether an interval excludes 1 (ratio) or 0 (difference); None when the file does not say.
    """

    engine: str
    reference: str = ""
    size: float = math.nan
    S: float = math.nan
    median_ratio: float = math.nan
    ratio_low: float = math.nan
    ratio_high: float = math.nan
    beta_diff: float = math.nan
    diff_low: float = math.nan
    diff_high: float = math.nan
    disagree: bool | None = None

    @classmethod
    def of(cls, comparison: FitComparison, engine: str, reference: str, size: float, S: float) -> StudyComparison:
        """The row of ``comparison`` (:func:`~housner.scenarios.studies.fragility.compare_fits`) of ``engine``
        against ``reference`` at one size: its figures and verdict under the same names."""
        figures = comparison._asdict()
        return cls(engine, reference, size, S, **{f.name: figures[f.name] for f in fields(cls) if f.name in figures})


@dataclass(frozen=True, eq=False)
class StudyFits(JsonValue):
    """fragility.json: the fits per (engine, size) and the comparisons with the reference."""

    fits: tuple[StudyFit, ...] = ()
    comparisons: tuple[StudyComparison, ...] = ()
