"""The diagnosis report: which effect the Housner model misses, and the error falling as it is added.

:func:`render_diagnosis` turns a :class:`housner.scenarios.campaigns.diagnose.Diagnosis` into
one self-contained HTML page (figures are base64 PNGs, the style sheet is
inline, no script, no network); :func:`write_diagnosis_report` writes it.

What it shows, top first: the verdict, stated once (what fails, which effect
explains it), the held-out error before (plain Housner model) and after (final
model) with their standard errors, and the effects' parameters with their
units; the measured rotation against both models for the worst and the median
ground-motion record and a free vibration; the residual against the
correct-model floor; the error
ladder (baseline, then each added effect, held-out error with its standard
error, against the noise floor); the candidates of every greedy round; the
theta_max/alpha CDFs of the measurement and of the model at every step; the
localisation figures, each with the measurement and the model at every step
side by side (energy ratio per impact and half-cycle duration against
amplitude, energy kept between impacts, uplift onset per direction,
direction bias, rotation before uplift, overturn fraction); the table of the
localisation quantities; a per-record table.

References
----------
Bachmann, J. A., Strand, M., Vassiliou, M. F., Broccardo, M., Stojadinovic, B.
(2017). Probabilistic validation of the Housner rocking model. COMPDYN 2017,
eqs. 7-8, Figs. 5 and 10.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import numpy as np
from housner.reports import figures
from housner.reports.page import Section, document, esc, html_figure, html_table, write_page
from housner.scenarios.campaigns.compare import on_grid
from housner.scenarios.campaigns.results import change_text, fmt_pm, params_text, signed_words
from matplotlib.figure import Figure

from housner.calibration import half_cycle_integral

__all__ = ["history_records", "render_diagnosis", "write_diagnosis_report"]

_MEASURED = "#000000"
_STEP_COLORS = ("#7f7f7f", "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd")


def _f(x: Any, digits: int = 4) -> str:
    try:
        v = float(x)
    except (TypeError, ValueError):
        return esc(x)
    if math.isnan(v):
        return "&ndash;"
    if math.isinf(v):
        return "overturned" if v > 0 else "&minus;&infin;"
    return f"{v:.{digits}g}" if abs(v) >= 1e4 or (v != 0 and abs(v) < 1e-3) else f"{v:.{digits}f}"


def _pm(value: Any, se: Any) -> str:
    """A value with its standard error on the page (:func:`housner.scenarios.campaigns.results.fmt_pm`)."""
    return fmt_pm(value, se, sep=" &plusmn; ", nan="&ndash;")  # digits, the separator and fixed words: no escaping


def _change(improvement: float, se: float) -> str:
    """A paired improvement in words on the page: "falls by x &plusmn; s" or "rises by x &plusmn; s"."""
    if not math.isfinite(improvement):
        return "&ndash;"
    return change_text(improvement, se, sep=" &plusmn; ")


def _params(name: str, params: dict) -> str:
    """An effect's fitted parameters with their units (each effect's ParamSpec)."""
    return esc(params_text(name, params))


def _candidate_params(c) -> str:
    """A candidate's parameters with units; a pair's are keyed ``"effect.param"``."""
    names = c.effect.split(" + ")
    if len(names) == 1:
        return _params(c.effect, c.params)
    return "; ".join(
        f"{esc(n)}: " + _params(n, {k.split(".", 1)[1]: v for k, v in c.params.items() if k.startswith(n + ".")})
        for n in names
    )


def _colors(steps) -> list[str]:
    return [_STEP_COLORS[i % len(_STEP_COLORS)] for i in range(len(steps))]


def _label(step) -> str:
    return step.label()


# ----------------------------------------------------------------------------
# figures
def _ladder_figure(diag) -> Figure:
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
        ax.plot(getattr(mod, xkey), getattr(mod, ykey), "x", color=c, ms=5, alpha=0.8, label=f"model: {_label(s)}")
    if lines:
        for xs, ys, lab, sty in lines:
            ax.plot(xs, ys, sty, color="#555555", lw=1, label=lab)
    return figures.finish(fig, ax, xlabel, ylabel, title)


def _energy_figure(diag) -> Figure:
    r_h = diag.campaign.specimen.r_housner
    return _scatter_figure(
        diag, "energy_amplitude", "energy_ratio",
        xlabel=r"amplitude before the impact $\theta_i/\alpha$ [-]", ylabel="energy ratio c_i [-] (seed eq. 8)",
        title="Energy ratio per impact against amplitude (free vibration)",
        lines=[([0, 1], [r_h, r_h], f"Housner r = {r_h:.4f}", "--")],
    )  # fmt: skip


def _half_cycle_figure(diag) -> Figure:
    spec = diag.campaign.specimen
    a = np.linspace(0.05, 0.95, 60)
    T = 2.0 * np.asarray(half_cycle_integral(a * spec.alpha, spec.alpha)) / spec.p
    return _scatter_figure(
        diag, "half_cycle_amplitude", "half_cycle_duration",
        xlabel=r"half-cycle amplitude $\theta_i/\alpha$ [-]", ylabel="half-cycle duration [s]",
        title="Half-cycle duration against amplitude (free vibration)",
        lines=[(a, T, f"Housner, p = {spec.p:.4f} 1/s (exact eq. 7)", "--")],
    )  # fmt: skip


def _flight_figure(diag) -> Figure:
    return _scatter_figure(
        diag, "flight_amplitude", "flight_ratio",
        xlabel=r"half-cycle amplitude $\theta_i/\alpha$ [-]",
        ylabel="(speed at closing / opening impact)$^2$ [-]",
        title="Energy kept between impacts (free vibration)",
        lines=[([0, 1], [1, 1], "no loss between impacts (Housner)", "--")],
    )  # fmt: skip


def _onset_figure(diag) -> Figure:
    fig = Figure(figsize=(7.4, 4.2))
    ax = fig.add_subplot()
    sources = [("measured", diag.steps[0].comparison.measured, _MEASURED)] + [
        (f"model: {_label(s)}", s.comparison.model, c) for s, c in zip(diag.steps, _colors(diag.steps), strict=True)
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


def _bars_figure(diag, keys: list[tuple[str, str]], title: str, ylabel: str, ref: float | None = None) -> Figure:
    fig = Figure(figsize=(7.4, 3.8))
    ax = fig.add_subplot()
    loc0 = diag.steps[0].comparison.localisation()
    sources = [("measured", _MEASURED, lambda k: loc0[k][0])] + [
        (f"model: {_label(s)}", c, (lambda k, s=s: s.comparison.localisation()[k][1]))
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


def _tilt_figure(diag) -> Figure:
    fig = Figure(figsize=(7.4, 4.2))
    ax = fig.add_subplot()
    meas = diag.steps[0].comparison.measured
    n = meas.tilt_acc.size
    step = max(1, n // 4000)
    ax.plot(meas.tilt_acc[::step], meas.tilt_theta[::step], ".", color="#bbbbbb", ms=2, label="measured samples")
    xs = np.array([-1.0, 1.0])
    loc0 = diag.steps[0].comparison.localisation()
    o, k = loc0["tilt_offset"][0], loc0["tilt_slope"][0]
    if math.isfinite(o.value):
        ax.plot(xs, o.value + k.value * xs, color=_MEASURED, lw=2.2, label="measured fit")
    for s, c in zip(diag.steps, _colors(diag.steps), strict=True):
        loc = s.comparison.localisation()
        o, k = loc["tilt_offset"][1], loc["tilt_slope"][1]
        if math.isfinite(o.value):
            ax.plot(xs, o.value + k.value * xs, color=c, lw=1.4, ls="--", label=f"model: {_label(s)}")
    sd = float(np.std(meas.tilt_theta)) if n else 0.01
    ax.set_ylim(-4 * sd - 0.01, 4 * sd + 0.01)
    return figures.finish(fig, ax, r"ground acceleration / $g\tan\alpha$ [-]", r"$\theta/\alpha$ before uplift [-]",
                          "Rotation before uplift (while |ground acc.| < g tan alpha)")  # fmt: skip


def _cdf_figure(diag) -> Figure:
    dist0 = diag.steps[0].comparison.distribution
    samples = {"measured": dist0.measured}
    colors = {"measured": _MEASURED}
    for s, c in zip(diag.steps, _colors(diag.steps), strict=True):
        name = f"model: {_label(s)}"
        samples[name] = s.comparison.distribution.model
        colors[name] = c
    return figures.plot_cdfs(samples, reference="measured", colors=colors)


def _final_heldout(diag) -> dict[str, float]:
    """Record id -> the final model's held-out (out-of-fold) error [alpha]; the comparison's error when absent."""
    f = diag.final
    if f.heldout_errors is not None and len(f.heldout_errors) == len(diag.heldout_ids):
        return {rid: float(e) for rid, e in zip(diag.heldout_ids, f.heldout_errors, strict=True)}
    return {r.id: float(r.error) for r in f.comparison.records}


def _baseline_heldout(diag) -> dict[str, float]:
    b = diag.baseline
    if b.heldout_errors is not None and len(b.heldout_errors) == len(diag.heldout_ids):
        return {rid: float(e) for rid, e in zip(diag.heldout_ids, b.heldout_errors, strict=True)}
    return {r.id: float(r.error) for r in diag.steps[0].comparison.records}


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


def _histories_figure(diag) -> Figure | None:
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
    fig = Figure(figsize=(7.8, 2.15 * len(picks) + 0.7))
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
    fig.legend([handles[i] for i in order], [labels[i] for i in order], loc="upper center",
               ncol=min(len(labels), 4), fontsize=8, frameon=False)  # fmt: skip
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.4 / fig.get_figheight()))
    return fig


def _txt(v) -> str:
    return "n/a" if v is None or not math.isfinite(v) else f"{v:.3g}"


# ----------------------------------------------------------------------------
# sections
_STATUS_CLASS = {"no_misfit": "ok", "explained": "ok", "partly_explained": "bad", "unexplained": "bad",
                 "inconclusive": "warn"}  # fmt: skip


def _verdict_text(v) -> str:
    """The verdict's paragraph without its leading status word (the badge before it says it), and without
    its pointer to where to look when the list under it ("Where to look next") gives every class with its
    evidence."""
    head = v.status.replace("_", " ")
    text = v.text
    if _shows_next(v) and " Where to look first: " in text:
        text = text[: text.index(" Where to look first: ")] + " Where to look: see the list below."
    if text[: len(head) + 1].lower() == head + ":":
        text = text[len(head) + 1 :].lstrip()
        text = text[:1].upper() + text[1:]
    return text


def _shows_next(v) -> bool:
    return bool(v.next) and v.status in ("partly_explained", "unexplained")


def _headline(diag) -> str:
    """The verdict (the only place the page states it), the held-out error before and after, the effects."""
    v = diag.verdict
    out = ""
    if v is not None:
        out += (f'<p class="lead"><span class="{_STATUS_CLASS.get(v.status, "")}">'
                f"{esc(v.status.replace('_', ' ').upper())}</span> &mdash; {esc(_verdict_text(v))}</p>")  # fmt: skip
    b, f = diag.baseline, diag.final
    if len(diag.steps) > 1:
        d, se = _paired_fall(diag)
        pct = 100 * diag.reduction
        verb = "falls" if pct >= 0 else "rises"
        eff = "; ".join(f"<code>{esc(n)}</code> ({_params(n, p)})" for n, p in f.effects)
        out += (
            f'<p class="lead">Held-out error {verb} by {abs(pct):.0f} %: from {_pm(b.heldout_error, b.heldout_se)} '
            f"&alpha; (plain Housner model) to {_pm(f.heldout_error, f.heldout_se)} &alpha; (with {eff}); record by "
            f"record, the error {_change(d, se)} &alpha;.</p>"
        )
    else:
        out += (
            f'<p class="lead">No effect was added: the plain Housner model\'s held-out error is '
            f"{_pm(b.heldout_error, b.heldout_se)} &alpha;.</p>"
        )
    return out


def _paired_fall(diag) -> tuple[float, float]:
    """Mean paired fall of the held-out error from the baseline to the final model [alpha], and its standard error."""
    b, f = diag.baseline, diag.final
    if b.heldout_errors is not None and f.heldout_errors is not None and len(b.heldout_errors) == len(f.heldout_errors):
        d = np.asarray(b.heldout_errors, float) - np.asarray(f.heldout_errors, float)
        d = d[np.isfinite(d)]
        if d.size > 1:
            return float(d.mean()), float(d.std(ddof=1) / math.sqrt(d.size))
    return b.heldout_error - f.heldout_error, math.hypot(b.heldout_se, f.heldout_se)


def _histories(diag) -> str:
    fig = _histories_figure(diag)
    if fig is None:
        return ""
    after = " and the final model with the chosen effects (after)" if len(diag.steps) > 1 else ""
    return html_figure(
        fig,
        "Measured rotation against the plain Housner model (before)" + after + ", for the ground-motion record "
        "with the largest held-out error of the final model, the median one, and the free-vibration record the "
        "final model fits worst. The curves are the models fitted on every record; the errors in the titles are "
        "held out (each record scored by the model fitted without its fold), over the window up to the dotted "
        "line; a ground motion is drawn to 1.5 s past it (later, chaos alone separates model and measurement).",
        "measured and modelled theta(t)",
    )


def _verdict_detail(diag) -> str:
    """The residual against the measured floor, where to look next, how stable the selection is."""
    v = diag.verdict
    if v is None:
        return ""
    rows = []
    for label, res in (("plain Housner model", v.baseline), ("final model", v.residual)):
        for kind, g in res.groups.items():
            rows.append([esc(label), esc(kind.replace("_", " ")), str(g["n"]), _f(g["error"]), _f(g["floor"]),
                         f"{g['ratio']:.2f}", f"{g['z']:+.1f}", '<span class="bad">yes</span>' if g["misfit"] else "no",
                         f"{g.get('detectable_ratio', float('nan')):.2f}"])  # fmt: skip
    from housner.scenarios.campaigns.verdict import RATIO_MISFIT, Z_LOCAL, Z_MISFIT

    table = html_table(
        ["model", "records", "n", "held-out error [alpha]", "correct-model floor", "ratio", "z", "misfit",
         "detectable ratio"],
        rows,
        caption=(
            "Held-out (out-of-fold) time-history error against the floor a correct model shows on the same records, "
            "measured by a parametric bootstrap of the fitted model (housner.scenarios.campaigns.verdict). "
            "A misfit is z > "
            f"{Z_MISFIT:g} and ratio > {RATIO_MISFIT:g}, or a localisation quantity more than {Z_LOCAL:g} "
            "standard errors from the measured one; the detectable ratio is what these records would reveal "
            "with 80 % power."
        ),
    )  # fmt: skip
    nxt = ""
    if _shows_next(v):
        items = []
        for c in v.next:
            ev = "; ".join(
                f"{esc(e['label'])}: measured {_pm(e['measured'], e['measured_se'])}, model "
                f"{_pm(e['model'], e['model_se'])} (z = {e['z']:+.1f})"
                for e in c["evidence"]
            )
            items.append(
                f"<li><b>{esc(c['class'])}</b> &mdash; {esc(c['meaning'])}<br><span class=sub>{ev}</span></li>"
            )
        nxt = "<h3>Where to look next</h3><ol>" + "".join(items) + "</ol>"
    freq = ""
    if diag.selection_frequency:
        k = diag.settings.get("folds", "?")
        cells = ", ".join(f"<code>{esc(n)}</code> {100 * f:.0f} %" for n, f in
                          sorted(diag.selection_frequency.items(), key=lambda kv: -kv[1]))  # fmt: skip
        freq = f'<p class="sub">Best candidate of its round, fold by fold ({k} folds): {cells}.</p>'
    dist = ""
    if v.distribution and not all(d in v.text for d in v.distribution):
        dist = '<p class="bad">Distributions: ' + esc("; ".join(v.distribution)) + ".</p>"
    return table + dist + nxt + freq


def _summary(diag) -> str:
    spec = diag.campaign.specimen
    c = diag.campaign
    skipped = ""
    if c.skipped:
        items = "".join(f"<li><code>{esc(rid)}</code> ({esc(f)}): {esc(msg)}</li>" for rid, f, msg in c.skipped)
        skipped = f'<p class="bad">{len(c.skipped)} record(s) skipped:</p><ul>{items}</ul>'
    return (
        _headline(diag) + _histories(diag) + _verdict_detail(diag)
        + f'<p class="sub">Specimen: 2H = {spec.height:g} m, 2B = {spec.width:g} m, m = {spec.mass:g} kg, '
        f"alpha = {spec.alpha:.4f} rad, p = {spec.p:.4f} 1/s, Housner r = {spec.r_housner:.4f}. "
        f"{len(c.free_vibration)} free-vibration and {len(c.ground_motion)} ground-motion records, "
        f"{diag.settings.get('folds', '?')}-fold cross-validation (seed {esc(diag.settings.get('seed'))}): every "
        f"record is fitted on in the other folds and held out once; sensor noise sigma/alpha "
        f"{diag.noise_floor:.2g}.</p>{skipped}"
    )  # fmt: skip


def _ladder(diag) -> str:
    rows = []
    for s in diag.steps:
        prm = "<br>".join(f"<code>{esc(n)}</code>: {_params(n, p)}" for n, p in s.effects)
        rows.append(
            [
                esc(s.label()) + (" <span class=muted>(by hand)</span>" if s.by_hand else ""),
                prm or "&ndash;",
                _pm(s.heldout_error, s.heldout_se),
                _f(s.train_error),
                "&ndash;" if s.added is None else _change(s.improvement, s.improvement_se),
                "&ndash;" if s.added is None else ('<span class="ok">yes</span>' if s.significant else "no"),
            ]
        )
    table = html_table(
        ["step", "effects (fitted parameters)", "held-out error [alpha]", "training error",
         "held-out error against the previous step [alpha]", "significant"],
        rows,
        caption=(
            "Time-history error over the measured window (see housner.scenarios.campaigns.compare), mean over every "
            "record held "
            "out once (out-of-fold) with its standard error; its change is the mean paired difference to the "
            f"previous step. The sensor noise alone (sigma/alpha) is {diag.noise_floor:.2g}; the correct-model floor "
            "the verdict uses is in the table above."
        ),
    )  # fmt: skip
    fig = html_figure(_ladder_figure(diag), "Held-out error at each step, with the noise floor.", "error ladder")
    return table + fig


def _candidates(diag) -> str:
    out = []
    for k, rnd in enumerate(diag.rounds):
        base = " + ".join(rnd[0].base) if rnd and rnd[0].base else "the plain Housner model"
        rows = [
            [
                f"<code>{esc(c.effect)}</code>",
                _candidate_params(c),
                _f(c.train_error),
                _pm(c.heldout_error, c.heldout_se),
                _change(c.improvement, c.improvement_se),
                _f(c.pvalue, 2),
                ('<span class="ok">yes</span>' if c.significant else "no")
                + f" <span class=muted>({esc(signed_words(c.reason))})</span>",
            ]
            for c in rnd
        ]  # fmt: skip
        out.append(f"<h3>Round {k + 1}: candidates added to {esc(base)}</h3>")
        out.append(
            html_table(
                [
                    "effect",
                    "fitted parameters",
                    "training error",
                    "held-out error [alpha]",
                    "held-out error against the model it was added to [alpha]",
                    "p (Wilcoxon)",
                    "significant",
                ],
                rows,
            )  # fmt: skip
        )
    if not out:
        return "<p>No candidates were tried.</p>"
    return "".join(out)


def _localisation(diag) -> str:
    parts = [
        html_figure(
            _cdf_figure(diag),
            "theta_max/alpha of the ground-motion records: measurement and model at every step (model peaks seen "
            "through the same sensor noise as the measurement).",
            "CDFs",
        ),
        html_figure(
            _energy_figure(diag),
            "Energy ratio of each free-vibration impact from successive peaks (seed eq. 8) against the amplitude "
            "before it. A constant lower than Housner's says restitution; a trend with amplitude says "
            "amplitude-dependent restitution or damping.",
            "energy ratio",
        ),
        html_figure(
            _half_cycle_figure(diag),
            "Duration of each complete free-vibration half-cycle against its amplitude, with Housner's exact "
            "relation for the stated p: a uniform shift says p is mis-stated.",
            "half-cycle duration",
        ),
        html_figure(
            _flight_figure(diag),
            "Squared ratio of the speeds at the closing and the opening impact of each half-cycle: 1 when no "
            "energy is lost between impacts (Housner); below 1 with damping.",
            "decay between impacts",
        ),
        html_figure(
            _onset_figure(diag),
            "Per ground-motion record and direction: the largest ground acceleration toward the first uplift "
            "before the block is seen to move (onset, an upper estimate of the threshold) and the largest toward "
            "each direction it stood up to 50 ms before (stood). Housner's threshold is g tan alpha; asymmetric "
            "pivots split the two directions.",
            "uplift onset",
        ),
        html_figure(
            _bars_figure(
                diag,
                [
                    ("share_pos", "excursions toward +theta"),
                    ("first_uplift_pos", "first uplifts toward +theta"),
                    ("overturn_fraction", "overturn fraction"),
                ],
                "Direction bias and overturning (95 % intervals)",
                "share [-]",
                ref=0.5,
            ),  # fmt: skip
            "Share of excursions and of first uplifts toward +theta (0.5 for a symmetric block), and the overturn "
            "fraction of the ground-motion records.",
            "direction bias",
        ),
        html_figure(
            _bars_figure(
                diag,
                [("alternation", "ln c (ends +) - ln c (ends -)")],
                "Alternation of free-vibration energy ratios (95 % intervals)",
                "[-]",
                ref=0.0,
            ),  # fmt: skip
            "Difference of the mean log energy ratio of impacts that end a theta > 0 half-cycle and of those that "
            "end a theta < 0 one: 0 for a symmetric block; peaks alternating in size give a non-zero value.",
            "alternation",
        ),
        html_figure(
            _tilt_figure(diag),
            "Rotation before the first uplift while the ground acceleration is below g tan alpha, against the "
            "ground acceleration: Housner's block does not move (0); a sensor offset shifts it, a flexible base "
            "tilts it in proportion to the acceleration.",
            "rotation before uplift",
        ),
    ]
    return "".join(parts) + _metric_table(diag)


def _metric_table(diag) -> str:
    from housner.scenarios.campaigns.compare import METRICS
    from housner.scenarios.campaigns.verdict import Z_LOCAL

    header = ["quantity", "unit", "measured"] + [f"model: {esc(_label(s))}" for s in diag.steps]
    rows = []
    locs = [s.comparison.localisation() for s in diag.steps]
    for key, (label, unit) in METRICS.items():
        m = locs[0][key][0]
        row = [esc(label), esc(unit), _pm(m.value, m.se)]
        for loc in locs:
            x = loc[key][1]
            se = math.hypot(m.se if math.isfinite(m.se) else 0.0, x.se if math.isfinite(x.se) else 0.0)
            z = (x.value - m.value) / se if se > 0 and math.isfinite(x.value) and math.isfinite(m.value) else math.nan
            beyond = math.isfinite(z) and abs(z) > Z_LOCAL
            cell = _pm(x.value, x.se) + (f" (z = {z:+.1f})" if beyond else "")
            row.append(f'<span class="bad">{cell}</span>' if beyond else cell)
        rows.append(row)
    return html_table(
        header,
        rows,
        caption=f"Localisation quantities with standard errors; a model value more than {Z_LOCAL:g} combined "
        "standard errors from the measurement is marked, with its z: beyond that the verdict counts the quantity "
        "as a misfit even when the model's errors are at the floor (housner.scenarios.campaigns.verdict.Z_LOCAL).",
    )


def _records(diag) -> str:
    steps = diag.steps
    held = set(diag.heldout_ids)
    header = ["record", "kind", "set", "window [s]"] + [f"error: {esc(_label(s))}" for s in steps] + [
        "theta_max/alpha measured", f"theta_max/alpha {esc(_label(steps[-1]))}", "diverges at [s]"]  # fmt: skip
    rows = []
    per_step = [{r.id: r for r in s.comparison.records} for s in steps]
    for rec in diag.campaign.records:
        r0 = per_step[0][rec.id]
        rl = per_step[-1][rec.id]
        which = "held out" if rec.id in held else "train"
        rows.append(
            [f"<code>{esc(rec.id)}</code>", esc(rec.kind), which, _f(r0.window_end, 3)]
            + [_f(p[rec.id].error) for p in per_step]
            + [_f(r0.theta_max_over_alpha_measured, 3), _f(rl.theta_max_over_alpha_model, 3),
               _f(rl.divergence_time, 3)]
        )  # fmt: skip
    return html_table(header, rows, caption="Errors in units of alpha over each record's window; failures show a dash.")


def _settings(diag) -> str:
    rows = [[esc(k), f"<code>{esc(v)}</code>"] for k, v in diag.settings.items()]
    rows.append(["elapsed", f"{diag.elapsed:.1f} s"])
    rows.append(["campaign", f"<code>{esc(diag.campaign.path)}</code>"])
    return html_table(["setting", "value"], rows, cls="kv")


def render_diagnosis(diag) -> str:
    """The diagnosis report as one HTML string (self-contained: inline CSS, base64 PNG figures).

    Parameters
    ----------
    diag : housner.scenarios.campaigns.diagnose.Diagnosis
        From :func:`housner.scenarios.campaigns.diagnose.diagnose` with ``compare_steps=True``
        (every step carries its comparison with the campaign).
    """
    if any(s.comparison is None for s in diag.steps):
        raise ValueError("the diagnosis has no comparisons per step; run diagnose(..., compare_steps=True)")
    t0 = time.perf_counter()
    sections = [
        ("summary", "Verdict", _summary(diag)),
        ("ladder", "Error ladder", _ladder(diag)),
        ("candidates", "Candidate effects", _candidates(diag)),
        ("where", "Where the model fails, step by step", _localisation(diag)),
        ("records", "Records", _records(diag)),
        ("settings", "Settings", _settings(diag)),
    ]
    took = time.perf_counter() - t0
    return document(
        f"{diag.campaign.name}: diagnosis",
        f"Diagnosis: <code>{esc(diag.campaign.name)}</code>",
        '<p class="sub">Which physical effect the Housner model misses, judged on held-out records.</p>',
        [Section(i, t, b) for i, t, b in sections],
        f"Page built in {took:.1f} s.",
    )


def write_diagnosis_report(diag, path: str | Path) -> Path:
    """Write :func:`render_diagnosis` to ``path`` (parents created) and return the path."""
    return write_page(path, render_diagnosis(diag))
