"""The Rezaeian & Der Kiureghian site-based stochastic ground-motion model: fit to a record, simulate ensembles.

A ground acceleration is modelled as a modulated, filtered white-noise process (Rezaeian & Der Kiureghian
2008, 2010): unit pulses through a linear oscillator whose frequency drifts in time, normalised to unit
variance, modulated by a gamma-shaped q(t) set by the Arias intensity, D5-95 and t_mid, then through the
papers' critically damped high-pass filter, followed until it is at rest so that every motion ends with
zero velocity and displacement (:func:`simulate`, :class:`RDKParams`). :func:`fit` is the papers' method of
moments on one record. The model's equations, the fit, and the limit of its single-mode filter are in
``docs/explanation/ground-motions.md`` ("The published model").

References
----------
Rezaeian, S. & Der Kiureghian, A. (2008). A stochastic ground motion model with
separable temporal and spectral nonstationarities. Earthquake Engng Struct.
Dyn. 37, 1565-1584.
Rezaeian, S. & Der Kiureghian, A. (2010). Simulation of synthetic ground
motions for specified earthquake and site characteristics. Earthquake Engng
Struct. Dyn. 39, 1155-1180.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numba
import numpy as np
from scipy import signal
from scipy.optimize import minimize_scalar

from housner.motion import GroundMotion
from housner.scenarios.motions.elastic import sdof_history
from housner.scenarios.motions.rdk_envelope import P5, P45, P95
from housner.scenarios.motions.rdk_params import DEFAULT_OMEGA_C, RDKParams
from housner.scenarios.motions.records import arias_intensity, husid_time, pmnm_count, upcrossing_count

__all__ = [
    "DEFAULT_COUNT_LOWPASS",
    "DEFAULT_FIT_SEED",
    "fit",
    "highpass",
    "modulated_noise",
    "seed_sequence",
    "simulate",
    "white_noise",
]

#: Default low-pass corner [Hz] applied to record and simulations alike before
#: positive minima and negative maxima are counted in :func:`fit`: the PEER
#: 1999 El Centro file was low-passed at 15 Hz in processing, while the model
#: has content up to the Nyquist frequency, and extrema counts are dominated by
#: that high-frequency content.
DEFAULT_COUNT_LOWPASS = 15.0

#: Seed of the simulations that identify zeta_f in :func:`fit`.
DEFAULT_FIT_SEED = 20100101

#: Impulse responses are dropped once their envelope exp(-zeta omega tau) falls
#: below this fraction of its start [-]; the normalisation uses the same
#: truncated sums, so the process keeps unit variance exactly.
_KERNEL_TOL = 1e-10


# ----------------------------------------------------------------------
# Simulation
# ----------------------------------------------------------------------
@numba.njit(cache=True)
def _filtered_noise(u, omega, zeta, dt, tol):  # pragma: no cover - compiled
    """Unit-variance filtered white noise sum_{i<j} h(t_j - t_i, omega_i) u[i, :] / sigma_h(t_j).

    Every column of ``u`` goes through the same operations in the same order
    whatever the number of columns, so a column's result does not depend on the others.
    """
    n, m = u.shape
    x = np.zeros((n, m))
    var = np.zeros(n)
    sq = math.sqrt(1.0 - zeta * zeta)
    log_tol = -math.log(tol)
    for i in range(n - 1):
        w = omega[i]
        amp = w / sq
        decay = math.exp(-zeta * w * dt)
        c = decay * math.cos(w * sq * dt)
        s = decay * math.sin(w * sq * dt)
        lmax = n - 1 - i
        lcut = int(log_tol / (zeta * w * dt)) + 1
        if lcut < lmax:
            lmax = lcut
        # z^lag = exp((-zeta + i sqrt(1 - zeta^2)) w lag dt) by repeated complex multiplication
        zr = c
        zi = s
        for lag in range(1, lmax + 1):
            h = amp * zi
            j = i + lag
            var[j] += h * h
            for col in range(m):
                x[j, col] += h * u[i, col]
            zr, zi = zr * c - zi * s, zr * s + zi * c
    for j in range(n):
        if var[j] > 0.0:
            inv = 1.0 / math.sqrt(var[j])
            for col in range(m):
                x[j, col] *= inv
    return x


def modulated_noise(params: RDKParams, u: np.ndarray) -> np.ndarray:
    """The modulated filtered noise x before the high-pass filter, shape (params.n, m) [m/s^2].

    ``u`` holds white-noise columns of shape (params.n_warm + params.n_noise, m);
    the first ``n_warm`` pulses fall before t = 0. x is zero after ``duration``.
    Also the entry point of :mod:`housner.scenarios.motions.rdk_match`, which reshapes x's
    spectrum before the high-pass filter.
    """
    nw, nn = params.n_warm, params.n_noise
    tu = (np.arange(nw + nn) - nw) * params.dt
    noise = _filtered_noise(np.ascontiguousarray(u), params.filter_frequency(tu), params.zeta_f, params.dt, _KERNEL_TOL)
    x = np.zeros((params.n, u.shape[1]))
    x[:nn] = noise[nw:] * params.modulating(tu[nw:])[:, None]
    return x


def highpass(x: np.ndarray, dt: float, omega_c: float) -> np.ndarray:
    """ü = x - 2 omega_c u' - omega_c^2 u with u'' + 2 omega_c u' + omega_c^2 u = x from rest [m/s^2], along axis 0."""
    disp, vel = sdof_history(x, dt, omega_c, 1.0)
    return x - 2.0 * omega_c * vel - omega_c**2 * disp


def _simulate_array(params: RDKParams, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Model accelerations for white-noise columns u of shape (params.n_warm + params.n_noise, m).

    The first ``n_warm`` pulses fall before t = 0. Returns the high-pass-filtered
    accelerations and the modulated noise x before the filter, both of shape
    (params.n, m) [m/s^2].
    """
    x = modulated_noise(params, u)
    return highpass(x, params.dt, params.omega_c), x


