"""HTML pieces shared by the run, study and diagnosis reports (:mod:`housner.reports.run`, ...).

Cells (:func:`fmt_num`, :func:`fmt_p`, :func:`fmt_g`, :func:`ci_cell`), blocks
(:func:`html_table`, :func:`html_figure`, :func:`html_note`, :func:`status_badge`),
sections (:class:`Section`, :func:`guarded`), the page (:func:`document`, one
style sheet :data:`CSS`) and its atomic write (:func:`write_page`). Everything is
self-contained: figures are base64 PNGs, the style is inline, there is no script.
"""

from __future__ import annotations

import hashlib
import html
import inspect
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from housner._values import json_number
from housner.reports import figures
from housner.reports.glossary import spell_out
from housner.scenarios.execution.cache import code_version, content_key, default_cache_dir, store_text


def esc(x: Any) -> str:
    return html.escape(str(x), quote=True)


def fmt_num(x: Any, digits: int = 3, *, inf: str = "overturn") -> str:
    """A number for a table cell: +inf as ``inf``, NaN as an en dash."""
    v = json_number(x) if not isinstance(x, (int, float, np.integer, np.floating)) else float(x)
    if math.isnan(v):
        return "&ndash;"
    if math.isinf(v):
        return inf if v > 0 else "&minus;&infin;"
    return f"{v:.{digits}f}"


def fmt_p(x: Any) -> str:
    """A p-value: two decimals, or scientific notation below 0.01."""
    v = json_number(x)
    if math.isnan(v):
        return "&ndash;"
    return f"{v:.2f}" if v >= 0.01 else f"{v:.1e}"


def fmt_g(x: Any, digits: int = 4) -> str:
    v = json_number(x)
    if math.isnan(v):
        return esc(x) if isinstance(x, str) else "&ndash;"
    return f"{v:.{digits}g}"


def ci_cell(value: Any, low: Any, high: Any, digits: int = 2) -> str:
    """'value [low, high]' with overturn for +inf."""
    return f"{fmt_num(value, digits)} <span class=ci>[{fmt_num(low, digits)}, {fmt_num(high, digits)}]</span>"


def html_table(header: list[str], rows: list[list[str]], *, cls: str = "", caption: str = "") -> str:
    """An HTML table with its caption below; header and cells are HTML already (escape data before).

    An all-empty header is left out. The caption is a paragraph under the table
    rather than a <caption>, so that a narrow table does not squeeze its text.
    """
    head = ""
    if any(header):
        head = "<thead><tr>" + "".join(f"<th>{c}</th>" for c in header) + "</tr></thead>"
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in r) + "</tr>" for r in rows)
    cap = f'<p class="caption">{caption}</p>' if caption else ""
    return f'<div class="tbl"><table class="{cls}">{head}<tbody>{body}</tbody></table>{cap}</div>'


def html_figure(fig, caption: str, alt: str) -> str:
    return _figure_html(figures.to_png_base64(fig), caption, alt)


def _figure_html(png_base64: str, caption: str, alt: str) -> str:
    return (
        f'<figure><img src="data:image/png;base64,{png_base64}" alt="{esc(alt)}">'
        f"<figcaption>{caption}</figcaption></figure>"
    )


#: The base64 of a PNG file's signature: how every stored figure begins.
_PNG_BASE64 = "iVBORw0KGgo"


def html_stored_figure(draw: Callable[..., Any], args: tuple, data: Any, caption: str, alt: str) -> str:
    """:func:`html_figure` of ``draw(*args)``, a figure drawn from stored data only (a shipped frontier, say).

    ``data`` is that stored data, as read (JSON-able): ``args`` must follow from it. The PNG is
    kept in the result cache's folder (``$HOUSNER_CACHE_DIR`` or ``~/.cache/housner``,
    ``figures/``) under a hash of ``data``, of the source of the module that defines ``draw`` and
    of matplotlib's version, so a report draws it once per machine rather than once per run (each
    frontier is 0.5-0.7 s of matplotlib; five of them were 2.3 s of a 5 s report). A cache that
    cannot be read or written is skipped.
    """
    path = _stored_figure_path(draw, data)
    if path is not None:
        try:
            png = path.read_text(encoding="ascii")
            if png.startswith(_PNG_BASE64):  # else damaged: drawn again
                return _figure_html(png, caption, alt)
        except (OSError, UnicodeDecodeError):
            pass
    png = figures.to_png_base64(draw(*args))
    if path is not None:
        store_text(path, png)
    return _figure_html(png, caption, alt)


