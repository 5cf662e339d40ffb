"""Results as values (issue 49): every results file of a run or a study is written from a typed value, and that
value read back from what it wrote is the value itself.

Each value is built by the real code on a small input (a scenario of a few motions, a small study, a campaign
of a few records), written as its file writes it (non-finite numbers as that file writes them) and read back:
``T.from_json(x.to_json()) == x``, through the JSON text. A run directory also reads back byte for byte: its
run.json written again from the value read is the file.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import trimesh

from housner import Specimen
from housner._values import JsonValue, same
from housner.cli.specimen import SideFacts
from housner.cli.specimen import SpecimenFacts as ScanSpecimenFacts
from housner.engines.analytic import HousnerEngine
from housner.engines.base import ENGINES, get_engine, register_engine
from housner.engines.tuning import TuningResult, tune
from housner.reports.explain_text import explain_document
from housner.scan import specimen_from_mesh
from housner.scenarios.execution.options import RunOptions
from housner.scenarios.execution.run_meta import (
    EngineFacts,
    Provenance,
    RunAnalysis,
    RunMeta,
    ScenarioCopy,
    SpecimenFacts,
)
from housner.scenarios.execution.rundir import jsonable
from housner.scenarios.motions.build import BandCheck, MatchedGain, MotionFacts, RecordFacts
from housner.scenarios.runs.campaign_run import (
    CampaignFacts,
    OutcomeScore,
    PublishedScore,
    ScanPivots,
    published_rows,
    run_campaign,
)
from housner.scenarios.runs.chaos import ChaosFloor, EngineErrors
from housner.scenarios.runs.explain import Explanation, explain_engine
from housner.scenarios.runs.explain_floor import FloorParts
from housner.scenarios.runs.explain_maps import MapsExplained
from housner.scenarios.runs.frontier import Frontier, FrontierPoint, engine_frontier
from housner.scenarios.runs.impact_map import EngineMaps, measure_maps
from housner.scenarios.runs.run import run_scenario
from housner.scenarios.runs.spread import EquivalentAmplitudes, RecordGap, Table2Spread
from housner.scenarios.runs.view import Run
from housner.scenarios.studies.study import StudyMeta, StudySettings, run_study
from housner.scenarios.studies.study_fits import StudyFits

MINI = """name = "mini"
description = "four matched El Centro motions, Table 2 and its spread"
[specimen]
preset = "bachmann2017"
[motions]
source = "rdk"
record = "elcentro"
model = "matched"
n = 4
seed = 2017
prototype_height = 5.0
[engines]
names = ["housner", "mujoco"]
[analysis]
reference = "housner"
paper_percentiles = { 25 = 0.37, 50 = 0.77, 75 = "overturn" }
paper_note = "the paper's own motions are not available"
seed_spread = 2
EFFECTS"""

STUDY = """name = "tiny-study"
[specimen]
preset = "bachmann2017"
[motions]
source = "rdk"
record = "elcentro"
model = "rdk2010"
n = 4
seed = 5
prototype_height = 5.0
[engines]
names = ["housner", "pybullet"]
[study]
levels = [0.8, 1.6, 3.2]
prototype_heights = [2.5, 10.0]
thresholds = [0.5, 1.0]
bootstrap = 100
"""


def round_trip(value: JsonValue, nonfinite: str = "string") -> JsonValue:
    """``value`` written as its file writes it and read back; asserts the value read is ``value``."""
    cls = type(value)
    assert cls.from_json(value.to_json()) == value  # the JSON data itself
    text = json.dumps(jsonable(value.to_json(), nonfinite=nonfinite))
    back = cls.from_json(json.loads(text))
    assert back == value, cls.__name__
    assert json.dumps(jsonable(back.to_json(), nonfinite=nonfinite)) == text  # and writes the same file again
    return back


@pytest.fixture(scope="module")
def options(tmp_path_factory):
    return RunOptions(jobs=1, progress=False, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.fixture(scope="module")
def mini(tmp_path_factory, options):
    """A run of the analytic model and MuJoCo on four motions: Table 2, its spread, the engines' errors."""
    root = tmp_path_factory.mktemp("values")
    scenario = root / "mini.toml"
    scenario.write_text(MINI.replace("EFFECTS", ""))
    done = run_scenario(scenario, out=root / "run", options=options)
    return done, Run.load(root / "run")


