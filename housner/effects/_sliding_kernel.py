"""The sliding kernel: a block on rigid ground with Coulomb friction at its base (:mod:`housner.effects.sliding`).

:func:`run_sliding` integrates the regimes rest, slide, rock and slide-rock with RK4 substeps cut at
every change of regime; its constants vector's layout is ``S_*``, its regimes ``REST`` ... ``OVERTURNED``.
The model is :class:`housner.effects.sliding.Sliding`'s docstring.
"""

from __future__ import annotations

import math

from numba import njit

from housner._kernel_parts import (
    EPS,
    HALF_PI,
    grid,
    initial_state,
    pivot_constants,
    reduced_ground,
    restitution,
    rk4_update,
    secant,
    store,
    substep_of,
    uplift,
)
from housner.effects._mechanics import MAX_EVENTS_PER_SAMPLE, illinois

#: Layout of the constants vector of ``run_sliding`` (per unit mass):
#: g [m/s^2], mu [-], c [1/s], r [-], r_exp [-], then per side (+x, -x):
#: alpha [rad], R [m], i0 [m^2] (inertia about the corner / m), p^2 [1/s^2].
S_G, S_MU, S_C, S_R, S_REXP = range(5)
S_ALPHA_P, S_R_P, S_I0_P, S_P2_P, S_ALPHA_N, S_R_N, S_I0_N, S_P2_N = range(5, 13)
N_SLIDE = 13

#: Regimes (also written to the regime history).
REST, SLIDE, ROCK, SLIDE_ROCK, OVERTURNED = 0, 1, 2, 3, 4


@njit(cache=True)
def _sl_side(q, s):
    """alpha [rad], R [m], i0 [m^2], p^2 [1/s^2] of the corner of side s."""
    if s > 0.0:
        return q[S_ALPHA_P], q[S_R_P], q[S_I0_P], q[S_P2_P]
    return q[S_ALPHA_N], q[S_R_N], q[S_I0_N], q[S_P2_N]


@njit(cache=True)
def _sl_acc(mode, s, sig, fric, phi, w, a, q):
    """(phi'', x'') [rad/s^2, m/s^2] in reduced coordinates phi = s theta, w = s theta'.

    ``a`` is s ug''/g [-] (reduced, as in :mod:`housner._kernel`); x is the
    slip of the pivot [m] (not reduced), ``sig`` its direction.
    """
    g = q[S_G]
    if mode == SLIDE:
        return 0.0, -s * a * g - q[S_MU] * g * sig
    alpha, rr, i0, p2 = _sl_side(q, s)
    d = alpha - phi
    if mode == ROCK:
        return -p2 * (math.sin(d) + a * math.cos(d)) - q[S_C] * w, 0.0
    # slide-rock: pivot slides in direction sig with friction mu N (0 when N < 0)
    sn = rr * math.sin(d)
    cn = rr * math.cos(d)
    mu = q[S_MU] if fric else 0.0
    sp = sig * s
    gn = g - cn * w * w
    phidd = ((mu * sp * cn - sn) * gn - q[S_C] * i0 * w) / (i0 - rr * rr + sn * sn - mu * sp * cn * sn)
    nn = g + sn * phidd - cn * w * w
    xdd = -mu * sig * nn - s * a * g - s * cn * phidd - s * sn * w * w
    return phidd, xdd


