"""The reports' words: every abbreviation spelled out at its first use on a page, and a glossary at its end.

:func:`spell_out` rewrites a page's HTML so that the first time each abbreviation of
:data:`ABBREVIATIONS` appears in the page's text (not in code, a tag or the page's title) it
is followed by its words, e.g. "KS (Kolmogorov-Smirnov)"; :func:`glossary_html` is the
glossary section the run report ends with (:data:`GLOSSARY`, each entry with an anchor
``glossary-KEY`` that other sections link to).
"""

from __future__ import annotations

import re

__all__ = ["ABBREVIATIONS", "GLOSSARY", "glossary_html", "spell_out"]

#: Abbreviation -> its words, spelled out at the first use on a page (matched as a whole word, case kept).
ABBREVIATIONS = {
    "KS": "Kolmogorov&ndash;Smirnov",
    "RDK": "Rezaeian &amp; Der Kiureghian",
    "CDF": "cumulative distribution function",
    "CI": "confidence interval",
    "Seed paper": "Bachmann et al., COMPDYN 2017",
    "seed paper": "Bachmann et al., COMPDYN 2017",
    "VSR": "Virtual Shake Robot, the PyBullet simulations published with these tests (Seismica 3(1))",
}

#: (anchor key, term as the page writes it (HTML), definition (HTML)), in reading order.
GLOSSARY = (
    (
        "theta-max",
        "&theta;<sub>max</sub>/&alpha;",
        "A record's largest absolute rotation of the block &theta;<sub>max</sub> [rad] divided by its slenderness "
        "&alpha;: 1 is the angle at which a block at rest would topple. <em>overturn</em> (+&infin; in the data) when "
        "the block fell.",
    ),
    (
        "alpha",
        "&alpha;",
        "The slenderness angle atan(B/H) [rad], B and H the half width between the pivots and the half height.",
    ),
    (
        "p",
        "p",
        "The frequency parameter &radic;(m g R / I<sub>0</sub>) [1/s], R the half diagonal and "
        "I<sub>0</sub> the moment of inertia about a pivot: the time scale of rocking.",
    ),
    (
        "r",
        "r",
        "The energy ratio of an impact: the kinetic energy just after a pivot change over the energy just "
        "before. Housner's r follows from the conservation of angular momentum about the new pivot (the seed paper's "
        "eq. 4: 0.9465 for its specimen); an engine's r is measured on free releases.",
    ),
    (
        "p-overturn",
        "P[overturn]",
        "The share of an ensemble's records in which the block overturned, with its 95 % "
        "Wilson score interval; &Delta;P[overturn] is an engine's minus the reference's.",
    ),
    (
        "ks",
        "KS distance",
        "Kolmogorov&ndash;Smirnov distance: the largest vertical gap between two cumulative "
        "distribution functions (CDFs) of &theta;<sub>max</sub>/&alpha; (overturns counted as +&infin;), from 0 "
        "(identical) to 1.",
    ),
    (
        "agreement",
        "records that agree",
        "Record by record, an engine agrees with the reference on a record when "
        "both overturn, or both rock with peaks &theta;<sub>max</sub>/&alpha; within 3 % of each other.",
    ),
    (
        "chaos-floor",
        "chaos floor",
        "Rocking is chaotic: a tiny change of r or p changes single records, not the "
        "distribution. The chaos floor is the lowest share of records on which the analytic model agrees with itself "
        "when its r and p are off by as much as an engine's are measured to be (four runs: r and p each up and down). "
        "An engine whose share of agreeing records reaches it (within its 95 % interval) departs record by record no "
        "more than its own measured errors explain.",
    ),
    ("ensemble", "ensemble", "The set of ground motions of a run, all engines on the same motions."),
    (
        "rdk",
        "RDK",
        "Ground motions generated with the stochastic model of Rezaeian &amp; Der Kiureghian (2010), its "
        "parameters fitted to a real record (here El Centro 1940 NS), scaled from the prototype to the model by the "
        "length scale S (time by &radic;S).",
    ),
    (
        "seed-paper",
        "seed paper",
        "Bachmann, J. A. et al. (2017), <em>Probabilistic validation of the Housner rocking "
        "model</em>, COMPDYN 2017: the specimen (2H = 0.5 m, 2B = 0.075 m, 3.94 kg) and the calibration this suite "
        "starts from.",
    ),
    (
        "ci",
        "CI",
        "Confidence interval: P[overturn]'s are Wilson score intervals; a median's and a share's are "
        "percentile bootstraps over the records or Wilson intervals, as each table says.",
    ),
)

_WORD = {k: re.compile(rf"(?<![\w&;-]){re.escape(k)}(?![\w-])") for k in ABBREVIATIONS}
#: Elements whose text is left as written: code, the head, and an abbreviation already spelled out.
_SKIP = ("code", "pre", "style", "title", "script", "abbr", "head")
_TAG = re.compile(r"(<[^>]*>)")


def spell_out(page: str) -> str:
    """``page`` (HTML) with the first use of each abbreviation in its text followed by its words in brackets.

    An abbreviation inside ``<code>``, ``<pre>``, ``<abbr>``, the head or a tag's attributes is left alone;
    "Seed paper" and "seed paper" count as one term.
    """
    todo = dict(ABBREVIATIONS)
    out, depth = [], 0
    for part in _TAG.split(page):
        if part.startswith("<"):
            name = re.match(r"</?\s*([a-zA-Z0-9]+)", part)
            if name and name.group(1).lower() in _SKIP and not part.endswith("/>"):
                depth += -1 if part.startswith("</") else 1
            out.append(part)
            continue
        if depth > 0 or not todo:
            out.append(part)
            continue
        for key in list(todo):
            m = _WORD[key].search(part)
            if m is None:
                continue
            words = todo.pop(key)
            todo.pop(key.lower() if key[0].isupper() else key.capitalize(), None)  # one term, either case
            part = f"{part[: m.end()]} ({words}){part[m.end() :]}"
        out.append(part)
    return "".join(out)


def glossary_html() -> str:
    """The glossary section's body: a definition list, each term with its anchor ``glossary-KEY``."""
    items = "".join(f'<dt id="glossary-{k}">{term}</dt><dd>{text}</dd>' for k, term, text in GLOSSARY)
    return f'<dl class="glossary">{items}</dl>'
