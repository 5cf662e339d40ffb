"""Synthetic measurement campaigns with a known ("hidden") physical effect, for the diagnosis tests.

This is test code, written separately from :mod:`housner.model` and
:mod:`housner.effects` so that the diagnosis is checked against physics it
did not produce itself: its own integrator (fixed-step RK4 on a finer grid
than the suite's, events located by bisection instead of Newton, the pivot
carried in the state, its own rest rule), its own impact law (angular
momentum about the landing corner computed from the corner vectors, not from
the library's closed form), its own ground motions, noise and file writer.

A campaign is written in the measurement format (``campaign.toml`` and
``records/<id>.csv``, see campaign-format.md) for the seed specimen
(Bachmann et al. 2017: 2H = 0.5 m, 2B = 0.075 m, 3.94 kg, p = 4.8883 1/s),
sampled at 500 Hz with 0.8 mrad Gaussian noise on theta (seed section 3.4).

Hidden effects (:data:`HIDDEN`; units SI): ``none``, ``rotational_damping``
(viscous moment -c I0 theta'), ``asymmetric_pivots`` (centre of mass e off
the centre line), ``sensor_offset`` (constant angle offset), ``p_misstated``
(the block rocks with another p than campaign.toml states; its r is the
stated specimen's), ``p_misstated_consistent`` (the same, with the impacts
of the true inertia: two effects at once), ``restitution``
(another constant r), ``amplitude_dependent_restitution`` (r falling with the
impact speed), ``time_lag`` (theta channel late), ``sliding`` (Coulomb friction below
tan(alpha): the block slides under a ground motion and never rocks, Shenton 1996), and
``flexible_foundation`` (a second, compliant-contact integrator: the block as a free 3-DOF rigid
body on compression-only spring-dashpots at its corners with elastic-plastic Coulomb friction,
semi-implicit Euler; the library's model has 2 DOF, a kinematic pivot and no horizontal compliance).

Hidden effects the library does not have (:data:`OUTSIDE`): ``air_drag``
(quadratic moment -cd I0 theta'|theta'|), ``pivot_friction`` (a constant
Coulomb moment at the pivot against the rotation), ``random_restitution``
(every impact keeps a random share of Housner's energy ratio, as if it acted
at a different point of the contact strip each time).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numba import njit
from scipy import signal

G = 9.80665
#: Seed specimen (Bachmann et al. 2017, Table 1 and section 3.1).
HEIGHT, WIDTH, DEPTH, MASS, P_SEED = 0.5, 0.075, 0.4, 3.94, 4.8883
#: 500 Hz, 0.8 mrad (seed section 3.4).
DT = 0.002
NOISE = 0.8e-3
#: Integrator substeps per 2 ms sample: h = 0.25 ms, p h ~ 1.2e-3 (RK4 error ~ (p h)^4 per unit time).
SUBSTEPS = 8
#: Ground motions: band-pass centre [Hz] and peak over g tan(alpha) [-].
FG_RANGE = (2.0, 4.0)
PGA_RANGE = (1.0, 2.0)

#: The hidden effects: the generator's own parameters, and the registry names the diagnosis should give.
HIDDEN: dict[str, tuple[dict, tuple[str, ...]]] = {
    "none": ({}, ()),
    "rotational_damping": ({"c": 0.6}, ("rotational_damping",)),  # c [1/s]
    "asymmetric_pivots": ({"e": 0.3 * WIDTH / 2}, ("asymmetric_pivots",)),  # e [m], 30 % of B
    "sensor_offset": ({"offset": 4.0e-3}, ("sensor_offset",)),  # [rad], 5 noise sigmas
    "p_misstated": ({"p_true": 1.08 * P_SEED}, ("frequency_parameter",)),  # [1/s]
    "restitution": ({"r": 0.88}, ("restitution",)),  # [-]
    "amplitude_dependent_restitution": ({"exponent": 0.6}, ("amplitude_dependent_restitution",)),  # [-]
    "time_lag": ({"tau": 0.02}, ("time_lag",)),  # [s]
    # p mis-stated, and the impacts those of the true inertia (Housner's r 0.938 instead of 0.9465)
    "p_misstated_consistent": ({"p_true": 1.08 * P_SEED, "consistent": True}, ("frequency_parameter", "restitution")),
    # compliant contact (a free 3-DOF body on corner springs, :func:`_integrate_contact`): a 25 Hz
    # foundation (the seed's measured eigenfrequency) with 30 % damping, horizontally stiff (1000 Hz)
    "flexible_foundation": (
        {"contact_freq": 25.0, "contact_zeta": 0.3, "tangential_freq": 1000.0, "mu": 2.0},
        ("flexible_foundation",),
    ),
    # Coulomb friction mu = 0.12 below tan(alpha) = 0.15 on rigid ground: a ground motion makes the block
    # slide, never rock (Shenton 1996); the free vibrations rock as Housner's block (their friction demand
    # stays below 0.091, the impulse ratio of an impact (1 - sqrt r) / ((1 + sqrt r) tan alpha) is 0.091)
    "sliding": ({"mu": 0.12}, ("sliding",)),
}


#: Hidden effects that the effect library does NOT have (the diagnosis must say so): the generator's
#: parameters, and the localisation class (housner.scenarios.diagnosis.comparison.pointers.CLASSES) that should come
# first.
OUTSIDE: dict[str, tuple[dict, str]] = {
    # quadratic air drag: theta'' gains -cd theta' |theta'| [cd in 1/rad]; the loss grows with the speed
    "air_drag": ({"cd": 2.0}, "dissipation"),
    # a constant (Coulomb) friction moment at the pivot, m g R mu_r, against the rotation [mu_r in rad]; it
    # takes a fixed energy per half-cycle, so the energy ratio per impact that the free-vibration
    # localisation measures rises with the amplitude (the loss weighs most at small amplitude), where an
    # impact law that loses more at higher speeds makes it fall: dissipation between impacts
    "pivot_friction": ({"mu_r": 0.003}, "dissipation"),
    # the impact acts at a different point of the contact strip every time: each impact keeps a random
    # share u ~ U(0.85, 1) of what Housner's impact keeps (energy), drawn per impact
    "random_restitution": ({"u_low": 0.85}, "impact"),
}


@dataclass(frozen=True)
class Truth:
    """The physics a synthetic campaign is generated with (SI units)."""

    alpha_pos: float
    alpha_neg: float
    p_pos: float
    p_neg: float
    rho_pn: float  # theta' ratio, impact that leaves the +x corner and lands on the -x corner
    rho_np: float
    c: float = 0.0  # [1/s]
    exponent: float = 0.0  # r_eff = rho^2 (|w| / (p_s alpha_s))^n
    offset: float = 0.0  # [rad]
    tau: float = 0.0  # [s]
    cd: float = 0.0  # quadratic drag [1/rad]
    mu_r: float = 0.0  # Coulomb pivot friction, moment / (m g R) [rad]
    u_low: float = 1.0  # per-impact energy share drawn from U(u_low, 1) [-]
    # Coulomb friction at the base [-]; on rigid ground (contact_freq 0) only 0.1 <= mu < tan(alpha)
    mu: float = math.inf
    # compliant contact (the 3-DOF integrator :func:`_integrate_contact` when contact_freq > 0)
    contact_freq: float = 0.0  # vertical frequency of the block on its two corner springs [Hz]
    contact_zeta: float = 0.0  # damping ratio of that mode [-]
    tangential_freq: float = 0.0  # the same for the corners' horizontal stick springs [Hz]
    both_corners_hold: bool = False  # both corners in contact hold horizontally (else the pivot only)


def truth_for(hidden: str) -> Truth:
    """The generator's physics for a hidden effect name of :data:`HIDDEN`."""
    kw = HIDDEN[hidden][0] if hidden in HIDDEN else OUTSIDE[hidden][0]
    hh, bb = HEIGHT / 2, WIDTH / 2
    R = math.hypot(hh, bb)
    p = kw.get("p_true", P_SEED)
    i0 = MASS * G * R / p**2
    ic = i0 - MASS * R**2
    e = kw.get("e", 0.0)
    b_pos, b_neg = bb - e, bb + e  # horizontal distances centre of mass -> corners
    corners = {+1: np.array([b_pos, 0.0]), -1: np.array([-b_neg, 0.0])}
    com = np.array([0.0, hh])

    def inertia(s):
        d = com - corners[s]
        return ic + MASS * float(d @ d)

    def ratio(s_old):
        # Angular momentum about the landing corner, just before and just after the impact
        # (rotation rate W about the old corner): L = Ic W + m (G - O_new) x v_G, v_G = W z x (G - O_old).
        s_new = -s_old
        r_old = com - corners[s_old]
        v = np.array([-r_old[1], r_old[0]])  # W = 1
        r_new = com - corners[s_new]
        L = ic + MASS * (r_new[0] * v[1] - r_new[1] * v[0])
        return L / inertia(s_new)

    def p_of(s):
        d = com - corners[s]
        return math.sqrt(MASS * G * math.hypot(*d) / inertia(s))

    rho_pn, rho_np = ratio(+1), ratio(-1)
    if "r" in kw:  # another constant r: both impacts lose 1 - r of the energy
        rho_pn = rho_np = math.sqrt(kw["r"])
    if "p_true" in kw and not kw.get("consistent", False):
        # The block rocks with p_true, but its impacts lose what Housner's formula gives for the stated
        # specimen (a block whose r is what it is, e.g. calibrated separately, as in seed Table 1): the
        # mis-stated p is then the only thing wrong. (Housner's r for p_true would be 0.938, not 0.9465.)
        i0_stated = MASS * G * R / P_SEED**2
        rho_pn = rho_np = 1.0 - 2.0 * MASS * bb * bb / i0_stated
    return Truth(
        alpha_pos=math.atan2(b_pos, hh),
        alpha_neg=math.atan2(b_neg, hh),
        p_pos=p_of(+1),
        p_neg=p_of(-1),
        rho_pn=rho_pn,
        rho_np=rho_np,
        c=kw.get("c", 0.0),
        exponent=kw.get("exponent", 0.0),
        offset=kw.get("offset", 0.0),
        tau=kw.get("tau", 0.0),
        cd=kw.get("cd", 0.0),
        mu_r=kw.get("mu_r", 0.0),
        u_low=kw.get("u_low", 1.0),
        contact_freq=kw.get("contact_freq", 0.0),
        contact_zeta=kw.get("contact_zeta", 0.0),
        tangential_freq=kw.get("tangential_freq", 0.0),
        mu=kw.get("mu", math.inf),
    )


