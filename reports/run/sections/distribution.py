"""Report section on the distribution of theta_max/alpha: CDFs, percentiles, and the seed's Table 2.

The CDFs of every engine with DKW bands (seed Fig. 10), percentiles with
bootstrap intervals, and, where the scenario states the paper's percentiles,
how far the ensemble is from them and how much stronger the paper's motions
were in effect (:func:`housner.scenarios.runs.spread.equivalent_amplitude`).
"""

from __future__ import annotations

import json
import math

import numpy as np

from housner._values import json_number
from housner.reports import figures
from housner.reports.page import (
    ci_cell,
    engine_tag,
    esc,
    fmt_g,
    fmt_num,
    fmt_signed,
    guarded,
    html_figure,
    html_note,
    html_table,
    view_colors,
)
from housner.scenarios.execution.rundir import jsonable
from housner.scenarios.execution.tables import EngineSummary, percentile_table
from housner.scenarios.runs.spread import AmplitudeFactor, RecordGap, Table2Spread
from housner.scenarios.runs.view import QUARTILES, Run, source_record
from housner.statistics import ensemble_stats as stats


def distribution_section(run: Run) -> str:
    samples = {e: run.values(e) for e in run.engines if run.values(e).size}
    if not samples:
        return html_note("No usable record: nothing to plot.", "warn")
    paper = {float(k): json_number(v) for k, v in (run.meta.analysis.paper_percentiles or {}).items()}
    fig = figures.plot_cdfs(samples, reference=run.reference, ci=0.95, paper=paper or None, colors=view_colors(run))
    parts = [
        html_figure(
            fig,
            "Empirical CDF of &theta;<sub>max</sub>/&alpha; per engine over all its usable records, with a 95 % "
            "Dvoretzky-Kiefer-Wolfowitz band (the true CDF lies inside the whole band with 95 % confidence). "
            "Overturned records have no finite peak: each curve stops at 1 &minus; P[overturn], and the gap to 1 "
            "is drawn at the right edge (marker at the CDF's last value). Look for curves that leave each other's "
            "bands, and for different gaps at the edge."
            + (" Crosses: the seed paper's numerical percentiles (Table 2)." if paper else ""),
            "CDF of theta_max over alpha for every engine",
        )
    ]
    # percentiles with intervals, the paper beside them
    header = ["percentile"]
    if paper:
        header.append("seed paper<br><small>(numerical, Table 2)</small>")
    header += [engine_tag(e, run) for e in run.engines]
    rows = []
    for q in QUARTILES:
        r = [stats.percentile_label(q) if hasattr(stats, "percentile_label") else f"{q:g}th"]
        if paper:
            r.append(fmt_num(paper.get(q, math.nan), 2))
        for e in run.engines:
            r.append(ci_cell(*run.summaries[e].percentile(q), 2))
        rows.append(r)
    r = ["P[overturn]"]
    if paper:
        r.append("&ndash;")
    for e in run.engines:
        r.append(ci_cell(*run.summaries[e].p_overturn, 2))
    rows.append(r)
    parts.append(
        html_table(
            header,
            rows,
            caption="&theta;<sub>max</sub>/&alpha; at the 25th, 50th and 75th percentiles with 90 % bootstrap "
            "intervals, and P[overturn] with its 95 % Wilson interval; &ldquo;overturn&rdquo; where the "
            "percentile falls in the overturned records.",
        )
    )
    if len(run.engines) > 1 or paper:
        parts.append("<h3>In the layout of the seed's Table 2</h3>")
        parts.append(_table2(run, paper))
    spread = run.meta.table2_spread
    if spread is not None:
        parts.append("<h3>Spread over independent ensembles</h3>")
        parts.append(guarded("The seed-spread table", lambda: _spread_table(spread)))
    if paper:
        parts.append('<div id="table2-gap"><h3>Why these percentiles differ from the paper&rsquo;s</h3>')
        parts.append(guarded("The comparison with the paper", lambda: _table2_gap(run, paper, spread)))
        parts.append("</div>")
    return "".join(parts)