@njit(cache=True)
def _sl_rk4(mode, s, sig, fric, phi, w, x, xd, tau, h, a0, slope, q):
    """One RK4 step of length h [s]; reduced ground acc a0 + slope * tau [-]."""
    hh = 0.5 * h
    a_beg = a0 + slope * tau
    a_mid = a0 + slope * (tau + hh)
    a_end = a0 + slope * (tau + h)
    k1, l1 = _sl_acc(mode, s, sig, fric, phi, w, a_beg, q)
    w2 = w + hh * k1
    v2 = xd + hh * l1
    k2, l2 = _sl_acc(mode, s, sig, fric, phi + hh * w, w2, a_mid, q)
    w3 = w + hh * k2
    v3 = xd + hh * l2
    k3, l3 = _sl_acc(mode, s, sig, fric, phi + hh * w2, w3, a_mid, q)
    w4 = w + h * k3
    v4 = xd + h * l3
    k4, l4 = _sl_acc(mode, s, sig, fric, phi + h * w3, w4, a_end, q)
    phi_h, w_h = rk4_update(phi, w, h, w, w2, w3, w4, k1, k2, k3, k4)
    x_h, xd_h = rk4_update(x, xd, h, xd, v2, v3, v4, l1, l2, l3, l4)
    return phi_h, w_h, x_h, xd_h


@njit(cache=True)
def _sl_stick(s, phi, w, a, q):
    """Friction demand F/m and normal force N/m [m/s^2] of a rocking block whose pivot sticks."""
    g = q[S_G]
    alpha, rr, _i0, _p2 = _sl_side(q, s)
    phidd, _x = _sl_acc(ROCK, s, 0.0, True, phi, w, a, q)
    d = alpha - phi
    sn = rr * math.sin(d)
    cn = rr * math.cos(d)
    f = s * a * g + s * cn * phidd + s * sn * w * w
    nn = g + sn * phidd - cn * w * w
    return f, nn


@njit(cache=True)
def _sl_painleve(s, sig, phi, q):
    """Denominator of the slide-rock equation [m^2]; <= 0 is Painleve's paradox (no consistent slip)."""
    alpha, rr, i0, _p2 = _sl_side(q, s)
    d = alpha - phi
    sn = rr * math.sin(d)
    cn = rr * math.cos(d)
    return i0 - rr * rr + sn * sn - q[S_MU] * sig * s * cn * sn


@njit(cache=True)
def _sl_margin(mode, s, sig, fric, jam, phi, w, xd, a, q):
    """Smallest mode margin: negative once the frozen regime is violated."""
    if mode == SLIDE:
        return sig * xd
    m = phi
    v = HALF_PI - phi
    if v < m:
        m = v
    if mode == ROCK:
        f, nn = _sl_stick(s, phi, w, a, q)
        v = q[S_MU] * nn - abs(f)
        if jam:
            v = -v
        if v < m:
            m = v
        return m
    v = sig * xd
    if v < m:
        m = v
    if fric:
        v = _sl_painleve(s, sig, phi, q)
        if v < m:
            m = v
    _alpha, rr, _i0, _p2 = _sl_side(q, s)
    v = q[S_G] - rr * math.cos(_alpha - phi) * w * w
    if not fric:
        v = -v
    if v < m:
        m = v
    return m


@njit(cache=True)
def _sl_bracket(kind, mode, s, sig, fric, jam, phi, w, x, xd, tau, hl, vl, hr, vr, a0, slope, q):
    """First h in (hl, hr] where the margin (kind 0) or w (kind 1) turns negative; returns (h, state)."""
    y0, y1, y2, y3 = _sl_rk4(mode, s, sig, fric, phi, w, x, xd, tau, hr, a0, slope, q)
    side = 0
    for _ in range(200):
        if hr - hl <= 4.0 * EPS * (tau + hr):
            break
        h = secant(hl, vl, hr, vr)
        z0, z1, z2, z3 = _sl_rk4(mode, s, sig, fric, phi, w, x, xd, tau, h, a0, slope, q)
        if kind == 0:
            v = _sl_margin(mode, s, sig, fric, jam, z0, z1, z3, a0 + slope * (tau + h), q)
        else:
            v = z1
        if v < 0.0:
            y0, y1, y2, y3 = z0, z1, z2, z3
        hl, vl, hr, vr, side = illinois(h, v, hl, vl, hr, vr, side)
    return hr, y0, y1, y2, y3


