"""Record by record, a model against an engine: which records agree, and where the others part.

:func:`record_thetas` reads theta_max/alpha per record off the runner's table, :func:`record_agreement` and
:func:`disagreeing` apply the per-record rule (both overturned, or both rocked with theta_max/alpha within
:data:`~housner.scenarios.runs.chaos.RECORD_RTOL` of the engine's).

An agreement says how many records a model gets right, not where it goes wrong. For each record on which
they disagree, :func:`departures` finds the first sample where the two theta histories differ by more than
:data:`DEPART_TOL` alpha, and says what the engine's block was doing there:

- ``"uplift"``: neither had an impact yet: the two part while the block lifts off or in its first
  half-cycle (the uplift threshold, the contact's give before uplift, the forcing in flight);
- ``"small rocking"``: after the k-th impact, in an engine's half-cycle whose amplitude is below
  :data:`SMALL_ROCKING` alpha, where contact conventions weigh most (the impact at low speed, the
  velocity thresholds of the engines' contacts);
- ``"rocking"``: after the k-th impact, in larger rocking (the impact law at speed, the flight).

:func:`summarise` counts the phases and the impacts before departure, and names the records.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from housner._values import JsonValue
from housner.free_vibration.impacts import impact_times
from housner.scenarios.runs.chaos import RECORD_RTOL
from housner.statistics.ensemble_stats import ks_2samp, per_record_agreement

__all__ = [
    "DEPART_TOL",
    "PHASES",
    "SMALL_ROCKING",
    "DepartureSummary",
    "ImpactsBefore",
    "Departure",
    "departure",
    "departures",
    "disagreeing",
    "record_agreement",
    "record_ks",
    "record_thetas",
    "summarise",
]

#: |theta_engine - theta_model| at which the two have parted [alpha]. Ten times the shared rocking threshold
#: (:data:`housner.engines._planar.ROCKING_TOL`, 5e-3 alpha, below which a block counts as at rest), so that
#: the tilt of a contact at rest never counts, and a fifth of :data:`housner.scenarios.runs.chaos.RECORD_RTOL`'s
#: scale of theta_max on the records that matter (theta_max/alpha ~ 0.3-1): a record that disagrees by that
#: criterion has parted by this much somewhere.
DEPART_TOL = 0.05
#: A half-cycle below this amplitude [alpha] is small rocking (the engines' impact maps depart from Housner's
#: constant ratio below about 0.05 alpha of release; ``docs/results.md#impacts``).
SMALL_ROCKING = 0.1
#: Where two histories part (:attr:`Departure.phase`), in the order the summary counts them.
PHASES = ("uplift", "small rocking", "rocking", "never")
#: |theta| above which a sign change counts as an impact in :func:`departure` [alpha] (the shared rocking
#: threshold, :data:`housner.engines._planar.ROCKING_TOL`).
_IMPACT_TOL = 5e-3


# ----------------------------------------------------------------------------
# which records agree
def record_thetas(results: pd.DataFrame, engine: str, offset: int = 0) -> pd.Series:
    """theta_max/alpha per ground motion (+inf: overturned) of an engine's ok rows, indexed by motion."""
    ok = results[(results["engine"] == engine) & (results["status"] == "ok") & (results["motion_id"] >= offset)]
    v = np.where(ok["overturned"].to_numpy(bool), np.inf, ok["theta_max_over_alpha"].to_numpy(float))
    return pd.Series(v, index=ok["motion_id"].to_numpy(int) - offset)


def record_ks(engine_theta: pd.Series, model_theta: pd.Series) -> float:
    """KS distance [-] between the engine's and the model's theta_max/alpha on the records both ran."""
    both = engine_theta.index.intersection(model_theta.index)
    return ks_2samp(engine_theta[both].to_numpy(), model_theta[both].to_numpy()).distance if len(both) else math.nan


def record_agreement(engine_theta: pd.Series, model_theta: pd.Series) -> tuple[float, int]:
    """Per-record agreement share [-] of the model with the engine (the reference) on the records both ran."""
    both = engine_theta.index.intersection(model_theta.index)
    if not len(both):
        return math.nan, 0
    ag = per_record_agreement(model_theta[both].to_numpy(), engine_theta[both].to_numpy(), rtol=RECORD_RTOL, atol=0.0)
    return ag.share, ag.n


def disagreeing(engine_theta: pd.Series, model_theta: pd.Series) -> list[int]:
    """The records (ids both ran) on which the model disagrees with the engine by :func:`record_agreement`'s rule:
    not both overturned, and not both rocked with theta_max/alpha within RECORD_RTOL of the engine's."""
    both = engine_theta.index.intersection(model_theta.index)
    e = engine_theta[both].to_numpy(float)
    m = model_theta[both].to_numpy(float)
    with np.errstate(invalid="ignore"):  # inf - inf where both overturned: decided by the first term
        close = np.isfinite(e) & np.isfinite(m) & (np.abs(m - e) <= RECORD_RTOL * np.abs(e))
    agree = (np.isinf(e) & np.isinf(m)) | close
    return [int(i) for i, ok in zip(both, agree, strict=True) if not ok]


