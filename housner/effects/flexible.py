"""The flexible foundation: a block on two compression-only corner spring-dashpots (effect, driver, kernel)."""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass

import numpy as np
from numba import njit

from housner._kernel_parts import EPS, HALF_PI, grid, rk4_update, secant
from housner.effects._mechanics import MAX_EVENTS_PER_SAMPLE, corner_geometry, illinois, pos_int_or_none, run_kernel
from housner.effects.registry import STAGE_MECHANICS, Effect, param, register_effect
from housner.model import PH_MAX
from housner.motion import GroundMotion
from housner.response import Response
from housner.rocking_params import RockingParams
from housner.specimen import Specimen
from housner.units import G

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
    th_h, thd_h = rk4_update(th, thd, h, thd, v2t, v3t, v4t, k1t, k2t, k3t, k4t)
    w_h, wd_h = rk4_update(w, wd, h, wd, v2w, v3w, v4w, k1w, k2w, k3w, k4w)
    return th_h, thd_h, w_h, wd_h


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
        h = secant(hl, vl, hr, vr)
        z0, z1, z2, z3 = _ff_rk4(th, thd, w, wd, tau, h, a0, slope, s, ap, an, q)
        if kind == 0:
            v = _ff_margin(z0, z1, z2, z3, s, ap, an, q)
        else:
            v = s * z1
        if v < 0.0:
            y0, y1, y2, y3 = z0, z1, z2, z3
        hl, vl, hr, vr, side = illinois(h, v, hl, vl, hr, vr, side)
    return hr, y0, y1, y2, y3


@njit(cache=True, inline="always")
def _ff_step(th, thd, w, wd, tau, tend, a0, slope, s, ap, an, q, theta_max):
    """The RK4 step from local time tau to tend [s], cut at the first change of the contact mode.

    Returns (event, h, theta, theta', w, w', theta_max): whether the step was
    cut, its length h [s], the state at its end, and theta_max raised by a
    peak of |theta| inside the step.
    """
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
        _h, p0, _p1, _p2, _p3 = _ff_bracket(1, th, thd, w, wd, tau, 0.0, s * thd, hs, s * y1, a0, slope, s, ap, an, q)
        if abs(p0) > theta_max:
            theta_max = abs(p0)
    if abs(y0) > theta_max:
        theta_max = abs(y0)
    return event, hs, y0, y1, y2, y3, theta_max


@njit(cache=True)
def _ff_contacts(th, thd, w, wd, ap, an, q):
    """The contacts after a mode change: a corner whose margin turned negative switches (on <-> off)."""
    gp, gn = _ff_gap(th, thd, w, wd, q)
    if (gp if ap else -gp) < 0.0:
        ap = not ap
    if (gn if an else -gn) < 0.0:
        an = not an
    return ap, an


@njit(cache=True)
def _ff_store(th_out, thd_out, w_out, wd_out, i, th, thd, w, wd):
    """Write sample i of the histories."""
    th_out[i] = th
    thd_out[i] = thd
    w_out[i] = w
    wd_out[i] = wd


