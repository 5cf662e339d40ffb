"""Figures of a fragility study, drawn with matplotlib's object API (no pyplot, no global state).

A study runs one ensemble of ground motions on several engines, scaled to
several intensity stripes, for several structure sizes, and fits a lognormal
fragility function P[overturn | IM = x] = Phi(ln(x / median) / beta) per
(engine, size). The functions here draw, from the study's tables
(``fragility.parquet``, ``exceedance.parquet``, the fits of ``fragility.json``):

- :func:`plot_fragility`: the stripes' overturn fractions with Wilson bars and
  the fitted curves, one size;
- :func:`plot_size_effect`: the median capacity against the prototype height;
- :func:`plot_exceedance`: P[theta_max/alpha >= threshold] per stripe, one
  panel per threshold, one size.

Every function returns a :class:`matplotlib.figure.Figure` (embed it with
:func:`housner.reports.figures.to_png_base64`). Each drawn series carries a ``gid``
("points:ENGINE", "curve:ENGINE", "median:ENGINE", "not-a-fit:ENGINE") so that
its data can be found again, e.g. by the tests.

References
----------
Baker, J. W. (2015). Efficient analytical fragility function fitting using
dynamic structural analysis. Earthquake Spectra 31(1), 579-599.
Wilson, E. B. (1927). Probable inference, the law of succession, and
statistical inference. JASA 22, 209-212.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.legend_handler import HandlerTuple
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from housner._values import json_number
from housner.reports.figures import engine_colors
from housner.scenarios.studies.fragility import fragility_curve
from housner.scenarios.studies.study_fits import StudyFit

__all__ = ["LOG_SPAN", "plot_exceedance", "plot_fragility", "plot_size_effect"]

#: An axis whose positive values span more than this factor is drawn on a log scale.
LOG_SPAN = 4.0

#: Fraction of the smallest gap between stripes over which the engines' points are spread, so
#: that their Wilson bars stand side by side; under a half keeps each stripe's group apart.
_SPREAD = 0.3


# ----------------------------------------------------------------------------
# helpers
def _same(a, b) -> np.ndarray:
    """Sizes equal up to rounding (they pass through JSON and parquet as floats)."""
    return np.isclose(np.asarray(a, dtype=float), float(b), rtol=1e-9, atol=0.0)


def _use_log(values) -> bool:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v) & (v > 0)]
    return v.size > 1 and float(v.max() / v.min()) > LOG_SPAN


def _engine_order(names: Sequence[str], reference: str | None) -> list[str]:
    """Unique names, the reference first (drawn underneath the others)."""
    names = list(dict.fromkeys(str(n) for n in names))
    return sorted(names, key=lambda n: n != reference)


def _offsets(x_levels: np.ndarray, n_series: int, log: bool, spread: float = _SPREAD) -> list:
    """A function per series that shifts x so that the series' error bars do not overlap."""
    u = np.unique(np.asarray(x_levels, dtype=float)[np.isfinite(x_levels)])
    if log:
        u = np.log(u[u > 0])
    gap = float(np.min(np.diff(u))) if u.size > 1 else (0.1 if log else 0.1 * max(abs(float(u[0])), 1.0))
    step = spread * gap / max(n_series, 1)
    out = []
    for k in range(n_series):
        d = (k - 0.5 * (n_series - 1)) * step
        out.append((lambda x, d=d: np.asarray(x, dtype=float) * math.exp(d)) if log else (lambda x, d=d: x + d))
    return out


