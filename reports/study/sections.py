"""The study report's sections after the verdict: figures, stripe counts, failed records, provenance."""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

from housner.reports.page import ci_cell, engine_tag, esc, fmt_g, guarded, html_figure, html_note, html_table
from housner.reports.run.sections.tuning import settings_html
from housner.reports.study.figures import plot_exceedance, plot_fragility, plot_size_effect
from housner.reports.study.view import StudyView, key
from housner.scenarios.execution.run_meta import EngineFacts

__all__ = [
    "MAX_FAILURE_ROWS",
    "exceedance_figures",
    "failures",
    "fragility_figures",
    "provenance",
    "size_figure",
    "stripes",
]

#: Failed records listed in full; beyond this the table is cut (the counts above it stay complete), so that a
#: study where an engine failed on thousands of records still gives a page a browser opens.
MAX_FAILURE_ROWS = 300


def _per_size(study: StudyView, name: str, figure: Callable[[float, str], str]) -> str:
    """A heading and a figure per size, ``figure(size, title)``; one that fails to draw is noted in its place."""
    parts = []
    for size in study.sizes:
        title = study.size_title(size)
        parts.append(study.size_heading(size))
        parts.append(guarded(f"The {name} figure at {esc(title)}", lambda size=size, title=title: figure(size, title)))
    return "".join(parts)


def fragility_figures(study: StudyView) -> str:
    def figure(size: float, title: str) -> str:
        kw = {"reference": study.reference, "colors": study.colors, "ci": study.ci}
        fig = plot_fragility(study.fragility, study.fits, size, study.label, **kw)
        return html_figure(
            fig,
            f"Fragility at {esc(title)}: overturn fraction per stripe with Wilson {study.ci:.0%} intervals "
            "(points slightly shifted per engine so that the bars stand apart) and the fitted lognormal "
            "curves; a dashed curve is a degenerate fit (a step), not a maximum-likelihood fit, and an engine "
            "without a fitted median has no curve.",
            f"fragility curves at {title}",
        )

    return _per_size(study, "fragility", figure) or html_note("No size in this study.", "warn")


def size_figure(study: StudyView) -> str:
    if len(study.sizes) < 2:
        return html_note("One size only: no size effect to draw.")

    def build():
        fig = plot_size_effect(
            study.fits, label=study.label, reference=study.reference, colors=study.colors, ci=study.ci
        )
        return html_figure(
            fig,
            f"Median capacity of each engine against the prototype height, with its bootstrap {study.ci:.0%} "
            "interval; open markers are steps of separated data (not maximum-likelihood fits), and sizes without a "
            "fitted median are left out.",
            "median capacity against prototype height",
        )

    return guarded("The size-effect figure", build)


def exceedance_figures(study: StudyView) -> str:
    thresholds = ", ".join(f"{v:g}" for v in sorted(study.exceedance["threshold"].dropna().unique()))
    note = html_note(
        f"Probability that the peak rotation reaches theta_max/alpha &ge; threshold ({thresholds}) at each stripe, "
        f"with Wilson {study.ci:.0%} intervals; an overturned block counts as exceeding every threshold."
    )

    def figure(size: float, title: str) -> str:
        fig = plot_exceedance(
            study.exceedance, size, study.label, reference=study.reference, colors=study.colors, ci=study.ci
        )
        return html_figure(fig, f"Exceedance of response thresholds at {esc(title)}.", f"exceedance at {title}")

    return note + _per_size(study, "exceedance", figure)


def stripes(study: StudyView) -> str:
    fr = study.fragility
    parts = []
    for size in study.sizes:
        sub = fr[fr["size"].map(key) == size]
        engines = [e for e in study.engines if (sub["engine"].astype(str) == e).any()]
        levels = sub.groupby("stripe")["intensity"].first().sort_index()
        rows = []
        for stripe, x in levels.items():
            row = [esc(int(stripe)), fmt_g(x, 4)]
            for e in engines:
                r = sub[(sub["engine"].astype(str) == e) & (sub["stripe"] == stripe)]
                if not len(r):
                    row.append("&ndash;")
                    continue
                r = r.iloc[0]
                n, k = int(r["n"]), int(r["n_overturned"])
                if n == 0:
                    row.append('<span class="bad">0 / 0</span> (no valid record)')
                else:
                    row.append(f"{k} / {n}<br>{ci_cell(r['p'], r['p_low'], r['p_high'], 2)}")
            rows.append(row)
        header = ["stripe", esc(study.label)] + [engine_tag(e, study) for e in engines]
        table = html_table(
            header,
            rows,
            caption=f"Overturned / valid records and the overturn fraction p with its Wilson {study.ci:.0%} interval.",
        )
        parts.append(
            f"<details><summary>Stripes at {esc(study.size_title(size))} ({len(rows)} stripes, "
            f"{len(engines)} engines)</summary>{table}</details>"
        )
    return "".join(parts) or html_note("No stripe in fragility.parquet.", "warn")


