"""Report section on what each engine's departure from the analytic model is made of, and what it costs.

Reads, for each of the run's engines, the stored measurements next to its tuning file
(:func:`~housner.reports.run.sections.tuning.model_file`):

* ``explain-<engine>.json`` (``housner explain ENGINE --json FILE``): the effects that carry
  the analytic model to the engine, its per-record agreement with the engine before and
  after them, the agreement a correct model could reach (the *reachable agreement*: the report's single
  floor concept, the chaos floor, on the scenario the explanation was measured on, or the model-form limit
  if lower),
  and what remains;
* ``frontier-<engine>.json`` (``housner frontier ENGINE --json FILE``): the engine's
  accuracy-cost frontier, its defaults and its knee.

Both were measured on a named scenario, not on this run; the section says which.
"""

from __future__ import annotations

import math

from housner.reports.explain_text import page_maps_remains_text, page_remains_text
from housner.reports.frontier_figure import frontier_figure
from housner.reports.impact_map_figure import maps_figure
from housner.reports.page import engine_tag, esc, fmt_g, html_note, html_stored_figure, html_table, status_badge
from housner.reports.run.sections.tuning import StoredFile, engine_defaults, model_data, model_file, settings_differ
from housner.scenarios.execution.rundir import jsonable
from housner.scenarios.runs.explain import EffectFound, Explanation, KsDistances
from housner.scenarios.runs.explain_maps import MapsExplained
from housner.scenarios.runs.frontier import Frontier, knee_reason, same_setting
from housner.scenarios.runs.view import Run

__all__ = ["engines_explained", "has_engine_measurements"]


def _pct(x) -> str:
    return "&ndash;" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:.0%}"


def _signed(x, fmt: str) -> str:
    """A signed error in ``fmt`` (e.g. ``"+.2%"``), or a dash where it could not be measured (None, NaN, inf)."""
    return "&ndash;" if x is None or not math.isfinite(float(x)) else format(x, fmt)


def _effects_html(effects: tuple[EffectFound, ...]) -> str:
    if not effects:
        return "none"
    return "<br>".join(
        f"<code>{esc(e.name)}</code> (" + ", ".join(f"{esc(k)} = {fmt_g(v, 4)}" for k, v in e.params.items()) + ")"
        for e in effects
    )


def _measured(x: float | None) -> bool:
    """A figure the file holds: not missing (None), not unmeasured (NaN, written as null)."""
    return x is not None and not math.isnan(x)


def _ks_html(ks: KsDistances | None) -> str:
    if ks is None or not _measured(ks.plain):
        return ""
    return f"<br><small>KS {fmt_g(ks.plain, 3)} &rarr; {fmt_g(ks.with_effects, 3)}</small>"


def _decomposition(run: Run, found: dict[str, StoredFile]) -> str:
    rows = []
    for name, stored in found.items():
        if not (isinstance(stored.data, dict) and "engine" in stored.data):
            rows.append([engine_tag(name, run), f"<code>{esc(stored.path.name)}</code>: unreadable", *[""] * 6])
            continue
        d = Explanation.from_json(stored.data)
        parts = d.floor_parts
        maps = d.maps
        rows.append(
            [
                engine_tag(name, run),
                f"{esc(d.scenario)}, {esc('' if d.n_records is None else d.n_records)} records",
                _effects_html(d.effects),
                f"{_pct(d.agreement_plain)} &rarr; {_pct(d.agreement)}" + _ks_html(d.ks),
                _maps_cell(maps, d.ks),
                f"{_pct(d.floor)} <small>(chaos floor {_pct(parts.chaos)}, "
                f"model-form limit {_pct(parts.model_form)})</small>",
                status_badge(d.reaches_floor, "reaches it", "below it") if d.reaches_floor is not None else "&ndash;",
                esc(page_remains_text(d))
                + (
                    f"<br><small>With its maps: {esc(page_maps_remains_text(d))}</small>"
                    if maps is not None and maps.maps is not None
                    else ""
                ),
            ]
        )
    return html_table(
        [
            "engine",
            "measured on",
            "effects found",
            "agreement: Housner &rarr; Housner + effects",
            "Housner + the engine's measured maps",
            "reachable agreement",
            "reaches it (within 5 points)",
            "what remains",
        ],
        rows,
        caption="Per-record agreement: the share of ground motions on which the analytic model and the engine both "
        "overturn, or both rock with &theta;<sub>max</sub>/&alpha; within 3 % (the rule of the verdict above, "
        "here on the scenario each explanation was measured on). The reachable agreement is what a correct model "
        "could still reach: the lower of the <a href='#glossary-chaos-floor'>chaos floor</a> and the "
        "model-form limit (two correct integrators' conventions agreeing with each other). The measured maps "
        "are the engine's own impact law (energy kept against the speed of the impact) and flight loss, "
        "measured on free rocking and composed into the analytic model (figure below); their scatter limit is"
        " the agreement that model keeps with an engine whose impacts also scatter as measured (three "
        "realisations).",
    )


def _maps_cell(maps: MapsExplained | None, ks: KsDistances | None) -> str:
    """The agreement of Housner + the engine's measured maps, whether it reaches the floor, its KS."""
    if maps is None or not _measured(maps.agreement):
        return "&ndash;"
    reached = bool(maps.reaches_floor or maps.reaches_scatter_floor)
    badge = status_badge(reached, "reaches it", "below both")
    ks_m = ks.with_maps if ks is not None else None
    sf = maps.scatter_floor.share
    return (
        f"{_pct(maps.agreement)} {badge}"
        + (f"<br><small>scatter limit {_pct(sf)}</small>" if _measured(sf) else "")
        + (f"<br><small>KS {fmt_g(ks_m, 3)}</small>" if _measured(ks_m) else "")
    )


