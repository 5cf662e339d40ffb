"""Fitting an effect's parameters to measured records: grids over the bounds, then a local search.

Used by the diagnosis (:mod:`housner.scenarios.diagnosis.diagnose`, step 2 "Fit" of
``docs/explanation/diagnosis.md``, "The search, step by step") and by the verdict's floor
(:mod:`housner.scenarios.diagnosis.verdict.decision`, which perturbs fitted parameters within the same
bounds). The objective is any function of an effect instance, in practice the training loss of
:class:`housner.scenarios.diagnosis.selection.record_scoring.Scorer` [alpha]; parameters are searched in log
space where their bounds span more than a factor 20.

A parameter value the effect refuses (a ``ValueError``) is a point the search avoids; a model whose
histories are not finite (:class:`housner.scenarios.diagnosis.selection.record_scoring.NonFiniteScore`) is not: it
stops the fit, and the caller refuses the effect by name.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import optimize

from housner.effects import effect_class, make_effect
from housner.scenarios.diagnosis.selection.record_scoring import NonFiniteScore

__all__ = [
    "FIT_BOUNDS",
    "N_GRID",
    "N_GRID_MULTI",
    "N_ZOOM",
    "N_ZOOM_MULTI",
    "ParamDim",
    "build_model",
    "effect_objective",
    "fit_effect",
    "joint_refit",
    "param_dims",
]

#: Grid points per parameter of the coarse search (one-parameter effects) [-].
N_GRID = 17
#: Grid points of the zoom around the best coarse point [-].
N_ZOOM = 9
#: Grid points per parameter of an effect with several parameters, and of the zoom around its best
#: point [-]: a 9 x 9 grid puts a point within 7 % of any frequency in 10-100 Hz (log-spaced), and the
#: error of a flexible foundation's fit doubles within ~10 % of its frequency (measured on a
#: synthetic 25 Hz campaign), so a coarser grid can land outside the basin.
N_GRID_MULTI = 9
N_ZOOM_MULTI = 5
#: Search ranges that differ from the effect's own bounds, with the reason.
#: flexible_foundation.frequency: below 10 Hz the block would settle by more than g/(2 pi 10 Hz)^2 = 2.5 mm
#: under its own weight (not a rocking test on a table); above 100 Hz an impact lasts about half a
#: vertical period, 5 ms or less, under 2.5 samples at 500 Hz: what the sensor can resolve of it is an
#: instantaneous impact law (``restitution``), while the kernel needs ever more substeps per sample.
#: flexible_foundation.damping_ratio: an over-damped pad (above 1) is left out of the search; its
#: kernel's step shrinks with the damping (cost x2 at 1, x4 at 2) and the time budget goes elsewhere.
FIT_BOUNDS: dict[tuple[str, str], tuple[float, float]] = {
    ("flexible_foundation", "frequency"): (10.0, 100.0),
    ("flexible_foundation", "damping_ratio"): (0.0, 1.0),
}


@dataclass(frozen=True)
class ParamDim:
    """One fitted parameter: its key, search bounds (in its own units), log scale, and neutral value."""

    key: str
    lo: float
    hi: float
    log: bool
    neutral: float | None

    def to_u(self, x: float) -> float:
        """The search coordinate of a value (its logarithm on a log scale)."""
        return math.log(x) if self.log else x

    def from_u(self, u: float) -> float:
        """The value of a search coordinate, clipped to the bounds."""
        x = math.exp(u) if self.log else u
        return min(max(x, self.lo), self.hi)

    @property
    def u_bounds(self) -> tuple[float, float]:
        return self.to_u(self.lo), self.to_u(self.hi)


def search_bounds(name: str, key: str, specimen=None) -> tuple[float, float] | None:
    """The search range of parameter ``key`` of effect ``name``: :data:`FIT_BOUNDS`, else the effect's own bounds
    (None where they depend on a specimen that is not given)."""
    return FIT_BOUNDS.get((name, key)) or effect_class(name).param_specs[key].bounds_for(specimen)


def param_dims(name: str, specimen) -> list[ParamDim]:
    """The fitted parameters of effect ``name`` on ``specimen``: :data:`FIT_BOUNDS` or the effect's own bounds."""
    cls = effect_class(name)
    dims = []
    for key, spec in cls.param_specs.items():
        b = search_bounds(name, key, specimen)
        if b is None:
            raise ValueError(f"effect {name!r}: parameter `{key}` has no bounds to fit within")
        lo, hi = float(b[0]), float(b[1])
        neutral = spec.neutral_for(specimen)
        dims.append(ParamDim(key, lo, hi, lo > 0 and hi / lo >= 20.0, neutral))
    return dims


