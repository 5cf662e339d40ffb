"""An engine's accuracy-cost frontier: its time step and main contact setting swept, each point measured.

:func:`engine_frontier` sweeps an engine's settings along the axes its class declares
(``FRONTIER``: the time step and its main contact setting, 3-5 values each, the other
settings at their defaults; :func:`frontier_axes`) and measures, at every point:

* the tuner's checks (:mod:`housner.engines.tuning.checks`): the worst error of the
  energy ratio r over releases at 0.2-0.9 alpha, the worst at small amplitudes, the free
  decay over 40 impacts, the pulses, whether all are met, and the CPU seconds per simulated
  second on the check records;
* the scenario's ground motions: per-record agreement of the engine's theta_max/alpha with
  the analytic model's (within :data:`~housner.scenarios.runs.chaos.RECORD_RTOL`), the
  two-sample KS statistic of the two distributions, and the extended floor
  (:func:`~housner.scenarios.runs.explain_floor.extended_floor`: the chaos floor of the
  point's own r and p errors, or the model-form floor of a correct integrator, the lower).

:func:`knee` picks the point where accuracy stops improving: the cheapest point that meets
every tuner check some point meets (:func:`admissible`), scores no worse on them than the
defaults (no accuracy the checks see is traded for time), keeps the run report's distribution
verdict where the defaults pass it (KS at most :data:`~housner.statistics.ensemble_stats.KS_MAX`,
:func:`keeps_the_verdict`)
and whose per-record agreement is not significantly below the best point's (a two-proportion z-test at
95 %, :data:`KNEE_Z`). ``housner frontier ENGINE`` runs it from the shell and stores the result that the
run report draws (``engines/models/frontier-<engine>.json``).
"""

from __future__ import annotations

import datetime
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from housner._values import JsonValue
from housner.engines.base import engine_class
from housner.engines.tuning import COST_TIE, tune
from housner.scenarios.catalogue.scenario import Scenario
from housner.scenarios.execution.options import RunOptions
from housner.scenarios.execution.rundir import jsonable
from housner.scenarios.execution.runner import run_engines
from housner.scenarios.motions.build import build_motions
from housner.scenarios.runs.departure import record_agreement, record_thetas
from housner.scenarios.runs.engine_campaign import check_engine, ground_motion_scenario
from housner.scenarios.runs.explain_floor import FloorParts, engine_chaos_floor, extended_floor, model_form_floor
from housner.statistics.ensemble_stats import KS_MAX, ks_2samp

__all__ = [
    "KNEE_Z",
    "TIMESTEP_FACTORS",
    "Frontier",
    "FrontierPoint",
    "admissible",
    "engine_frontier",
    "frontier_axes",
    "knee",
    "knee_reason",
    "not_worse_checked",
    "same_setting",
    "unmet_everywhere",
]

#: Time steps swept for an engine that declares no ``FRONTIER``: its default times these [-].
TIMESTEP_FACTORS = (0.5, 1.0, 2.0, 4.0)
#: One-sided z of the knee's test [-]: a point's agreement counts as below the best point's when the
#: difference exceeds 1.96 standard errors of a difference of two shares (95 %, two-sided).
KNEE_Z = 1.96


