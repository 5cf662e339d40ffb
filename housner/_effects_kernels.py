"""Compiled equations of motion for the effects that change the mechanics (private).

Two hybrid (piecewise-smooth) systems, both integrated with classic RK4 on
steps aligned to the motion's samples (ground acceleration linear inside a
sample interval). Each has a discrete *mode* (pivot side, contacts, slip
direction); within a step the mode is frozen, so the right-hand side is
smooth and RK4 keeps its order. A step whose end state violates the mode
(a *margin* turns negative) is cut at the first violation, found by
bracketing (Illinois false position with bisection safeguard) on the length
of one RK4 step from the start of the step, to machine precision; the mode
is then updated and the step resumed. See :mod:`housner.effects` for the
physics and the public entry points.

* ``run_flexible``: a block on two compression-only spring-dashpots at its
  corners (vertical displacement w of the base point below the centre of
  mass, and rotation theta).
* ``run_sliding``: a block on rigid ground with Coulomb friction (pivot slip
  x and rotation theta), regimes rest, slide, rock and slide-rock.

Units: SI, angles [rad]; ``run_sliding`` takes the ground acceleration in
units of g [-] like :mod:`housner._kernel`, ``run_flexible`` in m/s^2.
"""

from __future__ import annotations

import math

from numba import njit

from housner._kernel import _uplift_side

HALF_PI = 0.5 * math.pi
EPS = 2.220446049250313e-16

#: Most mode changes allowed in one sample interval before the kernel gives up
#: (chattering); the Python side turns it into an EngineError.
MAX_EVENTS_PER_SAMPLE = 20_000

# ----------------------------------------------------------------------
# flexible foundation
#: Layout of the constants vector of ``run_flexible`` (per unit mass).
#: g [m/s^2], H [m] (pivot line to centre of mass), b_pos, b_neg [m] (horizontal
#: distance from the centre of mass to the +x and -x corner), i_c [m^2]
#: (centroidal inertia / m), i0_pos, i0_neg [m^2] (inertia about each corner / m),
#: c [1/s] (rotational damping rate), kappa [1/s^2] (k/m per corner), eta [1/s]
#: (dashpot c/m per corner).
F_G, F_H, F_BP, F_BN, F_IC, F_I0P, F_I0N, F_C, F_KAPPA, F_ETA = range(10)
N_FLEX = 10


@njit(cache=True)
def _grid(j, m, dt):
    """Local time of substep boundary j of m [s] (exactly dt at j = m)."""
    if j >= m:
        return dt
    return dt * j / m


@njit(cache=True)
def _ff_forces(th, thd, w, wd, ap, an, q):
    """Corner forces per unit mass [m/s^2] of the active contacts (mode frozen: may be < 0)."""
    sn = math.sin(th)
    cs = math.cos(th)
    fp = 0.0
    fn = 0.0
    if ap:
        fp = q[F_KAPPA] * (q[F_BP] * sn - w) + q[F_ETA] * (q[F_BP] * cs * thd - wd)
    if an:
        fn = q[F_KAPPA] * (-w - q[F_BN] * sn) + q[F_ETA] * (-wd - q[F_BN] * cs * thd)
    return fp, fn


@njit(cache=True)
def _ff_acc(th, thd, w, wd, ag, s, ap, an, q):
    """(theta'', w'') [rad/s^2, m/s^2] with the horizontal constraint at the corner of side s."""
    sn = math.sin(th)
    cs = math.cos(th)
    hh = q[F_H]
    if s > 0:
        sb = q[F_BP]
        i0s = q[F_I0P]
    else:
        sb = -q[F_BN]
        i0s = q[F_I0N]
    a = sb * sn + hh * cs  # d x_G / d theta
    ath = sb * cs - hh * sn  # d a / d theta
    fp, fn = _ff_forces(th, thd, w, wd, ap, an, q)
    num = -a * (ag + ath * thd * thd) + hh * sn * (fp + fn) - cs * (q[F_BP] * fp - q[F_BN] * fn) - q[F_C] * i0s * thd
    thdd = num / (q[F_IC] + a * a)
    wdd = -q[F_G] + fp + fn + hh * sn * thdd + hh * cs * thd * thd
    return thdd, wdd