# ----------------------------------------------------------------------------
# the integrator
@njit(cache=True)
def _rhs(s, th, w, a, al_p, al_n, p2_p, p2_n, c, cd, mu):
    # Housner's equation on pivot s (s = +1: +x corner), a = ug''/g [-], with viscous (c), quadratic (cd)
    # and Coulomb (mu, a moment m g R mu against the rotation) losses
    extra = -c * w - cd * w * abs(w)
    if s > 0:
        d = al_p - th
        return -p2_p * (math.sin(d) + a * math.cos(d) + mu * np.sign(w)) + extra
    d = -al_n - th
    return -p2_n * (math.sin(d) + a * math.cos(d) + mu * np.sign(w)) + extra


@njit(cache=True)
def _step(s, th, w, a0, a1, h, al_p, al_n, p2_p, p2_n, c, cd, mu):
    # one RK4 step of length h with a(t) linear from a0 (t = 0) to a1 (t = h)
    am = 0.5 * (a0 + a1)
    k1t, k1w = w, _rhs(s, th, w, a0, al_p, al_n, p2_p, p2_n, c, cd, mu)
    k2t, k2w = w + 0.5 * h * k1w, _rhs(s, th + 0.5 * h * k1t, w + 0.5 * h * k1w, am, al_p, al_n, p2_p, p2_n, c, cd, mu)
    k3t, k3w = w + 0.5 * h * k2w, _rhs(s, th + 0.5 * h * k2t, w + 0.5 * h * k2w, am, al_p, al_n, p2_p, p2_n, c, cd, mu)
    k4t, k4w = w + h * k3w, _rhs(s, th + h * k3t, w + h * k3w, a1, al_p, al_n, p2_p, p2_n, c, cd, mu)
    return th + h / 6 * (k1t + 2 * k2t + 2 * k3t + k4t), w + h / 6 * (k1w + 2 * k2w + 2 * k3w + k4w)


