"""The HTML report of a scenario run: one self-contained page, figures embedded.

:func:`write_report` reads a run directory written by
:func:`scenarios.runner.write_run` (``results.parquet``, ``histories.parquet``,
``motions.npz``, ``run.json``) and writes ``report.html`` next to it. The page
needs no network: figures are base64 PNGs, the style sheet is inline, and there
is no script.

What it answers, top first: how far each engine is from the reference (the
analytic Housner model) and how sure we are; then the specimen and engine
settings, the ground motions, the distribution of theta_max/alpha (seed Fig. 10
and Table 2), record-by-record agreement, rocking spectra for pulse scenarios,
free rocking for release scenarios, failed records and provenance.

All statistics come from :mod:`housner.stats`; theta_max/alpha is +inf for an
overturned block and failed records are left out of every statistic (and
listed).

References
----------
Bachmann, J. A., Strand, M., Vassiliou, M. F., Broccardo, M., Stojadinovic, B.
(2017). Probabilistic validation of the Housner rocking model. COMPDYN 2017.
"""

from __future__ import annotations

import html
import json
import math
import time
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from housner import stats
from housner.errors import DataFileError
from housner.units import G
from reports import figures
from scenarios.rundir import load_results, read_histories, read_motions
from scenarios.tables import compare_engines, percentile_table, split_failed

__all__ = [
    "DEFAULT_KS_MAX",
    "DEFAULT_OVERTURN_TOL",
    "RECORD_RTOL",
    "render_report",
    "write_report",
]

#: Default tolerances of the headline verdict; the same as the defaults of
#: :func:`reports.assertions.assert_cdf_agreement`, so the page says what users' CI says.
DEFAULT_KS_MAX = 0.15
DEFAULT_OVERTURN_TOL = 0.08
#: Record-by-record agreement: theta_max/alpha within this relative tolerance of the reference [-].
RECORD_RTOL = 0.03
#: Bootstrap resamples for percentile intervals (Efron and Tibshirani 1993, ch. 13, ask for at
#: least 1000 for percentile intervals) and the fixed seed that makes pages reproducible.
N_BOOT = 2000
BOOT_SEED = 0
#: Records with the largest disagreement shown as time histories.
N_WORST = 4

#: Folder of the tuning results ``tuning-<engine>.json`` written by ``housner tune``;
#: None means ``engines/models`` of the installed package.
TUNING_DIR: Path | None = None

_Q = (25.0, 50.0, 75.0)


# ----------------------------------------------------------------------------
# public API
def render_report(run_dir: str | Path) -> str:
    """The HTML report of a run directory, as a string.

    Parameters
    ----------
    run_dir : str or pathlib.Path
        Directory written by :func:`scenarios.runner.write_run`; it must hold
        ``results.parquet``; ``run.json``, ``motions.npz`` and
        ``histories.parquet`` add sections when present.

    Returns
    -------
    str
        A complete HTML5 document with every figure embedded.

    Raises
    ------
    housner.errors.DataFileError
        When the directory or its results table is missing or unreadable.
    """
    t0 = time.perf_counter()
    run = _Run.load(run_dir)
    sections = _build_sections(run)
    return _page(run, sections, time.perf_counter() - t0)


def write_report(run_dir: str | Path, out: str | Path | None = None) -> Path:
    """Write the HTML report of a run directory.

    Parameters
    ----------
    run_dir : str or pathlib.Path
        A run directory (see :func:`render_report`).
    out : str or pathlib.Path, optional
        File to write; default ``run_dir/report.html``.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    text = render_report(run_dir)
    path = Path(out) if out is not None else Path(run_dir) / "report.html"
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)
    return path


# ----------------------------------------------------------------------------
# the run directory
def _num(x: Any) -> float:
    """A number from run.json, where non-finite floats are written as strings ("inf", "nan")."""
    if isinstance(x, str) and x.strip().lower() in ("overturn", "overturned"):
        return math.inf
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


@dataclass
class _Run:
    """A loaded run directory with lazily read motions and histories."""

    path: Path
    results: pd.DataFrame
    meta: dict

    @classmethod
    def load(cls, run_dir: str | Path) -> _Run:
        path = Path(run_dir)
        if not path.is_dir():
            raise DataFileError(path, "not a directory (expected a run directory with results.parquet)")
        results = load_results(path)
        meta = results.attrs.get("run", {})
        results = results.copy()
        results["engine"] = results["engine"].astype(str)
        if "motion_name" not in results.columns:
            results["motion_name"] = results["motion_id"].astype(str)
        # Tables written by other tools may lack the runner's optional columns.
        for col, default in (("wall_s", math.nan), ("cached", False), ("error", "")):
            if col not in results.columns:
                results[col] = default
        return cls(path=path, results=results, meta=meta)

    # --- derived facts
    @cached_property
    def split(self) -> tuple[pd.DataFrame, pd.DataFrame]:
        return split_failed(self.results)

    @property
    def ok(self) -> pd.DataFrame:
        return self.split[0]

    @property
    def failed(self) -> pd.DataFrame:
        return self.split[1]

    @cached_property
    def engines(self) -> list[str]:
        """Engine names, the reference first, then in the order of the results table."""
        names = list(dict.fromkeys(self.results["engine"]))
        ref = self.reference
        if ref in names:
            names.remove(ref)
            names.insert(0, ref)
        return names

    @cached_property
    def reference(self) -> str:
        names = list(dict.fromkeys(self.results["engine"]))
        want = (self.meta.get("analysis") or {}).get("reference") or "housner"
        if want in names:
            return want
        return names[0] if names else want

    @property
    def reference_is_requested(self) -> bool:
        want = (self.meta.get("analysis") or {}).get("reference") or "housner"
        return want == self.reference

    @property
    def others(self) -> list[str]:
        return [e for e in self.engines if e != self.reference]

    @cached_property
    def colors(self) -> dict[str, str]:
        return figures.engine_colors(self.engines, self.reference)

    @property
    def specimen(self) -> dict:
        return self.meta.get("specimen") or {}

    @property
    def alpha(self) -> float:
        return _num(self.specimen.get("alpha_rad"))

    @property
    def motions_meta(self) -> dict:
        return self.meta.get("motions") or {}

    @property
    def S(self) -> float:
        """Size ratio prototype / model of the motions (1 when not stated)."""
        S = _num(self.motions_meta.get("S", 1.0))
        return S if math.isfinite(S) and S > 0 else 1.0

    @property
    def source(self) -> str:
        return str(self.motions_meta.get("source", ""))

    def values(self, engine: str) -> np.ndarray:
        """theta_max/alpha of the usable records of ``engine`` [-] (+inf = overturned)."""
        ok = self.ok
        return ok.loc[ok["engine"] == engine, "theta_max_over_alpha"].to_numpy(np.float64)

    def by_motion(self, engine: str) -> pd.Series:
        """theta_max/alpha of ``engine`` indexed by motion_id, NaN where failed."""
        r = self.results[self.results["engine"] == engine].set_index("motion_id")
        v = r["theta_max_over_alpha"].astype(np.float64)
        v = v.where(~r["overturned"].astype(bool), np.inf)
        return v.where(r["status"].astype(str) == "ok", np.nan)

    @cached_property
    def comparison(self) -> pd.DataFrame:
        return compare_engines(
            self.results,
            self.reference,
            q=_Q,
            ci=0.90,
            p_ci=0.95,
            n_boot=N_BOOT,
            seed=BOOT_SEED,
            rtol=RECORD_RTOL,
            atol=0.0,
        )

    @cached_property
    def motions(self) -> dict | None:
        return read_motions(self.path)

    @cached_property
    def record_gap(self) -> dict:
        """:func:`scenarios.analysis.record_against_ensemble` for this run: the record among its ensemble."""
        from scenarios.analysis import record_against_ensemble

        record, why = _record(self)
        if record is None:
            raise DataFileError(self.path / "run.json", why)
        if self.motions is None:
            raise DataFileError(self.path / "motions.npz", "missing: the ensemble is needed")
        specimen = self.specimen_obj
        amp = _num(((self.meta.get("scenario") or {}).get("motions") or {}).get("amplitude", 1.0))
        settings = {
            k: v
            for k, v in ((self.meta.get("engines") or {}).get(self.reference, {}).get("settings") or {}).items()
            if v is not None
        }
        ids = self.ok.loc[self.ok["engine"] == self.reference, "motion_id"].to_numpy(int)
        motions = _motion_list(self)
        return record_against_ensemble(
            specimen,
            record,
            [motions[i] for i in ids if i < len(motions)],
            self.S,
            amplitude=amp if math.isfinite(amp) else 1.0,
            engine=self.reference,
            settings=settings,
            ensemble_values=self.values(self.reference),
        )

    @cached_property
    def paper_factors(self) -> dict | None:
        """:func:`scenarios.analysis.equivalent_amplitude` of this run's ensemble for the paper's percentiles.

        The analytic model with the specimen's own r (the paper's numerical column is Housner's model),
        whatever the run's reference: how much stronger, in effect, the paper's motions were.
        """
        from scenarios.analysis import equivalent_amplitude

        analysis = self.meta.get("analysis") or {}
        targets = {float(k): _num(v) for k, v in (analysis.get("paper_percentiles") or {}).items()}
        targets = {q: v for q, v in targets.items() if not math.isnan(v)}
        if not targets or self.motions is None:
            return None
        ids = self.ok.loc[self.ok["engine"] == self.reference, "motion_id"].to_numpy(int)
        motions = _motion_list(self)
        return equivalent_amplitude(
            self.specimen_obj, [motions[i] for i in ids if i < len(motions)], targets, seed=BOOT_SEED
        )

    @cached_property
    def specimen_obj(self):
        """The run's specimen as a :class:`housner.Specimen` (from run.json)."""
        from housner import Specimen

        sp = self.specimen
        return Specimen(
            height=_num(sp.get("height_m")),
            width=_num(sp.get("width_m")),
            depth=_num(sp.get("depth_m")),
            mass=_num(sp.get("mass_kg")),
            I0=_num(sp.get("I0_kgm2")),
            name=str(sp.get("name", "specimen")),
        )

    def motion_dt(self, motion_id: int) -> float:
        m = self.motions
        if m is not None and "dt" in m and motion_id < len(m["dt"]):
            return float(m["dt"][motion_id])
        return math.nan

    def histories(self, motion_ids: Iterable[int]) -> dict[tuple[str, int], tuple[np.ndarray, np.ndarray]]:
        """(engine, motion_id) -> (t [s], theta [rad]) for the given motions (empty when not stored)."""
        ids = {int(i) for i in motion_ids}
        return read_histories(self.path, ids, {i: self.motion_dt(i) for i in ids})


