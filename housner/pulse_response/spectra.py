"""Rocking spectra: peak rotation of a block under analytical pulses (seed Figure 2).

By dimensional analysis (seed eq. 6) the peak rotation of a rigid block under
a pulse of given shape is theta_max / alpha = phi(alpha, omega_p / p,
a_p / (g tan alpha)) (and r). A rocking spectrum is theta_max / alpha on a grid
of omega_p / p and a_p / (g tan alpha) for one slenderness.

Each grid point is one simulation of Housner's model (:mod:`housner.model`)
over the pulse only; the rocking after the pulse is free, so its largest
excursion follows in closed form from the state at the end of the pulse
(energy conservation between impacts, energy ratio r at the impact; see
:func:`free_rocking_peak`). No simulated time is spent waiting for the block to
reach its last peak, however slowly it rocks near the overturning angle.

References
----------
Housner, G. W. (1963). The behavior of inverted pendulum structures during
earthquakes. BSSA 53(2), 403-417.
Makris, N., Konstantinidis, D. (2003). The rocking spectrum and the limitations
of practical design methodologies. Earthquake Eng. Struct. Dyn. 32(2), 265-289.
Dimitrakopoulos, E. G., DeJong, M. J. (2012). Revisiting the rocking block:
closed-form solutions and similarity laws. Proc. R. Soc. A 468, 2294-2318.
Bachmann, J. A. et al. (2017). Probabilistic validation of the Housner rocking
model. COMPDYN 2017, eqs. 5-6 and Figure 2.
"""

from __future__ import annotations

import math
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from housner.errors import unknown_choice
from housner.model import simulate_many
from housner.motion import GroundMotion
from housner.pulse_response.pulses import one_sine, ricker, ricker_half_width
from housner.specimen import Specimen
from housner.units import G

__all__ = [
    "PULSES",
    "RockingSpectrum",
    "free_rocking_peak",
    "pulse_motion",
    "rocking_spectrum",
]

#: Pulse shapes of a spectrum (:mod:`housner.pulse_response.pulses` makes the motions, for the
#: spectrum and for the engines): name -> Ricker kind, or None for the one-sine pulse.
PULSES: dict[str, str | None] = {
    "symmetric_ricker": "symmetric",
    "antisymmetric_ricker": "antisymmetric",
    "one_sine": None,
}

#: Samples per period of the faster of the pulse (2 pi / omega_p) and the block
#: (2 pi / p). The motion is linear between samples, so the pulse is
#: represented to (2 pi / 128)^2 / 8 = 3e-4 of a_p; the solver's own RK4 step is
#: set by p independently (p h <= 0.01).
SAMPLES_PER_PERIOD = 128


def free_rocking_peak(theta, theta_dot, alpha: float, p: float, r: float) -> tuple[np.ndarray, np.ndarray]:
    """Largest |theta| still to come in free rocking from a given state, and whether it overturns.

    Parameters
    ----------
    theta : array_like
        Rotation at the start of the free rocking [rad].
    theta_dot : array_like
        Angular velocity there [rad/s].
    alpha : float
        Slenderness [rad].
    p : float
        Frequency parameter [1/s].
    r : float
        Kinetic-energy ratio at impact [-].

    Returns
    -------
    peak : ndarray
        Largest |theta| reached after that instant [rad] (pi/2 where it overturns).
    overturned : ndarray of bool

    Notes
    -----
    With no ground motion the energy over m g R, e = cos(alpha - |theta|) - cos(alpha)
    + theta_dot^2 / (2 p^2), is conserved between impacts and multiplied by r
    at each impact, so the excursions after the present one only get smaller:
    * moving away from theta = 0 (theta theta_dot >= 0): the next peak is the
      current excursion's, cos(alpha - theta_pk) = cos(alpha) + e; the block
      overturns if e >= 1 - cos(alpha) (it passes theta = alpha);
    * moving toward theta = 0: the current excursion's peak is past; after the
      impact the energy is r e, giving the next peak the same way.
    A block already beyond alpha and moving outward overturns; moving inward it
    comes back only with e > 1 - cos(alpha).

    References
    ----------
    Housner (1963); Bachmann et al. (2017), eqs. 2 and 4.
    """
    th = np.asarray(theta, dtype=float)
    w = np.asarray(theta_dot, dtype=float)
    a = np.abs(th)
    e = np.cos(alpha - a) - math.cos(alpha) + w * w / (2.0 * p * p)
    e_top = 1.0 - math.cos(alpha)
    outward = th * w >= 0.0
    beyond = a >= alpha
    # energy of the next excursion that is still to come: this one if moving outward, else after the impact
    e_next = np.where(outward, e, r * e)
    c = np.clip(math.cos(alpha) + e_next, -1.0, 1.0)
    over_inside = e_next >= e_top
    # beyond alpha: outward it falls; inward it comes back over the top only with e > e_top, then
    # impacts and the next excursion has r e
    over_beyond = outward | (e <= e_top) | (r * e >= e_top)
    over = np.where(beyond, over_beyond, over_inside)
    peak = np.where(beyond, a, alpha - np.arccos(c))
    return np.where(over, math.pi / 2, peak), over