def seed_sequence(seed) -> np.random.SeedSequence:
    """A fresh SeedSequence (spawning from it never advances the caller's object)."""
    if isinstance(seed, np.random.SeedSequence):
        return np.random.SeedSequence(seed.entropy, spawn_key=seed.spawn_key, pool_size=seed.pool_size)
    if isinstance(seed, (np.random.Generator, np.random.RandomState)):
        raise ValueError(
            "`seed` must be an int or a numpy SeedSequence (motion i comes from SeedSequence(seed).spawn(n)[i]); "
            "a generator would make motion i depend on earlier draws"
        )
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"`seed` must be a non-negative int or a numpy SeedSequence, got {seed!r}")
    return np.random.SeedSequence(int(seed))


def white_noise(children: list, n_samples: int) -> np.ndarray:
    """Standard normal columns, column c from ``default_rng(children[c])``."""
    u = np.empty((n_samples, len(children)))
    for c, child in enumerate(children):
        u[:, c] = np.random.default_rng(child).standard_normal(n_samples)
    return u


#: Motions simulated per compiled call (bounds memory: 256 x 5000 x 8 B = 10 MB per array).
_CHUNK = 256


def simulate(params: RDKParams, n: int, seed, *, name: str = "rdk") -> list[GroundMotion]:
    """Simulate ``n`` ground motions of the model.

    Parameters
    ----------
    params : RDKParams
    n : int
        Number of motions.
    seed : int or numpy.random.SeedSequence
        Motion i is drawn from ``np.random.default_rng(np.random.SeedSequence(seed).spawn(n)[i])``
        (spawned from a copy, so a SeedSequence passed in is not advanced); the
        spawned children do not depend on n, so neither does motion i.
    name : str
        Prefix of the motion names: ``"rdk-000"``, ``"rdk-001"``, ...

    Returns
    -------
    list of GroundMotion
        Accelerations [m/s^2] at ``params.dt``, ``params.n`` samples each
        (noise up to ``params.duration``, then the high-pass filter coming to
        rest); the provenance names the model, parameters and seed.

    Notes
    -----
    About 0.2 s for 100 motions of 4000 samples on one core (compiled, after
    the first call).
    """
    if not isinstance(params, RDKParams):
        raise TypeError(f"`params` must be an RDKParams, got {type(params).__name__}")
    what = f"Rezaeian & Der Kiureghian (2010) model ({describe_text(params)})"
    return simulate_motions(params, n, seed, name, what, lambda u: _simulate_array(params, u)[0])