# ----------------------------------------------------------------------------
# HTML helpers
def _e(x: Any) -> str:
    return html.escape(str(x), quote=True)


def _fmt(x: Any, digits: int = 3, *, inf: str = "overturn") -> str:
    """A number for a table cell: +inf as ``inf``, NaN as an en dash."""
    v = _num(x) if not isinstance(x, (int, float, np.integer, np.floating)) else float(x)
    if math.isnan(v):
        return "&ndash;"
    if math.isinf(v):
        return inf if v > 0 else "&minus;&infin;"
    return f"{v:.{digits}f}"


def _fmt_p(x: Any) -> str:
    """A p-value: two decimals, or scientific notation below 0.01."""
    v = _num(x)
    if math.isnan(v):
        return "&ndash;"
    return f"{v:.2f}" if v >= 0.01 else f"{v:.1e}"


def _fmt_g(x: Any, digits: int = 4) -> str:
    v = _num(x)
    if math.isnan(v):
        return _e(x) if isinstance(x, str) else "&ndash;"
    return f"{v:.{digits}g}"


def _ci(value: Any, low: Any, high: Any, digits: int = 2) -> str:
    """'value [low, high]' with overturn for +inf."""
    return f"{_fmt(value, digits)} <span class=ci>[{_fmt(low, digits)}, {_fmt(high, digits)}]</span>"


def _table(header: list[str], rows: list[list[str]], *, cls: str = "", caption: str = "") -> str:
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


def _figure(fig, caption: str, alt: str) -> str:
    data = figures.to_png_base64(fig)
    return (
        f'<figure><img src="data:image/png;base64,{data}" alt="{_e(alt)}"><figcaption>{caption}</figcaption></figure>'
    )


def _note(text: str, kind: str = "note") -> str:
    return f'<p class="{kind}">{text}</p>'


def _badge(ok: bool | None, yes: str = "PASS", no: str = "FAIL") -> str:
    if ok is None:
        return '<span class="badge na">not evaluated</span>'
    return f'<span class="badge {"pass" if ok else "fail"}">{yes if ok else no}</span>'


def _engine(name: str, run: _Run) -> str:
    c = run.colors.get(name, "#000")
    return f'<span class="eng"><span class="swatch" style="background:{c}"></span>{_e(name)}</span>'


@dataclass
class _Section:
    id: str
    title: str
    body: str


def _guard(title: str, build: Callable[[], str]) -> str:
    """Build a section body; an error in one optional part is shown in the page, not fatal."""
    try:
        return build()
    except Exception as e:  # a figure helper of another module failing must not lose the whole report
        return _note(f"{_e(title)} could not be drawn: <code>{_e(type(e).__name__)}: {_e(e)}</code>", "warn")


# ----------------------------------------------------------------------------
# sections
def _build_sections(run: _Run) -> list[_Section]:
    out = [
        _Section("verdict", "How far is each engine from the reference?", _headline(run)),
        _Section("specimen", "Specimen and engines", _specimen(run)),
        _Section("ensemble", "Ground motions", _ensemble(run)),
        _Section("distribution", "Distribution of the peak rotation", _distribution(run)),
        _Section("agreement", "Cross-engine agreement", _agreement(run)),
    ]
    if run.source == "pulses":
        out.append(_Section("rocking-spectra", "Rocking spectra", _guard("The rocking spectra", lambda: _spectra(run))))
    if run.source == "free_vibration":
        out.append(_Section("free-vibration", "Free rocking", _guard("Free rocking", lambda: _free_vibration(run))))
    out.append(_Section("failures", "Failed records", _failures(run)))
    out.append(_Section("provenance", "Provenance", _provenance(run)))
    return out


def _verdict(row: pd.Series) -> tuple[bool | None, list[str]]:
    """Pass/fail of one engine against the default tolerances, with the reason for each criterion."""
    ks, dp, nf = float(row["ks_distance"]), float(row["overturn_diff"]), int(row["n_failed"])
    if math.isnan(ks) or math.isnan(dp):
        return None, ["no usable records to compare"]
    checks = [
        (ks <= DEFAULT_KS_MAX, f"KS {ks:.3f} {'&le;' if ks <= DEFAULT_KS_MAX else '&gt;'} {DEFAULT_KS_MAX}"),
        (
            abs(dp) <= DEFAULT_OVERTURN_TOL,
            f"|&Delta;P[overturn]| {abs(dp):.3f} {'&le;' if abs(dp) <= DEFAULT_OVERTURN_TOL else '&gt;'} "
            f"{DEFAULT_OVERTURN_TOL}",
        ),
        (nf == 0, f"{nf} failed record{'s' if nf != 1 else ''}"),
    ]
    return all(c for c, _ in checks), [f'<span class="{"ok" if c else "bad"}">{t}</span>' for c, t in checks]


def _effect_series(run: _Run) -> dict[str, str]:
    """Series of the run that are an engine with the scenario's [[effects]]: series -> engine without them."""
    info = run.meta.get("engines") or {}
    return {n: str(v["engine"]) for n, v in info.items() if isinstance(v, dict) and v.get("effects") and "engine" in v}


def _moved(run: _Run, base: str, series: str) -> str:
    """How an effect moves an engine's distribution: median, P[overturn] and KS distance, without -> with."""
    from housner import stats

    a, b = run.values(base), run.values(series)
    if not (a.size and b.size):
        return "no usable records to compare"
    ks = stats.ks_2samp(a, b)
    med = [float(run.comparison.loc[n, "q50"]) for n in (base, series)]  # as in the table below
    po = [float(np.mean(np.isinf(v))) for v in (a, b)]
    return (
        f"against {_e(base)} without the effects: median &theta;<sub>max</sub>/&alpha; {_fmt(med[0], 3)} &rarr; "
        f"{_fmt(med[1], 3)}, P[overturn] {_fmt(po[0], 2)} &rarr; {_fmt(po[1], 2)}, KS distance "
        f"{_fmt(ks.distance, 3)} (p = {_fmt_p(ks.pvalue)})"
    )


def _headline(run: _Run) -> str:
    cmp = run.comparison
    ref = run.reference
    parts = []
    if not run.reference_is_requested:
        want = (run.meta.get("analysis") or {}).get("reference") or "housner"
        parts.append(
            _note(
                f"The reference engine {_e(want)!s} is not in this run; {_e(ref)} stands in as the reference.", "warn"
            )
        )
    # one line per engine, the answer first
    lines = []
    try:
        caveats = _tuning_caveats(run)
    except Exception as e:  # an unreadable tuning file must not lose the verdict; say so instead
        caveats = {}
        parts.append(
            _note(f"The tuning files could not be checked: <code>{_e(type(e).__name__)}: {_e(e)}</code>", "warn")
        )
    effects = _effect_series(run)
    if effects:
        label = _e((run.meta.get("effects") or {}).get("label", ""))
        parts.append(
            _note(
                f"This run adds physical effects (the scenario's <code>[[effects]]</code>): <strong>{label}</strong>. "
                "Each series &ldquo;ENGINE + effects&rdquo; is that engine with them, beside the same engine "
                "without them: an effect is meant to move the distribution, so it gets no pass or fail, only "
                "how far it moves it."
            )
        )
    for name in run.others:
        row = cmp.loc[name]
        if name in effects:
            base = effects[name]
            lines.append(
                f'<li><span class="badge na">effect</span> {_engine(name, run)}: {_moved(run, base, name)}</li>'
            )
            continue
        ok, reasons = _verdict(row)
        extra = f'<div class="caveat">{caveats[name]}</div>' if name in caveats else ""
        lines.append(f"<li>{_badge(ok)} {_engine(name, run)}: {'; '.join(reasons)}{extra}</li>")
    if lines:
        parts.append(f'<ul class="verdicts">{"".join(lines)}</ul>')
    else:
        parts.append(_note(f"Only one engine ({_e(ref)}) in this run: nothing to compare it with."))
    header = [
        "engine",
        "records<br>ok / failed",
        "KS distance<br>(p-value)",
        "P[overturn]<br>[95 % CI]",
        "&Delta;P[overturn]",
        "median &theta;<sub>max</sub>/&alpha;<br>[90 % CI]",
        "verdict",
    ]
    rows = []
    for name in run.engines:
        row = cmp.loc[name]
        is_ref = name == ref
        ok, _ = _verdict(row) if not is_ref else (None, [])
        nf = int(row["n_failed"])
        rows.append(
            [
                _engine(name, run) + (" <small>(reference)</small>" if is_ref else ""),
                f"{int(row['n_ok'])} / " + (f'<span class="bad">{nf}</span>' if nf else "0"),
                "&ndash;" if is_ref else f"{_fmt(row['ks_distance'])} (p = {_fmt_p(row['ks_pvalue'])})",
                _ci(row["p_overturn"], row["p_overturn_low"], row["p_overturn_high"], 2),
                "&ndash;" if is_ref else _signed(row["overturn_diff"], 3),
                _ci(row["q50"], row["q50_low"], row["q50_high"], 3),
                "reference"
                if is_ref
                else "effect"
                if name in effects
                else _badge(ok) + (_caveat_mark(caveats[name]) if name in caveats else ""),
            ]
        )
    parts.append(_table(header, rows, cls="headline"))
    n = int(cmp.loc[ref, "n_ok"]) if ref in cmp.index else 0
    # Smirnov's asymptotic 5 % critical distance for two samples of n: sqrt(-ln(0.025) / 2) sqrt(2 / n).
    crit = math.sqrt(-math.log(0.025) / 2.0) * math.sqrt(2.0 / n) if n else math.nan
    parts.append(
        _note(
            f"Pass means KS distance &le; {DEFAULT_KS_MAX}, |&Delta;P[overturn]| &le; {DEFAULT_OVERTURN_TOL} and no "
            "failed record (the defaults of <code>reports.assertions.assert_cdf_agreement</code>). "
            "P[overturn] intervals are Wilson score intervals; median intervals are percentile bootstraps "
            f"({N_BOOT} resamples, seed {BOOT_SEED}). How sure: two <em>independent</em> ensembles of "
            f"n = {n} records from one distribution differ by a KS distance above {_fmt(crit, 2)} one time in "
            "twenty; here every engine sees the very same motions, so engines that agree should sit well below "
            "that, and the p-value (which assumes independent samples) is conservative."
        )
    )
    return "".join(parts)


def _caveat_mark(text: str) -> str:
    n = text.count('class="bad"')
    return f"<br><small>{n} tuning check{'s' if n != 1 else ''} not met (above)</small>" if n else ""


