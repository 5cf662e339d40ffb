"""Mechanics as composable terms of the one compiled analytic kernel.

An effect that changes the rocking mechanics without replacing the whole equation of motion returns *terms*
from its ``terms(params, specimen)`` hook: a module-level ``@njit`` function (importable by its module and
qualified name, of an installed module or of a plugin loaded with :func:`housner.effects.load_plugin`, and
best written ``@njit(cache=True)``) and its parameter array ``q``, as a :class:`MomentTerm` (an extra
angular acceleration), a :class:`CoulombTerm` (the capacity of a dry moment that holds the block and raises
its uplift threshold) or an :class:`ImpactTerm` (the energy ratio of an impact). The analytic engine
compiles one kernel with every term of a simulation in it, so that several compose: Housner's event-driven
kernel (:mod:`housner._kernel`, :mod:`housner._kernel_steps`) with these hooks, generated from the plain
kernel's source and cached on disk by :mod:`housner.effects.codegen` (:meth:`TermSet.kernel`). Each term's
arguments, units and signs are in ``docs/reference/effects-api.md``; how the kernel locates its events, in
``docs/explanation/physics.md`` ("How the analytic model solves it").
"""

from __future__ import annotations

import importlib
import inspect
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from housner.effects.codegen import compiled_kernel

__all__ = ["CoulombTerm", "ImpactTerm", "MomentTerm", "TermSet"]


def _check_fn(kind: str, fn: Any, n_args: int) -> tuple[str, str]:
    """(module, qualified name) of a term function; ValueError unless it is a module-level @njit function."""
    py = getattr(fn, "py_func", None)
    if py is None:
        raise ValueError(f"a {kind} term's function must be a numba @njit function, got {fn!r}")
    n = len(inspect.signature(py).parameters)
    if n != n_args:
        raise ValueError(f"{kind} term function {py.__qualname__!r} must take {n_args} arguments, it takes {n}")
    mod, qual = py.__module__, py.__qualname__
    found = _import_term(mod, qual, missing=None)
    # the same function, or the same code re-executed (a plugin loaded again)
    same = found is fn or getattr(getattr(found, "py_func", None), "__code__", None) == py.__code__
    if "<locals>" in qual or not same:
        raise ValueError(
            f"{kind} term function {qual!r} must be defined at the top level of an importable module "
            f"(or of a plugin loaded with housner.effects.load_plugin); {mod!r} does not hold it"
        )
    return mod, qual


def _q_values(kind: str, q) -> tuple[float, ...]:
    """The parameters ``q`` of a term as floats; ValueError unless each is a finite number."""
    out = []
    for x in tuple(q):
        if isinstance(x, bool) or not isinstance(x, (int, float, np.integer, np.floating)) or not math.isfinite(x):
            raise ValueError(f"the parameters `q` of a {kind} term must be finite numbers, got {q!r}")
        out.append(float(x))
    return tuple(out)