def build_model(model: Sequence[tuple[str, dict]]) -> list:
    """Effect instances of a model given as (name, parameters) pairs."""
    return [make_effect(n, **p) for n, p in model]


def fit_effect(
    name: str,
    objective: Callable[[Any], float],
    specimen,
    *,
    start: dict[str, float] | None = None,
    local_only: bool = False,
    local_iterations: int = 14,
    pinned: dict[str, dict] | None = None,
) -> tuple[dict[str, float], float, int]:
    """Fit one effect's parameters by minimising ``objective(effect)`` within the bounds.

    Parameters
    ----------
    name : str
        Registered effect name.
    objective : callable
        Effect instance -> training error [alpha].
    specimen : Specimen
        For specimen-dependent bounds.
    start : dict, optional
        Starting parameters (for ``local_only``).
    local_only : bool
        Skip the grids: a local search from ``start``.
    local_iterations : int
        Budget of the local search: Brent iterations (one parameter); Powell
        evaluations are 10/14 of it per parameter (more).
    pinned : dict, optional
        Effect name -> parameters measured directly (``Effect.measured_params``): kept, not fitted.

    Returns
    -------
    (params, error, n_evaluations)

    Notes
    -----
    One parameter: a grid of :data:`N_GRID` points (plus the neutral value
    when it lies inside the bounds, so the fit is never worse than the effect
    switched off), a zoom grid of :data:`N_ZOOM` points over +-1 step around
    the best, then a bounded Brent search over +-1 zoom step. d parameters:
    a grid of :data:`N_GRID_MULTI` points per parameter, a zoom grid of
    :data:`N_ZOOM_MULTI` points per parameter over +-1 step around the best,
    then a bounded Powell search of at most 10 d evaluations.
    """
    fixed = dict((pinned or {}).get(name, {}))
    dims = [d for d in param_dims(name, specimen) if d.key not in fixed]
    if not dims:
        return fixed, float(objective(make_effect(name, **fixed))), 1
    f_u = _SearchObjective(name, objective, dims, fixed)
    lo = np.array([d.u_bounds[0] for d in dims])
    hi = np.array([d.u_bounds[1] for d in dims])
    if start is not None:
        best_u = np.array([d.to_u(min(max(float(start[d.key]), d.lo), d.hi)) for d in dims])
    else:
        best_u = None
    if not local_only or best_u is None:
        best_u, step = _grid_search(f_u, dims, lo, hi)
    else:
        step = (hi - lo) / (N_GRID - 1)
    best_u = _local_search(f_u, best_u, lo, hi, step, local_iterations)
    return f_u.params(best_u), f_u(best_u), len(f_u.cache)


