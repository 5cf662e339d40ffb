"""Report sections on the verdict and the specimen: how far each engine is from the reference, and with what.

The headline gives each engine's one verdict (:mod:`housner.scenarios.runs.verdicts`: agrees, ensemble only,
fails, inconclusive), one badge and one sentence with the figure that decided it, the same verdict
``housner run`` prints and :func:`housner.reports.assertions.verdict.assert_verdict` asserts; then the
figures behind it, and for a scenario with effects how far they moved the distribution. The specimen
section lists the geometry and every engine's settings.
"""

from __future__ import annotations

import math

import numpy as np

from housner.reports.page import (
    ci_cell,
    engine_tag,
    esc,
    fmt_g,
    fmt_num,
    fmt_p,
    fmt_signed,
    guarded,
    html_note,
    html_table,
)
from housner.reports.run.sections.tuning import settings_html, tuning_caveats, tuning_section
from housner.scenarios.runs.chaos import RECORD_RTOL
from housner.scenarios.runs.verdicts import KINDS, MIN_RECORDS, EngineVerdict
from housner.scenarios.runs.view import BOOT_SEED, N_BOOT, Run
from housner.statistics import ensemble_stats as stats
from housner.statistics.ensemble_stats import KS_MAX, OVERTURN_TOL
from housner.units import G


def _moved(run: Run, base: str, series: str) -> str:
    """How an effect moves an engine's distribution: median, P[overturn] and KS distance, without -> with."""

    a, b = run.values(base), run.values(series)
    if not (a.size and b.size):
        return "no usable records to compare"
    ks = stats.ks_2samp(a, b)
    med = [run.summaries[n].median.value for n in (base, series)]  # as in the table below
    po = [float(np.mean(np.isinf(v))) for v in (a, b)]
    return (
        f"against {esc(base)} without the effects: median &theta;<sub>max</sub>/&alpha; {fmt_num(med[0], 3)} &rarr; "
        f"{fmt_num(med[1], 3)}, P[overturn] {fmt_num(po[0], 2)} &rarr; {fmt_num(po[1], 2)}, KS distance "
        f"{fmt_num(ks.distance, 3)} (p = {fmt_p(ks.pvalue)})"
    )


def headline_section(run: Run) -> str:
    """The verdict section: one line per engine with its verdict and figures, the table behind them, the rule."""
    parts = []
    if not run.reference_is_requested:
        parts.append(
            html_note(
                f"The reference engine {esc(run.meta.reference)!s} is not in this run; {esc(run.reference)} stands in "
                "as the reference.",
                "warn",
            )
        )
    try:
        caveats = tuning_caveats(run)
    except Exception as e:  # an unreadable tuning file must not lose the verdict; say so instead
        caveats = {}
        parts.append(
            html_note(f"The tuning files could not be checked: <code>{esc(type(e).__name__)}: {esc(e)}</code>", "warn")
        )
    if run.meta.effect_series:
        parts.append(
            html_note(
                "This run adds physical effects (the scenario's <code>[[effects]]</code>): "
                f"<strong>{esc(run.meta.effects_label)}</strong>. "
                "Each series &ldquo;ENGINE + effects&rdquo; is that engine with them, beside the same engine "
                "without them: an effect is meant to move the distribution, so it gets no pass or fail, only "
                "how far it moves it."
            )
        )
    verdicts = run.verdicts(_floors(run, parts))
    parts.append(_verdict_lines(run, verdicts, caveats))
    parts.append(_headline_table(run, verdicts))
    parts.append(html_note(_rule_text(run)))
    parts.extend(
        f'<div class="caveat"><strong>{engine_tag(n, run)}</strong>: {caveats[n]}</div>'
        for n in run.others
        if n in caveats and n in verdicts
    )
    return "".join(parts)


def verdict_badge(v: EngineVerdict) -> str:
    """The verdict's one badge (its colour: :data:`housner.scenarios.runs.verdicts.KINDS`)."""
    return f'<span class="badge {KINDS[v.kind][1]}">{v.badge}</span>'


def _verdict_lines(run: Run, verdicts: dict[str, EngineVerdict], caveats: dict[str, str]) -> str:
    """One line per engine, the answer first: its badge, its sentence with the deciding figure, the figures
    behind it; or how far an effect moves its engine."""
    effects = run.meta.effect_series
    lines = []
    for name in run.others:
        if name in effects:
            lines.append(
                f'<li><span class="badge na">effect</span> {engine_tag(name, run)}: '
                f"{_moved(run, effects[name], name)}</li>"
            )
            continue
        if name not in verdicts:  # a 3D engine: its theta is not the planar block's (Run.mesh_engines)
            lines.append(
                f'<li><span class="badge na">3D</span> {engine_tag(name, run)}: no distribution verdict '
                "against the planar block (its &theta;<sub>max</sub> is the tilt of the scan's 3D body, not "
                "the block's rotation); judged by the measured outcomes</li>"
            )
            continue
        v = verdicts[name]
        head, figure, good = v.parts()
        good = f": {esc(good)}" if good else ""
        mark = f' <small class="bad">{_caveat_count(caveats[name])} (below)</small>' if name in caveats else ""
        lines.append(
            f"<li>{verdict_badge(v)} {engine_tag(name, run)}: {esc(head)}: <strong>{_html_figures(figure)}"
            f"</strong>{good}.{mark}<div class=figs>{_figures_line(run, name, v)}</div></li>"
        )
    if lines:
        return f'<ul class="verdicts">{"".join(lines)}</ul>'
    return html_note(f"Only one engine ({esc(run.reference)}) in this run: nothing to compare it with.")


