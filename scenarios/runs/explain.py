"""Explain an engine: its own responses go through the comparison and the diagnosis that measurements get.

An engine departs from the analytic model record by record (on the ``elcentro`` scenario its per-record
agreement is far below the chaos floor); how much of that is a numerical convention and how much contact
physics the analytic model lacks is the question :func:`explain_engine` answers: the engine's free
vibrations and ground-motion responses written as a campaign (:mod:`housner.scenarios.runs.engine_campaign`,
with :data:`EXPLAIN_SIGMA` of white noise), diagnosed like a measured one, the analytic model with the
effects found run on the same motions (agreement within :data:`RECORD_RTOL`), judged against the extended
floor of :mod:`housner.scenarios.runs.explain_floor` (within :data:`REACH_MARGIN`), then the engine's own
maps (:mod:`housner.scenarios.runs.impact_map`). Every engine run goes through the runner, so its records
are cached like a scenario's. The steps are in ``docs/how-to/explain-engine.md``.
"""

from __future__ import annotations

import math
import tempfile
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from housner._values import JsonValue
from housner.effects import available_effects, make_effect
from housner.errors import unknown_choice
from housner.scenarios.campaigns.campaign import load_campaign
from housner.scenarios.catalogue.scenario import Scenario
from housner.scenarios.diagnosis.comparison.pointers import Evidence, PointerClass
from housner.scenarios.diagnosis.diagnose import diagnose
from housner.scenarios.execution.options import RunOptions
from housner.scenarios.execution.outputs import check_output_dir
from housner.scenarios.execution.rundir import jsonable
from housner.scenarios.execution.runner import run_engines
from housner.scenarios.runs.chaos import ChaosFloor
from housner.scenarios.runs.departure import record_agreement, record_ks, record_thetas
from housner.scenarios.runs.engine_campaign import (
    AMPLITUDES,
    check_engine,
    check_sigma,
    ground_motion_scenario,
    run_engine_records,
    write_engine_campaign,
)
from housner.scenarios.runs.explain_floor import (
    FloorParts,
    ModelFormFloor,
    engine_chaos_floor,
    extended_floor,
    model_form_floor,
)
from housner.scenarios.runs.explain_maps import MapsExplained, compare_with_maps

__all__ = [
    "EXPLAIN_SIGMA",
    "REACH_MARGIN",
    "DiagnosisSummary",
    "EffectFound",
    "ExplainDetails",
    "Explanation",
    "KsDistances",
    "explain_engine",
]

#: Noise added to the engine's theta before the diagnosis [rad]. The diagnosis takes a record as signal plus
#: white noise of the level it estimates from the record (third differences,
#: :func:`housner.free_vibration.calibration.estimate_noise`); on an engine's noise-free samples that estimate reads the
#: signal's own third differences and the float32 rounding (1e-8 to 1e-7 rad), not a white noise, and the
#: floor and the localisation built on it fail (the analytic engine explained by itself came out
#: "unexplained", z = +24 on the scatter of its energy ratio).
#: 1e-5 rad (7e-5 alpha on the seed specimen) is a hundred times that estimate, and 80 times below the seed's
#: 0.8 mrad sensor: it hides no difference an engine shows (MuJoCo's plain held-out error: 4e-3 alpha).
EXPLAIN_SIGMA = 1e-5
#: The agreement reaches the floor when it is at least the floor minus this [-] (issue 25's criterion).
REACH_MARGIN = 0.05


# ----------------------------------------------------------------------------
# the explanation
@dataclass(frozen=True, eq=False)
class EffectFound(JsonValue):
    """An effect of the diagnosis' final model: its registry ``name`` and fitted ``params`` (name -> value)."""

    name: str = ""
    params: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True, eq=False)
class HeldoutError(JsonValue):
    """The diagnosis' held-out error [alpha] of the plain model (``before``) and of its final model (``after``)."""

    before: float = math.nan
    after: float = math.nan