@njit(cache=True, inline="always")
def _sl_step(mode, s, sig, fric, jam, phi, w, x, xd, tau, tgt, a0, slope, q, theta_max):
    """The RK4 step from local time tau to tgt [s], cut at the first violation of the regime.

    Returns (event, h, phi, w, x, xd, theta_max): whether the step was cut,
    its length h [s], the state at its end, and theta_max raised by the peak
    of a rocking block inside the step.
    """
    hs = tgt - tau
    y0, y1, y2, y3 = _sl_rk4(mode, s, sig, fric, phi, w, x, xd, tau, hs, a0, slope, q)
    mr = _sl_margin(mode, s, sig, fric, jam, y0, y1, y3, a0 + slope * tgt, q)
    event = mr < 0.0
    if event:
        ml = _sl_margin(mode, s, sig, fric, jam, phi, w, xd, a0 + slope * tau, q)
        if ml < 0.0:
            ml = 0.0
        hs, y0, y1, y2, y3 = _sl_bracket(0, mode, s, sig, fric, jam, phi, w, x, xd, tau, 0.0, ml, hs, mr, a0, slope, q)
    if mode != SLIDE and w > 0.0 and y1 < 0.0:
        _h, p0, _p1, _p2, _p3 = _sl_bracket(
            1, mode, s, sig, fric, jam, phi, w, x, xd, tau, 0.0, w, hs, y1, a0, slope, q
        )
        if p0 > theta_max:
            theta_max = p0
    if mode != SLIDE and y0 > theta_max:
        theta_max = y0
    return event, hs, y0, y1, y2, y3, theta_max


@njit(cache=True)
def _sl_rock_or_slip(s, phi, w, a, q):
    """Regime of a rocking block whose pivot is not slipping: (mode, sig, jam)."""
    f, nn = _sl_stick(s, phi, w, a, q)
    if abs(f) <= q[S_MU] * nn:
        return ROCK, 0.0, False
    sig = -1.0 if f > 0.0 else 1.0
    if _sl_painleve(s, sig, phi, q) <= 0.0:
        return ROCK, 0.0, True
    return SLIDE_ROCK, sig, False


@njit(cache=True)
def _sl_start_slide(sig, s, fric, tan_p, tan_n, q):
    """(mode, s, fric) of a base starting to slip toward sig: slide, or slide-rock on that corner if mu > tan(alpha)."""
    tan_s = tan_p if sig > 0.0 else tan_n
    if q[S_MU] > tan_s:
        return SLIDE_ROCK, sig, True
    return SLIDE, s, fric


@njit(cache=True)
def _sl_slip_stops(s, sig, fric, a, tan_p, tan_n, q):
    """(mode, s, sig, fric) when the slip of a sliding block stops at reduced ground acc a [-]: rest, or slip again."""
    a_phys = s * a
    if abs(a_phys) <= q[S_MU]:
        return REST, s, sig, fric
    sig = -1.0 if a_phys > 0.0 else 1.0
    mode, s, fric = _sl_start_slide(sig, s, fric, tan_p, tan_n, q)
    return mode, s, sig, fric


@njit(cache=True, inline="always")
def _sl_leave_rest(g0, g1, tau, dt, s, sig, fric, jam, tan_p, tan_n, q):
    """How a block at rest starts to move at or after local time tau [s] (ground acc g0 -> g1 [g]).

    Returns (tau, mode, s, sig, fric, jam, n_jam, tipped, slipped): the time it
    starts (inf when it stays at rest through the sample), its new regime,
    whether the start counts a jam, lifts a corner, slips the base.
    """
    mu = q[S_MU]
    tu_p, tu_n = uplift(g0, g1, tau, dt, tan_p, tan_n)
    ts_p, ts_n = uplift(g0, g1, tau, dt, mu, mu)  # slides toward +x, -x
    t_tip = min(tu_p, tu_n)
    t_sl = min(ts_p, ts_n)
    if t_tip == math.inf and t_sl == math.inf:
        return math.inf, REST, s, sig, fric, jam, 0, False, False
    tau = min(t_tip, t_sl)
    a_now = g0 + (g1 - g0) * (tau / dt)
    side = 1.0 if a_now < 0.0 else -1.0
    tan_s = tan_p if side > 0.0 else tan_n
    if t_sl < t_tip or (t_sl == t_tip and mu < tan_s):
        mode, s, fric = _sl_start_slide(side, s, fric, tan_p, tan_n, q)
        return tau, mode, s, side, fric, jam, 0, mode == SLIDE_ROCK, True
    mode, sig, jam = _sl_rock_or_slip(side, 0.0, 0.0, side * a_now, q)
    if mode == SLIDE_ROCK:
        fric = True
    return tau, mode, side, sig, fric, jam, 1 if jam else 0, True, mode == SLIDE_ROCK