def _yerr(p: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    # Clipped at 0: a point estimate may sit a rounding error outside its interval, and matplotlib
    # refuses negative bar lengths.
    return np.vstack([np.clip(p - low, 0.0, None), np.clip(high - p, 0.0, None)])


def _fit_of(fits: Sequence[StudyFit], engine: str, size: float) -> StudyFit | None:
    for f in fits:
        if str(f.engine) == engine and _same([json_number(f.size)], size)[0]:
            return f
    return None


def _size_title(frame: pd.DataFrame, size: float) -> str:
    s = frame["S"].dropna().unique() if "S" in frame else []
    return f"prototype height {size:g} m" + (f" (S = {float(s[0]):g})" if len(s) == 1 else "")


def _at_size(
    frame: pd.DataFrame, size: float, also: Sequence[str], reference: str | None, colors: Mapping[str, str] | None
) -> tuple:
    """A table's rows at one size, and what every figure of one size needs of them.

    Returns the rows, the engines (the reference first, then those of the rows and ``also``), their colours,
    the stripes' intensities, whether that axis is logarithmic, and each engine's shift along it.
    """
    sub = frame[_same(frame["size"], size)] if len(frame) else frame
    names = _engine_order(list(sub["engine"]) + list(also), reference)
    colors = dict(colors) if colors is not None else engine_colors(names, reference)
    levels = np.sort(sub["intensity"].dropna().unique().astype(float)) if len(sub) else np.array([1.0])
    log = _use_log(levels)
    return sub, names, colors, levels, log, _offsets(levels, len(names), log)


def _stripe_points(ax, d: pd.DataFrame, shift, name: str, **style):
    """An engine's fraction p per stripe with its Wilson bars (gid "points:ENGINE"), ``shift``-ed along x."""
    p, lo, hi = (d[col].to_numpy(float) for col in ("p", "p_low", "p_high"))
    eb = ax.errorbar(shift(d["intensity"].to_numpy(float)), p, yerr=_yerr(p, lo, hi), capsize=2.5, zorder=3, **style)
    eb.lines[0].set_gid(f"points:{name}")
    return eb


def _log_x_at(ax, values) -> None:
    """A logarithmic x axis, its ticks at ``values`` themselves when they are 12 or fewer (the stripes' intensities,
    the sizes [m]): a log axis over less than a decade has few labelled ticks."""
    ax.set_xscale("log")
    u = np.unique(np.asarray(values, dtype=float))
    if u.size <= 12:
        ax.set_xticks(u, [f"{v:g}" for v in u])
        ax.minorticks_off()


def _set_intensity_axis(ax, levels, label: str) -> None:
    if _use_log(levels):
        _log_x_at(ax, levels)
    ax.set_xlabel(label)


# ----------------------------------------------------------------------------
# fragility of one size
def plot_fragility(
    fr: pd.DataFrame,
    fits: Sequence[StudyFit],
    size: float,
    label: str,
    *,
    reference: str | None = "housner",
    colors: Mapping[str, str] | None = None,
    ci: float = 0.95,
) -> Figure:
    """Overturn fraction per stripe with Wilson bars and the fitted lognormal curve of every engine, one size.

    Parameters
    ----------
    fr : pandas.DataFrame
        ``fragility.parquet``: one row per (engine, size, stripe) with ``engine``,
        ``size`` [m], ``S``, ``intensity``, ``n``, ``n_overturned``, ``p``,
        ``p_low``, ``p_high``.
    fits : sequence of StudyFit
        The ``fits`` of ``fragility.json``: ``engine``, ``size``, ``median``,
        ``beta``, ``status`` (non-finite numbers may be the strings "nan", "inf").
    size : float
        Prototype height to draw [m].
    label : str
        Intensity measure with its unit, for the x axis (e.g. "PGA / (g tan alpha) [-]").
    reference : str, optional
        Engine drawn in black, underneath.
    colors : mapping, optional
        Engine -> colour (default :func:`housner.reports.figures.engine_colors`).
    ci : float
        Confidence level of the intervals in the tables [-] (for the title).

    Returns
    -------
    matplotlib.figure.Figure
        One axes; per engine an error-bar series (gid "points:ENGINE") and,
        where the fit has a median, its curve (gid "curve:ENGINE"), solid for
        status "ok" and dashed otherwise (a step or a degenerate fit is not a
        maximum-likelihood fit).

    Notes
    -----
    Stripes without a valid record (n = 0) are not drawn. The x axis is
    logarithmic when the intensities span more than :data:`LOG_SPAN`; the
    engines' points are shifted slightly about each stripe so that the bars
    do not overlap, while the curves are drawn at the true intensity.
    """
    fitted = [str(f.engine) for f in fits if _same([json_number(f.size)], size)[0]]
    sub, names, colors, levels, log, shift = _at_size(fr, size, fitted, reference, colors)
    grid = _curve_grid(levels, log)
    fig = Figure(figsize=(7.8, 4.8), layout="constrained")
    ax = fig.add_subplot()
    handles, labels = [], []
    for k, name in enumerate(names):
        d = sub[sub["engine"] == name].sort_values("intensity")
        drawn = _fragility_series(
            ax,
            d[d["n"].astype(float) > 0],
            name,
            _fit_of(fits, name, size),
            grid,
            shift[k],
            colors.get(name, "#444444"),
            name == reference,
        )
        if drawn is not None:
            handles.append(drawn[0])
            labels.append(drawn[1])
    ax.set_ylim(-0.02, 1.02)
    _set_intensity_axis(ax, levels, label)
    ax.set_ylabel("P[overturn] [-]")
    ax.set_title(f"Fragility, {_size_title(sub, size)}: stripes with Wilson {ci:.0%} bars, lognormal fits", fontsize=11)
    ax.grid(True, alpha=0.3)
    if handles:
        # Upper left is where a rising fragility curve leaves room.
        ax.legend(
            handles,
            labels,
            handler_map={tuple: HandlerTuple(ndivide=None)},
            loc="upper left",
            fontsize=8,
            framealpha=0.9,
        )
    return fig


def _curve_grid(levels: np.ndarray, log: bool) -> np.ndarray:
    """400 intensities the fitted curves are drawn at: a little beyond the stripes on each side."""
    if log:
        return np.geomspace(levels.min() / 1.4, levels.max() * 1.4, 400)
    pad = 0.12 * (levels.max() - levels.min() or max(levels.max(), 1.0))
    return np.linspace(max(levels.min() - pad, 0.0), levels.max() + pad, 400)


def _fragility_series(
    ax, d: pd.DataFrame, name: str, fit: StudyFit | None, grid: np.ndarray, shift, c: str, is_reference: bool
) -> tuple[tuple, str] | None:
    """One engine of :func:`plot_fragility`: its stripes ``d`` (those with a valid record) as points with
    Wilson bars, and its fitted curve over ``grid`` where the fit has a median. Returns the legend's handle
    (the drawn artists) and text, or None when nothing was drawn."""
    parts = []
    if len(d):
        parts.append(_stripe_points(ax, d, shift, name, fmt="o", ms=5 if is_reference else 4, lw=1.0, color=c))
    med = json_number(fit.median) if fit else math.nan
    beta = json_number(fit.beta) if fit else math.nan
    status = str(fit.status) if fit else "missing"
    if math.isfinite(med) and med > 0 and math.isfinite(beta) and beta >= 0:
        (ln,) = ax.plot(
            grid,
            fragility_curve(grid, med, beta),
            ls="-" if status == "ok" else "--",
            lw=1.8 if is_reference else 1.3,
            color=c,
            zorder=2,
        )
        ln.set_gid(f"curve:{name}")
        parts.append(ln)
    if not parts:
        return None
    if status == "ok":
        text = f"{name}: median {med:.3g}, \N{GREEK SMALL LETTER BETA} = {beta:.2f}"
    elif status == "missing":
        text = f"{name}: no fit in fragility.json"
    else:
        text = f"{name}: no lognormal fit ({status.replace('_', ' ')})"
    return tuple(parts), text


# ----------------------------------------------------------------------------
# median against size
def plot_size_effect(
    fits: Sequence[StudyFit],
    *,
    label: str = "intensity",
    reference: str | None = "housner",
    colors: Mapping[str, str] | None = None,
    ci: float = 0.95,
) -> Figure:
    """Median capacity against prototype height, one series per engine with its bootstrap interval.

    Parameters
    ----------
    fits : sequence of StudyFit
        The ``fits`` of ``fragility.json``: ``engine``, ``size`` [m],
        ``median``, ``median_low``, ``median_high``, ``status``.
    label : str
        Intensity measure with its unit (the median is in it).
    reference, colors, ci
        As :func:`plot_fragility`.

    Returns
    -------
    matplotlib.figure.Figure
        Per engine with at least one "ok" fit an error-bar series (gid
        "median:ENGINE"); medians of fits that are not "ok" but still report a
        value (a step) are open markers without bars (gid "not-a-fit:ENGINE"),
        and sizes without a median are left out.
    """
    names = _engine_order([str(f.engine) for f in fits], reference)
    colors = dict(colors) if colors is not None else engine_colors(names, reference)
    sizes = np.array(sorted({json_number(f.size) for f in fits}), dtype=float)
    sizes = sizes[np.isfinite(sizes)]
    log_x = _use_log(sizes) or (sizes.size > 2 and float(sizes.max() / sizes.min()) >= 3.0)
    # Sizes are few and far apart (a factor 2 or more): a narrower spread keeps each point near its size.
    shift = _offsets(sizes if sizes.size else np.array([1.0]), len(names), log_x or sizes.size == 0, _SPREAD / 3)

    fig = Figure(figsize=(7.2, 4.6), layout="constrained")
    ax = fig.add_subplot()
    medians = []
    open_drawn = False
    for k, name in enumerate(names):
        drawn, has_open = _size_series(ax, fits, name, shift[k], colors.get(name, "#444444"), name == reference)
        medians.extend(drawn)
        open_drawn = open_drawn or has_open
    if log_x:
        _log_x_at(ax, sizes)
    if _use_log(medians) or log_x:
        # a size effect is a power law: straight on log-log axes; ticks as plain numbers, not 4 x 10^0
        ax.set_yscale("log")
        ax.yaxis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 1.5, 2.0, 3.0, 5.0, 7.0)))
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v:g}"))
        ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("prototype height [m]")
    ax.set_ylabel(f"median capacity: {label}")
    ax.set_title(f"Size effect: fitted median with bootstrap {ci:.0%} interval", fontsize=11)
    ax.grid(True, alpha=0.3)
    if open_drawn:
        # A proxy entry explains the open markers once instead of once per engine.
        ax.plot([], [], ls="none", marker="o", mfc="none", color="#555555", label="open: not a lognormal fit (step)")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8, framealpha=0.9)
    return fig


