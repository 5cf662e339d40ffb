"""The figures of the diagnosis page: the error ladder, the measured and modelled theta(t), the localisation.

Each takes a :class:`housner.scenarios.diagnosis.results.Diagnosis` whose steps carry their comparisons and
returns a matplotlib Figure; the measurement is drawn black, each step of the ladder in its own colour.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from housner.free_vibration.closed_forms import half_cycle_integral
from housner.reports import figures
from housner.scenarios.diagnosis.comparison.record_comparison import on_grid

__all__ = [
    "bars_figure",
    "cdf_figure",
    "energy_figure",
    "flight_figure",
    "half_cycle_figure",
    "histories_figure",
    "history_records",
    "ladder_figure",
    "onset_figure",
    "sensor_figure",
    "step_label",
    "tilt_figure",
]

_MEASURED = "#000000"
_STEP_COLORS = ("#7f7f7f", "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd")


def _colors(steps) -> list[str]:
    return [_STEP_COLORS[i % len(_STEP_COLORS)] for i in range(len(steps))]


def step_label(step) -> str:
    return step.label()


def ladder_figure(diag) -> Figure:
    steps = diag.steps
    fig = Figure(figsize=(7.4, 3.6))
    ax = fig.add_subplot()
    x = np.arange(len(steps))
    y = np.array([s.heldout_error for s in steps])
    se = np.array([s.heldout_se if math.isfinite(s.heldout_se) else 0.0 for s in steps])
    tr = np.array([s.train_error for s in steps])
    ax.errorbar(x, y, yerr=1.96 * se, fmt="o-", color="#0b5394", capsize=4, lw=1.8, label="held-out (95 % interval)")
    ax.plot(x, tr, "s--", color="#999999", ms=4, lw=1, label="training")
    ax.axhline(
        diag.noise_floor, color="#2b6a2b", ls=":", lw=1.4, label=f"noise floor sigma/alpha = {diag.noise_floor:.4f}"
    )
    ax.set_xticks(x)
    ax.set_xticklabels(["baseline"] + [f"+ {s.added}" for s in steps[1:]], rotation=12, fontsize=8)
    ax.set_ylabel(r"time-history error [$\alpha$]")
    ax.set_yscale("log")
    ax.set_title("Error ladder", fontsize=11)
    ax.grid(True, alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    return fig


def _scatter_figure(diag, xkey: str, ykey: str, *, xlabel: str, ylabel: str, title: str, lines=None) -> Figure:
    fig = Figure(figsize=(7.4, 4.2))
    ax = fig.add_subplot()
    meas = diag.steps[0].comparison.measured
    ax.plot(getattr(meas, xkey), getattr(meas, ykey), "o", color=_MEASURED, ms=4.5, label="measured", zorder=5)
    for s, c in zip(diag.steps, _colors(diag.steps), strict=True):
        mod = s.comparison.model
        ax.plot(getattr(mod, xkey), getattr(mod, ykey), "x", color=c, ms=5, alpha=0.8, label=f"model: {step_label(s)}")
    if lines:
        for xs, ys, lab, sty in lines:
            ax.plot(xs, ys, sty, color="#555555", lw=1, label=lab)
    return figures.finish(fig, ax, xlabel, ylabel, title)


def energy_figure(diag) -> Figure:
    r_h = diag.campaign.specimen.r_housner
    return _scatter_figure(
        diag,
        "energy_amplitude",
        "energy_ratio",
        xlabel=r"amplitude before the impact $\theta_i/\alpha$ [-]",
        ylabel="energy ratio c_i [-] (seed eq. 8)",
        title="Energy ratio per impact against amplitude (free vibration)",
        lines=[([0, 1], [r_h, r_h], f"Housner r = {r_h:.4f}", "--")],
    )


def half_cycle_figure(diag) -> Figure:
    spec = diag.campaign.specimen
    a = np.linspace(0.05, 0.95, 60)
    T = 2.0 * np.asarray(half_cycle_integral(a * spec.alpha, spec.alpha)) / spec.p
    return _scatter_figure(
        diag,
        "half_cycle_amplitude",
        "half_cycle_duration",
        xlabel=r"half-cycle amplitude $\theta_i/\alpha$ [-]",
        ylabel="half-cycle duration [s]",
        title="Half-cycle duration against amplitude (free vibration)",
        lines=[(a, T, f"Housner, p = {spec.p:.4f} 1/s (exact eq. 7)", "--")],
    )


def flight_figure(diag) -> Figure:
    return _scatter_figure(
        diag,
        "flight_amplitude",
        "flight_ratio",
        xlabel=r"half-cycle amplitude $\theta_i/\alpha$ [-]",
        ylabel="(speed at closing / opening impact)$^2$ [-]",
        title="Energy kept between impacts (free vibration)",
        lines=[([0, 1], [1, 1], "no loss between impacts (Housner)", "--")],
    )


def onset_figure(diag) -> Figure:
    fig = Figure(figsize=(7.4, 4.2))
    ax = fig.add_subplot()
    sources = [("measured", diag.steps[0].comparison.measured, _MEASURED)] + [
        (f"model: {step_label(s)}", s.comparison.model, c) for s, c in zip(diag.steps, _colors(diag.steps), strict=True)
    ]
    width = 0.8 / len(sources)
    for k, (lab, f, c) in enumerate(sources):
        for j, (sgn, key_st) in enumerate(((1, "withstood_pos"), (-1, "withstood_neg"))):
            on = f.onset_ratio[(f.onset_sign == sgn) & np.isfinite(f.onset_ratio)]
            st = getattr(f, key_st)
            st = st[np.isfinite(st)]
            x0 = j * 2 + (k - (len(sources) - 1) / 2) * width
            ax.plot(np.full(on.size, x0), on, "^", color=c, ms=4, alpha=0.6)
            ax.plot(np.full(st.size, x0 + 1), st, "v", color=c, ms=4, alpha=0.6)
            for xx, v in ((x0, on), (x0 + 1, st)):
                if v.size:
                    ax.plot([xx - width / 2, xx + width / 2], [np.median(v)] * 2, color=c, lw=2.5)
        ax.plot([], [], "s", color=c, label=lab)
    ax.axhline(1.0, color="#555555", ls="--", lw=1, label=r"$g\tan\alpha$ (Housner)")
    ax.set_xticks([0, 1, 2, 3])
    ax.set_xticklabels(
        ["onset toward +theta", "stood toward +theta", "onset toward -theta", "stood toward -theta"], fontsize=8
    )
    ax.set_ylabel(r"ground acceleration / $g\tan\alpha$ [-]")
    ax.set_title("Uplift onset per direction (ground motion; bars: medians)", fontsize=11)
    ax.grid(True, alpha=0.3, axis="y")
    ax.legend(fontsize=7.5)
    fig.tight_layout()
    return fig


def bars_figure(diag, keys: list[tuple[str, str]], title: str, ylabel: str, ref: float | None = None) -> Figure:
    fig = Figure(figsize=(7.4, 3.8))
    ax = fig.add_subplot()
    loc0 = diag.steps[0].comparison.localisation()
    sources = [("measured", _MEASURED, lambda k: loc0[k][0])] + [
        (f"model: {step_label(s)}", c, (lambda k, s=s: s.comparison.localisation()[k][1]))
        for s, c in zip(diag.steps, _colors(diag.steps), strict=True)
    ]
    width = 0.8 / len(sources)
    for k, (lab, c, get) in enumerate(sources):
        for j, (key, _name) in enumerate(keys):
            m = get(key)
            x = j + (k - (len(sources) - 1) / 2) * width
            if math.isfinite(m.value):
                err = 1.96 * m.se if math.isfinite(m.se) else 0.0
                ax.bar(x, m.value, width * 0.9, color=c, alpha=0.75, label=lab if j == 0 else None)
                ax.errorbar(x, m.value, yerr=err, color="#333333", capsize=3, lw=1)
    if ref is not None:
        ax.axhline(ref, color="#555555", ls="--", lw=1)
    ax.set_xticks(range(len(keys)))
    ax.set_xticklabels([n for _k, n in keys], fontsize=8)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=11)
    ax.grid(True, alpha=0.3, axis="y")
    ax.legend(fontsize=7.5)
    fig.tight_layout()
    return fig


def tilt_figure(diag) -> Figure:
    fig = Figure(figsize=(7.4, 4.2))
    ax = fig.add_subplot()
    meas = diag.steps[0].comparison.measured
    n = meas.tilt_acc.size
    step = max(1, n // 4000)
    ax.plot(meas.tilt_acc[::step], meas.tilt_theta[::step], ".", color="#bbbbbb", ms=2, label="measured samples")
    xs = np.array([-1.0, 1.0])
    o, k = meas.tilt_line()
    if math.isfinite(o.value):
        ax.plot(xs, o.value + k.value * xs, color=_MEASURED, lw=2.2, label="measured fit")
    for s, c in zip(diag.steps, _colors(diag.steps), strict=True):
        o, k = s.comparison.model.tilt_line()
        if math.isfinite(o.value):
            ax.plot(xs, o.value + k.value * xs, color=c, lw=1.4, ls="--", label=f"model: {step_label(s)}")
    sd = float(np.std(meas.tilt_theta)) if n else 0.01
    ax.set_ylim(-4 * sd - 0.01, 4 * sd + 0.01)
    return figures.finish(
        fig,
        ax,
        r"ground acceleration / $g\tan\alpha$ [-]",
        r"$\theta/\alpha$ before uplift [-]",
        "Rotation before uplift (while |ground acc.| < g tan alpha)",
    )


def sensor_figure(diag) -> Figure | None:
    """The theta sensor's noise as measured on the quiet samples: its autocorrelation against lag, beside white
    noise's (1 at lag 0, 0 beyond); None when it was not measured."""
    sensor = getattr(diag.campaign, "sensor", None)
    if sensor is None or sensor.noise.n_samples == 0:
        return None
    noise = sensor.noise
    fig = Figure(figsize=(7.4, 3.6))
    ax = fig.add_subplot()
    if noise.white:
        ax.axhline(0.0, color=_MEASURED, lw=1.6, label="measured: white (no correlation told apart)")
    else:
        lags = np.arange(noise.rho.size) * noise.dt * 1e3
        ax.plot(
            lags,
            noise.rho,
            color=_MEASURED,
            lw=1.6,
            label=f"measured (correlation time {noise.correlation_time * 1e3:.3g} ms)",
        )
    ax.plot([0.0], [1.0], "o", color="#1f77b4", label="white noise: 1 at lag 0, 0 beyond")
    ax.axhline(0.0, color="#1f77b4", lw=0.8, ls="--")
    return figures.finish(
        fig,
        ax,
        "lag [ms]",
        "autocorrelation of the noise [-]",
        f"The theta sensor's noise: sigma {noise.sigma * 1e3:.3g} mrad on {noise.n_samples} quiet samples",
    )


