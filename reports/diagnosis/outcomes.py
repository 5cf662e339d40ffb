"""The outcome report: the mission loop on records whose only measurement is whether the block overturned.

:func:`render_outcome_report` turns a :class:`housner.scenarios.diagnosis.outcomes.outcome_results.OutcomeDiagnosis`
into one
self-contained HTML page (the page pieces of :mod:`housner.reports.page`: inline style sheet, base64 PNG
figures of :mod:`housner.reports.diagnosis.outcome_figures`, no script, no network);
:func:`write_outcome_report` writes it.

What it shows, top first: the verdict, stated once (the status in words, the final model with its fitted
parameters and units, the held-out accuracy, F1 and log loss with their intervals, the floor a correct model
reaches, the best baseline, and what remains unexplained); the scores of every rung of the ladder and of every
baseline; the measured outcomes over PGA and PGV/PGA with the P = 0.5 lines before and after; the confusion
matrices; the calibration curve; where the plain model fails and the records missed; the candidate effects;
the block's geometry and the settings.
"""

from __future__ import annotations

import math
import time
from dataclasses import fields
from pathlib import Path

import numpy as np

from housner.reports.diagnosis.outcome_figures import (
    baseline_label,
    calibration_figure,
    engine_azimuth_figure,
    outcome_map_figure,
)
from housner.reports.diagnosis.outcome_text import (
    engine_model_text,
    judgement_text,
    left_out_text,
    outcome_pointer_text,
    transfer_text,
)
from housner.reports.page import (
    Section,
    ci_cell,
    document,
    esc,
    fmt_num,
    fmt_p,
    fmt_signed,
    guarded,
    html_figure,
    html_note,
    html_table,
    write_page,
)
from housner.scenarios.diagnosis.outcomes.outcome_diagnosis import LEVEL
from housner.scenarios.diagnosis.outcomes.outcome_effects import GRID_SHARES
from housner.scenarios.diagnosis.outcomes.outcome_models import AMPLITUDE_SPREAD
from housner.scenarios.diagnosis.outcomes.outcome_results import OutcomeGeometry
from housner.scenarios.diagnosis.outcomes.outcome_scores import (
    SCORE_KEYS,
    OutcomeScores,
    calibration_table,
)

__all__ = ["MISSES_SHOWN", "STATUS", "render_outcome_report", "step_label", "write_outcome_report"]

#: Rows of the table of misses shown per model (the most confident misses first); the rest are counted.
MISSES_SHOWN = 30

#: Status -> (the verdict's words, its style class, its sentence; ``{effects}`` is the effects added).
STATUS = {
    "no_misfit": (
        "NO MISFIT",
        "ok",
        "The plain model's held-out log loss is at the floor that a correct model with its "
        "probabilities reaches; no candidate effect lowered it significantly.",
    ),
    "explained": (
        "EXPLAINED",
        "ok",
        "With {effects} added, the held-out log loss is at the floor that a correct model with its "
        "probabilities reaches.",
    ),
    "partly_explained": (
        "PARTLY EXPLAINED",
        "bad",
        "Adding {effects} lowered the held-out log loss significantly, but it stays above the floor "
        "that a correct model with its probabilities reaches: a part of the outcomes is "
        "unexplained.",
    ),
    "unexplained": (
        "UNEXPLAINED",
        "bad",
        "The plain model's held-out log loss is above the floor that a correct model with its "
        "probabilities reaches, and no candidate effect lowered it significantly.",
    ),
}

#: Score key -> column heading.
_SCORE_HEADINGS = {
    "accuracy": "accuracy",
    "f1": "F1",
    "log_loss": "log loss [nats]",
    "brier": "Brier",
    "precision": "precision",
    "recall": "recall",
    "roc_auc": "ROC AUC",
}

#: Fitted parameter -> (what it is, symbol, unit).
_PARAMS = {
    "alpha_eff": ("effective contact angle", "alpha_eff", "rad"),
    "spread": ("log-normal spread of alpha_eff", "sigma", "-"),
    "lapse": ("lapse rate (share of outcomes the model does not decide)", "lapse", "-"),
    "r": ("kinetic-energy ratio at impact", "r", "-"),
}