def _paper_position(x: float, paper: dict[float, float]) -> str:
    """Where a theta_max/alpha falls among the paper's percentiles, in words."""
    qs = sorted(paper)
    below = [q for q in qs if _finite_or_inf(paper[q]) <= x]
    above = [q for q in qs if _finite_or_inf(paper[q]) > x]
    pv = ", ".join(fmt_num(paper[q], 2) for q in qs)
    if not below:
        return f"below the paper's {stats.percentile_label(qs[0])} percentile ({pv})"
    if not above:
        return f"above the paper's {stats.percentile_label(qs[-1])} percentile ({pv})"
    return (
        f"between the paper's {stats.percentile_label(below[-1])} and {stats.percentile_label(above[0])} "
        f"percentiles ({fmt_num(paper[below[-1]], 2)} and {fmt_num(paper[above[0]], 2)})"
    )


def _finite_or_inf(v: float) -> float:
    return math.inf if not math.isfinite(v) and not math.isnan(v) else v


def _table2_gap(run: Run, paper: dict[float, float], spread: Table2Spread | None) -> str:
    """The gap to the paper's Table 2, and its measured cause: the record against its own ensemble."""
    ref_summary = run.summaries[run.reference]
    ref = run.reference
    head, gap = _gap_head(run, ref_summary, paper, spread)
    parts = [f"<p>{head}</p>"]
    record, why = source_record(run)
    if run.source != "rdk" or record is None or run.motions is None:
        why = why or (
            "motions.npz is missing" if run.motions is None else "the motions are not simulated from a record"
        )
        parts.append(
            html_note(f"No measured cause on this page: {esc(why)}, so the record cannot be set against its ensemble.")
        )
        return "".join(parts)
    g = run.record_gap
    x, pct = g.record_theta_max_over_alpha, g.record_percentile
    rec_line = _record_line(run, g, ref_summary, paper)
    ia_line = _intensity_line(g, ref_summary, paper, gap)
    spec_line, lo, hi = _spectrum_line(run, g)
    verdict = _gap_verdict(gap, pct, lo, hi, x, paper)
    items = [rec_line, ia_line, spec_line]
    if gap:
        items.append(guarded("The equivalent amplitudes", lambda: _factor_line(run)))
    lis = "".join(f"<li>{t}</li>" for t in items)
    parts.append(f"<p>Measured cause, on this run's own motions:</p><ul class=cause>{lis}</ul><p>{verdict}</p>")
    note = run.meta.analysis.paper_note
    if gap and note:
        parts.append(
            "<p><strong>What this page cannot measure</strong> (from the scenario's <code>paper_note</code>): "
            f"{esc(note)}</p>"
        )
    parts.append(
        html_note(
            "Computed by <code>housner.scenarios.runs.spread.record_against_ensemble</code> when this page was "
            "written: "
            "the "
            f"record through {esc(ref)} with the run's settings, the ensemble's {g.n_ensemble} usable records "
            f"ranked against it (ties half), spectra at {len(g.band_periods_s)} log-spaced periods per range."
        )
    )
    return "".join(parts)


def _gap_verdict(gap: list[float], pct: float, lo: float, hi: float, x: float, paper: dict[float, float]) -> str:
    """What the record's rank (``pct`` [%]) and the band's PSa ratios (``lo``, ``hi``) say about the gap."""
    weak = pct >= 75 and hi < 0.8
    matched = lo >= 0.8 and hi <= 1.25 and 25 <= pct <= 75
    if gap and weak:
        return (
            "So the gap lies in the motions rather than in the rocking model or the engines: the record's own "
            "long-period content, which the synthetic motions lack, rocks the block "
            + (
                "into the range of the paper's percentiles."
                if _paper_position(x, paper).startswith("between")
                else "much further than they do."
            )
        )
    elif gap and matched:
        return (
            "So this ensemble stands for its record: it carries the record's spectrum where rocking is decided "
            "and holds the record's own response near its middle. The remaining gap is not in the spectral shape "
            "of the motions, and, the engines agreeing, not in an engine."
        )
    elif gap:
        return "These figures do not single out the motions' spectral shape as the cause of the remaining gap."
    else:
        return "The paper's percentiles are reproduced within the ensemble's sampling noise."


