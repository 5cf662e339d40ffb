"""The analytic kernel's equation of motion with the terms' hooks, its RK4 step and its events (private).

Housner's equation (seed eq. 2, plus a viscous term) in reduced coordinates on the current pivot ``s``
(phi = s theta >= 0, w = s theta_dot, a = s ug''/g, v = a_v/g not mirrored; time [s], angles [rad], angular
velocity [rad/s], ground accelerations in units of g, the hooks' reduced angular accelerations in 1/s^2),
with four hooks that the effects' terms (:mod:`housner.effects.terms`) fill in: ``_moment`` (smooth moments),
``_dry`` (Coulomb capacities, times sgn(w)), ``impact_ratio`` (the energy ratio, chained) and ``AT_REST``;
``q`` is every term's parameters in one array, a generated hook passing each term its own slice. The
section between the ``hooks`` markers below is what :mod:`housner.effects.terms` replaces to generate the
kernel of a set of terms (with :mod:`housner._kernel`, which runs the record); as written it holds the no-op
hooks: Housner's equation, the plain kernel. The equation, and how the events (impact, peak, overturn, the
zero of w under a dry term, uplift and release from a stick) are located, are in
``docs/explanation/physics.md`` ("How the analytic model solves it").
"""

from __future__ import annotations

import math

from numba import njit

from housner._kernel_parts import (
    EPS,
    EV_IMPACT,
    EV_NONE,
    EV_OVERTURN,
    EV_REVERSE,
    EV_SETTLE,
    EV_STALL,
    HALF_PI,
    grid,
    reduced_ground,
    rk4_update,
    secant,
    substep_of,
)

# <hooks>
#: Whether the kernel has smooth moment terms, dry (Coulomb) terms, impact terms, and a term that
#: acts at rest (the uplift and release rule is then the net moment's).
HAS_MOMENT = False
HAS_DRY = False
HAS_IMPACT = False
AT_REST = False


@njit(cache=True)
def _moment(phi, w, t, a, v, s, alpha, p2, q):
    """Sum of the smooth moment terms: extra phi'' [rad/s^2]."""
    return 0.0


@njit(cache=True)
def _dry(phi, t, a, v, s, alpha, p2, q):
    """Sum of the dry terms' capacities [rad/s^2] (>= 0)."""
    return 0.0


@njit(cache=True)
def impact_ratio(w, r, s, alpha, p2, q):
    """Energy ratio [-] of an impact at speed w [rad/s] after the impact terms, from the ratio r in force."""
    return r


# </hooks>

#: Whether a hook reads the terms' parameters ``q`` (:func:`housner._kernel.run_one` runs without them else).
TERMS = HAS_MOMENT or HAS_DRY or HAS_IMPACT


# ----------------------------------------------------------------------
# the right-hand side on one step: a frame of constants
@njit(cache=True)
def frame(s, g0, g1, v0, v1, dt, t_k, alpha_p, alpha_n, p2_p, p2_n, c, sig):
    """Constants of a step on pivot s: (a0, a slope, v0, v slope, t_k, s, alpha, p^2, c, sig).

    a = a0 + slope tau and v = v0 + v_slope tau at local time tau [s] of the sample that starts at
    t_k [s]; sig is the frozen direction of motion (dry terms), 0 for none.
    """
    a0, slope = reduced_ground(s, g0, g1, dt)
    alpha = alpha_p if s > 0.0 else alpha_n
    p2 = p2_p if s > 0.0 else p2_n
    return (a0, slope, v0, (v1 - v0) / dt, t_k, s, alpha, p2, c, sig)


@njit(cache=True)
def _with_sig(fr, sig):
    """The frame ``fr`` with direction of motion ``sig``."""
    return (fr[0], fr[1], fr[2], fr[3], fr[4], fr[5], fr[6], fr[7], fr[8], sig)