#: Geometry key -> (label, unit).
_GEOMETRY = {
    "h_m": ("centre-of-mass height above the contact h", "m"),
    "b_pos_m": ("centre of mass to the +x pivot b+", "m"),
    "b_neg_m": ("centre of mass to the -x pivot b-", "m"),
    "alpha_pos_rad": ("alpha+ = atan(b+/h)", "rad"),
    "alpha_neg_rad": ("alpha- = atan(b-/h)", "rad"),
    "centroidal_inertia_kgm2": ("centroidal moment of inertia", "kg m²"),
    "mass_kg": ("mass", "kg"),
}


def render_outcome_report(diag) -> str:
    """The outcome report as one HTML string (self-contained: inline CSS, base64 PNG figures, no script).

    Parameters
    ----------
    diag : housner.scenarios.diagnosis.outcomes.outcome_results.OutcomeDiagnosis
        From :func:`housner.scenarios.diagnosis.outcomes.outcome_diagnosis.diagnose_outcomes`.
    """
    if not diag.steps or not diag.baselines:
        raise ValueError("`diag` has no ladder or no baselines; pass the result of diagnose_outcomes")
    t0 = time.perf_counter()
    best = _best_baseline(diag)
    sections = [
        ("verdict", "Verdict", _verdict(diag, best)),
        ("scores", "Scores of the ladder and the baselines", _scores(diag, best)),
        ("map", "Outcomes over PGA and PGV/PGA", guarded("The outcome map", lambda: _map(diag, best))),
        ("confusion", "Confusion matrices", _confusion(diag)),
        ("calibration", "Calibration", guarded("The calibration curve", lambda: _calibration(diag, best))),
        ("where", "Where it fails", _where(diag)),
        ("candidates", "Candidate effects", _candidates(diag)),
        ("settings", "Geometry and settings", _settings(diag)),
    ]
    if diag.transfer is not None:
        sections.insert(
            2, ("transfer", "Transfer from another campaign", f"<p>{esc(transfer_text(diag.transfer))}</p>")
        )
    if diag.engine_model is not None:
        sections.insert(2, ("engine", "A 3D engine as the model", _engine(diag)))
    took = time.perf_counter() - t0
    n, k = len(diag.ids), int(np.sum(diag.observed))
    return document(
        f"{diag.campaign}: outcome diagnosis",
        f"Outcome diagnosis: <code>{esc(diag.campaign)}</code>",
        f'<p class="sub">{n} shake-table tests whose only measurement is whether the block overturned ({k} did): '
        "P(overturn) from the specimen's model, judged on held-out records against the floor a correct model "
        "reaches and against logistic regressions on the measured peaks.</p>",
        [Section(i, t, b) for i, t, b in sections],
        f"Page built in {took:.1f} s; diagnosis {diag.elapsed:.1f} s.",
    )


def write_outcome_report(diag, path: str | Path) -> Path:
    """Write :func:`render_outcome_report` to ``path`` (parents created) and return the path."""
    return write_page(path, render_outcome_report(diag))


# ----------------------------------------------------------------------------
# cells and words
def step_label(name: str) -> str:
    """A rung of the ladder in words: ``"plain"`` -> "plain model", ``"a+b"`` -> "plain + a + b"."""
    return "plain model" if name == "plain" else "plain + " + " + ".join(name.split("+"))


def _best_baseline(diag) -> str:
    """The baseline with the lowest held-out log loss (the one the verdict compares with)."""
    return min(diag.baselines, key=lambda k: diag.baselines[k].log_loss)


def _ci(scores: OutcomeScores, key: str, digits: int = 3) -> str:
    """'value [lo, hi]' of a score; the value alone where it has no interval."""
    ci = scores.interval(key)
    if not ci:
        return fmt_num(scores.score(key), digits)
    return ci_cell(scores.score(key), ci[0], ci[1], digits)