@njit(cache=True, inline="always")
def _ff_contact_event(t, th, thd, w, wd, s, ap, an, lifted, t_uplift, t_both, imp_both, n_imp, impacts, durations, q):
    """The block's state after a step of :func:`run_flexible` cut at time ``t`` [s] by an event (not an overturn).

    A crossing of theta = 0 switches the pivot side s and, after a corner had lost contact, is an impact
    (its time stored in ``impacts``, its duration in ``durations`` once a corner lets go again); the
    contacts (ap, an) are updated, and the first loss of double contact is the uplift.

    Returns (s, ap, an, lifted, t_uplift, t_both, imp_both, n_imp): t_both [s] the time both corners began
    to push, imp_both the impact whose double contact lasts (-1 when none).
    """
    cap = impacts.size
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
    ap, an = _ff_contacts(th, thd, w, wd, ap, an, q)
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
    return s, ap, an, lifted, t_uplift, t_both, imp_both, n_imp


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
    th, thd, w, wd = theta0, theta_dot0, w0, w_dot0
    s = 1.0 if th > 0.0 or (th == 0.0 and thd >= 0.0) else -1.0
    gp, gn = _ff_gap(th, thd, w, wd, q)
    ap, an = gp > 0.0, gn > 0.0
    lifted = not (ap and an)
    t_uplift = 0.0 if lifted else math.nan
    t_both, imp_both, theta_max, w_min = 0.0, -1, abs(th), w
    over, t_over, n_imp, guard = False, math.nan, 0, 0
    if record:
        _ff_store(th_out, thd_out, w_out, wd_out, 0, th, thd, w, wd)
    for k in range(acc.size - 1):
        if over:
            if not record:
                break
            _ff_store(th_out, thd_out, w_out, wd_out, k + 1, th, 0.0, w, 0.0)
            continue
        t_k = k * dt
        a0 = acc[k]
        slope = (acc[k + 1] - a0) / dt
        tau, n_ev = 0.0, 0
        for j in range(msub):
            tend = grid(j + 1, msub, dt)
            while tau < tend and not over:
                event, hs, th, thd, w, wd, theta_max = _ff_step(
                    th, thd, w, wd, tau, tend, a0, slope, s, ap, an, q, theta_max
                )
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
                    th, thd = s * HALF_PI, 0.0
                    break
                s, ap, an, lifted, t_uplift, t_both, imp_both, n_imp = _ff_contact_event(
                    t, th, thd, w, wd, s, ap, an, lifted, t_uplift, t_both, imp_both, n_imp, impacts, durations, q
                )
            if over:
                break
        if record:
            _ff_store(th_out, thd_out, w_out, wd_out, k + 1, th, thd, w, wd)
    return theta_max, over, t_over, t_uplift, n_imp, guard, w_min


def simulate_flexible(
    specimen: Specimen,
    motion: GroundMotion,
    params=None,
    *,
    frequency: float,
    damping_ratio: float = 0.5,
    substeps: int | None = None,
    rest_tol: float = 1e-6,
) -> Response:
    """Rocking on a flexible foundation (see :class:`FlexibleFoundation` for the model).

    The solver of that effect: ``run_flexible`` integrates theta and the
    vertical displacement w with RK4 steps cut at every change of contact.

    Parameters
    ----------
    specimen : Specimen
    motion : GroundMotion
        Ground acceleration [m/s^2] and initial rotation theta0 [rad],
        theta_dot0 [rad/s]; the block starts with its weight on the springs.
    params : RockingParams, optional
        alpha and p per corner (asymmetric pivots, frequency parameter) and
        ``damping`` [1/s] are used; r and r_amp_exponent are not (the springs
        replace the impact law). Default: the specimen's. The centroidal
        inertia is I_c = m (g R_s / p_s^2 - R_s^2); where the two corners imply
        different values (p scaled on an asymmetric block) their mean is used
        and ``info['inertia_mismatch']`` gives their relative difference.
    frequency : float
        Vertical natural frequency of the block on its foundation [Hz].
    damping_ratio : float
        Damping ratio of that vertical mode [-].
    substeps : int, optional
        RK4 substeps per sample; default: enough for 0.05 rad of the fastest
        contact mode per step and p h <= 0.01.
    rest_tol : float
        Unused (no rest rule is needed: the springs bring the block to rest).

    Returns
    -------
    Response
        ``info`` adds ``w`` and ``w_dot`` (vertical displacement [m] and
        velocity [m/s] of the base point below the centre of mass, 0 when the
        springs are unloaded, histories on the sample grid), ``w_min`` [m],
        ``impact_durations`` [s] (time both corners push around each impact;
        NaN where the block crossed theta = 0 with at most one corner
        pushing), ``substeps``, ``inertia_mismatch`` and the foundation
        constants ``k`` [N/m] and ``c`` [N s/m] per corner. An impact is a
        crossing of theta = 0 after a corner lost contact (not the small
        rocking of a block that sits on both springs).
    """
    prm = RockingParams.from_specimen(specimen) if params is None else params
    f, zeta = _checked_foundation(frequency, damping_ratio)
    q, mismatch = _foundation_constants(specimen, prm, f, zeta)
    m = pos_int_or_none("substeps", substeps) or _default_substeps(q, zeta, prm.p_max, motion.dt)
    th0, thd0 = motion.theta0, motion.theta_dot0
    w0 = _settled_w(q, th0)
    th, thd, w, wd = (np.empty(motion.n) for _ in range(4))
    acc = np.ascontiguousarray(motion.acc, dtype=np.float64)
    chatter = (
        f"flexible_foundation: contact chattering on motion {motion.name!r} (more than "
        f"{MAX_EVENTS_PER_SAMPLE} contact changes in one sample); raise the damping ratio"
    )
    out, (imp, dur) = run_kernel(run_flexible, (acc, motion.dt, m, q, th0, thd0, w0, 0.0), (th, thd, w, wd), 2, chatter)
    info = {
        "kernel": "flexible_foundation",
        "substeps": m,
        "params": asdict(prm),
        "frequency_hz": f,
        "damping_ratio": zeta,
        "k": float(q[F_KAPPA]) * specimen.mass,
        "c": float(q[F_ETA]) * specimen.mass,
        "w": w,
        "w_dot": wd,
        "w_min": float(out[6]),
        "impact_durations": dur,
        "inertia_mismatch": mismatch,
    }
    return Response.from_kernel(motion.t, th, thd, imp, out, specimen.alpha, info)


