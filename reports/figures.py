"""Figures of a scenario run, drawn with matplotlib's object API (no pyplot, no global state).

Every function returns a :class:`matplotlib.figure.Figure`; :func:`to_png_base64`
turns one into the base64 PNG that the HTML report embeds. The quantity
plotted throughout is the peak rotation normalised by the slenderness,
theta_max / alpha [-], with an overturned block written as ``+inf`` (as in
:mod:`housner.statistics.ensemble_stats`); overturns are drawn at a marked edge of each plot
rather than dropped.

References
----------
Bachmann, J. A., Strand, M., Vassiliou, M. F., Broccardo, M., Stojadinovic, B.
(2017). Probabilistic validation of the Housner rocking model. COMPDYN 2017,
Fig. 2 (rocking spectrum), Fig. 5 (free vibration), Fig. 9 (time histories),
Fig. 10 (CDF of theta_max/alpha).
"""

from __future__ import annotations

import base64
import io
import math
from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

from housner.pulse_response.spectra import draw_spectrum
from housner.statistics import ensemble_stats as stats

__all__ = [
    "engine_colors",
    "finish",
    "plot_agreement_scatter",
    "plot_cdfs",
    "plot_energy_ratios",
    "plot_free_vibration",
    "plot_histories",
    "plot_rocking_spectra",
    "plot_tuning",
    "to_png_base64",
]

#: Colours of the engines after the reference (which is drawn in black).
_PALETTE = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#7f7f7f")
_REFERENCE_COLOR = "#000000"

#: Resolution of the embedded PNGs [dots per inch]; 110 keeps labels sharp at the
#: page width (about 800 px) while a figure stays below ~150 kB.
_DPI = 110
_MAX_WIDTH_PX = 1150


def engine_colors(names: Sequence[str], reference: str | None = None) -> dict[str, str]:
    """A fixed colour per engine: the reference in black, the others from a palette in order.

    Parameters
    ----------
    names : sequence of str
        Engine names in the order of the report.
    reference : str, optional
        The reference engine.
    """
    out: dict[str, str] = {}
    k = 0
    for name in names:
        if name == reference:
            out[name] = _REFERENCE_COLOR
        else:
            out[name] = _PALETTE[k % len(_PALETTE)]
            k += 1
    return out


def to_png_base64(fig: Figure, dpi: int = _DPI) -> str:
    """The figure as a base64-encoded PNG (ASCII), ready for a ``data:image/png;base64,`` URI.

    Wide figures get a lower resolution so that no PNG is wider than the page
    (about 1150 px): more pixels would only cost time and bytes.
    """
    dpi = min(dpi, _MAX_WIDTH_PX / fig.get_figwidth())
    buf = io.BytesIO()
    # Layouts are set by each figure (tight or constrained), so no second "tight bbox" draw is needed.
    fig.savefig(buf, format="png", dpi=dpi, metadata={"Software": None})
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _colors(names, colors, reference):
    return dict(colors) if colors is not None else engine_colors(list(names), reference)


