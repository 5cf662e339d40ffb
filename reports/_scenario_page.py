"""The page of a scenario's report, a run's (:mod:`housner.reports.run`) or a study's (:mod:`housner.reports.study`).

One layout: a header naming the scenario, its specimen, the engines and the reference and when it ran;
the sections; a footer naming the function that wrote the page (:func:`housner.reports.page.document`).
"""

from __future__ import annotations

from typing import Any

from housner.reports.page import Section, document, engine_tag, esc, written_by


def scenario_page(
    view: Any,
    sections: list[Section],
    seconds: float,
    *,
    title: str,
    heading: str,
    writer: str,
    specimen: str,
    n_motions: Any = None,
) -> str:
    """The HTML page of a run or study directory.

    Parameters
    ----------
    view : housner.scenarios.runs.view.Run or housner.reports.study.view.StudyView
        The directory loaded: anything with ``meta`` (its metadata, with ``scenario`` and ``provenance``
        tables), ``path``, ``engines`` and ``reference``.
    sections : list of Section
        The page's sections, in order.
    seconds : float
        Time taken to build the page [s], for the footer.
    title : str
        What the page is, after the scenario's name in the browser's title (e.g. "housner report").
    heading : str
        What the page is, before the scenario's name in the heading (e.g. "Scenario").
    writer : str
        Dotted name of the public function that writes the page, for the footer.
    specimen : str
        The specimen's name.
    n_motions : int, optional
        Motions of the ensemble, shown after the specimen when given.

    Returns
    -------
    str
        A complete HTML5 document; the scenario is named by ``meta.scenario.name``, or else by
        the directory's name.
    """
    scen = view.meta.scenario
    name = scen.name or view.path.name
    created = view.meta.provenance.created or ""
    motions = "" if n_motions is None else f"{esc(n_motions)} motions &middot; "
    tags = ", ".join(engine_tag(e, view) for e in view.engines)
    subtitle = (
        f'<p class="sub">{esc(scen.description)}</p>'
        f'<p class="sub">{esc(specimen)} &middot; {motions}engines {tags} &middot; reference {esc(view.reference)}'
        f"{' &middot; run ' + esc(created) if created else ''}</p>"
    )
    footer = written_by(writer, view.path, seconds)
    return document(f"{name}: {title}", f"{heading} <code>{esc(name)}</code>", subtitle, sections, footer)
