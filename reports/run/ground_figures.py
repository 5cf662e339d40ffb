"""Figures of ground motions: a record and the elastic spectra of a simulated ensemble (seed paper, Figure 8).

Figures are drawn on :class:`matplotlib.figure.Figure` objects with an Agg
canvas, never through pyplot, so nothing opens a window and the global backend
is left alone. Functions return the Figure; the caller saves or embeds it.

Units on the axes: time [s], acceleration and pseudo-acceleration [g],
displacement [mm], period [s].

References
----------
Bachmann, J. A. et al. (2017). Probabilistic validation of the Housner rocking
model. COMPDYN 2017, Figure 8.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from housner.motion import GroundMotion
from housner.scenarios.motions.elastic import ensemble_spectra, response_spectrum
from housner.units import G

__all__ = ["DEFAULT_PERIODS", "plot_ensemble_spectra", "plot_record"]

#: Default periods of the spectra, 0.01 s to 3 s, log-spaced [s].
DEFAULT_PERIODS = np.logspace(-2, math.log10(3.0), 60)

_RECORD = {"color": "black", "lw": 1.6}
_MEAN = {"color": "tab:red", "lw": 2.2}
_MEMBER = {"color": "0.6", "lw": 0.4, "alpha": 0.5}


def plot_record(record: GroundMotion, ax: Axes, *, label: str | None = None) -> Axes:
    """Draw the acceleration trace of ``record`` [g] against time [s] on ``ax`` and return ``ax``."""
    if not isinstance(record, GroundMotion):
        raise TypeError(f"`record` must be a housner.GroundMotion, got {type(record).__name__}")
    ax.plot(record.t, record.acc / G, color="black", lw=0.6, label=label or record.name)
    ax.axhline(0.0, color="0.7", lw=0.5)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("ground acceleration [g]")
    ax.set_xlim(0.0, record.duration)
    peak = record.pga / G
    ax.set_ylim(-1.15 * peak, 1.15 * peak)
    ax.set_title(f"{record.name}: PGA {peak:.3f} g", fontsize="medium")
    return ax


def _spectra_panels(axes, T, rec_psa, rec_sd, psa, sd, title: str) -> None:
    """PSa of every member with the mean and the record; mean PSa; mean Sd."""
    ax_all, ax_mean_a, ax_mean_d = axes
    for row in psa:
        ax_all.plot(T, row / G, **_MEMBER)
    ax_all.plot(T, psa.mean(axis=0) / G, label=f"mean of {len(psa)}", **_MEAN)
    ax_all.plot(T, rec_psa / G, label="record", **_RECORD)
    ax_all.set_ylabel("PSa [g]")
    ax_all.set_title(f"{title}: PSa of each motion", fontsize="medium")
    ax_mean_a.plot(T, psa.mean(axis=0) / G, label="ensemble mean", **_MEAN)
    ax_mean_a.plot(T, rec_psa / G, label="record", **_RECORD)
    ax_mean_a.fill_between(
        T, *(np.percentile(psa, [16, 84], axis=0) / G), color="tab:red", alpha=0.15, lw=0, label="16-84 %"
    )
    ax_mean_a.set_ylabel("PSa [g]")
    ax_mean_a.set_title(f"{title}: mean PSa", fontsize="medium")
    ax_mean_d.plot(T, 1e3 * sd.mean(axis=0), label="ensemble mean", **_MEAN)
    ax_mean_d.plot(T, 1e3 * rec_sd, label="record", **_RECORD)
    ax_mean_d.fill_between(
        T, *(1e3 * np.percentile(sd, [16, 84], axis=0)), color="tab:red", alpha=0.15, lw=0, label="16-84 %"
    )
    ax_mean_d.set_ylabel("Sd [mm]")
    ax_mean_d.set_title(f"{title}: mean Sd", fontsize="medium")
    for ax in axes:
        ax.set_xscale("log")
        ax.set_xlabel("period T [s]")
        ax.set_xlim(T[0], T[-1])
        ax.set_ylim(bottom=0.0)
        ax.grid(True, which="both", lw=0.3, color="0.85")
        ax.legend(fontsize="small", loc="upper left" if ax is ax_mean_d else "upper right")


def plot_ensemble_spectra(
    record: GroundMotion,
    motions: Sequence[GroundMotion],
    *,
    S: float | None = None,
    periods=DEFAULT_PERIODS,
    damping: float = 0.05,
    fig: Figure | None = None,
) -> Figure:
    """The seed paper's Figure 8: a record and the elastic spectra of an ensemble simulated from it.

    Parameters
    ----------
    record : GroundMotion
        The recorded motion [m/s^2].
    motions : sequence of GroundMotion
        The simulated ensemble, at prototype scale [m/s^2].
    S : float, optional
        Size ratio prototype / model [-]. When given, a third row shows the
        same spectra for the record and the motions compressed in time by
        sqrt(S) (seed eq. 9, ``GroundMotion.to_model_scale``).
    periods : array_like
        Oscillator periods [s].
    damping : float
        Damping ratio of the spectra [-] (0.05 is 5 %).
    fig : matplotlib.figure.Figure, optional
        Figure to draw on (cleared first); a new one with an Agg canvas otherwise.

    Returns
    -------
    matplotlib.figure.Figure
        Row 1: the record's acceleration trace. Row 2: PSa of every motion (thin
        grey) with their mean (bold) and the record's; mean PSa and mean Sd of
        the ensemble against the record's, with the 16-84 % band. Row 3 (with
        ``S``): the same after time scaling.
    """
    if not isinstance(record, GroundMotion):
        raise TypeError(f"`record` must be a housner.GroundMotion, got {type(record).__name__}")
    motions = list(motions)
    if not motions:
        raise ValueError("`motions` is empty")
    if S is not None and not (isinstance(S, (int, float, np.floating)) and math.isfinite(S) and S > 0):
        raise ValueError(f"`S` must be a positive number, got {S!r}")
    T = np.asarray(periods, dtype=float)
    rows = 3 if S is not None else 2
    if fig is None:
        fig = Figure(figsize=(13.0, 3.6 * rows), layout="constrained")
        FigureCanvasAgg(fig)
    else:
        fig.clear()
    grid = fig.add_gridspec(rows, 3)
    plot_record(record, fig.add_subplot(grid[0, :]))

    rec_psa, rec_sd = response_spectrum(record, T, damping)
    psa, sd = ensemble_spectra(motions, T, damping)
    _spectra_panels([fig.add_subplot(grid[1, j]) for j in range(3)], T, rec_psa, rec_sd, psa, sd, "prototype scale")
    if S is not None:
        scaled_rec = record.to_model_scale(S)
        rec_psa_s, rec_sd_s = response_spectrum(scaled_rec, T, damping)
        psa_s, sd_s = ensemble_spectra([m.to_model_scale(S) for m in motions], T, damping)
        _spectra_panels(
            [fig.add_subplot(grid[2, j]) for j in range(3)],
            T,
            rec_psa_s,
            rec_sd_s,
            psa_s,
            sd_s,
            f"time-scaled, S = {S:g}",
        )
    fig.suptitle(f"{record.name} and {len(motions)} simulated motions, {100 * damping:g} % damped spectra")
    return fig