# ----------------------------------------------------------------------------
# distributions
def finish(fig, ax, xlabel: str, ylabel: str, title: str, *, legend_size: float = 7.5):
    """Label a single-axes figure, grid it, put the legend in its best corner and fit the layout; returns ``fig``."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=11)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=legend_size)
    fig.tight_layout()
    return fig


def plot_cdfs(
    samples: Mapping[str, np.ndarray],
    *,
    reference: str | None = None,
    ci: float = 0.95,
    paper: Mapping[float, float] | None = None,
    colors: Mapping[str, str] | None = None,
) -> Figure:
    """Empirical CDFs of theta_max/alpha of every engine, with DKW confidence bands.

    Parameters
    ----------
    samples : mapping
        Engine name -> theta_max/alpha per record [-], ``+inf`` for an overturn
        (failed records already removed).
    reference : str, optional
        Engine drawn in black and thicker.
    ci : float
        Confidence level of the Dvoretzky-Kiefer-Wolfowitz band [-].
    paper : mapping, optional
        Percentile level [%] -> theta_max/alpha [-] from the seed paper (Table 2);
        finite values are drawn as crosses at (value, level/100).
    colors : mapping, optional
        Engine -> colour (default :func:`engine_colors`).

    Notes
    -----
    Each CDF is taken over all records, so it ends at 1 - P[overturn]; the gap to
    1 is drawn at the right edge as a vertical bar labelled "overturn", with a
    marker at the CDF's last value (seed Fig. 10).

    References
    ----------
    Bachmann et al. (2017), Fig. 10; Dvoretzky, Kiefer and Wolfowitz (1956).
    """
    colors = _colors(samples, colors, reference)
    fig = Figure(figsize=(7.6, 4.6))
    ax = fig.add_subplot()
    finite_max = max(
        (float(np.max(v[np.isfinite(v)])) for v in samples.values() if np.any(np.isfinite(v))), default=1.0
    )
    # The overturn edge sits a little right of the largest finite response and
    # never left of theta/alpha = 1.1, so curves do not collide with it.
    edge = max(1.1, finite_max) * 1.08
    names = [n for n, v in samples.items() if np.asarray(v).size]
    # Each engine's overturn bar gets its own slot inside the edge strip, so bars and markers do not overlap.
    slot = 0.035 * edge / max(len(names), 1)
    for k, name in enumerate(names):
        c = colors.get(name, _PALETTE[k % len(_PALETTE)])
        filled = name == reference or reference not in names
        _draw_cdf(
            ax, samples[name], name, c, ci, edge, edge + (k + 0.5) * slot, reference=name == reference, filled=filled
        )
    if paper:
        pts = [(float(v), float(q) / 100.0) for q, v in paper.items() if _finite_number(v)]
        if pts:
            px, py = zip(*pts, strict=True)
            ax.plot(px, py, ls="none", marker="X", ms=9, mec="white", mfc="#444444", label="seed Table 2 (numerical)")
    ax.axvline(1.0, color="#999999", lw=0.8, ls=":", label=r"$\theta/\alpha$ = 1: centre of mass over the pivot")
    right = edge + 0.06 * edge
    ax.axvspan(
        edge - 0.005 * edge,
        right,
        color="#f2dede",
        zorder=0,
        label="overturned: bar from the CDF's end to 1 = P[overturn]",
    )
    ax.text(right - 0.012 * edge, 0.02, "overturn", rotation=90, ha="center", va="bottom", fontsize=8, color="#a94442")
    ax.set_xlim(0.0, right)
    ax.set_ylim(0.0, 1.02)
    ax.set_xlabel(r"$\theta_{max}/\alpha$ [-]")
    ax.set_ylabel("cumulative probability [-]")
    ax.set_title(rf"CDF of $\theta_{{max}}/\alpha$ with {ci:.0%} DKW bands", fontsize=11)
    ax.grid(True, alpha=0.3)
    # Lower right, the emptiest corner of a CDF, but left of the overturn strip so that its label stays visible.
    ax.legend(loc="lower right", bbox_to_anchor=(0.99 * edge / right - 0.01, 0.0), fontsize=8, framealpha=0.9)
    fig.tight_layout()
    return fig


def _draw_cdf(
    ax, values, name: str, c: str, ci: float, edge: float, xe: float, *, reference: bool, filled: bool
) -> None:
    """One engine's empirical CDF of theta_max/alpha, run on to ``edge``, with its DKW band (``filled``, or
    its two edges dashed) and its overturn atom: a bar from the CDF's end to 1 at ``xe``, a marker at its foot."""
    v = np.asarray(values, dtype=np.float64)
    e = stats.ecdf(v)
    lo, hi = e.band(ci)
    last = e.F[-1] if e.F.size else 0.0
    x = np.concatenate(([0.0], e.x, [edge]))
    F = np.concatenate(([0.0], e.F, [last]))
    eps = float(hi[0] - e.F[0]) if e.F.size else 0.0
    lo = np.concatenate(([0.0], lo, [lo[-1] if lo.size else 0.0]))
    hi = np.concatenate(([min(eps, 1.0)], hi, [hi[-1] if hi.size else 0.0]))
    label = f"{name} (n={e.n}, P[overturn]={e.p_overturn:.2f})" + (" - reference" if reference else "")
    if filled:
        # One filled band (the reference's) keeps the plot readable; the others get band edges.
        ax.fill_between(x, lo, hi, step="post", color=c, alpha=0.10, linewidth=0)
    else:
        for b in (lo, hi):
            ax.step(x, b, where="post", color=c, lw=0.7, ls=(0, (2, 2)), alpha=0.7)
    ax.step(x, F, where="post", color=c, lw=2.2 if reference else 1.6, label=label)
    # The overturn atom: the CDF's gap to 1, drawn at the right edge with a marker at its foot.
    if e.p_overturn > 0:
        ax.plot([xe, xe], [last, 1.0], color=c, lw=3.0, solid_capstyle="butt", zorder=4)
    ax.plot([xe], [last], marker="o" if reference else "D", color=c, ms=6, mec="white", clip_on=False, zorder=5)