@dataclass(frozen=True, eq=False)
class FrontierPoint(JsonValue):
    """One point of the sweep: the settings that differ from the defaults and what they measured.

    Errors are relative [-] (engine / analytic - 1, the worst by magnitude); shares are of the
    records both engines ran [-]; ``cpu_per_sim_second`` is CPU seconds per simulated second
    on the tuner's check records. ``floor_parts`` is None where the point did not run on the ground
    motions (written as an empty table); the JSON also holds the point's :attr:`label`.
    """

    axis: str = ""  # the setting swept ("" for the defaults)
    settings: dict = field(default_factory=dict)  # the settings that differ from the defaults
    r_error: float = math.nan
    small_error: float = math.nan
    decay_error: float = math.nan
    pulse_error: float = math.nan
    checks_met: bool = False
    failed: str = ""  # the tuner's checks not met, comma-separated
    score: float = math.nan  # the tuner's score: the largest error over its tolerance (<= 1: all met)
    agreement: float = math.nan
    n_records: int = 0
    ks: float = math.nan
    floor: float = math.nan
    floor_parts: FloorParts | None = None
    overturned: int = 0
    cpu_per_sim_second: float = math.nan
    error: str = ""

    _EMPTY_WHEN_NONE = ("floor_parts",)

    def to_json(self) -> dict:
        """The point's keys and values, then its label."""
        return {**super().to_json(), "label": self.label}

    @classmethod
    def from_json(cls, data: Any) -> FrontierPoint:
        """The point of :meth:`to_json`'s data (its label follows from the settings: read, not kept)."""
        data = {k: v for k, v in data.items() if k != "label"} if isinstance(data, dict) else data
        return super().from_json(data)

    @property
    def label(self) -> str:
        """The point as a table names it: ``timestep=0.0001``, or ``defaults``."""
        return ", ".join(f"{k}={_fmt(v)}" for k, v in self.settings.items()) or "defaults"

    def agreement_se(self) -> float:
        """Binomial standard error of :attr:`agreement` [-]."""
        p, n = self.agreement, self.n_records
        return math.sqrt(max(p * (1.0 - p), 0.0) / n) if n and math.isfinite(p) else math.nan


@dataclass(frozen=True, eq=False)
class Frontier(JsonValue):
    """The sweep of one engine on one scenario (module docstring); ``housner frontier ENGINE --json`` writes
    :meth:`to_dict`."""

    engine: str
    scenario: str
    n_motions: int
    defaults: dict
    axes: dict
    points: tuple[FrontierPoint, ...]
    knee: int  # index into points
    default: int  # index into points
    model_form_floor: float
    version: str = ""
    date: str = ""
    wall_s: float = 0.0

    def to_dict(self) -> dict:
        """The frontier JSON: :meth:`to_json` with NaN as null."""
        return jsonable(self.to_json(), nonfinite="null")

    @classmethod
    def from_dict(cls, d: Mapping) -> Frontier:
        """The frontier of a frontier JSON (:meth:`from_json`); KeyError without its points."""
        if not isinstance(d, Mapping) or "points" not in d:
            raise KeyError("points")
        return cls.from_json(d)

    def knee_settings(self) -> dict:
        """The knee's settings, complete (the defaults with the knee's changes)."""
        return {**self.defaults, **self.points[self.knee].settings}

    def summary(self) -> str:
        """The frontier as a text table, the default and the knee marked."""
        head = (
            f"{'point':32s} {'r err':>7s} {'small':>7s} {'decay':>7s} {'pulse':>7s} {'checks':>6s} "
            f"{'agree':>6s} {'floor':>6s} {'KS':>6s} {'cpu/s':>8s}"
        )
        lines = [f"{self.engine} on {self.scenario} ({self.n_motions} motions): accuracy against cost", head]
        for i, p in enumerate(self.points):
            mark = ("*" if i == self.knee else " ") + ("d" if i == self.default else " ")
            if p.error:
                lines.append(f"{mark}{p.label[:30]:30s} failed: {p.error}")
                continue
            lines.append(
                f"{mark}{p.label[:30]:30s} {p.r_error:+7.2%} {p.small_error:+7.2%} {p.decay_error:+7.1%} "
                f"{p.pulse_error:+7.2%} {'met' if p.checks_met else 'NOT':>6s} {p.agreement:6.0%} "
                f"{p.floor:6.0%} {p.ks:6.3f} {p.cpu_per_sim_second:8.4f}"
            )
        k, d = self.points[self.knee], self.points[self.default]
        lines.append(f"d: the defaults; *: the knee ({k.label}): {knee_reason(self)}")
        if self.knee != self.default and math.isfinite(k.cpu_per_sim_second) and d.cpu_per_sim_second > 0:
            lines.append(f"the knee costs {k.cpu_per_sim_second / d.cpu_per_sim_second:.2f}x the defaults")
        return "\n".join(lines)


