"""Report sections on the run itself: failed records, provenance, speed and the scenario as TOML."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from housner.reports.page import engine_tag, esc, fmt_g, html_note, html_table
from housner.scenarios.execution.run_meta import EngineFacts, ScenarioCopy
from housner.scenarios.runs.view import Run


def failures_section(run: Run) -> str:
    failed = run.failed
    if failed.empty:
        return html_note("No record failed.", "good")
    counts = failed.groupby("engine").size()
    summary = ", ".join(f"{esc(e)}: {int(n)}" for e, n in counts.items())
    rows = [
        [engine_tag(r.engine, run), esc(r.motion_id), esc(r.motion_name), f"<code>{esc(r.error)}</code>"]
        for r in failed.itertuples()
    ]
    return html_note(
        f"{len(failed)} record(s) failed ({summary}); they are left out of every statistic above.", "warn"
    ) + html_table(["engine", "motion", "name", "error"], rows, cls="failures")


def provenance_section(run: Run) -> str:
    meta = run.meta
    prov = meta.provenance
    parts = []
    rows = [[esc(k), esc(v)] for k, v in (prov.versions or {}).items()]
    for name, info in meta.engines.items():
        if info.version:
            rows.append([f"engine {esc(name)}", esc(info.version)])
    for label, v in (
        ("git commit", prov.git_commit),
        ("platform", prov.platform),
        ("cpus", prov.cpus),
        ("created", prov.created),
    ):
        if v not in (None, ""):
            rows.append([esc(label), f"<code>{esc(v)}</code>"])
    mm = run.motions_meta
    if mm.seed is not None:
        rows.append(["ensemble seed", esc(mm.seed)])
    wall = meta.wall_s
    if isinstance(wall, dict):
        for k, v in wall.items():
            rows.append([f"wall time: {esc(k)}", f"{fmt_g(v, 4)} s"])
    elif wall is not None:
        rows.append(["wall time", f"{fmt_g(wall, 4)} s"])
    parts.append(html_table(["", ""], rows, cls="kv"))
    parts.append("<h3>Speed</h3>")
    parts.append(_speed(run))
    parts.append("<h3>Scenario file</h3>")
    parts.append(f"<pre>{esc(_scenario_text(meta.scenario))}</pre>")
    return "".join(parts)


def _speed(run: Run) -> str:
    info = run.meta.engines
    m = run.motions
    rows = []
    for e in run.engines:
        sub = run.results[run.results["engine"] == e]
        ok = sub[sub["status"].astype(str) == "ok"]
        wall = float(sub["wall_s"].sum(min_count=1))
        sim = math.nan
        if m is not None:
            ids = ok["motion_id"].to_numpy(int)
            ids = ids[ids < len(m.n)]
            sim = float(np.sum((np.asarray(m.n)[ids] - 1) * np.asarray(m.dt, dtype=float)[ids]))
        ratio = sim / wall if wall > 0 and math.isfinite(sim) else math.nan
        i = info.get(e) or EngineFacts()
        cached = int(sub["cached"].astype(bool).sum())
        rows.append(
            [
                engine_tag(e, run),
                str(len(sub)),
                str(cached),
                f"{fmt_g(math.nan if i.wall_s is None else i.wall_s, 4)} s",
                f"{fmt_g(wall, 4)} s",
                f"{fmt_g(sub['wall_s'].median() * 1000 if len(sub) else math.nan, 3)} ms",
                fmt_g(sim, 4),
                fmt_g(ratio, 4),
            ]
        )
    return html_table(
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


def _scenario_text(scen: ScenarioCopy) -> str:
    """The scenario file as written (comments included) when it still says what the run used, else the run's copy."""
    f = scen.file
    used = {k: v for k, v in scen.table.items() if k != "file"}
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
            and {k: v for k, v in used.items() if k in parsed} == parsed
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
