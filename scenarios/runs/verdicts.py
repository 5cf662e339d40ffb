"""An engine's one verdict against the reference in a run, from one rule: the distribution test and the
record-by-record agreement against the chaos floor, combined.

:func:`engine_verdict` judges one engine's row of the run's comparison table
(:func:`housner.scenarios.execution.tables.compare_engines`, read as an
:class:`~housner.scenarios.execution.tables.EngineSummary`) by the rule of ``docs/explanation/verdict.md``:
the distribution test (:data:`housner.statistics.ensemble_stats.KS_MAX`,
:data:`housner.statistics.ensemble_stats.OVERTURN_TOL`, no failed record,
at least :data:`MIN_RECORDS` records: the defaults of
:func:`housner.reports.assertions.runs.assert_cdf_agreement`) and the share of agreeing records against the
chaos floor, into one of :data:`KINDS`. ``housner run``, the report's headline and
:func:`housner.reports.assertions.verdict.assert_verdict` all ask it through
:meth:`housner.scenarios.runs.view.Run.verdicts`, so they say the same.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from housner.scenarios.execution.tables import EngineSummary
from housner.scenarios.runs.chaos import floor_check, floor_verdict
from housner.statistics.ensemble_stats import KS_MAX, OVERTURN_TOL

__all__ = ["KINDS", "MIN_RECORDS", "EngineVerdict", "RecordAgreement", "engine_verdict"]

#: Fewest records of each engine that a distribution verdict is drawn from: one record moves the KS distance
#: by 1/n, so below 3 / KS_MAX = 20 records a single record's difference is a third of the tolerance
#: or more, and one record gives KS 0 or 1 whatever the engines do. Fewer records: "inconclusive".
MIN_RECORDS = math.ceil(3 / KS_MAX)

#: The verdict's kinds: (badge, the page's badge class, what the engine is good for). Best first.
KINDS = {
    "agrees": ("AGREES", "pass", "good for ensembles and for single records"),
    "ensemble": (
        "ENSEMBLE ONLY",
        "warn",
        "good for ensemble statistics (P[overturn], fragility, percentiles), not for one record's response",
    ),
    "fails": ("FAILS", "fail", "good for neither"),
    "inconclusive": ("INCONCLUSIVE", "na", "too few records to tell"),
    "no data": ("NO DATA", "na", "no usable records"),
}


#: The verdict's first words, by kind.
_HEADS = {
    "agrees": "agrees in distribution and record by record, as closely as chaos allows",
    "ensemble": "its distribution of peak rotations agrees, but record by record it departs more than chaos explains",
    "fails": "its distribution of peak rotations differs from the reference's",
    "inconclusive": "too few records for a verdict",
    "no data": "no usable records to compare",
}


@dataclass(frozen=True)
class RecordAgreement:
    """An engine's record-by-record agreement with the reference against the chaos floor.

    Attributes
    ----------
    share, low, high : float
        The share of records that agree and its 95 % Wilson interval [-].
    floor : float
        The chaos floor: the lowest share the analytic model keeps with itself under the engine's errors [-].
    """

    share: float
    low: float
    high: float
    floor: float

    def text(self) -> str:
        return f"{self.share:.0%} [{self.low:.0%}, {self.high:.0%}] of records agree, chaos floor {self.floor:.0%}"


@dataclass(frozen=True)
class EngineVerdict:
    """What a run says of one engine against the reference (the page, the command line and the assertions).

    Attributes
    ----------
    status : str
        The distribution test alone: ``"PASS"``, ``"FAIL"`` (against the default tolerances),
        ``"inconclusive"`` (fewer than :data:`MIN_RECORDS` records, none failed) or ``"no data"``.
    checks : tuple of (bool, str)
        Each criterion of the distribution test: met, and its figures.
    records : str or None
        The record-by-record verdict against the chaos floor in a sentence
        (:func:`housner.scenarios.runs.chaos.floor_verdict`), None where the run has no floor.
    below_floor : bool or None
        Whether the record-by-record agreement lies below the chaos floor (None: no floor).
    agreement : RecordAgreement or None
        The record-by-record figures (None without a floor).
    """

    status: str
    checks: tuple
    records: str | None = None
    below_floor: bool | None = None
    agreement: RecordAgreement | None = None

    @property
    def records_short(self) -> str | None:
        """The record-by-record figures in short: "28 % [20 %, 37 %] of records agree, chaos floor 47 %" (None
        without a floor)."""
        return None if self.agreement is None else self.agreement.text()

    @property
    def ok(self) -> bool | None:
        """The distribution test: True for PASS, False for FAIL, None otherwise."""
        return {"PASS": True, "FAIL": False}.get(self.status)

    @property
    def kind(self) -> str:
        """The one verdict (a key of :data:`KINDS`), by the rule of ``docs/explanation/verdict.md``."""
        if self.status == "PASS":
            return "agrees" if self.below_floor is False else "ensemble"
        return {"FAIL": "fails", "inconclusive": "inconclusive"}.get(self.status, "no data")

    @property
    def badge(self) -> str:
        """The verdict's badge text: "AGREES", "ENSEMBLE ONLY", "FAILS", "INCONCLUSIVE" or "NO DATA"."""
        return KINDS[self.kind][0]

    @property
    def good_for(self) -> str:
        """What the engine is good for, in a few words."""
        if self.kind == "ensemble" and self.records_short is None:
            return "good for ensemble statistics; for single records not judged"
        return KINDS[self.kind][2]

    @property
    def decided_by(self) -> str:
        """The one figure that decided the verdict, in words."""
        failed = [t for c, t in self.checks if not c]
        if self.kind in ("fails", "inconclusive", "no data"):
            return failed[0] if failed else self.checks[0][1]
        return self.checks[0][1] if self.records_short is None else self.records_short

    def parts(self) -> tuple[str, str, str]:
        """The sentence's three parts: its first words, the deciding figure (:attr:`decided_by`) and what the engine
        is good for (``""`` where too few records or none tell)."""
        kind = self.kind
        if kind == "ensemble" and self.records_short is None:
            head = "its distribution of peak rotations agrees; record by record it was not judged (no chaos floor)"
        elif kind == "fails" and any(not c and "failed record" in t for c, t in self.checks):
            head = "records failed to run"
        else:
            head = _HEADS[kind]
        return head, self.decided_by, "" if kind in ("inconclusive", "no data") else self.good_for

    def sentence(self) -> str:
        """The verdict in one sentence of plain words, its deciding figure in brackets."""
        head, figure, good = self.parts()
        return f"{head} ({figure})" + (f": {good}" if good else "")

    def line(self) -> str:
        """One line for the command line: the badge and the sentence."""
        return f"{self.badge}: {self.sentence()}"

    def figures(self) -> str:
        """Every figure behind the verdict, in one line: the distribution test's, then the record-by-record one."""
        out = f"distribution test {self.status}: " + "; ".join(t for _, t in self.checks)
        if self.records_short:
            out += f"; record by record: {self.records_short}, {'below' if self.below_floor else 'at'} the floor"
        return out