@njit(cache=True)
def _ff_rk4(th, thd, w, wd, tau, h, a0, slope, s, ap, an, q):
    """One RK4 step of length h [s] from local time tau [s]; ground acc a0 + slope * tau [m/s^2]."""
    hh = 0.5 * h
    g_beg = a0 + slope * tau
    g_mid = a0 + slope * (tau + hh)
    g_end = a0 + slope * (tau + h)
    k1t, k1w = _ff_acc(th, thd, w, wd, g_beg, s, ap, an, q)
    v2t = thd + hh * k1t
    v2w = wd + hh * k1w
    k2t, k2w = _ff_acc(th + hh * thd, v2t, w + hh * wd, v2w, g_mid, s, ap, an, q)
    v3t = thd + hh * k2t
    v3w = wd + hh * k2w
    k3t, k3w = _ff_acc(th + hh * v2t, v3t, w + hh * v2w, v3w, g_mid, s, ap, an, q)
    v4t = thd + h * k3t
    v4w = wd + h * k3w
    k4t, k4w = _ff_acc(th + h * v3t, v4t, w + h * v3w, v4w, g_end, s, ap, an, q)
    h6 = h / 6.0
    return (
        th + h6 * (thd + 2.0 * v2t + 2.0 * v3t + v4t),
        thd + h6 * (k1t + 2.0 * k2t + 2.0 * k3t + k4t),
        w + h6 * (wd + 2.0 * v2w + 2.0 * v3w + v4w),
        wd + h6 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w),
    )


@njit(cache=True)
def _ff_gap(th, thd, w, wd, q):
    """Contact functions of the +x and -x corner: > 0 exactly when the corner pushes (compression-only)."""
    sn = math.sin(th)
    cs = math.cos(th)
    dp = q[F_BP] * sn - w
    dn = -w - q[F_BN] * sn
    fp = q[F_KAPPA] * dp + q[F_ETA] * (q[F_BP] * cs * thd - wd)
    fn = q[F_KAPPA] * dn + q[F_ETA] * (-wd - q[F_BN] * cs * thd)
    return min(dp, fp), min(dn, fn)


@njit(cache=True)
def _ff_margin(th, thd, w, wd, s, ap, an, q):
    """Smallest mode margin [mixed units]: negative once the frozen mode is violated."""
    gp, gn = _ff_gap(th, thd, w, wd, q)
    m = s * th
    v = gp if ap else -gp
    if v < m:
        m = v
    v = gn if an else -gn
    if v < m:
        m = v
    v = HALF_PI - abs(th)
    if v < m:
        m = v
    return m


@njit(cache=True)
def _ff_bracket(kind, th, thd, w, wd, tau, hl, vl, hr, vr, a0, slope, s, ap, an, q):
    """First h in (hl, hr] where a function of one RK4 step from tau turns negative.

    kind 0: the mode margin; kind 1: s theta' (a peak of |theta|). vl >= 0 and
    vr < 0 are its values at the bracket ends. Returns (h, state at h) with the
    function negative at h and non-negative just before (to rounding).
    """
    y0, y1, y2, y3 = _ff_rk4(th, thd, w, wd, tau, hr, a0, slope, s, ap, an, q)
    side = 0
    for _ in range(200):
        if hr - hl <= 4.0 * EPS * (tau + hr):
            break
        h = hr - vr * (hr - hl) / (vr - vl)
        if not (hl < h < hr):
            h = 0.5 * (hl + hr)
        z0, z1, z2, z3 = _ff_rk4(th, thd, w, wd, tau, h, a0, slope, s, ap, an, q)
        if kind == 0:
            v = _ff_margin(z0, z1, z2, z3, s, ap, an, q)
        else:
            v = s * z1
        if v < 0.0:
            hr = h
            vr = v
            y0, y1, y2, y3 = z0, z1, z2, z3
            if side == -1:
                vl *= 0.5
            side = -1
        else:
            hl = h
            vl = v
            if side == 1:
                vr *= 0.5
            side = 1
    return hr, y0, y1, y2, y3


