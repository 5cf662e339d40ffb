"""Compiled core of the analytic Housner solver (private; use :mod:`housner.model`).

Everything here works in *reduced coordinates* on the current pivot ``s``
(+1 for the +x corner, -1 for the -x corner)::

    phi = s theta >= 0,   w = s theta_dot,   a = s ug'' / g

in which Housner's equation of motion (seed eq. 2, plus a viscous term) reads
the same on both pivots::

    phi'' = -p_s^2 (sin(alpha_s - phi) + a cos(alpha_s - phi)) - c w

The negative pivot is therefore computed by the very same floating-point
operations as the positive one, with the inputs negated; IEEE rounding is
symmetric under negation, so ug -> -ug gives theta -> -theta bit for bit.

Time is split into the motion's sample intervals (ug'' linear inside each)
and every interval into ``m`` equal substeps of classic RK4. Events (impact,
peak, overturn) are located by Newton iteration on the length of a single
RK4 step from the start of the substep, so that the located root is a root
of the very integrator that is being used, to machine precision.

Units: time [s], angles [rad], angular velocity [rad/s], ground acceleration
in units of g [-] (the caller divides by g once).

The pieces that do not depend on the equation of motion (the substep grid,
the RK4 update, the secant trial point, uplift from rest, the rest rule,
restitution, the history) are shared with the kernels of the mechanics
effects (:mod:`housner.effects.sliding`, :mod:`housner.effects.flexible`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

HALF_PI = 0.5 * math.pi
EPS = 2.220446049250313e-16

#: Layout of the parameter vector handed to the kernel. I_R is the common
#: ratio (kept for reference); the kernel uses I_R_POS for an impact that
#: lands on the +x corner and I_R_NEG for one that lands on the -x corner.
I_ALPHA_POS, I_ALPHA_NEG, I_P_POS, I_P_NEG, I_R, I_R_EXP, I_DAMPING, I_R_POS, I_R_NEG = range(9)
N_PARAMS = 9

#: Block states.
REST, ROCKING, OVERTURNED = 0, 1, 2

#: Event codes of one step.
_EV_NONE, _EV_IMPACT, _EV_OVERTURN, _EV_SETTLE = 0, 1, 2, 3

#: Safety net: most events allowed inside one sample interval before the
#: block is put to rest (never reached with rest_tol >= 1e-15, see model.py).
_MAX_EVENTS_PER_SAMPLE = 100_000


@njit(cache=True)
def _accel(phi, w, a, alpha, p2, c):
    """phi'' [rad/s^2] in reduced coordinates (a = s ug''/g [-], c [1/s])."""
    d = alpha - phi
    return -p2 * (math.sin(d) + a * math.cos(d)) - c * w


@njit(cache=True)
def _rk4_update(y, v, h, v1, v2, v3, v4, a1, a2, a3, a4):
    """End (y, v) of an RK4 step of length h [s] for a coordinate y with rate v.

    v1..v4 are the stage rates of y, a1..a4 those of v (weights 1, 2, 2, 1).
    """
    h6 = h / 6.0
    return y + h6 * (v1 + 2.0 * v2 + 2.0 * v3 + v4), v + h6 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)


@njit(cache=True)
def _rk4(phi, w, tau, h, a0, slope, alpha, p2, c):
    """One classic RK4 step of length h [s] from local time tau [s].

    The reduced ground acceleration is a(tau) = a0 + slope * tau [-].
    """
    hh = 0.5 * h
    a_beg = a0 + slope * tau
    a_mid = a0 + slope * (tau + hh)
    a_end = a0 + slope * (tau + h)
    k1 = _accel(phi, w, a_beg, alpha, p2, c)
    w2 = w + hh * k1
    k2 = _accel(phi + hh * w, w2, a_mid, alpha, p2, c)
    w3 = w + hh * k2
    k3 = _accel(phi + hh * w2, w3, a_mid, alpha, p2, c)
    w4 = w + h * k3
    k4 = _accel(phi + h * w3, w4, a_end, alpha, p2, c)
    return _rk4_update(phi, w, h, w, w2, w3, w4, k1, k2, k3, k4)


@njit(cache=True)
def _secant(hl, gl, hr, gr):
    """Next trial point of the bracket [hl, hr] [s] with values gl, gr: the secant root, or the midpoint."""
    h = hr - gr * (hr - hl) / (gr - gl)
    if not (hl < h < hr):
        h = 0.5 * (hl + hr)
    return h


@njit(cache=True)
def _locate(kind, target, hl, gl, hr, gr, phi0, w0, tau, a0, slope, alpha, p2, c):
    """Root h in [hl, hr] [s] of a function of one RK4 step of length h from tau.

    ``kind`` 0: phi(h) - target; ``kind`` 1: w(h). ``gl`` and ``gr`` are the
    function at the bracket ends and have opposite signs (``gr`` may be 0).
    Safeguarded Newton: the derivative is the step's own end state (w, or
    phi''), which matches d/dh of the step to O(h^4), so convergence is fast;
    a bisection replaces any Newton update that leaves the bracket.

    Returns (h, phi(h), w(h)).
    """
    if gr == 0.0:
        ph, wh = _rk4(phi0, w0, tau, hr, a0, slope, alpha, p2, c)
        return hr, ph, wh
    h = _secant(hl, gl, hr, gr)
    ph = 0.0
    wh = 0.0
    for _ in range(200):
        ph, wh = _rk4(phi0, w0, tau, h, a0, slope, alpha, p2, c)
        if kind == 0:
            g = ph - target
            d = wh
        else:
            g = wh
            d = _accel(ph, wh, a0 + slope * (tau + h), alpha, p2, c)
        if g == 0.0:
            break
        if (g > 0.0) == (gl > 0.0):
            hl = h
            gl = g
        else:
            hr = h
            gr = g
        hn = h - g / d if d != 0.0 else 0.5 * (hl + hr)
        if not (hl < hn < hr):
            hn = 0.5 * (hl + hr)
        if abs(hn - h) <= 4.0 * EPS * (tau + h) or hr - hl <= 4.0 * EPS * (tau + hr):
            break
        h = hn
    return h, ph, wh


@njit(cache=True)
def _uplift_side(b0, b1, tau_c, dt, thr):
    """First local time >= tau_c [s] at which b(tau) < thr (b linear b0 -> b1 over dt); inf if none."""
    b_c = b0 + (b1 - b0) * (tau_c / dt)
    if b_c < thr:
        return tau_c
    if b1 < thr:
        tu = dt * ((thr - b0) / (b1 - b0))
        if tu < tau_c:
            tu = tau_c
        if tu > dt:
            tu = dt
        return tu
    return math.inf


@njit(cache=True)
def _grid(j, m, dt):
    """Local time of substep boundary j of m [s] (exactly dt at j = m)."""
    if j >= m:
        return dt
    return dt * j / m


@njit(cache=True)
def _substep_of(tau, m, dt):
    """Index of the substep of m that contains local time tau [s] (m - 1 at tau = dt)."""
    j = int(tau * m / dt)
    if j > m - 1:
        j = m - 1
    return j


@njit(cache=True)
def _pivot_constants(alpha_p, alpha_n, p2_p, p2_n, rest_tol):
    """tan(alpha) [-] and the squared rest speed [rad^2/s^2] of the +x and the -x pivot.

    Rest rule: the free-rocking peak phi_pk of post-impact speed w obeys
    w^2 / (2 p^2) = cos(alpha - phi_pk) - cos(alpha); below rest_tol*alpha means
    w^2 < 2 p^2 (cos(alpha - x) - cos(alpha)) = 4 p^2 sin(alpha - x/2) sin(x/2).
    Returns (tan_p, tan_n, wrest2_p, wrest2_n).
    """
    x = rest_tol * alpha_p
    wrest2_p = 4.0 * p2_p * math.sin(alpha_p - 0.5 * x) * math.sin(0.5 * x)
    x = rest_tol * alpha_n
    wrest2_n = 4.0 * p2_n * math.sin(alpha_n - 0.5 * x) * math.sin(0.5 * x)
    return math.tan(alpha_p), math.tan(alpha_n), wrest2_p, wrest2_n


@njit(cache=True)
def _initial_state(theta0, theta_dot0):
    """(at_rest, s, phi, w, t_uplift) of a block released at theta0 [rad] with theta_dot0 [rad/s]."""
    if theta0 == 0.0 and theta_dot0 == 0.0:
        return True, 1.0, 0.0, 0.0, math.nan
    s = 1.0
    if theta0 < 0.0 or (theta0 == 0.0 and theta_dot0 < 0.0):
        s = -1.0
    return False, s, s * theta0, s * theta_dot0, 0.0


@njit(cache=True)
def _uplift(g0, g1, tau, dt, thr_p, thr_n):
    """First local times >= tau [s] at which g0 -> g1 [g] falls below -thr_p and rises above thr_n (inf: not here).

    With thr = tan(alpha) of each pivot: when a block at rest tips onto the +x and onto the -x corner.
    """
    return _uplift_side(g0, g1, tau, dt, -thr_p), _uplift_side(-g0, -g1, tau, dt, -thr_n)


@njit(cache=True)
def _reduced_ground(s, g0, g1, dt):
    """Reduced ground acceleration on pivot s: a0 = s g0 [-] at the sample start and its slope [1/s]."""
    if s > 0.0:
        a0 = g0
        a1 = g1
    else:
        a0 = -g0
        a1 = -g1
    return a0, (a1 - a0) / dt


@njit(cache=True)
def _restitution(v, r, r_exp, p2, alpha):
    """Speed [rad/s] after an impact at speed v: sqrt(r_eff) v, r_eff = clip(r (v / (p alpha))^r_exp, 0, 1)."""
    r_eff = r
    if r_exp != 0.0 and v > 0.0:
        r_eff = r * (v / (math.sqrt(p2) * alpha)) ** r_exp
        if r_eff > 1.0:
            r_eff = 1.0
        if r_eff < 0.0:
            r_eff = 0.0
    return math.sqrt(r_eff) * v


@njit(cache=True)
def _store(theta_out, theta_dot_out, i, s, phi, w, rocking, overturned):
    """Write sample i of the history: the state while rocking, +-pi/2 once overturned, else rest."""
    if rocking:
        theta_out[i] = s * phi
        theta_dot_out[i] = s * w
    elif overturned:
        theta_out[i] = s * HALF_PI
        theta_dot_out[i] = 0.0
    else:
        theta_out[i] = 0.0
        theta_dot_out[i] = 0.0


@njit(cache=True, inline="always")
def _crossing(phi, w, phi1, w1, hp, php, tau, H, a0, slope, alpha, p2, c):
    """Does phi cross zero inside the step (phi, w) -> (phi1, w1) of length H [s]?

    ``hp``, ``php``: time and value of a peak inside the step (hp < 0 if none).
    Returns (event, hl, gl, hr, gr): ``_EV_IMPACT`` with a bracket [hl, hr] of
    the first crossing (phi = gl > 0 at hl, gr <= 0 at hr), ``_EV_SETTLE`` or
    ``_EV_NONE``.
    """
    hl = -1.0
    gl = 0.0
    hr = H
    gr = phi1
    if phi1 < 0.0 or (phi1 == 0.0 and w1 < 0.0):
        if hp >= 0.0 and php > 0.0:
            hl = hp
            gl = php
        elif phi > 0.0:
            hl = 0.0
            gl = phi
        elif w > 0.0:
            # just after an impact (phi = 0, w > 0): find a point of the
            # step with phi > 0 to bracket the next crossing
            hb = 0.5 * H
            for _ in range(80):
                pb, _wb = _rk4(phi, w, tau, hb, a0, slope, alpha, p2, c)
                if pb > 0.0:
                    hl = hb
                    gl = pb
                    break
                hb *= 0.5
        if hl < 0.0:
            # fresh uplift that did not lift (threshold met to rounding only)
            return _EV_SETTLE, hl, gl, hr, gr
    elif w < 0.0 and w1 > 0.0 and phi1 > 0.0 and phi > 0.0:
        # a minimum inside the step: does it dip below zero?
        hm, phm, _wm = _locate(1, 0.0, 0.0, w, H, w1, phi, w, tau, a0, slope, alpha, p2, c)
        if phm < 0.0:
            hl = 0.0
            gl = phi
            hr = hm
            gr = phm
    return (_EV_IMPACT if hl >= 0.0 else _EV_NONE), hl, gl, hr, gr


@njit(cache=True, inline="always")
def _step_event(phi, w, phi1, w1, tau, H, a0, slope, alpha, p2, c, theta_max):
    """First event of the RK4 step (phi, w) -> (phi1, w1) of length H [s] from local time tau [s].

    Returns (event, h, w_h, theta_max): the event code (``_EV_*``), the time
    h [s] after tau at which it happens and the speed w_h [rad/s] there (for
    an impact), and theta_max raised by a peak of phi inside the step.
    """
    # a peak of phi inside the step (theta_max between samples)
    hp = -1.0
    php = 0.0
    if w > 0.0 and w1 < 0.0:
        hp, php, _wp = _locate(1, 0.0, 0.0, w, H, w1, phi, w, tau, a0, slope, alpha, p2, c)
    # overturn: phi reaches pi/2
    if (hp >= 0.0 and php >= HALF_PI) or phi1 >= HALF_PI:
        hr = H
        gr = phi1 - HALF_PI
        if hp >= 0.0 and php >= HALF_PI:
            hr = hp
            gr = php - HALF_PI
        h_o, _ph, _wh = _locate(0, HALF_PI, 0.0, phi - HALF_PI, hr, gr, phi, w, tau, a0, slope, alpha, p2, c)
        return _EV_OVERTURN, h_o, 0.0, HALF_PI
    if hp >= 0.0 and php > theta_max:
        theta_max = php
    # impact: phi crosses zero inside the step
    event, hl, gl, hr, gr = _crossing(phi, w, phi1, w1, hp, php, tau, H, a0, slope, alpha, p2, c)
    if event == _EV_IMPACT:
        h_i, _ph, w_i = _locate(0, 0.0, hl, gl, hr, gr, phi, w, tau, a0, slope, alpha, p2, c)
        return _EV_IMPACT, h_i, w_i, theta_max
    return event, 0.0, 0.0, theta_max


@njit(cache=True)
def run_one(acc_g, dt, m, prm, theta0, theta_dot0, rest_tol, record, theta_out, theta_dot_out, impacts):
    """Simulate one record.

    Parameters
    ----------
    acc_g : float64[:]
        Ground acceleration in units of g [-], n samples.
    dt : float
        Sample step [s].
    m : int
        RK4 substeps per sample.
    prm : float64[:]
        Parameter vector (see the ``I_*`` indices).
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
    alpha_p = prm[I_ALPHA_POS]
    alpha_n = prm[I_ALPHA_NEG]
    p2_p = prm[I_P_POS] * prm[I_P_POS]
    p2_n = prm[I_P_NEG] * prm[I_P_NEG]
    c = prm[I_DAMPING]
    tan_p, tan_n, wrest2_p, wrest2_n = _pivot_constants(alpha_p, alpha_n, p2_p, p2_n, rest_tol)
    at_rest, s, phi, w, t_uplift = _initial_state(theta0, theta_dot0)
    mode = REST if at_rest else ROCKING
    theta_max = abs(theta0)
    t_over = math.nan
    n_imp = 0
    guard = 0
    if record:
        theta_out[0] = theta0
        theta_dot_out[0] = theta_dot0

    for k in range(acc_g.size - 1):
        if mode == OVERTURNED and not record:
            break
        t_k, g0, g1 = k * dt, acc_g[k], acc_g[k + 1]
        tau, j, n_ev = 0.0, 0, 0  # local time [s], substep, events in this sample
        while mode != OVERTURNED:
            if mode == REST:
                tu_p, tu_n = _uplift(g0, g1, tau, dt, tan_p, tan_n)
                if tu_p == math.inf and tu_n == math.inf:
                    break
                s = 1.0 if tu_p < tu_n else -1.0
                tau = tu_p if tu_p < tu_n else tu_n
                if math.isnan(t_uplift):
                    t_uplift = t_k + tau
                mode = ROCKING
                phi = 0.0
                w = 0.0
                j = _substep_of(tau, m, dt)
            tgt = _grid(j + 1, m, dt)
            if tgt > tau:
                a0, slope = _reduced_ground(s, g0, g1, dt)
                alpha = alpha_p if s > 0.0 else alpha_n
                p2 = p2_p if s > 0.0 else p2_n
                H = tgt - tau
                phi1, w1 = _rk4(phi, w, tau, H, a0, slope, alpha, p2, c)
                event, h, w_h, theta_max = _step_event(phi, w, phi1, w1, tau, H, a0, slope, alpha, p2, c, theta_max)
                if event == _EV_OVERTURN:
                    mode = OVERTURNED
                    t_over = t_k + tau + h
                    break
                if event == _EV_IMPACT:
                    if n_imp < impacts.size:
                        impacts[n_imp] = t_k + tau + h
                    n_imp += 1
                    tau = tau + h
                    # restitution: the ratio of the corner that lands (s is still the
                    # old pivot, so -s is the new one), the amplitude reference of the old pivot
                    r_imp = prm[I_R_NEG] if s > 0.0 else prm[I_R_POS]
                    w = _restitution(-w_h, r_imp, prm[I_R_EXP], p2, alpha)
                    phi = 0.0
                    s = -s
                    if w * w < (wrest2_p if s > 0.0 else wrest2_n):
                        mode = REST
                        w = 0.0
                    n_ev += 1
                    if n_ev > _MAX_EVENTS_PER_SAMPLE:
                        mode = REST
                        w = 0.0
                        guard += 1
                        break
                    continue
                if event == _EV_NONE:
                    phi = phi1
                    w = w1
                    if phi > theta_max:
                        theta_max = phi
                else:  # settle
                    mode = REST
                    phi = 0.0
                    w = 0.0
                tau = tgt
            j += 1
            if j >= m:
                break
        if record:
            _store(theta_out, theta_dot_out, k + 1, s, phi, w, mode == ROCKING, mode == OVERTURNED)
    return theta_max, mode == OVERTURNED, t_over, t_uplift, n_imp, guard