def test_run_json_is_its_value_written(mini):
    done, view = mini
    meta = done.meta
    # every table of run.json is a value of its own, typed
    assert isinstance(meta.scenario, ScenarioCopy) and meta.scenario.name == "mini"
    assert isinstance(meta.specimen, SpecimenFacts) and meta.specimen.alpha_rad > 0
    assert isinstance(meta.motions, MotionFacts) and meta.motions.source == "rdk" and meta.motions.S == 10.0
    assert isinstance(meta.motions.record, RecordFacts) and meta.motions.record.name == "elcentro-peer1999"
    assert isinstance(meta.motions.band_check, BandCheck) and meta.motions.band_check.psa.bands
    assert isinstance(meta.motions.matched_gain, MatchedGain) and meta.motions.matched_gain.gain
    assert all(isinstance(v, EngineFacts) for v in meta.engines.values()) and meta.engines["mujoco"].version
    assert isinstance(meta.analysis, RunAnalysis) and meta.analysis.paper_targets == {25: 0.37, 50: 0.77, 75: math.inf}
    assert isinstance(meta.engine_errors["mujoco"], EngineErrors) and len(meta.engine_errors["mujoco"].amplitudes) == 5
    assert isinstance(meta.table2_spread, Table2Spread) and meta.table2_spread.k == 2
    assert set(meta.table2_spread.summary) == {25, 50, 75}
    assert isinstance(meta.provenance, Provenance) and meta.provenance.versions["housner"]
    # the value, the file and the value read back from the file
    round_trip(meta)
    # what Run.load reads is what the run wrote, with the completion marker and content key of the write
    assert view.meta.complete is True and set(view.meta.content) == {
        "results.parquet",
        "histories.parquet",
        "motions.npz",
    }
    assert replace(view.meta, complete=None, content=None) == meta
    text = (done.out / "run.json").read_text()
    again = json.dumps(jsonable(RunMeta.from_json(json.loads(text)).to_json()), indent=2)
    assert again == text  # byte for byte: the file read and written again is the file


def test_each_table_of_run_json_reads_back_as_itself(mini):
    done, _ = mini
    meta = done.meta
    for value in (
        meta.scenario,
        meta.specimen,
        meta.motions,
        meta.motions.record,
        meta.motions.band_check,
        meta.motions.matched_gain,
        meta.analysis,
        meta.table2_spread,
        meta.provenance,
        *meta.engines.values(),
        *meta.engine_errors.values(),
    ):
        round_trip(value)


def test_an_engine_whose_errors_could_not_be_measured_reads_back_with_its_reason():
    failed = EngineErrors(engine="flaky", error="EngineError: solver diverged")
    assert failed.to_json() == {"error": "EngineError: solver diverged"}
    assert EngineErrors.from_json(failed.to_json()).error == failed.error


def test_the_record_gap_and_the_equivalent_amplitudes_are_values(mini):
    _, view = mini
    gap = view.record_gap
    assert isinstance(gap, RecordGap) and gap.n_ensemble == 4 and len(gap.band_periods_s) == 16
    round_trip(gap)
    factors = view.paper_factors
    assert isinstance(factors, EquivalentAmplitudes) and set(factors.factors) == {25.0, 50.0, 75.0}
    round_trip(factors)


@register_engine("values-flaky")
class FlakyEngine(HousnerEngine):
    """The analytic engine, except that it fails on the second motion of an ensemble (its name ends in 001)."""

    def _simulate(self, specimen, motion, effects):
        if motion.name.endswith("001"):
            raise RuntimeError("solver diverged on purpose")
        return super()._simulate(specimen, motion, effects)


@pytest.fixture
def flaky():
    ENGINES.setdefault("values-flaky", FlakyEngine)  # another test file's fixture may have reset the registry
    yield


def test_a_run_with_effects_and_a_failed_record(tmp_path, options, flaky):
    """The [[effects]] series' facts and a failed record read back as written."""
    scenario = tmp_path / "eff.toml"
    scenario.write_text(
        MINI.replace("EFFECTS", '[[effects]]\nname = "restitution"\nr = 0.93\n')
        .replace("seed_spread = 2", "seed_spread = 0")
        .replace('names = ["housner", "mujoco"]', 'names = ["housner", "values-flaky"]')
    )
    done = run_scenario(scenario, out=tmp_path / "run", options=replace(options, use_cache=False))
    meta = done.meta
    assert meta.effects is not None and meta.effects.effects[0].to_json() == {"name": "restitution", "r": 0.93}
    assert meta.effect_series == {
        "housner + restitution(r=0.93)": "housner",
        "values-flaky + restitution(r=0.93)": "values-flaky",
    }
    assert [(f.engine, f.motion_id) for f in meta.failures] == [
        ("values-flaky", 1),
        ("values-flaky + restitution(r=0.93)", 1),
    ]
    assert "solver diverged on purpose" in meta.failures[0].error
    round_trip(meta)
    for value in (meta.effects, *meta.effects.effects, *meta.failures):
        round_trip(value)