class _SearchObjective:
    """The objective of one effect's fit as a function of the search coordinates, memoised by the parameter
    values (rounded to 12 decimals); ``fixed`` parameters are passed as they are."""

    def __init__(self, name: str, objective: Callable[[Any], float], dims: list[ParamDim], fixed: dict):
        self.name = name
        self.objective = objective
        self.below = getattr(objective, "below", None)
        self.dims = dims
        self.fixed = fixed
        self.cache: dict[tuple, float] = {}

    def params(self, u) -> dict[str, float]:
        """The effect's parameters at search coordinates ``u`` (the fixed ones included), in their units."""
        return {**self.fixed, **{d.key: d.from_u(float(x)) for d, x in zip(self.dims, np.atleast_1d(u), strict=True)}}

    def __call__(self, u, bound: float = math.inf) -> float:
        """The objective at ``u``; with a finite ``bound`` (a grid's best so far), a value above it may
        be a lower bound only (the objective's ``below``), and is not kept."""
        params = self.params(u)
        key = tuple(round(v, 12) for v in params.values())
        if key not in self.cache:
            try:
                if self.below is not None and math.isfinite(bound):
                    v = float(self.below(make_effect(self.name, **params), bound))
                    if v > bound:
                        return v  # abandoned above the bound: not the objective, not kept
                    self.cache[key] = v
                else:
                    self.cache[key] = float(self.objective(make_effect(self.name, **params)))
            except NonFiniteScore:
                raise  # a non-finite model is refused, not avoided
            except ValueError:
                self.cache[key] = math.inf  # a combination the effect refuses (e.g. an impossible inertia)
        return self.cache[key]