@dataclass(frozen=True, eq=False)
class DiagnosisSummary(JsonValue):
    """The diagnosis of the engine's campaign: its ``status``, the held-out error, the residual ratio [-] (the
    held-out error over the correct-model floor), the physical classes its verdict points to (``next``,
    strongest first) and the localisation quantities where its final model still differs (``where``). Its words
    are :mod:`housner.reports.explain_text`'s."""

    status: str = ""
    heldout_error: HeldoutError = field(default_factory=HeldoutError)
    residual_ratio: float = math.nan
    next: tuple[PointerClass, ...] = ()
    where: tuple[Evidence, ...] = ()


@dataclass(frozen=True, eq=False)
class KsDistances(JsonValue):
    """The two-sample KS distance [-] of the engine's theta_max/alpha from the analytic model's: plain, with the
    effects found, and with the engine's measured maps (None where the maps were not measured)."""

    plain: float = math.nan
    with_effects: float = math.nan
    with_maps: float | None = None

    _NULL_IS_NAN = ("with_maps",)


@dataclass(frozen=True, eq=False)
class OverturnCounts(JsonValue):
    """Ground motions overturned by the engine, the analytic model and the analytic model with the effects found,
    of ``records``."""

    engine: int = 0
    housner: int = 0
    housner_with_effects: int = 0
    records: int = 0


@dataclass(frozen=True, eq=False)
class CampaignRecordCounts(JsonValue):
    """The engine's campaign: its free-vibration and ground-motion records, and those skipped (id, file, why)."""

    free_vibration: int = 0
    ground_motion: int = 0
    skipped: tuple[tuple[str | None, ...], ...] = ()


@dataclass(frozen=True, eq=False)
class ExplainDetails(JsonValue):
    """The explanation's figures in full.

    Attributes
    ----------
    chaos_floor : ChaosFloor
    model_form_floor : ModelFormFloor
        The two floors, per perturbation.
    overturned : OverturnCounts
    settings : dict
        Engine -> the settings it ran with.
    campaign : str or None
        The campaign's folder when it was kept (``workdir``), else None.
    campaign_records : CampaignRecordCounts
    diagnosis_seconds : float
        Time the diagnosis took [s].
    """

    chaos_floor: ChaosFloor | None = None
    model_form_floor: ModelFormFloor | None = None
    overturned: OverturnCounts = field(default_factory=OverturnCounts)
    settings: dict[str, dict] = field(default_factory=dict)
    campaign: str | None = None
    campaign_records: CampaignRecordCounts = field(default_factory=CampaignRecordCounts)
    diagnosis_seconds: float = math.nan

    _ALWAYS = ("campaign",)


@dataclass(frozen=True, eq=False)
class Explanation(JsonValue):
    """What :func:`explain_engine` found (``housner explain ENGINE --json``: :meth:`to_dict`).

    Attributes
    ----------
    engine, scenario : str
    effects : tuple of EffectFound
        ``name`` and ``params`` of each effect of the diagnosis' final model, in the order added.
    agreement : float
        Per-record agreement of the analytic model with ``effects`` with the engine [-].
    agreement_plain : float
        The same for the plain analytic model [-].
    floor : float
        The extended floor: the lower of ``floor_parts`` [-].
    floor_parts : FloorParts
        ``chaos`` and ``model_form``: the mean shares of the two floors [-].
    reaches_floor : bool or None
        ``agreement >= floor - REACH_MARGIN`` (None: a file that does not say).
    diagnosis : DiagnosisSummary
        ``status``, ``heldout_error`` (``before``, ``after`` [alpha]), ``residual_ratio`` [-], ``next`` and
        ``where``.
    n_records : int or None
        Ground motions on which both the engine and the analytic model ran.
    ks : KsDistances or None
        ``plain``, ``with_effects`` and ``with_maps``: the two-sample KS distance [-] of the engine's
        theta_max/alpha distribution from the analytic model's, plain, with ``effects`` and with the engine's
        measured maps (overturns as +inf).
    maps : MapsExplained or None
        Housner + the engine's measured impact and flight maps (:mod:`housner.scenarios.runs.explain_maps`):
        ``agreement`` [-], ``reaches_floor``, ``n_records``, ``overturned``, ``departures`` and
        ``departures_plain`` (where the records that disagree part: phase of the motion, impacts before,
        the records) and ``maps`` (the maps, :class:`EngineMaps`). None when
        the step did not run (written as an empty table). Also ``scatter_floor`` (the agreement the maps' mean
        law keeps with an engine whose impacts scatter as measured,
        :func:`~housner.scenarios.runs.explain_maps.scatter_floor`) and ``reaches_scatter_floor``.
    details : ExplainDetails or None
        The two floors in full (per perturbation), overturn counts, settings and the campaign's path.
    wall_s : dict
        Wall time of the steps [s].
    """

    engine: str
    scenario: str
    effects: tuple[EffectFound, ...]
    agreement: float
    agreement_plain: float
    floor: float
    floor_parts: FloorParts
    reaches_floor: bool | None
    diagnosis: DiagnosisSummary
    n_records: int | None
    ks: KsDistances | None = None
    maps: MapsExplained | None = None
    details: ExplainDetails | None = None
    wall_s: dict = field(default_factory=dict)

    #: Every key is written; a table not measured as an empty one.
    _ALWAYS = ("reaches_floor", "n_records")
    _EMPTY_WHEN_NONE = ("ks", "maps", "details")

    def to_dict(self) -> dict:
        """Plain data for JSON (NaN as None): the explain JSON."""
        return jsonable(self.to_json(), nonfinite="null")