@njit(cache=True)
def _integrate(acc_g, dt, m, th0, w0, al_p, al_n, p_p, p_n, rho_pn, rho_np, c, expo, cd, mu, share, out):
    """theta at the samples of acc_g (units of g, linear in between); returns 1 if it overturned."""
    n = acc_g.size
    h = dt / m
    p2_p, p2_n = p_p * p_p, p_n * p_n
    rocking = th0 != 0.0 or w0 != 0.0
    s = 1 if (th0 > 0.0 or (th0 == 0.0 and w0 > 0.0)) else -1
    th, w = th0, w0
    n_imp = 0
    out[0] = th
    for k in range(n - 1):
        for j in range(m):
            t0 = j * h
            a0 = acc_g[k] + (acc_g[k + 1] - acc_g[k]) * (t0 / dt)
            a1 = acc_g[k] + (acc_g[k + 1] - acc_g[k]) * ((t0 + h) / dt)
            left = h
            while left > 0.0:
                if not rocking:
                    # at rest: lift off where the linear ground acceleration passes a threshold
                    lo_p, lo_n = -math.tan(al_p), math.tan(al_n)
                    t_up = -1.0
                    a_beg = a0 + (a1 - a0) * ((h - left) / h)
                    if a_beg < lo_p:
                        t_up, s = 0.0, 1
                    elif a_beg > lo_n:
                        t_up, s = 0.0, -1
                    elif a1 < lo_p:
                        t_up, s = left * (lo_p - a_beg) / (a1 - a_beg), 1
                    elif a1 > lo_n:
                        t_up, s = left * (lo_n - a_beg) / (a1 - a_beg), -1
                    if t_up < 0.0:
                        break
                    left -= t_up
                    rocking = True
                    th, w = 0.0, 0.0
                    continue
                a_beg = a0 + (a1 - a0) * ((h - left) / h)
                tn, wn = _step(s, th, w, a_beg, a1, left, al_p, al_n, p2_p, p2_n, c, cd, mu)
                if abs(tn) >= 0.5 * math.pi:
                    th = math.copysign(0.5 * math.pi, tn)
                    for kk in range(k + 1, n):
                        out[kk] = th
                    return 1
                if tn * s >= 0.0:
                    th, w = tn, wn
                    break
                # theta crosses zero inside the step: bisection on the step length
                lo, hi = 0.0, left
                for _ in range(80):
                    mid = 0.5 * (lo + hi)
                    am = a_beg + (a1 - a_beg) * (mid / left)
                    tm, _wm = _step(s, th, w, a_beg, am, mid, al_p, al_n, p2_p, p2_n, c, cd, mu)
                    if tm * s > 0.0:
                        lo = mid
                    else:
                        hi = mid
                am = a_beg + (a1 - a_beg) * (hi / left)
                tm, wm = _step(s, th, w, a_beg, am, hi, al_p, al_n, p2_p, p2_n, c, cd, mu)
                left -= hi
                # impact: the new pivot is the other corner
                rho = rho_pn if s > 0 else rho_np
                if expo != 0.0:
                    ref = (p_p * al_p) if s > 0 else (p_n * al_n)
                    r_eff = rho * rho * (abs(wm) / ref) ** expo
                    if r_eff > 1.0:
                        r_eff = 1.0
                    rho = math.sqrt(r_eff)
                w = wm * rho * math.sqrt(share[n_imp % share.size])
                n_imp += 1
                th = 0.0
                s = -s
                # rest: the excursion the new speed could reach is below 1e-7 rad
                if w * w < 2.0 * (p2_p if s > 0 else p2_n) * 1e-7 * (al_p if s > 0 else al_n):
                    rocking = False
                    w = 0.0
        out[k + 1] = th
    return 0


