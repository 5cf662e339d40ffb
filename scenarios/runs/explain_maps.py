"""Housner plus an engine's measured maps, against the engine record by record (a step of ``housner explain``).

The diagnosis of :mod:`housner.scenarios.runs.explain` searches the library's effects; none of them is an
engine's impact. This step measures the engine's own impact and flight maps on free-rocking releases
(:func:`housner.scenarios.runs.impact_map.measure_maps`), composes them into the analytic kernel
(:class:`housner.effects.measured.MeasuredMaps`: the impact law r' = r ratio(x) and the flight moment
-c(x_E) w), runs that model on the scenario's ground motions, and compares it with the engine record by
record, as the plain model and the diagnosis' model are compared. Where it disagrees, :mod:`departure`
says in which phase of the motion the two part (uplift, small rocking, rocking) and after how many impacts.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from housner._values import JsonValue
from housner.effects.measured import MeasuredMaps
from housner.scenarios.execution.runner import run_engines
from housner.scenarios.runs.departure import (
    DepartureSummary,
    departures,
    disagreeing,
    record_agreement,
    record_thetas,
    summarise,
)
from housner.scenarios.runs.impact_map import EngineMaps, measure_maps

__all__ = ["SCATTER_SEEDS", "MapsExplained", "ScatterFloor", "compare_with_maps", "maps_effect", "scatter_floor"]

#: Realisations of the measured impact scatter behind :func:`scatter_floor` (three: the floor is their mean; on
#: 100 records one realisation's share moves by a few points).
SCATTER_SEEDS = (1, 2, 3)


@dataclass(frozen=True, eq=False)
class ScatterFloor(JsonValue):
    """The agreement the maps' mean law keeps with realisations of an engine whose impacts scatter as measured
    (:func:`scatter_floor`): its mean ``share`` [-], each realisation's ``shares`` and their ``seeds``."""

    share: float = math.nan
    shares: tuple[float, ...] = ()
    seeds: tuple[int, ...] = ()


@dataclass(frozen=True, eq=False)
class MapsExplained(JsonValue):
    """Housner + the engine's measured impact and flight maps against the engine (explain.json's ``maps``).

    :func:`compare_with_maps` measures it; :mod:`housner.scenarios.runs.explain` sets its verdict against the
    extended floor (``reaches_floor``, ``reaches_scatter_floor``); :mod:`housner.reports.explain_text` says what
    remains.

    Attributes
    ----------
    agreement : float
        Per-record agreement of Housner + maps with the engine [-].
    n_records : int
        Records both ran.
    departures, departures_plain : DepartureSummary
        :func:`housner.scenarios.runs.departure.summarise` of the records that disagree, with the maps and for
        the plain model: where they part.
    scatter_floor : ScatterFloor
        :func:`scatter_floor`: the agreement the maps' mean law keeps with an engine whose impacts scatter as
        measured.
    wall_s : float
        Wall time of the step (measuring the maps included) [s].
    overturned : int
        Ground motions on which Housner + maps overturned.
    reaches_floor, reaches_scatter_floor : bool
        Whether the agreement reaches the extended floor, or the scatter floor (within
        :data:`housner.scenarios.runs.explain.REACH_MARGIN`).
    maps : EngineMaps
        The measured maps.
    """

    agreement: float = math.nan
    n_records: int = 0
    departures: DepartureSummary = field(default_factory=DepartureSummary)
    departures_plain: DepartureSummary = field(default_factory=DepartureSummary)
    scatter_floor: ScatterFloor = field(default_factory=ScatterFloor)
    wall_s: float = math.nan
    overturned: int = 0
    reaches_floor: bool = False
    reaches_scatter_floor: bool = False
    maps: EngineMaps | None = None