def _tuning_caveats(run: _Run) -> dict[str, str]:
    """engine -> HTML: the tuning checks its tuning file did not meet, by how much, and what that means here."""
    out = {}
    cmp = run.comparison
    for name, (f, d) in _tuning_data(run).items():
        if name not in run.others or d.get("met") is not False:
            continue
        failed = [c for c in _tuning_checks(d) if not c.met]
        if not failed:
            continue
        row = cmp.loc[name]
        ok, _ = _verdict(row)
        what = "; ".join(f'<span class="bad">{c.short}</span>' for c in failed)
        text = f"Tuning not met (<code>{_e(f.name)}</code>, {_e(d.get('date', ''))}): {what}. "
        names = {c.name for c in failed}
        first_impact_ok = all(c.met for c in _tuning_checks(d) if c.name.startswith("r of the first impact"))
        if any(n.startswith("free decay") for n in names) and first_impact_ok:
            text += (
                "The first-impact r is within tolerance at every amplitude checked, so the missing energy is lost "
                "between impacts and piles up only over many small rockings (the measured cause is in "
                "<code>engines/models/README.md</code>). "
            )
        decay = _frame(d, "decay_table")
        small_limit = math.nan
        if {"rel_error", "peak_analytic"} <= set(decay.columns):
            from engines.tuning import DECAY_RTOL

            bad = decay[np.abs(decay["rel_error"].to_numpy(float)) > DECAY_RTOL]
            if len(bad):
                small_limit = float(bad["peak_analytic"].max())
        ks = float(row["ks_distance"])
        if ok:
            text += (
                f"It does not change this verdict, which is measured on this run's own motions (KS {ks:.3f} "
                f"&le; {DEFAULT_KS_MAX}): a loss that mattered for them would show there"
            )
            if math.isfinite(small_limit):
                v = run.values(run.reference)
                k = int(np.sum(v <= small_limit))
                text += (
                    f"; the loss exceeds the tolerance at peaks of {small_limit:.3f} &alpha; and below, and "
                    f"{k} of the {v.size} records peak there in the reference (smallest peak "
                    f"{_fmt(np.min(v) if v.size else math.nan, 3)} &alpha;)"
                )
            text += (
                ". It does limit the engine where small free rocking matters (long free decays, motions that keep "
                "the block rocking at a few hundredths of &alpha;): check such uses against the analytic model."
            )
        else:
            text += "This run's verdict fails on its own criteria as well."
        out[name] = text
    return out


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


def _specimen(run: _Run) -> str:
    spec = run.specimen
    parts = []
    if spec:
        rows = []
        for key, value in spec.items():
            label, unit = _SPECIMEN_ROWS.get(key, (_e(key), ""))
            cell = _e(value) if isinstance(value, str) else _fmt_g(value, 6)
            rows.append([label, cell, unit])
        a = run.alpha
        if math.isfinite(a):
            rows.append(["&alpha; in degrees", f"{math.degrees(a):.4g}", "deg"])
            rows.append(["uplift acceleration g tan &alpha;", f"{G * math.tan(a):.4g}", "m/s&sup2;"])
        parts.append(_table(["quantity", "value", "unit"], rows, cls="kv"))
    else:
        parts.append(_note("run.json holds no specimen.", "warn"))
    engines = run.meta.get("engines") or {}
    rows = []
    for name in run.engines:
        info = engines.get(name, {})
        settings = info.get("settings") or {}
        sset = _settings_html(settings) or "defaults"
        rows.append([_engine(name, run), _e(info.get("version", "")) or "&ndash;", sset])
    parts.append("<h3>Engines</h3>")
    parts.append(_table(["engine", "version", "settings"], rows))
    parts.append(_guard("The tuning summary", lambda: _tuning(run)))
    return "".join(parts)


def _settings_html(settings: dict) -> str:
    """Engine settings one per line; None (the engine's default) is written as such."""
    return "<br>".join(
        f"<code>{_e(k)} = {'default' if v is None else _e(json.dumps(v))}</code>" for k, v in settings.items()
    )


def _tuning_file(engine: str) -> Path:
    if TUNING_DIR is not None:
        return Path(TUNING_DIR) / f"tuning-{engine}.json"
    import engines

    return Path(engines.__file__).resolve().parent / "models" / f"tuning-{engine}.json"


def _tuning_data(run: _Run) -> dict[str, tuple[Path, dict]]:
    """engine -> (file, parsed tuning-<engine>.json) for the run's engines that have one."""
    found = {}
    for name in run.engines:
        f = _tuning_file(name)
        if f.is_file():
            try:
                found[name] = (f, json.loads(f.read_text(encoding="utf-8")))
            except (OSError, json.JSONDecodeError) as e:
                found[name] = (f, {"error": f"cannot read: {e}"})
    return found


def _step_label(dt: float) -> str:
    return f"{dt * 1e3:.3g} ms sampling" if math.isfinite(dt) else "sample step not recorded"


@dataclass
class _Check:
    """One tuning check of a tuned engine, evaluated from its tuning file."""

    name: str
    measured: str  # HTML, the worst error and where it was measured
    accepted: str  # HTML
    met: bool
    short: str  # HTML, one phrase for the verdict line: the worst error, where, and what is accepted


def _frame(d: dict, key: str) -> pd.DataFrame:
    t = d.get(key) or {}
    try:
        df = pd.DataFrame(t)
    except ValueError:  # columns of different lengths: unusable
        return pd.DataFrame()
    if "dt" not in df.columns:
        df["dt"] = math.nan
    return df


def _tuning_checks(d: dict) -> list[_Check]:
    """The tuner's checks (``engines.tuning``) re-evaluated from the tables of a tuning file.

    Each check is judged with the tuner's own tolerances, so a check said "not met"
    here is the one ``housner tune`` counted; tables absent from the file give no row.
    """
    from engines.tuning import DECAY_RTOL, SMALL_WORST_FACTOR

    rtol = _num(d.get("rtol"))
    out: list[_Check] = []

    def worst_row(df: pd.DataFrame, col: str) -> pd.Series:
        return df.iloc[int(np.argmax(np.abs(df[col].to_numpy(float))))]

    table = _frame(d, "table")
    target = _num(d.get("target_r"))
    if "rel_error" not in table.columns and "r_engine" in table.columns and math.isfinite(target):
        table["rel_error"] = table["r_engine"].astype(float) / target - 1.0  # files older than the error column
    if {"amplitude", "rel_error"} <= set(table.columns) and len(table):
        w = worst_row(table, "rel_error")
        amps = table["amplitude"].to_numpy(float)
        rng = f"{amps.min():g}-{amps.max():g} &alpha;"
        ok = abs(w.rel_error) <= rtol
        out.append(
            _Check(
                f"r of the first impact, {rng}",
                f"worst {w.rel_error:+.2%} at {w.amplitude:g} &alpha; ({_step_label(w['dt'])}); "
                f"mean {table['rel_error'].mean():+.2%}",
                f"&plusmn;{rtol:.2%}",
                bool(ok),
                f"r at {rng} worst {w.rel_error:+.2%} (accepted &plusmn;{rtol:.2%})",
            )
        )
    small = _frame(d, "small_table")
    if {"amplitude", "rel_error"} <= set(small.columns) and len(small):
        w = worst_row(small, "rel_error")
        means = small.groupby("dt", dropna=False, sort=False)["rel_error"].mean()
        m = float(means.iloc[int(np.argmax(np.abs(means.to_numpy(float))))])
        amps = small["amplitude"].to_numpy(float)
        rng = f"{amps.min():g}-{amps.max():g} &alpha;"
        tol_w = SMALL_WORST_FACTOR * rtol
        ok = abs(w.rel_error) <= tol_w and abs(m) <= rtol
        out.append(
            _Check(
                f"r of the first impact, {rng}",
                f"worst {w.rel_error:+.2%} at {w.amplitude:g} &alpha; ({_step_label(w['dt'])}); worst mean {m:+.2%}",
                f"worst &plusmn;{tol_w:.2%}, mean &plusmn;{rtol:.2%}",
                bool(ok),
                f"r at {rng} worst {w.rel_error:+.2%}, mean {m:+.2%} (accepted &plusmn;{tol_w:.2%} and "
                f"&plusmn;{rtol:.2%})",
            )
        )
    decay = _frame(d, "decay_table")
    if {"impacts", "rel_error", "peak_engine", "peak_analytic"} <= set(decay.columns) and len(decay):
        w = worst_row(decay, "rel_error")
        bad = decay[np.abs(decay["rel_error"].to_numpy(float)) > DECAY_RTOL]
        where = ""
        if len(bad):
            where = (
                f"; beyond the tolerance from {int(bad['impacts'].min())} impacts on, i.e. at peaks of "
                f"{bad['peak_analytic'].max():.3f} &alpha; and below"
            )
        out.append(
            _Check(
                "free decay: peaks after " + ", ".join(str(int(k)) for k in sorted(set(decay["impacts"]))) + " impacts",
                f"worst {w.rel_error:+.1%} after {int(w.impacts)} impacts ({w.peak_engine:.4f} &alpha; against "
                f"{w.peak_analytic:.4f} &alpha;, {_step_label(w['dt'])}){where}",
                f"&plusmn;{DECAY_RTOL:.0%}",
                bool(abs(w.rel_error) <= DECAY_RTOL),
                f"a free decay's peak after {int(w.impacts)} impacts is {w.rel_error:+.1%} off the analytic "
                f"{w.peak_analytic:.4f} &alpha; ({_step_label(w['dt'])}; accepted &plusmn;{DECAY_RTOL:.0%})",
            )
        )
    pulses = _frame(d, "pulse_table")
    if {"rel_error", "theta_max_rel_error", "theta_max_rtol"} <= set(pulses.columns) and len(pulses):
        w = worst_row(pulses, "rel_error")
        scaled = np.abs(pulses["theta_max_rel_error"].to_numpy(float)) / pulses["theta_max_rtol"].to_numpy(float)
        k = int(np.argmax(scaled))
        wt = pulses.iloc[k]
        ok = abs(w.rel_error) <= rtol and scaled[k] <= 1.0
        n = pulses["pulse"].nunique() if "pulse" in pulses.columns else len(pulses)
        out.append(
            _Check(
                f"{n} one-sine pulses: first peak and &theta;<sub>max</sub>",
                f"first peak worst {w.rel_error:+.2%}; &theta;<sub>max</sub> worst {wt.theta_max_rel_error:+.2%} "
                f"({_e(wt.get('pulse', ''))}, {_step_label(wt['dt'])})",
                f"first peak &plusmn;{rtol:.2%}; &theta;<sub>max</sub> &plusmn;"
                + ", &plusmn;".join(f"{x:.2%}" for x in sorted(set(pulses["theta_max_rtol"]))),
                bool(ok),
                f"pulse &theta;<sub>max</sub> worst {wt.theta_max_rel_error:+.2%} "
                f"(accepted &plusmn;{wt.theta_max_rtol:.2%})",
            )
        )
    return out