@njit(cache=True, nogil=True)
def run_flexible(
    acc, dt, msub, q, theta0, theta_dot0, w0, w_dot0, record, th_out, thd_out, w_out, wd_out, impacts, durations
):
    """Simulate the block on two compression-only spring-dashpots.

    Parameters
    ----------
    acc : float64[:]
        Ground acceleration [m/s^2].
    dt : float
        Sample step [s].
    msub : int
        RK4 substeps per sample.
    q : float64[:]
        Constants (layout ``F_*``).
    theta0, theta_dot0, w0, w_dot0 : float
        Initial state [rad, rad/s, m, m/s].
    record : bool
        Write histories (theta, theta', w, w') on the sample grid.
    impacts, durations : float64[:]
        Buffers: impact times [s] and the duration of the double contact
        around each [s] (NaN when the block crossed theta = 0 off the ground).

    Returns
    -------
    (theta_max, overturned, t_over, t_uplift, n_impacts, guard, w_min)
    """
    n = acc.size
    th = theta0
    thd = theta_dot0
    w = w0
    wd = w_dot0
    if th > 0.0 or (th == 0.0 and thd >= 0.0):
        s = 1.0
    else:
        s = -1.0
    gp, gn = _ff_gap(th, thd, w, wd, q)
    ap = gp > 0.0
    an = gn > 0.0
    lifted = not (ap and an)
    t_uplift = 0.0 if lifted else math.nan
    t_both = 0.0
    imp_both = -1
    theta_max = abs(th)
    w_min = w
    over = False
    t_over = math.nan
    n_imp = 0
    cap = impacts.size
    guard = 0
    if record:
        th_out[0] = th
        thd_out[0] = thd
        w_out[0] = w
        wd_out[0] = wd
    for k in range(n - 1):
        if over:
            if not record:
                break
            th_out[k + 1] = th
            thd_out[k + 1] = 0.0
            w_out[k + 1] = w
            wd_out[k + 1] = 0.0
            continue
        t_k = k * dt
        a0 = acc[k]
        slope = (acc[k + 1] - a0) / dt
        tau = 0.0
        n_ev = 0
        for j in range(msub):
            tend = _grid(j + 1, msub, dt)
            while tau < tend and not over:
                hs = tend - tau
                y0, y1, y2, y3 = _ff_rk4(th, thd, w, wd, tau, hs, a0, slope, s, ap, an, q)
                mr = _ff_margin(y0, y1, y2, y3, s, ap, an, q)
                event = mr < 0.0
                if event:
                    ml = _ff_margin(th, thd, w, wd, s, ap, an, q)
                    if ml < 0.0:
                        ml = 0.0
                    hs, y0, y1, y2, y3 = _ff_bracket(0, th, thd, w, wd, tau, 0.0, ml, hs, mr, a0, slope, s, ap, an, q)
                # a peak of |theta| inside the accepted step
                if s * thd > 0.0 and s * y1 < 0.0:
                    _h, p0, _p1, _p2, _p3 = _ff_bracket(
                        1, th, thd, w, wd, tau, 0.0, s * thd, hs, s * y1, a0, slope, s, ap, an, q
                    )
                    if abs(p0) > theta_max:
                        theta_max = abs(p0)
                th = y0
                thd = y1
                w = y2
                wd = y3
                if abs(th) > theta_max:
                    theta_max = abs(th)
                if w < w_min:
                    w_min = w
                if not event:
                    tau = tend
                    break
                tau = tau + hs
                t = t_k + tau
                n_ev += 1
                if n_ev > MAX_EVENTS_PER_SAMPLE:
                    guard += 1
                    tau = tend
                    break
                if HALF_PI - abs(th) < 0.0:
                    over = True
                    t_over = t
                    theta_max = HALF_PI
                    th = s * HALF_PI
                    thd = 0.0
                    break
                if s * th < 0.0:
                    s = -s
                    if lifted:
                        if n_imp < cap:
                            impacts[n_imp] = t
                            durations[n_imp] = math.nan
                        if ap and an:
                            imp_both = n_imp
                        n_imp += 1
                        lifted = False
                both_before = ap and an
                gp, gn = _ff_gap(th, thd, w, wd, q)
                if (gp if ap else -gp) < 0.0:
                    ap = not ap
                if (gn if an else -gn) < 0.0:
                    an = not an
                if both_before and not (ap and an):
                    lifted = True
                    if math.isnan(t_uplift):
                        t_uplift = t
                    if imp_both >= 0:
                        if imp_both < cap:
                            durations[imp_both] = t - t_both
                        imp_both = -1
                if ap and an and not both_before:
                    t_both = t
            if over:
                break
        if record:
            th_out[k + 1] = th
            thd_out[k + 1] = thd
            w_out[k + 1] = w
            wd_out[k + 1] = wd
    return theta_max, over, t_over, t_uplift, n_imp, guard, w_min