def _param(key: str, value, geometry: OutcomeGeometry, *, long: bool, searched=()) -> str:
    """A fitted parameter with its unit (a library effect's from its ``searched`` entry); ``long`` says what it is
    (the verdict), else only its symbol (tables)."""
    lib = {e.param: (f"{e.name}'s {e.param}", e.param, e.unit) for e in searched}
    what, sym, unit = _PARAMS.get(key) or lib.get(key, (key, key, "?"))
    if value is None:
        return f"{esc(sym)}: Housner's impact law" + (" (from the geometry)" if long else "")
    text = (f"{esc(what)} " if long else "") + f"{esc(sym)} = {float(value):.4g} " + ("[-]" if unit == "-" else unit)
    if key == "alpha_eff":
        a = [geometry.alpha_pos_rad, geometry.alpha_neg_rad]
        if all(isinstance(v, (int, float)) and v > 0 for v in a):
            if math.isclose(a[0], a[1]):
                share = f"{100 * float(value) / a[0]:.0f} % of the footprint's alpha, {a[0]:.4f} rad"
            else:  # an asymmetric footprint: a share of either side would mislead; both sides are given
                share = f"the footprint's pivots: alpha {a[0]:.4f} / {a[1]:.4f} rad (+x / -x)"
            if long or math.isclose(a[0], a[1]):
                text += f" ({share})"
    return text


def _params(params: dict, geometry: OutcomeGeometry, *, long: bool = False, searched=()) -> str:
    return "; ".join(_param(k, v, geometry, long=long, searched=searched) for k, v in params.items()) or "&ndash;"


def _n(count: int, noun: str, plural: str | None = None) -> str:
    """``count`` with its noun, singular or plural."""
    return f"{count} {noun if count == 1 else plural or noun + 's'}"


def _effects(name: str) -> str:
    return " + ".join(f"<code>{esc(n)}</code>" for n in name.split("+"))


# ----------------------------------------------------------------------------
# sections
def _verdict(diag, best: str) -> str:
    """The verdict (the only place the page states it) and its evidence, then what remains, in words."""
    f, s, p0 = diag.final, diag.final.scores, diag.steps[0].scores
    words, cls, sentence = STATUS.get(diag.status, (diag.status.replace("_", " ").upper(), "", ""))
    lead = (
        f'<p class="lead"><span class="{cls}">{esc(words)}</span> &mdash; '
        f"{sentence.format(effects=_effects(f.name))}</p>"
    )
    if f.name == "plain":
        spread = f"&plusmn;{100 * AMPLITUDE_SPREAD:g} %"
        model = (
            "the plain model: the specimen's block as built, Housner's impact law; each pivot sampled over "
            f"the specimen's bracket and the table amplitude within {spread}."
        )
    else:
        model = f"{esc(step_label(f.name))}: {_params(f.params, diag.geometry, long=True, searched=diag.searched)}."
    held = f"accuracy {_ci(s, 'accuracy')}, F1 {_ci(s, 'f1')}, log loss {_ci(s, 'log_loss')} nats"
    if f is not diag.steps[0]:
        held += (
            f"; the plain model: accuracy {_ci(p0, 'accuracy')}, F1 {_ci(p0, 'f1')}, log loss "
            f"{_ci(p0, 'log_loss')} nats"
        )
    fl = diag.floor
    floor = (
        f"a correct model with these probabilities would score a log loss of {fmt_num(fl.log_loss)} "
        f"<span class=ci>[{fmt_num(fl.log_loss_ci[0])}, {fmt_num(fl.log_loss_ci[1])}]</span> nats (central 95 % "
        f"of campaigns drawn from them); measured {fmt_num(fl.measured_log_loss)} (z = {fmt_signed(fl.z, 1)}), "
        + (
            'inside that range: <span class="ok">at the floor</span>'
            if fl.at_floor
            else 'beyond that range: <span class="bad">above the floor</span>'
        )
    )
    items = [
        f"<li><b>Final model</b>: {model}</li>",
        f"<li><b>Held out</b> ({diag.folds} folds stratified by outcome, each ground motion's records in one fold; "
        f"the repeats' mean probabilities; 95 % bootstrap intervals resampling whole ground motions): {held}.</li>",
        f"<li><b>Floor</b>: {floor}.</li>",
        f"<li><b>Repeats</b>: {_repeats(diag)}</li>",
        f"<li><b>Best baseline</b>: {_against_baseline(diag, best)}</li>",
        f"<li><b>Every baseline</b>: {esc(judgement_text(diag.judgement))}.</li>",
        f"<li><b>What remains</b>: {_remains(diag)}</li>",
    ]
    note = html_note(
        "The floor is the log loss a model scores when the outcomes are drawn from its own probabilities: the nearer "
        "they lie to 1/2, the higher it is. At the floor means the outcomes are no more surprising than the model "
        "said; whether its probabilities are sharp enough to be useful is what the baselines and the confusion "
        "matrices show."
    )
    return lead + f'<ul class="cause">{"".join(items)}</ul>' + note