@njit(cache=True)
def run_batch(
    acc_g, offsets, dts, ms, prm, theta0s, theta_dot0s, rest_tol, record, theta, theta_dot, impacts, imp_offsets, out
):
    """Serial batch over records i with samples acc_g[offsets[i]:offsets[i+1]].

    ``out`` [n_rec, 6] receives (theta_max, overturned, t_over, t_uplift, n_imp, guard).
    When ``record`` is False, ``theta`` and ``theta_dot`` may be empty.
    """
    for i in range(offsets.size - 1):
        _one_of_batch(
            i, acc_g, offsets, dts, ms, prm, theta0s, theta_dot0s, rest_tol, record, theta, theta_dot, impacts,
            imp_offsets, out,
        )  # fmt: skip


@njit(cache=True, parallel=True)
def run_batch_parallel(
    acc_g, offsets, dts, ms, prm, theta0s, theta_dot0s, rest_tol, record, theta, theta_dot, impacts, imp_offsets, out
):
    """:func:`run_batch` with the records spread over threads (numba ``prange``)."""
    for i in prange(offsets.size - 1):
        _one_of_batch(
            i, acc_g, offsets, dts, ms, prm, theta0s, theta_dot0s, rest_tol, record, theta, theta_dot, impacts,
            imp_offsets, out,
        )  # fmt: skip


@njit(cache=True)
def _one_of_batch(
    i, acc_g, offsets, dts, ms, prm, theta0s, theta_dot0s, rest_tol, record, theta, theta_dot, impacts, imp_offsets, out
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
        dts[i],
        ms[i],
        prm[i],
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


def empty_buffers(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Two empty float64 arrays (placeholders for unrecorded histories)."""
    return np.empty(n, dtype=np.float64), np.empty(n, dtype=np.float64)
