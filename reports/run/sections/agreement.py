"""Report sections on record-by-record agreement, rocking spectra and free rocking.

Agreement: per engine the share of records within the relative tolerance of
the reference and with the same overturn verdict, and the time histories of the
records that disagree most. Rocking spectra for pulse scenarios, free-rocking
decay for release scenarios.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from housner._values import json_number
from housner.free_vibration import calibration
from housner.reports import figures
from housner.reports.page import (
    engine_tag,
    esc,
    fmt_g,
    fmt_num,
    fmt_p,
    fmt_pct,
    html_figure,
    html_note,
    html_table,
    view_colors,
)
from housner.scenarios.runs.chaos import RECORD_RTOL, floor_verdict
from housner.scenarios.runs.view import Run

#: Records with the largest disagreement shown as time histories.
N_WORST = 4


def _disagreement(run: Run) -> pd.DataFrame:
    """Per motion: each engine's theta_max/alpha and the largest disagreement with the reference.

    ``score`` is the largest |engine - reference| in units of alpha over the
    engines (an absolute measure: a 0.3 alpha miss matters, a 300 % miss at
    0.01 alpha does not), +inf where the overturn verdicts differ.
    """
    ref = run.by_motion(run.reference)
    wide = pd.DataFrame({e: run.by_motion(e) for e in run.engines})
    score = pd.Series(0.0, index=wide.index)
    for e in run.others:
        a = wide[e]
        both = a.notna() & ref.notna()
        verdict = both & (np.isposinf(a) != np.isposinf(ref))
        finite = both & np.isfinite(a) & np.isfinite(ref)
        s = pd.Series(0.0, index=wide.index)
        s[finite] = (a[finite] - ref[finite]).abs()
        s[verdict] = np.inf
        score = np.maximum(score, s)
    wide["score"] = score
    return wide


def _floor_cell(fl) -> str:
    """The chaos floor as a table cell: the lowest share of the four perturbations (the floor), and their range."""
    if fl is None:
        return "&ndash;"
    return f"{fl.share_min:.0%}<br><small>(of {fl.share_min:.0%}&ndash;{fl.share_max:.0%})</small>"


def agreement_section(run: Run) -> str:
    """The agreement section: each engine against the reference record by record, the scatter of every record,
    and the records where the engines disagree most with their time histories."""
    if not run.others:
        return html_note("Only one engine: no cross-engine comparison.")
    floors = run.chaos_floors
    parts = [_agreement_table(run, floors)]
    lines = []
    for e in run.others:
        r, fl = run.summaries[e], floors.get(e)
        if fl is None or not (r.n_paired > 0):
            continue
        n = int(r.n_paired)
        lines.append(f"{esc(e)}: {esc(floor_verdict(int(round(r.agreement_share * n)), n, fl))}.")
    if lines:
        parts.append(html_note("<br>".join(lines)))
    wide = _disagreement(run)
    parts.append(_scatter_figure(run, wide))
    worst = wide[wide["score"] > 0].sort_values("score", ascending=False, kind="stable").head(N_WORST)
    if worst.empty:
        parts.append(html_note("Every record agrees: no record to single out."))
        return "".join(parts)
    parts.append(_worst_records(run, worst))
    return "".join(parts)


def _agreement_table(run: Run, floors: dict) -> str:
    """Per engine: the distances to the reference, the shares of records in agreement and the chaos floor."""
    header = [
        "engine",
        "KS distance",
        "KS p-value",
        "Wasserstein W<sub>1</sub> [&alpha;]<br><small>(non-overturned)</small>",
        "&Delta;P[overturn]",
        "paired records",
        "same verdict",
        f"&theta;<sub>max</sub> within {RECORD_RTOL:.0%}",
        "chaos floor<br><small>(analytic model with the engine's r, p errors)</small>",
    ]
    rows = []
    for e in run.others:
        r = run.summaries[e]
        rows.append(
            [
                engine_tag(e, run),
                fmt_num(r.ks_distance),
                fmt_p(r.ks_pvalue),
                fmt_num(r.wasserstein),
                fmt_num(r.overturn_diff),
                fmt_num(r.n_paired, 0),
                fmt_pct(r.verdict_share),
                fmt_pct(r.agreement_share),
                _floor_cell(floors.get(e)),
            ]
        )
    return html_table(
        header,
        rows,
        caption=f"Each engine against {esc(run.reference)}. &ldquo;Same verdict&rdquo;: both overturned or "
        f"neither did; &ldquo;within {RECORD_RTOL:.0%}&rdquo;: both overturned, or both rocked with "
        f"&theta;<sub>max</sub> within {RECORD_RTOL:.0%} of the reference's. Rocking is sensitive to small "
        "perturbations (seed Fig. 9), so record-by-record agreement can be low while the distributions agree. "
        "The <a href='#glossary-chaos-floor'>chaos floor</a> is how often the analytic model agrees with itself, "
        "by the same rule, when its r and p are perturbed by the engine's measured free-rocking errors: the lowest "
        "of the four perturbations (r and p, each up and down; their range below it). Agreement at the floor is "
        "chaos, agreement below it a model difference.",
    )


def _scatter_figure(run: Run, wide: pd.DataFrame) -> str:
    """Each engine's theta_max/alpha against the reference's, one point per record ("" when no record pairs)."""
    pairs = {}
    for e in run.others:
        m = wide[e].notna() & wide[run.reference].notna()
        pairs[e] = (wide.loc[m, e].to_numpy(float), wide.loc[m, run.reference].to_numpy(float))
    if not any(a.size for a, _ in pairs.values()):
        return ""
    fig = figures.plot_agreement_scatter(pairs, run.reference, rtol=RECORD_RTOL, colors=view_colors(run))
    return html_figure(
        fig,
        f"&theta;<sub>max</sub>/&alpha; of each engine against {esc(run.reference)}, one point per record. "
        f"Points in the grey band agree within {RECORD_RTOL:.0%}. Overturned records sit in the shaded strips: "
        "at the top when only the engine overturned, at the right when only the reference did, in the corner "
        "when both did.",
        "engine against reference scatter",
    )


def _worst_records(run: Run, worst: pd.DataFrame) -> str:
    """The records where the engines disagree most: their table and every engine's time histories on them."""
    names = run.results.drop_duplicates("motion_id").set_index("motion_id")["motion_name"]
    rows = []
    for mid, r in worst.iterrows():
        rows.append(
            [esc(mid), esc(names.get(mid, mid))]
            + [fmt_num(r[e], 3) for e in run.engines]
            + ["overturn verdicts differ" if math.isinf(r["score"]) else f"{r['score']:.3f}"]
        )
    parts = [f"<h3>The {len(worst)} records where the engines disagree most</h3>"]
    parts.append(
        html_table(
            ["motion", "name"] + [engine_tag(e, run) for e in run.engines] + ["largest |difference| [&alpha;]"],
            rows,
            caption="&theta;<sub>max</sub>/&alpha; per engine and the largest absolute difference to the reference; "
            "a different overturn verdict ranks first.",
        )
    )
    hist = run.histories(worst.index)
    if hist and math.isfinite(run.alpha):
        panels = []
        for mid in worst.index:
            data = {e: (t, th / run.alpha) for (e, i), (t, th) in hist.items() if i == mid}
            if data:
                panels.append((f"motion {mid}: {names.get(mid, '')}", data))
        fig = figures.plot_histories(panels, reference=run.reference, colors=view_colors(run))
        parts.append(
            html_figure(
                fig,
                "&theta;/&alpha; against time on those records, every engine overlaid (dashed: &plusmn;1, the static "
                "overturning angle). Look for where the histories part: the first large uplift or an impact usually "
                "decides the rest.",
                "time histories of the records with the largest disagreement",
            )
        )
    elif not hist:
        parts.append(html_note("histories.parquet is missing: no time histories."))
    return "".join(parts)