def frontier_axes(engine: str) -> dict[str, tuple]:
    """The settings an engine's frontier sweeps and their values: the class's ``FRONTIER``, else its
    default ``timestep`` times :data:`TIMESTEP_FACTORS`.

    Raises
    ------
    ValueError
        For an engine with neither (nothing to sweep), naming it.
    """
    cls = engine_class(engine)
    axes = getattr(cls, "FRONTIER", None)
    if axes:
        return {str(k): tuple(v) for k, v in axes.items()}
    dt = (getattr(cls, "DEFAULTS", None) or {}).get("timestep")
    if not dt:
        raise ValueError(f"engine {engine!r} has no `timestep` setting and declares no FRONTIER axes: nothing to sweep")
    return {"timestep": tuple(float(dt) * f for f in TIMESTEP_FACTORS)}


def _points(defaults: Mapping, axes: Mapping[str, Sequence]) -> list[FrontierPoint]:
    """The defaults first, then each axis' values other than its default, the other settings at theirs."""
    pts = [FrontierPoint("", {})]
    for name, values in axes.items():
        if name not in defaults:
            raise ValueError(
                f"frontier axis {name!r} is not a setting of the engine; its settings: {', '.join(sorted(defaults))}"
            )
        pts += [FrontierPoint(name, {name: v}) for v in values if not same_setting(v, defaults[name])]
    return pts


def engine_frontier(
    engine: str,
    scenario: Scenario | str | Path = "elcentro",
    *,
    n_motions: int | None = None,
    axes: Mapping[str, Sequence] | None = None,
    options: RunOptions | None = None,
    progress: Callable[[str], None] | None = None,
) -> Frontier:
    """Sweep an engine's settings and measure accuracy and cost at each point (module docstring).

    Parameters
    ----------
    engine : str
        Registry name of the engine (not the analytic one: it is the reference).
    scenario : Scenario or str or Path
        A scenario of ground motions (default ``elcentro``); its specimen is tuned for.
    n_motions : int, optional
        Ground motions of an RDK ensemble (default: the scenario's).
    axes : mapping, optional
        Setting name -> values to sweep (default :func:`frontier_axes`).
    options : RunOptions, optional
        How the ground-motion records execute (workers, cache, progress bar).
    progress : callable, optional
        Called with a line of text as the work goes.

    Returns
    -------
    Frontier
    """
    t0 = time.perf_counter()
    say = progress or (lambda s: None)
    check_engine(engine)
    if engine == "housner":
        raise ValueError("`engine` 'housner' is the reference the frontier measures against; name another engine")
    sc = ground_motion_scenario(scenario, n_motions)
    cls = engine_class(engine)
    ax = {str(k): tuple(v) for k, v in (axes or frontier_axes(engine)).items()}
    base = dict(sc.engine_settings.get(engine, {}))
    probe = cls(**base)  # the scenario's settings checked, and the engine's full defaults with them
    defaults, version = probe.settings(), probe.version()
    pts = _points(defaults, ax)
    motions, _meta = build_motions(sc, n_motions)
    say(f"the tuner's checks at {len(pts)} points of {engine}")
    table = tune(engine, sc.specimen, candidates=[{**base, **p.settings} for p in pts], progress=False).candidates
    href = dict(sc.engine_settings.get("housner", {}))
    say(f"the analytic model on {len(motions)} ground motions")
    res_h, _h, _i = run_engines(sc.specimen, motions, {"housner": href}, options, histories=False)
    ref = record_thetas(res_h, "housner")
    mform = model_form_floor(sc.specimen, [motions[i] for i in sorted(ref.index)], href)
    for i, p in enumerate(pts):
        p = pts[i] = _take_checks(p, table.iloc[i])
        if p.error:
            continue
        say(f"{engine} {p.label} on {len(motions)} ground motions ({i + 1}/{len(pts)})")
        pts[i] = _measure_on_motions(p, engine, {**base, **p.settings}, sc.specimen, motions, ref, mform, href, options)
    return Frontier(
        engine=engine,
        scenario=sc.name,
        n_motions=len(motions),
        defaults=defaults,
        axes={k: list(v) for k, v in ax.items()},
        points=tuple(pts),
        knee=knee(pts),
        default=0,
        model_form_floor=float(mform.share),
        version=version,
        date=datetime.date.today().isoformat(),
        wall_s=time.perf_counter() - t0,
    )