def _grid_search(f_u: Callable, dims: list[ParamDim], lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Best point of the coarse grid and of the zoom around it (search coordinates), and the zoom's step.

    The coarse grid holds the neutral value of each parameter that has one within its bounds.
    """
    npd = N_GRID if len(dims) == 1 else N_GRID_MULTI
    axes, first = [], []
    for d, a, b in zip(dims, lo, hi, strict=True):
        ax = np.linspace(a, b, npd)
        if d.neutral is not None and d.lo <= d.neutral <= d.hi:
            ax = np.union1d(ax, [d.to_u(d.neutral)])
            first.append(d.to_u(d.neutral))
        else:
            first.append(0.5 * (a + b))
        axes.append(ax)
    best_u, _v = _grid_best(f_u, axes, first)
    step = (hi - lo) / (npd - 1)
    # a zoom grid over +-1 step around the best point
    nz = N_ZOOM if len(dims) == 1 else N_ZOOM_MULTI
    zaxes = [np.linspace(max(a, u - st), min(b, u + st), nz) for a, b, u, st in zip(lo, hi, best_u, step, strict=True)]
    z_u, z_v = _grid_best(f_u, zaxes, best_u)
    if z_v <= f_u(best_u):
        best_u = z_u
    return best_u, step / ((nz - 1) / 2)


def _grid_best(f_u: Callable, axes: list[np.ndarray], first=None) -> tuple[np.ndarray, float]:
    """The point of the grid spanned by ``axes`` where ``f_u`` is least, and its value.

    Each point is scored with the best value so far as its bound (``f_u(p, bound)``): a point whose
    records scored first already put it above the bound is abandoned there (its value is then a
    lower bound above the best, so it is not the least and the answer is the one every point fully
    scored gives). The point nearest ``first`` (search coordinates: the neutral point, the current
    model's value, or the best point so far; default the middle of the grid) is scored first, a
    tight bound from the start.
    """
    pts = np.array(np.meshgrid(*axes, indexing="ij")).reshape(len(axes), -1).T
    vals = np.full(len(pts), math.inf)
    i0 = len(pts) // 2 if first is None else int(np.argmin(np.sum((pts - np.asarray(first)) ** 2, axis=1)))
    order = [i0, *[i for i in range(len(pts)) if i != i0]]
    best = math.inf
    for i in order:
        vals[i] = f_u(pts[i], best)
        best = min(best, vals[i])
    return pts[int(np.argmin(vals))], vals.min()


def _local_search(
    f_u: Callable, best_u: np.ndarray, lo: np.ndarray, hi: np.ndarray, step: np.ndarray, local_iterations: int
) -> np.ndarray:
    """Bounded Brent (one parameter, within +-1 ``step``) or Powell search from ``best_u``; kept if no worse."""
    if len(best_u) == 1:
        a = max(lo[0], best_u[0] - step[0])
        b = min(hi[0], best_u[0] + step[0])
        if b > a:
            res = optimize.minimize_scalar(
                lambda x: f_u([x]),
                bounds=(a, b),
                method="bounded",
                options={"xatol": 1e-3 * step[0], "maxiter": local_iterations},
            )
            if res.fun <= f_u(best_u):
                best_u = np.array([res.x])
        return best_u
    res = optimize.minimize(
        f_u,
        best_u,
        method="Powell",
        bounds=list(zip(lo, hi, strict=True)),
        options={"maxfev": max(2, local_iterations * 10 // 14) * len(best_u), "xtol": 1e-3, "ftol": 1e-4},
    )
    if res.fun <= f_u(best_u):
        best_u = np.asarray(res.x)
    return best_u


def effect_objective(scorer, before: list, after: list) -> Callable[[Any], float]:
    """Training loss (``scorer.loss``) of ``before + [effect] + after`` as a function of ``effect``.

    Its ``below(effect, bound)`` is ``scorer.loss_below``: the loss, or a lower bound of it above
    ``bound`` (the grids' early stop, :func:`_grid_best`).
    """

    def f(effect) -> float:
        return scorer.loss([*before, effect, *after])

    if hasattr(scorer, "loss_below"):
        f.below = lambda effect, bound: scorer.loss_below([*before, effect, *after], bound)  # type: ignore[attr-defined]
    return f


def joint_refit(
    model: list[tuple[str, dict]],
    scorer,
    specimen,
    maxfev_per_dim: int = 15,
    free_from: int = 0,
    pinned: dict[str, dict] | None = None,
) -> tuple[list[tuple[str, dict]], float]:
    """Local search over the parameters of the model's effects ``free_from`` on, from their current values.

    Bounded Nelder-Mead; the effects before ``free_from`` keep their parameters, and so do the
    parameters in ``pinned`` (effect name -> measured parameters). ``scorer.loss`` of a list of
    effects is the objective [alpha]. Returns the model and its training error.
    """
    dims: list[tuple[int, ParamDim]] = []
    for i, (name, _p) in enumerate(model):
        if i >= free_from:
            keep = (pinned or {}).get(name, {})
            dims += [(i, d) for d in param_dims(name, specimen) if d.key not in keep]

    def build(u) -> list[tuple[str, dict]]:
        out = [(n, dict(p)) for n, p in model]
        for (i, d), x in zip(dims, u, strict=True):
            out[i][1][d.key] = d.from_u(float(x))
        return out

    def f(u) -> float:
        try:
            return scorer.loss(build_model(build(u)))
        except NonFiniteScore:
            raise
        except ValueError:
            return math.inf

    u0 = np.array([d.to_u(min(max(model[i][1][d.key], d.lo), d.hi)) for i, d in dims])
    f0 = f(u0)
    if len(dims) < 2:
        return model, f0  # one parameter: its own grid-and-Brent fit is already the best we do
    # Nelder-Mead from a simplex of half a zoom step per parameter: it follows the narrow diagonal
    # valleys of correlated parameters (p and r both set the free-vibration decay and timing), where
    # one-parameter-at-a-time searches stall.
    lo = np.array([d.u_bounds[0] for _i, d in dims])
    hi = np.array([d.u_bounds[1] for _i, d in dims])
    h = (hi - lo) / ((N_GRID - 1) * (N_ZOOM - 1))
    simplex = [u0]
    for k in range(len(dims)):
        v = u0.copy()
        v[k] = v[k] + h[k] if v[k] + h[k] <= hi[k] else v[k] - h[k]
        simplex.append(v)
    res = optimize.minimize(
        f,
        u0,
        method="Nelder-Mead",
        bounds=list(zip(lo, hi, strict=True)),
        options={
            "maxfev": maxfev_per_dim * len(dims),
            "initial_simplex": np.array(simplex),
            "xatol": 1e-3 * h.min(),
            "fatol": 1e-5,
        },
    )
    if res.fun < f0:
        return build(res.x), float(res.fun)
    return model, f0
