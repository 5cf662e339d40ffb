"""The effect library on outcome records: which registered effects can change whether a block overturns, the grid
each one's parameter is tabulated on, and every record's overturns over that grid.

An outcome record holds one bit, so an effect enters an outcome model through a table: the records run with the
effect at each value of its grid, over the same bracket of pivots as the plain model
(:mod:`housner.scenarios.diagnosis.outcomes.outcome_models`). Any registered effect is a candidate, a user's own
included, unless the records cannot feel it: an effect of the sensor stage changes only what a sensor reads, an
effect that reads a measured channel needs a channel outcome records do not carry, an effect without a finite
range has no grid, and an effect with its own equation of motion runs record by record, so it is tabulated only
where that takes at most :data:`SOLVER_BUDGET_S` (each is left out with its reason, :class:`LeftOut`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from housner._values import JsonValue
from housner.effects import Effect, apply_effects, available_effects, effect_class, make_effect
from housner.effects.registry import STAGE_SENSOR
from housner.model import theta_max_many
from housner.motion import GroundMotion

__all__ = [
    "GRID_SHARES",
    "SOLVER_BUDGET_S",
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
#: An effect with its own equation of motion (run record by record) is tabulated only where its table's runs are
#: estimated, from one timed run per grid value on a record of median length after a warm-up, to take at most
#: this [s]. The estimate is rough (records that rock longer cost more): on 120 short pulse records the flexible
#: foundation is estimated at 19 s and takes 44 s. Sliding on ASU SP1's 490 records is estimated at about 10 s (it
#: takes about 7 s), at this budget: whether it is searched there depends on the machine and its load, and two
#: runs of the same diagnosis have differed in it. The diagnosis names each effect it left out, with its estimate.
SOLVER_BUDGET_S = 10.0


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
        default) or ``"slow_solver"`` (its own equation of motion, estimated at ``seconds`` for its table).
    channels : tuple of str
    seconds : float
        The estimated time of its table [s] (``"slow_solver"``; nan otherwise).
    """

    name: str
    why: str
    channels: tuple[str, ...] = ()
    seconds: float = math.nan


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
    """

    effect: OutcomeEffect
    overturned: np.ndarray = field(repr=False)

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
    is left out (:class:`LeftOut` ``"slow_solver"``, with the time estimated so far: a lower bound) when timed runs
    on one record say its table would take more than :data:`SOLVER_BUDGET_S`."""
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
    typical = motions[int(np.argsort([mo.n for mo in motions])[len(motions) // 2])]  # a median-length record
    plans = _plans(effect, specimen, starts[0], typical)
    plans[0].run()  # a warm-up: the first run may compile the solver
    spent = 0.0
    for plan in reversed(plans):  # the far end of the grid first: a stiff foundation costs the most there
        t0 = time.perf_counter()
        plan.run()
        spent += time.perf_counter() - t0
        estimate = spent * len(motions) * len(starts)
        if estimate > SOLVER_BUDGET_S:
            return LeftOut(effect.name, "slow_solver", seconds=float(estimate))
    return EffectTable(effect, _record_by_record(effect, specimen, motions, starts))