def _tuning_series(d: dict) -> tuple[dict, dict]:
    """r against amplitude per sample step (large and small amplitudes joined), and decay errors per step."""
    parts = [t for t in (_frame(d, "small_table"), _frame(d, "table")) if {"amplitude", "r_engine"} <= set(t.columns)]
    curves: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    if parts:
        both = pd.concat(parts, ignore_index=True)
        for dt, g in both.groupby("dt", dropna=False, sort=False):
            g = g.sort_values("amplitude", kind="stable")
            curves[_step_label(float(dt)) if math.isfinite(float(dt)) else ""] = (
                g["amplitude"].to_numpy(float),
                g["r_engine"].to_numpy(float),
            )
    decay = _frame(d, "decay_table")
    dec: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    if {"impacts", "rel_error"} <= set(decay.columns):
        for dt, g in decay.groupby("dt", dropna=False, sort=False):
            g = g.sort_values("impacts", kind="stable")
            dec[_step_label(float(dt)) if math.isfinite(float(dt)) else ""] = (
                g["impacts"].to_numpy(float),
                g["rel_error"].to_numpy(float),
            )
    return curves, dec


def _settings_differ(tuned: dict, used: dict) -> list[str]:
    """Settings where the run differs from the tuning file (keys the run sets); empty when it runs as tuned."""

    def norm(v):
        return json.loads(json.dumps(v))

    return [k for k, v in used.items() if k in tuned and norm(tuned[k]) != norm(v)]


def _tuning(run: _Run) -> str:
    """Tuned contact checks and r against amplitude, from engines/models/tuning-<engine>.json when present."""
    found = _tuning_data(run)
    if not found:
        return _note(
            "No tuning results (engines/models/tuning-&lt;engine&gt;.json) for these engines: "
            "they run with the settings above. <code>housner tune ENGINE</code> finds contact settings that "
            "reproduce a target r."
        )
    from engines.tuning import DECAY_RTOL, DECAY_START, SMALL_WORST_FACTOR

    parts = ["<h3>Tuned contact parameters</h3>"]
    rows = []
    curves, decays = {}, {}
    target = rtol = None
    engines = run.meta.get("engines") or {}
    for name, (f, d) in found.items():
        if "error" in d and len(d) == 1:
            rows.append([_engine(name, run), f"<code>{_e(f.name)}</code>: {_e(d['error'])}", "", "", "", ""])
            continue
        tuned = d.get("settings") or {}
        used = (engines.get(name) or {}).get("settings") or {}
        differ = _settings_differ(tuned, used)
        if not used:
            same = f"{_settings_html(tuned) or '&ndash;'}<br><small>(the run recorded no settings)</small>"
        elif differ:
            same = '<span class="bad">the run differs:</span><br>' + "<br>".join(
                f"<code>{_e(k)}</code>: tuned {_e(json.dumps(tuned[k]))}, run {_e(json.dumps(used[k]))}" for k in differ
            )
        else:
            same = "the run's settings (above)"
        checks = _tuning_checks(d)
        met = d.get("met")
        check_cells = "<br>".join(
            f'<span class="{"ok" if c.met else "bad"}">{"met" if c.met else "NOT MET"}</span>: {c.name}: '
            f"{c.measured} <span class=muted>(accepted {c.accepted})</span>"
            for c in checks
        )
        rows.append(
            [
                _engine(name, run),
                same,
                _fmt_g(d.get("target_r"), 5),
                check_cells or "&ndash;",
                _badge(bool(met), "MET", "NOT MET") if met is not None else "&ndash;",
                f"{_e(d.get('date', ''))}, version {_e(d.get('version', ''))}",
            ]
        )
        c, dec = _tuning_series(d)
        if not c:  # older files: one table without sample steps
            table = d.get("table") or {}
            amp, r = table.get("amplitude"), table.get("r_engine")
            if isinstance(amp, list) and isinstance(r, list) and len(amp) == len(r) and amp:
                c = {"": (np.array([_num(x) for x in amp]), np.array([_num(x) for x in r]))}
        if c:
            curves[name] = c
        if dec:
            decays[name] = dec
        t = _num(d.get("target_r"))
        if math.isfinite(t):
            target = t
        if math.isfinite(_num(d.get("rtol"))):
            rtol = _num(d.get("rtol"))
    parts.append(
        _table(
            ["engine", "tuned settings", "target r", "the tuner's checks (worst case)", "verdict", "tuned on"],
            rows,
            caption="Contact settings chosen by <code>housner tune</code> so that free rocking loses the target "
            "energy per impact at every release amplitude, and each of its checks against the analytic model "
            "re-read from <code>engines/models/tuning-&lt;engine&gt;.json</code>. &ldquo;NOT MET&rdquo; means at "
            "least one check is outside its tolerance; what that means for this run is said under the verdict at "
            "the top.",
        )
    )
    if curves:
        bands = []
        if rtol is not None:
            amps = [a for c in curves.values() for a, _ in c.values()]
            lo = min(float(np.nanmin(a)) for a in amps)
            bands = [(0.2, 0.9, rtol)]
            if lo < 0.2:
                bands.insert(0, (lo, 0.2, SMALL_WORST_FACTOR * rtol))
        fig = figures.plot_tuning(
            curves,
            target_r=target,
            bands=bands,
            decay=decays or None,
            decay_rtol=DECAY_RTOL,
            decay_start=DECAY_START,
            colors=run.colors,
        )
        parts.append(
            _figure(
                fig,
                "Left: energy ratio r of the first impact after a release from rest against the release amplitude, "
                "one line per engine and sample step, with the accepted band around the target. A flat line on the "
                "target means the contact dissipates like Housner's impact at every amplitude; a trend means its "
                "losses depend on the impact velocity. Right: a free decay, the engine's peak after 10-40 impacts "
                "against the exact sequence; energy lost between impacts accumulates here.",
                "r against amplitude for the tuned engines, and the free-decay check",
            )
        )
    return "".join(parts)


def _ensemble(run: _Run) -> str:
    mm = run.motions_meta
    parts = []
    src = run.source or "unknown"
    words = {
        "rdk": "synthetic motions of the Rezaeian &amp; Der Kiureghian model fitted to a record",
        "record": "a recorded ground motion",
        "records": "a suite of recorded ground motions, each run as recorded",
        "pulses": "analytical pulses on a grid",
        "free_vibration": "free rocking after a release from rest (no ground motion)",
    }.get(src, _e(src))
    facts = [["source", words]]
    if "model" in mm:
        model = {"rdk2010": "published (Rezaeian &amp; Der Kiureghian 2010)", "matched": "spectrally matched"}
        facts.append(["ground-motion model", f"<code>{_e(mm['model'])}</code>: {model.get(mm['model'], '')}"])
    if "S" in mm:
        S = _num(mm["S"])
        facts.append(
            [
                "size ratio S = R<sub>prototype</sub>/R<sub>model</sub>",
                f"{_fmt_g(S)} (time compressed by &radic;S = {_fmt_g(math.sqrt(S)) if S > 0 else '&ndash;'}, "
                "seed eq. 9)",
            ]
        )
    if "seed" in mm:
        facts.append(["seed", _e(mm["seed"])])
    m = run.motions
    if m is not None and len(m.get("n", [])):
        n = np.asarray(m["n"])
        dt = np.asarray(m["dt"], dtype=float)
        dur = (n - 1) * dt
        acc = np.asarray(m["acc"], dtype=float)
        pga = np.max(np.abs(acc), axis=1) if acc.size else np.zeros(len(n))
        facts.append(["motions", f"{len(n)}"])
        facts.append(["step dt", _range(dt * 1000, "ms")])
        facts.append(["duration", _range(dur, "s")])
        if np.any(pga > 0):
            ratio = ""
            if math.isfinite(run.alpha):
                ratio = f"; PGA/(g tan &alpha;) {_range(pga / (G * math.tan(run.alpha)), '')}"
            facts.append(["peak ground acceleration", _range(pga, "m/s&sup2;") + f" ({_range(pga / G, 'g')}){ratio}"])
    parts.append(_table(["", ""], facts, cls="kv"))
    rec = mm.get("record")
    if isinstance(rec, dict):
        rows = [
            ["name", _e(rec.get("name", "")), ""],
            ["provenance", _e(rec.get("provenance", "")), ""],
            ["step dt", _fmt_g(rec.get("dt")), "s"],
            ["samples", _e(rec.get("n", "")), ""],
        ]
        if rec.get("file"):
            rows.insert(
                1, ["file", f"<code>{_e(rec['file'])}</code> (sha256 {_e(str(rec.get('sha256', ''))[:16])})", ""]
            )
        parts.append("<h3>Record</h3>")
        parts.append(_table(["", "value", "unit"], rows, cls="kv"))
    suite = mm.get("records")
    if isinstance(suite, list) and suite:
        rows = [
            [_e(r.get("name", "")), f"<code>{_e(r.get('file', ''))}</code>", _e(r.get("n", "")), _fmt_g(r.get("dt"))]
            for r in suite
            if isinstance(r, dict)
        ]
        parts.append("<h3>Records</h3>")
        parts.append(_table(["motion", "file", "samples", "dt [s]"], rows, cls="kv"))
    params = mm.get("rdk_params")
    if isinstance(params, dict) and params:
        parts.append("<h3>Fitted Rezaeian &amp; Der Kiureghian parameters</h3>")
        parts.append(_rdk_table(params))
    if isinstance(mm.get("band_check"), dict):
        parts.append("<h3>Spectral match, band by band</h3>")
        parts.append(_guard("The band check", lambda: _band_table(mm["band_check"], mm.get("matched_gain"))))
    if src in ("rdk", "record"):
        parts.append(_guard("The response spectra", lambda: _spectra_figure(run)))
    if src == "pulses" and "pulse" in mm:
        parts.append(
            _note(
                f"Pulse shape: <code>{_e(mm['pulse'])}</code> on a grid of &omega;<sub>p</sub>/p and "
                "a<sub>p</sub>/(g tan &alpha;); see <a href='#rocking-spectra'>Rocking spectra</a>."
            )
        )
    return "".join(parts)


