"""Report section on the engines' tuning: the contact settings tuned to reproduce r, checked against the run's.

Reads ``tuning-<engine>.json`` (written by ``housner tune``) from
:data:`TUNING_DIR`: the energy ratio against release amplitude and time step,
the free-rocking decay, the checks the tuner ran, and whether the run used the
settings that were tuned (a caveat on the headline when not).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from housner import engines
from housner.engines.base import engine_class
from housner.engines.tuning import DECAY_RTOL, DECAY_START, SMALL_WORST_FACTOR, TuningResult
from housner.engines.tuning.result import DecayCheck, PulseCheck, RatioCheck
from housner.reports import figures
from housner.reports.page import (
    engine_tag,
    esc,
    fmt_g,
    fmt_num,
    html_figure,
    html_note,
    html_table,
    status_badge,
    view_colors,
)
from housner.scenarios.runs.verdicts import engine_verdict
from housner.scenarios.runs.view import Run
from housner.statistics.ensemble_stats import KS_MAX

#: Folder of the tuning results ``tuning-<engine>.json`` written by ``housner tune``;
#: None means ``engines/models`` of the installed package.
TUNING_DIR: Path | None = None


def tuning_caveats(run: Run) -> dict[str, str]:
    """engine -> HTML: the tuning checks its tuning file did not meet, by how much, and what that means here."""
    out = {}
    for name, stored in model_data(run).items():
        if name not in run.others or stored.data is None:
            continue
        t = TuningResult.from_json(stored.data)
        if t.met is not False:
            continue
        failed = [c for c in _tuning_checks(t) if not c.met]
        if not failed:
            continue
        summary = run.summaries[name]
        ok = engine_verdict(summary).ok
        what = "; ".join(f'<span class="bad">{c.short}</span>' for c in failed)
        text = f"Tuning not met (<code>{esc(stored.path.name)}</code>, {esc(t.date)}): {what}. "
        names = {c.name for c in failed}
        first_impact_ok = all(c.met for c in _tuning_checks(t) if c.name.startswith("r of the first impact"))
        if any(n.startswith("free decay") for n in names) and first_impact_ok:
            text += (
                "The first-impact r is within tolerance at every amplitude the tuner releases from, so the missing "
                "energy goes where it does not look: in the slow impacts of small rocking, or in flight, and piles "
                "up over many small rockings. The engine's impact and flight maps say which "
                "(<code>housner impact-map ENGINE</code>; PyBullet's: its slow impacts, "
                "<code>docs/results.md#pybullet-verdict</code>). "
            )
        decay = _frame(t.decay_table)
        small_limit = math.nan
        if {"rel_error", "peak_analytic"} <= set(decay.columns):
            bad = decay[np.abs(decay["rel_error"].to_numpy(float)) > DECAY_RTOL]
            if len(bad):
                small_limit = float(bad["peak_analytic"].max())
        ks = summary.ks_distance
        if ok:
            text += (
                f"It does not change this verdict, which is measured on this run's own motions (KS {ks:.3f} "
                f"&le; {KS_MAX}): a loss that mattered for them would show there"
            )
            if math.isfinite(small_limit):
                v = run.values(run.reference)
                k = int(np.sum(v <= small_limit))
                text += (
                    f"; the loss exceeds the tolerance at peaks of {small_limit:.3f} &alpha; and below, and "
                    f"{k} of the {v.size} records peak there in the reference (smallest peak "
                    f"{fmt_num(np.min(v) if v.size else math.nan, 3)} &alpha;)"
                )
            text += (
                ". It does limit the engine where small free rocking matters (long free decays, motions that keep "
                "the block rocking at a few hundredths of &alpha;): check such uses against the analytic model."
            )
        else:
            text += "This run's verdict fails on its own criteria as well."
        out[name] = text
    return out


def settings_html(settings: dict) -> str:
    """Engine settings one per line; None (the engine's default) is written as such."""
    return "<br>".join(
        f"<code>{esc(k)} = {'default' if v is None else esc(json.dumps(v))}</code>" for k, v in settings.items()
    )


def model_file(kind: str, engine: str) -> Path:
    """The stored ``<kind>-<engine>.json`` (kind: tuning, explain, frontier) in :data:`TUNING_DIR`."""
    if TUNING_DIR is not None:
        return Path(TUNING_DIR) / f"{kind}-{engine}.json"
    return Path(engines.__file__).resolve().parent / "models" / f"{kind}-{engine}.json"


@dataclass(frozen=True)
class StoredFile:
    """An engine's stored measurement (``<kind>-<engine>.json``): its ``path``, its JSON ``data`` (None when the
    file cannot be read) and the ``error`` that says why not ("" when it was read)."""

    path: Path
    data: Any = None
    error: str = ""


def model_data(run: Run, kind: str = "tuning") -> dict[str, StoredFile]:
    """engine -> its stored ``<kind>-<engine>.json``, read, for the run's engines that have one."""
    found = {}
    for name in run.engines:
        f = model_file(kind, name)
        if f.is_file():
            try:
                found[name] = StoredFile(f, json.loads(f.read_text(encoding="utf-8")))
            except (OSError, json.JSONDecodeError) as e:
                found[name] = StoredFile(f, error=f"cannot read: {e}")
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


def _frame(table: pd.DataFrame) -> pd.DataFrame:
    """A table of a tuning file, with a ``dt`` column (NaN: a file older than the sample steps)."""
    df = table.copy()
    if "dt" not in df.columns:
        df["dt"] = math.nan
    return df


def _tuning_checks(t: TuningResult) -> list[_Check]:
    """The tuner's checks (``housner.engines.tuning``) re-evaluated from the tables of a tuning file.

    Each check is judged with the tuner's own tolerances, so a check said "not met"
    here is the one ``housner tune`` counted; tables absent from the file give no row.
    """
    rtol = t.rtol
    found = (_first_impact_check(t, rtol), _small_check(t, rtol), _decay_check(t), _pulse_check(t, rtol))
    return [c for c in found if c is not None]


def _worst_row(df: pd.DataFrame, col: str) -> pd.Series:
    """The row of ``df`` with the largest |``col``|."""
    return df.iloc[int(np.argmax(np.abs(df[col].to_numpy(float))))]


def _first_impact_check(t: TuningResult, rtol: float) -> _Check | None:
    """r of the first impact after a release at the large amplitudes (the file's ``table``), within rtol."""
    table = _frame(t.table)
    target = t.target_r
    if "rel_error" not in table.columns and "r_engine" in table.columns and math.isfinite(target):
        table["rel_error"] = table["r_engine"].astype(float) / target - 1.0  # files older than the error column
    if not ({"amplitude", "rel_error"} <= set(table.columns) and len(table)):
        return None
    w = RatioCheck.from_row(_worst_row(table, "rel_error"))
    amps = table["amplitude"].to_numpy(float)
    rng = f"{amps.min():g}-{amps.max():g} &alpha;"
    return _Check(
        f"r of the first impact, {rng}",
        f"worst {w.rel_error:+.2%} at {w.amplitude:g} &alpha; ({_step_label(w.dt)}); "
        f"mean {table['rel_error'].mean():+.2%}",
        f"&plusmn;{rtol:.2%}",
        bool(abs(w.rel_error) <= rtol),
        f"r at {rng} worst {w.rel_error:+.2%} (accepted &plusmn;{rtol:.2%})",
    )


def _small_check(t: TuningResult, rtol: float) -> _Check | None:
    """r of the first impact at small amplitudes (``small_table``): the worst within a wider band, each step's mean
    within rtol."""
    small = _frame(t.small_table)
    if not ({"amplitude", "rel_error"} <= set(small.columns) and len(small)):
        return None
    w = RatioCheck.from_row(_worst_row(small, "rel_error"))
    means = small.groupby("dt", dropna=False, sort=False)["rel_error"].mean()
    m = float(means.iloc[int(np.argmax(np.abs(means.to_numpy(float))))])
    amps = small["amplitude"].to_numpy(float)
    rng = f"{amps.min():g}-{amps.max():g} &alpha;"
    tol_w = SMALL_WORST_FACTOR * rtol
    return _Check(
        f"r of the first impact, {rng}",
        f"worst {w.rel_error:+.2%} at {w.amplitude:g} &alpha; ({_step_label(w.dt)}); worst mean {m:+.2%}",
        f"worst &plusmn;{tol_w:.2%}, mean &plusmn;{rtol:.2%}",
        bool(abs(w.rel_error) <= tol_w and abs(m) <= rtol),
        f"r at {rng} worst {w.rel_error:+.2%}, mean {m:+.2%} (accepted &plusmn;{tol_w:.2%} and &plusmn;{rtol:.2%})",
    )


def _decay_check(t: TuningResult) -> _Check | None:
    """A free decay's peaks after many impacts against the exact sequence (``decay_table``), within DECAY_RTOL."""
    decay = _frame(t.decay_table)
    if not ({"impacts", "rel_error", "peak_engine", "peak_analytic"} <= set(decay.columns) and len(decay)):
        return None
    w = DecayCheck.from_row(_worst_row(decay, "rel_error"))
    bad = decay[np.abs(decay["rel_error"].to_numpy(float)) > DECAY_RTOL]
    where = ""
    if len(bad):
        where = (
            f"; beyond the tolerance from {int(bad['impacts'].min())} impacts on, i.e. at peaks of "
            f"{bad['peak_analytic'].max():.3f} &alpha; and below"
        )
    return _Check(
        "free decay: peaks after " + ", ".join(str(int(k)) for k in sorted(set(decay["impacts"]))) + " impacts",
        f"worst {w.rel_error:+.1%} after {w.impacts} impacts ({w.peak_engine:.4f} &alpha; against "
        f"{w.peak_analytic:.4f} &alpha;, {_step_label(w.dt)}){where}",
        f"&plusmn;{DECAY_RTOL:.0%}",
        bool(abs(w.rel_error) <= DECAY_RTOL),
        f"a free decay's peak after {w.impacts} impacts is {w.rel_error:+.1%} off the analytic "
        f"{w.peak_analytic:.4f} &alpha; ({_step_label(w.dt)}; accepted &plusmn;{DECAY_RTOL:.0%})",
    )


def _pulse_check(t: TuningResult, rtol: float) -> _Check | None:
    """One-sine pulses (``pulse_table``): the first peak within rtol and theta_max within each pulse's tolerance."""
    pulses = _frame(t.pulse_table)
    if not ({"rel_error", "theta_max_rel_error", "theta_max_rtol"} <= set(pulses.columns) and len(pulses)):
        return None
    w = PulseCheck.from_row(_worst_row(pulses, "rel_error"))
    scaled = np.abs(pulses["theta_max_rel_error"].to_numpy(float)) / pulses["theta_max_rtol"].to_numpy(float)
    k = int(np.argmax(scaled))
    wt = PulseCheck.from_row(pulses.iloc[k])
    n = pulses["pulse"].nunique() if "pulse" in pulses.columns else len(pulses)
    return _Check(
        f"{n} one-sine pulses: first peak and &theta;<sub>max</sub>",
        f"first peak worst {w.rel_error:+.2%}; &theta;<sub>max</sub> worst {wt.theta_max_rel_error:+.2%} "
        f"({esc(wt.pulse)}, {_step_label(wt.dt)})",
        f"first peak &plusmn;{rtol:.2%}; &theta;<sub>max</sub> &plusmn;"
        + ", &plusmn;".join(f"{x:.2%}" for x in sorted(set(pulses["theta_max_rtol"]))),
        bool(abs(w.rel_error) <= rtol and scaled[k] <= 1.0),
        f"pulse &theta;<sub>max</sub> worst {wt.theta_max_rel_error:+.2%} (accepted &plusmn;{wt.theta_max_rtol:.2%})",
    )


def _tuning_series(t: TuningResult) -> tuple[dict, dict]:
    """r against amplitude per sample step (large and small amplitudes joined), and decay errors per step."""
    parts = [x for x in (_frame(t.small_table), _frame(t.table)) if {"amplitude", "r_engine"} <= set(x.columns)]
    curves: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    if parts:
        both = pd.concat(parts, ignore_index=True)
        for dt, g in both.groupby("dt", dropna=False, sort=False):
            g = g.sort_values("amplitude", kind="stable")
            curves[_step_label(float(dt)) if math.isfinite(float(dt)) else ""] = (
                g["amplitude"].to_numpy(float),
                g["r_engine"].to_numpy(float),
            )
    decay = _frame(t.decay_table)
    dec: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    if {"impacts", "rel_error"} <= set(decay.columns):
        for dt, g in decay.groupby("dt", dropna=False, sort=False):
            g = g.sort_values("impacts", kind="stable")
            dec[_step_label(float(dt)) if math.isfinite(float(dt)) else ""] = (
                g["impacts"].to_numpy(float),
                g["rel_error"].to_numpy(float),
            )
    return curves, dec


def settings_differ(tuned: dict, used: dict) -> list[str]:
    """Settings where the run differs from the tuning file (keys the run sets); empty when it runs as tuned."""

    def norm(v):
        return json.loads(json.dumps(v))

    return [k for k, v in used.items() if k in tuned and norm(tuned[k]) != norm(v)]


def engine_defaults(name: str) -> dict:
    """The registered engine's DEFAULTS, or none for an engine the registry does not know."""
    try:
        return dict(getattr(engine_class(name), "DEFAULTS", {}) or {})
    except (ValueError, ImportError):  # an unknown or unloadable engine: compare only what the file has
        return {}


def tuning_section(run: Run) -> str:
    """Tuned contact checks and r against amplitude, from housner.engines/models/tuning-<engine>.json when present."""
    found = model_data(run)
    if not found:
        return html_note(
            "No tuning results (engines/models/tuning-&lt;engine&gt;.json) for these engines: "
            "they run with the settings above. <code>housner tune ENGINE</code> finds contact settings that "
            "reproduce a target r."
        )
    parts = ["<h3>Tuned contact parameters</h3>"]
    rows = []
    curves, decays = {}, {}
    target = rtol = None
    for name, stored in found.items():
        if stored.data is None:
            rows.append(
                [engine_tag(name, run), f"<code>{esc(stored.path.name)}</code>: {esc(stored.error)}"] + [""] * 4
            )
            continue
        t = TuningResult.from_json(stored.data)
        rows.append(_tuning_row(run, name, t))
        c, dec = _tuning_curves(t)
        if c:
            curves[name] = c
        if dec:
            decays[name] = dec
        if math.isfinite(t.target_r):
            target = t.target_r
        if math.isfinite(t.rtol):
            rtol = t.rtol
    parts.append(
        html_table(
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
        parts.append(_tuning_figure(run, curves, decays, target, rtol))
    return "".join(parts)


def _tuning_row(run: Run, name: str, t: TuningResult) -> list[str]:
    """An engine's row of the tuning table: its tuned settings against the run's, the checks, the verdict, when."""
    tuned = t.settings
    used = run.meta.engine_settings(name)
    # a setting the file lacks did not exist when it was written: the engine's default keeps the
    # behaviour of that time (e.g. impact_energy_factor 1)
    tuned = {**engine_defaults(name), **tuned}
    differ = settings_differ(tuned, used)
    if not used:
        same = f"{settings_html(tuned) or '&ndash;'}<br><small>(the run recorded no settings)</small>"
    elif differ:
        same = '<span class="bad">the run differs:</span><br>' + "<br>".join(
            f"<code>{esc(k)}</code>: tuned {esc(json.dumps(tuned[k]))}, run {esc(json.dumps(used[k]))}" for k in differ
        )
    else:
        same = "the run's settings (above)"
    met = t.met
    check_cells = "<br>".join(
        f'<span class="{"ok" if c.met else "bad"}">{"met" if c.met else "NOT MET"}</span>: {c.name}: '
        f"{c.measured} <span class=muted>(accepted {c.accepted})</span>"
        for c in _tuning_checks(t)
    )
    return [
        engine_tag(name, run),
        same,
        fmt_g(t.target_r, 5),
        check_cells or "&ndash;",
        status_badge(bool(met), "MET", "NOT MET") if met is not None else "&ndash;",
        f"{esc(t.date)}, version {esc(t.version)}",
    ]


def _tuning_curves(t: TuningResult) -> tuple[dict, dict]:
    """:func:`_tuning_series` of a tuning file (an older file's one table without sample steps included)."""
    return _tuning_series(t)


def _tuning_figure(run: Run, curves: dict, decays: dict, target: float | None, rtol: float | None) -> str:
    """r against amplitude for every tuned engine with its accepted bands, and the free-decay check."""
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
        colors=view_colors(run),
    )
    return html_figure(
        fig,
        "Left: energy ratio r of the first impact after a release from rest against the release amplitude, "
        "one line per engine and sample step, with the accepted band around the target. A flat line on the "
        "target means the contact dissipates like Housner's impact at every amplitude; a trend means its "
        "losses depend on the impact velocity. Right: a free decay, the engine's peak after 10-40 impacts "
        "against the exact sequence; energy lost between impacts accumulates here.",
        "r against amplitude for the tuned engines, and the free-decay check",
    )