def _checked_foundation(frequency, damping_ratio) -> tuple[float, float]:
    """The vertical frequency [Hz] and damping ratio [-] as floats; ValueError naming the one out of range."""
    f = float(frequency)
    zeta = float(damping_ratio)
    if not (math.isfinite(f) and f > 0):
        raise ValueError(f"`frequency` must be positive and finite [Hz], got {frequency!r}")
    if not (math.isfinite(zeta) and zeta >= 0):
        raise ValueError(f"`damping_ratio` must be >= 0, got {damping_ratio!r}")
    return f, zeta


def _foundation_constants(specimen: Specimen, prm: RockingParams, f: float, zeta: float) -> tuple[np.ndarray, float]:
    """The constants vector of :func:`run_flexible` (layout ``F_*``) for a foundation of vertical frequency ``f``
    [Hz] and damping ratio ``zeta`` [-], and the relative difference of the two corners' centroidal inertias."""
    geo = corner_geometry(specimen, prm)
    bp, _rp, i0p, icp = geo["pos"]
    bn, _rn, i0n, icn = geo["neg"]
    # a rigid block has one centroidal inertia; p scaled on an asymmetric block implies two: take their mean
    ic = 0.5 * (icp + icn)
    omega_v = 2.0 * math.pi * f
    kappa = 0.5 * omega_v**2  # k/m per corner: 2 k / m = omega_v^2
    eta = zeta * omega_v  # c/m per corner: 2 c / m = 2 zeta omega_v
    q = np.zeros(N_FLEX)
    q[F_G], q[F_H], q[F_BP], q[F_BN] = G, specimen.H, bp, bn
    q[F_IC], q[F_I0P], q[F_I0N] = ic, i0p, i0n
    q[F_C], q[F_KAPPA], q[F_ETA] = prm.damping, kappa, eta
    return q, abs(icp - icn) / ic


def _default_substeps(q: np.ndarray, zeta: float, p_max: float, dt: float) -> int:
    """RK4 substeps per sample of ``dt`` [s]: :data:`_FLEX_STEP` of the fastest contact mode and p h <= PH_MAX."""
    # fastest mode: vertical (2 kappa) or one corner against the rotational inertia
    bmax, kappa, ic = max(float(q[F_BP]), float(q[F_BN])), float(q[F_KAPPA]), float(q[F_IC])
    lam = math.sqrt(kappa * max(2.0, 1.0 + bmax * bmax / ic)) * (zeta + math.sqrt(1.0 + zeta * zeta))
    return max(math.ceil(dt * lam / _FLEX_STEP - 1e-9), math.ceil(p_max * dt / PH_MAX - 1e-9), 1)


def _settled_w(q: np.ndarray, th0: float) -> float:
    """The vertical displacement w [m] of equilibrium at rotation ``th0`` [rad]: both corners pushing, or the
    lower one alone."""
    bp, bn, kappa = float(q[F_BP]), float(q[F_BN]), float(q[F_KAPPA])
    sn = math.sin(th0)
    w0 = 0.5 * ((bp - bn) * sn - G / kappa)
    if bp * sn - w0 <= 0.0 or -w0 - bn * sn <= 0.0:
        w0 = (bp * sn if th0 > 0 else -bn * sn) - G / kappa
    return w0


#: Flexible foundation: RK4 step as a fraction of the fastest contact period / (2 pi) [rad].
_FLEX_STEP = 0.05