def _pulse_window(pulse: str, omega_p: float, p: float) -> tuple[float, float]:
    """Sample step [s] and duration of the forcing window [s] of a pulse."""
    dt = 2.0 * math.pi / (max(omega_p, p) * SAMPLES_PER_PERIOD)
    if pulse == "one_sine":
        Tp = 2.0 * math.pi / omega_p
        n = max(1, math.ceil(Tp / dt - 1e-9))
        return Tp / n, Tp  # the pulse ends exactly on a sample
    return dt, 2.0 * ricker_half_width(PULSES[pulse]) / omega_p


def pulse_motion(pulse: str, a_p: float, omega_p: float, p: float, *, duration: float | None = None) -> GroundMotion:
    """The ground motion that :func:`rocking_spectrum` uses at one grid point.

    Parameters
    ----------
    pulse : str
        One of :data:`PULSES`.
    a_p : float
        Pulse amplitude [m/s^2] (peak |ug''|).
    omega_p : float
        Pulse frequency [rad/s].
    p : float
        Frequency parameter of the block [1/s] (sets the sample step).
    duration : float, optional
        Total duration [s]; default the forcing window only (the pulse's end).

    Returns
    -------
    GroundMotion
        :func:`housner.pulse_response.pulses.ricker` (centre t0 at the default half-width)
        or :func:`housner.pulse_response.pulses.one_sine` (phase 0) with this step.
        The one-sine pulse is a_p sin(omega_p t) for 0 <= t <= 2 pi / omega_p,
        phase 0 as in Zhang & Makris (2001): the block waits at rest until
        a_p sin(omega_p t) reaches g tan(alpha). (Their psi =
        asin(g tan(alpha) / a_p) is the phase at that uplift, not a shift of
        the pulse; see :func:`housner.pulse_response.pulses.one_sine`.)
    """
    if pulse not in PULSES:
        raise unknown_choice("pulse", pulse, PULSES)
    for key, v in (("a_p", a_p), ("omega_p", omega_p), ("p", p)):
        if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v)):
            raise ValueError(f"`{key}` must be a finite number, got {v!r}")
    if omega_p <= 0 or p <= 0:
        raise ValueError("`omega_p` and `p` must be positive")
    dt, window = _pulse_window(pulse, omega_p, p)
    total = window if duration is None else float(duration)
    if not (math.isfinite(total) and total > 0):
        raise ValueError(f"`duration` must be positive and finite, got {duration!r}")
    kind = PULSES[pulse]
    if kind is None:
        acc = one_sine(a_p, omega_p, dt=dt, duration=total).acc
    else:
        acc = ricker(a_p, omega_p, kind=kind, dt=dt, duration=total, t0=0.5 * window).acc
    name = f"{pulse} a_p={a_p:.4g} omega_p={omega_p:.4g}"
    return GroundMotion(acc, dt, name, f"housner.pulse_response.spectra.pulse_motion({pulse!r}, dt={dt!r})")


