"""A scenario's run: its motions, its engines (twice when it lists [[effects]]: without and with them),
the spread of Table 2 over independent ensembles, and the run directory
(:mod:`housner.scenarios.execution.rundir`, which owns its files and columns).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from housner.motion import GroundMotion
from housner.scenarios.catalogue.scenario import Scenario, load_scenario
from housner.scenarios.catalogue.schema import effects_label
from housner.scenarios.execution.options import RunOptions
from housner.scenarios.execution.outputs import check_output_dir
from housner.scenarios.execution.run_meta import RunMeta, build_run_meta
from housner.scenarios.execution.rundir import RUN_FILES, effect_data, write_run
from housner.scenarios.execution.runner import run_engines
from housner.scenarios.motions.build import MotionFacts, build_motions
from housner.scenarios.runs.chaos import run_engine_errors, run_engine_errors_meanwhile
from housner.scenarios.runs.spread import seed_spread

__all__ = ["RunResult", "effects_series", "run_scenario"]


# --------------------------------------------------------------------------
@dataclass
class RunResult:
    """What a run produced (also written to ``out``); ``meta`` is its run.json."""

    results: pd.DataFrame
    histories: dict[tuple[str, int], np.ndarray]
    motions: list[GroundMotion]
    meta: RunMeta = field(default_factory=RunMeta)
    out: Path | None = None

    @property
    def failures(self) -> pd.DataFrame:
        """Rows whose engine failed on the record (engine, motion, error)."""
        return self.results[self.results["status"] != "ok"]


def effects_series(engine: str, effects: tuple) -> str:
    """The series name of an engine's records with ``effects``, e.g. ``housner + restitution(r=0.95)``."""
    return f"{engine} + {effects_label(effects)}"


def _with_effects(scenario, motions, eng_settings, results, histories, info, options: RunOptions) -> tuple:
    """Run every engine again with the scenario's [[effects]]; its rows join the run as series "ENGINE + EFFECTS".

    The rows keep the engine's name in ``effects_series`` form in ``engine`` (so the statistics, the
    report and the pytest assertions compare them like any engine, against the same engine without
    the effects) and the effects in ``effects``; ``info`` gets one entry per series, with ``engine``
    and ``effects``.
    """
    eff = scenario.effects
    res_e, hist_e, info_e = run_engines(scenario.specimen, motions, eng_settings, options, effects=eff)
    series = {name: effects_series(name, eff) for name in eng_settings}
    res_e = res_e.assign(engine=res_e["engine"].map(series))
    hist = {**histories, **{(series[n], i): th for (n, i), th in hist_e.items()}}
    data = [effect_data(e) for e in eff]
    info = {**info, **{series[n]: {**v, "engine": n, "effects": data} for n, v in info_e.items()}}
    return pd.concat([results, res_e], ignore_index=True), hist, info


def run_scenario(
    scenario: Scenario | str | Path,
    *,
    engines: list[str] | None = None,
    n_motions: int | None = None,
    seed: int | None = None,
    out: str | Path | None = None,
    options: RunOptions | None = None,
    **execution: Any,
) -> RunResult:
    """Run a scenario on its engines (or ``engines``) and write the run directory.

    Parameters
    ----------
    scenario : Scenario or str or Path
        A loaded scenario, a catalogue name or a TOML file.
    engines : list of str, optional
        Override the scenario's engine list.
    n_motions : int, optional
        Fewer (or more) motions of an RDK ensemble; motion i is the same for any n.
    seed : int, optional
        Override the ensemble's seed.
    out : path, optional
        Run directory (default ``runs/<scenario>``).
    options : RunOptions, optional
        How the records execute (worker processes, Dask scheduler, result cache, progress bar,
        chunk size); see :class:`~housner.scenarios.execution.options.RunOptions`. The Table 2
        spread's ensembles (``seed_spread`` in [analysis]) use its cache settings, in this process.
    **execution
        :class:`RunOptions` fields as keywords (``jobs=1``, ``cache_dir=...``), over ``options``;
        another keyword is a TypeError naming it.
    """
    opts = RunOptions.merged(options, execution, "run_scenario")
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(scenario)
    names = list(engines) if engines else list(scenario.engines)
    scenario.check_engines(names)  # unknown names and refused settings fail here, naming the file
    out = Path(out) if out else Path("runs") / scenario.name
    check_output_dir(out, "run directory", files=RUN_FILES)  # before the work, not after it
    t0 = time.perf_counter()
    motions, mmeta = build_motions(scenario, n_motions, seed=seed, band_check=True)  # the report shows the bands
    t_motions = time.perf_counter() - t0
    eng_settings = {n: dict(scenario.engine_settings.get(n, {})) for n in names}
    # each engine's free-rocking r and p errors: the report's chaos floor perturbs the analytic model by them.
    # Measured here while worker processes run the records (this process only waits on them then).
    reference = str(scenario.analysis.get("reference", "housner"))
    errors_args = (scenario.specimen, eng_settings, motions, reference)
    errors_cache = opts.cache_folder()
    in_pool = opts.scheduler is not None or opts.local_jobs() > 1
    engine_errors = run_engine_errors_meanwhile(*errors_args, cache_dir=errors_cache) if in_pool else None
    results, histories, info = run_engines(scenario.specimen, motions, eng_settings, opts)
    if scenario.effects:
        results, histories, info = _with_effects(scenario, motions, eng_settings, results, histories, info, opts)
    engine_errors = engine_errors() if in_pool else run_engine_errors(*errors_args, cache_dir=errors_cache)
    spread = None
    k = int(scenario.analysis.get("seed_spread", 0) or 0)
    if k > 1 and "housner" in names and n_motions is None and seed is None:
        spread = seed_spread(scenario, k, options=RunOptions(cache_dir=opts.cache_dir, use_cache=opts.use_cache))
    meta = build_run_meta(
        scenario=scenario.describe(),
        specimen=scenario.specimen,
        motions=MotionFacts.from_json(mmeta),
        n_motions=len(motions),
        engines=info,
        analysis=scenario.analysis,
        results=results,
        wall_s={"motions": t_motions, "total": time.perf_counter() - t0},
        engine_errors=engine_errors,
        table2_spread=spread,
        effects=scenario.effects,
    )
    write_run(out, results, histories, motions, meta)
    return RunResult(results, histories, motions, meta, out)