@register_effect
@dataclass(frozen=True)
class FlexibleFoundation(Effect):
    """The block on two compression-only spring-dashpots at its corners (a two-spring foundation).

    Degrees of freedom: the rotation theta and the vertical displacement w of
    the base point below the centre of mass (2 DOF). Each corner pushes with
    F = max(0, k d + c d') while its penetration d = -z_corner > 0 and never
    pulls; z_+- = w -+ b+- sin(theta) with b+- the horizontal distances of the
    corners from the centre of mass. Horizontally the corner on the side of
    sgn(theta) is held to the ground (no sliding): it is the pivot of Housner's
    model, and the switch at theta = 0 is continuous in position and velocity
    (at theta = 0 both corners move vertically only). The constraint holds
    also while that corner is off its spring (the model has no sliding and no
    horizontal flight; a stiff, damped foundation barely lets the block hop). Lagrange's equations
    with u_g(t) the ground motion, a = d x_G / d theta = s b_s sin(theta) +
    H cos(theta)::

        (I_c + m a^2) theta'' = -m a (ug'' + a' theta'^2) + H sin(theta) (F+ + F-)
                                - cos(theta) (b+ F+ - b- F-) - c_rot I0 theta'
        m w'' = -m g + F+ + F- + m H (sin(theta) theta'' + cos(theta) theta'^2)

    Consequences: the block tilts before it lifts off (small-angle static tilt
    under a constant lateral acceleration a below uplift,
    theta = m a H / (2 k B^2 - m g H)); an impact takes time (both corners
    push for a while as the block rolls from one corner onto the other); with
    c = 0 the total energy (kinetic + gravity + springs) is conserved, with
    c > 0 it only decreases; there is no coefficient of restitution (the
    springs and dashpots replace the impact law, so ``restitution`` and
    ``amplitude_dependent_restitution`` cannot be combined with it). As k
    grows, the block approaches Housner's rigid block (energy loss per impact
    set by the damping: with ``damping_ratio`` 0.5, the default, a 1000 Hz
    foundation under the seed specimen loses Housner's r = 0.9465 per impact
    to 4 digits). The seed reports 25 Hz as the measured eigenfrequency of
    its specimen, an order of magnitude to start a fit from.

    Parameters
    ----------
    frequency : float
        Vertical natural frequency of the block on the two springs,
        sqrt(2 k / m) / (2 pi) [Hz], in [2, 2000]; neutral inf (rigid ground,
        Housner's model). k = m (2 pi f)^2 / 2 per corner.
    damping_ratio : float
        Damping ratio of that vertical mode [-], in [0, 2]; c = zeta m 2 pi f
        per corner. Default 0.5.

    References
    ----------
    Psycharis, I. N., Jennings, P. C. (1983). Rocking of slender rigid bodies
    allowed to uplift. Earthquake Engineering & Structural Dynamics 11(1), 57-76.
    Chopra, A. K., Yim, S. C.-S. (1985). Simplified earthquake analysis of
    structures with foundation uplift. Journal of Structural Engineering
    111(4), 906-930.
    """

    name = "flexible_foundation"
    stage = STAGE_MECHANICS
    changes_mechanics = True
    #: A step of its kernel costs about 6.5 of the sliding kernel's (2 cores, 2026-11-29: 6e8 steps in 101 s against
    #: sliding's 3.9e8 in 10.3 s, both beside the same other job): two coupled coordinates and the springs' contact.
    solver_step_cost = 6.5
    conflicts = frozenset({"restitution", "amplitude_dependent_restitution"})
    conflict_reason = "its springs and dashpots replace the instantaneous impact law (there is no r to set)"
    frequency: float = param("Hz", (2.0, 2000.0), neutral=math.inf, doc="vertical natural frequency on the foundation")
    damping_ratio: float = param("-", (0.0, 2.0), neutral=0.0, default=0.5, doc="damping ratio of the vertical mode")

    @classmethod
    def from_stiffness(cls, specimen: Specimen, k: float, c: float = 0.0) -> FlexibleFoundation:
        """The foundation with stiffness ``k`` [N/m] and dashpot ``c`` [N s/m] per corner."""
        if not (math.isfinite(k) and k > 0):
            raise ValueError(f"`k` must be positive [N/m], got {k!r}")
        if not (math.isfinite(c) and c >= 0):
            raise ValueError(f"`c` must be >= 0 [N s/m], got {c!r}")
        omega = math.sqrt(2.0 * k / specimen.mass)
        return cls(frequency=omega / (2.0 * math.pi), damping_ratio=c / (specimen.mass * omega))

    def solver(self):
        if math.isinf(self.frequency):
            return None
        return functools.partial(simulate_flexible, frequency=self.frequency, damping_ratio=self.damping_ratio)
