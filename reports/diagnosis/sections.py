"""The sections of the diagnosis page: the verdict, the error ladder, the candidates, where the model fails,
the records and the settings, each an HTML fragment (:mod:`housner.reports.diagnosis.page` puts them together).
"""

from __future__ import annotations

import math
from dataclasses import fields
from typing import Any

import numpy as np

from housner.reports.diagnosis import words
from housner.reports.diagnosis.figures import (
    bars_figure,
    cdf_figure,
    energy_figure,
    flight_figure,
    half_cycle_figure,
    histories_figure,
    ladder_figure,
    onset_figure,
    sensor_figure,
    step_label,
    tilt_figure,
)
from housner.reports.diagnosis.reason_text import reason_words
from housner.reports.diagnosis.sensor_text import fault_text, noise_text, sensor_notes
from housner.reports.diagnosis.verdict_text import (
    distribution_text,
    said_distributions,
    verdict_paragraph,
    verdict_text,
)
from housner.reports.diagnosis.words import change_text, fmt_pm, params_text
from housner.reports.page import esc, html_figure, html_table
from housner.scenarios.diagnosis.comparison.localise import METRICS
from housner.scenarios.diagnosis.verdict import decision as verdict
from housner.scenarios.diagnosis.verdict import residual_test as residual


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
    """A value with its standard error on the page (:func:`housner.scenarios.diagnosis.results.fmt_pm`)."""
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
    names = c.effects
    if len(names) == 1:
        return _params(c.effect, c.params)
    return "; ".join(
        f"{esc(n)}: " + _params(n, {k.split(".", 1)[1]: v for k, v in c.params.items() if k.startswith(n + ".")})
        for n in names
    )


# ----------------------------------------------------------------------------
# sections
_STATUS_CLASS = {
    "no_misfit": "ok",
    "explained": "ok",
    "partly_explained": "bad",
    "unexplained": "bad",
    "inconclusive": "warn",
}


