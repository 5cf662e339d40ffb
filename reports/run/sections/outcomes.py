"""Report section of a measured campaign's run: how well each engine predicts the measured outcomes.

One table, the engines in the run's order: accuracy, F1 and log loss with 95 % bootstrap intervals over the
records (:func:`housner.scenarios.diagnosis.outcomes.outcome_scores.outcome_scores`), the predicted and measured
overturns,
the 2x2 confusion matrix and the records each engine failed on (left out); then, where one is known, a published
figure of another model on the same specimen, marked as reported elsewhere. And what the campaign gave the
engines: its specimen's geometry, the 3D engines' mesh settings.
"""

from __future__ import annotations

import math

from housner.reports.page import ci_cell, engine_tag, esc, fmt_g, fmt_num, html_note, html_table
from housner.scenarios.runs.campaign_run import CampaignFacts, OutcomeScore
from housner.scenarios.runs.view import Run


def outcomes_section(run: Run) -> str:
    """The outcome table of a campaign run (a note when its records carry no outcome)."""
    rows = run.outcome_scores
    if not rows:
        return html_note(
            "This campaign's records carry no measured outcome: there is nothing to score the engines against."
        )
    header = [
        "engine",
        "records scored<br>(failed, left out)",
        "accuracy<br>[95 % CI]",
        "F1<br>[95 % CI]",
        "log loss [nats]<br>[95 % CI]",
        "predicted / measured<br>overturns",
        "confusion matrix<br>TP FN / FP TN",
    ]
    body = []
    for r in rows:
        failed = f'<span class="bad">{r.n_failed}</span>' if r.n_failed else "0"
        if not r.n:
            body.append([engine_tag(r.engine, run), f"0 ({failed})", *["&ndash;"] * 5])
            continue
        body.append(
            [
                engine_tag(r.engine, run),
                f"{r.n} ({failed})",
                _ci(r.accuracy, r.accuracy_ci),
                _ci(r.f1, r.f1_ci),
                _ci(r.log_loss, r.log_loss_ci),
                f"{r.n_predicted} / {r.n_overturned}",
                _confusion(r),
            ]
        )
    for p in run.published_outcomes:
        body.append(
            [
                f"<em>{esc(p.model)}</em><br><small>{esc(p.note)}</small>",
                "&ndash;",
                fmt_num(p.accuracy, 3),
                fmt_num(p.f1, 3),
                "&ndash;",
                f"{p.n_predicted} / {p.n_overturned}",
                "&ndash;",
            ]
        )
    clip = rows[0].p_clip
    n_failed = sum(r.n_failed for r in rows)
    caption = " ".join(
        [
            "Each engine's predicted outcome (overturned or not) on every record with a measured outcome, against "
            "that outcome. Every engine here is deterministic: it predicts P(overturn) = 0 or 1, so accuracy and F1 "
            f"count its predictions, and its log loss is taken with P clipped to [{clip:g}, {1 - clip:g}] (one wrong "
            f"record costs {fmt_num(-math.log(clip), 2)} nats): a clipped 0/1 log loss, not the log loss of a "
            "probability. Intervals: 95 % percentile bootstrap over the records (seed 0). Confusion matrix: TP "
            "overturned and predicted, FN overturned but not predicted, FP predicted but not overturned, TN neither.",
            f"{n_failed} engine-record pairs failed and are left out of their engine's scores."
            if n_failed
            else "No record failed.",
            "The published row is reported elsewhere, on its own list of tests: it is not recomputed here and is not "
            "scored on the same records."
            if run.published_outcomes
            else "",
        ]
    )
    return html_table(header, body, cls="headline", caption=caption) + _given(run)


def _ci(value: float | None, ci: tuple[float, float] | None) -> str:
    lo, hi = ci or (float("nan"), float("nan"))
    return ci_cell(value, lo, hi, 3)


def _confusion(r: OutcomeScore) -> str:
    return f'<table class="kv"><tr><td>{r.tp}</td><td>{r.fn}</td></tr><tr><td>{r.fp}</td><td>{r.tn}</td></tr></table>'


def _or(value, default):
    """A count of run.json's campaign table, or ``default`` where the table does not state it."""
    return default if value is None else value


def _given(run: Run) -> str:
    """What the campaign gave the engines: the records, the planar block's geometry effect, the mesh settings."""
    c = run.campaign or CampaignFacts()
    facts = [
        ["campaign", f"{esc(c.name)}<br><code>{esc(c.path)}</code>"],
        [
            "records",
            f"{esc(_or(c.n_records, ''))} ({esc(_or(c.n_outcomes, ''))} with a measured outcome, "
            f"{esc(_or(c.n_overturned, ''))} overturned; {esc(_or(c.skipped, 0))} unreadable, left out)",
        ],
    ]
    geo = c.geometry.label
    scan = c.scan
    if scan is not None:
        facts.append(
            [
                "scan pivots",
                f"b+ {fmt_g(scan.b_pos_m)} m, b&minus; {fmt_g(scan.b_neg_m)} m, "
                f"h {fmt_g(scan.h_m)} m (&alpha;+ {fmt_g(scan.alpha_pos_rad)}, &alpha;&minus; "
                f"{fmt_g(scan.alpha_neg_rad)} rad)",
            ]
        )
    facts.append(
        [
            "planar engines",
            "the symmetric block of the specimen"
            + (
                f" with <code>{esc(geo)}</code> always applied: the scan's own asymmetry, not a studied effect"
                if geo
                else " (a plain block: no effect)"
            ),
        ]
    )
    mesh = c.mesh
    if mesh:
        given = "<br>".join(f"{esc(k)} = <code>{esc(v)}</code>" for k, v in mesh.items())
        facts.append(["3D engines' settings", given])
    return "<h3>What the campaign gave the engines</h3>" + html_table(["", ""], facts, cls="kv")