def simulate_truth(
    truth: Truth, acc: np.ndarray, *, theta0: float = 0.0, rng: np.random.Generator | None = None, dt: float = DT
) -> tuple[np.ndarray, bool]:
    """theta [rad] at the samples of ``acc`` [m/s^2] (block released at rest from theta0), overturned.

    ``dt`` is the sample step [s] (default 500 Hz); the integrator's step stays near DT / SUBSTEPS
    (0.25 ms) whatever it is. ``rng`` draws the per-impact energy shares of ``truth.u_low`` < 1
    (required then). A truth with compliant contact (``contact_freq`` > 0) runs
    :func:`simulate_contact` instead.
    """
    if truth.contact_freq > 0.0:
        return simulate_contact(truth, acc, theta0=theta0, dt=dt)
    if truth.mu < math.inf:
        # rigid ground with friction: only mu below tan(alpha) (slide, never rock, from rest) is modelled
        # here; the free vibrations then need mu above their friction demand (0.091 for the seed specimen)
        if not 0.1 <= truth.mu < min(math.tan(truth.alpha_pos), math.tan(truth.alpha_neg)):
            raise NotImplementedError("the rigid generator models sliding only for 0.1 <= mu < tan(alpha)")
        if theta0 == 0.0:
            return np.zeros(acc.size), False  # the base slides with friction mu m g < m g tan(alpha): no uplift
    out = np.empty(acc.size)
    share = np.ones(1) if truth.u_low >= 1.0 else rng.uniform(truth.u_low, 1.0, 4096)
    over = _integrate(
        np.ascontiguousarray(acc, dtype=np.float64) / G,
        dt,
        _substeps(dt),
        float(theta0),
        0.0,
        truth.alpha_pos,
        truth.alpha_neg,
        truth.p_pos,
        truth.p_neg,
        truth.rho_pn,
        truth.rho_np,
        truth.c,
        truth.exponent,
        truth.cd,
        truth.mu_r,
        share,
        out,
    )
    return out, bool(over)