def _verdict_text(diag) -> str:
    """The verdict's paragraph without its leading status word (the badge before it says it), and without
    its pointer to where to look when the list under it ("Where to look next") gives every class with its
    evidence."""
    v = diag.verdict
    head = v.status.replace("_", " ")
    text = verdict_text(v.facts, v.status, pointer=False) if _shows_next(v) else verdict_paragraph(diag)
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
        out += (
            f'<p class="lead"><span class="{_STATUS_CLASS.get(v.status, "")}">'
            f"{esc(v.status.replace('_', ' ').upper())}</span> &mdash; {esc(_verdict_text(diag))}</p>"
        )
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
    fig = histories_figure(diag)
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
            rows.append(
                [
                    esc(label),
                    esc(kind.replace("_", " ")),
                    str(g.n),
                    _f(g.error),
                    _f(g.floor),
                    f"{g.ratio:.2f}",
                    esc(words.z_text(g.z)),
                    '<span class="bad">yes</span>' if g.misfit else "no",
                    f"{g.detectable_ratio:.2f}",
                ]
            )
    # the constants are read from the verdict's module when the page is built (they are its, never copied)
    fam, fam_plain = diag.settings.floor_family, diag.settings.floor_family_plain
    fams = ""
    if fam:
        plain_fam = fam_plain or fam
        fams = (
            f" The plain model's floor is over correct models of the {words.family_text(plain_fam)}"
            + ("" if plain_fam == fam else f"; the final model's over the {words.family_text(fam)}")
            + " (each model's narrowest family whose floor its ground motions reach; the widest when none)."
        )
    table = html_table(
        [
            "model",
            "records",
            "n",
            "held-out error [alpha]",
            "correct-model floor",
            "ratio",
            "z",
            "misfit",
            "detectable ratio",
        ],
        rows,
        caption=(
            "Held-out (out-of-fold) time-history error against the floor a correct model shows on the same records, "
            "measured by a parametric bootstrap of the fitted model (housner.scenarios.diagnosis.verdict.decision). "
            "A misfit is z > "
            f"{residual.Z_MISFIT:g} and ratio > {residual.RATIO_MISFIT:g}, or a ratio above {residual.RATIO_MISFIT:g} "
            f"with a localisation quantity more than {verdict.Z_LOCAL:g} "
            "standard errors from the measured one (never a ratio within the band: the status rule); the "
            f"detectable ratio is what these records would reveal with 80 % power. Ratio: the group's held-out "
            f"error over its floor (a correct model: 1); {words.Z_LEGEND}." + fams
        ),
    )
    nxt = ""
    if _shows_next(v):
        items = []
        names = diag.final.names if len(diag.steps) > 1 else []
        for c in v.next:
            who = "the model with " + " + ".join(names) if names and c.source != "plain" else "the plain model"
            ev = "; ".join(
                esc(words.evidence_text(e))
                if e.is_probe
                else f"{esc(e.label)}: measured {_pm(e.measured, e.measured_se)}, {esc(who)} "
                f"{_pm(e.model, e.model_se)} ({esc(words.z_text(e.z))})"
                for e in c.evidence
            )
            items.append(f"<li><b>{esc(c.name)}</b> &mdash; {esc(c.meaning)}<br><span class=sub>{ev}</span></li>")
        src = {c.source for c in v.next}
        if names and src == {"final"}:
            whose = f"what the model with {' + '.join(names)} still gets wrong"
        elif names:
            whose = (
                f"what the plain model gets wrong, in its order, each with the figures of the model with "
                f"{' + '.join(names)} where that model still departs there by more than 3 standard errors, else "
                "the plain model's (the added effects may cover those in part); then what only the model with "
                "them shows"
            )
        else:
            whose = "what the plain model gets wrong"
        legend = esc(words.Z_LOCAL_LEGEND)
        nxt = (
            f'<h3>Where to look next</h3><p class="sub">From {esc(whose)}; {legend}.</p><ol>' + "".join(items) + "</ol>"
        )
    freq = ""
    if diag.selection_frequency:
        k = diag.settings.folds
        cells = ", ".join(
            f"<code>{esc(n)}</code> {100 * f:.0f} %"
            for n, f in sorted(diag.selection_frequency.items(), key=lambda kv: -kv[1])
        )
        freq = f'<p class="sub">Best candidate of its round, fold by fold ({k} folds): {cells}.</p>'
    dist = ""
    if v.distribution and not all(d in said_distributions(v.facts, v.status) for d in v.distribution):
        dist = '<p class="bad">Distributions: ' + esc("; ".join(distribution_text(d) for d in v.distribution)) + ".</p>"
    return table + dist + nxt + freq


def summary_section(diag) -> str:
    spec = diag.campaign.specimen
    c = diag.campaign
    skipped = ""
    if c.skipped:
        items = "".join(f"<li><code>{esc(rid)}</code> ({esc(f)}): {esc(msg)}</li>" for rid, f, msg in c.skipped)
        skipped = f'<p class="bad">{len(c.skipped)} record(s) skipped:</p><ul>{items}</ul>'
    return (
        _headline(diag)
        + _histories(diag)
        + _verdict_detail(diag)
        + f'<p class="sub">Specimen: 2H = {spec.height:g} m, 2B = {spec.width:g} m, m = {spec.mass:g} kg, '
        f"alpha = {spec.alpha:.4f} rad, p = {spec.p:.4f} 1/s, Housner r = {spec.r_housner:.4f}. "
        f"{len(c.free_vibration)} free-vibration and {len(c.ground_motion)} ground-motion records, "
        f"{diag.settings.folds}-fold cross-validation (seed {esc(diag.settings.seed)}): every "
        f"record is fitted on in the other folds and held out once; sensor noise sigma/alpha "
        f"{diag.noise_floor:.2g}.</p>{skipped}"
    )