def _take_checks(p: FrontierPoint, row) -> FrontierPoint:
    """Point ``p`` with the tuner's checks of its row of the tuner's candidates table."""
    return replace(
        p,
        r_error=float(row["worst_rel_error"]),
        small_error=float(row["small_worst_rel_error"]),
        decay_error=float(row["decay_rel_error"]),
        pulse_error=float(row["pulse_rel_error"]),
        checks_met=bool(row["met"]),
        cpu_per_sim_second=float(row["cost_per_sim_second"]),
        failed=str(row.get("failed", "") or ""),
        score=float(row["score"]),
        error=str(row["error"] or ""),
    )


def _measure_on_motions(
    p: FrontierPoint,
    engine: str,
    settings: dict,
    specimen,
    motions: list,
    ref,
    mform,
    href: dict,
    options: RunOptions | None,
) -> FrontierPoint:
    """Point ``p`` run by ``engine`` with the point's ``settings`` on the ground motions: its agreement with the
    analytic model's theta_max/alpha ``ref``, KS distance, overturns and extended floor (``mform``: the
    model-form floor; ``href``: the analytic model's settings)."""
    res, _h, _i = run_engines(specimen, motions, {engine: settings}, options, histories=False)
    th = record_thetas(res, engine)
    agreement, n_records = record_agreement(th, ref)
    p = replace(p, agreement=agreement, n_records=n_records)
    both = th.index.intersection(ref.index)
    if not len(both):
        return replace(p, error="no record ran")
    chaos = engine_chaos_floor(engine, settings, specimen, [motions[j] for j in sorted(both)], href.get("r"))
    return replace(
        p,
        ks=float(ks_2samp(th[both].to_numpy(), ref[both].to_numpy()).distance),
        overturned=int(np.isinf(th[both].to_numpy()).sum()),
        floor_parts=FloorParts(chaos=float(chaos.share), model_form=float(mform.share)),
        floor=extended_floor(chaos, mform),
    )


def knee(points: Sequence[FrontierPoint]) -> int:
    """Index of the cheapest point where accuracy stops improving (module docstring).

    The admissible points ran and meet every tuner check that some point meets (all of them, where one
    point meets all; a check no point meets, such as a decay no setting reaches, is said, not chosen
    by), and score no worse on the checks than the defaults (:func:`not_worse_checked`: the largest
    error over its tolerance; the per-impact scatter makes it vary by +-0.3 from one step to the next,
    so a coarser step is taken only where it checks as well), and keep the run report's distribution
    verdict where the defaults do (:func:`keeps_the_verdict`). Among them: the cheapest whose agreement
    is at most :data:`KNEE_Z` standard errors of the difference below the best agreement among them,
    costs within :data:`~housner.engines.tuning.COST_TIE` (15 %) of each other counting as equal (then
    the defaults, the first point, stay). Where no point meets every check some point meets, the
    admissible point is the one of smallest score.
    """
    ok = _candidates(points)
    if not ok:
        return 0
    b = points[max(ok, key=lambda i: points[i].agreement)]

    def close(p: FrontierPoint) -> bool:
        se = math.hypot(p.agreement_se(), b.agreement_se())
        return b.agreement - p.agreement <= KNEE_Z * se

    near = [i for i in ok if close(points[i])]
    cheapest = min(points[i].cpu_per_sim_second for i in near)
    tie = [i for i in near if points[i].cpu_per_sim_second <= (1.0 + COST_TIE) * cheapest]
    # CPU time is noisy at 10-20 %: among the equally cheap, the defaults stay, else the most accurate
    return 0 if 0 in tie else max(tie, key=lambda i: (points[i].agreement, -points[i].cpu_per_sim_second))


def _ran(points: Sequence[FrontierPoint]) -> list[int]:
    """The points that ran on the ground motions."""
    return [i for i, p in enumerate(points) if not p.error and math.isfinite(p.agreement)]


def _checked(points: Sequence[FrontierPoint]) -> list[int]:
    """The points that ran, are admissible and check no worse than the defaults."""
    ran = _ran(points)
    return not_worse_checked(points, admissible(points, ran)) if ran else []


def _candidates(points: Sequence[FrontierPoint]) -> list[int]:
    """The points the knee is chosen among: :func:`_checked`, keeping the distribution verdict."""
    return keeps_the_verdict(points, _checked(points))