def _size_series(ax, fits: Sequence[StudyFit], name: str, shift, c: str, is_reference: bool) -> tuple[list, bool]:
    """One engine of :func:`plot_size_effect`: the medians of its "ok" fits with their intervals, and those of
    its other fits that report one as open markers. Returns the values drawn (for the y scale) and whether
    open markers were drawn."""
    rows = sorted((f for f in fits if str(f.engine) == name), key=lambda f: json_number(f.size))
    x, m, lo, hi, xo, mo = [], [], [], [], [], []
    for f in rows:
        s, med = json_number(f.size), json_number(f.median)
        if not (math.isfinite(s) and math.isfinite(med) and med > 0):
            continue
        if f.ok:
            x.append(s)
            m.append(med)
            lo.append(json_number(f.median_low))
            hi.append(json_number(f.median_high))
        else:
            xo.append(s)
            mo.append(med)
    drawn = []
    if x:
        m_, lo_, hi_ = np.array(m), np.array(lo), np.array(hi)
        eb = ax.errorbar(
            shift(np.array(x)),
            m_,
            yerr=_yerr(m_, lo_, hi_),
            fmt="-o",
            ms=5,
            lw=1.8 if is_reference else 1.2,
            capsize=3,
            color=c,
            label=name,
            zorder=3,
        )
        eb.lines[0].set_gid(f"median:{name}")
        drawn.extend(m_.tolist() + lo_[np.isfinite(lo_)].tolist() + hi_[np.isfinite(hi_)].tolist())
    if xo:
        (ln,) = ax.plot(
            shift(np.array(xo)),
            mo,
            ls="none",
            marker="o",
            ms=6,
            mfc="none",
            color=c,
            label=None if x else name,
            zorder=3,
        )
        ln.set_gid(f"not-a-fit:{name}")
        drawn.extend(mo)
    return drawn, bool(xo)


