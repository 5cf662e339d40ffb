"""The HTML report of a fragility study: one self-contained page, figures embedded.

A study directory, written by the study runner, holds:

- ``study.json``: scenario, specimen, the study's settings (intensity measure,
  stripe levels, prototype heights and scale factors S, response thresholds,
  motions, bootstrap replicates, seed, confidence level, reference engine),
  engines with settings, versions and wall times, record counts, provenance;
- ``fragility.parquet``: overturns per (engine, size, stripe) with Wilson intervals;
- ``exceedance.parquet``: P[theta_max/alpha >= threshold] per (engine, size, stripe, threshold);
- ``fragility.json``: the lognormal fits per (engine, size) with bootstrap
  intervals and status, and each engine's comparison with the reference
  (ratio of medians, difference of betas, paired-bootstrap intervals);
- ``results.parquet``: one row per record (engine, size, stripe, motion).

:func:`write_study_report` writes ``report.html`` next to them. What the page
answers, top first: what was run and, per engine and size, whether its
fragility function agrees with the reference's within the intervals (only when
the interval of the ratio of medians contains 1 and that of the difference of
betas contains 0), and by how much it differs otherwise; then the fits per
size, the fragility curves, the median against size, the exceedance of
response thresholds, the stripe counts, the failed records and provenance. A
fit whose status is not "ok" (no overturn, all overturned, separated data ...)
is not a maximum-likelihood fit: the page gives its message and no number as
its median or beta.

References
----------
Baker, J. W. (2015). Efficient analytical fragility function fitting using
dynamic structural analysis. Earthquake Spectra 31(1), 579-599.
Efron, B., Tibshirani, R. (1993). An Introduction to the Bootstrap, ch. 13.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import pandas as pd
from housner.reports.figures import engine_colors
from housner.reports.page import (
    Section,
    ci_cell,
    document,
    esc,
    fmt_g,
    fmt_signed,
    guarded,
    html_figure,
    html_note,
    html_table,
    status_badge,
    write_page,
)
from housner.reports.run.sections.tuning import _settings_html
from housner.reports.study import figures as study_figures
from housner.scenarios.execution.rundir import json_number
from housner.scenarios.studies.study import EXCEEDANCE_FILE, FRAGILITY_FILE, REPORT_FILE, RESULTS_FILE, STUDY_FILE
from housner.scenarios.studies.study import FITS_FILE as FRAGILITY_JSON

from housner.errors import DataFileError

__all__ = ["render_study_report", "write_study_report"]

#: Failed records listed in full; beyond this the table is cut (the counts above it stay complete), so that a
#: study where an engine failed on thousands of records still gives a page a browser opens.
MAX_FAILURE_ROWS = 300

#: The disagreement sentence of the headline: it appears exactly where an interval excludes 1 (ratio) or 0 (difference).
DISAGREE = "the engines disagree beyond the intervals"


# ----------------------------------------------------------------------------
# public API
def render_study_report(study_dir: str | Path) -> str:
    """The HTML report of a study directory, as a string.

    Parameters
    ----------
    study_dir : str or pathlib.Path
        Directory written by the study runner; it must hold ``study.json`` and
        ``fragility.parquet``. ``fragility.json``, ``exceedance.parquet`` and
        ``results.parquet`` add sections; when one is absent or unreadable the
        page says so where it would be used.

    Returns
    -------
    str
        A complete HTML5 document with every figure embedded.

    Raises
    ------
    housner.errors.DataFileError
        When the directory, ``study.json`` or ``fragility.parquet`` is missing or unreadable.
    """
    t0 = time.perf_counter()
    study = _Study.load(study_dir)
    sections = _build_sections(study)
    return _page(study, sections, time.perf_counter() - t0)


def write_study_report(study_dir: str | Path, out: str | Path | None = None) -> Path:
    """Write the HTML report of a study directory.

    Parameters
    ----------
    study_dir : str or pathlib.Path
        A study directory (see :func:`render_study_report`).
    out : str or pathlib.Path, optional
        File to write; default ``study_dir/report.html``.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    path = Path(out) if out is not None else Path(study_dir) / REPORT_FILE
    return write_page(path, render_study_report(study_dir))