@njit(cache=True)
def accel(phi, w, tau, fr, q):
    """phi'' [rad/s^2] at local time tau [s]: Housner's, the viscous rate, and the terms."""
    a = fr[0] + fr[1] * tau
    d = fr[6] - phi
    acc = -fr[7] * (math.sin(d) + a * math.cos(d)) - fr[8] * w
    if HAS_MOMENT or HAS_DRY:
        v = fr[2] + fr[3] * tau
        t = fr[4] + tau
        if HAS_MOMENT:
            acc = acc + _moment(phi, w, t, a, v, fr[5], fr[6], fr[7], q)
        if HAS_DRY:
            acc = acc - fr[9] * _dry(phi, t, a, v, fr[5], fr[6], fr[7], q)
    return acc


@njit(cache=True)
def _capacity(phi, tau, fr, q):
    """The dry terms' capacity [rad/s^2] at local time tau [s] (0 without dry terms)."""
    if not HAS_DRY:
        return 0.0
    return _dry(phi, fr[4] + tau, fr[0] + fr[1] * tau, fr[2] + fr[3] * tau, fr[5], fr[6], fr[7], q)


@njit(cache=True)
def rk4(phi, w, tau, h, fr, q):
    """One classic RK4 step of length h [s] from local time tau [s], a(tau) = a0 + slope tau (the frame's)."""
    hh = 0.5 * h
    k1 = accel(phi, w, tau, fr, q)
    w2 = w + hh * k1
    k2 = accel(phi + hh * w, w2, tau + hh, fr, q)
    w3 = w + hh * k2
    k3 = accel(phi + hh * w2, w3, tau + hh, fr, q)
    w4 = w + h * k3
    k4 = accel(phi + h * w3, w4, tau + h, fr, q)
    return rk4_update(phi, w, h, w, w2, w3, w4, k1, k2, k3, k4)


@njit(cache=True)
def _locate(kind, target, hl, gl, hr, gr, phi0, w0, tau, fr, q):
    """Root h in [hl, hr] [s] of a function of one RK4 step of length h from tau.

    ``kind`` 0: phi(h) - target; ``kind`` 1: w(h). ``gl`` and ``gr`` are the
    function at the bracket ends and have opposite signs (``gr`` may be 0).
    Safeguarded Newton: the derivative is the step's own end state (w, or
    phi''), which matches d/dh of the step to O(h^4), so convergence is fast;
    a bisection replaces any Newton update that leaves the bracket.

    Returns (h, phi(h), w(h)).
    """
    if gr == 0.0:
        ph, wh = rk4(phi0, w0, tau, hr, fr, q)
        return hr, ph, wh
    h = secant(hl, gl, hr, gr)
    ph = 0.0
    wh = 0.0
    for _ in range(200):
        ph, wh = rk4(phi0, w0, tau, h, fr, q)
        if kind == 0:
            g = ph - target
            d = wh
        else:
            g = wh
            d = accel(ph, wh, tau + h, fr, q)
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