@dataclass(frozen=True)
class MomentTerm:
    """A smooth extra angular acceleration of the block, a term of the analytic kernel.

    The kernel adds ``fn(...)`` to Housner's equation of motion, written in reduced coordinates on
    the pivot s the block rocks on: ``phi'' = -p2 (sin(alpha - phi) + a cos(alpha - phi)) + (sum of
    the moment terms) - sgn(w) (sum of the Coulomb capacities)``. A moment M [N m] on the block,
    positive when it turns the block toward +x (theta increasing), is the term ``s M / I0_s``, with
    I0_s = m g R_s / p_s^2 the inertia about pivot s.

    Parameters
    ----------
    fn : numba dispatcher
        ``fn(phi, w, t, a, v, s, alpha, p2, q) -> float``: returns the extra phi'' [rad/s^2],
        positive away from upright. Its arguments, in this order (names free), are floats but q:

        - ``phi`` = s theta [rad], the rotation toward the pivot: >= 0 while the block rocks on s,
          0 at rest, slightly negative while an impact is being located;
        - ``w`` = s theta' [rad/s]: > 0 moving away from upright, < 0 falling back;
        - ``t``: time since the start of the motion [s];
        - ``a`` = s ug''/g [-]: the horizontal ground acceleration the block feels (after every
          ``transform_input``), linear between samples; a < -tan(alpha) lifts the block onto s;
        - ``v`` = a_v/g [-]: the vertical table acceleration, positive up, the same on both
          pivots; 0 unless an effect of the simulation reads or makes the channel
          ``ground_acc_vertical``;
        - ``s``: the pivot, +1.0 for the +x corner (theta > 0), -1.0 for the -x corner;
        - ``alpha`` [rad] and ``p2`` = p^2 [1/s^2]: slenderness and squared frequency parameter
          of pivot s, after every ``modify_params``;
        - ``q``: this term's parameters, a float64 array in the order given.

        A numba ``@njit`` function (write ``@njit(cache=True)``) at the top level of a module
        importable by name (an installed module, or a plugin file loaded with
        ``housner.effects.load_plugin``); pure (it keeps no state and never writes into q: the
        kernel calls it at trial states, out of time order), finite, and smooth in phi, w and t
        within a sample (a moment that switches with the direction of motion is a
        ``CoulombTerm``).
    q : sequence of float
        The term's parameters, finite numbers in the units ``fn`` reads them in; run-time data (a
        new value recompiles nothing).
    at_rest : bool
        Whether the moment may be non-zero at phi = w = 0 (default True). With such a term (or a
        Coulomb term) in the simulation a block at rest, or stuck, starts to move at the first
        instant at which phi'' at w = 0, the terms included, is positive on a corner (exceeds the
        dry capacity): the uplift rule becomes the net moment's. Without one the kernel keeps
        Housner's rule a <= -tan(alpha) and does not evaluate the terms at rest. False is right
        for a moment that vanishes at rest (damping, drag: proportional to w); a moment that acts
        on a block at rest (a vertical input, a steady force, a tilted base) declared False is
        ignored until the block lifts by Housner's rule. MuJoCo realises only False moments.

    Raises
    ------
    ValueError
        ``fn`` is not a module-level numba function of 9 arguments, or ``q`` holds a value that is
        not a finite number.

    Notes
    -----
    The kernel calls ``fn`` at each of the four stages of each RK4 step while the block moves, in
    the iterations that locate its events (impact, peak, overturn), and, when a term acts at rest,
    at the hold checks on both corners. The moments of all effects add up.
    """

    fn: Any
    q: tuple = ()
    at_rest: bool = True

    def __post_init__(self) -> None:
        _check_fn("moment", self.fn, 9)
        object.__setattr__(self, "q", _q_values("moment", self.q))
        object.__setattr__(self, "at_rest", bool(self.at_rest))


@dataclass(frozen=True)
class CoulombTerm:
    """A dry (Coulomb) moment at the pivot, a term of the analytic kernel: it resists turning and holds the block.

    While the block turns, the kernel adds -C sgn(w) to phi'' (the direction is frozen over a
    step; a step in which w reaches 0 is cut there). At w = 0 the block holds while the other
    moments stay within +-C: stuck at phi > 0, or at rest on the ground, from which it lifts onto
    a corner only once phi'' there exceeds C (a raised uplift threshold). A Coulomb term makes the
    kernel use the net moment's uplift rule (see ``MomentTerm``'s ``at_rest``). The capacities of
    all Coulomb terms add up.

    Parameters
    ----------
    fn : numba dispatcher
        ``fn(phi, t, a, v, s, alpha, p2, q) -> float``: returns the capacity C >= 0 [rad/s^2],
        M_f / I0_s for a dry moment M_f [N m] at pivot s (I0_s = m g R_s / p_s^2). Its arguments
        are ``MomentTerm``'s without w: ``phi`` = s theta [rad], ``t`` [s], ``a`` = s ug''/g
        [-], ``v`` = a_v/g [-] (positive up; 0 without a ``ground_acc_vertical`` channel), ``s``
        (+1.0 for the +x corner, -1.0), ``alpha`` [rad] and ``p2`` = p^2 [1/s^2] of pivot s, and
        ``q``, this term's parameters (a float64 array). The same rules as a moment's function:
        a module-level numba ``@njit`` function, pure, finite.
    q : sequence of float
        The term's parameters, finite numbers (units as ``fn`` reads them).

    Raises
    ------
    ValueError
        ``fn`` is not a module-level numba function of 8 arguments, or ``q`` holds a value that is
        not a finite number.
    """

    fn: Any
    q: tuple = ()

    def __post_init__(self) -> None:
        _check_fn("Coulomb", self.fn, 8)
        object.__setattr__(self, "q", _q_values("Coulomb", self.q))


