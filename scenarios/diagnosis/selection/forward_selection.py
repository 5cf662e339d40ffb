"""The one forward selection of the diagnosis: rounds that try the candidate effects on the current model and add
the one that lowers the held-out error significantly, for every kind of evidence. What a kind of evidence brings is
an :class:`Evidence`: its pool of candidates, how it tries them and how it adds the chosen one (theta histories:
:class:`housner.scenarios.diagnosis.selection.history_search.HistoryEvidence`; outcomes:
:class:`housner.scenarios.diagnosis.outcomes.outcome_diagnosis.OutcomeEvidence`). The method is in
``docs/explanation/diagnosis.md``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Generic, Protocol, TypeVar

__all__ = ["Evidence", "Round", "Selection", "forward_selection"]

State = TypeVar("State")
Choice = TypeVar("Choice")


@dataclass(frozen=True)
class Round:
    """One round of the selection: its number (1 first) and the candidates it may try."""

    number: int
    pool: tuple[str, ...]


class Evidence(Protocol[State, Choice]):
    """What the forward selection asks of a kind of evidence; each method returns values and keeps no state."""

    def pool(self, state: State, number: int) -> tuple[str, ...]:
        """The candidates round ``number`` may try on ``state``'s current model (none: the selection stops)."""

    def not_searched(self, state: State, rnd: Round) -> list | None:
        """The round's record when nothing is left for an effect to lower (the selection stops), else None."""

    def run(self, state: State, rnd: Round) -> tuple[list, Choice | None]:
        """The round tried: every candidate's result, best first, and the chosen one (None: none is significant)."""

    def accept(self, state: State, rnd: Round, chosen: Choice) -> State:
        """``state`` with ``chosen`` added: the next step of the ladder."""

    def effects(self, chosen: Choice) -> tuple[str, ...]:
        """The effects ``chosen`` adds."""


@dataclass(frozen=True)
class Selection(Generic[Choice]):
    """What the forward selection did.

    Attributes
    ----------
    rounds : list of list
        Each round's results, as the evidence reports them (best first).
    pools : list of tuple of str
        Each round's candidates.
    selected : list of str
        The effects added, in order.
    chosen : list
        The chosen result of each round that added one.
    stopped_unsearched : bool
        Whether the last round was not searched: nothing was left for an effect to lower.
    """

    rounds: list[list[Any]]
    pools: list[tuple[str, ...]]
    selected: list[str]
    chosen: list[Choice]
    stopped_unsearched: bool = False


def forward_selection(evidence: Evidence[State, Choice], state: State, max_rounds: int) -> tuple[State, Selection]:
    """Forward selection from ``state``: at most ``max_rounds`` rounds, each adding the significant candidate the
    evidence chooses, until a round has no candidate, nothing left to lower, or no significant one.

    Returns the state it ends in and what it did.
    """
    rounds: list[list[Any]] = []
    pools: list[tuple[str, ...]] = []
    selected: list[str] = []
    chosen_all: list[Choice] = []
    unsearched = False
    for number in range(1, max_rounds + 1):
        pool = tuple(evidence.pool(state, number))
        if not pool:
            break
        rnd = Round(number, pool)
        pools.append(pool)
        skipped = evidence.not_searched(state, rnd)
        if skipped is not None:
            rounds.append(skipped)
            unsearched = True
            break
        tried, chosen = evidence.run(state, rnd)
        rounds.append(tried)
        if chosen is None:
            break
        state = evidence.accept(state, rnd, chosen)
        selected.extend(evidence.effects(chosen))
        chosen_all.append(chosen)
    return state, Selection(rounds, pools, selected, chosen_all, unsearched)
