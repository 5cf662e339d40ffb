"""The RDK model's modulating function from a record's Husid parameters: (Ia, D5-95, t_mid) -> alpha1-3.

The published model (Rezaeian & Der Kiureghian 2010) modulates its filtered
noise by q(t) = alpha1 (t - T0)^(alpha2 - 1) exp(-alpha3 (t - T0)); the
cumulative energy of q^2 is a regularised incomplete gamma function, so the
Arias intensity, the 5-95 % significant duration and the 45 % time t_mid of
the record fix alpha1, alpha2 and alpha3 by two nested one-dimensional root
searches.

References
----------
Rezaeian, S. & Der Kiureghian, A. (2010). Simulation of synthetic ground
motions for specified earthquake and site characteristics. Earthquake Engng
Struct. Dyn. 39, 1155-1180.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.optimize import brentq
from scipy.special import gammainc, gammaincc, gammainccinv, gammaincinv, gammaln

from housner.units import G

#: Smallest shape k = 2 alpha2 - 1 of q^2 accepted [-] (alpha2 >= 0.55): q^2 ~
#: (t - T0)^(k - 1) is integrable for any k > 0; on the sample grid the first
#: sample after T0 is then at most dt^(alpha2 - 1) times q(T0 + 1 s).
_K_MIN = 0.1

#: Husid fractions that define D5-95 and t_mid.
P5, P45, P95 = 0.05, 0.45, 0.95


def _husid_times(k: float, a3: float, T0: float, w0: float, w1: float, p) -> np.ndarray:
    """Times at Husid fractions p of q^2 ~ (t - T0)^(k - 1) exp(-2 a3 (t - T0)) on the window [w0, w1].

    Lower regularised incomplete gamma functions P serve the early part of the
    envelope and upper ones Q = 1 - P its tail, each where it keeps its digits.
    """
    p = np.asarray(p, dtype=float)
    s0, s1 = 2.0 * a3 * (w0 - T0), 2.0 * a3 * (w1 - T0)
    P0, P1 = gammainc(k, s0), gammainc(k, s1)
    Q0, Q1 = gammaincc(k, s0), gammaincc(k, s1)
    Pp = P0 + p * (P1 - P0)
    Qp = Q0 - p * (Q0 - Q1)
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.where(Pp <= 0.5, gammaincinv(k, np.minimum(Pp, 0.5)), gammainccinv(k, np.minimum(Qp, 0.5)))
    return T0 + s / (2.0 * a3)


def _alpha3_for_tmid(k: float, t_mid: float, T0: float, w0: float, w1: float) -> float | None:
    """The alpha3 [1/s] that puts 45 % of the windowed envelope energy at t_mid, or None if none does."""

    def g(log_a3: float) -> float:
        return float(_husid_times(k, math.exp(log_a3), T0, w0, w1, P45)) - t_mid

    span = w1 - T0
    lo, hi = math.log(1e-6 / span), math.log(1e6 / span)
    if w0 > T0:  # keep some of the envelope's energy inside the window (Q0 >~ exp(-300))
        hi = min(hi, math.log(300.0 / (2.0 * (w0 - T0))))
    glo, ghi = g(lo), g(hi)
    if not (glo > 0.0 > ghi):  # t45 falls from ~uniform-window value towards w0 as alpha3 grows
        return None
    return math.exp(brentq(g, lo, hi, xtol=1e-13, rtol=1e-13))


def _d595(k: float, t_mid: float, T0: float, w0: float, w1: float) -> float:
    """D5-95 [s] of the envelope with shape k = 2 alpha2 - 1 and t_mid fixed; nan if t_mid is unreachable."""
    a3 = _alpha3_for_tmid(k, t_mid, T0, w0, w1)
    if a3 is None:
        return math.nan
    t5, t95 = _husid_times(k, a3, T0, w0, w1, [P5, P95])
    return float(t95 - t5)


@functools.lru_cache(maxsize=64)
def solve_envelope(Ia: float, D: float, t_mid: float, T0: float, duration: float) -> tuple[float, float, float]:
    """alpha1 [m/s^2 s^(1 - alpha2)], alpha2 [-] and alpha3 [1/s] of q, or raise ValueError naming the cause."""
    w0, w1 = max(T0, 0.0), duration

    def excess(log_k: float) -> float:
        return _d595(math.exp(log_k), t_mid, T0, w0, w1) - D

    # D5-95 shrinks as the envelope's shape k = 2 alpha2 - 1 grows (energy more
    # concentrated around its mode); bracket the root by doubling / halving k.
    lo = hi = 0.0
    e_lo = e_hi = excess(0.0)
    if math.isnan(e_lo):
        raise ValueError(f"`t_mid` ({t_mid} s) is out of reach of the gamma envelope on [{w0}, {w1}] s")
    while e_lo < 0.0:
        lo -= math.log(2.0)
        e_lo = excess(lo)
        if not lo > math.log(_K_MIN) or math.isnan(e_lo):
            raise ValueError(
                f"`D5_95` ({D:g} s) is too long for t_mid = {t_mid:g} s with the envelope starting at T0 = {T0:g} s "
                f"and the motion ending at {w1:g} s: even alpha2 -> 1/2 falls short; start it earlier (smaller `T0`)"
            )
    while e_hi > 0.0:
        hi += math.log(2.0)
        e_hi = excess(hi)
        if hi > math.log(1e6) or math.isnan(e_hi):
            raise ValueError(f"`D5_95` ({D:g} s) is too short for the gamma envelope with t_mid = {t_mid:g} s")
    k = math.exp(brentq(excess, lo, hi, xtol=1e-13)) if lo < hi else 1.0
    a3 = _alpha3_for_tmid(k, t_mid, T0, w0, w1)
    s0, s1 = 2.0 * a3 * (w0 - T0), 2.0 * a3 * (w1 - T0)
    frac = gammainc(k, s1) - gammainc(k, s0) if gammainc(k, s0) < 0.5 else gammaincc(k, s0) - gammaincc(k, s1)
    # int_w0^w1 q^2 dt = a1^2 Gamma(k) / (2 a3)^k * frac = 2 g Ia / pi
    log_a1 = 0.5 * (math.log(2.0 * G * Ia / math.pi) - gammaln(k) + k * math.log(2.0 * a3) - math.log(frac))
    return math.exp(log_a1), 0.5 * (k + 1.0), a3