def _maps_figure(found: dict[str, StoredFile]) -> str:
    """The engines' measured impact and flight maps in one figure (drawn from the stored explanations)."""
    explained = {name: Explanation.from_json(s.data) for name, s in found.items() if isinstance(s.data, dict)}
    measured = {name: e.maps.maps for name, e in explained.items() if e.maps is not None and e.maps.maps is not None}
    if not measured:
        return ""
    maps = list(measured.values())
    data = {name: jsonable(m.to_dict(), nonfinite="null") for name, m in measured.items()}
    return html_stored_figure(
        maps_figure,
        (maps,),
        data,
        "Each engine's measured impact map (the kinetic-energy "
        "ratio of an impact over Housner's, against the impact speed) and flight map (the "
        "equivalent viscous loss between impacts), with Housner's constants",
        "impact and flight maps",
    )


def current_point(fr: Frontier, defaults: dict) -> int | None:
    """Index of the point whose swept settings equal the engine's ``defaults`` now, or None."""
    if not defaults:
        return None
    for i, p in enumerate(fr.points):
        full = {**fr.defaults, **p.settings}
        if all(k in defaults and same_setting(full[k], defaults[k]) for k in fr.axes):
            return i
    return None


def _score_html(p) -> str:
    """The tuner's score (largest error over its tolerance) and the checks not met, small under the badge."""
    score = f"score {p.score:.2f}" if math.isfinite(p.score) else ""
    return f"<br><small>{'; '.join(x for x in (score, esc(p.failed)) if x)}</small>"


def _frontier_rows(fr: Frontier, now: int | None) -> list[list[str]]:
    rows = []
    for i, p in enumerate(fr.points):
        marks = (
            ("swept from", i == fr.default and now != fr.default),
            ("knee", i == fr.knee),
            ("the defaults now", i == now),
        )
        mark = ", ".join(m for m, on in marks if on)
        if p.error:
            rows.append([esc(p.label), f"failed: {esc(p.error)}", *[""] * 8])
            continue
        se = p.agreement_se()
        rows.append(
            [
                f"<code>{esc(p.label)}</code>" + (f" <b>{mark}</b>" if mark else ""),
                _signed(p.r_error, "+.2%"),
                _signed(p.small_error, "+.2%"),
                _signed(p.decay_error, "+.1%"),
                _signed(p.pulse_error, "+.2%"),
                status_badge(p.checks_met, "met", "NOT met") + _score_html(p),
                f"{p.agreement:.0%} &plusmn; {se:.0%}",
                _pct(p.floor),
                f"{p.ks:.3f}",
                fmt_g(p.cpu_per_sim_second, 3),
            ]
        )
    return rows


def _frontier(run: Run, name: str, stored: StoredFile) -> str:
    try:
        fr = Frontier.from_dict(stored.data)
    except (KeyError, TypeError, ValueError) as e:
        return html_note(f"{engine_tag(name, run)}: the frontier file cannot be read ({esc(e)})", "warn")
    table = html_table(
        [
            "point",
            "r error 0.2-0.9 &alpha;",
            "small-amplitude r",
            "decay, 40 impacts",
            "pulses",
            "tuner checks",
            "agreement &plusmn; SE",
            "reachable agreement",
            "KS",
            "CPU s per sim. s",
        ],
        _frontier_rows(fr, current_point(fr, engine_defaults(name))),
        caption=f"{engine_tag(name, run)} on <code>{esc(fr.scenario)}</code> ({fr.n_motions} motions), measured "
        f"{esc(fr.date)}, version {esc(fr.version)}; errors are the worst by magnitude. Knee: "
        f"{esc(knee_reason(fr))}.",
    )
    used = run.meta.engine_settings(name)
    differ = settings_differ(fr.knee_settings(), used)
    note = html_note(f"This run's {esc(', '.join(differ))} differ from the knee's.", "warn") if differ else ""
    fig = html_stored_figure(
        frontier_figure, (fr,), fr.to_dict(), f"{esc(name)}: accuracy against cost", f"{name} frontier"
    )
    return f"<h4>{engine_tag(name, run)}</h4>{table}{note}{fig}"


def has_engine_measurements(run: Run) -> bool:
    """Whether an engine of the run other than the reference has a stored explanation or frontier."""
    kinds = ("explain", "frontier")
    return any(name != run.reference and any(model_file(k, name).is_file() for k in kinds) for name in run.engines)


def engines_explained(run: Run) -> str:
    """HTML: each engine's decomposition (explain) and its accuracy-cost frontier, from the stored files."""
    expl = {k: v for k, v in model_data(run, "explain").items() if k != run.reference}
    front = {k: v for k, v in model_data(run, "frontier").items() if k != run.reference}
    if not expl and not front:
        return html_note(
            "No stored explanation or frontier for these engines (engines/models/explain-&lt;engine&gt;.json, "
            "frontier-&lt;engine&gt;.json). <code>housner explain ENGINE --json FILE</code> and "
            "<code>housner frontier ENGINE --json FILE</code> measure them."
        )
    out = []
    if expl:
        out.append("<h3>The departure, decomposed</h3>" + _decomposition(run, expl) + _maps_figure(expl))
    if front:
        out.append(
            "<h3>Accuracy against cost</h3><p>Each engine's time step and main contact setting swept, the "
            "other settings at their defaults: the tuner's checks, per-record agreement with the analytic "
            "model and KS on the scenario's ground motions, and the CPU time.</p>"
        )
        out += [_frontier(run, name, stored) for name, stored in front.items()]
    return "".join(out)
