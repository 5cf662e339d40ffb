"""Report section on the ground motions: where they come from, their intensity, the bands they were checked in.

For a stochastic ensemble (Rezaeian & Der Kiureghian) the fitted model
parameters and the band check against the record; the ensemble's response
spectra against the record's.
"""

from __future__ import annotations

import math

import numpy as np

from housner._values import json_number
from housner.reports.page import esc, fmt_g, fmt_num, guarded, html_figure, html_note, html_table, status_badge
from housner.reports.run.ground_figures import plot_ensemble_spectra
from housner.scenarios.motions.build import BandCheck, MatchedGain, RdkParameter
from housner.scenarios.runs.view import Run, motion_list, source_record
from housner.units import G


def ensemble_section(run: Run) -> str:
    """The ground-motions section: their source and intensity, the record(s), the fitted model, the band check."""
    mm = run.motions_meta
    parts = []
    src = run.source or "unknown"
    words = {
        "rdk": "synthetic motions of the Rezaeian &amp; Der Kiureghian model fitted to a record",
        "record": "a recorded ground motion",
        "records": "a suite of recorded ground motions, each run as recorded",
        "pulses": "analytical pulses on a grid",
        "free_vibration": "free rocking after a release from rest (no ground motion)",
        "campaign": "a measured campaign's table motions, each run as recorded (free vibrations from their "
        "measured release)",
    }.get(src, esc(src))
    facts = [["source", words]]
    if mm.model is not None:
        model = {"rdk2010": "published (Rezaeian &amp; Der Kiureghian 2010)", "matched": "spectrally matched"}
        facts.append(["ground-motion model", f"<code>{esc(mm.model)}</code>: {model.get(mm.model, '')}"])
    if mm.S is not None:
        S = json_number(mm.S)
        facts.append(
            [
                "size ratio S = R<sub>prototype</sub>/R<sub>model</sub>",
                f"{fmt_g(S)} (time compressed by &radic;S = {fmt_g(math.sqrt(S)) if S > 0 else '&ndash;'}, seed eq. 9)",
            ]
        )
    if mm.seed is not None:
        facts.append(["seed", esc(mm.seed)])
    facts += _stored_facts(run)
    parts.append(html_table(["", ""], facts, cls="kv"))
    rec = mm.record
    if rec is not None:
        rows = [
            ["name", esc(_or(rec.name, "")), ""],
            ["provenance", esc(_or(rec.provenance, "")), ""],
            ["step dt", fmt_g(rec.dt), "s"],
            ["samples", esc(_or(rec.n, "")), ""],
        ]
        if rec.file:
            rows.insert(1, ["file", f"<code>{esc(rec.file)}</code> (sha256 {esc(str(_or(rec.sha256, ''))[:16])})", ""])
        parts.append("<h3>Record</h3>")
        parts.append(html_table(["", "value", "unit"], rows, cls="kv"))
    suite = mm.records
    if suite:
        rows = [
            [esc(_or(r.name, "")), f"<code>{esc(_or(r.file, ''))}</code>", esc(_or(r.n, "")), fmt_g(r.dt)]
            for r in suite
        ]
        parts.append("<h3>Records</h3>")
        parts.append(html_table(["motion", "file", "samples", "dt [s]"], rows, cls="kv"))
    params = mm.rdk_params
    if isinstance(params, dict) and params:
        parts.append("<h3>Fitted Rezaeian &amp; Der Kiureghian parameters</h3>")
        parts.append(_rdk_table(params))
    check = mm.band_check
    if check is not None:
        parts.append("<h3>Spectral match, band by band</h3>")
        parts.append(guarded("The band check", lambda: _band_table(check, mm.matched_gain)))
    if src in ("rdk", "record"):
        parts.append(guarded("The response spectra", lambda: _spectra_figure(run)))
    if src == "pulses" and mm.pulse is not None:
        parts.append(
            html_note(
                f"Pulse shape: <code>{esc(mm.pulse)}</code> on a grid of &omega;<sub>p</sub>/p and "
                "a<sub>p</sub>/(g tan &alpha;); see <a href='#rocking-spectra'>Rocking spectra</a>."
            )
        )
    return "".join(parts)


def _or(value, default):
    """A fact of run.json, or ``default`` where the file does not state it."""
    return default if value is None else value


def _stored_facts(run: Run) -> list[list[str]]:
    """Rows on the stored motions (motions.npz): how many, their steps, durations and peak accelerations."""
    m = run.motions
    if m is None or not len(m.n):
        return []
    n = np.asarray(m.n)
    dt = np.asarray(m.dt, dtype=float)
    dur = (n - 1) * dt
    acc = np.asarray(m.acc, dtype=float)
    pga = np.max(np.abs(acc), axis=1) if acc.size else np.zeros(len(n))
    facts = [["motions", f"{len(n)}"], ["step dt", _range(dt * 1000, "ms")], ["duration", _range(dur, "s")]]
    if np.any(pga > 0):
        ratio = ""
        if math.isfinite(run.alpha):
            ratio = f"; PGA/(g tan &alpha;) {_range(pga / (G * math.tan(run.alpha)), '')}"
        facts.append(["peak ground acceleration", _range(pga, "m/s&sup2;") + f" ({_range(pga / G, 'g')}){ratio}"])
    return facts


