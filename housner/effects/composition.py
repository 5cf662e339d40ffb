"""Composition of effects for one simulation: :func:`apply_effects` resolves them into an :class:`EffectPlan`."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace
from typing import Any

from housner.effects.registry import Effect
from housner.effects.terms import TermSet
from housner.model import simulate
from housner.motion import VERTICAL, GroundMotion
from housner.response import Response
from housner.rocking_params import RockingParams
from housner.specimen import Specimen

__all__ = ["EffectPlan", "apply_effects", "simulate_with_effects"]


@dataclass(frozen=True, eq=False)
class EffectPlan:
    """Effects resolved for one (specimen, motion): what the solver is given and what it does afterwards.

    Attributes
    ----------
    specimen : Specimen
    effects : tuple of Effect
        In the order of application.
    params : RockingParams
        The rocking parameters after every ``modify_params``.
    motion : GroundMotion
        The ground motion after every ``transform_input``.
    solver : callable or None
        The mechanics effect's equation of motion; None for Housner's.
    mechanics : Effect or None
        The effect that supplied ``solver``.
    terms : TermSet or None
        The effects' terms for the analytic kernel (:mod:`housner.effects.terms`); None for none.
    """

    specimen: Specimen
    effects: tuple
    params: Any
    motion: GroundMotion
    solver: Callable[..., Response] | None = None
    mechanics: Effect | None = None
    terms: Any = None

    def observe(self, response: Response) -> Response:
        """Apply every ``observe`` hook and list the effects in ``response.info['effects']``."""
        for e in self.effects:
            out = e.observe(response)
            if not isinstance(out, Response):
                raise TypeError(f"effect {e.name!r}: observe() must return a Response, got {type(out).__name__}")
            response = out
        return replace(response, info={**response.info, "effects": [e.describe() for e in self.effects]})

    def run(self, *, substeps: int | None = None, rest_tol: float = 1e-6) -> Response:
        """Simulate: the solver on (specimen, motion, params), then the observers.

        Parameters
        ----------
        substeps : int, optional
            RK4 substeps per sample; default: the solver's.
        rest_tol : float
            Rest rule of :func:`housner.model.simulate` [-].
        """
        if self.solver is None:
            res = simulate(
                self.specimen, self.motion, params=self.params, substeps=substeps, rest_tol=rest_tol, terms=self.terms
            )
        else:
            res = self.solver(self.specimen, self.motion, self.params, substeps=substeps, rest_tol=rest_tol)
        return self.observe(res)


def apply_effects(
    specimen: Specimen,
    motion: GroundMotion,
    effects: Iterable[Effect] = (),
    *,
    params=None,
    prefer_terms: bool = False,
) -> EffectPlan:
    """Resolve ``effects`` for one simulation (the order they compose in: the ``housner.effects`` package docstring).

    Parameters
    ----------
    specimen : Specimen
    motion : GroundMotion
    effects : iterable of Effect
        At most one of each name, and at most one that changes the mechanics.
    params : RockingParams, optional
        Starting parameters; default ``RockingParams.from_specimen(specimen)``.
    prefer_terms : bool
        Realise the effects that have a fast path (``Effect.fast_path``: restitution, its
        amplitude dependence, rotational damping) through their kernel terms instead; the same
        physics (the tests check it), for comparisons and benchmarks.

    Returns
    -------
    EffectPlan
        Call its ``run()`` to simulate.

    Raises
    ------
    ValueError
        An effect given twice, two mechanics effects, a mechanics effect with terms, a value out
        of bounds, or a channel an effect reads that ``motion`` does not carry (naming both).
    """
    if not isinstance(specimen, Specimen):
        raise TypeError(f"`specimen` must be a housner.Specimen, got {type(specimen).__name__}")
    if not isinstance(motion, GroundMotion):
        raise TypeError(f"`motion` must be a housner.GroundMotion, got {type(motion).__name__}")
    effects = tuple(effects)
    _check_effects(specimen, motion, effects)
    ordered = tuple(sorted(effects, key=lambda e: e.stage))
    by_terms = [prefer_terms and type(e).fast_path for e in ordered]
    prm = _rocking_params(specimen, ordered, by_terms, params)
    mo = motion
    for e in ordered:
        mo = e.transform_input(mo)
        if not isinstance(mo, GroundMotion):
            raise TypeError(f"effect {e.name!r}: transform_input() must return a GroundMotion, got {type(mo).__name__}")
    solver, mechanics = _solver(ordered)
    terms = _terms(specimen, ordered, by_terms, prm, mechanics)
    return EffectPlan(specimen, ordered, prm, mo, solver, mechanics, terms)


def _check_effects(specimen: Specimen, motion: GroundMotion, effects: tuple) -> None:
    """Refuse effects that are not Effects, given twice, out of bounds for ``specimen``, reading a channel
    ``motion`` lacks (and no effect makes), or two that each replace the equation of motion."""
    seen: dict[str, int] = {}
    made = {c for x in effects if isinstance(x, Effect) for c in type(x).makes_channels}
    for i, e in enumerate(effects):
        if not isinstance(e, Effect):
            raise TypeError(
                f"`effects[{i}]` must be a housner.effects.Effect (build one with make_effect(name, ...)), "
                f"got {type(e).__name__}"
            )
        if e.name in seen:
            raise ValueError(f"effect {e.name!r} given twice (effects[{seen[e.name]}] and effects[{i}]); give it once")
        seen[e.name] = i
        e.check(specimen)
        for ch in type(e).channels:
            if ch not in motion.channels and ch not in made:
                raise ValueError(
                    f"effect {e.name!r} reads the channel {ch!r}, which motion {motion.name!r} does not carry"
                )
    mech = [e.name for e in effects if e.changes_mechanics]
    if len(mech) > 1:
        raise ValueError(
            f"effects {' and '.join(repr(m) for m in mech)} each replace the equation of motion and cannot be "
            "combined: give at most one mechanics-changing effect per simulation"
        )


def _rocking_params(specimen: Specimen, ordered: tuple, by_terms: list, params) -> RockingParams:
    """The rocking parameters after every ``modify_params`` but those of the effects realised by their terms."""
    prm = RockingParams.from_specimen(specimen) if params is None else params
    for e, skip in zip(ordered, by_terms, strict=True):
        if skip:
            continue
        prm = e.modify_params(prm, specimen)
        if not isinstance(prm, RockingParams):
            raise TypeError(f"effect {e.name!r}: modify_params() must return a RockingParams, got {type(prm).__name__}")
    return prm


def _solver(ordered: tuple) -> tuple[Callable[..., Response] | None, Effect | None]:
    """The mechanics effect's equation of motion and that effect (None, None for Housner's); ValueError
    when it conflicts with another effect given."""
    solver = None
    mechanics = None
    for e in ordered:
        s = e.solver()
        if s is not None:
            solver, mechanics = s, e
    if mechanics is not None:
        clash = [e.name for e in ordered if e.name in mechanics.conflicts]
        if clash:
            raise ValueError(
                f"effect {mechanics.name!r} cannot be combined with {', '.join(repr(c) for c in clash)}: "
                f"{mechanics.conflict_reason}"
            )
    return solver, mechanics


def _terms(specimen: Specimen, ordered: tuple, by_terms: list, prm: RockingParams, mechanics: Effect | None):
    """The effects' kernel terms from the final rocking parameters (a TermSet, or None for none); ValueError
    when a mechanics effect would take them."""
    terms, with_terms = [], []
    for e, by in zip(ordered, by_terms, strict=True):
        if type(e).fast_path and not by:
            continue  # realised by its parameters
        ts = e.terms(prm, specimen)
        if not isinstance(ts, (tuple, list)):
            raise TypeError(f"effect {e.name!r}: terms() must return a tuple of terms, got {type(ts).__name__}")
        if ts:
            terms += list(ts)
            with_terms.append(e.name)
    if mechanics is not None and with_terms:
        raise ValueError(
            f"effect {mechanics.name!r} replaces the equation of motion and cannot take the kernel terms of "
            f"{', '.join(repr(n) for n in with_terms)}: give it alone or drop those"
        )
    vertical = any(VERTICAL in type(e).channels or VERTICAL in type(e).makes_channels for e in ordered)
    return TermSet(tuple(terms), vertical) if terms else None


def simulate_with_effects(
    specimen: Specimen,
    motion: GroundMotion,
    effects: Iterable[Effect] = (),
    *,
    params=None,
    substeps: int | None = None,
    rest_tol: float = 1e-6,
    prefer_terms: bool = False,
) -> Response:
    """Simulate ``motion`` on ``specimen`` with ``effects``: ``apply_effects(...).run(...)``.

    ``specimen``, ``motion``, ``effects``, ``params`` (the starting
    parameters, default the specimen's Housner parameters) and ``prefer_terms``
    are those of :func:`apply_effects`; ``substeps`` and ``rest_tol`` those of
    :meth:`EffectPlan.run`.
    """
    plan = apply_effects(specimen, motion, effects, params=params, prefer_terms=prefer_terms)
    return plan.run(substeps=substeps, rest_tol=rest_tol)
