"""Sliding: a block on rigid ground with Coulomb friction; rest, slide, rock, slide-rock (effect, driver, kernel)."""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass

import numpy as np
from numba import njit

from housner._kernel import _uplift_side
from housner.effects._mechanics import EPS, HALF_PI, MAX_EVENTS_PER_SAMPLE, _corner_geometry, _grid, _pos_int_or_none
from housner.effects.registry import STAGE_MECHANICS, Effect, ParamSpec, register_effect
from housner.errors import EngineError
from housner.motion import GroundMotion
from housner.response import Response
from housner.specimen import Specimen
from housner.units import G

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


def simulate_sliding(
    specimen: Specimen,
    motion: GroundMotion,
    params=None,
    *,
    mu: float,
    substeps: int | None = None,
    rest_tol: float = 1e-6,
) -> Response:
    """Rocking with Coulomb friction at the base (see :class:`Sliding` for the model).

    Parameters
    ----------
    specimen : Specimen
    motion : GroundMotion
        Ground acceleration [m/s^2] and initial state theta0 [rad],
        theta_dot0 [rad/s] (the base is not slipping at t = 0).
    params : RockingParams, optional
        Every field is used except the per-side ratios ``r_pos`` and
        ``r_neg`` (the sliding kernel's impacts use ``r``, the geometric mean
        of the two for :class:`AsymmetricPivots`); default: the specimen's.
    mu : float
        Friction coefficient [-].
    substeps : int, optional
        RK4 substeps per sample; default as :func:`housner.model.simulate` (p h <= 0.01).
    rest_tol : float
        Rest rule of :func:`housner.model.simulate` [-].

    Returns
    -------
    Response
        ``info`` adds ``slip`` (horizontal displacement of the base corner in
        contact relative to the ground [m], history), ``regime`` (int8
        history: 0 rest, 1 slide, 2 rock, 3 slide-rock, 4 overturned),
        ``slip_max`` [m], ``slide_time`` (first slip [s], NaN if none),
        ``painleve_jams`` and ``lift_off_time`` [s] (see :class:`Sliding`).
    """
    from housner.model import RockingParams, default_substeps

    prm = RockingParams.from_specimen(specimen) if params is None else params
    mu = float(mu)
    if not (math.isfinite(mu) and mu > 0):
        raise ValueError(f"`mu` must be positive and finite, got {mu!r}")
    if not (isinstance(rest_tol, (int, float)) and 0.0 < rest_tol < 1.0):
        raise ValueError(f"`rest_tol` must lie in (0, 1), got {rest_tol!r}")
    geo = _corner_geometry(specimen, prm)
    q = np.zeros(N_SLIDE)
    q[S_G], q[S_MU], q[S_C], q[S_R], q[S_REXP] = G, mu, prm.damping, prm.r, prm.r_amp_exponent
    for side, (ia, ir, ii, ip) in (
        ("pos", (S_ALPHA_P, S_R_P, S_I0_P, S_P2_P)),
        ("neg", (S_ALPHA_N, S_R_N, S_I0_N, S_P2_N)),
    ):
        _b, rr, i0, _ic = geo[side]
        q[ia] = getattr(prm, f"alpha_{side}")
        q[ir] = rr
        q[ii] = i0
        q[ip] = getattr(prm, f"p_{side}") ** 2
    m = _pos_int_or_none("substeps", substeps)
    if m is None:
        m = default_substeps(prm.p_max, motion.dt)
    n = motion.n
    th, thd, x = np.empty(n), np.empty(n), np.empty(n)
    reg = np.empty(n, dtype=np.int8)
    cap = max(64, n)
    imp = np.empty(cap)
    acc_g = np.ascontiguousarray(motion.acc, dtype=np.float64) / G
    args = (acc_g, motion.dt, m, q, motion.theta0, motion.theta_dot0, float(rest_tol))
    out = run_sliding(*args, True, th, thd, x, reg, imp)
    theta_max, over, t_over, t_up, n_imp, guard, x_max, t_slide, n_jam, t_lift = out
    if guard:
        raise EngineError(
            f"sliding: more than {MAX_EVENTS_PER_SAMPLE} regime changes in one sample on motion {motion.name!r}"
        )
    if n_imp > cap:
        imp = np.empty(n_imp)
        run_sliding(*args, False, th[:0], thd[:0], x[:0], reg[:0], imp)
    info = {
        "kernel": "sliding",
        "substeps": m,
        "rest_tol": rest_tol,
        "params": asdict(prm),
        "mu": mu,
        "slip": x,
        "regime": reg,
        "slip_max": float(x_max),
        "slide_time": float(t_slide),
        "painleve_jams": int(n_jam),
        "lift_off_time": float(t_lift),
    }
    return Response(
        t=motion.t,
        theta=th,
        theta_dot=thd,
        impact_times=imp[:n_imp].copy(),
        theta_max=math.pi / 2 if over else float(theta_max),
        alpha=specimen.alpha,
        overturned=bool(over),
        overturn_time=float(t_over),
        uplift_time=float(t_up),
        engine="housner",
        info=info,
    )