def _gap_head(
    run: Run, ref_summary: EngineSummary, paper: dict[float, float], spread: Table2Spread | None
) -> tuple[str, list[float]]:
    """Where the paper's percentiles stand against this run's noise: the sentence, and the levels outside it."""
    qs = [q for q in QUARTILES if q in paper]
    n = ref_summary.n_ok
    ref = run.reference
    summary = {json_number(k): v for k, v in (spread.summary if spread is not None else {}).items()}
    k_spread = spread.n_ensembles if spread is not None else 0
    # Is each paper value inside what another draw of motions gives: the spread when run, else the bootstrap interval?
    inside, ranges = {}, {}
    for q in qs:
        if q in summary:
            lo, _, hi = (json_number(x) for x in (list(summary[q]) + [math.nan] * 3)[:3])
        else:
            lo, hi = ref_summary.percentile(q).low, ref_summary.percentile(q).high
        ranges[q] = (lo, hi)
        pv = paper[q]
        inside[q] = bool(lo <= pv <= hi) if not math.isnan(pv) else None
    labels = " / ".join(stats.percentile_label(q) for q in qs)
    ours = " / ".join(fmt_num(ref_summary.percentile(q).value, 2) for q in qs)
    paper_txt = " / ".join(fmt_num(paper[q], 2) for q in qs)
    rng = " / ".join(f"{fmt_num(ranges[q][0], 2)}&ndash;{fmt_num(ranges[q][1], 2)}" for q in qs)
    gap = [q for q in qs if inside[q] is False]
    within = [q for q in qs if inside[q] is True]
    if summary:
        where = f"over {esc(k_spread)} independent ensembles of {n} motions (min&ndash;max) they range over {rng}"
        fr = spread.overturn_fraction_range if spread is not None else ()
        if fr:
            where += f", with P[overturn] {fmt_num(json_number(fr[0]), 2)}&ndash;{fmt_num(json_number(fr[-1]), 2)}"
        noise = "the spread of independent ensembles"
    else:
        where = f"their 90 % bootstrap intervals are {rng}"
        noise = "the intervals of this ensemble"
    head = (
        f"The paper's numerical percentiles ({labels}) are {paper_txt}; the analytic reference ({esc(ref)}) "
        f"gives {ours} on this ensemble of {n} motions, and {where}. "
    )
    if gap and not within:
        head += f"<strong>The paper's values lie outside {noise} at every percentile</strong>: another draw of "
        head += "motions does not close the gap."
    elif gap:
        head += (
            f"The paper's values lie outside {noise} at the "
            + " and ".join(stats.percentile_label(q) for q in gap)
            + " percentile"
            + ("s" if len(gap) > 1 else "")
            + ", within it at the "
            + " and ".join(stats.percentile_label(q) for q in within)
            + "."
        )
    else:
        head += f"<strong>The paper's values lie within {noise}</strong>: this run reproduces its Table 2."
    return head, gap


def _record_line(run: Run, g: RecordGap, ref_summary: EngineSummary, paper: dict[float, float]) -> str:
    """Where the record's own response falls in its ensemble."""
    x, pct = g.record_theta_max_over_alpha, g.record_percentile
    q75 = ref_summary.percentile(75.0).value
    amp = g.amplitude
    scaled = f" times {amp:g} as the ensemble," if amp != 1.0 else ""
    if pct >= 75:
        rank = f"higher than {pct:.0f} % of the {g.n_ensemble} motions, above their 75th percentile ({fmt_num(q75, 2)})"
    elif pct >= 50:
        rank = f"higher than {pct:.0f} % of the {g.n_ensemble} motions, above their median"
    else:
        rank = f"higher than only {pct:.0f} % of the {g.n_ensemble} motions: a typical member of the ensemble"
    return (
        f"The record itself ({esc(g.record)}),{scaled} compressed by &radic;S = {math.sqrt(run.S):.3g} and run "
        f"through the same model on the same specimen exactly as every motion of the ensemble, gives "
        f"&theta;<sub>max</sub>/&alpha; = <strong>{fmt_num(x, 2)}</strong>: {rank}"
        + (f", and {_paper_position(x, paper)}." if paper else ".")
    )