def _band_table(check: BandCheck, gain: MatchedGain | None) -> str:
    """Per third-octave band: ensemble-mean / record of PSa and Sd with PASS/FAIL (and the matched model's gain)."""
    rows: dict[float, list[str]] = {}
    for table, col in ((check.psa, 1), (check.sd, 2)):
        for b in table.bands if table is not None else ():
            c = round(json_number(b.centre_s), 6)
            row = rows.setdefault(c, [fmt_g(c, 3), "&ndash;", "&ndash;"])
            row[col] = f"{fmt_num(b.ratio, 3)} {status_badge(b.verdict == 'PASS')}"
    header = ["band centre [s]", "PSa ratio", "Sd ratio"]
    gain_note = ""
    if gain is not None and gain.gain_centres_s:
        header.append("gain G [&ndash;]")
        gain_note = (
            f" G: the matched model's spectral gain at the band centre, fitted in {esc(_or(gain.iterations, '?'))} "
            f"iterations on {esc(_or(gain.n_fit, '?'))} motions."
        )
        g = {round(json_number(c), 6): json_number(v) for c, v in zip(gain.gain_centres_s, gain.gain, strict=False)}
        for c, row in rows.items():
            row.append(fmt_num(g.get(c, math.nan), 3))
    lo, hi = (list(check.bounds) + [math.nan, math.nan])[:2]
    psa, sd = (t.range_s if t is not None and t.range_s else ("?", "?") for t in (check.psa, check.sd))
    verdict = status_badge(bool(check.passed)) if check.passed is not None else ""
    caption = (
        f"{verdict} {esc(_or(check.what, ''))}: ratio of the geometric mean over the band of ensemble mean / record, "
        f"accepted within [{fmt_g(lo)}, {fmt_g(hi)}]; PSa checked over {fmt_g(psa[0])}-"
        f"{fmt_g(psa[1])} s, Sd over {fmt_g(sd[0])}-{fmt_g(sd[1])} s "
        "(housner.scenarios.motions.bands.band_check)." + gain_note
    )
    return html_table(header, [rows[c] for c in sorted(rows)], cls="kv", caption=caption)


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


#: Fitted Rezaeian & Der Kiureghian parameters (keys of ``housner.scenarios.motions.rdk_params.RDKParams.describe()``):
#: key -> (symbol, meaning), or (symbol, meaning, unit) where the key's unit suffix (:func:`_unit_from_key`)
#: does not give the unit.
_RDK_ROWS = {
    "model": ("model", ""),
    "Ia_m_s": ("I<sub>a</sub>", "Arias intensity, &pi;/(2g) &int; &uuml;<sub>g</sub>&sup2; dt"),
    "D5_95_s": ("D<sub>5-95</sub>", "significant duration, from 5 % to 95 % of I<sub>a</sub>"),
    "t_mid_s": ("t<sub>mid</sub>", "time at 45 % of I<sub>a</sub>"),
    "omega_mid_rad_s": ("&omega;<sub>mid</sub>", "filter frequency at t<sub>mid</sub>"),
    "f_mid_Hz": ("f<sub>mid</sub>", "&omega;<sub>mid</sub>/2&pi;"),
    "omega_prime_rad_s2": ("&omega;&prime;", "rate of change of the filter frequency"),
    "zeta_f": ("&zeta;<sub>f</sub>", "filter damping ratio", "&ndash;"),
    "omega_c_rad_s": ("&omega;<sub>c</sub>", "corner frequency of the high-pass filter"),
    "T0_s": ("T<sub>0</sub>", "start of the modulating function q(t)"),
    "dt_s": ("dt", "step of the simulated motions (prototype scale)"),
    "duration_s": ("duration", "length of the simulated motions (prototype scale)"),
    "alpha1": (
        "&alpha;<sub>1</sub>",
        "scale of q(t) = &alpha;<sub>1</sub> (t&minus;T<sub>0</sub>)<sup>&alpha;2&minus;1</sup> "
        "exp(&minus;&alpha;<sub>3</sub>(t&minus;T<sub>0</sub>))",
        "m/s&sup2; s<sup>1&minus;&alpha;2</sup>",
    ),
    "alpha2": ("&alpha;<sub>2</sub>", "shape of q(t)", "&ndash;"),
    "alpha3_1_s": ("&alpha;<sub>3</sub>", "decay rate of q(t)"),
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
        if isinstance(v, RdkParameter):  # {value, unit, description}
            value, unit, desc = v.value, esc(_or(v.unit, "")), esc(_or(v.description, ""))
            symbol = f"<code>{esc(k)}</code>"
        else:
            symbol, desc, *unit = _RDK_ROWS.get(k, (f"<code>{esc(k)}</code>", ""))
            unit = unit[0] if unit else _unit_from_key(str(k))
            value = v
        cell = esc(value) if isinstance(value, str) else fmt_g(value, 5)
        rows.append([symbol, cell, unit, desc])
    return html_table(["parameter", "value", "unit", "meaning"], rows, cls="kv")


def _spectra_figure(run: Run) -> str:
    if run.motions is None:
        return html_note("motions.npz is missing: no spectra.")
    record, why = source_record(run)
    if record is None:
        return html_note(f"{esc(why)}: no spectra.", "warn" if "catalogue" in why or "Record file" in why else "note")
    S = run.S
    # motions.npz holds the model-scale motions (time compressed by sqrt(S), seed eq. 9); the figure takes
    # the prototype-scale ensemble and draws the time-scaled spectra itself.
    prototype = [m.scaled(time=math.sqrt(S)) for m in motion_list(run)]
    fig = plot_ensemble_spectra(record, prototype, S=S if S != 1.0 else None)
    return html_figure(
        fig,
        "Elastic response spectra of the record and of the simulated motions (seed Fig. 8). The simulated "
        "motions should scatter around the record; they match it only in linear elastic terms, which does "
        "not guarantee similar rocking responses.",
        "response spectra of the record and the ensemble",
    )