@dataclass(frozen=True, eq=False)
class RockingSpectrum:
    """theta_max / alpha of one block under one pulse shape on a grid.

    Attributes
    ----------
    pulse : str
        Pulse shape (a key of :data:`PULSES`).
    omega_ratio : ndarray, shape (n_w,)
        omega_p / p [-] (x axis).
    accel_ratio : ndarray, shape (n_a,)
        a_p / (g tan alpha) [-] (y axis).
    theta_max_over_alpha : ndarray, shape (n_a, n_w)
        theta_max / alpha [-], row i for accel_ratio[i], column j for
        omega_ratio[j]; +inf where the block overturned.
    overturned : ndarray of bool, shape (n_a, n_w)
    alpha : float
        Slenderness [rad].
    p : float
        Frequency parameter [1/s].
    r : float
        Kinetic-energy ratio at impact used [-].
    name : str
        The specimen's name.
    """

    pulse: str
    omega_ratio: np.ndarray
    accel_ratio: np.ndarray
    theta_max_over_alpha: np.ndarray
    overturned: np.ndarray
    alpha: float
    p: float
    r: float
    name: str = ""

    def min_overturn_accel(self) -> np.ndarray:
        """Smallest a_p / (g tan alpha) of the grid that overturns the block, per omega_p / p [-] (NaN if none)."""
        out = np.full(self.omega_ratio.size, np.nan)
        for j in range(self.omega_ratio.size):
            k = np.flatnonzero(self.overturned[:, j])
            if k.size:
                out[j] = self.accel_ratio[k[0]]
        return out

    def plot(self, ax=None, *, levels: int = 11, cmap: str = "viridis"):
        """Contour plot like the seed's Figure 2.

        Filled contours of theta_max / alpha in [0, 1] (values above 1 without
        overturning take the top colour), the overturning region hatched in
        dark grey with surviving grid points next to it drawn as dots, axes
        omega_p / p and a_p / (g tan alpha).

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure is made when omitted.
        levels : int
            Number of contour levels between 0 and 1.
        cmap : str
            Colour map of the filled contours.

        Returns
        -------
        matplotlib.axes.Axes
        """
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(6.4, 4.8), layout="constrained")
        W, A = np.meshgrid(self.omega_ratio, self.accel_ratio)
        v = np.where(self.overturned, np.inf, self.theta_max_over_alpha)
        mappable = draw_spectrum(ax, W.ravel(), A.ravel(), v.ravel(), levels=levels, cmap=cmap)
        ax.figure.colorbar(mappable, ax=ax, extend="max", label=r"$\theta_{max}/\alpha$; grey with crosses: overturn")
        if self.overturned.any():
            ax.legend(loc="upper left")
        ax.set_xlabel(r"$\omega_p / p$")
        ax.set_ylabel(r"$a_p / (g \tan\alpha)$")
        label = self.pulse.replace("_", " ")
        ax.set_title(
            f"Rocking spectrum, {label}, tan(alpha) = {math.tan(self.alpha):.3g}, r = {self.r:.4g}", fontsize=10
        )
        return ax


#: Colour of the overturn region of a rocking spectrum.
OVERTURN_GREY = "#c8c8c8"