def _substeps(dt: float) -> int:
    """Integrator substeps per sample of ``dt`` [s]: SUBSTEPS at DT, a step near DT / SUBSTEPS otherwise."""
    return SUBSTEPS if dt == DT else max(1, int(math.ceil(SUBSTEPS * dt / DT - 1e-9)))


# ----------------------------------------------------------------------------
# the compliant-contact integrator (flexible foundation, sliding)
@njit(cache=True)
def _integrate_contact(acc, dt, m, th0, mass, ic, hh, b_pos, b_neg, kn, cn, kt, ct, mu, both, out):
    """A free planar rigid body (x, y of the centre of mass relative to the table, theta) on two
    compliant corner contacts, theta at the samples of ``acc`` [m/s^2] (linear in between); returns
    1 if it overturned.

    Each corner in contact (penetration d > 0) feels a compression-only normal force
    N = max(0, kn d - cn vy) and a horizontal stick spring-dashpot anchored where it touched down,
    F = -kt (x - x_anchor) - ct vx, capped at mu N (Coulomb: beyond it the anchor follows the corner,
    elastic-plastic friction). With ``both`` False only the corner on the side of theta (the pivot)
    holds horizontally, the other one is frictionless: the idealisation of the library's flexible
    foundation (with both corners holding, a 0.8 alpha free vibration on a 25 Hz, 30 % foundation
    departs from it by 0.024 alpha rms over 12 s, 4.4 noise sigmas: friction at the landing corner
    during the roll-over, which the library's model leaves out). Semi-implicit Euler with ``m``
    substeps per sample. theta > 0 tips the block onto its +x corner (the sign of the rigid
    integrator above).
    """
    n = acc.size
    h = dt / m
    # corner offsets from the centre of mass in the body frame: (+b_pos, -hh), (-b_neg, -hh)
    ux = np.array([b_pos, -b_neg])
    uy = np.array([-hh, -hh])
    anchor = np.zeros(2)
    touching = np.zeros(2, dtype=np.bool_)
    th, w = th0, 0.0
    # released at rest on the pivot corner (both corners when th0 = 0), springs at their static set
    piv = 0 if th0 >= 0.0 else 1
    c0, s0 = math.cos(th), math.sin(th)
    n_down = 2 if th0 == 0.0 else 1
    set_ = mass * 9.80665 / (n_down * kn)
    y = -(-ux[piv] * s0 + uy[piv] * c0) - set_
    x = 0.0
    vx, vy = 0.0, 0.0
    for i in range(2):
        cy = y - ux[i] * s0 + uy[i] * c0
        if cy <= 0.0:
            touching[i] = True
            anchor[i] = x + ux[i] * c0 + uy[i] * s0
    out[0] = th
    for k in range(n - 1):
        for j in range(m):
            a = acc[k] + (acc[k + 1] - acc[k]) * ((j + 0.5) / m)
            c, s = math.cos(th), math.sin(th)
            fx, fy, tq = -mass * a, -mass * 9.80665, 0.0
            for i in range(2):
                # corner position and velocity (body rotation phi = -theta, counter-clockwise)
                rx = ux[i] * c + uy[i] * s
                ry = -ux[i] * s + uy[i] * c
                cx, cy = x + rx, y + ry
                cvx, cvy = vx + w * ry, vy - w * rx
                if cy >= 0.0:
                    touching[i] = False
                    continue
                if not touching[i]:
                    touching[i] = True
                    anchor[i] = cx
                nf = -kn * cy - cn * cvy
                if nf < 0.0:
                    nf = 0.0
                tf = -kt * (cx - anchor[i]) - ct * cvx
                if not both and ((i == 0) != (th >= 0.0)):
                    tf = 0.0  # only the corner on the side of theta holds (the pivot)
                    anchor[i] = cx
                cap = mu * nf
                if abs(tf) > cap:
                    tf = math.copysign(cap, tf)
                    anchor[i] = cx + (tf + ct * cvx) / kt  # the spring carries what friction allows
                fx += tf
                fy += nf
                # moment about the centre of mass, counter-clockwise, then in theta's sense
                tq -= rx * nf - ry * tf
            vx += h * fx / mass
            vy += h * fy / mass
            w += h * tq / ic
            x += h * vx
            y += h * vy
            th += h * w
            if abs(th) >= 0.5 * math.pi:
                for kk in range(k + 1, n):
                    out[kk] = math.copysign(0.5 * math.pi, th)
                return 1
        out[k + 1] = th
    return 0