# ----------------------------------------------------------------------
# sliding
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
    h6 = h / 6.0
    return (
        phi + h6 * (w + 2.0 * w2 + 2.0 * w3 + w4),
        w + h6 * (k1 + 2.0 * k2 + 2.0 * k3 + k4),
        x + h6 * (xd + 2.0 * v2 + 2.0 * v3 + v4),
        xd + h6 * (l1 + 2.0 * l2 + 2.0 * l3 + l4),
    )


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
        h = hr - vr * (hr - hl) / (vr - vl)
        if not (hl < h < hr):
            h = 0.5 * (hl + hr)
        z0, z1, z2, z3 = _sl_rk4(mode, s, sig, fric, phi, w, x, xd, tau, h, a0, slope, q)
        if kind == 0:
            v = _sl_margin(mode, s, sig, fric, jam, z0, z1, z3, a0 + slope * (tau + h), q)
        else:
            v = z1
        if v < 0.0:
            hr = h
            vr = v
            y0, y1, y2, y3 = z0, z1, z2, z3
            if side == -1:
                vl *= 0.5
            side = -1
        else:
            hl = h
            vl = v
            if side == 1:
                vr *= 0.5
            side = 1
    return hr, y0, y1, y2, y3


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
    n = acc_g.size
    mu = q[S_MU]
    r = q[S_R]
    r_exp = q[S_REXP]
    tan_p = math.tan(q[S_ALPHA_P])
    tan_n = math.tan(q[S_ALPHA_N])
    xr = q[S_ALPHA_P] * rest_tol
    wrest2_p = 4.0 * q[S_P2_P] * math.sin(q[S_ALPHA_P] - 0.5 * xr) * math.sin(0.5 * xr)
    xr = q[S_ALPHA_N] * rest_tol
    wrest2_n = 4.0 * q[S_P2_N] * math.sin(q[S_ALPHA_N] - 0.5 * xr) * math.sin(0.5 * xr)

    s = 1.0
    sig = 0.0
    fric = True
    jam = False
    phi = 0.0
    w = 0.0
    x = 0.0
    xd = 0.0
    t_uplift = math.nan
    t_slide = math.nan
    if theta0 == 0.0 and theta_dot0 == 0.0:
        mode = REST
    else:
        if theta0 < 0.0 or (theta0 == 0.0 and theta_dot0 < 0.0):
            s = -1.0
        phi = s * theta0
        w = s * theta_dot0
        t_uplift = 0.0
        mode, sig, jam = _sl_rock_or_slip(s, phi, w, s * acc_g[0], q)
        if mode == SLIDE_ROCK:
            t_slide = 0.0
    theta_max = abs(theta0)
    x_max = 0.0
    t_over = math.nan
    n_imp = 0
    n_jam = 0
    t_lift = 0.0
    cap = impacts.size
    guard = 0
    if record:
        th_out[0] = theta0
        thd_out[0] = theta_dot0
        x_out[0] = 0.0
        reg_out[0] = mode

    for k in range(n - 1):
        if mode == OVERTURNED:
            if not record:
                break
            th_out[k + 1] = s * HALF_PI
            thd_out[k + 1] = 0.0
            x_out[k + 1] = x
            reg_out[k + 1] = mode
            continue
        t_k = k * dt
        g0 = acc_g[k]
        g1 = acc_g[k + 1]
        tau = 0.0
        j = 0
        n_ev = 0
        while True:
            if mode == REST:
                tu_p = _uplift_side(g0, g1, tau, dt, -tan_p)
                tu_n = _uplift_side(-g0, -g1, tau, dt, -tan_n)
                ts_p = _uplift_side(g0, g1, tau, dt, -mu)  # slides toward +x
                ts_n = _uplift_side(-g0, -g1, tau, dt, -mu)
                t_tip = min(tu_p, tu_n)
                t_sl = min(ts_p, ts_n)
                if t_tip == math.inf and t_sl == math.inf:
                    break
                tau = min(t_tip, t_sl)
                a_now = g0 + (g1 - g0) * (tau / dt)
                side = 1.0 if a_now < 0.0 else -1.0
                tan_s = tan_p if side > 0.0 else tan_n
                phi = 0.0
                w = 0.0
                xd = 0.0
                if t_sl < t_tip or (t_sl == t_tip and mu < tan_s):
                    mode = SLIDE
                    sig = side
                    if math.isnan(t_slide):
                        t_slide = t_k + tau
                    if mu > tan_s:
                        s = side
                        mode = SLIDE_ROCK
                        fric = True
                        if math.isnan(t_uplift):
                            t_uplift = t_k + tau
                else:
                    s = side
                    if math.isnan(t_uplift):
                        t_uplift = t_k + tau
                    mode, sig, jam = _sl_rock_or_slip(s, 0.0, 0.0, s * a_now, q)
                    if mode == SLIDE_ROCK:
                        fric = True
                        if math.isnan(t_slide):
                            t_slide = t_k + tau
                    n_jam += 1 if jam else 0
                j = int(tau * msub / dt)
                if j > msub - 1:
                    j = msub - 1
            tgt = _grid(j + 1, msub, dt)
            if tgt <= tau:
                j += 1
                if j >= msub:
                    break
                continue
            if s > 0.0:
                a0 = g0
                a1 = g1
            else:
                a0 = -g0
                a1 = -g1
            slope = (a1 - a0) / dt
            hs = tgt - tau
            y0, y1, y2, y3 = _sl_rk4(mode, s, sig, fric, phi, w, x, xd, tau, hs, a0, slope, q)
            mr = _sl_margin(mode, s, sig, fric, jam, y0, y1, y3, a0 + slope * tgt, q)
            event = mr < 0.0
            if event:
                ml = _sl_margin(mode, s, sig, fric, jam, phi, w, xd, a0 + slope * tau, q)
                if ml < 0.0:
                    ml = 0.0
                hs, y0, y1, y2, y3 = _sl_bracket(
                    0, mode, s, sig, fric, jam, phi, w, x, xd, tau, 0.0, ml, hs, mr, a0, slope, q
                )
            if mode != SLIDE and w > 0.0 and y1 < 0.0:
                _h, p0, _p1, _p2, _p3 = _sl_bracket(
                    1, mode, s, sig, fric, jam, phi, w, x, xd, tau, 0.0, w, hs, y1, a0, slope, q
                )
                if p0 > theta_max:
                    theta_max = p0
            if mode == SLIDE_ROCK and not fric:
                t_lift += hs
            phi = y0
            w = y1
            x = y2
            xd = y3
            if mode != SLIDE and phi > theta_max:
                theta_max = phi
            if abs(x) > x_max:
                x_max = abs(x)
            if not event:
                tau = tgt
                j += 1
                if j >= msub:
                    break
                continue
            tau = tau + hs
            t = t_k + tau
            a_now = a0 + slope * tau
            n_ev += 1
            if n_ev > MAX_EVENTS_PER_SAMPLE:
                guard += 1
                break
            if mode == SLIDE:
                # the slip stops
                xd = 0.0
                a_phys = s * a_now
                if abs(a_phys) <= mu:
                    mode = REST
                else:
                    sig = -1.0 if a_phys > 0.0 else 1.0
                    tan_s = tan_p if sig > 0.0 else tan_n
                    if mu > tan_s:
                        s = sig
                        mode = SLIDE_ROCK
                        fric = True
                continue
            if HALF_PI - phi < 0.0:
                mode = OVERTURNED
                t_over = t
                theta_max = HALF_PI
                break
            if phi < 0.0:
                # impact: Housner's law on theta', the slip velocity is kept
                if n_imp < cap:
                    impacts[n_imp] = t
                n_imp += 1
                alpha, _rr, _i0, p2 = _sl_side(q, s)
                v = -w
                r_eff = r
                if r_exp != 0.0 and v > 0.0:
                    r_eff = r * (v / (math.sqrt(p2) * alpha)) ** r_exp
                    if r_eff > 1.0:
                        r_eff = 1.0
                    if r_eff < 0.0:
                        r_eff = 0.0
                w = math.sqrt(r_eff) * v
                phi = 0.0
                s = -s
                wrest2 = wrest2_p if s > 0.0 else wrest2_n
                if w * w < wrest2:
                    w = 0.0
                    if xd == 0.0:
                        mode = REST
                        continue
                    mode = SLIDE
                    sig = 1.0 if xd > 0.0 else -1.0
                    tan_s = tan_p if sig > 0.0 else tan_n
                    if mu > tan_s:
                        s = sig
                        mode = SLIDE_ROCK
                        fric = True
                    continue
                if xd != 0.0:
                    sig = 1.0 if xd > 0.0 else -1.0
                    mode = SLIDE_ROCK
                    fric = True
                    if _sl_painleve(s, sig, phi, q) <= 0.0:
                        xd = 0.0
                        mode = ROCK
                        jam = True
                        n_jam += 1
                else:
                    mode, sig, jam = _sl_rock_or_slip(s, phi, w, s * (g0 + (g1 - g0) * (tau / dt)), q)
                    n_jam += 1 if jam else 0
                continue
            if mode == ROCK:
                if jam:
                    jam = False  # friction suffices again
                    continue
                mode, sig, jam = _sl_rock_or_slip(s, phi, w, a_now, q)
                if mode == SLIDE_ROCK:
                    fric = True
                    if math.isnan(t_slide):
                        t_slide = t
                n_jam += 1 if jam else 0
                continue
            # slide-rock: which margin?
            if sig * xd < 0.0:
                xd = 0.0
                mode, sig, jam = _sl_rock_or_slip(s, phi, w, a_now, q)
                n_jam += 1 if jam else 0
                if mode == SLIDE_ROCK:
                    fric = True
                continue
            if fric and _sl_painleve(s, sig, phi, q) < 0.0:
                xd = 0.0
                mode = ROCK
                jam = True
                n_jam += 1
                continue
            _alpha, rr, _i0, _p2 = _sl_side(q, s)
            fric = q[S_G] - rr * math.cos(_alpha - phi) * w * w > 0.0
        if record:
            x_out[k + 1] = x
            reg_out[k + 1] = mode
            if mode == ROCK or mode == SLIDE_ROCK:
                th_out[k + 1] = s * phi
                thd_out[k + 1] = s * w
            elif mode == OVERTURNED:
                th_out[k + 1] = s * HALF_PI
                thd_out[k + 1] = 0.0
            else:
                th_out[k + 1] = 0.0
                thd_out[k + 1] = 0.0
    return theta_max, mode == OVERTURNED, t_over, t_uplift, n_imp, guard, x_max, t_slide, n_jam, t_lift