def _band_table(check: dict, gain: dict | None) -> str:
    """Per third-octave band: ensemble-mean / record of PSa and Sd with PASS/FAIL (and the matched model's gain)."""
    rows: dict[float, list[str]] = {}
    for q, col in (("psa", 1), ("sd", 2)):
        for b in (check.get(q) or {}).get("bands", []):
            c = round(_num(b.get("centre_s")), 6)
            row = rows.setdefault(c, [_fmt_g(c, 3), "&ndash;", "&ndash;"])
            row[col] = f"{_fmt(b.get('ratio'), 3)} {_badge(b.get('verdict') == 'PASS')}"
    header = ["band centre [s]", "PSa ratio", "Sd ratio"]
    gain_note = ""
    if isinstance(gain, dict) and gain.get("gain_centres_s"):
        header.append("gain G [&ndash;]")
        gain_note = (
            f" G: the matched model's spectral gain at the band centre, fitted in {_e(gain.get('iterations', '?'))} "
            f"iterations on {_e(gain.get('n_fit', '?'))} motions."
        )
        g = {round(_num(c), 6): _num(v) for c, v in zip(gain["gain_centres_s"], gain.get("gain", []), strict=False)}
        for c, row in rows.items():
            row.append(_fmt(g.get(c, math.nan), 3))
    lo, hi = (list(check.get("bounds") or []) + [math.nan, math.nan])[:2]
    ranges = {q: (check.get(q) or {}).get("range_s") or ["?", "?"] for q in ("psa", "sd")}
    verdict = _badge(bool(check.get("passed"))) if "passed" in check else ""
    caption = (
        f"{verdict} {_e(check.get('what', ''))}: ratio of the geometric mean over the band of ensemble mean / record, "
        f"accepted within [{_fmt_g(lo)}, {_fmt_g(hi)}]; PSa checked over {_fmt_g(ranges['psa'][0])}-"
        f"{_fmt_g(ranges['psa'][1])} s, Sd over {_fmt_g(ranges['sd'][0])}-{_fmt_g(ranges['sd'][1])} s "
        "(scenarios.rdk_match.band_check)." + gain_note
    )
    return _table(header, [rows[c] for c in sorted(rows)], cls="kv", caption=caption)


def _range(x: np.ndarray, unit: str) -> str:
    x = np.asarray(x, dtype=float)
    x = x[np.isfinite(x)]
    if x.size == 0:
        return "&ndash;"
    lo, hi = float(x.min()), float(x.max())
    u = f" {unit}" if unit else ""
    if math.isclose(lo, hi, rel_tol=1e-9, abs_tol=1e-12):
        return f"{lo:.4g}{u}"
    return f"{lo:.4g} &ndash; {hi:.4g}{u} (median {float(np.median(x)):.4g})"


#: Fitted Rezaeian & Der Kiureghian parameters (keys of ``scenarios.rdk.RDKParams.describe()``):
#: key -> (symbol, unit, meaning).
_RDK_ROWS = {
    "model": ("model", "", ""),
    "Ia_m_s": ("I<sub>a</sub>", "m/s", "Arias intensity, &pi;/(2g) &int; &uuml;<sub>g</sub>&sup2; dt"),
    "D5_95_s": ("D<sub>5-95</sub>", "s", "significant duration, from 5 % to 95 % of I<sub>a</sub>"),
    "t_mid_s": ("t<sub>mid</sub>", "s", "time at 45 % of I<sub>a</sub>"),
    "omega_mid_rad_s": ("&omega;<sub>mid</sub>", "rad/s", "filter frequency at t<sub>mid</sub>"),
    "f_mid_Hz": ("f<sub>mid</sub>", "Hz", "&omega;<sub>mid</sub>/2&pi;"),
    "omega_prime_rad_s2": ("&omega;&prime;", "rad/s&sup2;", "rate of change of the filter frequency"),
    "zeta_f": ("&zeta;<sub>f</sub>", "&ndash;", "filter damping ratio"),
    "omega_c_rad_s": ("&omega;<sub>c</sub>", "rad/s", "corner frequency of the high-pass filter"),
    "T0_s": ("T<sub>0</sub>", "s", "start of the modulating function q(t)"),
    "dt_s": ("dt", "s", "step of the simulated motions (prototype scale)"),
    "duration_s": ("duration", "s", "length of the simulated motions (prototype scale)"),
    "alpha1": (
        "&alpha;<sub>1</sub>",
        "m/s&sup2; s<sup>1&minus;&alpha;2</sup>",
        "scale of q(t) = &alpha;<sub>1</sub> (t&minus;T<sub>0</sub>)<sup>&alpha;2&minus;1</sup> "
        "exp(&minus;&alpha;<sub>3</sub>(t&minus;T<sub>0</sub>))",
    ),
    "alpha2": ("&alpha;<sub>2</sub>", "&ndash;", "shape of q(t)"),
    "alpha3_1_s": ("&alpha;<sub>3</sub>", "1/s", "decay rate of q(t)"),
}

#: Unit suffixes of plain keys, longest first: key_m_s2 is in m/s^2, and so on.
_UNIT_SUFFIXES = (
    ("_rad_s2", "rad/s&sup2;"),
    ("_m_s2", "m/s&sup2;"),
    ("_rad_s", "rad/s"),
    ("_1_s", "1/s"),
    ("_m_s", "m/s"),
    ("_hz", "Hz"),
    ("_rad", "rad"),
    ("_kg", "kg"),
    ("_s", "s"),
    ("_m", "m"),
)


def _unit_from_key(key: str) -> str:
    k = key.lower()
    for suffix, unit in _UNIT_SUFFIXES:
        if k.endswith(suffix):
            return unit
    return ""


def _rdk_table(params: dict) -> str:
    """Table of fitted RDK parameters with symbols, units and meanings (unknown keys by their unit suffix)."""
    rows = []
    for k, v in params.items():
        if isinstance(v, dict):  # {value, unit, description}
            value, unit, desc = v.get("value"), _e(v.get("unit", "")), _e(v.get("description", ""))
            symbol = f"<code>{_e(k)}</code>"
        else:
            symbol, unit, desc = _RDK_ROWS.get(k, (f"<code>{_e(k)}</code>", _unit_from_key(str(k)), ""))
            value = v
        cell = _e(value) if isinstance(value, str) else _fmt_g(value, 5)
        rows.append([symbol, cell, unit, desc])
    return _table(["parameter", "value", "unit", "meaning"], rows, cls="kv")


def _motion_list(run: _Run):
    from housner.motion import GroundMotion

    m = run.motions
    out = []
    names = m.get("names", [])
    for i, (n, dt) in enumerate(zip(m["n"], m["dt"], strict=True)):
        name = str(names[i]) if i < len(names) else f"motion {i}"
        out.append(GroundMotion(np.asarray(m["acc"][i, : int(n)], dtype=float), float(dt), name=name))
    return out


def _record(run: _Run):
    """(the record the run's motions come from, at prototype scale, None) or (None, why not)."""
    from scenarios.records import RECORDS, file_sha256, read_record_file

    scen = run.meta.get("scenario") or {}
    facts = run.motions_meta.get("record") or {}
    key = (scen.get("motions") or {}).get("record") or facts.get("name")
    if not key:
        return None, "run.json names no record"
    if facts.get("path"):  # a user's file: read it again if it has not changed since the run
        path = Path(facts["path"])
        try:
            same = file_sha256(path) == facts.get("sha256")
        except OSError:
            return None, f"Record file {_e(path)} is no longer there"
        if not same:
            return None, f"Record file {_e(path)} has changed since the run"
        return read_record_file(path), ""
    if key not in RECORDS:
        return None, f"Record {_e(key)!r} is not in the catalogue (scenarios.records.RECORDS)"
    return RECORDS[key](), ""


def _spectra_figure(run: _Run) -> str:
    if run.motions is None:
        return _note("motions.npz is missing: no spectra.")
    try:
        from reports.ground_figures import plot_ensemble_spectra
    except ImportError:
        return _note("The spectra figure needs reports/ground_figures.py, which is not installed.", "warn")
    record, why = _record(run)
    if record is None:
        return _note(f"{why}: no spectra.", "warn" if "catalogue" in why or "Record file" in why else "note")
    S = run.S
    # motions.npz holds the model-scale motions (time compressed by sqrt(S), seed eq. 9); the figure takes
    # the prototype-scale ensemble and draws the time-scaled spectra itself.
    prototype = [m.scaled(time=math.sqrt(S)) for m in _motion_list(run)]
    fig = plot_ensemble_spectra(record, prototype, S=S if S != 1.0 else None)
    return _figure(
        fig,
        "Elastic response spectra of the record and of the simulated motions (seed Fig. 8). The simulated "
        "motions should scatter around the record; they match it only in linear elastic terms, which does "
        "not guarantee similar rocking responses.",
        "response spectra of the record and the ensemble",
    )