def simulate_contact(truth: Truth, acc: np.ndarray, *, theta0: float = 0.0, dt: float = DT) -> tuple[np.ndarray, bool]:
    """theta [rad] at the samples of ``acc`` [m/s^2] (step ``dt``, 500 Hz by default), compliant contact."""
    hh = HEIGHT / 2
    R = math.hypot(hh, WIDTH / 2)
    i0 = MASS * G * R / truth.p_pos**2
    ic = i0 - MASS * R * R
    kn = MASS * (2 * math.pi * truth.contact_freq) ** 2 / 2  # per corner
    cn = truth.contact_zeta * MASS * 2 * math.pi * truth.contact_freq
    kt = MASS * (2 * math.pi * truth.tangential_freq) ** 2 / 2
    ct = 0.5 * MASS * 2 * math.pi * truth.tangential_freq
    # substeps: 40 per period of the stiffest spring, at least 8 per sample
    m = max(8, int(math.ceil(40 * max(truth.contact_freq, truth.tangential_freq) * dt)))
    out = np.empty(acc.size)
    b = WIDTH / 2
    over = _integrate_contact(
        np.ascontiguousarray(acc, dtype=np.float64),
        dt,
        m,
        float(theta0),
        MASS,
        ic,
        hh,
        b,
        b,
        kn,
        cn,
        kt,
        ct,
        truth.mu,
        truth.both_corners_hold,
        out,
    )
    return out, bool(over)