def _against_baseline(diag, best: str) -> str:
    """The final model against the best baseline in log loss: the paired difference on the same folds, with its
    standard error clustered by ground motion (:attr:`OutcomeDiagnosis.judgement`)."""
    b = diag.baselines[best]
    c = diag.judgement.against[best]
    ahead = c.advantage > 0
    text = (
        f"{esc(baseline_label(best))} on the same folds, log loss {_ci(b, 'log_loss')} nats, accuracy "
        f"{_ci(b, 'accuracy')}: the model is "
        + ('<span class="ok">ahead</span>' if ahead else '<span class="bad">NOT ahead</span>')
        + f" in log loss (the baseline's minus the model's, per record over the repeats: {fmt_signed(c.advantage, 3)}"
        f" &plusmn; {fmt_num(c.se)} nats, clustered by ground motion"
    )
    if ahead and c.p_better >= LEVEL:
        text += ", not significant: not a clear lead"
    text += ")."
    if not ahead:
        text += " The measured peaks alone predict these outcomes at least as well as the model does."
    return text


def _repeats(diag) -> str:
    """The repeats of the cross-validation: what each ended in, and each score's spread over them."""
    rep, f = diag.repeats, diag.final
    shares = ", ".join(f"<code>{esc(e)}</code> {100 * v:.0f} %" for e, v in rep.selection_share.items())
    spread = "; ".join(
        f"{_SCORE_HEADINGS.get(k, esc(k))} {fmt_num(f.over_seeds[k].mean)} "
        f"<span class=ci>[{fmt_num(f.over_seeds[k].low)}, {fmt_num(f.over_seeds[k].high)}]</span>"
        for k in ("accuracy", "f1", "log_loss")
    )
    return (
        f"{len(rep.seeds)} repeats of the cross-validation, fold seeds {', '.join(str(x) for x in rep.seeds)}; the "
        f"final model is the one {rep.finals.count(rep.chosen)} of them ended in; each effect's share of the repeats: "
        f"{shares}. The final model over the repeats, mean [lowest, highest]: {spread}."
    )


def _remains(diag) -> str:
    """What the final model leaves unexplained, in words: its misses against what its own probabilities allow."""
    s, n, fl = diag.final.scores, len(diag.ids), diag.floor
    fn, fp = s.fn, s.fp
    lo, hi = n * (1 - fl.accuracy_ci[1]), n * (1 - fl.accuracy_ci[0])
    expect = (
        f"a correct model with these probabilities would miss about {n * (1 - fl.accuracy):.0f} "
        f"<span class=ci>[{lo:.0f}, {hi:.0f}]</span>"
    )
    if fn + fp == 0:
        text = f"no record is missed: the final model puts all {n} on the right side of P = 0.5 ({expect})."
    else:
        text = (
            f"{fn + fp} of {n} records {'is' if fn + fp == 1 else 'are'} missed by the final model: "
            f"{_n(fn, 'overturn')} it gave P &lt; 0.5 and {_n(fp, 'standing record')} it gave P &ge; 0.5 "
            f'(listed under <a href="#where">Where it fails</a>); {expect}.'
        )
    if not fl.at_floor:
        text += (
            f" The log loss lies {fmt_num(fl.z, 1)} standard deviations above the floor: the outcomes are more "
            "surprising than the model's probabilities say, which no candidate effect removed."
        )
    return text