def draw_spectrum(ax, omega_ratio, accel_ratio, values, *, levels: int = 11, cmap: str = "viridis"):
    """One rocking-spectrum panel on ``ax``; returns the colour mapping for a colour bar.

    Filled contours of theta_max/alpha [-] over omega_p/p and a_p/(g tan alpha)
    on 0 .. 1 when the points fill a grid, coloured markers otherwise; overturns
    (``+inf``) are the grey region above the top level, each marked with a cross,
    and failed points (NaN) open squares. Rocking peaks are capped just below 1,
    so that only an overturn takes the grey (theta_max > alpha without overturning
    happens: a late lobe of a pulse pushes the block back).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    omega_ratio, accel_ratio : array_like
        omega_p / p [-] and a_p / (g tan alpha) [-] of each point.
    values : array_like
        theta_max/alpha of each point [-].
    levels : int
        Contour levels between 0 and 1.
    cmap : str
        Colour map of the rocking responses.

    References
    ----------
    Bachmann et al. (2017), Fig. 2 and eq. 6.
    """
    import matplotlib as mpl

    w, a = np.asarray(omega_ratio, dtype=float), np.asarray(accel_ratio, dtype=float)
    v = np.asarray(values, dtype=float)
    wu, au = np.unique(w), np.unique(a)
    cm = mpl.colormaps[cmap].with_extremes(over=OVERTURN_GREY)
    bounds = np.linspace(0.0, 1.0, levels)
    norm = mpl.colors.BoundaryNorm(bounds, cm.N, extend="max")
    over = np.isposinf(v)
    z = np.where(over, 2.0, np.minimum(v, 0.999))  # overturns above the top level: the bands run up to them
    if wu.size >= 2 and au.size >= 2 and wu.size * au.size == w.size:
        Z = np.full((au.size, wu.size), np.nan)
        Z[np.searchsorted(au, a), np.searchsorted(wu, w)] = z
        ax.contourf(wu, au, Z, levels=bounds, cmap=cm, norm=norm, extend="max")
    else:
        ax.scatter(w, a, c=z, cmap=cm, norm=norm, s=30)
    ax.plot(w[over], a[over], ls="none", marker="x", ms=4, color="#a94442", label="overturn")
    failed = np.isnan(v)
    if failed.any():
        ax.plot(w[failed], a[failed], ls="none", marker="s", ms=5, mfc="none", color="#d62728", label="failed")
    return mpl.cm.ScalarMappable(norm=norm, cmap=cm)


@contextmanager
def _numba_threads(n: int | None):
    if n is None:
        yield
        return
    import numba

    old = numba.get_num_threads()
    numba.set_num_threads(max(1, min(int(n), numba.config.NUMBA_NUM_THREADS)))
    try:
        yield
    finally:
        numba.set_num_threads(old)