# ----------------------------------------------------------------------------
# ground motions
def ground_motion(rng: np.random.Generator, duration: float = 6.0, dt: float = DT) -> np.ndarray:
    """A short pulse-like filtered-noise record at model scale [m/s^2].

    White noise through a second-order band-pass (Kanai-Tajimi-like, centre
    :data:`FG_RANGE`, damping 0.35), under a (t/t1)^2 exp(2 (1 - t/t1))
    envelope, plus a one-cycle sine pulse of 1-2 Hz in half the records,
    scaled to a peak of :data:`PGA_RANGE` times g tan(alpha) (1.47 m/s^2 for
    the seed specimen), then 1.5 s of free rocking at the end (zeros). For
    the seed specimen about a quarter of the records overturn and the median
    theta_max/alpha of the others is ~0.15. ``dt``: the sample step [s] (default 500 Hz).
    """
    n_shake = int(round((duration - 1.5) / dt))
    n = int(round(duration / dt)) + 1
    t = np.arange(n_shake) * dt
    fg = rng.uniform(FG_RANGE[0], FG_RANGE[1])
    wg, zg = 2 * math.pi * fg, 0.35
    # band-pass 2 z w s / (s^2 + 2 z w s + w^2), discretised with the bilinear transform
    b, a = signal.bilinear([2 * zg * wg, 0.0], [1.0, 2 * zg * wg, wg * wg], fs=1.0 / dt)
    y = signal.lfilter(b, a, rng.standard_normal(n_shake))
    t1 = rng.uniform(0.6, 1.4)
    env = (t / t1) ** 2 * np.exp(2.0 * (1.0 - t / t1))
    a = y * env
    if rng.random() < 0.5:
        fp = rng.uniform(1.0, 2.0)
        t0 = rng.uniform(0.8, 2.0)
        tp = t - t0
        pulse = np.where((tp > 0) & (tp < 1 / fp), np.sin(2 * math.pi * fp * tp), 0.0)
        a = a / np.max(np.abs(a)) + rng.choice([-1.0, 1.0]) * rng.uniform(0.6, 1.0) * pulse
    a = a / np.max(np.abs(a)) * rng.uniform(PGA_RANGE[0], PGA_RANGE[1]) * G * WIDTH / HEIGHT
    # taper the last 0.2 s of shaking so the record ends at rest
    taper = np.ones(n_shake)
    k = int(0.2 / dt)
    taper[-k:] = 0.5 * (1 + np.cos(np.linspace(0, math.pi, k)))
    out = np.zeros(n)
    out[:n_shake] = a * taper
    return out


# ----------------------------------------------------------------------------
# campaigns
def _observe(truth: Truth, theta: np.ndarray, rng: np.random.Generator, dt: float = DT) -> np.ndarray:
    th = theta
    if truth.tau:
        k = np.arange(th.size)
        th = np.interp(k - truth.tau / dt, k, th)  # the theta channel shows theta(t - tau)
    return th + truth.offset + rng.normal(0.0, NOISE, th.size)


def _write_csv(path: Path, acc: np.ndarray, theta: np.ndarray, dt: float = DT) -> None:
    t = np.arange(acc.size) * dt
    tfmt = "%.4f" if dt == DT else f"%.{max(4, 3 + int(math.ceil(-math.log10(dt))))}f"
    np.savetxt(
        path,
        np.column_stack((t, acc, theta)),
        fmt=(tfmt, "%.9e", "%.9e"),
        delimiter=",",
        header="time,ground_acc,theta",
        comments="",
    )