# ----------------------------------------------------------------------
# events of a step without dry terms
@njit(cache=True, inline="always")
def _crossing(phi, w, phi1, w1, hp, php, tau, H, fr, q):
    """Does phi cross zero inside the step (phi, w) -> (phi1, w1) of length H [s]?

    ``hp``, ``php``: time and value of a peak inside the step (hp < 0 if none).
    Returns (event, hl, gl, hr, gr): ``EV_IMPACT`` with a bracket [hl, hr] of
    the first crossing (phi = gl > 0 at hl, gr <= 0 at hr), ``EV_SETTLE`` or
    ``EV_NONE``.
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
                pb, _wb = rk4(phi, w, tau, hb, fr, q)
                if pb > 0.0:
                    hl = hb
                    gl = pb
                    break
                hb *= 0.5
        if hl < 0.0:
            # fresh uplift that did not lift (threshold met to rounding only)
            return EV_SETTLE, hl, gl, hr, gr
    elif w < 0.0 and w1 > 0.0 and phi1 > 0.0 and phi > 0.0:
        # a minimum inside the step: does it dip below zero?
        hm, phm, _wm = _locate(1, 0.0, 0.0, w, H, w1, phi, w, tau, fr, q)
        if phm < 0.0:
            hl = 0.0
            gl = phi
            hr = hm
            gr = phm
    return (EV_IMPACT if hl >= 0.0 else EV_NONE), hl, gl, hr, gr


@njit(cache=True, inline="always")
def step_event(phi, w, phi1, w1, tau, H, fr, q, theta_max):
    """First event of the RK4 step (phi, w) -> (phi1, w1) of length H [s] from local time tau [s].

    Returns (event, h, w_h, theta_max): the event code (``_EV_*``), the time
    h [s] after tau at which it happens and the speed w_h [rad/s] there (for
    an impact), and theta_max raised by a peak of phi inside the step.
    """
    # a peak of phi inside the step (theta_max between samples)
    hp = -1.0
    php = 0.0
    if w > 0.0 and w1 < 0.0:
        hp, php, _wp = _locate(1, 0.0, 0.0, w, H, w1, phi, w, tau, fr, q)
    # overturn: phi reaches pi/2
    if (hp >= 0.0 and php >= HALF_PI) or phi1 >= HALF_PI:
        hr = H
        gr = phi1 - HALF_PI
        if hp >= 0.0 and php >= HALF_PI:
            hr = hp
            gr = php - HALF_PI
        h_o, _ph, _wh = _locate(0, HALF_PI, 0.0, phi - HALF_PI, hr, gr, phi, w, tau, fr, q)
        return EV_OVERTURN, h_o, 0.0, HALF_PI
    if hp >= 0.0 and php > theta_max:
        theta_max = php
    # impact: phi crosses zero inside the step
    event, hl, gl, hr, gr = _crossing(phi, w, phi1, w1, hp, php, tau, H, fr, q)
    if event == EV_IMPACT:
        h_i, _ph, w_i = _locate(0, 0.0, hl, gl, hr, gr, phi, w, tau, fr, q)
        return EV_IMPACT, h_i, w_i, theta_max
    return event, 0.0, 0.0, theta_max


# ----------------------------------------------------------------------
# events of a step with dry terms: phi is monotone between reversals
@njit(cache=True, inline="always")
def step_event_dry(phi, w, phi1, w1, tau, H, fr, q, theta_max):
    """First event of the step (phi, w) -> (phi1, w1) of length H [s] with the direction sig = fr[9] frozen.

    Returns (event, h, phi_h, w_h, theta_max): ``EV_REVERSE`` at the first zero of w (h, phi
    there), ``EV_IMPACT`` (h, w there), ``EV_OVERTURN``, ``EV_STALL`` (released at w = 0, the
    block does not move in the direction sig), ``EV_SETTLE`` (reaches phi = 0 at w = 0) or
    ``EV_NONE``. Until its first zero w keeps the sign sig, so phi is monotone there and every
    bracket below is a bracket of the only root.
    """
    sig = fr[9]
    h_end = H
    p_end = phi1
    rev = False
    if sig * w1 <= 0.0:
        hl = 0.0
        gl = w
        if sig * w <= 0.0:
            # released at w = 0: find a point of the step at which it moves in direction sig
            hl = -1.0
            hb = 0.5 * H
            for _ in range(80):
                _pb, wb = rk4(phi, w, tau, hb, fr, q)
                if sig * wb > 0.0:
                    hl = hb
                    gl = wb
                    break
                hb *= 0.5
            if hl < 0.0:
                return EV_STALL, 0.0, phi, 0.0, theta_max
        if w1 == 0.0:
            h_end = H
        else:
            h_end, p_end, _w = _locate(1, 0.0, hl, gl, H, w1, phi, w, tau, fr, q)
        rev = True
    if sig > 0.0:
        if p_end >= HALF_PI:
            h_o, _ph, _wh = _locate(0, HALF_PI, 0.0, phi - HALF_PI, h_end, p_end - HALF_PI, phi, w, tau, fr, q)
            return EV_OVERTURN, h_o, HALF_PI, 0.0, HALF_PI
        if rev and p_end > theta_max:
            theta_max = p_end
    elif p_end < 0.0 or (p_end == 0.0 and not rev):
        if phi > 0.0:
            h_i, _ph, w_i = _locate(0, 0.0, 0.0, phi, h_end, p_end, phi, w, tau, fr, q)
            return EV_IMPACT, h_i, 0.0, w_i, theta_max
        return EV_SETTLE, 0.0, 0.0, 0.0, theta_max
    elif p_end == 0.0:
        return EV_SETTLE, 0.0, 0.0, 0.0, theta_max
    if rev:
        return EV_REVERSE, h_end, p_end, 0.0, theta_max
    return EV_NONE, 0.0, 0.0, 0.0, theta_max


# ----------------------------------------------------------------------
# a block held still: when does it start to move?
@njit(cache=True)
def hold_margin(phi, stuck, tau, fr, q):
    """> 0 when a block held at phi (w = 0) starts to move at local time tau [s] [rad/s^2].

    At rest on the ground (``stuck`` False) it lifts onto the frame's pivot when phi'' > capacity;
    stuck at phi > 0 it moves either way when |phi''| > capacity (phi'' without the dry terms).
    """
    acc = accel(phi, 0.0, tau, fr, q)
    if stuck:
        acc = abs(acc)
    return acc - _capacity(phi, tau, fr, q)


@njit(cache=True)
def _first_positive(phi, stuck, tl, fl, th, fh, fr, q, scale):
    """Earliest local time in (tl, th] [s] at which the hold margin is positive (fl <= 0 < fh).

    Illinois false position on the margin, to 4 ulps of ``scale`` [s]; returns the bracket's right
    end, where the margin is positive, so that the block does move.
    """
    side = 0
    for _ in range(200):
        if th - tl <= 4.0 * EPS * scale:
            break
        t = th - fh * (th - tl) / (fh - fl)
        if not (tl < t < th):
            t = 0.5 * (tl + th)
        f = hold_margin(phi, stuck, t, fr, q)
        if f > 0.0:
            th = t
            fh = f
            if side == 1:
                fl *= 0.5
            side = 1
        else:
            tl = t
            fl = f
            if side == -1:
                fh *= 0.5
            side = -1
    return th


@njit(cache=True)
def leave(stuck, phi, s, tau, m, dt, g0, g1, v0, v1, t_k, alpha_p, alpha_n, p2_p, p2_n, c, q):
    """(local time [s], pivot, direction) at which a block held still starts to move in [tau, dt].

    At rest (``stuck`` False, phi = 0) both corners are tried and the earlier wins; stuck at
    phi > 0 it stays on pivot s. The margin (:func:`hold_margin`) is checked at tau and at every
    substep boundary after it. Time inf when the block stays put through the sample.
    """
    best = math.inf
    s_best = s
    for i in range(1 if stuck else 2):
        sd = s if stuck else (1.0 if i == 0 else -1.0)
        fr = frame(sd, g0, g1, v0, v1, dt, t_k, alpha_p, alpha_n, p2_p, p2_n, c, 0.0)
        tl = tau
        fl = hold_margin(phi, stuck, tl, fr, q)
        t_go = math.inf
        if fl > 0.0:
            t_go = tau
        else:
            j = substep_of(tau, m, dt)
            while j < m:
                th = grid(j + 1, m, dt)
                if th > tl:
                    fh = hold_margin(phi, stuck, th, fr, q)
                    if fh > 0.0:
                        t_go = _first_positive(phi, stuck, tl, fl, th, fh, fr, q, dt)
                        break
                    tl = th
                    fl = fh
                j += 1
        if t_go < best:
            best = t_go
            s_best = sd
    sig = 0.0
    if best < math.inf:
        fr = frame(s_best, g0, g1, v0, v1, dt, t_k, alpha_p, alpha_n, p2_p, p2_n, c, 0.0)
        sig = 1.0 if accel(phi, 0.0, best, fr, q) > 0.0 else -1.0
    return best, s_best, sig


@njit(cache=True)
def after_reversal(phi, tau, fr, q, sig_before):
    """The direction after w reached 0 at phi > 0 moving in sig_before: 0 (stuck) or -sig_before.

    It turns back when phi'' at w = 0 without the dry terms exceeds their capacity; a phi'' that
    still points along sig_before (it was slowing down, so only by rounding) counts as stuck.
    """
    fr = _with_sig(fr, 0.0)
    acc = accel(phi, 0.0, tau, fr, q)
    if abs(acc) <= _capacity(phi, tau, fr, q) or (acc > 0.0) == (sig_before > 0.0):
        return 0.0
    return -sig_before