def _figures_line(run: Run, name: str, v: EngineVerdict) -> str:
    """The figures behind a verdict, in words: the distribution test's and the record-by-record one."""
    s, ref = run.summaries[name], run.summaries[run.reference]
    nf = s.n_failed
    dist = (
        f"Distribution: KS distance {fmt_num(s.ks_distance)} (limit {KS_MAX}); P[overturn] "
        f"{fmt_num(s.p_overturn.value, 2)} against {fmt_num(ref.p_overturn.value, 2)} (limit &plusmn;{OVERTURN_TOL}); "
        f"median &theta;<sub>max</sub>/&alpha; {fmt_num(s.median.value, 3)} against {fmt_num(ref.median.value, 3)} "
        f"(the reference's 90 % interval {fmt_num(ref.median.low, 3)}-{fmt_num(ref.median.high, 3)}); "
        f"{nf} failed record{'s' if nf != 1 else ''}."
    )
    if v.records_short is None:
        return dist + " Record by record: not judged (no chaos floor for this run)."
    return dist + f" Record by record: {_html_figures(v.records_short)}."


def _headline_table(run: Run, verdicts: dict[str, EngineVerdict]) -> str:
    """Every engine's records, KS distance, P[overturn], median, record agreement and verdict, the reference first."""
    ref = run.reference
    header = [
        "engine",
        "records<br>ok / failed",
        "KS distance<br>(p-value)",
        "P[overturn]<br>[95 % CI]",
        "&Delta;P[overturn]",
        "median &theta;<sub>max</sub>/&alpha;<br>[90 % CI]",
        "records that agree<br>[95 % CI] / chaos floor",
        "verdict",
    ]
    rows = []
    for name in run.engines:
        s = run.summaries[name]
        is_ref = name == ref
        nf = s.n_failed
        v = verdicts.get(name)
        if is_ref:
            verdict = "reference"
        elif v is not None:
            verdict = verdict_badge(v)
        else:
            verdict = "3D: outcomes only" if name in run.mesh_engines else "effect"
        records = "&ndash;" if v is None or v.agreement is None else _html_figures(_agreement_cell(v.agreement))
        rows.append(
            [
                engine_tag(name, run) + (" <small>(reference)</small>" if is_ref else ""),
                f"{s.n_ok} / " + (f'<span class="bad">{nf}</span>' if nf else "0"),
                "&ndash;" if is_ref else f"{fmt_num(s.ks_distance)} (p = {fmt_p(s.ks_pvalue)})",
                ci_cell(*s.p_overturn, 2),
                "&ndash;" if is_ref else fmt_signed(s.overturn_diff, 3),
                ci_cell(*s.median, 3),
                records,
                verdict,
            ]
        )
    return html_table(header, rows, cls="headline")


def _rule_text(run: Run) -> str:
    """The one rule behind the verdicts, and how sure a verdict on this many records is."""
    ref = run.summaries.get(run.reference)
    n = ref.n_ok if ref is not None else 0
    # Smirnov's asymptotic 5 % critical distance for two samples of n: sqrt(-ln(0.025) / 2) sqrt(2 / n).
    crit = math.sqrt(-math.log(0.025) / 2.0) * math.sqrt(2.0 / n) if n else math.nan
    if n >= MIN_RECORDS:
        how_sure = (
            f"How sure: two <em>independent</em> ensembles of n = {n} records from one distribution differ by a KS "
            f"distance above {fmt_num(crit, 2)} one time in twenty; here every engine sees the very same motions, "
            "so engines that agree should sit well below that. The KS distance is the largest gap between the two "
            "cumulative distributions; where the peaks spread over a decade, a gap of 0.1 can move the median by "
            "20 %, which is why the medians are shown beside it."
        )
    else:
        how_sure = (
            f"With {n} record{'s' if n != 1 else ''} the verdict is <strong>inconclusive</strong>: one "
            f"record moves the KS distance by 1/n, so at least {MIN_RECORDS} records are needed for a tolerance of "
            f"{KS_MAX}; the figures are shown, not judged."
        )
    return (
        "<strong>The rule</strong> (one for the page, <code>housner run</code> and "
        "<code>housner.reports.assertions.verdict.assert_verdict</code>; docs/explanation/verdict.md). "
        f"<em>Distribution test</em>: KS distance &le; {KS_MAX}, |&Delta;P[overturn]| &le; {OVERTURN_TOL}, no "
        f"failed record, on at least {MIN_RECORDS} records. <em>Record by record</em>: the share of records on "
        f"which the engine and the reference agree (both overturn, or both peak within {RECORD_RTOL:.0%}) against the "
        "<a href='#glossary-chaos-floor'><em>chaos floor</em></a>, the lowest share the analytic model keeps with "
        "itself when its r and p are off by "
        "this engine's measured errors; the engine is at the floor when the 95 % interval of its share reaches "
        "it. <span class='badge pass'>AGREES</span>: both hold. <span class='badge warn'>ENSEMBLE ONLY</span>: "
        "the distribution test holds, the records fall below the floor. <span class='badge fail'>FAILS</span>: the "
        "distribution test fails. P[overturn] intervals are Wilson score intervals; median intervals are "
        f"percentile bootstraps ({N_BOOT} resamples, seed {BOOT_SEED}). " + how_sure
    )