def write_campaign(
    root: str | Path,
    hidden: str = "none",
    *,
    n_ground: int = 60,
    seed: int = 0,
    fv_theta0_over_alpha: tuple[float, ...] = (0.8, -0.65, 0.5),
    fv_duration: float = 12.0,
    gm_duration: float = 6.0,
    dt: float = DT,
) -> dict:
    """Write a synthetic campaign to ``root`` and return what it holds.

    Parameters
    ----------
    root : path
        Directory to create (campaign.toml and records/).
    hidden : str
        Key of :data:`HIDDEN`.
    n_ground : int
        Number of ground-motion records.
    seed : int
        Seed of the ground motions and the noise (numpy SeedSequence; record
        i draws from the i-th child, so records do not change when n grows).
    fv_theta0_over_alpha : tuple of float
        Release angles of the free-vibration records over the stated alpha [-].
    fv_duration, gm_duration : float
        Record lengths [s].
    dt : float
        Sample step [s] (default :data:`DT`, 500 Hz); the noise per sample stays :data:`NOISE`.

    Returns
    -------
    dict
        ``root``, ``hidden``, ``expected`` (tuple of registry names, empty for none), ``truth``,
        ``overturned`` (per ground-motion record), ``gm_ids``.
    """
    root = Path(root)
    (root / "records").mkdir(parents=True, exist_ok=True)
    truth = truth_for(hidden)
    alpha = math.atan2(WIDTH, HEIGHT)
    ss = np.random.SeedSequence([seed, 7919])
    fv_ss, gm_ss = ss.spawn(2)
    entries = []
    for i, (x, child) in enumerate(zip(fv_theta0_over_alpha, fv_ss.spawn(len(fv_theta0_over_alpha)), strict=True)):
        rid = f"fv{i + 1:02d}"
        acc = np.zeros(int(round(fv_duration / dt)) + 1)
        th, _ = simulate_truth(truth, acc, theta0=x * alpha, rng=np.random.default_rng(child.spawn(1)[0]), dt=dt)
        _write_csv(root / "records" / f"{rid}.csv", acc, _observe(truth, th, np.random.default_rng(child), dt), dt)
        entries.append((rid, "free_vibration"))
    overturned = []
    gm_ids = []
    for i, child in enumerate(gm_ss.spawn(n_ground)):
        rid = f"gm{i + 1:03d}"
        motion_ss, noise_ss, impact_ss = child.spawn(3)
        acc = ground_motion(np.random.default_rng(motion_ss), gm_duration, dt)
        th, over = simulate_truth(truth, acc, rng=np.random.default_rng(impact_ss), dt=dt)
        _write_csv(root / "records" / f"{rid}.csv", acc, _observe(truth, th, np.random.default_rng(noise_ss), dt), dt)
        entries.append((rid, "ground_motion"))
        overturned.append(over)
        gm_ids.append(rid)
    lines = [
        f'name = "synthetic campaign, hidden effect: {hidden}"',
        "[specimen]",
        f"height = {HEIGHT}",
        f"width = {WIDTH}",
        f"depth = {DEPTH}",
        f"mass = {MASS}",
        f"p = {P_SEED}",
    ]
    for rid, kind in entries:
        lines += ["[[record]]", f'id = "{rid}"', f'kind = "{kind}"', f'file = "records/{rid}.csv"']
    (root / "campaign.toml").write_text("\n".join(lines) + "\n")
    return {
        "root": root,
        "hidden": hidden,
        "expected": _expected(hidden),
        "truth": truth,
        "overturned": np.array(overturned),
        "gm_ids": gm_ids,
    }


def _expected(hidden: str):
    """Registry names the diagnosis should give (a tuple), or the localisation class of an effect outside it."""
    return HIDDEN[hidden][1] if hidden in HIDDEN else OUTSIDE[hidden][1]


def cached_campaign(base: str | Path, hidden: str, *, n_ground: int = 60, seed: int = 0) -> dict:
    """:func:`write_campaign` into ``base/<hidden>-<n_ground>-<seed>``, reusing it when a test already wrote it.

    Test modules share one campaign per (hidden, n_ground, seed) through a common base folder
    (pytest's session base temp), so it is generated once per session.
    """
    root = Path(base) / f"{hidden}-{n_ground}-{seed}"
    done = root / ".complete"
    if done.exists():
        truth = truth_for(hidden)
        return {"root": root, "hidden": hidden, "expected": _expected(hidden), "truth": truth}
    info = write_campaign(root, hidden, n_ground=n_ground, seed=seed)
    done.write_text("ok\n")
    return info
