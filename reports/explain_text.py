"""``housner explain``'s words: what remains, where the records part, the console summary and the JSON document,
rendered from the typed :class:`~housner.scenarios.runs.explain.Explanation` (``docs/how-to/explain-engine.md``).

Two readers get their own words from the same figures: the command line and its JSON (the diagnosis' terms: the
correct-model floor, the residual ratio) and the run report's page (:func:`page_remains_text`: the page has one
floor, the reachable agreement, and does not explain the diagnosis' test statistics).
"""

from __future__ import annotations

import json
from pathlib import Path

from housner.reports.diagnosis.verdict_text import pointer_text
from housner.reports.diagnosis.words import evidence_text
from housner.scenarios.runs.departure import DEPART_TOL, SMALL_ROCKING, DepartureSummary
from housner.scenarios.runs.explain import REACH_MARGIN, Explanation, KsDistances
from housner.scenarios.runs.explain_maps import MapsExplained

__all__ = [
    "departures_text",
    "explain_document",
    "explanation_summary",
    "maps_remains_text",
    "page_maps_remains_text",
    "page_remains_text",
    "remains_text",
    "write_explain_json",
]

#: Statuses of the diagnosis that leave nothing for an effect to explain.
_DONE = ("explained", "no_misfit")

_WHERE = {
    "uplift": "before the first impact (at uplift or in the first half-cycle)",
    "small rocking": f"in small rocking (below {SMALL_ROCKING:g} alpha) after an impact",
    "rocking": f"in rocking above {SMALL_ROCKING:g} alpha after an impact",
}


def departures_text(s: DepartureSummary) -> str:
    """Where the records that disagree part, in one or two sentences ("" for no record)."""
    if not s.n:
        return ""
    parts = [f"{k} {'part' if k != 1 else 'parts'} {_WHERE[ph]}" for ph in _WHERE if (k := s.by_phase.get(ph, 0))]
    never = s.by_phase.get("never", 0)
    if never:
        parts.append(f"{never} never part by {DEPART_TOL:g} alpha (they differ only in the peak's last few per cent)")
    text = f"Of the {s.n} records where they disagree, " + "; ".join(parts) + "."
    q = s.impacts_before
    if q.median == q.median:  # some records part after an impact
        text += (
            f" Those that part after an impact do so after a median {q.median:.0f} impacts "
            f"(quartiles {q.q25:.0f}-{q.q75:.0f})."
        )
    return text


def _where(e: Explanation) -> str:
    """The verdict's pointer, else the misfit that remains, else the first quantity where the model differs."""
    d = e.diagnosis
    if d.next:
        return pointer_text(d.next)
    if d.status == "partly_explained":
        return f"A misfit of {d.residual_ratio:.2f}x the floor (the worse group of records) remains."
    return f"it differs in {evidence_text(d.where[0])}." if d.where else ""


def _head(e: Explanation) -> str:
    model = " + ".join(["Housner", *(f.name for f in e.effects)])
    return f"{model} agrees with {e.engine} on {e.agreement:.0%} of the records"


def remains_text(e: Explanation) -> str:
    """What is left and where, in one sentence or two, in the diagnosis' terms."""
    return _remains(e, page=False)


def page_remains_text(e: Explanation) -> str:
    """What is left, in the run report's words: the floor called the reachable agreement, the gap in points, the
    diagnosis' status without its test statistics, and the class to look at first."""
    return _remains(e, page=True)


def _remains(e: Explanation, *, page: bool) -> str:
    """:func:`remains_text` (the diagnosis' terms) or, ``page``, :func:`page_remains_text` (the run report's): the
    same sentences, the floor named and the gap counted in each reader's words."""
    floor = "reachable agreement" if page else "floor"
    head, status = _head(e), e.diagnosis.status.replace("_", " ")
    if e.reaches_floor and e.diagnosis.status in _DONE:
        return (
            f"Nothing beyond the {floor}: {head}, against a {floor} of {e.floor:.0%}, and the diagnosis finds "
            f"{status} in the time histories."
        )
    short = f"{(e.floor - e.agreement) * 100:.0f} points" if page else f"{e.floor - e.agreement:.0%}"
    gap = f"{short} below the {floor} of {e.floor:.0%}" if not e.reaches_floor else f"at the {floor} of {e.floor:.0%}"
    if e.diagnosis.status in _DONE:
        leaves = "" if page else ", not in the errors a correct model leaves"
        return (
            f"{head}, {gap}, though the diagnosis finds {status} in the time histories: what remains shows in the "
            f"records' peaks and overturns{leaves}."
        )
    if page:
        look = f" Where to look first: {e.diagnosis.next[0].meaning}." if e.diagnosis.next else ""
        said = f"; the diagnosis is {status}" if status else ""  # a file without its diagnosis says none
        return f"{head}, {gap}{said}.{look}"
    return (
        f"{head}, {gap}; the diagnosis is {status} (residual ratio {e.diagnosis.residual_ratio:.2f} against the "
        f"correct-model floor). {_where(e)}"
    ).strip()


def _maps_head(engine: str, mp: MapsExplained) -> str:
    return f"Housner + {engine}'s measured maps agrees with {engine} on {mp.agreement:.0%} of the records"