def _scores(diag, best: str) -> str:
    rows = []
    for st in diag.steps:
        tag = " <span class=muted>(final)</span>" if st is diag.final else ""
        rows.append([esc(step_label(st.name)) + tag] + [_ci(st.scores, k) for k in SCORE_KEYS])
    for name, sc in diag.baselines.items():
        tag = " <span class=muted>(best baseline)</span>" if name == best else ""
        rows.append([esc(baseline_label(name)) + tag] + [_ci(sc, k) for k in SCORE_KEYS])
    return html_table(
        ["model"] + [_SCORE_HEADINGS.get(k, esc(k)) for k in SCORE_KEYS],
        rows,
        caption=(
            f"Out-of-fold scores: every record predicted by the fit without its fold ({diag.folds} folds stratified "
            f"by outcome that keep each ground motion's records together, {len(diag.repeats.seeds)} repeats from "
            f"seed {diag.seed}: the repeats' mean probability), the ladder's steps and the baselines on the same "
            "folds; value [95 % bootstrap interval resampling whole ground motions]. Accuracy, F1, precision and "
            "recall count P &ge; 0.5 as a predicted overturn; log loss (nats) and Brier score the probabilities, "
            "lower is better."
        ),
    )


def _map(diag, best: str) -> str:
    return html_figure(
        outcome_map_figure(diag, best),
        "Every record at its measured PGA and PGV/PGA (log axes): overturned and stood. The lines are where "
        f"P(overturn) = 0.5: for {'the plain and the final model' if len(diag.steps) > 1 else 'the model'}, the 0.5 "
        "level of a logistic surface with quadratic "
        "terms in log PGA and log PGV/PGA fitted to the model's out-of-fold probabilities as soft targets (a smooth "
        "summary of the records' P, not the model run off the records); for the best baseline, dashed, the same "
        "with linear terms (it is linear in the logs). Circled: the records the final model misses.",
        "measured outcomes over PGA and PGV/PGA with the P = 0.5 lines",
    )


def _confusion(diag) -> str:
    steps = [diag.steps[0]] if len(diag.steps) == 1 else [diag.steps[0], diag.final]
    tables = []
    for st in steps:
        c = st.scores
        title = step_label(st.name) + (" (final)" if st is diag.final else "")
        tables.append(
            f"<div><h4>{esc(title)}</h4>"
            + html_table(
                ["observed \\ predicted", "overturn", "stand"],
                [
                    ["<b>overturned</b>", f"{c.tp}", f"<span class=bad>{c.fn}</span>" if c.fn else "0"],
                    ["<b>stood</b>", f"<span class=bad>{c.fp}</span>" if c.fp else "0", f"{c.tn}"],
                ],
            )
            + "</div>"
        )
    return (
        '<div style="display:flex;flex-wrap:wrap;gap:0 2.5rem">'
        + "".join(tables)
        + "</div>"
        + html_note(
            f"Out-of-fold predictions of all {len(diag.ids)} records: rows are what was observed, columns "
            "what the model predicted (overturn where P &ge; 0.5). The off-diagonal cells are the misses."
        )
    )


def _calibration(diag, best: str) -> str:
    fig = calibration_figure(
        diag.calibration,
        calibration_table(diag.baseline_p[best], diag.observed),
        f"final model: {step_label(diag.final.name)}",
        f"best baseline: {baseline_label(best)}",
    )
    return html_figure(
        fig,
        "Records binned by their out-of-fold P (bins of 0.2): the observed share of overturns against the mean P of "
        "the bin, with its 95 % Wilson interval and the bin's number of records. A calibrated model lies on the "
        "diagonal; a model whose probabilities are all near 0 or 1 puts every record in the end bins.",
        "calibration curve",
    )


def _engine(diag) -> str:
    e = diag.engine_model
    az = np.array(e.ensemble.member_azimuths)
    counts = np.array(e.member_overturns, dtype=float)
    at = sorted(set(az.tolist()))
    mean = [float(counts[az == a].mean()) for a in at]

    def figure() -> str:
        fig = engine_azimuth_figure(at, mean, int(np.sum(diag.observed)), e.azimuths, e.ensemble.engine)
        return html_figure(
            fig,
            "Records whose runs overturn at each azimuth of the ensemble (the mean over its frictions and amplitudes), "
            "against the tests that overturned; the dark bars are the orientation the fit chose on every record.",
            "3D engine overturns by azimuth",
        )

    return f"<p>{esc(engine_model_text(e))}</p>" + guarded("The azimuth figure", figure)