# ----------------------------------------------------------------------------
# the study directory
def _key(size: Any) -> float:
    """A size as a dictionary key: sizes pass through JSON and parquet, so equal ones may differ in the last bits."""
    return round(json_number(size), 9)


def _read_table(path: Path, required: bool) -> tuple[pd.DataFrame | None, str]:
    if not path.is_file():
        if required:
            raise DataFileError(path, "no such file; is this a finished study directory?")
        return None, f"<code>{esc(path.name)}</code> is missing from the study directory."
    try:
        return pd.read_parquet(path), ""
    except Exception as e:  # pyarrow and pandas raise many kinds; all mean "not a readable table"
        if required:
            raise DataFileError(path, f"cannot read as parquet: {e}") from None
        return None, f"<code>{esc(path.name)}</code> cannot be read: <code>{esc(e)}</code>."


def _read_json(path: Path, required: bool) -> tuple[dict, str]:
    if not path.is_file():
        if required:
            raise DataFileError(path, "no such file; is this a study directory?")
        return {}, f"<code>{esc(path.name)}</code> is missing from the study directory."
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as e:
        if required:
            raise DataFileError(path, f"invalid JSON: {e.msg} (column {e.colno})", line=e.lineno) from None
        return {}, f"<code>{esc(path.name)}</code> is not valid JSON: {esc(e.msg)} (line {e.lineno})."
    except OSError as e:
        if required:
            raise DataFileError(path, f"cannot read: {e.strerror or e}") from None
        return {}, f"<code>{esc(path.name)}</code> cannot be read: {esc(e.strerror or e)}."
    if not isinstance(data, dict):
        if required:
            raise DataFileError(path, "expected a JSON object")
        return {}, f"<code>{esc(path.name)}</code> does not hold a JSON object."
    return data, ""


