"""The diagnosis report: which effect the Housner model misses, and the error falling as it is added.

:func:`render_diagnosis` turns a :class:`scenarios.diagnose.Diagnosis` into
one self-contained HTML page (figures are base64 PNGs, the style sheet is
inline, no script, no network); :func:`write_diagnosis_report` writes it.

What it shows, top first: a summary (what fails, which effect explains it
with which parameters, by how much the held-out error fell); the error
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
from matplotlib.figure import Figure

from housner.calibration import half_cycle_integral
from reports import figures
from reports.page import Section, document, esc, html_figure, html_table, write_page

__all__ = ["render_diagnosis", "write_diagnosis_report"]

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
        return "overturn" if v > 0 else "&minus;&infin;"
    return f"{v:.{digits}g}" if abs(v) >= 1e4 or (v != 0 and abs(v) < 1e-3) else f"{v:.{digits}f}"


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


# ----------------------------------------------------------------------------
# sections
_STATUS_CLASS = {"no_misfit": "ok", "explained": "ok", "partly_explained": "bad", "unexplained": "bad",
                 "inconclusive": "warn"}  # fmt: skip


def _verdict(diag) -> str:
    """The verdict: status, its paragraph, the residual against the measured floor, where to look next."""
    v = diag.verdict
    if v is None:
        return ""
    head = (f'<p class="lead"><span class="{_STATUS_CLASS.get(v.status, "")}">'
            f"{esc(v.status.replace('_', ' ').upper())}</span> &mdash; {esc(v.text)}</p>")  # fmt: skip
    rows = []
    for label, res in (("plain Housner model", v.baseline), ("final model", v.residual)):
        for kind, g in res.groups.items():
            rows.append([esc(label), esc(kind.replace("_", " ")), str(g["n"]), _f(g["error"]), _f(g["floor"]),
                         f"{g['ratio']:.2f}", f"{g['z']:+.1f}", '<span class="bad">yes</span>' if g["misfit"] else "no",
                         f"{g.get('detectable_ratio', float('nan')):.2f}"])  # fmt: skip
    from scenarios.verdict import RATIO_MISFIT, Z_MISFIT

    table = html_table(
        ["model", "records", "n", "held-out error [alpha]", "correct-model floor", "ratio", "z", "misfit",
         "detectable ratio"],
        rows,
        caption=(
            "Held-out (out-of-fold) time-history error against the floor a correct model shows on the same records, "
            "measured by a parametric bootstrap of the fitted model (scenarios.verdict). A misfit is z > "
            f"{Z_MISFIT:g} and ratio > {RATIO_MISFIT:g}; the detectable ratio is what these records would reveal "
            "with 80 % power."
        ),
    )  # fmt: skip
    nxt = ""
    if v.next and v.status in ("partly_explained", "unexplained"):
        items = []
        for c in v.next:
            ev = "; ".join(
                f"{esc(e['label'])}: measured {_f(e['measured'])} &plusmn; {_f(e['measured_se'], 2)}, model "
                f"{_f(e['model'])} &plusmn; {_f(e['model_se'], 2)} (z = {e['z']:+.1f})"
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
    if v.distribution:
        dist = '<p class="bad">Distributions: ' + esc("; ".join(v.distribution)) + ".</p>"
    return head + table + dist + nxt + freq


def _summary(diag) -> str:
    spec = diag.campaign.specimen
    c = diag.campaign
    skipped = ""
    if c.skipped:
        items = "".join(f"<li><code>{esc(rid)}</code> ({esc(f)}): {esc(msg)}</li>" for rid, f, msg in c.skipped)
        skipped = f'<p class="bad">{len(c.skipped)} record(s) skipped:</p><ul>{items}</ul>'
    rest = diag.summary().replace(diag.verdict.text, "").strip() if diag.verdict else diag.summary()
    return (
        _verdict(diag) + f'<p class="sub">{esc(rest)}</p>'
        f'<p class="sub">Specimen: 2H = {spec.height:g} m, 2B = {spec.width:g} m, m = {spec.mass:g} kg, '
        f"alpha = {spec.alpha:.4f} rad, p = {spec.p:.4f} 1/s, Housner r = {spec.r_housner:.4f}. "
        f"{len(c.free_vibration)} free-vibration and {len(c.ground_motion)} ground-motion records, "
        f"{diag.settings.get('folds', '?')}-fold cross-validation (seed {esc(diag.settings.get('seed'))}): every "
        f"record is fitted on in the other folds and held out once.</p>{skipped}"
    )


def _ladder(diag) -> str:
    rows = []
    for s in diag.steps:
        prm = "<br>".join(
            f"<code>{esc(n)}</code>: " + ", ".join(f"{esc(k)} = {_f(v)}" for k, v in p.items()) for n, p in s.effects
        )
        rows.append(
            [
                esc(s.label()) + (" <span class=muted>(by hand)</span>" if s.by_hand else ""),
                prm or "&ndash;",
                f"{_f(s.heldout_error)} &plusmn; {_f(s.heldout_se, 2)}",
                _f(s.train_error),
                "&ndash;" if s.added is None else f"{_f(s.improvement)} &plusmn; {_f(s.improvement_se, 2)}",
                "&ndash;" if s.added is None else ('<span class="ok">yes</span>' if s.significant else "no"),
            ]
        )
    table = html_table(
        ["step", "effects (fitted parameters)", "held-out error [alpha]", "training error", "improvement",
         "significant"],
        rows,
        caption=(
            "Time-history error over the measured window (see scenarios.compare), mean over every record held "
            "out once (out-of-fold) with its standard error; the improvement is the mean paired difference to the "
            f"previous step. The sensor noise alone (sigma/alpha) is {diag.noise_floor:.4f}; the correct-model floor "
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
                ", ".join(f"{esc(key)} = {_f(v)}" for key, v in c.params.items()),
                _f(c.train_error),
                f"{_f(c.heldout_error)} &plusmn; {_f(c.heldout_se, 2)}",
                f"{_f(c.improvement)} &plusmn; {_f(c.improvement_se, 2)}",
                _f(c.pvalue, 2),
                ('<span class="ok">yes</span>' if c.significant else "no")
                + f" <span class=muted>({esc(c.reason)})</span>",
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
                    "held-out error",
                    "improvement",
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
    from scenarios.compare import METRICS

    header = ["quantity", "unit", "measured"] + [f"model: {esc(_label(s))}" for s in diag.steps]
    rows = []
    locs = [s.comparison.localisation() for s in diag.steps]
    for key, (label, unit) in METRICS.items():
        m = locs[0][key][0]
        row = [esc(label), esc(unit), f"{_f(m.value)} &plusmn; {_f(m.se, 2)}"]
        for loc in locs:
            x = loc[key][1]
            se = math.hypot(m.se if math.isfinite(m.se) else 0.0, x.se if math.isfinite(x.se) else 0.0)
            z = (x.value - m.value) / se if se > 0 and math.isfinite(x.value) and math.isfinite(m.value) else math.nan
            flag = ' class="bad"' if math.isfinite(z) and abs(z) > 3 else ""
            row.append(f"<span{flag}>{_f(x.value)} &plusmn; {_f(x.se, 2)}</span>")
        rows.append(row)
    return html_table(
        header,
        rows,
        caption="Localisation quantities with standard errors; a model value more than 3 combined standard errors "
        "from the measurement is marked.",
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
    diag : scenarios.diagnose.Diagnosis
        From :func:`scenarios.diagnose.diagnose` with ``compare_steps=True``
        (every step carries its comparison with the campaign).
    """
    if any(s.comparison is None for s in diag.steps):
        raise ValueError("the diagnosis has no comparisons per step; run diagnose(..., compare_steps=True)")
    t0 = time.perf_counter()
    sections = [
        ("summary", "Summary", _summary(diag)),
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