def check_count(n, name: str, minimum: int = 0) -> int:
    """``n`` as an int of at least ``minimum`` (0 or 1), else a ValueError naming ``name``."""
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or n < minimum:
        kind = "non-negative" if minimum == 0 else "positive"
        raise ValueError(f"`{name}` must be a {kind} int, got {n!r}")
    return int(n)


def seed_text(seed) -> str:
    """The SeedSequence of ``seed`` as provenance names it."""
    ss = seed_sequence(seed)
    return f"SeedSequence(entropy={ss.entropy}, spawn_key={tuple(ss.spawn_key)})"


def describe_text(params: RDKParams) -> str:
    """``params.describe()`` as one line, ``key=value, ...``."""
    return ", ".join(f"{k}={v:.6g}" if isinstance(v, float) else f"{k}={v}" for k, v in params.describe().items())


def simulate_motions(params: RDKParams, n, seed, name: str, what: str, acc_of) -> list[GroundMotion]:
    """The ensemble loop of :func:`simulate` and of the matched model (:mod:`housner.scenarios.motions.rdk_match`).

    ``acc_of(u)`` turns white-noise columns u, shape (params.n_warm + params.n_noise, m), into
    accelerations [m/s^2] with one column per motion; motion i gets child i of SeedSequence(seed)
    (in chunks of :data:`_CHUNK`) and the provenance ``what``, its index and its seed.
    """
    n = check_count(n, "n", 0)
    ss = seed_sequence(seed)
    children = ss.spawn(n)
    seed_txt = seed_text(ss)
    out: list[GroundMotion] = []
    for start in range(0, n, _CHUNK):
        block = children[start : start + _CHUNK]
        acc = acc_of(white_noise(block, params.n_warm + params.n_noise))
        for c in range(len(block)):
            i = start + c
            out.append(
                GroundMotion(
                    acc=acc[:, c].copy(),
                    dt=params.dt,
                    name=f"{name}-{i:03d}",
                    provenance=f"{what}; motion {i}, default_rng({seed_txt}.spawn(n)[{i}])",
                )
            )
    return out


def _window_counts(count: np.ndarray, j0: int, j1: int) -> np.ndarray:
    """Counts on samples j0..j1 relative to the count just before j0."""
    base = count[j0 - 1] if j0 > 0 else 0.0 * count[0]
    return count[j0 : j1 + 1] - base


# ----------------------------------------------------------------------
# Fit
# ----------------------------------------------------------------------
def _fit_frequency(t: np.ndarray, n_up: np.ndarray, t_mid: float) -> tuple[float, float]:
    """Least squares of N(t) = c + (omega_mid (t - t_mid) + omega' (t - t_mid)^2 / 2) / (2 pi) [rad/s, rad/s^2]."""
    s = t - t_mid
    design = np.column_stack([np.ones_like(s), s / (2.0 * math.pi), 0.25 * s * s / math.pi])
    coef, *_ = np.linalg.lstsq(design, n_up, rcond=None)
    return float(coef[1]), float(coef[2])


