"""An engine's responses as a measurement campaign: free vibrations and a scenario's ground motions.

:func:`export_engine_campaign` runs an engine (through the runner,
:func:`housner.scenarios.execution.runner.run_engines`, so its records are
cached like a scenario's) on free vibrations released from rest at
:data:`AMPLITUDES` alpha, alternately toward +x and -x, and on a scenario's
ground motions, and writes its responses in the campaign format
(docs/reference/campaign-format.md; read back with
:func:`housner.scenarios.campaigns.campaign.load_campaign`): the scenario's
specimen, one record per response with ``time`` [s], ``ground_acc`` [m/s^2]
and ``theta`` [rad], the free vibrations first, in the middle and last in the
record order, as the independent test campaigns order theirs. It is what
:func:`housner.scenarios.runs.explain.explain_engine` diagnoses.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from housner.engines.base import ENGINES
from housner.errors import unknown_choice
from housner.motion import GroundMotion
from housner.scenarios.catalogue.scenario import Scenario, load_scenario
from housner.scenarios.execution.options import RunOptions
from housner.scenarios.execution.outputs import check_output_dir
from housner.scenarios.execution.runner import run_engines
from housner.scenarios.motions.build import build_motions

__all__ = [
    "AMPLITUDES",
    "FV_DURATION",
    "EngineRuns",
    "check_engine",
    "check_sigma",
    "export_engine_campaign",
    "ground_motion_scenario",
    "run_engine_records",
    "write_engine_campaign",
]

#: Release amplitudes theta0 / alpha of the free vibrations [-]: from the small rocking where contact
#: conventions weigh most to the large ones near the overturning angle.
AMPLITUDES = (0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 0.8)
#: Length of a free-vibration record [s], as the ``free-vibration`` scenario's.
FV_DURATION = 10.0


@dataclass
class EngineRuns:
    """The engine's records of a scenario, and the analytic model's on the same ground motions."""

    engine: str
    scenario: Scenario
    releases: list[GroundMotion]
    motions: list[GroundMotion]
    results: pd.DataFrame  # the runner's table; motion_id < len(releases): a release
    histories: dict
    settings: dict  # engine name -> settings (the engine's and "housner")
    wall_s: float


def ground_motion_scenario(scenario: Scenario | str | Path, n_motions: int | None = None) -> Scenario:
    """The scenario loaded (a catalogue name or a TOML file), refused when it holds no ground motions, or
    when ``n_motions`` is given for one that is not an RDK ensemble."""
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    if sc.source == "free_vibration" or sc.study is not None:
        what = "free-vibration releases" if sc.source == "free_vibration" else "a fragility study"
        raise ValueError(
            f"`scenario` {sc.name!r} is {what}; explain needs a scenario of ground motions (e.g. 'elcentro')"
        )
    if n_motions is not None and sc.source != "rdk":
        raise ValueError(
            f"`n_motions` applies to RDK ensembles; scenario {sc.name!r} has a fixed set of "
            f"{sc.n_motions} motions (source {sc.source!r})"
        )
    return sc


def check_engine(engine: str) -> None:
    """A registered engine name, else the ValueError that lists the choices and suggests the closest."""
    if engine not in ENGINES:
        raise unknown_choice("engine", engine, ENGINES)


def _check_amplitudes(amplitudes: Sequence[float]) -> tuple[float, ...]:
    amps = tuple(float(a) for a in amplitudes)
    if not amps or not all(0.0 < a < 1.0 for a in amps):
        raise ValueError(f"`amplitudes` must be release amplitudes theta0/alpha in (0, 1), got {amplitudes!r}")
    return amps


def _releases(scenario: Scenario, amplitudes: Sequence[float], dt: float) -> list[GroundMotion]:
    """Releases from rest at each amplitude [alpha], alternately toward +x and -x, sampled at ``dt`` [s]."""
    alpha = scenario.specimen.alpha
    out = []
    for j, a in enumerate(amplitudes):
        sign = 1.0 if j % 2 == 0 else -1.0  # both pivots: an engine's asymmetry shows
        out.append(GroundMotion.free_vibration(sign * a * alpha, FV_DURATION, dt, name=f"release {sign * a:+g} alpha"))
    return out


def run_engine_records(
    engine: str, scenario: Scenario, n_motions: int | None, amplitudes: Sequence[float], options: RunOptions | None
) -> EngineRuns:
    """Run the engine on the releases and the ground motions, the analytic model on the ground motions.

    Arguments as :func:`export_engine_campaign`'s (``scenario`` loaded, :func:`ground_motion_scenario`).
    The results table numbers the releases first (motion_id 0 .. len(amplitudes) - 1), then the ground
    motions; the analytic model's rows use the same numbers.
    """
    check_engine(engine)
    scenario.check_engines([engine, "housner"])
    t0 = time.perf_counter()
    motions, _meta = build_motions(scenario, n_motions)
    dt = float(np.median([m.dt for m in motions]))  # the ensemble's step: the diagnosis reads one grid
    releases = _releases(scenario, _check_amplitudes(amplitudes), dt)
    settings = {n: dict(scenario.engine_settings.get(n, {})) for n in dict.fromkeys((engine, "housner"))}
    res, hist, _info = run_engines(scenario.specimen, releases + motions, {engine: settings[engine]}, options)
    if engine != "housner":
        res_h, _h, _i = run_engines(
            scenario.specimen, motions, {"housner": settings["housner"]}, options, histories=False
        )
        res = pd.concat([res, res_h.assign(motion_id=res_h["motion_id"] + len(releases))], ignore_index=True)
    return EngineRuns(engine, scenario, releases, motions, res, hist, settings, time.perf_counter() - t0)


def _record_order(n_fv: int, n_gm: int) -> list[tuple[str, int]]:
    """(kind, index) in recording order: a third of the releases first, then half of the ground motions,
    the next third, the other half, the last third.

    The releases of each third are every third amplitude (0.05, 0.3, 0.8 / 0.1, 0.5 / 0.2, 0.7 alpha), so
    that an amplitude dependence does not show as a drift along the order.
    """
    groups = [list(range(k, n_fv, 3)) for k in range(3)]
    half = n_gm // 2
    gm = [("ground_motion", i) for i in range(n_gm)]
    return [
        *(("free_vibration", j) for j in groups[0]),
        *gm[:half],
        *(("free_vibration", j) for j in groups[1]),
        *gm[half:],
        *(("free_vibration", j) for j in groups[2]),
    ]


def write_engine_campaign(runs: EngineRuns, out_dir: Path, sigma: float, seed: int) -> Path:
    """Write the engine's records as a campaign (campaign.toml, records/*.csv); the records it failed left out.

    Parameters
    ----------
    runs : EngineRuns
        From :func:`run_engine_records`.
    out_dir : Path
        The campaign directory (it exists and is writable).
    sigma : float
        Noise added to theta [rad]; ``seed`` seeds it (see :func:`export_engine_campaign`).
    seed : int

    Returns
    -------
    Path
        ``out_dir``.
    """
    eng, sc = runs.engine, runs.scenario
    rows = runs.results[runs.results["engine"] == eng].set_index("motion_id")
    n_fv = len(runs.releases)
    (out_dir / "records").mkdir(parents=True, exist_ok=True)
    sp = sc.specimen
    lines = [
        f"name = {_toml_str(f'{eng} on {sc.name}')}",
        f"description = {_toml_str(_description(runs, sigma, seed))}",
        "",
        "[specimen]",
        f"height = {sp.height!r}",
        f"width = {sp.width!r}",
        f"depth = {sp.depth!r}",
        f"mass = {sp.mass!r}",
        f"p = {sp.p!r}",
    ]
    fv_k = 0
    for kind, i in _record_order(n_fv, len(runs.motions)):
        mid = i if kind == "free_vibration" else n_fv + i
        row = rows.loc[mid]
        if row["status"] != "ok" or (eng, mid) not in runs.histories:
            continue
        if kind == "free_vibration":
            fv_k += 1
            rid = f"fv{fv_k:02d}"
        else:
            rid = f"gm{i + 1:03d}"
        motion = (runs.releases + runs.motions)[mid]
        theta = np.clip(np.asarray(runs.histories[(eng, mid)], dtype=float), -math.pi / 2, math.pi / 2)
        if sigma > 0.0:  # the record's own stream, numbered as in the results table
            rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(mid,)))
            theta = theta + rng.normal(0.0, sigma, theta.size)
        _write_record(out_dir / "records" / f"{rid}.csv", motion, theta)
        lines += ["", "[[record]]", f'id = "{rid}"', f'kind = "{kind}"', f'file = "records/{rid}.csv"']
        if bool(row["overturned"]):
            lines.append("overturned = true")
    (out_dir / "campaign.toml").write_text("\n".join(lines) + "\n")
    return out_dir


def _write_record(path: Path, motion: GroundMotion, theta: np.ndarray) -> None:
    """time [s], ground_acc [m/s^2], theta [rad]; time and acceleration written to round-trip exactly
    (rocking is chaotic: a part in 1e10 of the input moves a record's peak)."""
    n = min(motion.n, theta.size)
    t = np.arange(n) * motion.dt
    np.savetxt(
        path,
        np.column_stack((t, motion.acc[:n], theta[:n])),
        fmt=["%.17g", "%.17g", "%.9g"],
        delimiter=",",
        header="time,ground_acc,theta",
        comments="",
    )


def _toml_str(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _description(runs: EngineRuns, sigma: float, seed: int) -> str:
    eng = runs.engine
    failed = runs.results[(runs.results["engine"] == eng) & (runs.results["status"] != "ok")]
    names = [(runs.releases + runs.motions)[int(i)].name for i in failed["motion_id"]]
    text = (
        f"responses of engine {eng} (settings {runs.settings[eng] or 'default'}) to scenario "
        f"{runs.scenario.name!r}: {len(runs.releases)} free vibrations and {len(runs.motions)} ground motions; "
        f"theta noise {sigma:g} rad (seed {seed})"
    )
    if names:
        text += f"; {len(names)} record(s) the engine failed left out: {', '.join(names[:5])}"
    return text


def check_sigma(sigma: float) -> float:
    """A noise level [rad]: finite and >= 0."""
    s = float(sigma)
    if not (math.isfinite(s) and s >= 0.0):
        raise ValueError(f"`sigma` must be a finite noise level >= 0 [rad], got {sigma!r}")
    return s


def export_engine_campaign(
    engine: str,
    scenario: Scenario | str | Path,
    out_dir: str | Path,
    *,
    amplitudes: Sequence[float] = AMPLITUDES,
    n_motions: int | None = None,
    sigma: float = 0.0,
    seed: int = 0,
    options: RunOptions | None = None,
) -> Path:
    """Write an engine's free vibrations and ground-motion responses as a measurement campaign.

    Parameters
    ----------
    engine : str
        Registry name of the engine, run with the scenario's settings for it.
    scenario : Scenario or str or Path
        A scenario of ground motions (catalogue name, TOML file or loaded); its specimen is the campaign's.
    out_dir : path
        The campaign directory (created; ``campaign.toml`` and ``records/`` written in it).
    amplitudes : sequence of float
        Release amplitudes theta0 / alpha of the free vibrations [-], each in (0, 1); the j-th is released
        toward +x for even j, toward -x for odd j.
    n_motions : int, optional
        Ground motions of an RDK ensemble (default: the scenario's); motion i is the same for any n.
    sigma : float
        Standard deviation of Gaussian noise added to theta [rad] (0: the engine's own samples).
    seed : int
        Seed of that noise; record k draws from ``SeedSequence(seed, spawn_key=(k,))``, k counting the
        releases first, then the ground motions (so a record's noise does not change when n grows).
    options : RunOptions, optional
        How the engine's records execute (workers, cache, progress bar).

    Returns
    -------
    pathlib.Path
        ``out_dir``, readable with :func:`housner.scenarios.campaigns.campaign.load_campaign`.

    Notes
    -----
    Record files hold ``time`` [s], ``ground_acc`` [m/s^2] and ``theta`` [rad] on the ensemble's
    median sample step (the releases too). A record the block overturned in says
    ``overturned = true``; theta is held within +-pi/2. Records the engine failed are left out
    and named in the campaign's ``description``.
    """
    check_engine(engine)  # the arguments before the work
    sc = ground_motion_scenario(scenario, n_motions)
    sig = check_sigma(sigma)
    amplitudes = _check_amplitudes(amplitudes)
    out = check_output_dir(Path(out_dir), "`out_dir`", files=("campaign.toml",))  # before the work
    runs = run_engine_records(engine, sc, n_motions, amplitudes, options)
    return write_engine_campaign(runs, out, sig, int(seed))