def keeps_the_verdict(points: Sequence[FrontierPoint], idx: Sequence[int]) -> list[int]:
    """The points of ``idx`` whose KS distance is within the run report's criterion
    (:data:`~housner.statistics.ensemble_stats.KS_MAX`)
    or, where the defaults' is not, no larger than theirs: a default never makes its engine fail a report it
    passed (an example: docs/results.md#defaults-frontier). A point without a KS (not measured) is not held
    back by it."""
    d = points[0]
    if 0 not in idx or not math.isfinite(d.ks):
        return list(idx)
    bound = max(KS_MAX, d.ks)
    return [i for i in idx if not points[i].ks > bound]


def not_worse_checked(points: Sequence[FrontierPoint], idx: Sequence[int]) -> list[int]:
    """The points of ``idx`` whose tuner score is no worse than the defaults' (``points[0]``), when the defaults
    are among them: accuracy the checks can see is not traded for CPU time."""
    d = points[0]
    if 0 not in idx or not math.isfinite(d.score):
        return list(idx)
    return [i for i in idx if points[i].score <= d.score]


def _failed(p: FrontierPoint) -> set[str]:
    if p.checks_met:
        return set()
    return {c.strip() for c in p.failed.split(",") if c.strip()} or {"a check"}


def unmet_everywhere(points: Sequence[FrontierPoint], idx: Sequence[int] | None = None) -> set[str]:
    """The tuner's checks that no point (of ``idx``) meets."""
    idx = range(len(points)) if idx is None else idx
    sets = [_failed(points[i]) for i in idx if not points[i].error]
    return set.intersection(*sets) if sets else set()


def admissible(points: Sequence[FrontierPoint], idx: Sequence[int]) -> list[int]:
    """The points of ``idx`` that meet every tuner check some point of ``idx`` meets, else the best-scoring one."""
    never = unmet_everywhere(points, idx)
    ok = [i for i in idx if _failed(points[i]) <= never]
    if ok:
        return ok
    return [min(idx, key=lambda i: points[i].score if math.isfinite(points[i].score) else math.inf)]


def knee_reason(f: Frontier) -> str:
    """Why the knee is where it is, in one sentence or two."""
    pts = f.points
    k = pts[f.knee]
    checked = _checked(pts)
    ok = keeps_the_verdict(pts, checked)
    best = max((pts[i] for i in ok), key=lambda p: p.agreement, default=k)
    never = unmet_everywhere(pts, _ran(pts))
    lead = (
        "it meets every tuner check"
        if k.checks_met
        else f"no point meets the {', '.join(sorted(never))} check; it meets every other"
    )
    lead += f", scores {k.score:.2f} on them (the defaults {pts[0].score:.2f})"
    held = [pts[i] for i in checked if i not in ok and pts[i].cpu_per_sim_second < k.cpu_per_sim_second]
    tail = ""
    if held:
        verb = "checks" if len(held) == 1 else "check"
        tail = (
            ". " + ", ".join(f"{p.label} (KS {p.ks:.2f})" for p in held) + f" {verb} as well for less CPU "
            f"time but would fail the run report's KS criterion ({KS_MAX})"
        )
    return (
        f"{lead}, its agreement ({k.agreement:.0%}) is within {KNEE_Z:g} standard errors of the best "
        f"({best.agreement:.0%}, {best.label}), and it costs the least CPU time of those "
        f"({k.cpu_per_sim_second:.4g} s per simulated second; within {COST_TIE:.0%} counts as equal, and then "
        f"the defaults stay){tail}"
    )


def same_setting(a, b) -> bool:
    """Equal settings: numbers to 1e-12, sequences (a tuple or its JSON list) element by element."""
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(same_setting(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        return math.isclose(float(a), float(b), rel_tol=1e-12)
    return a == b


def _fmt(v) -> str:
    """A setting's value as a label writes it: ``0.0004``, ``(0.0004, 1)`` (a tuple or its JSON list alike)."""
    if isinstance(v, (list, tuple)):
        return "(" + ", ".join(_fmt(x) for x in v) + ")"
    return f"{v:g}" if isinstance(v, float) else str(v)