def spectra_section(run: Run) -> str:
    mm = run.motions_meta
    w = np.asarray([json_number(x) for x in mm.omega_ratio or ()])
    a = np.asarray([json_number(x) for x in mm.accel_ratio or ()])
    n = int(run.results["motion_id"].max()) + 1 if len(run.results) else 0
    if w.size == 0 or w.size != a.size or w.size < n:
        return html_note("run.json lacks the pulse grid (omega_ratio, accel_ratio per motion): no spectra.", "warn")
    values = {}
    for e in run.engines:
        s = run.by_motion(e).reindex(range(w.size))
        values[e] = s.to_numpy(float)
    fig = figures.plot_rocking_spectra(w, a, values, title=f"{mm.pulse or 'pulse'}: rocking spectra")
    parts = [
        html_figure(
            fig,
            "&theta;<sub>max</sub>/&alpha; over the pulse frequency &omega;<sub>p</sub>/p and amplitude "
            "a<sub>p</sub>/(g tan &alpha;) (seed Fig. 2, eq. 6), one panel per engine; grey with crosses: "
            "overturned. Compare the boundary of the overturn region between engines: it is where engines most "
            "often part.",
            "rocking spectra per engine",
        )
    ]
    if run.others:
        rows = []
        ref = values[run.reference]
        for e in run.others:
            v = values[e]
            both = np.isfinite(_nan_to_num(v)) & np.isfinite(_nan_to_num(ref))
            differ = int(np.sum(both & (np.isposinf(v) != np.isposinf(ref))))
            rows.append([engine_tag(e, run), str(int(np.sum(both))), str(differ)])
        parts.append(
            html_table(
                ["engine", "grid points compared", "overturn verdict differs"],
                rows,
                caption=f"Grid points where the engine and {esc(run.reference)} disagree on overturning.",
            )
        )
    return "".join(parts)


