"""The verdict of a study report: per engine and size, does its fragility agree with the reference's?

The comparison and its verdict are the study's own (:func:`housner.scenarios.studies.study.analyse`,
fragility.json's ``disagree``, by :func:`housner.scenarios.studies.fragility.interval_disagreement`);
this module puts them in words: the headline of the page (:func:`headline`) with the fits that are not
maximum-likelihood fits, and the fit tables per size (:func:`fit_tables`). A fit whose status is not
"ok" gets its message and no number as its median or beta.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from housner._values import json_number
from housner.reports.page import ci_cell, engine_tag, esc, fmt_g, fmt_signed, html_note, html_table, status_badge
from housner.reports.study.view import StudyView, count, is_ok, status_words
from housner.scenarios.studies.fragility import interval_disagreement

__all__ = ["DISAGREE", "fit_tables", "headline"]

#: The disagreement sentence of the headline: it appears exactly where an interval excludes 1 (ratio) or 0 (difference).
DISAGREE = "the engines disagree beyond the intervals"


def _ci_g(value: Any, low: Any, high: Any, digits: int = 3) -> str:
    """'value [low, high]' in significant digits: medians carry the intensity's unit, whatever its magnitude."""
    return f"{fmt_g(value, digits)} <span class=ci>[{fmt_g(low, digits)}, {fmt_g(high, digits)}]</span>"


def _ci_signed(value: Any, low: Any, high: Any) -> str:
    return f"{fmt_signed(value)} <span class=ci>[{fmt_signed(low)}, {fmt_signed(high)}]</span>"


def _end(v: float, boundary: float, *, signed: bool = False) -> str:
    """An interval end, with more digits where the usual ones would round it onto the boundary it is judged by.

    A ratio interval ending at 0.9996 printed as "1" would read as containing 1 while the verdict says it
    does not; likewise a difference of -0.001 printed as "+0.00".
    """
    text = ""
    for digits in range(2 if signed else 3, 7):
        text = fmt_signed(v, digits) if signed else fmt_g(v, digits)
        if v == boundary or float(text) != boundary:
            return text
    return text


def _or(value: Any, default: str) -> Any:
    """A setting of study.json, or ``default`` where the file does not state it."""
    return default if value is None else value


def _badge(kind: str) -> str:
    """A verdict badge: 'agree', 'disagree', or a grey one with the given words."""
    if kind == "agree":
        return status_badge(True, yes="AGREE")
    if kind == "disagree":
        return status_badge(False, no="DISAGREE")
    return f'<span class="badge na">{esc(kind)}</span>'


@dataclass
class _Verdict:
    """The verdict of one engine at one size: 'agree', 'disagree' or why there is none, and the sentence."""

    kind: str
    text: str
    caveat: str = ""


def _verdict(study: StudyView, engine: str, size: float) -> _Verdict:
    """Compare an engine's fit at a size with the reference's, in words; no number of a fit that is not "ok"."""
    ref = study.reference
    ok_records, failed = study.record_counts(engine, size)
    if study.valid_at(engine, size) == 0 and ok_records == 0:
        why = f"every one of its {failed} records failed" if failed else "it has no record"
        return _Verdict("no fit", f"no verdict: {why} at this size, so there is nothing to fit")
    fe, fr = study.fit(engine, size), study.fit(ref, size)
    c = study.comparison(engine, size)
    # Replicates whose fits exist can still separate the engines when a point fit is degenerate; that is worth
    # knowing, but their interval is not the interval of a fit, so no number is given.
    flagged = (
        "; the bootstrap replicates that could be fitted do flag a difference from the reference"
        if c is not None and c.disagree is True
        else ""
    )
    if not is_ok(fe):
        return _Verdict("no fit", f"no verdict: its fit is degenerate ({esc(status_words(fe))}, see below){flagged}")
    if not is_ok(fr):
        words = esc(status_words(fr))
        return _Verdict("not evaluated", f"no verdict: the reference's fit is degenerate ({words}, see below){flagged}")
    if c is None:
        return _Verdict("not evaluated", "no verdict: fragility.json holds no comparison with the reference")
    r, rl, rh = (json_number(v) for v in (c.median_ratio, c.ratio_low, c.ratio_high))
    d, dl, dh = (json_number(v) for v in (c.beta_diff, c.diff_low, c.diff_high))
    if not all(math.isfinite(v) for v in (r, rl, rh, d, dl, dh)):
        return _Verdict(
            "not evaluated",
            "no verdict: the bootstrap gave no interval for the comparison (every replicate's fit was degenerate)",
        )
    median_differs, beta_differs = interval_disagreement(rl, rh, dl, dh)
    r_ends = f"[{_end(rl, 1.0)}, {_end(rh, 1.0)}]"
    diff = f"{fmt_signed(d)} [{_end(dl, 0.0, signed=True)}, {_end(dh, 0.0, signed=True)}]"
    if not median_differs:
        median = f"median within the interval: ratio to the reference's {fmt_g(r, 3)} {r_ends} contains 1"
    else:
        median = f'<span class="bad">median {fmt_g(r, 3)} times the reference\'s {r_ends}: {DISAGREE}</span>'
    if not beta_differs:
        beta = f"beta within the interval: difference {diff} contains 0"
    else:
        side = "above" if d > 0 else "below"
        beta = (
            f'<span class="bad">beta {fmt_g(abs(d), 2)} {side} the reference\'s (difference {diff}): {DISAGREE}</span>'
        )
    # The verdict is the study's (fragility.json's flag); the sentence names the intervals by the same rule, so
    # the two differ only in a file edited by hand or written by another rule, and the page then says so.
    flag = c.disagree
    disagree = (median_differs or beta_differs) if flag is None else bool(flag)
    caveat = ""
    if disagree != (median_differs or beta_differs):
        caveat = (
            f"fragility.json marks this comparison disagree = {str(disagree).lower()}, but its intervals say "
            "otherwise; the verdict follows fragility.json, the sentence above the intervals"
        )
    return _Verdict("disagree" if disagree else "agree", f"{median}; {beta}", caveat)