def ladder_section(diag) -> str:
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
        [
            "step",
            "effects (fitted parameters)",
            "held-out error [alpha]",
            "training error",
            "held-out error against the previous step [alpha]",
            "significant",
        ],
        rows,
        caption=(
            "Time-history error over the measured window (see "
            "housner.scenarios.diagnosis.comparison.record_comparison), mean over every record held "
            "out once (out-of-fold) with its standard error; its change is the mean paired difference to the "
            f"previous step. The sensor noise alone (sigma/alpha) is {diag.noise_floor:.2g}; the correct-model floor "
            "the verdict uses is in the table above."
        ),
    )
    fig = html_figure(ladder_figure(diag), "Held-out error at each step, with the noise floor.", "error ladder")
    return table + fig


def candidates_section(diag) -> str:
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
                + f" <span class=muted>({esc(reason_words(c.reason))})</span>",
            ]
            for c in rnd
        ]
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
            )
        )
    if not out:
        return "<p>No candidates were tried.</p>"
    return "".join(out)


def localisation_section(diag) -> str:
    parts = [
        html_figure(
            cdf_figure(diag),
            "theta_max/alpha of the ground-motion records: measurement and model at every step (model peaks seen "
            "through the same sensor noise as the measurement).",
            "CDFs",
        ),
        html_figure(
            energy_figure(diag),
            "Energy ratio of each free-vibration impact from successive peaks (seed eq. 8) against the amplitude "
            "before it. A constant lower than Housner's says restitution; a trend with amplitude says "
            "amplitude-dependent restitution or damping.",
            "energy ratio",
        ),
        html_figure(
            half_cycle_figure(diag),
            "Duration of each complete free-vibration half-cycle against its amplitude, with Housner's exact "
            "relation for the stated p: a uniform shift says p is mis-stated.",
            "half-cycle duration",
        ),
        html_figure(
            flight_figure(diag),
            "Squared ratio of the speeds at the closing and the opening impact of each half-cycle: 1 when no "
            "energy is lost between impacts (Housner); below 1 with damping.",
            "decay between impacts",
        ),
        html_figure(
            onset_figure(diag),
            "Per ground-motion record and direction: the largest ground acceleration toward the first uplift "
            "before the block is seen to move (onset, an upper estimate of the threshold) and the largest toward "
            "each direction it stood up to 50 ms before (stood). Housner's threshold is g tan alpha; asymmetric "
            "pivots split the two directions.",
            "uplift onset",
        ),
        html_figure(
            bars_figure(
                diag,
                [
                    ("share_pos", "excursions toward +theta"),
                    ("first_uplift_pos", "first uplifts toward +theta"),
                    ("overturn_fraction", "overturn fraction"),
                ],
                "Direction bias and overturning (95 % intervals)",
                "share [-]",
                ref=0.5,
            ),
            "Share of excursions and of first uplifts toward +theta (0.5 for a symmetric block), and the overturn "
            "fraction of the ground-motion records.",
            "direction bias",
        ),
        html_figure(
            bars_figure(
                diag,
                [("alternation", "ln c (ends +) - ln c (ends -)")],
                "Alternation of free-vibration energy ratios (95 % intervals)",
                "[-]",
                ref=0.0,
            ),
            "Difference of the mean log energy ratio of impacts that end a theta > 0 half-cycle and of those that "
            "end a theta < 0 one: 0 for a symmetric block; peaks alternating in size give a non-zero value.",
            "alternation",
        ),
        html_figure(
            tilt_figure(diag),
            "Rotation before the first uplift while the ground acceleration is below g tan alpha, against the "
            "ground acceleration: Housner's block does not move (0); a sensor offset shifts it, a flexible base "
            "tilts it in proportion to the acceleration.",
            "rotation before uplift",
        ),
    ]
    return "".join(parts) + _metric_table(diag)


