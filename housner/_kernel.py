"""Compiled core of the analytic Housner solver (private; use :mod:`housner.model`).

:func:`run_one` simulates a record, :func:`run_batch` and :func:`run_batch_parallel` many, with
Housner's equation of motion and its events (:mod:`housner._kernel_steps`: reduced coordinates,
the effects' hooks, event location). Time is split into the motion's sample intervals (ug''
linear inside each) and every interval into ``m`` equal substeps of classic RK4. Block states:
ROCKING -> impact (phi = 0, then the rest rule), overturn (phi = pi/2); REST -> ROCKING at
uplift (Housner's rule a <= -tan(alpha_s), or the net moment's when a term acts at rest); with a
dry term, ROCKING -> STUCK where w reaches 0 and the moments stay within the dry capacity, and
STUCK -> ROCKING when they leave it; REST also after a reversal at phi <= 0. The negative pivot
is computed by the very same floating-point operations as the positive one, with the inputs
negated; IEEE rounding is symmetric under negation, so ug -> -ug gives theta -> -theta bit for bit.

This module and :mod:`housner._kernel_steps` are the plain kernel, and the template from which
:mod:`housner.effects.terms` generates the kernel of a set of terms (the hooks replaced, the
rest the same). Units: time [s], angles [rad], angular velocity [rad/s], ground acceleration in
units of g [-] (the caller divides by g once).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from housner._kernel_parts import (
    EV_IMPACT,
    EV_NONE,
    EV_OVERTURN,
    EV_REVERSE,
    EV_STALL,
    I_ALPHA_NEG,
    I_ALPHA_POS,
    I_DAMPING,
    I_P_NEG,
    I_P_POS,
    I_R_EXP,
    I_R_NEG,
    I_R_POS,
    MAX_EVENTS_PER_SAMPLE,
    OVERTURNED,
    REST,
    ROCKING,
    STUCK,
    grid,
    initial_state,
    pivot_constants,
    restitution,
    store,
    substep_of,
    uplift,
)
from housner._kernel_steps import (
    AT_REST,
    HAS_DRY,
    HAS_IMPACT,
    TERMS,
    accel,
    after_reversal,
    frame,
    hold_margin,
    impact_ratio,
    leave,
    rk4,
    step_event,
    step_event_dry,
)

#: The entry points (the parameter vector's layout is :mod:`housner._kernel_parts`'s).
__all__ = ["run_batch", "run_batch_parallel", "run_one"]

#: The terms' parameters of a kernel without terms: a constant, so that the hot calls count no
#: references to it (an array argument passed down them costs ~10 % of the plain kernel's time).
_NO_Q = np.zeros(0)


@njit(cache=True)
def run_one(acc_g, v_g, dt, m, prm, q, theta0, theta_dot0, rest_tol, record, theta_out, theta_dot_out, impacts):
    """Simulate one record.

    Parameters
    ----------
    acc_g : float64[:]
        Ground acceleration in units of g [-], n samples.
    v_g : float64[:]
        Vertical table acceleration over g [-] at the samples; read only by terms (any n-array else).
    dt : float
        Sample step [s].
    m : int
        RK4 substeps per sample.
    prm : float64[:]
        Parameter vector (see the ``I_*`` indices).
    q : float64[:]
        The terms' parameters (any array without terms).
    theta0, theta_dot0 : float
        Initial state [rad, rad/s].
    rest_tol : float
        Rest rule: the block rests after an impact whose free-rocking peak is below rest_tol * alpha [-].
    record : bool
        Write the sampled history into theta_out and theta_dot_out (length n).
    theta_out, theta_dot_out : float64[:]
        History on the sample grid [rad, rad/s] (ignored unless ``record``).
    impacts : float64[:]
        Buffer for impact times [s]; impacts beyond its length are counted but not stored.

    Returns
    -------
    theta_max : float
        Largest |theta| [rad] (pi/2 if overturned).
    overturned : bool
    t_over : float
        Overturn time [s] or NaN.
    t_uplift : float
        First uplift time [s] (0 when released off rest) or NaN.
    n_imp : int
        Number of impacts.
    guard : int
        Number of times the per-sample event safety net put the block to rest (0 normally).
    """
    if TERMS:
        return _run(acc_g, v_g, dt, m, prm, q, theta0, theta_dot0, rest_tol, record, theta_out, theta_dot_out, impacts)
    return _run(acc_g, v_g, dt, m, prm, _NO_Q, theta0, theta_dot0, rest_tol, record, theta_out, theta_dot_out, impacts)


@njit(cache=True, inline="always")
def _run(acc_g, v_g, dt, m, prm, q, theta0, theta_dot0, rest_tol, record, theta_out, theta_dot_out, impacts):
    """:func:`run_one`'s loop; inlined, so that without terms ``q`` is the constant :data:`_NO_Q`."""
    alpha_p = prm[I_ALPHA_POS]
    alpha_n = prm[I_ALPHA_NEG]
    p2_p = prm[I_P_POS] * prm[I_P_POS]
    p2_n = prm[I_P_NEG] * prm[I_P_NEG]
    c = prm[I_DAMPING]
    tan_p, tan_n, wrest2_p, wrest2_n = pivot_constants(alpha_p, alpha_n, p2_p, p2_n, rest_tol)
    mode, s, phi, w, t_uplift, sig = _start(acc_g, v_g, dt, theta0, theta_dot0, alpha_p, alpha_n, p2_p, p2_n, c, q)
    theta_max, t_over, n_imp, guard = abs(theta0), math.nan, 0, 0
    if record:
        theta_out[0] = theta0
        theta_dot_out[0] = theta_dot0

    for k in range(acc_g.size - 1):
        if mode == OVERTURNED and not record:
            break
        t_k, g0, g1 = k * dt, acc_g[k], acc_g[k + 1]
        u0, u1 = v_g[k], v_g[k + 1]
        tau, j, n_ev = 0.0, 0, 0
        while mode != OVERTURNED:
            if mode == REST or mode == STUCK:
                tl, s, phi, sig, t_uplift = _depart(
                    mode,
                    phi,
                    s,
                    sig,
                    tau,
                    m,
                    dt,
                    g0,
                    g1,
                    u0,
                    u1,
                    t_k,
                    t_uplift,
                    alpha_p,
                    alpha_n,
                    p2_p,
                    p2_n,
                    c,
                    tan_p,
                    tan_n,
                    q,
                )
                if tl == math.inf:
                    break
                tau = tl
                mode, w = ROCKING, 0.0
                j = substep_of(tau, m, dt)
            tgt = grid(j + 1, m, dt)
            if tgt > tau:
                fr = frame(s, g0, g1, u0, u1, dt, t_k, alpha_p, alpha_n, p2_p, p2_n, c, sig)
                H = tgt - tau
                phi1, w1 = rk4(phi, w, tau, H, fr, q)
                ph_h = 0.0
                if HAS_DRY:
                    event, h, ph_h, w_h, theta_max = step_event_dry(phi, w, phi1, w1, tau, H, fr, q, theta_max)
                else:
                    event, h, w_h, theta_max = step_event(phi, w, phi1, w1, tau, H, fr, q, theta_max)
                if event == EV_OVERTURN:
                    mode = OVERTURNED
                    t_over = t_k + tau + h
                    break
                if event == EV_IMPACT or event == EV_REVERSE:
                    if event == EV_IMPACT:
                        if n_imp < impacts.size:
                            impacts[n_imp] = t_k + tau + h
                        n_imp += 1
                        tau = tau + h
                        mode, s, phi, w, sig = _land(s, w_h, prm, fr, q, wrest2_p, wrest2_n)
                    else:  # the velocity reached zero at phi = ph_h (dry terms)
                        tau = tau + h
                        mode, phi, w, sig = _turn(ph_h, tau, fr, q, sig)
                    n_ev += 1
                    if n_ev > MAX_EVENTS_PER_SAMPLE:
                        mode, phi, w = REST, 0.0, 0.0
                        guard += 1
                        break
                    continue
                if event == EV_NONE:
                    phi = phi1
                    w = w1
                    if phi > theta_max:
                        theta_max = phi
                elif event == EV_STALL:
                    mode = STUCK if phi > 0.0 else REST
                    w = 0.0
                else:  # settle
                    mode = REST
                    phi = 0.0
                    w = 0.0
                tau = tgt
            j += 1
            if j >= m:
                break
        if record:
            store(theta_out, theta_dot_out, k + 1, s, phi, w, mode == ROCKING or mode == STUCK, mode == OVERTURNED)
    return theta_max, mode == OVERTURNED, t_over, t_uplift, n_imp, guard