def _intensity_line(g: RecordGap, ref_summary: EngineSummary, paper: dict[float, float], gap: list[float]) -> str:
    """Whether the ensemble's Arias intensity explains the gap."""
    ia, ia_rec = g.arias_ensemble_mean_m_s, g.arias_record_m_s
    ia_lo, ia_hi = g.arias_ensemble_5_95_m_s
    ia_ok = ia_lo <= ia_rec <= ia_hi
    # which way the gap goes: this run's percentiles below the paper's (or above)
    below = [
        ref_summary.percentile(q).value < _finite_or_inf(paper[q])
        for q in gap
        if not math.isnan(ref_summary.percentile(q).value)
    ]
    facts = (
        f"the ensemble's mean Arias intensity is {ia:.2f} m/s against the record's {ia_rec:.2f} m/s (prototype "
        f"scale; 5&ndash;95 % of the ensemble {ia_lo:.2f}&ndash;{ia_hi:.2f} m/s"
    )
    if ia_ok:
        return f"Not the intensity: {facts})."
    elif below and all(below) and ia > ia_rec:
        return (
            f"Not a lack of intensity: {facts}, so the ensemble carries <em>more</em> energy than the record, "
            f"&times;{ia / ia_rec:.2f}), yet its percentiles stay below the paper's."
        )
    elif below and all(below):
        return f"Partly the intensity: {facts}, which leaves the record out, below it)."
    else:
        return f"The intensity differs: {facts}, which leaves the record out)."


def _spectrum_line(run: Run, g: RecordGap) -> tuple[str, float, float]:
    """The ensemble's mean PSa against the record's where rocking is decided; with the band's min and max ratio."""
    b0, b1 = g.band_s
    w0, w1 = g.omega_ratio_band
    lo, hi, mean = g.band_ratio_min, g.band_ratio_max, g.band_ratio_mean
    h_proto = fmt_g(run.S * json_number(run.specimen.height_m), 3)
    band = (
        f"between {b0:g} and {b1:g} s (prototype periods; for the {h_proto} m prototype, "
        f"p = {g.p_prototype_1_s:.3g} 1/s, that is &omega;/p = {w0:.2g}&ndash;{w1:.2g}, where "
        "rocking and overturning are decided, seed Fig. 2)"
    )
    damp = f"{100 * g.damping:g} %-damped"
    if hi < 0.8:
        text = (
            f"The spectral shape: {band}, the ensemble's mean {damp} PSa is only <strong>{lo:.2f}&ndash;{hi:.2f}"
            f"</strong> of the record's (mean {mean:.2f}), while at {g.short_s[0]:g}&ndash;{g.short_s[1]:g} s "
            f"it reaches {g.short_ratio_max:.2f} of it (at {g.short_ratio_max_period_s:.2g} s): the fitted "
            "model puts the record's energy at short periods, which rock a block of this size much less."
        )
    elif lo > 1.25:
        text = (
            f"The spectral shape: {band}, the ensemble's mean {damp} PSa exceeds the record's, "
            f"{lo:.2f}&ndash;{hi:.2f} of it."
        )
    elif lo >= 0.8 and hi <= 1.25:
        text = (
            f"The spectral shape: {band}, the ensemble's mean {damp} PSa is {lo:.2f}&ndash;{hi:.2f} of the "
            "record's, within &plusmn;25 %: the ensemble carries the record's content there."
        )
    else:
        text = (
            f"The spectral shape: {band}, the ensemble's mean {damp} PSa is {lo:.2f}&ndash;{hi:.2f} of the record's "
            f"(mean {mean:.2f})."
        )
    return text, lo, hi


def _factor_line(run: Run) -> str:
    """The factors on this ensemble that reach each of the paper's percentiles, and whether one factor does."""
    f = run.paper_factors
    if not f:
        return "No equivalent amplitude: the paper gives no percentile or motions.npz is missing."
    fac = f.factors
    ci = f"{100 * f.ci:g} %"

    def one(q: float, d: AmplitudeFactor) -> str:
        tgt = "overturn" if math.isinf(d.target) else fmt_num(d.target, 2)
        if not math.isfinite(d.factor):
            return f"none within &times;1/8&ndash;8 for the {stats.percentile_label(q)} ({tgt})"
        return f"&times;{d.factor:.2f} [{d.low:.2f}, {d.high:.2f}] for the {stats.percentile_label(q)} ({tgt})"

    text = (
        "How much stronger, in effect, the paper's motions were: the analytic model reaches the paper's "
        "percentiles with this ensemble's accelerations multiplied by "
        + "; ".join(one(q, d) for q, d in sorted(fac.items()))
        + " ("
        f"{100 * f.step:g} % grid, {ci} bootstrap intervals over the {f.n} records)."
    )
    ok = [d for _q, d in sorted(fac.items()) if math.isfinite(d.low) and math.isfinite(d.high)]
    if len(ok) >= 2:
        lo, hi = max(d.low for d in ok), min(d.high for d in ok)
        if lo <= hi:
            text += (
                f" One factor, {lo:.2f}&ndash;{hi:.2f}, reaches them all: the paper's distribution has this "
                "ensemble's shape at a higher intensity."
            )
        else:
            a, b = min(ok, key=lambda d: d.high), max(ok, key=lambda d: d.low)
            order = [d for _q, d in sorted(fac.items())]
            text += (
                f" <strong>No single factor does</strong> (the intervals {a.low:.2f}&ndash;{a.high:.2f} and "
                f"{b.low:.2f}&ndash;{b.high:.2f} do not overlap): the paper's distribution is not this "
                "ensemble's made stronger, but "
                + (
                    "wider"
                    if next(i for i, d in enumerate(order) if d is a) < next(i for i, d in enumerate(order) if d is b)
                    else "narrower"
                )
                + " than it: its motions differed from these in their spread, not only in intensity."
            )
    return text