def explain_engine(
    engine: str,
    scenario: Scenario | str | Path = "elcentro",
    *,
    n_motions: int | None = None,
    sigma: float = EXPLAIN_SIGMA,
    seed: int = 0,
    effects: Iterable[str] | None = None,
    options: RunOptions | None = None,
    workdir: str | Path | None = None,
    progress: Callable[[str], None] | None = None,
    maps: bool = True,
) -> Explanation:
    """Explain how an engine departs from the analytic model (``docs/how-to/explain-engine.md``).

    Parameters
    ----------
    engine : str
        Registry name of the engine.
    scenario : Scenario or str or Path
        A scenario of ground motions (default ``elcentro``).
    n_motions : int, optional
        Ground motions of an RDK ensemble (default: the scenario's).
    sigma : float
        Noise added to the engine's theta in the campaign [rad] (default :data:`EXPLAIN_SIGMA`, the least
        the diagnosis' noise model needs; 0 leaves the samples as the engine wrote them).
    seed : int
        Seed of the noise and of the diagnosis' folds.
    effects : iterable of str, optional
        Candidate effects of the diagnosis (default: the library's).
    options : RunOptions, optional
        How the engines' records execute (workers, cache, progress bar).
    workdir : path, optional
        Folder where the campaign is written (in ``ENGINE-SCENARIO/``) and kept; default a temporary
        folder, removed after.
    progress : callable, optional
        Called with a line of text as the work goes (the diagnosis' lines among them).
    maps : bool
        Also measure the engine's impact and flight maps and compare Housner + those maps with the engine
        (:mod:`housner.scenarios.runs.explain_maps`; about a minute of CPU per engine).

    Returns
    -------
    Explanation
    """
    t0 = time.perf_counter()
    say = progress or (lambda s: None)
    check_engine(engine)  # the arguments before the work
    sc = ground_motion_scenario(scenario, n_motions)
    sig = check_sigma(sigma)
    if effects is not None:
        effects = list(effects)
        known = available_effects()
        for nm in effects:
            if nm not in known:
                raise unknown_choice("effect", nm, known)
    if workdir is None:
        with tempfile.TemporaryDirectory(prefix="housner-explain-") as tmp:
            return _explain(engine, sc, n_motions, sig, int(seed), effects, options, Path(tmp), say, t0, False, maps)
    return _explain(engine, sc, n_motions, sig, int(seed), effects, options, Path(workdir), say, t0, True, maps)