def _metric_table(diag) -> str:
    z_local = verdict.Z_LOCAL  # read when the page is built
    header = ["quantity", "unit", "measured"] + [f"model: {esc(step_label(s))}" for s in diag.steps]
    rows = []
    locs = [s.comparison.localisation() for s in diag.steps]
    for key, (label, unit) in METRICS.items():
        m = locs[0][key][0]
        row = [esc(label), esc(unit), _pm(m.value, m.se)]
        for loc in locs:
            x = loc[key][1]
            se = math.hypot(m.se if math.isfinite(m.se) else 0.0, x.se if math.isfinite(x.se) else 0.0)
            z = (x.value - m.value) / se if se > 0 and math.isfinite(x.value) and math.isfinite(m.value) else math.nan
            beyond = math.isfinite(z) and abs(z) > z_local
            cell = _pm(x.value, x.se) + (f" (z = {z:+.1f})" if beyond else "")
            row.append(f'<span class="bad">{cell}</span>' if beyond else cell)
        rows.append(row)
    return html_table(
        header,
        rows,
        caption=f"Localisation quantities with standard errors; a model value more than {z_local:g} combined "
        "standard errors from the measurement is marked, with its z: beyond that the verdict counts the quantity "
        "as a misfit when the model's errors lie above the floor's band, and calls it unusual when they are within "
        "it (housner.scenarios.diagnosis.verdict.decision.Z_LOCAL, the status rule).",
    )


def records_section(diag) -> str:
    steps = diag.steps
    held = set(diag.heldout_ids)
    header = (
        ["record", "kind", "set", "window [s]"]
        + [f"error: {esc(step_label(s))}" for s in steps]
        + ["theta_max/alpha measured", f"theta_max/alpha {esc(step_label(steps[-1]))}", "diverges at [s]"]
    )
    rows = []
    per_step = [{r.id: r for r in s.comparison.records} for s in steps]
    for rec in diag.campaign.records:
        r0 = per_step[0][rec.id]
        rl = per_step[-1][rec.id]
        which = "held out" if rec.id in held else "train"
        rows.append(
            [f"<code>{esc(rec.id)}</code>", esc(rec.kind), which, _f(r0.window_end, 3)]
            + [_f(p[rec.id].error) for p in per_step]
            + [_f(r0.theta_max_over_alpha_measured, 3), _f(rl.theta_max_over_alpha_model, 3), _f(rl.divergence_time, 3)]
        )
    return html_table(header, rows, caption="Errors in units of alpha over each record's window; failures show a dash.")


def sensor_section(diag) -> str:
    """The theta sensor as assessed before the physics: its noise, its faults and what was done about them."""
    sensor = getattr(diag.campaign, "sensor", None)
    if sensor is None:
        return "<p>The sensor was not assessed.</p>"
    n = sensor.noise
    rows = [
        ["noise", esc(noise_text(n))],
        [
            "records' sigma",
            f"mean {sensor.sigma_before * 1e3:.3g} mrad from differences, {sensor.sigma_after * 1e3:.3g} mrad as used",
        ],
        ["quiet samples", esc(", ".join(f"{k}: {v}" for k, v in n.sources.items()) or "none")],
    ]
    rows += [[esc(f"fault: {f.kind.replace('_', ' ')}"), esc(fault_text(f))] for f in sensor.faults]
    rows += [["note", esc(t)] for t in sensor_notes(sensor)]
    out = html_table(
        ["", ""],
        rows,
        cls="kv",
        caption="What the records say the theta sensor did, before any physics "
        "was fitted (housner.scenarios.diagnosis.sensor_assessment): faults' samples are left out of every error, "
        "drifts are corrected, and the floor draws noise of the measured correlation.",
    )
    fig = sensor_figure(diag)
    if fig is not None:
        out += html_figure(
            fig,
            "The autocorrelation of the noise on the quiet samples (the hold before a release, "
            "the rest after the motion), beside white noise's.",
            "noise autocorrelation",
        )
    return out


def _settings_items(settings) -> list[tuple[str, Any]]:
    """The diagnosis' settings, field by field (a tuple shown as the list the JSON holds)."""
    return [
        (f.name, list(v) if isinstance(v, tuple) else v) for f in fields(settings) for v in (getattr(settings, f.name),)
    ]


def settings_section(diag) -> str:
    rows = [[esc(k), f"<code>{esc(v)}</code>"] for k, v in _settings_items(diag.settings)]
    rows.append(["elapsed", f"{diag.elapsed:.1f} s"])
    rows.append(["campaign", f"<code>{esc(diag.campaign.path)}</code>"])
    return html_table(["setting", "value"], rows, cls="kv")
