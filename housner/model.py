"""The analytic Housner rocking model: the reference solver of the suite.

A rigid block on a rigid base rocks on one of its two bottom corners and impacts when the rotation passes
through zero. :func:`simulate` (and :func:`simulate_many`, :func:`theta_max_many`) integrate the full
nonlinear equation of the seed paper (eq. 2, with pivot-dependent parameters and an optional viscous term)
by RK4 aligned to the motion's samples, and locate uplift, impact, rest, overturn and peaks to machine
precision on the integrator's own trajectory, in the compiled kernel of :mod:`housner._kernel` (or one
generated with the effects' terms, :mod:`housner.effects.terms`). The equation, the events, the numerics
and their accuracy are in ``docs/explanation/physics.md`` ("How the analytic model solves it").

References
----------
Housner, G. W. (1963). The behavior of inverted pendulum structures during
earthquakes. Bulletin of the Seismological Society of America 53(2), 403-417.
Bachmann, J. A., Strand, M., Vassiliou, M. F., Broccardo, M., Stojadinovic, B.
(2017). Probabilistic validation of the Housner rocking model. COMPDYN 2017,
eqs. 1-4.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict
from typing import NamedTuple

import numpy as np

from housner._kernel import run_batch, run_batch_parallel
from housner._validate import finite as _finite
from housner.motion import VERTICAL, GroundMotion
from housner.response import Response
from housner.rocking_params import RockingParams
from housner.specimen import Specimen
from housner.units import G

__all__ = ["REST_TOL", "default_substeps", "simulate", "simulate_many", "theta_max_many"]

#: Default accuracy target: the RK4 step h is chosen so that p h <= PH_MAX [-].
#: RK4's global error scales as (p h)^4; at 0.01 theta_max is converged to
#: about 1e-8 alpha (see tests/test_model.py and benchmarks/bench_analytic.py).
PH_MAX = 0.01

#: Largest number of substeps per sample accepted [-].
MAX_SUBSTEPS = 100_000
#: Default rest rule: a block whose next peak would stay below REST_TOL * alpha is at rest [-].
REST_TOL = 1e-6


def default_substeps(p: float, dt: float) -> int:
    """RK4 substeps per sample so that p h <= PH_MAX, h = dt / substeps [-].

    Parameters
    ----------
    p : float
        Largest frequency parameter [1/s].
    dt : float
        Sample step [s].
    """
    return max(1, math.ceil(p * dt / PH_MAX - 1e-9))


# ----------------------------------------------------------------------
# validation shared by the public entry points
def _resolve_params(specimen: Specimen, r, params) -> RockingParams:
    if not isinstance(specimen, Specimen):
        raise TypeError(f"`specimen` must be a housner.Specimen, got {type(specimen).__name__}")
    if params is None:
        return RockingParams.from_specimen(specimen, r=r)
    if not isinstance(params, RockingParams):
        raise TypeError(f"`params` must be a housner.model.RockingParams, got {type(params).__name__}")
    return params if r is None else params.with_r(r)


def _check_rest_tol(rest_tol) -> float:
    v = _finite("rest_tol", rest_tol)
    if not 0.0 < v < 1.0:
        raise ValueError(f"`rest_tol` must lie in (0, 1), got {rest_tol!r}")
    return v


def _check_substeps(substeps, p: float, dt: float) -> int:
    if substeps is None:
        return default_substeps(p, dt)
    if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)):
        raise ValueError(f"`substeps` must be a positive integer, got {substeps!r}")
    if not 1 <= substeps <= MAX_SUBSTEPS:
        raise ValueError(f"`substeps` must lie in [1, {MAX_SUBSTEPS}], got {substeps!r}")
    return int(substeps)


def _check_initial(theta0, theta_dot0) -> tuple[float, float]:
    th = _finite("theta0", theta0)
    if abs(th) >= math.pi / 2:
        raise ValueError(f"`theta0` must lie within (-pi/2, pi/2) rad, got {theta0!r}")
    return th, _finite("theta_dot0", theta_dot0)


def _record_start(motion: GroundMotion, prm: RockingParams, theta0, theta_dot0, substeps) -> tuple[tuple, int]:
    """A prepared motion's initial state, (theta0 [rad], theta_dot0 [rad/s]) as given or else the motion's own, and
    its substeps per sample, checked."""
    init = _check_initial(
        motion.theta0 if theta0 is None else theta0, motion.theta_dot0 if theta_dot0 is None else theta_dot0
    )
    return init, _check_substeps(substeps, prm.p_max, motion.dt)


def _prepare_motion(motion, duration) -> GroundMotion:
    if not isinstance(motion, GroundMotion):
        raise TypeError(f"`motion` must be a housner.GroundMotion, got {type(motion).__name__}")
    if duration is None:
        return motion
    d = _finite("duration", duration)
    if d <= 0.0:
        raise ValueError(f"`duration` must be positive [s], got {duration!r}")
    if d == motion.duration:
        return motion
    return motion.with_duration(d)


# ----------------------------------------------------------------------
def simulate(
    specimen: Specimen,
    motion: GroundMotion,
    *,
    theta0: float | None = None,
    theta_dot0: float | None = None,
    r: float | None = None,
    duration: float | None = None,
    substeps: int | None = None,
    params: RockingParams | None = None,
    rest_tol: float = REST_TOL,
    terms=None,
) -> Response:
    """Rocking response of a rigid block to one ground motion (Housner's model).

    Parameters
    ----------
    specimen : Specimen
        The block (alpha [rad], p [1/s], r_housner [-]).
    motion : GroundMotion
        Ground acceleration [m/s^2], linear between samples.
    theta0, theta_dot0 : float, optional
        Initial rotation [rad] and angular velocity [rad/s]; default to
        ``motion.theta0`` and ``motion.theta_dot0``. The block starts at rest
        only when both are zero.
    r : float, optional
        Kinetic-energy ratio at impact [-], in [0, 1]; defaults to
        ``specimen.r_housner`` (or to ``params.r``). Given together with
        ``params`` it replaces ``params.r`` (``params.with_r(r)``: per-side
        ratios are scaled alike).
    duration : float, optional
        Simulated time [s]; defaults to the motion's duration. A longer
        duration pads the motion with zeros (free rocking after the shaking),
        a shorter one cuts it.
    substeps : int, optional
        RK4 steps per sample interval; by default the fewest with p h <= 0.01.
    params : RockingParams, optional
        Overrides the parameters derived from ``specimen`` (asymmetric
        pivots, amplitude-dependent restitution, damping).
    rest_tol : float
        Rest rule threshold [-], in (0, 1): after an impact whose free-rocking
        peak would stay below ``rest_tol * alpha`` the block is at rest.
    terms : housner.effects.terms.TermSet, optional
        The effects' terms (extra moments, dry moments, impact laws); they run
        in a kernel generated for them (:mod:`housner.effects.terms`). None
        (default) runs the plain kernel.

    Returns
    -------
    Response
        Histories on the motion's sample grid, impact times, theta_max, and
        the overturn and uplift times; ``alpha`` is ``specimen.alpha`` and
        ``info`` holds ``substeps``, ``rest_tol`` and ``params`` (as a dict),
        and ``terms`` when there are terms.
        ``uplift_time`` is 0 for a block released off its rest position.

    Notes
    -----
    The physics and the event handling are described in ``docs/explanation/physics.md``,
    "How the analytic model solves it".

    References
    ----------
    Housner (1963); Bachmann et al. (2017), eqs. 2-4.
    """
    prm = _resolve_params(specimen, r, params)
    motion = _prepare_motion(motion, duration)
    init, m = _record_start(motion, prm, theta0, theta_dot0, substeps)
    tol = _check_rest_tol(rest_tol)
    return _simulate_batch(specimen, [motion], [init], prm, [m], tol, parallel=False, terms=terms or None)[0]


def simulate_many(
    specimen: Specimen,
    motions: Sequence[GroundMotion],
    *,
    theta0: float | None = None,
    theta_dot0: float | None = None,
    r: float | None = None,
    duration: float | None = None,
    substeps: int | None = None,
    params: RockingParams | None = None,
    rest_tol: float = REST_TOL,
    parallel: bool = True,
    terms=None,
) -> list[Response]:
    """:func:`simulate` for many motions in one compiled call.

    Parameters are those of :func:`simulate` (``terms`` included), applied to
    every motion (``theta0``/``theta_dot0`` default to each motion's own), plus
    ``parallel`` : bool, spread the records over numba threads.

    Returns
    -------
    list of Response
        One per motion, in order; identical to calling :func:`simulate` on each.

    Notes
    -----
    ``parallel=True`` uses numba's threading layer (OpenMP here): pass
    ``parallel=False`` inside worker processes that are forked from a parent
    that already ran a parallel kernel, and when the caller itself runs many
    of these calls in parallel.
    """
    prm = _resolve_params(specimen, r, params)
    tol = _check_rest_tol(rest_tol)
    prepared, inits, ms = [], [], []
    for i, mo in enumerate(motions):
        try:
            mo = _prepare_motion(mo, duration)
        except TypeError:
            raise TypeError(f"`motions[{i}]` must be a housner.GroundMotion, got {type(mo).__name__}") from None
        init, m = _record_start(mo, prm, theta0, theta_dot0, substeps)
        prepared.append(mo)
        inits.append(init)
        ms.append(m)
    if not prepared:
        return []
    return _simulate_batch(specimen, prepared, inits, prm, ms, tol, parallel=bool(parallel), terms=terms or None)


def _vertical(motions, terms) -> np.ndarray:
    """The terms' v [-]: each motion's vertical channel over g when the terms read it, else zeros."""
    if not terms.vertical:
        return np.zeros(sum(mo.n for mo in motions))
    for mo in motions:
        if VERTICAL not in mo.channels:
            raise ValueError(f"the terms read the channel {VERTICAL!r}, which motion {mo.name!r} does not carry")
    return np.concatenate([mo.channels[VERTICAL] for mo in motions]) / G


class _Records(NamedTuple):
    """The records of one kernel call, one after another: the kernel's arguments before ``rest_tol``
    (:func:`housner._kernel.run_batch`); ``v_g`` and ``q`` are None without terms."""

    acc_g: np.ndarray  # ground acceleration over g [-], all the records' samples
    v_g: np.ndarray | None  # vertical table acceleration over g [-], the same samples (terms only)
    offsets: np.ndarray  # record i's samples: offsets[i]:offsets[i + 1]
    dts: np.ndarray  # sample steps [s], one per record
    ms: np.ndarray  # RK4 substeps per sample, one per record
    prm: np.ndarray  # parameter vectors, one row per record
    q: np.ndarray | None  # the terms' parameters, one row per record (terms only)
    th0: np.ndarray  # initial rotations [rad]
    thd0: np.ndarray  # initial angular velocities [rad/s]

    def one(self, i: int) -> _Records:
        """Record i alone."""
        ab, row = slice(self.offsets[i], self.offsets[i + 1]), slice(i, i + 1)
        return _Records(
            self.acc_g[ab],
            None if self.v_g is None else self.v_g[ab],
            np.array([0, self.offsets[i + 1] - self.offsets[i]], dtype=np.int64),
            self.dts[row],
            self.ms[row],
            self.prm[row],
            None if self.q is None else self.q[row],
            self.th0[row],
            self.thd0[row],
        )


def _run_kernel(terms, parallel: bool, recs: _Records, rest_tol, record, theta, theta_dot, impacts, imp_off, out):
    """Run the plain kernel (``terms`` None: no v_g nor q) or the one generated for ``terms`` on ``recs``."""
    if terms is None:
        kern = run_batch_parallel if parallel else run_batch
        recs = recs._replace(v_g=recs.acc_g, q=_no_terms(recs.dts.size))
    else:
        mod = terms.kernel()
        kern = mod.run_batch_parallel if parallel else mod.run_batch
    kern(*recs, rest_tol, record, theta, theta_dot, impacts, imp_off, out)


def _no_terms(n_rec: int) -> np.ndarray:
    """The terms' parameters of ``n_rec`` records without terms (the plain kernel reads none)."""
    return np.empty((n_rec, 0))


def _simulate_batch(specimen, motions, inits, prm: RockingParams, ms, rest_tol: float, parallel: bool, terms=None):
    n_rec = len(motions)
    sizes = np.array([mo.n for mo in motions], dtype=np.int64)
    offsets = np.zeros(n_rec + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    acc_g = np.concatenate([mo.acc for mo in motions]) / G
    v_g = None if terms is None else _vertical(motions, terms)
    q = None if terms is None else np.tile(terms.q_array(), (n_rec, 1))
    dts = np.array([mo.dt for mo in motions], dtype=np.float64)
    ms_a = np.asarray(ms, dtype=np.int64)
    prm_a = np.tile(prm.as_array(), (n_rec, 1))
    th0 = np.array([i[0] for i in inits], dtype=np.float64)
    thd0 = np.array([i[1] for i in inits], dtype=np.float64)
    theta = np.empty(offsets[-1])
    theta_dot = np.empty(offsets[-1])
    # impact buffer: a generous guess, rerun the rare record that overflows it
    caps = np.maximum(64, sizes // 4)
    imp_off = np.zeros(n_rec + 1, dtype=np.int64)
    np.cumsum(caps, out=imp_off[1:])
    impacts = np.empty(imp_off[-1])
    out = np.empty((n_rec, 6))
    recs = _Records(acc_g, v_g, offsets, dts, ms_a, prm_a, q, th0, thd0)
    _run_kernel(terms, parallel and n_rec > 1, recs, rest_tol, True, theta, theta_dot, impacts, imp_off, out)
    results = []
    prm_d = asdict(prm)  # once: a record's info holds its own shallow copy (the values are numbers)
    for i, mo in enumerate(motions):
        n_imp = int(out[i, 4])
        if n_imp > caps[i]:
            imp_i = np.empty(n_imp)
            imp_off_i = np.array([0, n_imp], dtype=np.int64)
            _run_kernel(
                terms, False, recs.one(i), rest_tol, False, theta[:0], theta_dot[:0], imp_i, imp_off_i, np.empty((1, 6))
            )
        else:
            imp_i = impacts[imp_off[i] : imp_off[i] + n_imp].copy()
        info = {"substeps": int(ms_a[i]), "rest_tol": rest_tol, "params": dict(prm_d)}
        if terms is not None:
            info["terms"] = terms.describe()
        if out[i, 5]:
            info["rest_guard_trips"] = int(out[i, 5])
        th, thd = theta[offsets[i] : offsets[i + 1]].copy(), theta_dot[offsets[i] : offsets[i + 1]].copy()
        results.append(Response.from_kernel(mo.t, th, thd, imp_i, out[i], specimen.alpha, info))
    return results


def theta_max_many(
    specimen: Specimen,
    acc,
    dt,
    *,
    theta0=0.0,
    theta_dot0=0.0,
    r: float | None = None,
    substeps: int | None = None,
    params: RockingParams | Sequence[RockingParams] | None = None,
    rest_tol: float = REST_TOL,
    parallel: bool = True,
    terms=None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Peak response of many records without building their histories.

    Parameters
    ----------
    specimen : Specimen
        The block; its ``alpha`` [rad] normalises theta_max.
    acc : array_like or sequence of array_like
        Ground accelerations [m/s^2]: a 2-D array (one record per row) or a
        list of 1-D arrays of any lengths.
    dt : float or array_like
        Sample step [s], one for all or one per record.
    theta0, theta_dot0 : float or array_like
        Initial state [rad, rad/s], one for all or one per record.
    r : float, optional
        Kinetic-energy ratio at impact [-]; see :func:`simulate`.
    substeps : int, optional
        RK4 steps per sample; by default p h <= 0.01 for each record's dt.
    params : RockingParams or sequence of RockingParams, optional
        One parameter set for all records or one per record.
    rest_tol : float
        Rest rule threshold [-]; see :func:`simulate`.
    parallel : bool
        Spread the records over numba threads.
    terms : housner.effects.terms.TermSet, optional
        The effects' terms (see :func:`simulate`); terms that read the vertical channel cannot run on bare
        accelerations (ValueError).

    Returns
    -------
    theta_max_over_alpha : ndarray of float
        theta_max / specimen.alpha [-]; +inf where the block overturned.
    overturned : ndarray of bool
    n_impacts : ndarray of int
    """
    rows = _acc_rows(acc)
    n_rec = len(rows)
    if n_rec == 0:
        return np.empty(0), np.empty(0, dtype=bool), np.empty(0, dtype=np.int64)
    dts = _per_record("dt", dt, n_rec)
    if not np.all(dts > 0.0):
        raise ValueError(f"`dt` must be positive [s], got {dt!r}")
    th0 = _per_record("theta0", theta0, n_rec)
    if np.any(np.abs(th0) >= math.pi / 2):
        raise ValueError("`theta0` must lie within (-pi/2, pi/2) rad")
    thd0 = _per_record("theta_dot0", theta_dot0, n_rec)
    tol = _check_rest_tol(rest_tol)
    prms = _params_per_record(specimen, r, params, n_rec)
    prm_a = np.array([p.as_array() for p in prms])
    ms = np.array([_check_substeps(substeps, p.p_max, d) for p, d in zip(prms, dts, strict=True)], dtype=np.int64)
    offsets = np.zeros(n_rec + 1, dtype=np.int64)
    np.cumsum([a.size for a in rows], out=offsets[1:])
    acc_g = np.concatenate(rows) / G
    out = np.empty((n_rec, 6))
    empty = np.empty(0)
    if terms is not None and terms.vertical:
        raise ValueError("`terms` read the vertical channel, which bare accelerations do not carry; use simulate_many")
    q = None if terms is None else np.tile(terms.q_array(), (n_rec, 1))
    v_g = None if terms is None else np.zeros_like(acc_g)  # the terms read no vertical channel (checked above)
    recs = _Records(acc_g, v_g, offsets, dts, ms, prm_a, q, th0, thd0)
    _run_kernel(
        terms, parallel and n_rec > 1, recs, tol, False, empty, empty, empty, np.zeros(n_rec + 1, np.int64), out
    )
    overturned = out[:, 1] != 0.0
    ratio = np.where(overturned, np.inf, out[:, 0] / specimen.alpha)
    return ratio, overturned, out[:, 4].astype(np.int64)


def _acc_rows(acc) -> list[np.ndarray]:
    """The records of :func:`theta_max_many`'s ``acc`` as a list of non-empty, finite 1-D float arrays [m/s^2]."""
    if isinstance(acc, np.ndarray) and acc.ndim == 2:
        rows = [np.asarray(a, dtype=np.float64) for a in acc]
    elif isinstance(acc, np.ndarray) and acc.ndim == 1 and acc.dtype != object:
        raise ValueError("`acc` must be a 2-D array (one record per row) or a list of 1-D arrays, got a 1-D array")
    else:
        try:
            rows = [np.asarray(a, dtype=np.float64) for a in acc]
        except (TypeError, ValueError):
            raise ValueError("`acc` must be a 2-D array or a list of 1-D numeric arrays") from None
    for i, a in enumerate(rows):
        if a.ndim != 1 or a.size == 0:
            raise ValueError(f"`acc[{i}]` must be a non-empty 1-D array, got shape {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"`acc[{i}]` is not finite at sample {int(np.flatnonzero(~np.isfinite(a))[0])}")
    return rows


def _params_per_record(specimen: Specimen, r, params, n_rec: int) -> list[RockingParams]:
    """One RockingParams per record: ``params`` given once or per record, or the specimen's with ``r``."""
    if params is None or isinstance(params, RockingParams):
        return [_resolve_params(specimen, r, params)] * n_rec
    params = list(params)
    if len(params) != n_rec:
        raise ValueError(f"`params` must be one RockingParams or {n_rec} of them, got {len(params)}")
    return [_resolve_params(specimen, r, p) for p in params]


def _per_record(name: str, value, n: int) -> np.ndarray:
    """A number or one value per record, as a contiguous float array of ``n`` finite values."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be a number or an array of numbers, got {value!r}") from None
    if a.ndim == 0:
        a = np.full(n, float(a))
    elif a.shape != (n,):
        raise ValueError(f"`{name}` must be a number or have one value per record ({n}), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"`{name}` must be finite")
    return np.ascontiguousarray(a)