def _nan_to_num(v: np.ndarray) -> np.ndarray:
    """+inf kept finite for 'is compared' masks: NaN stays NaN, inf becomes a large number."""
    return np.where(np.isposinf(v), 1e300, v)


def free_vibration_section(run: Run) -> str:
    alpha = run.alpha
    if not math.isfinite(alpha):
        return html_note("run.json holds no specimen: cannot normalise the free rocking.", "warn")
    ids = sorted(int(i) for i in run.results["motion_id"].unique())
    hist = run.histories(ids)
    if not hist:
        return html_note("histories.parquet is missing: no free-rocking plots.")
    m = run.motions
    amps = run.motions_meta.theta0_over_alpha
    names = run.results.drop_duplicates("motion_id").set_index("motion_id")["motion_name"]

    def amp_of(i: int) -> float:
        if amps is not None and i < len(amps):
            return json_number(amps[i])
        if m is not None and m.theta0 is not None and i < len(m.theta0):
            return float(m.theta0[i]) / alpha
        return math.nan

    releases = []
    for i in ids:
        data = {e: (t, th / alpha) for (e, k), (t, th) in hist.items() if k == i}
        if data:
            releases.append((amp_of(i), {e: data[e] for e in run.engines if e in data}))
    parts = [
        html_figure(
            figures.plot_free_vibration(releases, reference=run.reference, colors=view_colors(run)),
            "Free rocking after a release from rest at each amplitude (seed Fig. 5). The time between impacts "
            "shrinks as the amplitude decays (seed eq. 7); engines whose curves drift apart dissipate differently "
            "per impact or have another p.",
            "free rocking per release amplitude",
        )
    ]
    ratios: dict[str, tuple[list, list]] = {e: ([], []) for e in run.engines}
    cal_rows = []
    for i in ids:
        row = [f"{amp_of(i):.2f}" if math.isfinite(amp_of(i)) else esc(names.get(i, i))]
        for e in run.engines:
            if (e, i) not in hist:
                row.append("&ndash;")
                continue
            t, th = hist[(e, i)]
            try:
                cal = calibration.calibrate_free_vibration(t, th, alpha)
            except Exception as err:  # e.g. a block that rests after one impact: this cell only, not the page
                row.append(f'<span class="muted" title="{esc(err)}">&ndash;</span>')
                continue
            ratios[e][0].extend(cal.c_amplitude / alpha)
            ratios[e][1].extend(cal.c)
            row.append(f"r = {cal.r:.4f} &plusmn; {cal.r_std:.1g}<br><small>p = {cal.p:.4f} 1/s</small>")
        cal_rows.append(row)
    data = {e: (np.asarray(a), np.asarray(r)) for e, (a, r) in ratios.items() if a}
    r_h = json_number(run.specimen.r_housner)
    if data:
        parts.append(
            html_figure(
                figures.plot_energy_ratios(
                    data,
                    r_housner=r_h if math.isfinite(r_h) else None,
                    reference=run.reference,
                    colors=view_colors(run),
                ),
                "Energy ratio of every impact, c<sub>i</sub> = (cos(&alpha; &minus; &theta;<sub>i+1</sub>) &minus; "
                "cos &alpha;)/(cos(&alpha; &minus; &theta;<sub>i</sub>) &minus; cos &alpha;) (seed eq. 8), against "
                "the amplitude before the impact. Housner's impact gives the dashed line at every amplitude; a "
                "contact model that loses more at fast impacts slopes down to the right.",
                "energy ratio per impact against amplitude",
            )
        )
    p_spec = json_number(run.specimen.p_1_s)
    parts.append(
        html_table(
            ["&theta;<sub>0</sub>/&alpha;"] + [engine_tag(e, run) for e in run.engines],
            cal_rows,
            caption="r fitted over all impacts of each release (energy-decay line, &plusmn; one standard error) and "
            "p from the exact half-cycle durations "
            "(<code>housner.free_vibration.calibration.calibrate_free_vibration</code>). "
            f"The specimen has r = {fmt_g(r_h, 5)} and p = {fmt_g(p_spec, 5)} 1/s.",
        )
    )
    return "".join(parts)