# ----------------------------------------------------------------------------
# where the others part
@dataclass(frozen=True)
class Departure:
    """Where one record's model and engine histories part.

    Attributes
    ----------
    record : int
        The record's index (motion id).
    time : float
        Time of the first sample where they differ by more than :data:`DEPART_TOL` alpha [s]; NaN if never.
    phase : str
        ``"uplift"``, ``"small rocking"``, ``"rocking"`` (module docstring) or ``"never"``.
    impacts_before : int
        The engine's impacts before ``time``.
    amplitude : float
        The engine's largest |theta| in the half-cycle of ``time`` (between the impacts around it) [alpha].
    """

    record: int
    time: float
    phase: str
    impacts_before: int
    amplitude: float


def departure(record: int, theta_engine, theta_model, dt: float, alpha: float) -> Departure:
    """Where the model's history ``theta_model`` parts from the engine's ``theta_engine`` (both [rad], step ``dt`` [s]).

    The histories are compared over their common length; a history that ends early (an engine stops at an
    overturn) is compared up to its end.
    """
    te = np.asarray(theta_engine, dtype=float)
    tm = np.asarray(theta_model, dtype=float)
    n = min(te.size, tm.size)
    te, tm = te[:n], tm[:n]
    far = np.flatnonzero(~(np.abs(te - tm) <= DEPART_TOL * alpha))  # NaN counts as parted
    if far.size == 0:
        return Departure(int(record), math.nan, "never", 0, math.nan)
    k = int(far[0])
    t = np.arange(n) * dt
    hits = impact_times(t, te, _IMPACT_TOL * alpha)
    n_imp = int(np.count_nonzero(hits <= t[k]))
    start = int(math.ceil(hits[n_imp - 1] / dt)) if n_imp else 0
    stop = int(math.floor(hits[n_imp] / dt)) + 1 if n_imp < hits.size else n
    amp = float(np.max(np.abs(te[start:stop]))) / alpha
    if n_imp == 0:
        phase = "uplift"
    else:
        phase = "small rocking" if amp < SMALL_ROCKING else "rocking"
    return Departure(int(record), float(k * dt), phase, n_imp, amp)


def departures(records, engine_histories: dict, model_histories: dict, dts: dict, alpha: float) -> list[Departure]:
    """:func:`departure` of each of ``records`` (ids); the histories and steps [s] are dicts by record id."""
    return [departure(i, engine_histories[i], model_histories[i], dts[i], alpha) for i in records]


@dataclass(frozen=True, eq=False)
class ImpactsBefore(JsonValue):
    """The impacts before departure over the records that part after an impact: quartiles and median (NaN: none)."""

    q25: float = math.nan
    median: float = math.nan
    q75: float = math.nan


@dataclass(frozen=True, eq=False)
class DepartureSummary(JsonValue):
    """Where the records that disagree part (:func:`summarise`).

    Attributes
    ----------
    n : int
        Records.
    by_phase : dict
        Phase -> records that part in it.
    impacts_before : ImpactsBefore
    records : dict
        Phase -> the first records (ids) that part in it.

    Its words are :func:`housner.reports.explain_text.departures_text`'s.
    """

    n: int = 0
    by_phase: dict[str, int] = field(default_factory=dict)
    impacts_before: ImpactsBefore = field(default_factory=ImpactsBefore)
    records: dict[str, tuple[int, ...]] = field(default_factory=dict)


def summarise(deps: list[Departure], max_named: int = 8) -> DepartureSummary:
    """Counts by phase, the impacts before departure (median and quartiles), and the records by phase.

    Returns
    -------
    DepartureSummary
        ``n``, ``by_phase`` {phase: count}, ``impacts_before`` (``median``, ``q25``, ``q75``) over the records
        that part after an impact, and ``records`` {phase: ids, at most ``max_named``}.
    """
    by = {ph: [d for d in deps if d.phase == ph] for ph in PHASES}
    after = np.array([d.impacts_before for d in deps if d.impacts_before > 0], dtype=float)
    q = {
        k: (float(np.percentile(after, p)) if after.size else math.nan)
        for k, p in (("q25", 25), ("median", 50), ("q75", 75))
    }
    return DepartureSummary(
        n=len(deps),
        by_phase={ph: len(by[ph]) for ph in PHASES},
        impacts_before=ImpactsBefore(**q),
        records={ph: tuple(d.record for d in by[ph][:max_named]) for ph in PHASES},
    )