def _finite_number(v) -> bool:
    try:
        return math.isfinite(float(v))
    except (TypeError, ValueError):
        return False


def plot_agreement_scatter(
    pairs: Mapping[str, tuple[np.ndarray, np.ndarray]],
    reference: str,
    *,
    rtol: float = 0.03,
    colors: Mapping[str, str] | None = None,
) -> Figure:
    """Record-by-record theta_max/alpha of each engine against the reference.

    Parameters
    ----------
    pairs : mapping
        Engine -> (engine values, reference values) [-] on the same motions,
        ``+inf`` for an overturn.
    reference : str
        Name of the reference engine (the x axis).
    rtol : float
        Relative band drawn around the diagonal [-].
    colors : mapping, optional
        Engine -> colour.

    Notes
    -----
    Overturned records are drawn on a shaded edge strip beyond the largest
    finite value: at the top when the engine overturned, at the right when the
    reference did, in the corner when both did.
    """
    colors = _colors(list(pairs), colors, reference)
    fig = Figure(figsize=(6.6, 6.0))
    ax = fig.add_subplot()
    finite = [v[np.isfinite(v)] for a, b in pairs.values() for v in (a, b)]
    top = max((float(f.max()) for f in finite if f.size), default=1.0)
    top = max(top, 0.2)
    edge = top * 1.15
    for name, (a, b) in pairs.items():
        oa, ob = np.isposinf(a), np.isposinf(b)
        # Points pile up in the overturn strips, so the legend counts them.
        label = f"{name} (overturned: both {int(np.sum(oa & ob))}, engine only {int(np.sum(oa & ~ob))}, "
        label += f"reference only {int(np.sum(ob & ~oa))})"
        ax.plot(
            np.where(ob, edge, b),
            np.where(oa, edge, a),
            ls="none",
            marker="o",
            ms=4.5,
            alpha=0.7,
            color=colors.get(name),
            label=label,
        )
    d = np.array([0.0, top * 1.05])
    ax.plot(d, d, color="#555555", lw=1)
    ax.fill_between(d, d * (1 - rtol), d * (1 + rtol), color="#999999", alpha=0.25, lw=0, label=f"within {rtol:.0%}")
    for span in (ax.axvspan, ax.axhspan):
        span(top * 1.08, top * 1.22, color="#f2dede", zorder=0)
    ax.text(edge, top * 0.02, "overturned", rotation=90, ha="center", va="bottom", fontsize=8, color="#a94442")
    ax.text(top * 0.02, edge, "overturned", ha="left", va="center", fontsize=8, color="#a94442")
    ax.set_xlim(0, top * 1.22)
    ax.set_ylim(0, top * 1.22)
    ax.set_aspect("equal")
    ax.set_xlabel(rf"{reference}: $\theta_{{max}}/\alpha$ [-]")
    ax.set_ylabel(r"engine: $\theta_{max}/\alpha$ [-]")
    ax.set_title("Record by record against the reference", fontsize=11)
    ax.grid(True, alpha=0.3)
    # Below the axes: with a hundred records any corner inside would hide points.
    ax.legend(loc="upper center", fontsize=8, bbox_to_anchor=(0.5, -0.13), frameon=False)
    fig.tight_layout()
    return fig