def _stored_figure_path(draw: Callable[..., Any], data: Any) -> Path | None:
    """Where :func:`html_stored_figure` keeps this figure's PNG, or None when the drawing code cannot be read."""
    import matplotlib

    try:
        source = Path(inspect.getsourcefile(draw) or "").read_bytes()
    except (TypeError, OSError):
        return None
    content = {
        "what": "figure",
        "data": data,
        "draw": f"{draw.__module__}.{draw.__qualname__}",
        "source": hashlib.sha256(source).hexdigest(),
        "matplotlib": matplotlib.__version__,
        "code": code_version(),
    }
    return default_cache_dir() / "figures" / f"{content_key(content)[:32]}.b64"


def html_note(text: str, kind: str = "note") -> str:
    return f'<p class="{kind}">{text}</p>'


def status_badge(ok: bool | None, yes: str = "PASS", no: str = "FAIL") -> str:
    if ok is None:
        return '<span class="badge na">not evaluated</span>'
    return f'<span class="badge {"pass" if ok else "fail"}">{yes if ok else no}</span>'


def view_colors(view: Any) -> dict[str, str]:
    """Engine -> its colour on a page of ``view``, anything with ``engines`` and ``reference`` (a run or a study):
    :func:`housner.reports.figures.engine_colors` in the view's engine order."""
    return figures.engine_colors(view.engines, view.reference)


def engine_tag(name: str, view: Any) -> str:
    """An engine's name with its colour swatch (:func:`view_colors`)."""
    c = view_colors(view).get(name, "#000")
    return f'<span class="eng"><span class="swatch" style="background:{c}"></span>{esc(name)}</span>'


@dataclass
class Section:
    id: str
    title: str
    body: str


def guarded(title: str, build: Callable[[], str]) -> str:
    """Build a section body; an error in one optional part is shown in the page, not fatal."""
    try:
        return build()
    except Exception as e:  # a figure helper of another module failing must not lose the whole report
        return html_note(f"{esc(title)} could not be drawn: <code>{esc(type(e).__name__)}: {esc(e)}</code>", "warn")


def fmt_signed(v: Any, digits: int = 2) -> str:
    """A difference with its sign ("+0.00" for a rounded zero), an en dash when undefined."""
    v = json_number(v)
    if not math.isfinite(v):
        return "&ndash;"
    return f"{0.0 if round(v, digits) == 0 else v:+.{digits}f}"


def fmt_pct(x: Any) -> str:
    v = json_number(x)
    return "&ndash;" if math.isnan(v) else f"{v:.0%}"