@njit(cache=True, inline="always")
def _start(acc_g, v_g, dt, theta0, theta_dot0, alpha_p, alpha_n, p2_p, p2_n, c, q):
    """The state of a block released at theta0 [rad], theta_dot0 [rad/s]: (mode, s, phi, w, t_uplift, sig).

    With a dry term, a block released at w = 0 is STUCK while the moments stay within the dry capacity,
    else it starts to turn the way the net moment drives it (sig, the sign of w's motion).
    """
    at_rest, s, phi, w, t_uplift = initial_state(theta0, theta_dot0)
    mode = REST if at_rest else ROCKING
    sig = 0.0
    if HAS_DRY and not at_rest:
        if w != 0.0:
            sig = 1.0 if w > 0.0 else -1.0
        else:
            k1 = 1 if acc_g.size > 1 else 0
            fr = frame(s, acc_g[0], acc_g[k1], v_g[0], v_g[k1], dt, 0.0, alpha_p, alpha_n, p2_p, p2_n, c, 0.0)
            if hold_margin(phi, True, 0.0, fr, q) <= 0.0:
                mode = STUCK
            else:
                sig = 1.0 if accel(phi, 0.0, 0.0, fr, q) > 0.0 else -1.0
    return mode, s, phi, w, t_uplift, sig