# ----------------------------------------------------------------------------
# time histories
def plot_histories(
    panels: Sequence[tuple[str, Mapping[str, tuple[np.ndarray, np.ndarray]]]],
    *,
    reference: str | None = None,
    colors: Mapping[str, str] | None = None,
    ylim: float = 1.6,
    ncols: int = 1,
) -> Figure:
    """theta/alpha against time for several records, all engines overlaid in each panel.

    Parameters
    ----------
    panels : sequence of (title, mapping)
        One panel per record: title and engine -> (t [s], theta/alpha [-]).
    reference : str, optional
        Engine drawn in black, underneath the others.
    colors : mapping, optional
        Engine -> colour.
    ylim : float
        Largest half-span of the y axis [-]; each panel spans just beyond its
        largest |theta/alpha| and beyond +-1, up to this. An overturned block
        (held at +-pi/2) leaves the panel at the edge.
    ncols : int
        Panels per row.

    References
    ----------
    Bachmann et al. (2017), Figs. 5 and 9.
    """
    names = list(dict.fromkeys(n for _, d in panels for n in d))
    colors = _colors(names, colors, reference)
    n = max(len(panels), 1)
    ncols = max(1, min(ncols, n))
    nrows = math.ceil(n / ncols)
    fig = Figure(figsize=(7.8 if ncols == 1 else 4.0 * ncols, 2.1 * nrows + 0.6))
    axes = fig.subplots(nrows, ncols, squeeze=False, sharex=False)
    for k, (title, data) in enumerate(panels):
        ax = axes[k // ncols][k % ncols]
        order = sorted(data, key=lambda e: e != reference)  # reference first, underneath
        for name in order:
            t, y = data[name]
            is_ref = name == reference
            ax.plot(t, y, color=colors.get(name), lw=1.6 if is_ref else 1.0, alpha=0.9, label=name)
        for s in (-1, 1):
            ax.axhline(s, color="#a94442", lw=0.7, ls="--")
        ax.axhline(0, color="#999999", lw=0.5)
        peak = max((float(np.max(np.abs(y))) for _, y in data.values() if np.size(y)), default=1.0)
        lim = min(ylim, max(1.1, 1.05 * peak))
        ax.set_ylim(-lim, lim)
        ax.set_title(title, fontsize=9, loc="left")
        ax.set_ylabel(r"$\theta/\alpha$ [-]")
        ax.grid(True, alpha=0.3)
    for k in range(len(panels), nrows * ncols):
        axes[k // ncols][k % ncols].set_visible(False)
    for c in range(ncols):
        axes[-1][c].set_xlabel("t [s]")
    if panels:
        handles, labels = axes[0][0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="upper center", ncol=min(len(labels), 5), fontsize=8, frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.35 / fig.get_figheight()))
    return fig


def plot_free_vibration(
    releases: Sequence[tuple[float, Mapping[str, tuple[np.ndarray, np.ndarray]]]],
    *,
    reference: str | None = None,
    colors: Mapping[str, str] | None = None,
) -> Figure:
    """Free rocking after a release from rest: theta/alpha against time, one panel per release amplitude.

    Parameters
    ----------
    releases : sequence of (theta0/alpha, mapping)
        Release amplitude [-] and engine -> (t [s], theta/alpha [-]).
    reference, colors
        As in :func:`plot_histories`.

    References
    ----------
    Bachmann et al. (2017), Fig. 5.
    """
    panels = [(rf"released at $\theta_0/\alpha$ = {a:.2f}", d) for a, d in releases]
    return plot_histories(panels, reference=reference, colors=colors, ylim=1.05, ncols=2 if len(panels) > 2 else 1)


def plot_energy_ratios(
    data: Mapping[str, tuple[np.ndarray, np.ndarray]],
    *,
    r_housner: float | None = None,
    reference: str | None = None,
    colors: Mapping[str, str] | None = None,
) -> Figure:
    """Kinetic-energy ratio per impact against the amplitude before the impact.

    Parameters
    ----------
    data : mapping
        Engine -> (theta_i/alpha [-], r_i [-]): the peak before impact i,
        normalised, and the energy ratio of that impact (seed eq. 8).
    r_housner : float, optional
        Housner's r of the specimen [-], drawn as a horizontal line.
    reference, colors
        As in :func:`plot_cdfs`.

    References
    ----------
    Bachmann et al. (2017), eq. 8 and Table 1.
    """
    colors = _colors(list(data), colors, reference)
    fig = Figure(figsize=(7.0, 4.0))
    ax = fig.add_subplot()
    for name, (amp, r) in data.items():
        amp, r = np.asarray(amp, dtype=float), np.asarray(r, dtype=float)
        ok = np.isfinite(amp) & np.isfinite(r)
        ax.plot(
            amp[ok],
            r[ok],
            ls="none",
            marker="o" if name == reference else ".",
            ms=5,
            color=colors.get(name),
            alpha=0.75,
            label=name,
        )
    if r_housner is not None:
        ax.axhline(r_housner, color="#555555", ls="--", lw=1, label=f"Housner r = {r_housner:.4f}")
    return finish(
        fig,
        ax,
        r"peak before the impact $\theta_i/\alpha$ [-]",
        r"energy ratio $r_i$ [-]",
        "Energy ratio per impact (seed eq. 8)",
        legend_size=8,
    )


def plot_tuning(
    curves: Mapping[str, Mapping[str, tuple[np.ndarray, np.ndarray]] | tuple[np.ndarray, np.ndarray]],
    *,
    target_r: float | None = None,
    bands: Sequence[tuple[float, float, float]] = (),
    decay: Mapping[str, Mapping[str, tuple[np.ndarray, np.ndarray]]] | None = None,
    decay_rtol: float | None = None,
    decay_start: float | None = None,
    colors: Mapping[str, str] | None = None,
) -> Figure:
    """Tuned engines: kinetic-energy ratio r against release amplitude, and the free-decay check.

    Parameters
    ----------
    curves : mapping
        Engine -> {series label -> (theta0/alpha [-], r [-])}, one series per
        way the tuner measured (e.g. per sample step); a bare (theta0/alpha, r)
        pair is one unnamed series. Each series is drawn as one line sorted by
        amplitude, the engine's colour, one line style per series label.
    target_r : float, optional
        The r the tuning aimed at [-].
    bands : sequence of (amplitude low, amplitude high, rtol)
        Accepted |r / target_r - 1| over amplitude ranges, drawn as grey bands
        around the target.
    decay : mapping, optional
        Engine -> {series label -> (impacts, peak_engine / peak_analytic - 1)}
        of a free decay; drawn in a second panel.
    decay_rtol : float, optional
        Accepted relative error of the decay peaks [-].
    decay_start : float, optional
        Release amplitude of the decay, theta0/alpha [-] (for the title).
    """
    colors = _colors(list(curves), colors, None)
    styles = (("-", "o"), ("--", "s"), (":", "^"), ("-.", "v"))
    labels = list(dict.fromkeys(lab for c in curves.values() if isinstance(c, Mapping) for lab in c))
    style = {lab: styles[k % len(styles)] for k, lab in enumerate(labels)}
    has_decay = bool(decay) and any(decay.values())
    fig = Figure(figsize=(9.6, 4.6) if has_decay else (6.8, 4.6), layout="constrained")
    if has_decay:
        ax, axd = fig.subplots(1, 2, gridspec_kw={"width_ratios": (1.7, 1.0)})
    else:
        ax, axd = fig.add_subplot(), None
    handles: dict[str, object] = {}
    if target_r is not None:
        _draw_target_r(ax, target_r, bands, handles)

    def line(axis, x, y, name, lab, ms):
        ls, marker = style.get(lab, ("-", "o"))
        (h,) = axis.plot(x, y, ls=ls, marker=marker, ms=ms, lw=0.8, alpha=0.85, color=colors.get(name))
        handles.setdefault(f"{name}, {lab}" if lab else name, h)

    for name, c in curves.items():
        series = c if isinstance(c, Mapping) else {"": c}
        for lab, (a, r) in series.items():
            a, r = np.asarray(a, dtype=float), np.asarray(r, dtype=float)
            ok = np.isfinite(a) & np.isfinite(r)
            order = np.argsort(a[ok], kind="stable")
            line(ax, a[ok][order], r[ok][order], name, lab, 2.8)
    ax.set_xlabel(r"release amplitude $\theta_0/\alpha$ [-]")
    ax.set_ylabel("r of the first impact [-]")
    ax.set_title("Tuned contact: r against amplitude", fontsize=11)
    ax.grid(True, alpha=0.3)
    if axd is not None:
        _draw_decay_panel(axd, decay, decay_rtol, decay_start, handles, line)
    # One legend for both panels, below them: the series are the same in each, and inside they hide points.
    fig.legend(list(handles.values()), list(handles), loc="outside lower center", ncol=3, fontsize=8, frameon=False)
    return fig


def _draw_target_r(ax, target_r: float, bands: Sequence[tuple[float, float, float]], handles: dict) -> None:
    """The accepted bands about the target r (grey) and the target itself (dashed), their legend entries
    added to ``handles``."""
    for lo, hi, tol in bands:
        h = ax.fill_between([lo, hi], target_r * (1 - tol), target_r * (1 + tol), color="#999999", alpha=0.18, lw=0)
        handles.setdefault(f"accepted: $\\pm${tol:.1%} of the target at {lo:g}-{hi:g} $\\alpha$", h)
    handles[f"target r = {target_r:.4f}"] = ax.axhline(target_r, color="#555555", ls="--", lw=1)


def _draw_decay_panel(
    axd, decay: Mapping, decay_rtol: float | None, decay_start: float | None, handles: dict, line
) -> None:
    """The free-decay panel of :func:`plot_tuning`: each series' peak error [%] against the impact, sorted by
    impact and drawn by ``line`` (as the r panel's), with the accepted band."""
    if decay_rtol is not None:
        h = axd.axhspan(-100 * decay_rtol, 100 * decay_rtol, color="#999999", alpha=0.18, lw=0, ec="none")
        handles[f"free decay accepted: $\\pm${decay_rtol:.0%}"] = h
    axd.axhline(0.0, color="#555555", ls="--", lw=1)
    for name, series in decay.items():
        for lab, (k, e) in series.items():
            k, e = np.asarray(k, dtype=float), np.asarray(e, dtype=float)
            order = np.argsort(k, kind="stable")
            line(axd, k[order], 100 * e[order], name, lab, 4.0)
    axd.set_xlabel("impacts after the release")
    axd.set_ylabel("peak: engine / analytic - 1 [%]")
    start = rf" from {decay_start:g} $\alpha$" if decay_start is not None else ""
    axd.set_title(f"Free decay{start}", fontsize=11)
    axd.grid(True, alpha=0.3)


# ----------------------------------------------------------------------------
# rocking spectra
def plot_rocking_spectra(
    omega_ratio: np.ndarray,
    accel_ratio: np.ndarray,
    values: Mapping[str, np.ndarray],
    *,
    title: str = "",
) -> Figure:
    """Rocking spectra: contours of theta_max/alpha over omega_p/p and a_p/(g tan alpha), one panel per engine.

    Parameters
    ----------
    omega_ratio, accel_ratio : ndarray
        omega_p / p [-] and a_p / (g tan alpha) [-] of each motion.
    values : mapping
        Engine -> theta_max/alpha per motion [-] (``+inf`` overturned, NaN failed).
    title : str
        Figure title (e.g. the pulse shape).

    Notes
    -----
    Rocking responses are filled contours on 0 .. 1; the overturn region is grey
    and its grid points are marked with crosses; failed points are open squares. On an
    irregular grid the points are drawn as coloured markers instead.

    References
    ----------
    Bachmann et al. (2017), Fig. 2 and eq. 6.
    """
    n = max(len(values), 1)
    ncols = min(n, 3)
    nrows = math.ceil(n / ncols)
    fig = Figure(figsize=(4.0 * ncols + 0.8, 3.6 * nrows + 0.4), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False)
    sm = None
    for k, (name, v) in enumerate(values.items()):
        ax = axes[k // ncols][k % ncols]
        sm = draw_spectrum(ax, omega_ratio, accel_ratio, v)
        ax.set_title(name, fontsize=10)
        ax.set_xlabel(r"$\omega_p/p$ [-]")
        ax.set_ylabel(r"$a_p/(g\,\tan\alpha)$ [-]")
    for k in range(len(values), nrows * ncols):
        axes[k // ncols][k % ncols].set_visible(False)
    if sm is not None:
        cb = fig.colorbar(sm, ax=axes.ravel().tolist(), extend="max", shrink=0.9)
        cb.set_label(r"$\theta_{max}/\alpha$ [-]; grey with crosses: overturn")
    if title:
        fig.suptitle(title, fontsize=11)
    return fig