def _overview(study: StudyView) -> str:
    """What was run, in one paragraph."""
    s = study.settings
    meta = study.meta
    levels = [json_number(v) for v in s.levels]
    sizes = study.sizes
    n_failed = count(meta.n_failed, len(study.failed))
    n_records = meta.n_records
    if n_records is None:
        n_records = len(study.results)
    wall = json_number(meta.wall_s)
    engines = ", ".join(engine_tag(e, study) for e in study.engines)
    failed = f'<span class="bad">{n_failed} failed</span>' if n_failed else "none failed"
    return (
        f'<p class="lead">{len(study.engines)} engine{"s" if len(study.engines) != 1 else ""} ({engines}; reference '
        f"{esc(study.reference)}) &times; {len(sizes)} size{'s' if len(sizes) != 1 else ''} (prototype heights "
        f"{', '.join(f'{v:g}' for v in sizes)} m) &times; {len(levels)} stripes of {esc(study.label)} "
        f"({', '.join(f'{v:g}' for v in levels)}) &times; {esc(_or(s.n_motions, '?'))} ground motions: "
        f"{esc(n_records)} records, {failed}"
        f"{f', wall time {fmt_g(wall, 4)} s' if math.isfinite(wall) else ''}.</p>"
    )


def _widest(study: StudyView) -> float:
    """The largest distance of a median-ratio interval's end from 1 over the comparisons [-] (0 if none)."""
    ends = [abs(json_number(v) - 1.0) for c in study.comparisons for v in (c.ratio_low, c.ratio_high)]
    ends = [e for e in ends if math.isfinite(e)]
    return max(ends, default=0.0)


def headline(study: StudyView) -> str:
    compare = study.settings.compare_ci
    each = json_number(study.ci if compare is None else compare)  # each comparison interval's level
    parts = [_overview(study)]
    ref = study.reference
    if ref not in study.engines:
        parts.append(html_note(f"The reference engine {esc(ref)} is not in this study: nothing is compared.", "warn"))
    ok_ref, failed_ref = study.record_counts(ref)
    if ref in study.engines and ok_ref == 0:
        parts.append(
            html_note(
                f"Every record of the reference {esc(ref)} failed ({failed_ref}): there is no reference fit, "
                "so no engine can be compared.",
                "warn",
            )
        )
    items = []
    for engine in study.others:
        ok_records, failed = study.record_counts(engine)
        if ok_records == 0:
            why = f"every one of its {failed} records failed" if failed else "it has no record in this study"
            items.append(f"<li>{_badge('no fit')} {engine_tag(engine, study)}: {why}; no fit, nothing to compare.</li>")
            continue
        verdicts = [(size, _verdict(study, engine, size)) for size in study.sizes]
        kinds = {v.kind for _, v in verdicts}
        overall = "disagree" if "disagree" in kinds else "agree" if kinds == {"agree"} else "not evaluated"
        lines = "".join(
            f"<li>at {esc(study.size_title(size))}: {v.text}"
            + (f'<div class="caveat">{esc(v.caveat)}</div>' if v.caveat else "")
            + "</li>"
            for size, v in verdicts
        )
        items.append(f"<li>{_badge(overall)} {engine_tag(engine, study)} against {esc(ref)}<ul>{lines}</ul></li>")
    if items:
        parts.append(f'<ul class="verdicts">{"".join(items)}</ul>')
    elif ref in study.engines:
        parts.append(html_note(f"Only the reference {esc(ref)} is in this study: nothing to compare it with."))
    parts.append(_degenerate(study))
    n_failed = len(study.failed)
    if n_failed:
        parts.append(
            html_note(
                f'{n_failed} record(s) failed and are left out of every count and fit: see <a href="#failures">'
                "Failed records</a>.",
                "warn",
            )
        )
    s = study.settings
    parts.append(
        html_note(
            f"An engine agrees with the reference at a size when the {esc(f'{each:.1%}')} interval of the ratio of "
            "the fitted medians contains 1 and that of the difference of the betas contains 0: no difference beyond "
            f"what {esc(_or(s.n_motions, 'these'))} motions resolve, not proof of none (a difference smaller than "
            f"the interval, here up to {_widest(study):.0%} on the median, is not excluded). The intervals are "
            f"percentile bootstraps over the motions ({esc(_or(s.n_boot, '?'))} replicates, seed "
            f"{esc(_or(s.seed, '?'))}), paired: each replicate refits both engines on the same resampled motions, "
            "so the motion-to-motion scatter common to both cancels. Two intervals are checked per size, each at "
            f"{esc(f'{each:.1%}')} (Bonferroni), so engines that agree are called in disagreement with a probability "
            f"of at most about {1 - study.ci:.0%} per size."
        )
    )
    return "".join(parts)