def _floors(run: Run, parts: list[str]) -> dict:
    """The run's chaos floors; one that cannot be computed (its record gone) loses only the record-by-record
    verdict, said in a note."""
    try:
        return run.chaos_floors
    except Exception as e:
        parts.append(
            html_note(f"The chaos floors could not be computed: <code>{esc(type(e).__name__)}: {esc(e)}</code>", "warn")
        )
        return {}


def _html_figures(text: str) -> str:
    """A verdict's plain figures as the page writes them (entities for <=, > and Delta, spaced percent signs)."""
    return esc(text).replace("&lt;=", "&le;").replace("dP[", "&Delta;P[").replace("%", "&#8239;%")


def _caveat_count(text: str) -> str:
    n = text.count('class="bad"')
    return f"{n} tuning check{'s' if n != 1 else ''} not met"


_SPECIMEN_ROWS = {
    "name": ("name", ""),
    "height_m": ("height 2H", "m"),
    "width_m": ("width 2B (between pivots)", "m"),
    "depth_m": ("depth", "m"),
    "mass_kg": ("mass m", "kg"),
    "I0_kgm2": ("moment of inertia about a pivot I<sub>0</sub>", "kg m&sup2;"),
    "alpha_rad": ("slenderness &alpha; = atan(B/H)", "rad"),
    "R_m": ("semi-diagonal R", "m"),
    "p_1_s": ("frequency parameter p = &radic;(m g R / I<sub>0</sub>)", "1/s"),
    "r_housner": ("Housner's energy ratio r (seed eq. 4)", "&ndash;"),
}


def specimen_section(run: Run) -> str:
    spec = run.specimen.to_json()
    parts = []
    geometry = run.campaign.geometry.label if run.campaign is not None else ""
    if geometry:
        parts.append(
            html_note(
                "The planar engines ran this symmetric block with <code>" + esc(geometry) + "</code>, the scan's two "
                "pivots (see <a href='#outcomes'>What the campaign gave the engines</a>); "
                "&theta;<sub>max</sub>/&alpha; "
                "in this report is taken with the &alpha; below, that of the mean pivot."
            )
        )
    if spec:
        rows = []
        for key, value in spec.items():
            label, unit = _SPECIMEN_ROWS.get(key, (esc(key), ""))
            cell = esc(value) if isinstance(value, str) else fmt_g(value, 6)
            rows.append([label, cell, unit])
        a = run.alpha
        if math.isfinite(a):
            rows.append(["&alpha; in degrees", f"{math.degrees(a):.4g}", "deg"])
            rows.append(["uplift acceleration g tan &alpha;", f"{G * math.tan(a):.4g}", "m/s&sup2;"])
        parts.append(html_table(["quantity", "value", "unit"], rows, cls="kv"))
    else:
        parts.append(html_note("run.json holds no specimen.", "warn"))
    rows = []
    for name in run.engines:
        info = run.meta.engine(name)
        sset = settings_html(info.settings or {}) or "defaults"
        rows.append([engine_tag(name, run), esc(info.version or "") or "&ndash;", sset])
    parts.append("<h3>Engines</h3>")
    parts.append(html_table(["engine", "version", "settings"], rows))
    parts.append(guarded("The tuning summary", lambda: tuning_section(run)))
    return "".join(parts)


def _agreement_cell(a) -> str:
    """The record-by-record figures in a table cell: "28 % [20 %, 37 %] / 47 %" (share, its interval / floor)."""
    return f"{a.share:.0%} [{a.low:.0%}, {a.high:.0%}] / {a.floor:.0%}"