CSS = """
:root { --fg:#1d2327; --muted:#5f6b73; --line:#d8dee4; --bg:#ffffff; --alt:#f6f8fa; --accent:#0b5394; }
* { box-sizing: border-box; }
body { font: 15px/1.5 system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif;
       color: var(--fg); background: var(--bg); margin: 0; }
main { max-width: 1080px; margin: 0 auto; padding: 1.5rem 1.5rem 4rem; }
header.top { border-bottom: 3px solid var(--accent); margin-bottom: 1rem; }
h1 { font-size: 1.6rem; margin: 0.2rem 0; }
h2 { font-size: 1.3rem; border-bottom: 1px solid var(--line); padding-bottom: .2rem; margin-top: 2.4rem; }
h3 { font-size: 1.05rem; margin-top: 1.6rem; }
h4 { font-size: 0.98rem; margin: 1rem 0 .3rem; }
.sub { color: var(--muted); margin: 0 0 .6rem; }
nav.toc { background: var(--alt); border: 1px solid var(--line); border-radius: 6px; padding: .5rem 1rem;
          margin: 1rem 0; }
nav.toc ol { margin: .3rem 0; padding-left: 1.4rem; columns: 2; }
a { color: var(--accent); }
table { border-collapse: collapse; margin: .8rem 0; font-size: 0.92rem; }
th, td { border: 1px solid var(--line); padding: .3rem .55rem; text-align: left; vertical-align: top; }
thead th { background: var(--alt); font-weight: 600; }
tbody tr:nth-child(even) { background: #fbfcfd; }
div.tbl { margin: .8rem 0 1.2rem; overflow-x: auto; }
div.tbl table { margin: 0; }
p.caption { color: var(--muted); font-size: .86rem; margin: .3rem 0 0; max-width: 60rem; }
table.kv td:first-child { color: var(--muted); }
table.headline { font-size: 0.98rem; }
table.failures code { white-space: pre-wrap; word-break: break-word; }
.ci { color: var(--muted); font-size: .86em; white-space: nowrap; }
figure { margin: 1rem 0; }
figure img { max-width: 100%; height: auto; border: 1px solid var(--line); border-radius: 4px; }
figcaption { color: var(--muted); font-size: .88rem; max-width: 60rem; margin-top: .3rem; }
.badge { display: inline-block; border-radius: 4px; padding: 0 .45rem; font-weight: 700; font-size: .85rem;
         letter-spacing: .03em; white-space: nowrap; }
.badge.pass { background: #dff0d8; color: #2b6a2b; border: 1px solid #9ccc9c; }
.badge.fail { background: #f2dede; color: #a94442; border: 1px solid #e4a5a5; }
.badge.na { background: #eee; color: #555; border: 1px solid #ccc; }
.badge.warn { background: #fcefd2; color: #7a5200; border: 1px solid #e2bf6e; }
ul.verdicts { list-style: none; padding: 0; font-size: 1.05rem; }
ul.verdicts li { margin: .55rem 0; max-width: 64rem; }
ul.verdicts div.figs { color: var(--muted); font-size: .86rem; margin: .15rem 0 0 1.2rem; }
div.caveat { font-size: .88rem; max-width: 60rem; margin: .2rem 0 .4rem 1.2rem; padding: .3rem .6rem;
             background: #fcf8e3; border-left: 3px solid #f0e1a1; }
.ok { color: #2b6a2b; } .bad { color: #a94442; font-weight: 600; } .muted { color: var(--muted); }
.eng { white-space: nowrap; font-weight: 600; }
.swatch { display: inline-block; width: .8em; height: .8em; border-radius: 2px; margin-right: .35em;
          vertical-align: baseline; }
p.note { color: var(--muted); font-size: .9rem; max-width: 60rem; }
p.warn { background: #fcf8e3; border: 1px solid #f0e1a1; padding: .4rem .7rem; border-radius: 4px; }
p.good { color: #2b6a2b; }
ul.cause { max-width: 62rem; } ul.cause li { margin: .35rem 0; }
pre { background: var(--alt); border: 1px solid var(--line); padding: .7rem; overflow-x: auto; font-size: .85rem; }
code { font-size: .9em; }
footer { color: var(--muted); font-size: .82rem; margin-top: 3rem; border-top: 1px solid var(--line); }
p.lead { font-size: 1.08rem; background: var(--alt); border-left: 4px solid var(--accent); padding: .6rem .9rem; }
span.warn { color: #8a6d3b; font-weight: 600; }
dl.glossary { max-width: 62rem; } dl.glossary dt { font-weight: 600; margin-top: .6rem; }
dl.glossary dd { margin: .1rem 0 0 1.2rem; }
"""


def document(title: str, heading: str, subtitle: str, sections: list[Section], footer: str) -> str:
    """A complete HTML5 page: header, table of contents, the sections, a footer.

    ``heading``, ``subtitle`` and ``footer`` are HTML already; ``title`` and the
    section titles are escaped here.
    """
    toc = "".join(f'<li><a href="#{s.id}">{esc(s.title)}</a></li>' for s in sections)
    body = "".join(f'<section id="{s.id}"><h2>{esc(s.title)}</h2>{s.body}</section>' for s in sections)
    return spell_out(
        "<!DOCTYPE html>\n"
        '<html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        '<link rel="icon" href="data:,">'
        f"<title>{esc(title)}</title><style>{CSS}</style></head><body><main>"
        f'<header class="top"><h1>{heading}</h1>{subtitle}</header>'
        f'<nav class="toc"><strong>Contents</strong><ol>{toc}</ol></nav>'
        f"{body}<footer><p>{footer}</p></footer>"
        "</main></body></html>\n"
    )  # every abbreviation spelled out at its first use


def write_page(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` (parents created) through a temporary file, so that no half page is left."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)
    return path


def render_directory(
    directory: str | Path,
    load: Callable[[str | Path], Any],
    sections: Callable[[Any], list[Section]],
    page: Callable[[Any, list[Section], float], str],
) -> str:
    """The report of a run or study directory: ``load`` it, build its ``sections``, lay out its ``page``.

    ``page`` is given the view, the sections and the seconds taken (for :func:`written_by`).
    """
    t0 = time.perf_counter()
    view = load(directory)
    return page(view, sections(view), time.perf_counter() - t0)


def write_directory_report(
    directory: str | Path, out: str | Path | None, render: Callable[[str | Path], str], name: str
) -> Path:
    """Write ``render(directory)`` to ``out``, by default to the file ``name`` in ``directory``; returns the file."""
    path = Path(out) if out is not None else Path(directory) / name
    return write_page(path, render(directory))


def written_by(writer: str, source: str | Path, seconds: float) -> str:
    """The footer of a report: the function that wrote it, from which directory, in how long."""
    return f"Written by <code>{writer}</code> from <code>{esc(source)}</code> in {seconds:.1f} s."
