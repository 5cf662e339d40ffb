"""The impact-map figure: each engine's departure from Housner's model at the impact and in flight, against x.

Left, the kinetic-energy ratio of an impact over Housner's, r / r_housner [-], against the normalised impact
speed x = |w-| / (p alpha) [-] (log axis), each engine's binned median with its spread as a band, beside
Housner's constant (1). Right, the equivalent viscous coefficient of the flight between impacts, c [1/s]
(dE/dt = -c w^2, c > 0 a loss), against the flight's x = sqrt(2 E) / (p alpha), on a symmetric-log axis
so that gains, losses and the analytic engine's zero all show. The maps are measured by
:func:`housner.scenarios.runs.impact_map.measure_maps`.

Drawn with matplotlib's object API (no pyplot, no global state), like :mod:`housner.reports.figures`.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from housner.reports.figures import engine_colors
from housner.scenarios.runs.impact_map import EngineMaps

__all__ = ["maps_figure", "save_figure"]

#: |c| [1/s] below which the flight panel's axis is linear: the analytic engine's c is ~1e-10, the engines' 1e-6-1e-1.
C_LINTHRESH = 1e-5
#: Formats :func:`save_figure` writes, by suffix.
FORMATS = {".png": "png", ".svg": "svg"}
_DPI = 110


def maps_figure(maps: Sequence[EngineMaps], reference: str = "housner") -> Figure:
    """The impact and flight maps of several engines side by side.

    Parameters
    ----------
    maps : sequence of EngineMaps
        One per engine, in the legend's order.
    reference : str
        The engine drawn in black (the analytic one).

    Returns
    -------
    matplotlib.figure.Figure
    """
    maps = list(maps)
    if not maps:
        raise ValueError("`maps` must hold at least one EngineMaps")
    colors = engine_colors([m.engine for m in maps], reference)
    fig = Figure(figsize=(11.0, 4.4), layout="constrained")
    ax_i, ax_f = fig.subplots(1, 2)
    ax_i.axhline(1.0, color="0.4", lw=1.0, ls="--", label="Housner (r / r_housner = 1)")
    ax_f.axhline(0.0, color="0.4", lw=1.0, ls="--", label="Housner (c = 0)")
    for m in maps:
        col = colors[m.engine]
        x = np.asarray(m.impacts["x"], float)
        y = np.asarray(m.impacts["ratio_median"], float)
        s = np.nan_to_num(np.asarray(m.impacts["ratio_spread"], float))
        ax_i.fill_between(x, y - s, y + s, color=col, alpha=0.15, lw=0)
        ax_i.plot(x, y, "o-", color=col, ms=3.5, lw=1.2, label=f"{m.label} ({sum(m.impacts['n'])} impacts)")
        xf = np.asarray(m.flights["x"], float)
        c = np.asarray(m.flights["c_median_per_s"], float)
        cs = np.nan_to_num(np.asarray(m.flights["c_spread_per_s"], float))
        ax_f.fill_between(xf, c - cs, c + cs, color=col, alpha=0.15, lw=0)
        ax_f.plot(xf, c, "o-", color=col, ms=3.5, lw=1.2, label=f"{m.label} ({sum(m.flights['n'])} flights)")
    spec = maps[0].specimen
    ax_i.set_xscale("log")
    _plain_log_ticks(ax_i)
    ax_i.set_xlabel("impact speed x = |w-| / (p alpha)  [-]")
    ax_i.set_ylabel("r / r_housner  [-]")
    ax_i.set_title(f"impact: energy kept over Housner's (r_housner = {maps[0].r_housner:.4f})", fontsize=10.5)
    ax_f.set_xscale("log")
    _plain_log_ticks(ax_f)
    ax_f.set_yscale("symlog", linthresh=C_LINTHRESH)
    ax_f.set_xlabel("flight energy x = sqrt(2 E) / (p alpha)  [-]")
    ax_f.set_ylabel("c [1/s]  (dE/dt = -c w^2; > 0 a loss)")
    ax_f.set_title("flight: equivalent viscous coefficient", fontsize=10.5)
    for ax in (ax_i, ax_f):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7.5)
    fig.suptitle(
        f"Departure from Housner's model, free rocking of {spec.name or 'the specimen'}, "
        f"sampled every {1e3 * maps[0].dt_s:g} ms, engines at their settings",
        fontsize=11,
    )
    return fig


def _plain_log_ticks(ax) -> None:
    """Label a log x axis with plain numbers at 1-2-5 steps (matplotlib's minor labels overlap on a short span)."""
    ax.xaxis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v:g}"))
    ax.xaxis.set_minor_formatter(NullFormatter())


def save_figure(fig: Figure, path: str | Path, dpi: int = _DPI) -> Path:
    """Write ``fig`` as PNG or SVG, chosen by the suffix of ``path``; no date or software in the file's metadata,
    so the same figure writes the same bytes."""
    path = Path(path)
    fmt = FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise ValueError(f"figure {str(path)!r}: the name must end in one of {', '.join(FORMATS)}")
    meta = {"Software": None} if fmt == "png" else {"Date": None, "Creator": None}
    fig.savefig(path, format=fmt, dpi=dpi, metadata=meta)
    return path