@njit(cache=True, inline="always")
def _depart(
    mode, phi, s, sig, tau, m, dt, g0, g1, u0, u1, t_k, t_uplift, alpha_p, alpha_n, p2_p, p2_n, c, tan_p, tan_n, q
):
    """When a block at REST (or STUCK) starts to rock, at or after local time tau [s] of the sample from t_k [s].

    Returns (tau, s, phi, sig, t_uplift): the local time it starts (inf when it stays through the sample,
    the rest unchanged then), its pivot, angle, direction, and the first uplift time [s].
    """
    if AT_REST:
        tl, sd, sg = leave(mode == STUCK, phi, s, tau, m, dt, g0, g1, u0, u1, t_k, alpha_p, alpha_n, p2_p, p2_n, c, q)
        if tl == math.inf:
            return tl, s, phi, sig, t_uplift
        if mode == REST:
            s = sd
            phi = 0.0
            if math.isnan(t_uplift):
                t_uplift = t_k + tl
        return tl, s, phi, sg, t_uplift
    tu_p, tu_n = uplift(g0, g1, tau, dt, tan_p, tan_n)
    if tu_p == math.inf and tu_n == math.inf:
        return math.inf, s, phi, sig, t_uplift
    s = 1.0 if tu_p < tu_n else -1.0
    tau = tu_p if tu_p < tu_n else tu_n
    if math.isnan(t_uplift):
        t_uplift = t_k + tau
    return tau, s, 0.0, 1.0, t_uplift


@njit(cache=True, inline="always")
def _land(s, w_h, prm, fr, q, wrest2_p, wrest2_n):
    """An impact on pivot s at speed -w_h [rad/s]: the block rocks on -s, or rests if it is too slow.

    Returns (mode, s, phi, w, sig) after the impact.
    """
    r_imp = prm[I_R_NEG] if s > 0.0 else prm[I_R_POS]
    if HAS_IMPACT:
        r_imp = impact_ratio(-w_h, r_imp, s, fr[6], fr[7], q)
    w = restitution(-w_h, r_imp, prm[I_R_EXP], fr[7], fr[6])
    s = -s
    if w * w < (wrest2_p if s > 0.0 else wrest2_n):
        return REST, s, 0.0, 0.0, 1.0
    return ROCKING, s, 0.0, w, 1.0


@njit(cache=True, inline="always")
def _turn(ph_h, tau, fr, q, sig):
    """The velocity reached zero at phi = ph_h [rad] (dry terms): the block turns back, sticks or rests.

    Returns (mode, phi, w, sig).
    """
    phi = ph_h
    sig = after_reversal(phi, tau, fr, q, sig) if phi > 0.0 else 0.0
    if sig == 0.0:
        if phi > 0.0:
            return STUCK, phi, 0.0, sig
        return REST, 0.0, 0.0, sig
    return ROCKING, phi, 0.0, sig


@njit(cache=True)
def run_batch(*batch):
    """Serial batch over records i with samples acc_g[offsets[i]:offsets[i+1]].

    ``batch`` is (acc_g, v_g, offsets, dts, ms, prm, q, theta0s, theta_dot0s, rest_tol, record, theta, theta_dot,
    impacts, imp_offsets, out), :func:`_one_of_batch`'s arguments after the record's index; ``q`` [n_rec, n_q]:
    the records' terms. ``out`` [n_rec, 6] receives (theta_max, overturned, t_over, t_uplift, n_imp, guard).
    When ``record`` is False, ``theta`` and ``theta_dot`` may be empty.
    """
    for i in range(batch[2].size - 1):  # batch[2]: offsets
        _one_of_batch(i, *batch)


@njit(cache=True, parallel=True)
def run_batch_parallel(*batch):
    """:func:`run_batch` with the records spread over threads (numba ``prange``)."""
    for i in prange(batch[2].size - 1):
        _one_of_batch(i, *batch)


@njit(cache=True)
def _one_of_batch(
    i,
    acc_g,
    v_g,
    offsets,
    dts,
    ms,
    prm,
    q,
    theta0s,
    theta_dot0s,
    rest_tol,
    record,
    theta,
    theta_dot,
    impacts,
    imp_offsets,
    out,
):
    a = offsets[i]
    b = offsets[i + 1]
    if record:
        th = theta[a:b]
        thd = theta_dot[a:b]
    else:
        th = theta[0:0]
        thd = theta_dot[0:0]
    res = run_one(
        acc_g[a:b],
        v_g[a:b],
        dts[i],
        ms[i],
        prm[i],
        q[i],
        theta0s[i],
        theta_dot0s[i],
        rest_tol,
        record,
        th,
        thd,
        impacts[imp_offsets[i] : imp_offsets[i + 1]],
    )
    out[i, 0] = res[0]
    out[i, 1] = 1.0 if res[1] else 0.0
    out[i, 2] = res[2]
    out[i, 3] = res[3]
    out[i, 4] = res[4]
    out[i, 5] = res[5]