def _distribution(run: _Run) -> str:
    cmp = run.comparison
    samples = {e: run.values(e) for e in run.engines if run.values(e).size}
    if not samples:
        return _note("No usable record: nothing to plot.", "warn")
    analysis = run.meta.get("analysis") or {}
    paper = {float(k): _num(v) for k, v in (analysis.get("paper_percentiles") or {}).items()}
    fig = figures.plot_cdfs(samples, reference=run.reference, ci=0.95, paper=paper or None, colors=run.colors)
    parts = [
        _figure(
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
    header += [_engine(e, run) for e in run.engines]
    rows = []
    for q in _Q:
        qn = f"q{q:g}"
        r = [stats.percentile_label(q) if hasattr(stats, "percentile_label") else f"{q:g}th"]
        if paper:
            r.append(_fmt(paper.get(q, math.nan), 2))
        for e in run.engines:
            row = cmp.loc[e]
            r.append(_ci(row[qn], row[f"{qn}_low"], row[f"{qn}_high"], 2))
        rows.append(r)
    r = ["P[overturn]"]
    if paper:
        r.append("&ndash;")
    for e in run.engines:
        row = cmp.loc[e]
        r.append(_ci(row["p_overturn"], row["p_overturn_low"], row["p_overturn_high"], 2))
    rows.append(r)
    parts.append(
        _table(
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
    spread = run.meta.get("table2_spread")
    if spread:
        parts.append("<h3>Spread over independent ensembles</h3>")
        parts.append(_guard("The seed-spread table", lambda: _spread_table(spread)))
    if paper:
        parts.append('<div id="table2-gap"><h3>Why these percentiles differ from the paper&rsquo;s</h3>')
        parts.append(_guard("The comparison with the paper", lambda: _table2_gap(run, paper, spread)))
        parts.append("</div>")
    return "".join(parts)


def _paper_position(x: float, paper: dict[float, float]) -> str:
    """Where a theta_max/alpha falls among the paper's percentiles, in words."""
    qs = sorted(paper)
    below = [q for q in qs if _finite_or_inf(paper[q]) <= x]
    above = [q for q in qs if _finite_or_inf(paper[q]) > x]
    pv = ", ".join(_fmt(paper[q], 2) for q in qs)
    if not below:
        return f"below the paper's {stats.percentile_label(qs[0])} percentile ({pv})"
    if not above:
        return f"above the paper's {stats.percentile_label(qs[-1])} percentile ({pv})"
    return (
        f"between the paper's {stats.percentile_label(below[-1])} and {stats.percentile_label(above[0])} "
        f"percentiles ({_fmt(paper[below[-1]], 2)} and {_fmt(paper[above[0]], 2)})"
    )


def _finite_or_inf(v: float) -> float:
    return math.inf if not math.isfinite(v) and not math.isnan(v) else v


def _table2_gap(run: _Run, paper: dict[float, float], spread: dict | None) -> str:
    """The gap to the paper's Table 2, and its measured cause: the record against its own ensemble."""
    cmp = run.comparison.loc[run.reference]
    qs = [q for q in _Q if q in paper]
    n = int(cmp["n_ok"])
    ref = run.reference
    summary = {_num(k): v for k, v in ((spread or {}).get("summary") or {}).items()}
    k_spread = (spread or {}).get("k", len((spread or {}).get("seeds", [])))
    # Is each paper value inside what another draw of motions gives: the spread when run, else the bootstrap interval?
    inside, ranges = {}, {}
    for q in qs:
        if q in summary:
            lo, _, hi = (_num(x) for x in (list(summary[q]) + [math.nan] * 3)[:3])
        else:
            lo, hi = _num(cmp[f"q{q:g}_low"]), _num(cmp[f"q{q:g}_high"])
        ranges[q] = (lo, hi)
        pv = paper[q]
        inside[q] = bool(lo <= pv <= hi) if not math.isnan(pv) else None
    labels = " / ".join(stats.percentile_label(q) for q in qs)
    ours = " / ".join(_fmt(cmp[f"q{q:g}"], 2) for q in qs)
    paper_txt = " / ".join(_fmt(paper[q], 2) for q in qs)
    rng = " / ".join(f"{_fmt(ranges[q][0], 2)}&ndash;{_fmt(ranges[q][1], 2)}" for q in qs)
    gap = [q for q in qs if inside[q] is False]
    within = [q for q in qs if inside[q] is True]
    if summary:
        where = f"over {_e(k_spread)} independent ensembles of {n} motions (min&ndash;max) they range over {rng}"
        fr = (spread or {}).get("overturn_fraction_range")
        if fr:
            where += f", with P[overturn] {_fmt(_num(fr[0]), 2)}&ndash;{_fmt(_num(fr[-1]), 2)}"
        noise = "the spread of independent ensembles"
    else:
        where = f"their 90 % bootstrap intervals are {rng}"
        noise = "the intervals of this ensemble"
    head = (
        f"The paper's numerical percentiles ({labels}) are {paper_txt}; the analytic reference ({_e(ref)}) "
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
    parts = [f"<p>{head}</p>"]
    record, why = _record(run)
    if run.source != "rdk" or record is None or run.motions is None:
        why = why or (
            "motions.npz is missing" if run.motions is None else "the motions are not simulated from a record"
        )
        parts.append(_note(f"No measured cause on this page: {why}, so the record cannot be set against its ensemble."))
        return "".join(parts)
    g = run.record_gap
    x, pct = g["record_theta_max_over_alpha"], g["record_percentile"]
    q75 = _num(cmp["q75"])
    amp = g.get("amplitude", 1.0)
    scaled = f" times {amp:g} as the ensemble," if amp != 1.0 else ""
    if pct >= 75:
        rank = f"higher than {pct:.0f} % of the {g['n_ensemble']} motions, above their 75th percentile ({_fmt(q75, 2)})"
    elif pct >= 50:
        rank = f"higher than {pct:.0f} % of the {g['n_ensemble']} motions, above their median"
    else:
        rank = f"higher than only {pct:.0f} % of the {g['n_ensemble']} motions: a typical member of the ensemble"
    rec_line = (
        f"The record itself ({_e(g['record'])}),{scaled} compressed by &radic;S = {math.sqrt(run.S):.3g} and run "
        f"through the same model on the same specimen exactly as every motion of the ensemble, gives "
        f"&theta;<sub>max</sub>/&alpha; = <strong>{_fmt(x, 2)}</strong>: {rank}"
        + (f", and {_paper_position(x, paper)}." if paper else ".")
    )
    ia, ia_rec = g["arias_ensemble_mean_m_s"], g["arias_record_m_s"]
    ia_lo, ia_hi = g["arias_ensemble_5_95_m_s"]
    ia_ok = ia_lo <= ia_rec <= ia_hi
    # which way the gap goes: this run's percentiles below the paper's (or above)
    below = [_num(cmp[f"q{q:g}"]) < _finite_or_inf(paper[q]) for q in gap if not math.isnan(_num(cmp[f"q{q:g}"]))]
    facts = (
        f"the ensemble's mean Arias intensity is {ia:.2f} m/s against the record's {ia_rec:.2f} m/s (prototype "
        f"scale; 5&ndash;95 % of the ensemble {ia_lo:.2f}&ndash;{ia_hi:.2f} m/s"
    )
    if ia_ok:
        ia_line = f"Not the intensity: {facts})."
    elif below and all(below) and ia > ia_rec:
        ia_line = (
            f"Not a lack of intensity: {facts}, so the ensemble carries <em>more</em> energy than the record, "
            f"&times;{ia / ia_rec:.2f}), yet its percentiles stay below the paper's."
        )
    elif below and all(below):
        ia_line = f"Partly the intensity: {facts}, which leaves the record out, below it)."
    else:
        ia_line = f"The intensity differs: {facts}, which leaves the record out)."
    b0, b1 = g["band_s"]
    w0, w1 = g["omega_ratio_band"]
    lo, hi, mean = g["band_ratio_min"], g["band_ratio_max"], g["band_ratio_mean"]
    h_proto = _fmt_g(run.S * _num(run.specimen.get("height_m")), 3)
    band = (
        f"between {b0:g} and {b1:g} s (prototype periods; for the {h_proto} m prototype, "
        f"p = {g['p_prototype_1_s']:.3g} 1/s, that is &omega;/p = {w0:.2g}&ndash;{w1:.2g}, where "
        "rocking and overturning are decided, seed Fig. 2)"
    )
    damp = f"{100 * g['damping']:g} %-damped"
    if hi < 0.8:
        spec_line = (
            f"The spectral shape: {band}, the ensemble's mean {damp} PSa is only <strong>{lo:.2f}&ndash;{hi:.2f}"
            f"</strong> of the record's (mean {mean:.2f}), while at {g['short_s'][0]:g}&ndash;{g['short_s'][1]:g} s "
            f"it reaches {g['short_ratio_max']:.2f} of it (at {g['short_ratio_max_period_s']:.2g} s): the fitted "
            "model puts the record's energy at short periods, which rock a block of this size much less."
        )
    elif lo > 1.25:
        spec_line = (
            f"The spectral shape: {band}, the ensemble's mean {damp} PSa exceeds the record's, "
            f"{lo:.2f}&ndash;{hi:.2f} of it."
        )
    elif lo >= 0.8 and hi <= 1.25:
        spec_line = (
            f"The spectral shape: {band}, the ensemble's mean {damp} PSa is {lo:.2f}&ndash;{hi:.2f} of the "
            "record's, within &plusmn;25 %: the ensemble carries the record's content there."
        )
    else:
        spec_line = (
            f"The spectral shape: {band}, the ensemble's mean {damp} PSa is {lo:.2f}&ndash;{hi:.2f} of the record's "
            f"(mean {mean:.2f})."
        )
    weak = pct >= 75 and hi < 0.8
    matched = lo >= 0.8 and hi <= 1.25 and 25 <= pct <= 75
    if gap and weak:
        verdict = (
            "So the gap lies in the motions rather than in the rocking model or the engines: the record's own "
            "long-period content, which the synthetic motions lack, rocks the block "
            + (
                "into the range of the paper's percentiles."
                if _paper_position(x, paper).startswith("between")
                else "much further than they do."
            )
        )
    elif gap and matched:
        verdict = (
            "So this ensemble stands for its record: it carries the record's spectrum where rocking is decided "
            "and holds the record's own response near its middle. The remaining gap is not in the spectral shape "
            "of the motions, and, the engines agreeing, not in an engine."
        )
    elif gap:
        verdict = "These figures do not single out the motions' spectral shape as the cause of the remaining gap."
    else:
        verdict = "The paper's percentiles are reproduced within the ensemble's sampling noise."
    items = [rec_line, ia_line, spec_line]
    if gap:
        items.append(_guard("The equivalent amplitudes", lambda: _factor_line(run)))
    lis = "".join(f"<li>{t}</li>" for t in items)
    parts.append(f"<p>Measured cause, on this run's own motions:</p><ul class=cause>{lis}</ul><p>{verdict}</p>")
    note = (run.meta.get("analysis") or {}).get("paper_note")
    if gap and note:
        parts.append(
            "<p><strong>What this page cannot measure</strong> (from the scenario's <code>paper_note</code>): "
            f"{_e(note)}</p>"
        )
    parts.append(
        _note(
            "Computed by <code>scenarios.analysis.record_against_ensemble</code> when this page was written: the "
            f"record through {_e(ref)} with the run's settings, the ensemble's {g['n_ensemble']} usable records "
            f"ranked against it (ties half), spectra at {len(g['band_periods_s'])} log-spaced periods per range."
        )
    )
    return "".join(parts)


def _factor_line(run: _Run) -> str:
    """The factors on this ensemble that reach each of the paper's percentiles, and whether one factor does."""
    f = run.paper_factors
    if not f:
        return "No equivalent amplitude: the paper gives no percentile or motions.npz is missing."
    fac = f["factors"]
    qs = sorted(fac)
    ci = f"{100 * f['ci']:g} %"

    def one(q: float) -> str:
        d = fac[q]
        tgt = "overturn" if math.isinf(d["target"]) else _fmt(d["target"], 2)
        if not math.isfinite(d["factor"]):
            return f"none within &times;1/8&ndash;8 for the {stats.percentile_label(q)} ({tgt})"
        return f"&times;{d['factor']:.2f} [{d['low']:.2f}, {d['high']:.2f}] for the {stats.percentile_label(q)} ({tgt})"

    text = (
        "How much stronger, in effect, the paper's motions were: the analytic model reaches the paper's "
        "percentiles with this ensemble's accelerations multiplied by " + "; ".join(one(q) for q in qs) + " ("
        f"{100 * f['step']:g} % grid, {ci} bootstrap intervals over the {f['n']} records)."
    )
    ok = [fac[q] for q in qs if math.isfinite(fac[q]["low"]) and math.isfinite(fac[q]["high"])]
    if len(ok) >= 2:
        lo, hi = max(d["low"] for d in ok), min(d["high"] for d in ok)
        if lo <= hi:
            text += (
                f" One factor, {lo:.2f}&ndash;{hi:.2f}, reaches them all: the paper's distribution has this "
                "ensemble's shape at a higher intensity."
            )
        else:
            a, b = min(ok, key=lambda d: d["high"]), max(ok, key=lambda d: d["low"])
            text += (
                f" <strong>No single factor does</strong> (the intervals {a['low']:.2f}&ndash;{a['high']:.2f} and "
                f"{b['low']:.2f}&ndash;{b['high']:.2f} do not overlap): the paper's distribution is not this "
                "ensemble's made stronger, but "
                + (
                    "wider"
                    if qs.index(next(q for q in qs if fac[q] is a)) < qs.index(next(q for q in qs if fac[q] is b))
                    else "narrower"
                )
                + " than it: its motions differed from these in their spread, not only in intensity."
            )
    return text


def _table2(run: _Run, paper: dict[float, float]) -> str:
    """Percentiles and their differences to the reference (and to the paper), one row per quantity."""
    t2 = percentile_table(run.results, run.reference, q=_Q)
    labels = [_e(i) for i in t2.index]
    rows = []
    ref = t2.iloc[:, 0].to_numpy(float)
    if paper:
        pv = np.array([paper.get(q, math.nan) for q in _Q])
        rows.append(["seed paper, numerical [&alpha;]"] + [_fmt(v, 2) for v in pv])
        with np.errstate(invalid="ignore", divide="ignore"):
            rel = np.where(np.isfinite(ref) & np.isfinite(pv), (ref - pv) / pv, np.nan)
        rows.append([f"{_engine(run.reference, run)} [&alpha;]"] + [_fmt(v, 2) for v in ref])
        rows.append([f"({_e(run.reference)} &minus; paper)/paper [&ndash;]"] + [_signed(v) for v in rel])
    else:
        rows.append([f"{_engine(run.reference, run)} [&alpha;]"] + [_fmt(v, 2) for v in ref])
    for e in run.others:
        mine = t2[f"{e} [alpha]"].to_numpy(float)
        diff = t2[f"{e} - {run.reference} [alpha]"].to_numpy(float)
        rel = t2[f"({e} - {run.reference})/{run.reference} [-]"].to_numpy(float)
        rows.append([f"{_engine(e, run)} [&alpha;]"] + [_fmt(v, 2) for v in mine])
        rows.append([f"{_e(e)} &minus; {_e(run.reference)} [&alpha;]"] + [_signed(v) for v in diff])
        rows.append(
            [f"({_e(e)} &minus; {_e(run.reference)})/{_e(run.reference)} [&ndash;]"] + [_signed(v) for v in rel]
        )
    return _table(
        [""] + labels,
        rows,
        caption="&theta;<sub>max</sub>/&alpha; at each percentile and the differences to the reference, absolute and "
        "relative (&ldquo;&ndash;&rdquo; where a side overturns). The seed found its experiment within 0.18 "
        "(relative) of the Housner model at the median.",
    )


def _signed(v: Any, digits: int = 2) -> str:
    """A difference with its sign ("+0.00" for a rounded zero), an en dash when undefined."""
    v = _num(v)
    if not math.isfinite(v):
        return "&ndash;"
    return f"{0.0 if round(v, digits) == 0 else v:+.{digits}f}"


def _spread_table(spread: dict) -> str:
    summary = spread.get("summary") or {}
    k = spread.get("k", len(spread.get("seeds", [])))
    rows = []
    for q, v in summary.items():
        lo, med, hi = (list(v) + [math.nan] * 3)[:3]
        rows.append([stats.percentile_label(_num(q)), _fmt(lo, 2), _fmt(med, 2), _fmt(hi, 2)])
    fr = spread.get("overturn_fraction_range")
    if fr:
        lo, med, hi = (list(fr) + [math.nan] * 3)[:3]
        rows.append(["P[overturn]", _fmt(lo, 2), _fmt(med, 2), _fmt(hi, 2)])
    if not rows:
        return f"<pre>{_e(json.dumps(spread, indent=1)[:4000])}</pre>"
    return _table(
        ["", "min", "median", "max"],
        rows,
        caption=f"The reference engine on {_e(k)} independent ensembles of the same size (other seeds): how much "
        "Table 2 moves with another draw of motions. Differences between engines smaller than this spread are "
        "within the ensemble's own sampling noise.",
    )


def _disagreement(run: _Run) -> pd.DataFrame:
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


def _agreement(run: _Run) -> str:
    if not run.others:
        return _note("Only one engine: no cross-engine comparison.")
    cmp = run.comparison
    header = [
        "engine",
        "KS distance",
        "KS p-value",
        "Wasserstein W<sub>1</sub> [&alpha;]<br><small>(non-overturned)</small>",
        "&Delta;P[overturn]",
        "paired records",
        "same verdict",
        f"&theta;<sub>max</sub> within {RECORD_RTOL:.0%}",
    ]
    rows = []
    for e in run.others:
        r = cmp.loc[e]
        rows.append(
            [
                _engine(e, run),
                _fmt(r["ks_distance"]),
                _fmt_p(r["ks_pvalue"]),
                _fmt(r["wasserstein"]),
                _fmt(r["overturn_diff"]),
                _fmt(r["n_paired"], 0),
                _pct(r["verdict_share"]),
                _pct(r["agreement_share"]),
            ]
        )
    parts = [
        _table(
            header,
            rows,
            caption=f"Each engine against {_e(run.reference)}. &ldquo;Same verdict&rdquo;: both overturned or "
            f"neither did; &ldquo;within {RECORD_RTOL:.0%}&rdquo;: both overturned, or both rocked with "
            f"&theta;<sub>max</sub> within {RECORD_RTOL:.0%} of the reference's. Rocking is sensitive to small "
            "perturbations (seed Fig. 9), so record-by-record agreement can be low while the distributions agree.",
        )
    ]
    wide = _disagreement(run)
    pairs = {}
    for e in run.others:
        m = wide[e].notna() & wide[run.reference].notna()
        pairs[e] = (wide.loc[m, e].to_numpy(float), wide.loc[m, run.reference].to_numpy(float))
    if any(a.size for a, _ in pairs.values()):
        fig = figures.plot_agreement_scatter(pairs, run.reference, rtol=RECORD_RTOL, colors=run.colors)
        parts.append(
            _figure(
                fig,
                f"&theta;<sub>max</sub>/&alpha; of each engine against {_e(run.reference)}, one point per record. "
                f"Points in the grey band agree within {RECORD_RTOL:.0%}. Overturned records sit in the shaded strips: "
                "at the top when only the engine overturned, at the right when only the reference did, in the corner "
                "when both did.",
                "engine against reference scatter",
            )
        )
    worst = wide[wide["score"] > 0].sort_values("score", ascending=False, kind="stable").head(N_WORST)
    if worst.empty:
        parts.append(_note("Every record agrees: no record to single out."))
        return "".join(parts)
    names = run.results.drop_duplicates("motion_id").set_index("motion_id")["motion_name"]
    rows = []
    for mid, r in worst.iterrows():
        rows.append(
            [_e(mid), _e(names.get(mid, mid))]
            + [_fmt(r[e], 3) for e in run.engines]
            + ["overturn verdicts differ" if math.isinf(r["score"]) else f"{r['score']:.3f}"]
        )
    parts.append(f"<h3>The {len(worst)} records where the engines disagree most</h3>")
    parts.append(
        _table(
            ["motion", "name"] + [_engine(e, run) for e in run.engines] + ["largest |difference| [&alpha;]"],
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
        fig = figures.plot_histories(panels, reference=run.reference, colors=run.colors)
        parts.append(
            _figure(
                fig,
                "&theta;/&alpha; against time on those records, every engine overlaid (dashed: &plusmn;1, the static "
                "overturning angle). Look for where the histories part: the first large uplift or an impact usually "
                "decides the rest.",
                "time histories of the records with the largest disagreement",
            )
        )
    elif not hist:
        parts.append(_note("histories.parquet is missing: no time histories."))
    return "".join(parts)


def _pct(x: Any) -> str:
    v = _num(x)
    return "&ndash;" if math.isnan(v) else f"{v:.0%}"


def _spectra(run: _Run) -> str:
    mm = run.motions_meta
    w = np.asarray([_num(x) for x in mm.get("omega_ratio", [])])
    a = np.asarray([_num(x) for x in mm.get("accel_ratio", [])])
    n = int(run.results["motion_id"].max()) + 1 if len(run.results) else 0
    if w.size == 0 or w.size != a.size or w.size < n:
        return _note("run.json lacks the pulse grid (omega_ratio, accel_ratio per motion): no spectra.", "warn")
    values = {}
    for e in run.engines:
        s = run.by_motion(e).reindex(range(w.size))
        values[e] = s.to_numpy(float)
    fig = figures.plot_rocking_spectra(w, a, values, title=f"{mm.get('pulse', 'pulse')}: rocking spectra")
    parts = [
        _figure(
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
            rows.append([_engine(e, run), str(int(np.sum(both))), str(differ)])
        parts.append(
            _table(
                ["engine", "grid points compared", "overturn verdict differs"],
                rows,
                caption=f"Grid points where the engine and {_e(run.reference)} disagree on overturning.",
            )
        )
    return "".join(parts)


def _nan_to_num(v: np.ndarray) -> np.ndarray:
    """+inf kept finite for 'is compared' masks: NaN stays NaN, inf becomes a large number."""
    return np.where(np.isposinf(v), 1e300, v)


def _free_vibration(run: _Run) -> str:
    from housner import calibration

    alpha = run.alpha
    if not math.isfinite(alpha):
        return _note("run.json holds no specimen: cannot normalise the free rocking.", "warn")
    ids = sorted(int(i) for i in run.results["motion_id"].unique())
    hist = run.histories(ids)
    if not hist:
        return _note("histories.parquet is missing: no free-rocking plots.")
    m = run.motions
    amps = run.motions_meta.get("theta0_over_alpha")
    names = run.results.drop_duplicates("motion_id").set_index("motion_id")["motion_name"]

    def amp_of(i: int) -> float:
        if isinstance(amps, list) and i < len(amps):
            return _num(amps[i])
        if m is not None and "theta0" in m and i < len(m["theta0"]):
            return float(m["theta0"][i]) / alpha
        return math.nan

    releases = []
    for i in ids:
        data = {e: (t, th / alpha) for (e, k), (t, th) in hist.items() if k == i}
        if data:
            releases.append((amp_of(i), {e: data[e] for e in run.engines if e in data}))
    parts = [
        _figure(
            figures.plot_free_vibration(releases, reference=run.reference, colors=run.colors),
            "Free rocking after a release from rest at each amplitude (seed Fig. 5). The time between impacts "
            "shrinks as the amplitude decays (seed eq. 7); engines whose curves drift apart dissipate differently "
            "per impact or have another p.",
            "free rocking per release amplitude",
        )
    ]
    ratios: dict[str, tuple[list, list]] = {e: ([], []) for e in run.engines}
    cal_rows = []
    for i in ids:
        row = [f"{amp_of(i):.2f}" if math.isfinite(amp_of(i)) else _e(names.get(i, i))]
        for e in run.engines:
            if (e, i) not in hist:
                row.append("&ndash;")
                continue
            t, th = hist[(e, i)]
            try:
                cal = calibration.calibrate_free_vibration(t, th, alpha)
            except Exception as err:  # e.g. a block that rests after one impact: this cell only, not the page
                row.append(f'<span class="muted" title="{_e(err)}">&ndash;</span>')
                continue
            ratios[e][0].extend(cal.c_amplitude / alpha)
            ratios[e][1].extend(cal.c)
            row.append(f"r = {cal.r:.4f} &plusmn; {cal.r_std:.1g}<br><small>p = {cal.p:.4f} 1/s</small>")
        cal_rows.append(row)
    data = {e: (np.asarray(a), np.asarray(r)) for e, (a, r) in ratios.items() if a}
    r_h = _num(run.specimen.get("r_housner"))
    if data:
        parts.append(
            _figure(
                figures.plot_energy_ratios(
                    data, r_housner=r_h if math.isfinite(r_h) else None, reference=run.reference, colors=run.colors
                ),
                "Energy ratio of every impact, c<sub>i</sub> = (cos(&alpha; &minus; &theta;<sub>i+1</sub>) &minus; "
                "cos &alpha;)/(cos(&alpha; &minus; &theta;<sub>i</sub>) &minus; cos &alpha;) (seed eq. 8), against "
                "the amplitude before the impact. Housner's impact gives the dashed line at every amplitude; a "
                "contact model that loses more at fast impacts slopes down to the right.",
                "energy ratio per impact against amplitude",
            )
        )
    p_spec = _num(run.specimen.get("p_1_s"))
    parts.append(
        _table(
            ["&theta;<sub>0</sub>/&alpha;"] + [_engine(e, run) for e in run.engines],
            cal_rows,
            caption="r fitted over all impacts of each release (energy-decay line, &plusmn; one standard error) and "
            "p from the exact half-cycle durations (<code>housner.calibration.calibrate_free_vibration</code>). "
            f"The specimen has r = {_fmt_g(r_h, 5)} and p = {_fmt_g(p_spec, 5)} 1/s.",
        )
    )
    return "".join(parts)


def _failures(run: _Run) -> str:
    failed = run.failed
    if failed.empty:
        return _note("No record failed.", "good")
    counts = failed.groupby("engine").size()
    summary = ", ".join(f"{_e(e)}: {int(n)}" for e, n in counts.items())
    rows = [
        [_engine(r.engine, run), _e(r.motion_id), _e(r.motion_name), f"<code>{_e(r.error)}</code>"]
        for r in failed.itertuples()
    ]
    return _note(
        f"{len(failed)} record(s) failed ({summary}); they are left out of every statistic above.", "warn"
    ) + _table(["engine", "motion", "name", "error"], rows, cls="failures")


def _provenance(run: _Run) -> str:
    meta = run.meta
    prov = meta.get("provenance") or {}
    parts = []
    rows = [[_e(k), _e(v)] for k, v in (prov.get("versions") or {}).items()]
    for name, info in (meta.get("engines") or {}).items():
        if info.get("version"):
            rows.append([f"engine {_e(name)}", _e(info["version"])])
    for k in ("git_commit", "platform", "cpus", "created"):
        if prov.get(k) not in (None, ""):
            rows.append([_e(k.replace("_", " ")), f"<code>{_e(prov[k])}</code>"])
    mm = run.motions_meta
    if "seed" in mm:
        rows.append(["ensemble seed", _e(mm["seed"])])
    wall = meta.get("wall_s")
    if isinstance(wall, dict):
        for k, v in wall.items():
            rows.append([f"wall time: {_e(k)}", f"{_fmt_g(v, 4)} s"])
    elif wall is not None:
        rows.append(["wall time", f"{_fmt_g(wall, 4)} s"])
    parts.append(_table(["", ""], rows, cls="kv"))
    parts.append("<h3>Speed</h3>")
    parts.append(_speed(run))
    parts.append("<h3>Scenario file</h3>")
    parts.append(f"<pre>{_e(_scenario_text(meta.get('scenario') or {}))}</pre>")
    return "".join(parts)


def _speed(run: _Run) -> str:
    info = run.meta.get("engines") or {}
    m = run.motions
    rows = []
    for e in run.engines:
        sub = run.results[run.results["engine"] == e]
        ok = sub[sub["status"].astype(str) == "ok"]
        wall = float(sub["wall_s"].sum(min_count=1))
        sim = math.nan
        if m is not None:
            ids = ok["motion_id"].to_numpy(int)
            ids = ids[ids < len(m["n"])]
            sim = float(np.sum((np.asarray(m["n"])[ids] - 1) * np.asarray(m["dt"], dtype=float)[ids]))
        ratio = sim / wall if wall > 0 and math.isfinite(sim) else math.nan
        i = info.get(e, {})
        cached = int(sub["cached"].astype(bool).sum())
        rows.append(
            [
                _engine(e, run),
                str(len(sub)),
                str(cached),
                f"{_fmt_g(i.get('wall_s', math.nan), 4)} s",
                f"{_fmt_g(wall, 4)} s",
                f"{_fmt_g(sub['wall_s'].median() * 1000 if len(sub) else math.nan, 3)} ms",
                _fmt_g(sim, 4),
                _fmt_g(ratio, 4),
            ]
        )
    return _table(
        [
            "engine",
            "records",
            "cached",
            "engine time this run",
            "engine time, all records",
            "median per record",
            "simulated [s]",
            "simulated s per wall s",
        ],
        rows,
        caption="Engine time summed over records (&ldquo;this run&rdquo; leaves out records taken from the cache; "
        "&ldquo;all records&rdquo; counts each at the time it took when it was computed). Simulated seconds are "
        "the durations of the usable records. Times from a loaded shared machine are noisy.",
    )


def _scenario_text(scen: dict) -> str:
    """The scenario file as written (comments included) when it still says what the run used, else the run's copy."""
    f = scen.get("file")
    used = {k: v for k, v in scen.items() if k != "file"}
    if f and Path(f).is_file():
        try:
            import tomllib
        except ImportError:  # pragma: no cover - Python 3.10
            import tomli as tomllib
        try:
            text = Path(f).read_text(encoding="utf-8")
            parsed = json.loads(json.dumps(tomllib.loads(text), default=str))
        except Exception:  # unreadable or changed beyond parsing: fall back to the run's copy
            parsed = None
        # The runner adds "name" when the file has none; everything else must be the same.
        if (
            parsed is not None
            and all(used.get(k) == v for k, v in parsed.items())
            and set(used) - set(parsed) <= {"name"}
        ):
            return f"# {f}\n{text}"
        head = f"# {f} has changed since this run; the run used:\n"
    else:
        head = f"# {f} (as used by this run)\n" if f else ""
    return head + _to_toml(used)


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_toml_key(k)} = {_toml_value(x)}" for k, x in v.items()) + " }"
    return json.dumps(str(v))


def _toml_key(k: Any) -> str:
    k = str(k)
    return k if k.replace("_", "").replace("-", "").isalnum() and not k[:1].isdigit() else json.dumps(k)


def _to_toml(d: Mapping, prefix: str = "") -> str:
    """A small TOML writer for the scenario tables (scalars, lists, nested tables)."""
    lines = [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in d.items() if not isinstance(v, dict)]
    for k, v in d.items():
        if isinstance(v, dict):
            name = f"{prefix}.{_toml_key(k)}" if prefix else _toml_key(k)
            scalars = {kk: vv for kk, vv in v.items() if not isinstance(vv, dict) or _flat(vv)}
            lines.append(f"\n[{name}]")
            lines.extend(f"{_toml_key(kk)} = {_toml_value(vv)}" for kk, vv in scalars.items())
            nested = {kk: vv for kk, vv in v.items() if kk not in scalars}
            if nested:
                lines.append(_to_toml(nested, name))
    return "\n".join(lines) + "\n"


def _flat(d: dict) -> bool:
    return all(not isinstance(v, dict) for v in d.values())


# ----------------------------------------------------------------------------
# the page
_CSS = """
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
         letter-spacing: .03em; }
.badge.pass { background: #dff0d8; color: #2b6a2b; border: 1px solid #9ccc9c; }
.badge.fail { background: #f2dede; color: #a94442; border: 1px solid #e4a5a5; }
.badge.na { background: #eee; color: #555; border: 1px solid #ccc; }
ul.verdicts { list-style: none; padding: 0; font-size: 1.05rem; }
ul.verdicts li { margin: .3rem 0; }
ul.verdicts div.caveat { font-size: .88rem; max-width: 60rem; margin: .2rem 0 .4rem 1.2rem; padding: .3rem .6rem;
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
"""


def _page(run: _Run, sections: list[_Section], seconds: float) -> str:
    scen = run.meta.get("scenario") or {}
    name = scen.get("name") or run.path.name
    desc = scen.get("description", "")
    spec = run.specimen.get("name", "")
    n_motions = run.meta.get("n_motions", run.results["motion_id"].nunique())
    toc = "".join(f'<li><a href="#{s.id}">{_e(s.title)}</a></li>' for s in sections)
    body = "".join(f'<section id="{s.id}"><h2>{_e(s.title)}</h2>{s.body}</section>' for s in sections)
    created = (run.meta.get("provenance") or {}).get("created", "")
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        '<link rel="icon" href="data:,">'
        f"<title>{_e(name)}: housner report</title><style>{_CSS}</style></head><body><main>"
        f'<header class="top"><h1>Scenario <code>{_e(name)}</code></h1>'
        f'<p class="sub">{_e(desc)}</p>'
        f'<p class="sub">{_e(spec)} &middot; {_e(n_motions)} motions &middot; engines '
        f"{', '.join(_engine(e, run) for e in run.engines)} &middot; reference {_e(run.reference)}"
        f"{' &middot; run ' + _e(created) if created else ''}</p></header>"
        f'<nav class="toc"><strong>Contents</strong><ol>{toc}</ol></nav>'
        f"{body}"
        f"<footer><p>Written by <code>reports.html.write_report</code> from <code>{_e(run.path)}</code> "
        f"in {seconds:.1f} s.</p></footer>"
        "</main></body></html>\n"
    )