@dataclass
class _Study:
    """A study directory read into memory, with the look-ups the sections share."""

    path: Path
    meta: dict
    fragility: pd.DataFrame
    exceedance: pd.DataFrame | None
    fits: list[dict]
    comparisons: list[dict]
    results: pd.DataFrame | None
    problems: dict[str, str] = field(default_factory=dict)

    @classmethod
    def load(cls, study_dir: str | Path) -> _Study:
        path = Path(study_dir).expanduser()
        if not path.is_dir():
            raise DataFileError(path, "no such directory (expected a study directory holding study.json)")
        meta, _ = _read_json(path / STUDY_FILE, required=True)
        fr, _ = _read_table(path / FRAGILITY_FILE, required=True)
        ex, ex_problem = _read_table(path / EXCEEDANCE_FILE, required=False)
        fj, fj_problem = _read_json(path / FRAGILITY_JSON, required=False)
        res, res_problem = _read_table(path / RESULTS_FILE, required=False)
        problems = {k: v for k, v in (("exceedance", ex_problem), ("fits", fj_problem), ("results", res_problem)) if v}
        fits = [f for f in fj.get("fits") or [] if isinstance(f, dict)]
        comparisons = [c for c in fj.get("comparisons") or [] if isinstance(c, dict)]
        return cls(path.resolve(), meta, fr, ex, fits, comparisons, res, problems)

    # --- the study's settings
    @property
    def settings(self) -> dict:
        return self.meta.get("study") or {}

    @property
    def reference(self) -> str:
        return str(self.settings.get("reference") or "housner")

    @property
    def label(self) -> str:
        return str(self.settings.get("intensity_label") or self.settings.get("intensity") or "intensity")

    @property
    def ci(self) -> float:
        c = json_number(self.settings.get("ci", 0.95))
        return c if 0.0 < c < 1.0 else 0.95

    @cached_property
    def engines(self) -> list[str]:
        """Engines of study.json in order, then any found only in the tables; the reference first."""
        names = list(self.meta.get("engines") or {})
        for frame in (self.fragility, self.results):
            if frame is not None and "engine" in frame:
                names.extend(str(e) for e in frame["engine"].unique())
        names.extend(str(f.get("engine")) for f in self.fits)
        names = list(dict.fromkeys(names))
        return sorted(names, key=lambda n: n != self.reference)

    @property
    def others(self) -> list[str]:
        return [e for e in self.engines if e != self.reference]

    @cached_property
    def colors(self) -> dict[str, str]:
        return engine_colors(self.engines, self.reference)

    @cached_property
    def sizes(self) -> list[float]:
        """Prototype heights [m], ascending: those of study.json and any found in the tables."""
        found = {_key(s) for s in self.settings.get("prototype_heights") or []}
        found |= {_key(s) for s in self.fragility.get("size", pd.Series(dtype=float))}
        found |= {_key(f.get("size")) for f in self.fits}
        return sorted(s for s in found if math.isfinite(s))

    def scale(self, size: float) -> float:
        """The scale factor S of a size (NaN when not recorded)."""
        heights = [_key(s) for s in self.settings.get("prototype_heights") or []]
        factors = self.settings.get("S") or []
        if size in heights and len(factors) == len(heights):
            return json_number(factors[heights.index(size)])
        for f in self.fits:
            if _key(f.get("size")) == size and "S" in f:
                return json_number(f["S"])
        rows = self.fragility[self.fragility["size"].map(_key) == size] if "size" in self.fragility else []
        return float(rows["S"].iloc[0]) if len(rows) and "S" in rows else math.nan

    def size_title(self, size: float) -> str:
        s = self.scale(size)
        return f"prototype height {size:g} m" + (f" (S = {s:g})" if math.isfinite(s) else "")

    # --- fits and comparisons
    def fit(self, engine: str, size: float) -> dict | None:
        for f in self.fits:
            if str(f.get("engine")) == engine and _key(f.get("size")) == size:
                return f
        return None

    def comparison(self, engine: str, size: float) -> dict | None:
        for c in self.comparisons:
            if str(c.get("engine")) == engine and _key(c.get("size")) == size:
                return c
        return None

    # --- records
    @cached_property
    def failed(self) -> pd.DataFrame:
        r = self.results
        if r is None or "status" not in r:
            return pd.DataFrame()
        return r[r["status"].astype(str) != "ok"]

    @cached_property
    def _counts(self) -> dict[tuple[str, float], tuple[int, int]]:
        """(engine, size) -> (usable, failed) records: from results.parquet, else the stripes' valid counts."""
        r = self.results
        if r is not None and {"engine", "size", "status"} <= set(r.columns):
            ok = (r["status"].astype(str) == "ok").rename("ok")
            g = ok.groupby([r["engine"].astype(str), r["size"].map(_key)]).agg(["sum", "size"])
            return {(e, s): (int(row["sum"]), int(row["size"] - row["sum"])) for (e, s), row in g.iterrows()}
        fr = self.fragility
        g = fr["n"].groupby([fr["engine"].astype(str), fr["size"].map(_key)]).sum()
        return {(e, s): (int(n), 0) for (e, s), n in g.items()}

    def record_counts(self, engine: str, size: float | None = None) -> tuple[int, int]:
        """(usable, failed) records of an engine, at one size or over all sizes."""
        hits = [v for (e, s), v in self._counts.items() if e == engine and (size is None or s == size)]
        return sum(v[0] for v in hits), sum(v[1] for v in hits)

    def valid_at(self, engine: str, size: float) -> int:
        """Records of an engine at a size that entered the stripe counts (0 when every one failed)."""
        fr = self.fragility
        sub = fr[(fr["engine"].astype(str) == engine) & (fr["size"].map(_key) == size)]
        return int(sub["n"].sum()) if len(sub) else 0


# ----------------------------------------------------------------------------
# HTML helpers
def _tag(name: str, study: _Study) -> str:
    c = study.colors.get(name, "#000")
    return f'<span class="eng"><span class="swatch" style="background:{c}"></span>{esc(name)}</span>'


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