def _table2(run: Run, paper: dict[float, float]) -> str:
    """Percentiles and their differences to the reference (and to the paper), one row per quantity."""
    t2 = percentile_table(run.results, run.reference, q=QUARTILES)
    labels = [esc(i) for i in t2.index]
    rows = []
    ref = t2.iloc[:, 0].to_numpy(float)
    if paper:
        pv = np.array([paper.get(q, math.nan) for q in QUARTILES])
        rows.append(["seed paper, numerical [&alpha;]"] + [fmt_num(v, 2) for v in pv])
        with np.errstate(invalid="ignore", divide="ignore"):
            rel = np.where(np.isfinite(ref) & np.isfinite(pv), (ref - pv) / pv, np.nan)
        rows.append([f"{engine_tag(run.reference, run)} [&alpha;]"] + [fmt_num(v, 2) for v in ref])
        rows.append([f"({esc(run.reference)} &minus; paper)/paper [&ndash;]"] + [fmt_signed(v) for v in rel])
    else:
        rows.append([f"{engine_tag(run.reference, run)} [&alpha;]"] + [fmt_num(v, 2) for v in ref])
    for e in run.others:
        mine = t2[f"{e} [alpha]"].to_numpy(float)
        diff = t2[f"{e} - {run.reference} [alpha]"].to_numpy(float)
        rel = t2[f"({e} - {run.reference})/{run.reference} [-]"].to_numpy(float)
        rows.append([f"{engine_tag(e, run)} [&alpha;]"] + [fmt_num(v, 2) for v in mine])
        rows.append([f"{esc(e)} &minus; {esc(run.reference)} [&alpha;]"] + [fmt_signed(v) for v in diff])
        rows.append(
            [f"({esc(e)} &minus; {esc(run.reference)})/{esc(run.reference)} [&ndash;]"] + [fmt_signed(v) for v in rel]
        )
    return html_table(
        [""] + labels,
        rows,
        caption="&theta;<sub>max</sub>/&alpha; at each percentile and the differences to the reference, absolute and "
        "relative (&ldquo;&ndash;&rdquo; where a side overturns). The seed found its experiment within 0.18 "
        "(relative) of the Housner model at the median.",
    )


def _spread_table(spread: Table2Spread) -> str:
    summary = spread.summary
    k = spread.n_ensembles
    rows = []
    for q, v in summary.items():
        lo, med, hi = (list(v) + [math.nan] * 3)[:3]
        rows.append([stats.percentile_label(json_number(q)), fmt_num(lo, 2), fmt_num(med, 2), fmt_num(hi, 2)])
    fr = spread.overturn_fraction_range
    if fr:
        lo, med, hi = (list(fr) + [math.nan] * 3)[:3]
        rows.append(["P[overturn]", fmt_num(lo, 2), fmt_num(med, 2), fmt_num(hi, 2)])
    if not rows:
        return f"<pre>{esc(json.dumps(jsonable(spread.to_json()), indent=1)[:4000])}</pre>"
    return html_table(
        ["", "min", "median", "max"],
        rows,
        caption=f"The reference engine on {esc(k)} independent ensembles of the same size (other seeds): how much "
        "Table 2 moves with another draw of motions. Differences between engines smaller than this spread are "
        "within the ensemble's own sampling noise.",
    )