def cdf_figure(diag) -> Figure:
    dist0 = diag.steps[0].comparison.distribution
    samples = {"measured": dist0.measured}
    colors = {"measured": _MEASURED}
    for s, c in zip(diag.steps, _colors(diag.steps), strict=True):
        name = f"model: {step_label(s)}"
        samples[name] = s.comparison.distribution.model
        colors[name] = c
    return figures.plot_cdfs(samples, reference="measured", colors=colors)


def _heldout(diag, step, compared) -> dict[str, float]:
    """Record id -> ``step``'s held-out (out-of-fold) error [alpha]; the errors of ``compared``'s comparison
    when it has none."""
    if step.heldout_errors is not None and len(step.heldout_errors) == len(diag.heldout_ids):
        return {rid: float(e) for rid, e in zip(diag.heldout_ids, step.heldout_errors, strict=True)}
    return {r.id: float(r.error) for r in compared.comparison.records}


def _final_heldout(diag) -> dict[str, float]:
    """Record id -> the final model's held-out (out-of-fold) error [alpha]; the comparison's error when absent."""
    return _heldout(diag, diag.final, diag.final)


def _baseline_heldout(diag) -> dict[str, float]:
    return _heldout(diag, diag.baseline, diag.steps[0])


def history_records(diag) -> list[tuple[str, str]]:
    """The records the top figure shows: (record id, role) for the worst and the median ground motion (by the
    final model's held-out error) and the free vibration the final model fits worst (each when the campaign
    has one)."""
    err = _final_heldout(diag)
    out: list[tuple[str, str]] = []
    gm = sorted((err[r.id], r.id) for r in diag.campaign.ground_motion if math.isfinite(err.get(r.id, math.nan)))
    if gm:
        out.append((gm[-1][1], "worst ground motion"))
        if len(gm) > 1:
            med = gm[(len(gm) - 1) // 2][1]
            out.append((med if med != gm[-1][1] else gm[-2][1], "median ground motion"))
    fv = sorted((err[r.id], r.id) for r in diag.campaign.free_vibration if math.isfinite(err.get(r.id, math.nan)))
    if fv:
        out.append((fv[-1][1], "free vibration"))
    return out


def histories_figure(diag) -> Figure | None:
    """theta/alpha against time: measured, the plain Housner model (before) and the final model (after)."""
    picks = history_records(diag)
    if not picks:
        return None
    alpha = diag.campaign.specimen.alpha
    before = {r.id: r for r in diag.steps[0].comparison.records}
    after = {r.id: r for r in diag.final.comparison.records} if len(diag.steps) > 1 else {}
    e_before, e_after = _baseline_heldout(diag), _final_heldout(diag)
    c_before, c_after = _colors(diag.steps)[0], _colors(diag.steps)[-1]
    lab_after = "after: Housner + " + " + ".join(diag.final.names)
    # constrained layout with the legend "outside": the layout makes room for it, whatever its labels' length
    fig = Figure(figsize=(7.8, 2.15 * len(picks) + 0.7), layout="constrained")
    axes = fig.subplots(len(picks), 1, squeeze=False)[:, 0]
    for ax, (rid, role) in zip(axes, picks, strict=True):
        rec = diag.campaign.record(rid)
        t = rec.t
        ys = [rec.theta / alpha]
        styles = (
            (before.get(rid), "before: Housner (plain)", dict(color=c_before, lw=1.3, ls="--", alpha=0.9, zorder=2)),
            (after.get(rid), lab_after, dict(color=c_after, lw=2.6, alpha=0.55, zorder=1)),
        )
        for rc, lab, style in styles:
            if rc is None or rc.response is None:
                continue
            y = on_grid(rc.response, rec) / alpha
            ys.append(y)
            ax.plot(t, y, label=lab, **style)
        # the measurement on top, thin: where the final model fits, it runs inside the model's band
        ax.plot(t, rec.theta / alpha, color=_MEASURED, lw=0.8, zorder=3, label="measured")
        ax.axvline(before[rid].window_end, color="#a94442", lw=0.8, ls=":", label="end of the error window")
        for sgn in (-1, 1):
            ax.axhline(sgn, color="#a94442", lw=0.5, ls="--", alpha=0.5)
        peak = max(float(np.nanmax(np.abs(y))) for y in ys if y.size)
        lim = min(1.6, max(1.1, 1.05 * peak))
        ax.set_ylim(-lim, lim)
        end = float(t[-1])
        if not rec.is_free_vibration:  # past the window the records are chaotic and not scored
            end = min(end, before[rid].window_end + 1.5)
        ax.set_xlim(float(t[0]), end)
        errs = f"held-out error {_txt(e_before.get(rid))}"
        if after:
            errs += f" before, {_txt(e_after.get(rid))} after"
        over = " (overturned)" if rec.overturned else ""
        ax.set_title(f"{rid}, {role}{over}: {errs} [$\\alpha$]", fontsize=9, loc="left")
        ax.set_ylabel(r"$\theta/\alpha$ [-]")
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("t [s]" + (" (free vibration: from the release)" if picks[-1][1] == "free vibration" else ""))
    handles, labels = axes[0].get_legend_handles_labels()
    order = sorted(range(len(labels)), key=lambda i: labels[i] != "measured")  # the measurement first
    # one row when the labels fit the figure's width (about 110 characters at 8 pt on 7.8 in), else two columns
    ncol = min(len(labels), 4) if sum(len(lab) + 8 for lab in labels) <= 110 else 2
    fig.legend(
        [handles[i] for i in order],
        [labels[i] for i in order],
        loc="outside upper center",
        ncol=ncol,
        fontsize=8,
        frameon=False,
    )
    return fig


def _txt(v) -> str:
    return "n/a" if v is None or not math.isfinite(v) else f"{v:.3g}"