def _int(x: Any, default: int = 0) -> int:
    """A count from JSON; ``default`` when it is absent or not a number (null, "nan")."""
    v = json_number(x)
    return int(v) if math.isfinite(v) else default


def _first_upper(text: str) -> str:
    # str.capitalize would lower the rest ("S = 1" -> "s = 1").
    return text[:1].upper() + text[1:]


def _is_ok(fit: Mapping | None) -> bool:
    return fit is not None and str(fit.get("status")) == "ok"


def _status_words(fit: Mapping | None) -> str:
    if fit is None:
        return "no fit in fragility.json"
    return str(fit.get("status") or "unknown").replace("_", " ")


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


def _verdict(study: _Study, engine: str, size: float) -> _Verdict:
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
        if c is not None and c.get("disagree") is True
        else ""
    )
    if not _is_ok(fe):
        return _Verdict("no fit", f"no verdict: its fit is degenerate ({esc(_status_words(fe))}, see below){flagged}")
    if not _is_ok(fr):
        words = esc(_status_words(fr))
        return _Verdict("not evaluated", f"no verdict: the reference's fit is degenerate ({words}, see below){flagged}")
    if c is None:
        return _Verdict("not evaluated", "no verdict: fragility.json holds no comparison with the reference")
    r, rl, rh = (json_number(c.get(k)) for k in ("median_ratio", "ratio_low", "ratio_high"))
    d, dl, dh = (json_number(c.get(k)) for k in ("beta_diff", "diff_low", "diff_high"))
    if not all(math.isfinite(v) for v in (r, rl, rh, d, dl, dh)):
        return _Verdict(
            "not evaluated",
            "no verdict: the bootstrap gave no interval for the comparison (every replicate's fit was degenerate)",
        )
    median_ok = rl <= 1.0 <= rh
    beta_ok = dl <= 0.0 <= dh
    r_ends = f"[{_end(rl, 1.0)}, {_end(rh, 1.0)}]"
    diff = f"{fmt_signed(d)} [{_end(dl, 0.0, signed=True)}, {_end(dh, 0.0, signed=True)}]"
    if median_ok:
        median = f"median within the interval: ratio to the reference's {fmt_g(r, 3)} {r_ends} contains 1"
    else:
        median = f'<span class="bad">median {fmt_g(r, 3)} times the reference\'s {r_ends}: {DISAGREE}</span>'
    if beta_ok:
        beta = f"beta within the interval: difference {diff} contains 0"
    else:
        side = "above" if d > 0 else "below"
        beta = (
            f'<span class="bad">beta {fmt_g(abs(d), 2)} {side} the reference\'s (difference {diff}): {DISAGREE}</span>'
        )
    agree = median_ok and beta_ok
    caveat = ""
    flag = c.get("disagree")
    if flag is not None and bool(flag) == agree:
        # The runner decides from the same intervals; a mismatch means the file was edited or written by another rule.
        caveat = (
            f"fragility.json marks this comparison disagree = {str(bool(flag)).lower()}, "
            "but its intervals say otherwise; the sentence above follows the intervals"
        )
    return _Verdict("agree" if agree else "disagree", f"{median}; {beta}", caveat)


# ----------------------------------------------------------------------------
# sections
def _overview(study: _Study) -> str:
    """What was run, in one paragraph."""
    s = study.settings
    meta = study.meta
    levels = [json_number(v) for v in s.get("levels") or []]
    sizes = study.sizes
    n_failed = _int(meta.get("n_failed"), len(study.failed))
    n_records = meta.get("n_records")
    if n_records is None and study.results is not None:
        n_records = len(study.results)
    wall = json_number(meta.get("wall_s"))
    engines = ", ".join(_tag(e, study) for e in study.engines)
    failed = f'<span class="bad">{n_failed} failed</span>' if n_failed else "none failed"
    return (
        f'<p class="lead">{len(study.engines)} engine{"s" if len(study.engines) != 1 else ""} ({engines}; reference '
        f"{esc(study.reference)}) &times; {len(sizes)} size{'s' if len(sizes) != 1 else ''} (prototype heights "
        f"{', '.join(f'{v:g}' for v in sizes)} m) &times; {len(levels)} stripes of {esc(study.label)} "
        f"({', '.join(f'{v:g}' for v in levels)}) &times; {esc(s.get('n_motions', '?'))} ground motions: "
        f"{esc(n_records if n_records is not None else '?')} records, {failed}"
        f"{f', wall time {fmt_g(wall, 4)} s' if math.isfinite(wall) else ''}.</p>"
    )