def _ratios(name: str, values) -> np.ndarray:
    try:
        a = np.atleast_1d(np.asarray(values, dtype=float))
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be an array of numbers, got {values!r}") from None
    if a.ndim != 1 or a.size == 0:
        raise ValueError(f"`{name}` must be a non-empty 1-D array, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"`{name}` must be finite")
    return a


def rocking_spectrum(
    specimen: Specimen,
    pulse: str = "symmetric_ricker",
    omega_ratio=None,
    accel_ratio=None,
    *,
    r: float | None = None,
    n_jobs: int | None = None,
) -> RockingSpectrum:
    """theta_max / alpha of ``specimen`` under a pulse on a grid (seed Figure 2).

    Parameters
    ----------
    specimen : Specimen
        The block (alpha [rad], p [1/s]).
    pulse : {"symmetric_ricker", "antisymmetric_ricker", "one_sine"}
        Pulse shape; see :mod:`housner.pulse_response.pulses`.
    omega_ratio : array_like, optional
        omega_p / p [-], positive; default 100 values from 1 to 12.
    accel_ratio : array_like, optional
        a_p / (g tan alpha) [-]; default 100 values from 0.5 to 12.
    r : float, optional
        Kinetic-energy ratio at impact [-]; default ``specimen.r_housner``.
    n_jobs : int, optional
        Threads for the compiled solver; default all of numba's.

    Returns
    -------
    RockingSpectrum

    Notes
    -----
    Each grid point simulates the pulse's forcing window only: the Ricker
    wavelets until |psi| < 1e-6 (2 x 8.3/omega_p symmetric, 2 x 10.6/omega_p
    antisymmetric), the one-sine pulse (phase 0, as Zhang & Makris 2001) until
    2 pi/omega_p. The peak of the free
    rocking that follows comes from the end state in closed form
    (:func:`free_rocking_peak`), which is exact for Housner's model and costs
    nothing, where simulating it would need a time that grows without bound
    near theta_max -> alpha. Samples: :data:`SAMPLES_PER_PERIOD` per period of
    the faster of pulse and block.

    References
    ----------
    Makris & Konstantinidis (2003); Bachmann et al. (2017), eq. 6 and Figure 2.
    """
    W, A, r_used = _spectrum_args(specimen, pulse, omega_ratio, accel_ratio, r, n_jobs)
    ratio, over = _grid_response(specimen, pulse, W, A, r_used, n_jobs)
    shape2 = (W.size, A.size)
    return RockingSpectrum(
        pulse=pulse,
        omega_ratio=W,
        accel_ratio=A,
        theta_max_over_alpha=ratio.reshape(shape2).T.copy(),
        overturned=over.reshape(shape2).T.copy(),
        alpha=specimen.alpha,
        p=specimen.p,
        r=r_used,
        name=specimen.name,
    )


def _spectrum_args(specimen, pulse, omega_ratio, accel_ratio, r, n_jobs) -> tuple[np.ndarray, np.ndarray, float]:
    """The checked grid and r of :func:`rocking_spectrum`: (omega_p/p [-], a_p/(g tan alpha) [-], r [-])."""
    if not isinstance(specimen, Specimen):
        raise TypeError(f"`specimen` must be a housner.Specimen, got {type(specimen).__name__}")
    if pulse not in PULSES:
        raise unknown_choice("pulse", pulse, PULSES)
    W = _ratios("omega_ratio", np.linspace(1.0, 12.0, 100) if omega_ratio is None else omega_ratio)
    A = _ratios("accel_ratio", np.linspace(0.5, 12.0, 100) if accel_ratio is None else accel_ratio)
    if np.any(W <= 0):
        raise ValueError("`omega_ratio` must be positive")
    if n_jobs is not None and not (isinstance(n_jobs, (int, np.integer)) and n_jobs >= 1):
        raise ValueError(f"`n_jobs` must be a positive integer, got {n_jobs!r}")
    r_used = specimen.r_housner if r is None else float(r)
    if not (math.isfinite(r_used) and 0.0 <= r_used <= 1.0):
        raise ValueError(f"`r` must lie in [0, 1], got {r!r}")
    return W, A, r_used


def _grid_response(
    specimen: Specimen, pulse: str, W: np.ndarray, A: np.ndarray, r: float, n_jobs: int | None
) -> tuple[np.ndarray, np.ndarray]:
    """theta_max/alpha [-] (+inf where overturned) and the overturn flags, one per grid point, omega-major.

    Each point simulates the pulse's forcing window; the free rocking after it is closed-form
    (:func:`free_rocking_peak`).
    """
    alpha, p = specimen.alpha, specimen.p
    a_up = G * specimen.tan_alpha
    motions = []
    for w in W:
        shape = pulse_motion(pulse, 1.0, w * p, p)  # unit amplitude; every a_p is a multiple of it
        for a in A:
            motions.append(shape.scaled(amplitude=a * a_up))
    with _numba_threads(n_jobs):
        res = simulate_many(specimen, motions, r=r, parallel=n_jobs != 1)

    theta_max = np.array([x.theta_max for x in res])
    over = np.array([x.overturned for x in res])
    th_end = np.array([x.theta[-1] for x in res])
    thd_end = np.array([x.theta_dot[-1] for x in res])
    after, over_after = free_rocking_peak(th_end, thd_end, alpha, p, r)
    over = over | over_after
    ratio = np.where(over, np.inf, np.maximum(theta_max, np.where(over, 0.0, after)) / alpha)
    return ratio, over
