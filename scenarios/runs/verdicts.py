"""An engine's verdict against the reference in a run: the distribution's, and record by record against the
chaos floor.

:func:`engine_verdict` judges one engine's row of the run's comparison table
(:func:`housner.scenarios.execution.tables.compare_engines`) against the default tolerances of
:func:`housner.reports.assertions.runs.assert_cdf_agreement` (:data:`housner.stats.KS_MAX`,
:data:`housner.stats.OVERTURN_TOL`, no failed record), so that ``housner run``, the report's
headline and users' CI say the same; :meth:`housner.scenarios.runs.view.Run.verdicts` asks it for
every engine of a run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import pandas as pd

from housner.scenarios.runs.chaos import floor_check, floor_verdict
from housner.stats import KS_MAX, OVERTURN_TOL

__all__ = ["MIN_RECORDS", "EngineVerdict", "engine_verdict"]

#: Fewest records of each engine that a distribution verdict is drawn from: one record moves the KS distance
#: by 1/n, so below 3 / KS_MAX = 20 records a single record's difference is a third of the tolerance
#: or more, and one record gives KS 0 or 1 whatever the engines do. Fewer records: "inconclusive".
MIN_RECORDS = math.ceil(3 / KS_MAX)


@dataclass(frozen=True)
class EngineVerdict:
    """What a run says of one engine against the reference, in plain text (the page and the command line).

    Attributes
    ----------
    status : str
        The distribution verdict: ``"PASS"``, ``"FAIL"`` (against the default tolerances),
        ``"inconclusive"`` (fewer than :data:`MIN_RECORDS` records, none failed) or ``"no data"``.
    checks : tuple of (bool, str)
        Each criterion: met, and its figures.
    records : str or None
        The record-by-record verdict against the chaos floor
        (:func:`housner.scenarios.runs.chaos.floor_verdict`), None where the run has no floor.
    below_floor : bool or None
        Whether the record-by-record agreement lies below the chaos floor.
    records_short : str or None
        The record-by-record figures in short: "28 % [20 %, 37 %] vs chaos floor 66 %" (None without a floor).
    """

    status: str
    checks: tuple
    records: str | None = None
    below_floor: bool | None = None
    records_short: str | None = None

    @property
    def ok(self) -> bool | None:
        """True for PASS, False for FAIL, None otherwise (as a page's badge takes it)."""
        return {"PASS": True, "FAIL": False}.get(self.status)

    def line(self) -> str:
        """One line for the command line: the distribution verdict, its figures, the record-by-record one."""
        figures = "; ".join(t for _, t in self.checks)
        if self.records_short:
            side = "below the floor" if self.below_floor else "at the floor"
            return f"{self.status}: {figures}; record by record: {self.records_short}, {side}"
        return f"{self.status}: {figures}"


def engine_verdict(row: pd.Series, floor=None) -> EngineVerdict:
    """The verdict of one engine (its row of the run's comparison table) against the default tolerances.

    ``floor`` is the engine's :class:`housner.scenarios.runs.chaos.ChaosFloor`, if the run has one.
    """
    ks, dp, nf = float(row["ks_distance"]), float(row["overturn_diff"]), int(row["n_failed"])
    if math.isnan(ks) or math.isnan(dp):
        return EngineVerdict("no data", ((False, "no usable records to compare"),))
    checks = (
        (ks <= KS_MAX, f"KS {ks:.3f} {'<=' if ks <= KS_MAX else '>'} {KS_MAX}"),
        (
            abs(dp) <= OVERTURN_TOL,
            f"|dP[overturn]| {abs(dp):.3f} {'<=' if abs(dp) <= OVERTURN_TOL else '>'} {OVERTURN_TOL}",
        ),
        (nf == 0, f"{nf} failed record{'s' if nf != 1 else ''}"),
    )
    n = int(row["n_ok"])
    if n < MIN_RECORDS and nf == 0:  # a failed record fails at any size; the two statistics need records
        status = "inconclusive"
        checks = ((False, f"only {n} record{'s' if n != 1 else ''} (a distribution verdict needs {MIN_RECORDS}: one "
                   f"record moves the KS distance by 1/n = {1 / max(n, 1):.2f})"), *checks)  # fmt: skip
    else:
        status = "PASS" if all(c for c, _ in checks) else "FAIL"
    paired = float(row.get("n_paired", 0) or 0)
    if floor is None or not paired > 0:  # (NaN: no paired records)
        return EngineVerdict(status, checks)
    n_pair = int(paired)
    k = int(round(float(row["agreement_share"]) * n_pair))
    lo, hi, below = floor_check(k, n_pair, floor)
    short = f"{k / n_pair:.0%} [{lo:.0%}, {hi:.0%}] vs chaos floor {floor.share:.0%}"
    return EngineVerdict(status, checks, floor_verdict(k, n_pair, floor), below, short)
