"""The diagnosis' one status vocabulary and its rule, for every kind of evidence (theta histories and outcomes);
the rule is explained in ``docs/explanation/verdict.md``."""

from __future__ import annotations

__all__ = ["STATUSES", "STATUS_RULE", "status_rule"]

#: Every status a diagnosis can end in, whatever its evidence.
STATUSES = ("no_misfit", "explained", "partly_explained", "unexplained", "inconclusive")

#: The status rule: (enough records, an effect in the final model, the plain model's residual a misfit, the final
#: model's a misfit, powered) -> status; None: any. What makes a residual a misfit is the evidence's own test (the
#: residual test against the correct-model floor for theta histories, the outcome floor for outcomes).
STATUS_RULE: tuple[tuple[tuple, str], ...] = (
    ((False, None, None, None, None), "inconclusive"),
    ((True, False, False, None, True), "no_misfit"),
    ((True, False, False, None, False), "inconclusive"),
    ((True, False, True, None, None), "unexplained"),
    ((True, True, None, False, True), "explained"),
    ((True, True, None, False, False), "inconclusive"),
    ((True, True, None, True, None), "partly_explained"),
)


def status_rule(enough_records: bool, has_effects: bool, plain_misfit: bool, final_misfit: bool, powered: bool) -> str:
    """The status from the residual's tests alone (:data:`STATUS_RULE`, one truth table).

    ``plain_misfit`` / ``final_misfit``: the plain / final model's residual is a misfit by its evidence's test;
    ``powered``: the records would show a misfit of the size the verdict promises. A theta-history residual is a
    misfit when its held-out error is significantly and materially above its correct-model floor in a group of
    records, drifts along the recording order, is lowered by a probe of physics outside the library, or lies above
    the floor's band with a localisation quantity far off
    (:func:`housner.scenarios.diagnosis.verdict.decision.decide`); an outcome residual when its held-out log loss
    is above the outcome floor (:func:`housner.scenarios.diagnosis.outcomes.outcome_scores.outcome_floor`).
    """
    got = (bool(enough_records), bool(has_effects), bool(plain_misfit), bool(final_misfit), bool(powered))
    for row, status in STATUS_RULE:
        if all(r is None or r == g for r, g in zip(row, got, strict=True)):
            return status
    raise AssertionError(f"the status rule has no row for {got}")  # the table covers every case