@register_effect
@dataclass(frozen=True)
class Sliding(Effect):
    """Rocking with Coulomb friction mu at the base: rest, slide, rock and slide-rock.

    Rigid block, rigid ground; degrees of freedom theta and the horizontal
    slip x of the base corner in contact (the pivot stays on the ground, as in
    Housner's model). Friction F <= mu N, N the normal force. Regimes:

    * rest: the block moves with the ground while |ug''| <= mu g and it does
      not uplift (ug'' within [-g tan(alpha+), g tan(alpha-)]);
    * slide (theta = 0): m x'' = -m ug'' - mu m g sgn(x'); it stops when x'
      returns to zero and |ug''| <= mu g;
    * rock (x' = 0): Housner's equation; the pivot holds while the friction
      demand F = m (ug'' + zeta theta'' - xi theta'^2) stays within mu N,
      N = m (g - xi theta'' - zeta theta'^2), where (xi, zeta) = position of the
      centre of mass relative to the pivot;
    * slide-rock: both; with F = -mu N sgn(x') the moment balance about the
      pivot gives (I_c + m xi^2 + mu sgn(x') m zeta xi) theta'' =
      m (mu sgn(x') zeta + xi)(g - zeta theta'^2) - c I0 theta'. When this
      coefficient is not positive the Coulomb problem has no consistent slip
      (Painleve's paradox): the slip is stopped (a tangential jam, counted in
      ``info['painleve_jams']``). When the normal-force demand turns negative
      (the block would jump) friction vanishes and the pivot is kept on the
      ground (time counted in ``info['lift_off_time']``).

    Impacts follow Housner's law (theta' times sqrt(r), with every
    restitution effect) and keep the slip velocity: with x' unchanged,
    angular momentum about the landing corner is conserved exactly as on a
    fixed base, and the impulse lies inside the friction cone whenever
    mu >= tan(alpha) (it needs (1 - sqrt r) / ((1 + sqrt r) tan(alpha)) < tan(alpha)).

    Start of motion from rest under horizontal ground acceleration (Shenton
    1996): the block slides if mu < tan(alpha) and |ug''| > mu g, and then
    never rocks (friction caps the inertia force the base can transmit at
    mu m g < m g tan(alpha)); it rocks if mu > tan(alpha) and |ug''| > g tan(alpha),
    and slides while rocking when the friction demand exceeds mu N.

    Parameters
    ----------
    mu : float
        Coulomb friction coefficient at the base [-], in [0.01, 2]; neutral inf
        (no sliding: Housner's model).

    References
    ----------
    Shenton, H. W., Jones, N. P. (1991). Base excitation of rigid bodies. I:
    Formulation. Journal of Engineering Mechanics 117(10), 2286-2306.
    Shenton, H. W. (1996). Criteria for initiation of slide, rock, and
    slide-rock rigid-body modes. Journal of Engineering Mechanics 122(7), 690-693.
    Zhang, J., Makris, N. (2001). Rocking response of free-standing blocks
    under cycloidal pulses. Journal of Engineering Mechanics 127(5), 473-483.
    Genot, F., Brogliato, B. (1999). New results on Painleve paradoxes.
    European Journal of Mechanics A/Solids 18(4), 653-677.
    """

    name = "sliding"
    params = {"mu": ParamSpec("-", (0.01, 2.0), math.inf, None, "Coulomb friction coefficient at the base")}
    stage = STAGE_MECHANICS
    changes_mechanics = True
    mu: float

    def solver(self):
        if math.isinf(self.mu):
            return None
        return functools.partial(simulate_sliding, mu=self.mu)