def failures(study: StudyView) -> str:
    parts = []
    failed = study.failed
    if failed.empty:
        return html_note("No record failed.", "good")
    for engine in study.engines:
        ok, bad = study.record_counts(engine)
        if ok == 0 and bad:
            parts.append(html_note(f"Every record of {engine_tag(engine, study)} failed ({bad}).", "warn"))
    counts = failed.groupby(["engine", "size"]).size()
    summary = ", ".join(f"{esc(e)} at {s:g} m: {int(n)}" for (e, s), n in counts.items())
    parts.append(
        html_note(
            f"{len(failed)} record(s) failed ({summary}); they are left out of every count, fit and figure.", "warn"
        )
    )
    shown = failed.sort_values(["engine", "size", "stripe", "motion_id"]).head(MAX_FAILURE_ROWS)
    rows = [
        [
            engine_tag(str(r.engine), study),
            fmt_g(r.size, 4),
            esc(r.stripe),
            fmt_g(r.intensity, 4),
            f"{esc(r.motion_id)}: {esc(r.motion_name)}",
            f"<code>{esc(r.error)}</code>",
        ]
        for r in shown.itertuples()
    ]
    caption = f"First {MAX_FAILURE_ROWS} of {len(failed)} failed records." if len(failed) > MAX_FAILURE_ROWS else ""
    parts.append(
        html_table(
            ["engine", "size [m]", "stripe", esc(study.label), "motion", "error"], rows, cls="failures", caption=caption
        )
    )
    return "".join(parts)


def _kv_value(v: Any) -> str:
    if v is None:
        return "&ndash;"
    if isinstance(v, (list, tuple)):
        return esc(", ".join(f"{x:g}" if isinstance(x, float) else str(x) for x in v))
    if isinstance(v, dict):
        return f"<code>{esc(json.dumps(v))}</code>"
    if isinstance(v, float):
        return fmt_g(v, 6)
    return esc(v)


def provenance(study: StudyView) -> str:
    meta = study.meta
    parts = []
    scen = meta.scenario.to_json()
    rows = [[esc(k), _kv_value(v)] for k, v in scen.items() if v not in (None, "")]
    rows += [[f"study: {esc(k)}", _kv_value(v)] for k, v in study.settings.to_json().items()]
    motions = meta.motions.to_json()
    rows += [[f"motions: {esc(k)}", _kv_value(v)] for k, v in motions.items() if isinstance(v, (str, int, float))]
    for k, v in (("n_records", meta.n_records), ("n_failed", meta.n_failed), ("wall_s", meta.wall_s)):
        if v is not None:
            rows.append([esc(k), _kv_value(v)])
    parts.append(html_table(["", ""], rows, cls="kv"))
    spec = meta.specimen.to_json()
    if spec:
        parts.append("<h3>Specimen</h3>")
        parts.append(html_table(["", ""], [[esc(k), _kv_value(v)] for k, v in spec.items()], cls="kv"))
    parts.append("<h3>Engines</h3>")
    info = meta.engines
    rows = []
    for name in study.engines:
        i = info.get(name) or EngineFacts()
        rows.append(
            [
                engine_tag(name, study),
                esc(i.version or "") or "&ndash;",
                settings_html(i.settings or {}) or "defaults",
                f"{fmt_g(i.wall_s, 4)} s" if i.wall_s is not None else "&ndash;",
                esc(i.cached) if i.cached is not None else "&ndash;",
            ]
        )
    parts.append(
        html_table(
            ["engine", "version", "settings", "engine time", "records from the cache"],
            rows,
            caption="Engine time is summed over the records computed in this study (cached ones cost none).",
        )
    )
    prov = meta.provenance
    if prov.to_json():
        parts.append("<h3>Software and machine</h3>")
        rows = [[esc(k), esc(v)] for k, v in (prov.versions or {}).items()]
        rows += [
            [esc(k.replace("_", " ")), f"<code>{esc(v)}</code>"]
            for k, v in prov.to_json().items()
            if k != "versions" and v not in (None, "")
        ]
        parts.append(html_table(["", ""], rows, cls="kv"))
    return "".join(parts)
