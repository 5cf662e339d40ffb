"""The one forward selection of the diagnosis: its loop on a toy evidence, and both kinds of campaign (theta
histories and outcomes) going through it with the one status vocabulary."""

from __future__ import annotations

from dataclasses import dataclass

import campaign_generators as cg
import numpy as np
import test_outcomes as to

from housner.scenarios.campaigns.campaign import load_campaign
from housner.scenarios.diagnosis import diagnose, diagnose_outcomes
from housner.scenarios.diagnosis.outcomes import outcome_diagnosis
from housner.scenarios.diagnosis.selection import forward_selection as fs
from housner.scenarios.diagnosis.selection import history_search
from housner.scenarios.diagnosis.verdict.status import STATUSES


@dataclass(frozen=True)
class _Toy:
    """Candidates with fixed falls: a candidate is chosen when its fall exceeds 1; the state is the tuple added."""

    falls: dict
    skip_at: int = 0

    def pool(self, state, number):
        return tuple(n for n in self.falls if n not in state)

    def not_searched(self, state, rnd):
        return ["skipped"] if rnd.number == self.skip_at else None

    def run(self, state, rnd):
        tried = sorted(rnd.pool, key=lambda n: -self.falls[n])
        return tried, tried[0] if self.falls[tried[0]] > 1 else None

    def accept(self, state, rnd, chosen):
        return (*state, chosen)

    def effects(self, chosen):
        return (chosen,)


def test_the_selection_adds_the_best_until_none_passes():
    state, found = fs.forward_selection(_Toy({"a": 3.0, "b": 2.0, "c": 0.5}), (), max_rounds=5)
    assert state == ("a", "b")
    assert found.selected == ["a", "b"]
    # three rounds: a chosen, b chosen, then c alone and not significant
    assert found.pools == [("a", "b", "c"), ("b", "c"), ("c",)]
    assert found.rounds[-1] == ["c"]


def test_the_selection_stops_at_its_bound_an_empty_pool_or_a_round_not_searched():
    _, found = fs.forward_selection(_Toy({"a": 3.0, "b": 2.0}), (), max_rounds=1)
    assert found.selected == ["a"]
    state, found = fs.forward_selection(_Toy({"a": 3.0, "b": 2.0}), (), max_rounds=5)
    assert state == ("a", "b") and len(found.rounds) == 2  # the third round has no candidate
    state, found = fs.forward_selection(_Toy({"a": 3.0, "b": 2.0}, skip_at=2), (), max_rounds=5)
    assert state == ("a",) and found.rounds[-1] == ["skipped"]


def test_both_kinds_of_campaign_go_through_the_one_selection(tmp_path, monkeypatch):
    # one function, imported by both searches
    assert history_search.forward_selection is fs.forward_selection is outcome_diagnosis.forward_selection
    seen = []

    def spy(evidence, state, max_rounds):
        seen.append(type(evidence).__name__)
        return fs.forward_selection(evidence, state, max_rounds)

    monkeypatch.setattr(history_search, "forward_selection", spy)
    monkeypatch.setattr(outcome_diagnosis, "forward_selection", spy)
    info = cg.cached_campaign(tmp_path / "campaigns", "rotational_damping")
    history = diagnose(load_campaign(info["root"]), effects=["rotational_damping"], n_replicas=4)
    accs = to._pulses(60, seed=5)
    outcomes = diagnose_outcomes(to._campaign(accs, to._truth(accs, 0.06)), folds=3, seed=0, repeats=2)
    assert seen == ["HistoryEvidence", "OutcomeEvidence", "OutcomeEvidence"]  # one selection per repeat
    # one status vocabulary
    assert history.status in STATUSES and outcomes.status in STATUSES
    assert history.selected == ["rotational_damping"]
    assert outcomes.effects and outcomes.effects[0].startswith("contact_inside")
    assert np.all(np.isfinite(outcomes.final.p))
