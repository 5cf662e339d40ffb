"""The effect library on outcome records: which registered effects can change whether a block overturns, the grid
each one's parameter is tabulated on, and every record's overturns over that grid.

An outcome record holds one bit, so an effect enters an outcome model through a table: the records run with the
effect at each value of its grid, over the same bracket of pivots as the plain model
(:mod:`housner.scenarios.diagnosis.outcomes.outcome_models`). Any registered effect is a candidate, a user's own
included, unless the records cannot feel it: an effect of the sensor stage changes only what a sensor reads, an
effect that reads a measured channel needs a channel outcome records do not carry, an effect without a finite
range has no grid, and an effect with its own equation of motion runs record by record, so it is tabulated only
where that takes at most :data:`SOLVER_BUDGET_STEPS` solver steps (each is left out with its reason,
:class:`LeftOut`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from housner._values import JsonValue
from housner.effects import Effect, apply_effects, available_effects, effect_class, make_effect
from housner.effects.registry import STAGE_SENSOR
from housner.model import theta_max_many
from housner.motion import GroundMotion

__all__ = [
    "GRID_SHARES",
    "SOLVER_BUDGET_STEPS",
    "EffectTable",
    "LeftOut",
    "OutcomeEffect",
    "effect_table",
    "outcome_effects",
]

#: A parameter's grid: the neutral value and these shares of the way from it to each bound [-]. A neutral value
#: outside the bounds (an infinitely stiff foundation) gives instead 2 len(GRID_SHARES) + 1 points spaced over the
#: bounds (logarithmically where both are positive).
GRID_SHARES = (0.1, 0.3, 0.6, 1.0)
#: An effect with its own equation of motion (run record by record) is tabulated only where its table takes at most
#: this many solver steps, in steps of the sliding kernel: the samples of a record of median length times the
#: solver's substeps, summed over the grid (each value run once on that record), times the records and the bracket
#: points, times the effect's ``solver_step_cost`` (a flexible foundation's step costs 6.5 of sliding's). A count
#: of work, not a timing, so that the same campaign searches the same effects on every machine and at any load.
#: Measured on 2 cores (2026-11-29): sliding on ASU SP1's 490 records takes 3.9e8 steps in 7-10 s (about 20 ns a
#: step), so the budget is about 25 s; the flexible foundation would take over 1.9e11 there, and 3.9e9 on 200 short
#: pulse records (101 s measured).
SOLVER_BUDGET_STEPS = 1.0e9


@dataclass(frozen=True)
class OutcomeEffect(JsonValue):
    """A library effect as an outcome model tabulates it: one parameter over a grid, any other at its default.

    Attributes
    ----------
    name : str
        Registry name.
    param : str
        The parameter tabulated.
    unit : str
        Its unit.
    neutral : float
        The value at which the effect does nothing [unit].
    values : tuple of float
        The grid [unit], the neutral value left out where it is finite (there the effect is the plain model).
    others : dict of str to float
        Any other parameter, at its default [their units].
    """

    name: str
    param: str
    unit: str
    neutral: float
    values: tuple[float, ...]
    others: dict = field(default_factory=dict)

    def build(self, specimen, value: float) -> Effect:
        """The effect with its parameter at ``value`` [unit]."""
        return make_effect(self.name, specimen, **{self.param: float(value)}, **self.others)

    def at(self, value: float) -> OutcomeEffect:
        """The same effect tabulated at one value (a frozen model's) [unit]."""
        return OutcomeEffect(self.name, self.param, self.unit, self.neutral, (float(value),), dict(self.others))


@dataclass(frozen=True)
class LeftOut(JsonValue):
    """A registered effect the outcome records cannot test, and why.

    Attributes
    ----------
    name : str
    why : str
        ``"sensor"`` (it changes only what a sensor reads), ``"channels"`` (it reads measured channels the
        records lack: ``channels``), ``"no_grid"`` (no finite range for any parameter, or a parameter without a
        default) or ``"slow_solver"`` (its own equation of motion, whose table would take ``steps``).
    channels : tuple of str
    steps : float
        The solver steps its table would take (``"slow_solver"``; nan otherwise), against
        :data:`SOLVER_BUDGET_STEPS`.
    """

    name: str
    why: str
    channels: tuple[str, ...] = ()
    steps: float = math.nan


def _grid(lo: float, hi: float, neutral: float) -> tuple[float, ...]:
    """The values of a parameter with bounds [lo, hi] and this neutral value (see :data:`GRID_SHARES`)."""
    if lo <= neutral <= hi:
        vals = {neutral + s * (b - neutral) for b in (lo, hi) if b != neutral for s in GRID_SHARES}
        return tuple(sorted(float(v) for v in vals))
    n = 2 * len(GRID_SHARES) + 1
    pts = np.geomspace(lo, hi, n) if lo > 0 else np.linspace(lo, hi, n)
    return tuple(float(v) for v in pts)


def _describe(name: str, specimen) -> OutcomeEffect | LeftOut:
    """The effect ``name`` as an outcome model tabulates it, or why it cannot be."""
    cls = effect_class(name)
    if cls.stage >= STAGE_SENSOR:
        return LeftOut(name, "sensor")
    if cls.channels:
        return LeftOut(name, "channels", channels=tuple(cls.channels))
    specs = cls.param_specs
    for key, spec in specs.items():
        bounds = spec.bounds_for(specimen)
        neutral = spec.neutral(specimen) if callable(spec.neutral) else spec.neutral
        others = {k: s.default for k, s in specs.items() if k != key}
        if bounds is None or not all(math.isfinite(b) for b in bounds) or None in others.values():
            continue
        return OutcomeEffect(name, key, spec.unit, float(neutral), _grid(*map(float, bounds), float(neutral)), others)
    return LeftOut(name, "no_grid")


def outcome_effects(specimen, names=None) -> tuple[list[OutcomeEffect], list[LeftOut]]:
    """The library effects an outcome diagnosis searches (``names``, default every registered one), and the ones
    it leaves out with their reasons (a slow solver is left out later, by :func:`effect_table`)."""
    found: list[OutcomeEffect] = []
    left: list[LeftOut] = []
    for name in available_effects() if names is None else names:
        d = _describe(name, specimen)
        (found if isinstance(d, OutcomeEffect) else left).append(d)
    return found, left


@dataclass(frozen=True)
class EffectTable:
    """Every record's overturns with one library effect over its grid.

    Attributes
    ----------
    effect : OutcomeEffect
    overturned : ndarray of bool
        (records, bracket points, len(effect.values)).
    steps : float
        The solver steps its table took, counted as :data:`SOLVER_BUDGET_STEPS` counts them (NaN: all records run
        in one compiled call per value).
    """

    effect: OutcomeEffect
    overturned: np.ndarray = field(repr=False)
    steps: float = math.nan

    def column(self, value: float) -> int:
        """The grid index of ``value`` [unit]; KeyError when the grid does not hold it."""
        hit = np.flatnonzero(np.isclose(self.effect.values, value, rtol=1e-9, atol=1e-12))
        if hit.size == 0:
            raise KeyError(f"{self.effect.name}: {self.effect.param} = {value!r} is not on its grid")
        return int(hit[0])


def _plans(effect: OutcomeEffect, specimen, start, motion: GroundMotion):
    """The effect's plan at every grid value on one motion (``start``: the bracket point's parameters)."""
    return [apply_effects(specimen, motion, [effect.build(specimen, v)], params=start) for v in effect.values]


def _record_by_record(effect: OutcomeEffect, specimen, motions, starts) -> np.ndarray:
    """Overturned or not, (records, starts, values): each record run with the effect's own solver, one plan a run."""
    out = np.empty((len(motions), len(starts), len(effect.values)), dtype=bool)
    for i, mo in enumerate(motions):
        for k, start in enumerate(starts):
            for j, plan in enumerate(_plans(effect, specimen, start, mo)):
                out[i, k, j] = plan.run().overturned
    return out


def effect_table(effect: OutcomeEffect, motions: list[GroundMotion], specimen, starts: list) -> EffectTable | LeftOut:
    """``effect`` tabulated on the records' ``motions`` at each of the pivots' ``starts`` (RockingParams, one per
    bracket point). Effects that only change the rocking parameters or bring kernel terms run all records in one
    compiled call per value; one with its own solver, or one that changes the input, runs record by record, and
    is left out (:class:`LeftOut` ``"slow_solver"``, with its count) when its table would take more than
    :data:`SOLVER_BUDGET_STEPS` solver steps, counted on a record of median length."""
    probe = apply_effects(specimen, motions[0], [effect.build(specimen, effect.values[0])], params=starts[0])
    per_record = probe.solver is not None or type(probe.effects[0]).transform_input is not Effect.transform_input
    n_v = len(effect.values)
    if not per_record:
        accs = [mo.acc for mo in motions]
        dts = np.array([mo.dt for mo in motions])
        out = np.empty((len(motions), len(starts), n_v), dtype=bool)
        for k, start in enumerate(starts):
            for j, plan in enumerate(_plans(effect, specimen, start, motions[0])):
                out[:, k, j] = theta_max_many(specimen, accs, dts, params=plan.params, terms=plan.terms)[1]
        return EffectTable(effect, out)
    typical = motions[int(np.argsort([mo.n for mo in motions], kind="stable")[len(motions) // 2])]  # median length
    per_record, cost = 0.0, float(type(probe.effects[0]).solver_step_cost)
    for plan in reversed(_plans(effect, specimen, starts[0], typical)):  # the stiff end first: it needs the most
        per_record += cost * typical.n * max(int(plan.run().info.get("substeps") or 1), 1)
        steps = per_record * len(motions) * len(starts)
        if steps > SOLVER_BUDGET_STEPS:
            return LeftOut(effect.name, "slow_solver", steps=steps)
    return EffectTable(effect, _record_by_record(effect, specimen, motions, starts), steps=steps)