def _explain(
    engine, sc, n_motions, sigma, seed, effects, options, workdir, say, t0, keep: bool, with_maps: bool
) -> Explanation:
    out = check_output_dir(workdir / f"{engine}-{sc.name}", "`workdir`", files=("campaign.toml",))
    say(f"running {engine} and the analytic model on {sc.name}")
    runs = run_engine_records(engine, sc, n_motions, AMPLITUDES, options)
    camp = load_campaign(write_engine_campaign(runs, out, sigma, seed))
    say(f"diagnosing {camp!r}")
    t1 = time.perf_counter()
    d = diagnose(
        camp, effects=effects, seed=seed, engine_settings=runs.settings["housner"], compare_steps=False, progress=say
    )
    t2 = time.perf_counter()
    final = [(n, dict(p)) for n, p in d.final.effects]
    n_fv = len(runs.releases)
    eng_theta = record_thetas(runs.results, engine, n_fv)
    plain_theta = record_thetas(runs.results, "housner", n_fv)
    plain, n = record_agreement(eng_theta, plain_theta)
    with_eff, eff_theta = plain, plain_theta
    if final:
        say(f"running the analytic model with {', '.join(n for n, _ in final)}")
        effs = tuple(make_effect(nm, **p) for nm, p in final)
        res_e, _h, _i = run_engines(
            sc.specimen, runs.motions, {"housner": runs.settings["housner"]}, options, effects=effs, histories=False
        )
        eff_theta = record_thetas(res_e, "housner")
        with_eff, n = record_agreement(eng_theta, eff_theta)
    t3 = time.perf_counter()
    say("measuring the floors (chaos: the engine's r and p errors; model form: correct integrators)")
    ms = [runs.motions[i] for i in sorted(eng_theta.index)]
    r = runs.settings["housner"].get("r")
    chaos = engine_chaos_floor(engine, runs.settings[engine], sc.specimen, ms, r)
    mform = model_form_floor(sc.specimen, ms, runs.settings["housner"])
    floor = extended_floor(chaos, mform)
    reaches = bool(with_eff >= floor - REACH_MARGIN)
    t4 = time.perf_counter()
    mp, maps_theta = compare_with_maps(engine, runs, eng_theta, options, say) if with_maps else (None, None)
    v = d.verdict
    return Explanation(
        engine=engine,
        scenario=sc.name,
        effects=tuple(EffectFound(nm, {k: float(x) for k, x in p.items()}) for nm, p in final),
        agreement=float(with_eff),
        agreement_plain=float(plain),
        floor=floor,
        floor_parts=FloorParts(chaos=chaos.share, model_form=mform.share),
        reaches_floor=reaches,
        diagnosis=DiagnosisSummary(
            status=v.status,
            heldout_error=HeldoutError(before=d.baseline.heldout_error, after=d.final.heldout_error),
            residual_ratio=v.residual.ratio,
            next=tuple(v.next),
            where=tuple(v.where),
        ),
        n_records=int(n),
        ks=KsDistances(
            plain=record_ks(eng_theta, plain_theta),
            with_effects=record_ks(eng_theta, eff_theta),
            with_maps=record_ks(eng_theta, maps_theta) if mp else None,
        ),
        maps=_maps_part(mp, floor),
        details=ExplainDetails(
            chaos_floor=chaos,
            model_form_floor=mform,
            overturned=OverturnCounts(
                engine=int(np.isinf(eng_theta).sum()),
                housner=int(np.isinf(plain_theta).sum()),
                housner_with_effects=int(np.isinf(eff_theta).sum()),
                records=int(eng_theta.size),
            ),
            settings=runs.settings,
            campaign=str(out) if keep else None,
            campaign_records=CampaignRecordCounts(
                free_vibration=len(camp.free_vibration),
                ground_motion=len(camp.ground_motion),
                skipped=tuple(tuple(s) for s in camp.skipped),
            ),
            diagnosis_seconds=d.elapsed,
        ),
        wall_s={
            "engine_runs": runs.wall_s,
            "diagnosis": t2 - t1,
            "with_effects": t3 - t2,
            "floors": t4 - t3,
            "maps": mp.wall_s if mp else 0.0,
            "total": time.perf_counter() - t0,
        },
    )


def _maps_part(mp: MapsExplained | None, floor: float) -> MapsExplained | None:
    """The Explanation's ``maps``: the comparison with whether it reaches the floor (the extended floor, or the
    scatter floor of the maps' own measured scatter); None when the step did not run."""
    if mp is None:
        return None
    reaches = bool(mp.agreement >= floor - REACH_MARGIN)
    reaches_scatter = bool(mp.agreement >= mp.scatter_floor.share - REACH_MARGIN)
    return replace(mp, reaches_floor=reaches, reaches_scatter_floor=reaches_scatter)