@njit(cache=True)
def _sl_impact(s, sig, fric, jam, w, xd, g_now, piv, q):
    """Housner's impact law on theta' at ground acc g_now [g]; the slip velocity xd [m/s] is kept; ``piv`` is
    (tan_p, tan_n, wrest2_p, wrest2_n) (:func:`housner._kernel_parts.pivot_constants`).

    Returns (mode, s, sig, fric, jam, w, xd, n_jam) after the impact (the block lands on the other corner, phi = 0).
    """
    tan_p, tan_n, wrest2_p, wrest2_n = piv
    alpha, _rr, _i0, p2 = _sl_side(q, s)
    w = restitution(-w, q[S_R], q[S_REXP], p2, alpha)
    s = -s
    if w * w < (wrest2_p if s > 0.0 else wrest2_n):
        if xd == 0.0:
            return REST, s, sig, fric, jam, 0.0, xd, 0
        sig = 1.0 if xd > 0.0 else -1.0
        mode, s, fric = _sl_start_slide(sig, s, fric, tan_p, tan_n, q)
        return mode, s, sig, fric, jam, 0.0, xd, 0
    if xd != 0.0:
        sig = 1.0 if xd > 0.0 else -1.0
        if _sl_painleve(s, sig, 0.0, q) <= 0.0:
            return ROCK, s, sig, True, True, w, 0.0, 1
        return SLIDE_ROCK, s, sig, True, jam, w, xd, 0
    mode, sig, jam = _sl_rock_or_slip(s, 0.0, w, s * g_now, q)
    return mode, s, sig, fric, jam, w, xd, 1 if jam else 0


@njit(cache=True)
def _sl_regime(mode, s, sig, fric, jam, phi, w, xd, a_now, q):
    """The regime after a margin of rock or slide-rock turned negative (reduced ground acc a_now [-]).

    Returns (mode, sig, fric, jam, xd, n_jam, slipped): the new regime and
    slip velocity, whether the change counts a jam and starts a slip.
    """
    if mode == ROCK:
        if jam:
            return ROCK, sig, fric, False, xd, 0, False  # friction suffices again
        mode, sig, jam = _sl_rock_or_slip(s, phi, w, a_now, q)
        if mode == SLIDE_ROCK:
            fric = True
        return mode, sig, fric, jam, xd, 1 if jam else 0, mode == SLIDE_ROCK
    # slide-rock: which margin?
    if sig * xd < 0.0:
        mode, sig, jam = _sl_rock_or_slip(s, phi, w, a_now, q)
        if mode == SLIDE_ROCK:
            fric = True
        return mode, sig, fric, jam, 0.0, 1 if jam else 0, False
    if fric and _sl_painleve(s, sig, phi, q) < 0.0:
        return ROCK, sig, fric, True, 0.0, 1, False
    _alpha, rr, _i0, _p2 = _sl_side(q, s)
    return mode, sig, q[S_G] - rr * math.cos(_alpha - phi) * w * w > 0.0, jam, xd, 0, False