def fit(
    record: GroundMotion,
    *,
    T0: float = 0.0,
    omega_c: float = DEFAULT_OMEGA_C,
    count_lowpass: float | None = DEFAULT_COUNT_LOWPASS,
    n_sim: int = 20,
    seed=DEFAULT_FIT_SEED,
    tail: float | None = None,
) -> RDKParams:
    """Fit the model to one record (Rezaeian & Der Kiureghian 2010, method of moments).

    Parameters
    ----------
    record : GroundMotion
        The target accelerogram [m/s^2].
    T0 : float
        Start of the modulating function [s]; 0 is the record's first sample.
    omega_c : float
        High-pass corner frequency [rad/s]; not fitted.
    count_lowpass : float or None
        Low-pass corner [Hz] of a 4th-order zero-phase Butterworth filter applied
        to the record and to the simulated motions alike before their positive
        minima and negative maxima are counted; it should not exceed the record's
        processing low-pass corner (15 Hz for PEER 1999 El Centro). None counts
        the raw samples.
    n_sim : int
        Motions simulated per trial value of zeta_f.
    seed : int or SeedSequence
        Seed of those simulations; the same white noise serves every trial
        zeta_f, so the objective varies smoothly with zeta_f.
    tail : float, optional
        Passed to :class:`RDKParams`.

    Returns
    -------
    RDKParams
        With the record's ``dt`` and ``duration``.

    Notes
    -----
    - Ia, D5-95 and t_mid are the record's (Husid curve, times from its first sample).
    - omega_mid and omega' minimise the squared difference between the record's
      cumulative count of zero-level up-crossings on [t5, t95] and
      c + int_{t_mid}^t omega_f / (2 pi) dt, linear in (c, omega_mid, omega').
    - zeta_f minimises the squared difference between the record's cumulative
      count of positive minima and negative maxima on [t5, t95] and the mean
      count of ``n_sim`` simulated motions: a grid of step 0.1 on [0.05, 0.95],
      then a bounded Brent search within 0.1 of the best (to 0.002), rounded to 0.001.
    - Why ``count_lowpass``: extrema counts are governed by the highest
      frequencies present. The model has content up to the Nyquist frequency,
      the processed record none above its low-pass corner; counted raw, the
      match drives zeta_f down to make up for content the record lost in
      processing (0.13 instead of 0.45 for El Centro, and a mean spectrum up
      to twice the record's near 0.2 s and a third of it at 1 s).
    - Ia is then divided by the share of int x^2 dt that survives the
      high-pass filter in the ``n_sim`` simulations at the fitted zeta_f
      (0.94 for El Centro; the same noise before and after the filter makes the
      ratio precise), so that simulated motions have the record's Arias
      intensity on average.
    - The high-pass filter raises the zero-crossing rate a little (it removes
      slow content), so omega_mid comes out ~3 % high when a simulated motion
      is fitted back.
    """
    lowpass = _count_filter(record, n_sim, count_lowpass)
    Ia = arias_intensity(record)
    t5, t45, t95 = (float(v) for v in husid_time(record, [P5, P45, P95]))
    j0 = int(np.searchsorted(record.t, t5, side="left"))
    j1 = int(np.searchsorted(record.t, t95, side="right")) - 1
    omega_mid, omega_prime = _record_frequency(record, j0, j1, t45, omega_c)
    target = _window_counts(pmnm_count(lowpass(record.acc)), j0, j1)
    base = RDKParams(Ia, t95 - t5, t45, omega_mid, omega_prime, 0.5, omega_c, record.dt, record.duration, T0, tail)
    n_white = max(replace(base, zeta_f=z).n_warm for z in (0.01, 0.99)) + base.n_noise
    u = white_noise(seed_sequence(seed).spawn(int(n_sim)), n_white)
    fitted = replace(base, zeta_f=_fit_zeta(base, u, lowpass, target, j0, j1))
    return _with_record_arias(fitted, u)


def _record_frequency(record: GroundMotion, j0: int, j1: int, t_mid: float, omega_c: float) -> tuple[float, float]:
    """omega_mid [rad/s] and omega' [rad/s^2] fitted to the record's zero-level up-crossings on samples j0..j1;
    a ValueError when omega_mid is not above the high-pass corner ``omega_c`` [rad/s]."""
    n_up = _window_counts(upcrossing_count(record.acc), j0, j1)
    omega_mid, omega_prime = _fit_frequency(record.t[j0 : j1 + 1], n_up, t_mid)
    if not omega_mid > omega_c:
        raise ValueError(
            f"record {record.name!r}: fitted omega_mid = {omega_mid:.4g} rad/s is not above "
            f"`omega_c` = {omega_c:.4g} rad/s"
        )
    return omega_mid, omega_prime