def _maps_spread(mp: MapsExplained) -> str:
    small, large = mp.maps.at(0.05), mp.maps.at(0.5)
    return (
        f"standard deviation of r/r_housner {small['ratio_spread']:.3f} at x = 0.05 and "
        f"{large['ratio_spread']:.3f} at x = 0.5, the band of the maps' figure"
    )


def maps_remains_text(e: Explanation) -> str:
    """What is left with the engine's measured maps ("" when they were not measured)."""
    mp = e.maps
    if mp is None or mp.maps is None:
        return ""
    head, spread = _maps_head(e.engine, mp), _maps_spread(mp)
    floor, sf, where = e.floor, mp.scatter_floor.share, departures_text(mp.departures)
    if mp.reaches_floor:
        return f"{head}, at the floor of {floor:.0%}: the departure is explained by what was measured."
    if mp.reaches_scatter_floor:
        return (
            f"{head}, {floor - mp.agreement:.0%} below the floor of {floor:.0%}, but as many as the maps' mean keeps "
            f"with an engine whose impacts scatter as {e.engine}'s were measured to ({spread}): {sf:.0%} (the "
            f"scatter floor). The departure is explained by what was measured, the mean impact law and its "
            f"scatter; no model with one law per impact can follow it record by record. {where}"
        ).strip()
    return (
        f"{head}, {floor - mp.agreement:.0%} below the floor of {floor:.0%} and below the {sf:.0%} the maps' "
        f"mean keeps with an engine whose impacts scatter as measured ({spread}): something else departs. {where}"
    ).strip()


def page_maps_remains_text(e: Explanation) -> str:
    """:func:`maps_remains_text` in the run report's words (the floor called the reachable agreement)."""
    mp = e.maps
    if mp is None or mp.maps is None:
        return ""
    head = _maps_head(e.engine, mp)
    if mp.reaches_floor:
        return f"{head}, at the reachable agreement: the departure is explained by what was measured."
    below = f"{(e.floor - mp.agreement) * 100:.0f} points below the reachable agreement of {e.floor:.0%}"
    if mp.reaches_scatter_floor:
        return (
            f"{head}, {below}, but as many as the maps' mean keeps with an engine whose impacts scatter as "
            f"measured ({mp.scatter_floor.share:.0%}): explained by the mean impact law and its scatter."
        )
    return f"{head}, {below} and below the {mp.scatter_floor.share:.0%} its measured scatter allows."


def explanation_summary(e: Explanation) -> str:
    """A few lines for the console: effects, agreement before and after beside the floor, reaching it, what
    remains (with the maps, where measured)."""
    eff = (
        "; ".join(f"{f.name} ({', '.join(f'{k} = {v:.4g}' for k, v in f.params.items())})" for f in e.effects) or "none"
    )
    fp, d, ks = e.floor_parts, e.diagnosis, e.ks or KsDistances()
    lines = [
        f"{e.engine} on {e.scenario} ({e.n_records} ground motions): diagnosis {d.status}",
        f"effects: {eff}",
        f"agreement with {e.engine}: plain Housner {e.agreement_plain:.0%} -> with the effects {e.agreement:.0%}; "
        f"floor {e.floor:.0%} (the lower of chaos {fp.chaos:.0%} and model form {fp.model_form:.0%})",
        f"reaches the floor (within {REACH_MARGIN:.0%}): {'yes' if e.reaches_floor else 'no'}",
        f"KS distance from {e.engine}: plain {ks.plain:.3f} -> with the effects {ks.with_effects:.3f}",
        f"held-out error {d.heldout_error.before:.4f} -> {d.heldout_error.after:.4f} alpha, "
        f"residual ratio {d.residual_ratio:.2f}",
        f"remains: {remains_text(e)}",
    ]
    m = e.maps
    if m is not None:
        with_maps = ks.with_maps if ks.with_maps is not None else float("nan")
        lines += [
            f"with {e.engine}'s measured impact and flight maps: agreement {m.agreement:.0%} "
            f"(plain {e.agreement_plain:.0%}, floor {e.floor:.0%}), KS {with_maps:.3f}; "
            f"reaches the floor: {'yes' if m.reaches_floor else 'no'}",
            f"remains with the maps: {maps_remains_text(e)}",
        ]
    return "\n".join(lines)


def explain_document(e: Explanation) -> dict:
    """The explain JSON's content: the value's data (NaN as null) with its words: ``remains``, the diagnosis'
    ``text`` (what remains in its terms: status, residual ratio, where to look) and, with the maps, the maps'
    ``remains`` and each departure summary's ``text``."""
    data = e.to_dict()
    data["remains"] = remains_text(e)
    data["diagnosis"]["text"] = _where(e)
    if e.maps is not None and data.get("maps"):
        data["maps"]["remains"] = maps_remains_text(e)
        for key in ("departures", "departures_plain"):
            data["maps"][key]["text"] = departures_text(getattr(e.maps, key))
    return data


def write_explain_json(e: Explanation, path: str | Path) -> None:
    """Write :func:`explain_document` to ``path`` (strict JSON)."""
    Path(path).write_text(json.dumps(explain_document(e), indent=2, allow_nan=False))