@njit(cache=True, inline="always")
def _sl_start(theta0, theta_dot0, acc0, q):
    """The state of a block released at theta0 [rad], theta_dot0 [rad/s] under ground acc acc0 [g], its pivot
    not slipping: (block, tally) as :func:`_sl_sample` takes them (t_slide 0 when it slips at once, else NaN)."""
    at_rest, s, phi, w, t_uplift = initial_state(theta0, theta_dot0)
    mode, sig, jam, t_slide = REST, 0.0, False, math.nan
    if not at_rest:
        mode, sig, jam = _sl_rock_or_slip(s, phi, w, s * acc0, q)
        if mode == SLIDE_ROCK:
            t_slide = 0.0
    return (mode, s, sig, True, jam, phi, w, 0.0, 0.0), (abs(theta0), 0.0, math.nan, t_uplift, t_slide, 0.0, 0, 0, 0)


@njit(cache=True, inline="always")
def _sl_event(mode, s, sig, fric, jam, phi, w, xd, tau, t_k, dt, g0, g1, a_now, piv, q, impacts, n_imp):
    """The regime after a step of :func:`run_sliding` cut at local time tau [s] (not by an overturn).

    A sliding block's slip stops (rest, or slip again); a rocking one lands (an impact at phi < 0, its
    time t_k + tau stored in ``impacts``) or changes regime (:func:`_sl_regime`). ``a_now`` is the
    reduced ground acceleration at tau [-], ``piv`` the pivot constants (tan_p, tan_n, wrest2_p, wrest2_n).

    Returns (mode, s, sig, fric, jam, phi, w, xd, n_imp, n_jam, slipped): the new state, the impacts
    counted so far, the jams this event counts and whether it starts a slip.
    """
    if mode == SLIDE:
        tan_p, tan_n, _wrest2_p, _wrest2_n = piv
        mode, s, sig, fric = _sl_slip_stops(s, sig, fric, a_now, tan_p, tan_n, q)
        return mode, s, sig, fric, jam, phi, w, 0.0, n_imp, 0, False
    if phi < 0.0:  # impact
        if n_imp < impacts.size:
            impacts[n_imp] = t_k + tau
        g_now = g0 + (g1 - g0) * (tau / dt)
        mode, s, sig, fric, jam, w, xd, dj = _sl_impact(s, sig, fric, jam, w, xd, g_now, piv, q)
        return mode, s, sig, fric, jam, 0.0, w, xd, n_imp + 1, dj, False
    mode, sig, fric, jam, xd, dj, slipped = _sl_regime(mode, s, sig, fric, jam, phi, w, xd, a_now, q)
    return mode, s, sig, fric, jam, phi, w, xd, n_imp, dj, slipped


@njit(cache=True, inline="always")
def _sl_sample(t_k, g0, g1, dt, msub, block, tally, piv, q, impacts):
    """:func:`run_sliding` through the sample interval from t_k [s] (ground acc g0 -> g1 [g]) in ``msub`` RK4
    substeps, each cut at the regime's events.

    ``block`` is the block's state (mode, s, sig, fric, jam, phi, w, x, xd), ``tally`` the running results
    (theta_max, x_max, t_over, t_uplift, t_slide, t_lift, n_imp, n_jam, guard), ``piv`` the pivot constants
    (tan_p, tan_n, wrest2_p, wrest2_n); returns (block, tally) at the interval's end.
    """
    mode, s, sig, fric, jam, phi, w, x, xd = block
    theta_max, x_max, t_over, t_uplift, t_slide, t_lift, n_imp, n_jam, guard = tally
    tan_p, tan_n, _wrest2_p, _wrest2_n = piv
    tau, j, n_ev = 0.0, 0, 0
    while mode != OVERTURNED:
        if mode == REST:
            tau, mode, s, sig, fric, jam, dj, tipped, slipped = _sl_leave_rest(
                g0, g1, tau, dt, s, sig, fric, jam, tan_p, tan_n, q
            )
            if tau == math.inf:
                break
            n_jam += dj
            t_uplift = t_k + tau if tipped and math.isnan(t_uplift) else t_uplift
            t_slide = t_k + tau if slipped and math.isnan(t_slide) else t_slide
            phi, w, xd = 0.0, 0.0, 0.0
            j = substep_of(tau, msub, dt)
        tgt = grid(j + 1, msub, dt)
        if tgt <= tau:
            j += 1
            if j >= msub:
                break
            continue
        a0, slope = reduced_ground(s, g0, g1, dt)
        event, hs, phi, w, x, xd, theta_max = _sl_step(
            mode, s, sig, fric, jam, phi, w, x, xd, tau, tgt, a0, slope, q, theta_max
        )
        if mode == SLIDE_ROCK and not fric:
            t_lift += hs
        if abs(x) > x_max:
            x_max = abs(x)
        if not event:
            tau = tgt
            j += 1
            if j >= msub:
                break
            continue
        tau = tau + hs
        n_ev += 1
        if n_ev > MAX_EVENTS_PER_SAMPLE:
            guard += 1
            break
        if HALF_PI - phi < 0.0 and mode != SLIDE:
            mode, t_over, theta_max = OVERTURNED, t_k + tau, HALF_PI
            continue
        mode, s, sig, fric, jam, phi, w, xd, n_imp, dj, slipped = _sl_event(
            mode, s, sig, fric, jam, phi, w, xd, tau, t_k, dt, g0, g1, a0 + slope * tau, piv, q, impacts, n_imp
        )
        n_jam += dj
        t_slide = t_k + tau if slipped and math.isnan(t_slide) else t_slide
    block = (mode, s, sig, fric, jam, phi, w, x, xd)
    return block, (theta_max, x_max, t_over, t_uplift, t_slide, t_lift, n_imp, n_jam, guard)


