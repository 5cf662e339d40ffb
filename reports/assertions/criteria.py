"""What an agreement assertion checks and says: criteria, the report of them, and the errors that carry it."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from housner.scenarios.execution.rundir import REPORT_FILE

#: Failed motions named in a message, at most.
SHOW_FAILED = 3


@dataclass(frozen=True)
class Criterion:
    """One tolerance criterion and its outcome.

    Attributes
    ----------
    name : str
        What is checked, e.g. "KS distance".
    passed : bool
    detail : str
        Both sides' figures, the threshold and the margin, in words.
    value : float
        The measured figure compared with the threshold.
    threshold : float
    excess : float
        By how much the figure is beyond the threshold (> 0 when failed, <= 0
        when passed; +inf when it cannot be met, e.g. one side overturns).
    """

    name: str
    passed: bool
    detail: str
    value: float = math.nan
    threshold: float = math.nan
    excess: float = math.nan

    def line(self) -> str:
        """One line of a message: ``[PASS]``/``[FAIL]``, name and detail."""
        return f"  [{'PASS' if self.passed else 'FAIL'}] {self.name}: {self.detail}"


@dataclass(frozen=True)
class AgreementReport:
    """Every criterion of an agreement check; returned when all of them pass.

    Attributes
    ----------
    title : str
    criteria : tuple of Criterion
    source : str or None
        Path of the results table, when known.
    report : pathlib.Path or None
        The HTML report of the run, when one exists.
    """

    title: str
    criteria: tuple[Criterion, ...]
    source: str | None = None
    report: Path | None = None
    notes: tuple[str, ...] = field(default=())

    @property
    def passed(self) -> bool:
        """True when every criterion passed."""
        return all(c.passed for c in self.criteria)

    @property
    def failed(self) -> tuple[Criterion, ...]:
        """The criteria that failed."""
        return tuple(c for c in self.criteria if not c.passed)

    def message(self) -> str:
        """The full text: a headline, every criterion, notes and where the report is."""
        n_fail = len(self.failed)
        verdict = f"FAILED {n_fail} of {len(self.criteria)} criteria" if n_fail else "passed"
        head = f"{self.title}: {verdict}"
        if self.source:
            head += f" (results: {self.source})"
        lines = [head, *(c.line() for c in self.criteria), *self.notes]
        if self.report is not None:
            lines.append(f"Report: {self.report}")
        elif self.source:
            run_dir = Path(self.source).parent
            lines.append(f"No {REPORT_FILE} next to the results; `housner report {run_dir}` renders the CDFs.")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.message()


class CDFAgreementError(AssertionError):
    """The distributions of two engines do not agree within the tolerances.

    Attributes
    ----------
    result : AgreementReport
        Every criterion checked (``result.failed`` for the failed ones).
    """

    def __init__(self, result: AgreementReport):
        self.result = result
        super().__init__(result.message())

    @property
    def criteria(self) -> tuple[Criterion, ...]:
        return self.result.criteria

    @property
    def report(self) -> Path | None:
        return self.result.report


class RecordAgreementError(CDFAgreementError):
    """Two engines disagree on too many records (see :func:`assert_record_agreement`)."""


def fmt_value(x: float, digits: int = 3) -> str:
    if np.isposinf(x):
        return "overturn"
    if np.isnan(x):
        return "n/a"
    return f"{x:.{digits}f}"


def limit_text(what: str, value: float, threshold: float, *, upper: bool = True) -> tuple[str, float]:
    """Words for 'value against threshold' and the excess (> 0 = failed)."""
    excess = value - threshold if upper else threshold - value
    if math.isnan(excess):
        return f"limit {what} = {threshold:g}; cannot be evaluated", math.inf
    if excess > 0:
        return f"limit {what} = {threshold:g}; {'exceeded' if upper else 'short'} by {excess:.3g}", excess
    return f"limit {what} = {threshold:g}; margin {-excess:.3g}", excess


def check_tol(name: str, value, *, allow_none: bool = True) -> None:
    if value is None and allow_none:
        return
    if not (isinstance(value, (int, float, np.integer, np.floating)) and math.isfinite(value) and value >= 0):
        raise ValueError(f"`{name}` must be a finite number >= 0{' or None' if allow_none else ''}, got {value!r}")


def shorten(text, limit: int = 160) -> str:
    """First line of an error, cut to ``limit`` characters."""
    line = str(text).strip().splitlines()[0] if str(text).strip() else ""
    return line if len(line) <= limit else line[: limit - 3] + "..."


def criterion_fields(c: Criterion) -> tuple:
    return c.passed, c.detail, c.value, c.threshold, c.excess


def check_count(name: str, value) -> None:
    if value is not None and not (isinstance(value, (int, np.integer)) and value >= 0):
        raise ValueError(f"`{name}` must be a non-negative integer or None, got {value!r}")


def check_percentiles(percentiles) -> list[tuple[float, float]]:
    if percentiles is None:
        return []
    if not isinstance(percentiles, Mapping):
        raise ValueError(
            "`percentiles` must map percentile levels [%] to absolute tolerances on theta_max/alpha, "
            f"e.g. {{50: 0.1}}; got {percentiles!r}"
        )
    out = []
    for q, tol in percentiles.items():
        if not (isinstance(q, (int, float, np.integer, np.floating)) and 0 <= q <= 100):
            raise ValueError(f"`percentiles` key {q!r} is not a percentile level in [0, 100]")
        if not (isinstance(tol, (int, float, np.integer, np.floating)) and math.isfinite(tol) and tol >= 0):
            raise ValueError(f"`percentiles`[{q!r}] must be a finite tolerance >= 0 on theta_max/alpha, got {tol!r}")
        out.append((float(q), float(tol)))
    return out