def engine_verdict(summary: EngineSummary, floor=None) -> EngineVerdict:
    """The verdict of one engine (its row of the run's comparison table as a value,
    :attr:`housner.scenarios.runs.view.Run.summaries`) against the default tolerances.

    ``floor`` is the engine's :class:`housner.scenarios.runs.chaos.ChaosFloor`, if the run has one.
    """
    ks, dp, nf = summary.ks_distance, summary.overturn_diff, summary.n_failed
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
    n = summary.n_ok
    if n < MIN_RECORDS and nf == 0:  # a failed record fails at any size; the two statistics need records
        status = "inconclusive"
        checks = (
            (
                False,
                f"only {n} record{'s' if n != 1 else ''}; a distribution verdict needs {MIN_RECORDS}: one "
                f"record moves the KS distance by 1/n = {1 / max(n, 1):.2f}",
            ),
            *checks,
        )
    else:
        status = "PASS" if all(c for c, _ in checks) else "FAIL"
    paired = summary.n_paired
    if floor is None or not paired > 0:  # (NaN: no paired records)
        return EngineVerdict(status, checks)
    n_pair = int(paired)
    k = int(round(summary.agreement_share * n_pair))
    lo, hi, below = floor_check(k, n_pair, floor)
    agreement = RecordAgreement(k / n_pair, float(lo), float(hi), float(floor.share_min))
    return EngineVerdict(status, checks, floor_verdict(k, n_pair, floor), below, agreement)