@njit(cache=True, nogil=True)
def run_sliding(acc_g, dt, msub, q, theta0, theta_dot0, rest_tol, record, th_out, thd_out, x_out, reg_out, impacts):
    """Simulate rocking with Coulomb friction at the pivot (regimes rest, slide, rock, slide-rock).

    Parameters
    ----------
    acc_g : float64[:]
        Ground acceleration in units of g [-].
    dt : float
        Sample step [s].
    msub : int
        RK4 substeps per sample.
    q : float64[:]
        Constants (layout ``S_*``).
    theta0, theta_dot0 : float
        Initial rotation and angular velocity [rad, rad/s] (pivot not slipping).
    rest_tol : float
        Rest rule of :mod:`housner.model` [-].
    record : bool
        Write histories (theta, theta', slip x, regime) on the sample grid.
    impacts : float64[:]
        Buffer for impact times [s].

    Returns
    -------
    (theta_max, overturned, t_over, t_uplift, n_impacts, guard, x_max, t_slide, n_jam, t_lift)
    where x_max is the largest |x| [m], t_slide the first slip time [s], n_jam
    the number of Painleve jams, and t_lift the time spent with a negative
    normal-force demand [s].
    """
    piv = pivot_constants(q[S_ALPHA_P], q[S_ALPHA_N], q[S_P2_P], q[S_P2_N], rest_tol)
    block, tally = _sl_start(theta0, theta_dot0, acc_g[0], q)
    if record:
        th_out[0] = theta0
        thd_out[0] = theta_dot0
        x_out[0] = 0.0
        reg_out[0] = block[0]

    for k in range(acc_g.size - 1):
        if block[0] == OVERTURNED and not record:  # block[0]: the regime
            break
        block, tally = _sl_sample(k * dt, acc_g[k], acc_g[k + 1], dt, msub, block, tally, piv, q, impacts)
        if record:
            mode, s, _sig, _fric, _jam, phi, w, x, _xd = block
            x_out[k + 1] = x
            reg_out[k + 1] = mode
            store(th_out, thd_out, k + 1, s, phi, w, mode == ROCK or mode == SLIDE_ROCK, mode == OVERTURNED)
    theta_max, x_max, t_over, t_uplift, t_slide, t_lift, n_imp, n_jam, guard = tally
    return theta_max, block[0] == OVERTURNED, t_over, t_uplift, n_imp, guard, x_max, t_slide, n_jam, t_lift