def _with_record_arias(fitted: RDKParams, u: np.ndarray) -> RDKParams:
    """``fitted`` with Ia [m/s] scaled so that its high-passed motions have the record's Arias intensity.

    Ia of the model refers to x before the high-pass filter, which removes the
    content below ~1 Hz in part (|H|^2 = r^4 / (1 + r^2)^2, r = omega / omega_c);
    scale it so that the filtered motions have the record's Arias intensity on
    average. The same noise before and after the filter makes the ratio precise.
    """
    acc, x = _run_on_shared_noise(fitted, u)
    kept = float(np.sum(_trapezoid_sq(acc, fitted.dt)) / np.sum(_trapezoid_sq(x, fitted.dt)))
    return replace(fitted, Ia=fitted.Ia / kept)


def _count_filter(record: GroundMotion, n_sim, count_lowpass: float | None):
    """Check the arguments of :func:`fit`; the low-pass applied before extrema are counted (identity for None)."""
    if not isinstance(record, GroundMotion):
        raise TypeError(f"`record` must be a housner.GroundMotion, got {type(record).__name__}")
    if isinstance(n_sim, (bool, np.bool_)) or not isinstance(n_sim, (int, np.integer)) or n_sim < 1:
        raise ValueError(f"`n_sim` must be a positive int, got {n_sim!r}")
    nyquist = 0.5 / record.dt
    if count_lowpass is not None and not (0.0 < float(count_lowpass) < nyquist):
        raise ValueError(f"`count_lowpass` must lie in (0, {nyquist:g}) Hz, below the Nyquist, got {count_lowpass!r}")
    if count_lowpass is None:

        def lowpass(a: np.ndarray) -> np.ndarray:
            return a

    else:
        sos = signal.butter(4, float(count_lowpass), fs=1.0 / record.dt, output="sos")

        def lowpass(a: np.ndarray) -> np.ndarray:
            return signal.sosfiltfilt(sos, a, axis=0)

    return lowpass


def _run_on_shared_noise(params: RDKParams, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_simulate_array` on the fit's noise ``u``: the last n_noise pulses are shared by every trial
    zeta_f; the warm-up takes what precedes them."""
    return _simulate_array(params, u[u.shape[0] - params.n_warm - params.n_noise :])


def _fit_zeta(base: RDKParams, u: np.ndarray, lowpass, target: np.ndarray, j0: int, j1: int) -> float:
    """zeta_f [-] whose simulations on ``u`` match the record's count of positive minima and negative maxima
    (``target``, samples j0..j1) in the mean: a coarse grid, then a bounded Brent search, rounded to 0.001."""

    def objective(zeta: float) -> float:
        acc, _ = _run_on_shared_noise(replace(base, zeta_f=zeta), u)
        sim = _window_counts(pmnm_count(lowpass(acc)), j0, j1).mean(axis=1)
        return float(np.sum((sim - target) ** 2))

    # the mean count grows monotonically with zeta_f, so the objective has one
    # valley: a coarse grid finds it, a bounded Brent search refines it
    coarse = np.arange(0.05, 0.951, 0.1)
    z0 = float(coarse[int(np.argmin([objective(z) for z in coarse]))])
    res = minimize_scalar(
        objective, bounds=(max(0.01, z0 - 0.1), min(0.99, z0 + 0.1)), method="bounded", options={"xatol": 2e-3}
    )
    return round(float(res.x), 3)


def _trapezoid_sq(a: np.ndarray, dt: float) -> np.ndarray:
    """int a^2 dt per column by the trapezoidal rule [m^2/s^3]."""
    sq = a * a
    return (sq.sum(axis=0) - 0.5 * (sq[0] + sq[-1])) * dt