def _degenerate(study: StudyView) -> str:
    """The fits that are not maximum-likelihood fits, each with its message, and the caveats of those that are."""
    rows, caveats = [], []
    for size in study.sizes:
        for engine in study.engines:
            f = study.fit(engine, size)
            if f is None:
                if study.record_counts(engine, size)[0] or study.valid_at(engine, size):
                    where = f"{engine_tag(engine, study)} at {esc(study.size_title(size))}"
                    rows.append(f"<li>{where}: no fit in fragility.json</li>")
                continue
            if is_ok(f):
                if f.caveat:
                    caveats.append(
                        f"<li>{engine_tag(engine, study)} at {esc(study.size_title(size))}: {esc(f.caveat)}</li>"
                    )
                continue
            msg = str(f.message or "no message")
            rows.append(
                f"<li>{engine_tag(engine, study)} at {esc(study.size_title(size))}: <strong>{esc(status_words(f))}"
                f"</strong>: {esc(msg)}</li>"
            )
    extra = ""
    if caveats:
        extra = html_note(f"{len(caveats)} fit{'s' if len(caveats) != 1 else ''} with a caveat:", "warn")
        extra += f'<ul class="cause">{"".join(caveats)}</ul>'
    if not rows:
        return html_note("Every fit is a maximum-likelihood fit (status ok).", "good") + extra
    return extra + (
        html_note(
            f"{len(rows)} fit{'s are' if len(rows) != 1 else ' is'} degenerate: not a maximum-likelihood lognormal "
            "fit, so no median or beta is reported for it and it is compared with nothing.",
            "warn",
        )
        + f'<ul class="cause">{"".join(rows)}</ul>'
    )


def _fit_cells(study: StudyView, engine: str, size: float) -> tuple[str, str]:
    f = study.fit(engine, size)
    if not is_ok(f):
        return f'<span class="bad">no fit</span> ({esc(status_words(f))})', "&ndash;"
    return (
        _ci_g(f.median, f.median_low, f.median_high),
        ci_cell(f.beta, f.beta_low, f.beta_high, 2),
    )


def fit_tables(study: StudyView) -> str:
    parts = []
    ref = study.reference
    header = [
        "engine",
        f"median<br><small>{esc(study.label)}</small>",
        "&beta; [-]",
        "median ratio<br>to the reference",
        "&beta; difference<br>to the reference",
        "verdict",
        "replicates<br>left out",
    ]
    for size in study.sizes:
        rows = []
        for engine in study.engines:
            median, beta = _fit_cells(study, engine, size)
            f = study.fit(engine, size)
            left_out = "&ndash;"
            if is_ok(f) and f.n_boot is not None:
                nf = count(f.n_failed)
                cell = f"{nf} of {count(f.n_boot)}"
                left_out = f'<span class="bad">{cell}</span>' if nf else cell
            if engine == ref:
                tag = f"{engine_tag(engine, study)} <small>(reference)</small>"
                rows.append([tag, median, beta, "&ndash;", "&ndash;", "reference", left_out])
                continue
            v = _verdict(study, engine, size)
            c = study.comparison(engine, size)
            if v.kind in ("agree", "disagree") and c is not None:
                ratio = _ci_g(c.median_ratio, c.ratio_low, c.ratio_high)
                diff = _ci_signed(c.beta_diff, c.diff_low, c.diff_high)
            else:
                # No comparison is shown where either fit is degenerate: its replicates are not a fit's interval.
                ratio = diff = "&ndash;"
            rows.append([engine_tag(engine, study), median, beta, ratio, diff, _badge(v.kind), left_out])
        parts.append(study.size_heading(size))
        parts.append(html_table(header, rows, cls="headline"))
    parts.append(
        html_note(
            f"Fits: maximum likelihood on the stripe counts (Baker 2015), intervals from {study.ci:.0%} percentile "
            "bootstraps over the motions; &ldquo;replicates left out&rdquo; counts bootstrap replicates whose own fit "
            "was degenerate. &ldquo;no fit&rdquo; marks a fit that is not a maximum-likelihood fit (the reasons are "
            'listed under <a href="#verdict">the verdict</a>). The ratio and difference intervals are paired '
            "bootstraps of the engine against the reference on the same resampled motions."
        )
    )
    return "".join(parts)