def _widest(study: _Study) -> float:
    """The largest distance of a median-ratio interval's end from 1 over the comparisons [-] (0 if none)."""
    ends = [abs(json_number(c.get(k)) - 1.0) for c in study.comparisons for k in ("ratio_low", "ratio_high")]
    ends = [e for e in ends if math.isfinite(e)]
    return max(ends, default=0.0)


def _headline(study: _Study) -> str:
    each = json_number(study.settings.get("compare_ci", study.ci))  # each comparison interval's level
    parts = [_overview(study)]
    for problem in study.problems.values():
        parts.append(html_note(problem, "warn"))
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
            items.append(f"<li>{_badge('no fit')} {_tag(engine, study)}: {why}; no fit, nothing to compare.</li>")
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
        items.append(f"<li>{_badge(overall)} {_tag(engine, study)} against {esc(ref)}<ul>{lines}</ul></li>")
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
            f"what {esc(s.get('n_motions', 'these'))} motions resolve, not proof of none (a difference smaller than "
            f"the interval, here up to {_widest(study):.0%} on the median, is not excluded). The intervals are "
            f"percentile bootstraps over the motions ({esc(s.get('n_boot', '?'))} replicates, seed "
            f"{esc(s.get('seed', '?'))}), paired: each replicate refits both engines on the same resampled motions, "
            "so the motion-to-motion scatter common to both cancels. Two intervals are checked per size, each at "
            f"{esc(f'{each:.1%}')} (Bonferroni), so engines that agree are called in disagreement with a probability "
            f"of at most about {1 - study.ci:.0%} per size."
        )
    )
    return "".join(parts)