@dataclass(frozen=True)
class ImpactTerm:
    """A change of the impact law, a term of the analytic kernel: it gives the energy ratio r' of an impact.

    At an impact the angular velocity after is sqrt(r') times the one before. The kernel starts
    from the rocking parameters' ratio of the corner that lands (``r_pos`` or ``r_neg``,
    Housner's by default) and passes it through the impact terms: those with ``replaces`` first,
    then the others, each in the order of the effects; the amplitude exponent of the rocking
    parameters applies last. Then the rest rule: a block whose new speed could not lift it above
    ``rest_tol`` alpha in free rocking is put at rest.

    Parameters
    ----------
    fn : numba dispatcher
        ``fn(w, r, s, alpha, p2, q) -> float``: returns the energy ratio r' [-], in [0, 1] (it is
        not clipped: above 1 the impact adds energy). Called once per impact with ``w`` the speed
        just before it [rad/s] (> 0), ``r`` the ratio in force [-] (of the corner that lands, or
        the previous impact term's result), ``s`` the pivot before the impact (+1.0 for the +x
        corner, -1.0; the block lands on -s), ``alpha`` [rad] and ``p2`` = p^2 [1/s^2] of pivot
        s, and ``q``, this term's parameters (a float64 array). A module-level numba ``@njit``
        function, pure, finite.
    q : sequence of float
        The term's parameters, finite numbers (units as ``fn`` reads them).
    replaces : bool
        The law sets the ratio without reading r (a restitution); such laws run before those
        that modify the ratio in force (an amplitude dependence), whatever the order of the
        effects. Default False.

    Raises
    ------
    ValueError
        ``fn`` is not a module-level numba function of 6 arguments, or ``q`` holds a value that is
        not a finite number.
    """

    fn: Any
    q: tuple = ()
    replaces: bool = False

    def __post_init__(self) -> None:
        _check_fn("impact", self.fn, 6)
        object.__setattr__(self, "q", _q_values("impact", self.q))
        object.__setattr__(self, "replaces", bool(self.replaces))


_KINDS = {MomentTerm: "moment", CoulombTerm: "coulomb", ImpactTerm: "impact"}


@dataclass(frozen=True)
class TermSet:
    """The terms of one simulation, in kernel order, and whether the kernel reads the vertical channel.

    Parameters
    ----------
    terms : sequence of MomentTerm, CoulombTerm, ImpactTerm
        In the order of the effects; impact terms that ``replaces`` are moved before the others.
    vertical : bool
        Drive v with the motion's ``ground_acc_vertical`` channel (else v = 0).
    """

    terms: tuple
    vertical: bool = False

    def __post_init__(self) -> None:
        terms = tuple(self.terms)
        for i, t in enumerate(terms):
            if type(t) not in _KINDS:
                raise TypeError(f"term {i} must be a MomentTerm, CoulombTerm or ImpactTerm, got {type(t).__name__}")
        impacts = [t for t in terms if isinstance(t, ImpactTerm)]
        ordered = [t for t in impacts if t.replaces] + [t for t in impacts if not t.replaces]
        it = iter(ordered)
        terms = tuple(next(it) if isinstance(t, ImpactTerm) else t for t in terms)
        object.__setattr__(self, "terms", terms)
        object.__setattr__(self, "vertical", bool(self.vertical))

    def __bool__(self) -> bool:
        return bool(self.terms)

    @property
    def structure(self) -> tuple:
        """What the compiled kernel depends on: each term's kind, function, parameter count and flag."""
        return tuple(
            (
                _KINDS[type(t)],
                t.fn.py_func.__module__,
                t.fn.py_func.__qualname__,
                len(t.q),
                getattr(t, "at_rest", getattr(t, "replaces", False)),
            )
            for t in self.terms
        )

    def q_array(self) -> np.ndarray:
        """Every term's parameters in one float64 array, in kernel order."""
        return np.array([x for t in self.terms for x in t.q], dtype=np.float64)

    def kernel(self) -> Any:
        """The compiled kernel of this structure (generated, imported and cached once): its module, whose
        entry points (``run_one``, ``run_batch``, ``run_batch_parallel``) run again once without numba's
        cache files when loading those raises."""
        return compiled_kernel(self.structure)

    def describe(self) -> list[dict]:
        """Plain data for ``Response.info``: each term's kind, function and parameters."""
        return [
            {"term": k, "fn": f"{m}.{n}", "q": list(t.q)}
            for (k, m, n, _nq, _f), t in zip(self.structure, self.terms, strict=True)
        ]


def _import_term(module: str, qualname: str, missing: Any = ...) -> Any:
    """The object ``qualname`` of ``module`` (imported if need be); ``missing`` when absent, if given.

    The kernels generated by :mod:`housner.effects.codegen` import their term functions with it, by
    this module's name (the text of a generated kernel is part of its cache key).
    """
    try:
        obj = sys.modules.get(module) or importlib.import_module(module)
        for part in qualname.split("."):
            obj = getattr(obj, part)
    except (ImportError, AttributeError):
        if missing is not ...:
            return missing
        raise
    return obj


def term_set(terms: Sequence, vertical: bool = False) -> TermSet | None:
    """A :class:`TermSet` of ``terms``, or None when there is none."""
    terms = tuple(terms)
    return TermSet(terms, vertical) if terms else None