def maps_effect(maps: EngineMaps, seed: int | None = None) -> MeasuredMaps:
    """The maps as an effect of the analytic kernel: the bins with a finite value (a bin no impact or flight
    fell in is left out; the effect interpolates between the others). With ``seed``, each impact also scatters
    by the bin's measured spread: one realisation of that scatter
    (:func:`housner.effects.measured.measured_scatter_law`)."""
    ix, ir = maps.impact_table()
    fx, fc = maps.flight_table()
    ok_i = np.isfinite(ix) & np.isfinite(ir)
    ok_f = np.isfinite(fx) & np.isfinite(fc)
    if not ok_i.any():
        raise ValueError(f"the impact map of {maps.engine!r} holds no impact: nothing to compose")
    if seed is None:
        return MeasuredMaps.from_tables(ix[ok_i], ir[ok_i], fx[ok_f], fc[ok_f])
    spread = np.nan_to_num(np.asarray(maps.impacts["ratio_spread"], float)[ok_i], nan=0.0)
    return MeasuredMaps(ix[ok_i], ir[ok_i], fx[ok_f], fc[ok_f], impact_spread=spread, seed=int(seed))


def scatter_floor(sc, motions, settings: dict, maps: EngineMaps, theta: pd.Series, options) -> ScatterFloor:
    """The agreement [-] of Housner + the maps' mean law (``theta``) with realisations of an engine whose impacts
    also scatter by the maps' measured spread (seeds :data:`SCATTER_SEEDS`): what the mean law must miss,
    record by record, of an engine that does exactly what was measured (``share``, ``shares``, ``seeds``)."""
    shares = []
    for seed in SCATTER_SEEDS:
        res, _h, _i = run_engines(
            sc.specimen, motions, settings, options, effects=(maps_effect(maps, seed),), histories=False
        )
        share, _n = record_agreement(record_thetas(res, "housner"), theta)
        shares.append(float(share))
    return ScatterFloor(share=float(np.mean(shares)), shares=tuple(shares), seeds=tuple(SCATTER_SEEDS))


def _departures(records, engine: str, runs, model_hist: dict, alpha: float) -> DepartureSummary:
    n_fv = len(runs.releases)
    eng = {i: runs.histories[(engine, n_fv + i)] for i in records}
    mod = {i: model_hist[("housner", i)] for i in records}
    dts = {i: runs.motions[i].dt for i in records}
    return summarise(departures(records, eng, mod, dts, alpha))


def compare_with_maps(
    engine: str,
    runs,
    engine_theta: pd.Series,
    options,
    progress: Callable[[str], None],
) -> tuple[MapsExplained, pd.Series]:
    """Measure the engine's maps, run Housner + maps on ``runs``' ground motions, compare record by record.

    Returns the comparison, its verdict against the floor not set (the explanation sets it), and theta_max/alpha
    per ground motion of Housner + maps (+inf: overturned).

    ``runs`` is the :class:`~housner.scenarios.runs.engine_campaign.EngineRuns` of the explanation (its
    engine histories are read), ``engine_theta`` the engine's theta_max/alpha per ground motion.
    """
    t0 = time.perf_counter()
    sc = runs.scenario
    progress(f"measuring {engine}'s impact and flight maps (free-rocking releases)")
    maps = measure_maps(engine, sc.specimen, settings=runs.settings[engine])
    effect = maps_effect(maps)
    progress(f"running Housner + {engine}'s measured maps on the {len(runs.motions)} ground motions")
    settings = {"housner": runs.settings["housner"]}
    res, hist, _ = run_engines(sc.specimen, runs.motions, settings, options, effects=(effect,))
    theta = record_thetas(res, "housner")
    agreement, n = record_agreement(engine_theta, theta)
    _r, plain_hist, _i = run_engines(sc.specimen, runs.motions, settings, options)  # cached: the plain model's
    plain_theta = record_thetas(_r, "housner")
    alpha = sc.specimen.alpha
    deps = _departures(disagreeing(engine_theta, theta), engine, runs, hist, alpha)
    deps_plain = _departures(disagreeing(engine_theta, plain_theta), engine, runs, plain_hist, alpha)
    progress(f"Housner + the maps' mean against {len(SCATTER_SEEDS)} realisations of their measured impact scatter")
    scatter = scatter_floor(sc, runs.motions, settings, maps, theta, options)
    found = MapsExplained(
        agreement=float(agreement) if n else math.nan,
        n_records=int(n),
        departures=deps,
        departures_plain=deps_plain,
        scatter_floor=scatter,
        wall_s=time.perf_counter() - t0,
        overturned=int(np.isinf(theta).sum()),
        maps=maps,
    )
    return found, theta