def _where(diag) -> str:
    pointer = f"<p>The plain model's misses: {esc(outcome_pointer_text(diag.pointer))}.</p>"
    by_model: dict[str, list] = {}
    for m in diag.misses:
        by_model.setdefault(m.model, []).append(m)
    if not by_model:
        return pointer + "<p>No record is missed by the plain or the final model.</p>"
    rows, more = [], []
    for model, ms in by_model.items():
        ms = sorted(ms, key=lambda m: -abs(m.predicted_p - 0.5))
        for m in ms[:MISSES_SHOWN]:
            rows.append(
                [
                    esc(step_label(model)),
                    f"<code>{esc(m.id)}</code>",
                    esc(m.observed),
                    fmt_num(m.predicted_p),
                    fmt_num(m.pga_g),
                    fmt_num(m.pgv_over_pga_s),
                ]
            )
        if len(ms) > MISSES_SHOWN:
            more.append(f"{len(ms) - MISSES_SHOWN} more of {esc(step_label(model))} not listed")
    counts = "; ".join(f"{esc(step_label(m))}: {len(v)}" for m, v in by_model.items())
    rest = f"; {'; '.join(more)}" if more else ""
    caption = (
        f"Records on the wrong side of P = 0.5, by model ({counts}), the most confident misses first (up "
        f"to {MISSES_SHOWN} per model){rest}. P is out of fold."
    )
    table = html_table(
        ["model", "record", "observed", "predicted P [-]", "PGA [g]", "PGV/PGA [s]"], rows, caption=caption
    )
    return pointer + table


def _candidates(diag) -> str:
    left = f"<p>{esc(left_out_text(diag.left_out))}</p>" if diag.left_out else ""
    if not diag.candidates:
        return "<p>No candidate effect was tried.</p>" + left
    rows = [
        [
            _effects(c.name),
            _params(c.params, diag.geometry, searched=diag.searched),
            fmt_num(c.log_loss),
            f"{fmt_signed(c.improvement, 3)} &plusmn; {fmt_num(c.improvement_se)}",
            fmt_p(c.p_value),
            '<span class="ok">yes</span>' if c.added else "no",
        ]
        for c in diag.candidates
    ]
    shares = ", ".join(f"{100 * x:g}" for x in GRID_SHARES)
    caption = (
        "Each candidate is fitted on the training folds by minimising the log loss and scored out of fold on the "
        "same folds; its fall is the mean paired per-record fall from the model it extends, with its standard "
        "error. It is added when the fall passes a one-sided Diebold-Mariano test at a family-wise "
        f"{100 * LEVEL:g} % (Bonferroni over the candidates of its round); the best of those passing is added. "
        f"A library effect is tabulated over a grid of its parameter (the neutral value and {shares} % of the way "
        "to each bound) and the pivots' bracket; its fit picks the grid value."
    )
    headings = [
        "candidate (added to the model of its round)",
        "fitted parameters (on all records)",
        "held-out log loss [nats]",
        "fall of the held-out log loss [nats per record]",
        "p (one-sided)",
        "added",
    ]
    return html_table(headings, rows, caption=caption) + left


def _settings(diag) -> str:
    rows = []
    for key, value in ((f.name, getattr(diag.geometry, f.name)) for f in fields(diag.geometry)):
        if key in _GEOMETRY:
            label, unit = _GEOMETRY[key]
            rows.append([esc(label), f"{float(value):.5g} {esc(unit)}"])
        elif key == "b_bracket_m" and isinstance(value, dict):
            for side, (lo, hi) in value.items():
                rows.append(
                    [
                        f"bracket of b{'+' if side == 'pos' else '-' if side == 'neg' else esc(side)} "
                        "(the specimen's uncertainty)",
                        f"{lo:.5g} .. {hi:.5g} m",
                    ]
                )
        else:
            rows.append([esc(key), f"<code>{esc(value)}</code>"])
    rows += [
        ["records", f"{len(diag.ids)} ({int(np.sum(diag.observed))} overturned)"],
        [
            "plain model's ensemble",
            f"pivots over their bracket &times; table amplitude &plusmn;{100 * AMPLITUDE_SPREAD:g} %",
        ],
        ["folds", f"{diag.folds} (stratified)"],
        ["seed", esc(diag.seed)],
        ["elapsed", f"{diag.elapsed:.1f} s"],
    ]
    return html_table(
        ["", ""], rows, cls="kv", caption="The planar block behind the model, and the diagnosis' settings."
    )