def _degenerate(study: _Study) -> str:
    """The fits that are not maximum-likelihood fits, each with its message, and the caveats of those that are."""
    rows, caveats = [], []
    for size in study.sizes:
        for engine in study.engines:
            f = study.fit(engine, size)
            if f is None:
                if study.record_counts(engine, size)[0] or study.valid_at(engine, size):
                    where = f"{_tag(engine, study)} at {esc(study.size_title(size))}"
                    rows.append(f"<li>{where}: no fit in fragility.json</li>")
                continue
            if _is_ok(f):
                if f.get("caveat"):
                    caveats.append(f"<li>{_tag(engine, study)} at {esc(study.size_title(size))}: "
                                   f"{esc(f['caveat'])}</li>")  # fmt: skip
                continue
            msg = str(f.get("message") or "no message")
            rows.append(
                f"<li>{_tag(engine, study)} at {esc(study.size_title(size))}: <strong>{esc(_status_words(f))}"
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


def _fit_cells(study: _Study, engine: str, size: float) -> tuple[str, str]:
    f = study.fit(engine, size)
    if not _is_ok(f):
        return f'<span class="bad">no fit</span> ({esc(_status_words(f))})', "&ndash;"
    return (
        _ci_g(f.get("median"), f.get("median_low"), f.get("median_high")),
        ci_cell(f.get("beta"), f.get("beta_low"), f.get("beta_high"), 2),
    )


def _fits(study: _Study) -> str:
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
            if _is_ok(f) and f.get("n_boot") is not None:
                nf = _int(f.get("n_failed"))
                cell = f"{nf} of {_int(f['n_boot'])}"
                left_out = f'<span class="bad">{cell}</span>' if nf else cell
            if engine == ref:
                tag = f"{_tag(engine, study)} <small>(reference)</small>"
                rows.append([tag, median, beta, "&ndash;", "&ndash;", "reference", left_out])
                continue
            v = _verdict(study, engine, size)
            c = study.comparison(engine, size)
            if v.kind in ("agree", "disagree") and c is not None:
                ratio = _ci_g(c.get("median_ratio"), c.get("ratio_low"), c.get("ratio_high"))
                diff = _ci_signed(c.get("beta_diff"), c.get("diff_low"), c.get("diff_high"))
            else:
                # No comparison is shown where either fit is degenerate: its replicates are not a fit's interval.
                ratio = diff = "&ndash;"
            rows.append([_tag(engine, study), median, beta, ratio, diff, _badge(v.kind), left_out])
        parts.append(f"<h3>{esc(_first_upper(study.size_title(size)))}</h3>")
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


def _fragility_figures(study: _Study) -> str:
    parts = []
    for size in study.sizes:
        title = study.size_title(size)

        def build(size=size, title=title):
            kw = {"reference": study.reference, "colors": study.colors, "ci": study.ci}
            fig = study_figures.plot_fragility(study.fragility, study.fits, size, study.label, **kw)
            return html_figure(
                fig,
                f"Fragility at {esc(title)}: overturn fraction per stripe with Wilson {study.ci:.0%} intervals "
                "(points slightly shifted per engine so that the bars stand apart) and the fitted lognormal "
                "curves; a dashed curve is a degenerate fit (a step), not a maximum-likelihood fit, and an engine "
                "without a fitted median has no curve.",
                f"fragility curves at {title}",
            )

        parts.append(f"<h3>{esc(_first_upper(title))}</h3>")
        parts.append(guarded(f"The fragility figure at {esc(title)}", build))
    return "".join(parts) or html_note("No size in this study.", "warn")


def _size_figure(study: _Study) -> str:
    if len(study.sizes) < 2:
        return html_note("One size only: no size effect to draw.")

    def build():
        fig = study_figures.plot_size_effect(
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


def _exceedance_figures(study: _Study) -> str:
    if study.exceedance is None:
        return html_note(study.problems.get("exceedance", "No exceedance table."), "warn")
    thresholds = ", ".join(f"{v:g}" for v in sorted(study.exceedance["threshold"].dropna().unique()))
    parts = [
        html_note(
            f"Probability that the peak rotation reaches theta_max/alpha &ge; threshold ({thresholds}) at each stripe, "
            f"with Wilson {study.ci:.0%} intervals; an overturned block counts as exceeding every threshold."
        )
    ]
    for size in study.sizes:
        title = study.size_title(size)

        def build(size=size, title=title):
            fig = study_figures.plot_exceedance(
                study.exceedance, size, study.label, reference=study.reference, colors=study.colors, ci=study.ci
            )
            return html_figure(fig, f"Exceedance of response thresholds at {esc(title)}.", f"exceedance at {title}")

        parts.append(f"<h3>{esc(_first_upper(title))}</h3>")
        parts.append(guarded(f"The exceedance figure at {esc(title)}", build))
    return "".join(parts)


def _stripes(study: _Study) -> str:
    fr = study.fragility
    parts = []
    for size in study.sizes:
        sub = fr[fr["size"].map(_key) == size]
        engines = [e for e in study.engines if (sub["engine"].astype(str) == e).any()]
        stripes = sub.groupby("stripe")["intensity"].first().sort_index()
        rows = []
        for stripe, x in stripes.items():
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
        header = ["stripe", esc(study.label)] + [_tag(e, study) for e in engines]
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


def _failures(study: _Study) -> str:
    parts = []
    if study.results is None:
        n = _int(study.meta.get("n_failed"))
        note = study.problems.get("results", "No results table.")
        if n:
            return html_note(f"study.json counts {n} failed record(s), but they cannot be listed: {note}", "warn")
        return html_note(note, "warn")
    failed = study.failed
    if failed.empty:
        return html_note("No record failed.", "good")
    for engine in study.engines:
        ok, bad = study.record_counts(engine)
        if ok == 0 and bad:
            parts.append(html_note(f"Every record of {_tag(engine, study)} failed ({bad}).", "warn"))
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
            _tag(str(r.engine), study),
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


def _provenance(study: _Study) -> str:
    meta = study.meta
    parts = []
    scen = meta.get("scenario") or {}
    rows = [[esc(k), _kv_value(v)] for k, v in scen.items() if v not in (None, "")]
    rows += [[f"study: {esc(k)}", _kv_value(v)] for k, v in study.settings.items()]
    motions = meta.get("motions") or {}
    if isinstance(motions, dict):
        rows += [[f"motions: {esc(k)}", _kv_value(v)] for k, v in motions.items() if isinstance(v, (str, int, float))]
    for k in ("n_records", "n_failed", "wall_s"):
        if k in meta:
            rows.append([esc(k), _kv_value(meta[k])])
    parts.append(html_table(["", ""], rows, cls="kv"))
    spec = meta.get("specimen") or {}
    if spec:
        parts.append("<h3>Specimen</h3>")
        parts.append(html_table(["", ""], [[esc(k), _kv_value(v)] for k, v in spec.items()], cls="kv"))
    parts.append("<h3>Engines</h3>")
    info = meta.get("engines") or {}
    rows = []
    for name in study.engines:
        i = info.get(name) or {}
        settings = i.get("settings") or {}
        rows.append(
            [
                _tag(name, study),
                esc(i.get("version", "")) or "&ndash;",
                (_settings_html(settings) if isinstance(settings, dict) else esc(settings)) or "defaults",
                f"{fmt_g(i.get('wall_s'), 4)} s" if "wall_s" in i else "&ndash;",
                esc(i["cached"]) if "cached" in i else "&ndash;",
            ]
        )
    parts.append(
        html_table(
            ["engine", "version", "settings", "engine time", "records from the cache"],
            rows,
            caption="Engine time is summed over the records computed in this study (cached ones cost none).",
        )
    )
    prov = meta.get("provenance") or {}
    if prov:
        parts.append("<h3>Software and machine</h3>")
        rows = [[esc(k), esc(v)] for k, v in (prov.get("versions") or {}).items()]
        rows += [
            [esc(k.replace("_", " ")), f"<code>{esc(v)}</code>"]
            for k, v in prov.items()
            if k != "versions" and v not in (None, "")
        ]
        parts.append(html_table(["", ""], rows, cls="kv"))
    return "".join(parts)


def _build_sections(study: _Study) -> list[Section]:
    return [
        Section(
            "verdict",
            "Does each engine's fragility agree with the reference?",
            guarded("The verdict", lambda: _headline(study)),
        ),
        Section("fits", "Fits per size", guarded("The fit tables", lambda: _fits(study))),
        Section("fragility", "Fragility curves", _fragility_figures(study)),
        Section("size-effect", "Median capacity against size", _size_figure(study)),
        Section("exceedance", "Exceedance of response thresholds", _exceedance_figures(study)),
        Section("stripes", "Stripe counts", guarded("The stripe tables", lambda: _stripes(study))),
        Section("failures", "Failed records", guarded("The failed records", lambda: _failures(study))),
        Section("provenance", "Provenance", guarded("The provenance", lambda: _provenance(study))),
    ]


# ----------------------------------------------------------------------------
# the page
def _page(study: _Study, sections: list[Section], seconds: float) -> str:
    scen = study.meta.get("scenario") or {}
    name = scen.get("name") or study.path.name
    spec = (study.meta.get("specimen") or {}).get("name", "")
    created = (study.meta.get("provenance") or {}).get("created", "")
    subtitle = (
        f'<p class="sub">{esc(scen.get("description") or "")}</p>'
        f'<p class="sub">{esc(spec)} &middot; engines {", ".join(_tag(e, study) for e in study.engines)} '
        f"&middot; reference {esc(study.reference)}{' &middot; run ' + esc(created) if created else ''}</p>"
    )
    footer = (
        f"Written by <code>housner.reports.study.page.write_study_report</code> from <code>{esc(study.path)}</code> "
        f"in {seconds:.1f} s."
    )
    return document(f"{name}: fragility study", f"Fragility study <code>{esc(name)}</code>", subtitle, sections, footer)
