"""The pieces of the analytic kernels that do not depend on the equation of motion (private).

The parameter vector's layout, the block states and event codes, and the @njit helpers that
:mod:`housner._kernel` (Housner's equation with the effects' terms) and the kernels of the
mechanics effects (:mod:`housner.effects.sliding`, :mod:`housner.effects.flexible`) share: the
substep grid, the RK4 update, the secant trial point, uplift from rest, the rest rule,
restitution and the sampled history. Reduced coordinates and units as in :mod:`housner._kernel`.
"""

from __future__ import annotations

import math

from numba import njit

HALF_PI = 0.5 * math.pi
EPS = 2.220446049250313e-16

#: Layout of the parameter vector handed to the kernel. I_R is the common
#: ratio (kept for reference); the kernel uses I_R_POS for an impact that
#: lands on the +x corner and I_R_NEG for one that lands on the -x corner.
I_ALPHA_POS, I_ALPHA_NEG, I_P_POS, I_P_NEG, I_R, I_R_EXP, I_DAMPING, I_R_POS, I_R_NEG = range(9)
N_PARAMS = 9

#: Block states. STUCK (held at phi > 0, w = 0 by a dry moment) only occurs with a dry term.
REST, ROCKING, OVERTURNED, STUCK = 0, 1, 2, 3

#: Event codes of one step; the velocity reaching zero (dry terms) and a block released at w = 0
#: that does not move within the step come with terms only.
EV_NONE, EV_IMPACT, EV_OVERTURN, EV_SETTLE, EV_REVERSE, EV_STALL = 0, 1, 2, 3, 4, 5

#: Safety net: most events allowed inside one sample interval before the
#: block is put to rest (never reached with rest_tol >= 1e-15, see model.py).
MAX_EVENTS_PER_SAMPLE = 100_000


@njit(cache=True)
def rk4_update(y, v, h, v1, v2, v3, v4, a1, a2, a3, a4):
    """End (y, v) of an RK4 step of length h [s] for a coordinate y with rate v.

    v1..v4 are the stage rates of y, a1..a4 those of v (weights 1, 2, 2, 1).
    """
    h6 = h / 6.0
    return y + h6 * (v1 + 2.0 * v2 + 2.0 * v3 + v4), v + h6 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)


@njit(cache=True)
def secant(hl, gl, hr, gr):
    """Next trial point of the bracket [hl, hr] [s] with values gl, gr: the secant root, or the midpoint."""
    h = hr - gr * (hr - hl) / (gr - gl)
    if not (hl < h < hr):
        h = 0.5 * (hl + hr)
    return h


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
def grid(j, m, dt):
    """Local time of substep boundary j of m [s] (exactly dt at j = m)."""
    if j >= m:
        return dt
    return dt * j / m


@njit(cache=True)
def substep_of(tau, m, dt):
    """Index of the substep of m that contains local time tau [s] (m - 1 at tau = dt)."""
    j = int(tau * m / dt)
    if j > m - 1:
        j = m - 1
    return j


@njit(cache=True)
def pivot_constants(alpha_p, alpha_n, p2_p, p2_n, rest_tol):
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
def initial_state(theta0, theta_dot0):
    """(at_rest, s, phi, w, t_uplift) of a block released at theta0 [rad] with theta_dot0 [rad/s]."""
    if theta0 == 0.0 and theta_dot0 == 0.0:
        return True, 1.0, 0.0, 0.0, math.nan
    s = 1.0
    if theta0 < 0.0 or (theta0 == 0.0 and theta_dot0 < 0.0):
        s = -1.0
    return False, s, s * theta0, s * theta_dot0, 0.0


@njit(cache=True)
def uplift(g0, g1, tau, dt, thr_p, thr_n):
    """First local times >= tau [s] at which g0 -> g1 [g] falls below -thr_p and rises above thr_n (inf: not here).

    With thr = tan(alpha) of each pivot: when a block at rest tips onto the +x and onto the -x corner.
    """
    return _uplift_side(g0, g1, tau, dt, -thr_p), _uplift_side(-g0, -g1, tau, dt, -thr_n)


@njit(cache=True)
def reduced_ground(s, g0, g1, dt):
    """Reduced ground acceleration on pivot s: a0 = s g0 [-] at the sample start and its slope [1/s]."""
    if s > 0.0:
        a0 = g0
        a1 = g1
    else:
        a0 = -g0
        a1 = -g1
    return a0, (a1 - a0) / dt


@njit(cache=True, inline="always")
def clip_unit(r_eff):
    """An energy ratio [-] clipped to [0, 1] (NaN passes through): the kernel's restitution and the effects'
    impact laws (:mod:`housner.effects.parameters`, :mod:`housner.effects.measured`)."""
    if r_eff > 1.0:
        r_eff = 1.0
    if r_eff < 0.0:
        r_eff = 0.0
    return r_eff


@njit(cache=True)
def restitution(v, r, r_exp, p2, alpha):
    """Speed [rad/s] after an impact at speed v: sqrt(r_eff) v, r_eff = clip(r (v / (p alpha))^r_exp, 0, 1)."""
    r_eff = r
    if r_exp != 0.0 and v > 0.0:
        r_eff = clip_unit(r * (v / (math.sqrt(p2) * alpha)) ** r_exp)
    return math.sqrt(r_eff) * v


@njit(cache=True)
def store(theta_out, theta_dot_out, i, s, phi, w, rocking, overturned):
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