# ----------------------------------------------------------------------------
# exceedance of response thresholds, one size
def plot_exceedance(
    ex: pd.DataFrame,
    size: float,
    label: str,
    *,
    reference: str | None = "housner",
    colors: Mapping[str, str] | None = None,
    ci: float = 0.95,
) -> Figure:
    """P[theta_max/alpha >= threshold] per stripe, one panel per threshold, engines as series with Wilson bars.

    Parameters
    ----------
    ex : pandas.DataFrame
        ``exceedance.parquet``: one row per (engine, size, stripe, threshold) with
        ``engine``, ``size`` [m], ``S``, ``intensity``, ``threshold``, ``n``,
        ``k``, ``p``, ``p_low``, ``p_high``.
    size, label, reference, colors, ci
        As :func:`plot_fragility`.

    Returns
    -------
    matplotlib.figure.Figure
        One axes per threshold (ascending), each with one error-bar series per
        engine that has a valid record at that size (gid "points:ENGINE").
    """
    sub, names, colors, levels, _, shift = _at_size(ex, size, (), reference, colors)
    thresholds = np.sort(sub["threshold"].dropna().unique().astype(float)) if len(sub) else np.array([])
    n = max(thresholds.size, 1)
    ncols = min(n, 3)
    nrows = math.ceil(n / ncols)
    fig = Figure(figsize=(3.9 * ncols + 0.4, 3.3 * nrows + 0.7), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False, sharey=True)
    handles: dict[str, object] = {}
    for j, t in enumerate(thresholds):
        ax = axes[j // ncols][j % ncols]
        dt = sub[np.isclose(sub["threshold"].astype(float), t)]
        for k, name in enumerate(names):
            d = dt[(dt["engine"] == name) & (dt["n"].astype(float) > 0)].sort_values("intensity")
            if not len(d):
                continue
            eb = _stripe_points(
                ax,
                d,
                shift[k],
                name,
                fmt="-o",
                ms=4,
                lw=1.6 if name == reference else 1.0,
                color=colors.get(name, "#444444"),
            )
            handles.setdefault(name, eb)
        what = " (overturn)" if t >= 1.0 else ""
        ax.set_title(rf"P[$\theta_{{max}}/\alpha \geq$ {t:g}]{what}", fontsize=10)
        ax.set_ylim(-0.02, 1.02)
        _set_intensity_axis(ax, levels, label)
        ax.grid(True, alpha=0.3)
        if j % ncols == 0:
            ax.set_ylabel("probability of exceedance [-]")
    for j in range(thresholds.size, nrows * ncols):
        axes[j // ncols][j % ncols].set_visible(thresholds.size == 0 and j == 0)
    fig.suptitle(f"Exceedance of response thresholds, {_size_title(sub, size)} (Wilson {ci:.0%} bars)", fontsize=11)
    if handles:
        # One legend below all panels: the series are the same in each, and inside they would hide points.
        fig.legend(
            list(handles.values()),
            list(handles),
            loc="outside lower center",
            ncol=min(len(handles), 5),
            fontsize=8,
            frameon=False,
        )
    return fig