def test_study_json_and_fragility_json_are_their_values_written(tmp_path, options):
    scenario = tmp_path / "study.toml"
    scenario.write_text(STUDY)
    res = run_study(scenario, out=tmp_path / "study", options=options)
    assert isinstance(res.meta, StudyMeta) and isinstance(res.meta.study, StudySettings)
    assert res.meta.study.prototype_heights == (2.5, 10.0) and res.meta.study.reference == "housner"
    round_trip(res.meta, "null")
    fits = StudyFits(tuple(res.fits), tuple(res.comparisons))
    assert len(fits.fits) == 4 and len(fits.comparisons) == 2
    assert all(isinstance(f.median, float) and isinstance(f.ok, bool) for f in fits.fits)
    round_trip(fits, "null")
    # the files themselves: read back, written again, the same bytes
    for name, cls in (("study.json", StudyMeta), ("fragility.json", StudyFits)):
        text = (tmp_path / "study" / name).read_text()
        again = json.dumps(jsonable(cls.from_json(json.loads(text)).to_json(), nonfinite="null"), indent=1)
        assert again == text, name


def test_a_campaign_run_keeps_its_campaign_and_outcome_scores(tmp_path, options):
    dt = 0.01
    rng = np.random.default_rng(5)
    root = tmp_path / "camp"
    (root / "records").mkdir(parents=True)
    records = ""
    for i in range(6):
        f, amp = rng.uniform(2.0, 6.0), rng.uniform(0.05, 0.35) * 9.80665
        t = np.arange(0.0, 1.0 / f, dt)
        a = np.concatenate((amp * np.sin(2 * np.pi * f * t), np.zeros(int(3.0 / dt))))
        rows = "\n".join(f"{k * dt:.3f},{x:.6g}" for k, x in enumerate(a))
        (root / "records" / f"r{i}.csv").write_text(f"time,ground_acc\n{rows}\n")
        records += (
            f'[[record]]\nid = "r{i}"\nkind = "ground_motion"\nfile = "records/r{i}.csv"\n'
            f"overturned = {'true' if i % 2 else 'false'}\n"
        )
    # a scan specimen: a prism whose centre of mass lies toward -x, so the planar engines get its two pivots
    base = [(x, y, 0.0) for x in (-0.1, 0.1) for y in (-0.1, 0.1)]
    pts = base + [(x, y, 0.5) for x in (-0.1, 0.0) for y in (-0.1, 0.1)]
    trimesh.convex.convex_hull(np.array(pts)).export(root / "rock.obj")
    (root / "campaign.toml").write_text(f'name = "small"\n[specimen]\nmesh = "rock.obj"\ndensity = 2600.0\n{records}')
    done = run_campaign(root, engines=["housner"], out=tmp_path / "run", options=options)
    facts = done.meta.campaign
    assert isinstance(facts, CampaignFacts) and facts.n_outcomes == 6
    assert isinstance(facts.scan, ScanPivots) and facts.scan.b_pos_m > facts.scan.b_neg_m
    assert [e.name for e in facts.geometry.effects] == ["asymmetric_pivots"] and facts.mesh["density"] == 2600.0
    round_trip(done.meta)
    round_trip(facts)
    round_trip(facts.scan)
    (score,) = Run.load(tmp_path / "run").outcome_scores
    assert isinstance(score, OutcomeScore) and score.n == 6 and len(score.accuracy_ci) == 2
    round_trip(score)
    # a published score of another model, for the campaign it was published on
    (published,) = published_rows("ASU granite shake-table tests 2024, specimen SP1")
    assert isinstance(published, PublishedScore) and published.n_predicted == 149
    round_trip(published)


def test_equality_is_the_results_not_the_objects():
    """NaN equals NaN (a missing number), a tuple its JSON list; a different number differs."""
    a = EngineErrors("x", (0.5,), (math.nan,), (1e-3,), 0.001)
    assert a == EngineErrors("x", [0.5], [float("nan")], [1e-3], 0.001)
    assert a != EngineErrors("x", (0.5,), (1e-3,), (1e-3,), 0.001)
    assert same({"a": [1.0, math.nan]}, {"a": (1.0, math.nan)}) and not same({"a": 1}, {"b": 1})


def test_run_json_of_an_earlier_version_still_loads(tmp_path):
    """A run.json without the keys of later versions: the missing tables empty, the unknown keys kept."""
    old = {
        "scenario": {"name": "old", "description": "before typed values"},
        "specimen": {"name": "block", "height_m": 0.5, "alpha_rad": 0.15},
        "motions": {"source": "record", "S": 1.0, "custom": 3},
        "engines": {"housner": {"settings": {"r": None}, "version": "0.0.9", "wall_s": "nan", "cached": 0}},
        "analysis": {"reference": "housner"},
        "failures": [],
        "wall_s": {"total": 1.0},
        "provenance": {"versions": {"housner": "0.0.9"}},
        "something_new": {"kept": True},
    }
    meta = RunMeta.from_json(old)
    assert meta.scenario.name == "old" and meta.specimen.alpha_rad == 0.15 and meta.motions.extra == {"custom": 3}
    assert math.isnan(meta.engines["housner"].wall_s) and meta.engine_errors == {} and meta.table2_spread is None
    assert meta.extra == {"something_new": {"kept": True}}
    assert jsonable(meta.to_json()) == {**old, "engine_errors": {}}  # the same keys and values, and the new table


# ----------------------------------------------------------------------------
# the engines' stored measurements: tune, frontier, explain, impact maps; the specimen of a scan
MODELS = Path(__file__).resolve().parents[1] / "engines" / "models"


def test_the_tune_json_is_its_value_written():
    tuned = tune("pybullet", Specimen.bachmann2017(), candidates=[get_engine("pybullet").settings()], progress=False)
    assert isinstance(tuned, TuningResult) and len(tuned.candidates) == 1 and len(tuned.table)
    text = json.dumps(tuned.to_json(), indent=2, default=str)  # as `housner tune --json` writes it
    back = TuningResult.from_json(json.loads(text))
    assert back == tuned and json.dumps(back.to_json(), indent=2, default=str) == text
    # the shipped tuning files read back with the same keys and values (a derived key an old file lacks is added)
    for f in sorted(MODELS.glob("tuning-*.json")):
        raw = json.loads(f.read_text())
        again = json.loads(json.dumps(TuningResult.from_json(raw).to_json(), default=str))
        assert {k: again[k] for k in raw} == raw and set(again) - set(raw) <= {"reached_r"}, f.name


def test_the_frontier_json_is_its_value_written(options):
    fr = engine_frontier("pybullet", "elcentro", n_motions=3, axes={"timestep": (1 / 1000, 1 / 500)}, options=options)
    assert isinstance(fr, Frontier) and all(isinstance(p, FrontierPoint) for p in fr.points)
    assert all(isinstance(p.floor_parts, FloorParts) for p in fr.points if not p.error)
    back = round_trip(fr, "null")
    assert back.to_dict() == fr.to_dict() == json.loads(json.dumps(fr.to_dict()))
    for f in sorted(MODELS.glob("frontier-*.json")):
        raw = json.loads(f.read_text())
        assert Frontier.from_dict(raw).to_dict() == raw, f.name


def test_the_explain_json_is_its_value_written(options, tmp_path):
    expl = explain_engine("housner", "elcentro", n_motions=4, effects=["restitution"], options=options)
    assert isinstance(expl, Explanation) and isinstance(expl.maps, MapsExplained) and expl.details is not None
    assert isinstance(expl.details.chaos_floor, ChaosFloor) and isinstance(expl.maps.maps, EngineMaps)
    back = round_trip(expl, "null")
    assert back.to_dict() == expl.to_dict()
    round_trip(expl.maps.departures, "null")
    round_trip(expl.details.model_form_floor, "null")
    # the shipped explanations read back and write the very same file, words included: the words are rendered
    # from the value (reports/explain_text.py), so a file is its value written
    for f in sorted(MODELS.glob("explain-*.json")):
        text = f.read_text()
        assert json.dumps(explain_document(Explanation.from_json(json.loads(text))), indent=2) == text, f.name


def test_the_impact_maps_json_is_its_value_written():
    maps = measure_maps("housner", Specimen.bachmann2017())
    assert EngineMaps.from_json(maps.to_json()) == maps
    # NaN bins (no impact fell there) equal themselves; a changed bin does not
    ratios = list(maps.impacts["ratio_median"])
    ratios[0] = ratios[0] + 1e-3
    other = replace(maps, impacts={**maps.impacts, "ratio_median": ratios})
    assert other != maps and EngineMaps.from_json(other.to_json()) == other


def test_the_specimen_json_is_its_value_written(tmp_path):
    base = [(x, y, 0.0) for x in (-0.1, 0.1) for y in (-0.1, 0.1)]
    pts = base + [(x, y, 0.5) for x in (-0.1, 0.0) for y in (-0.1, 0.1)]
    trimesh.convex.convex_hull(np.array(pts)).export(tmp_path / "rock.obj")
    scan = specimen_from_mesh(tmp_path / "rock.obj", azimuth=30.0)
    facts = ScanSpecimenFacts.from_json(scan.to_dict())
    assert isinstance(facts.pos, SideFacts) and facts.pos.b_m > facts.neg.b_m and facts.pos.b_m == scan.pos.b
    assert facts.to_json() == scan.to_dict()  # the typed value writes the specimen's data, key for key
    text = json.dumps(facts.to_json(), indent=1)  # as `housner specimen --json` writes it
    assert ScanSpecimenFacts.from_json(json.loads(text)) == facts
