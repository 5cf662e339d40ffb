"""A 3D scan-mesh engine scored as an outcome model (``housner diagnose --engine-model``), on a box's mesh."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from housner import GroundMotion
from housner.cli import main
from housner.engines import get_engine
from housner.reports.diagnosis.outcome_text import engine_model_text
from housner.scan import specimen_from_mesh
from housner.scenarios.campaigns.campaign import load_campaign
from housner.scenarios.diagnosis.outcomes.engine_ensemble import engine_ensemble
from housner.scenarios.diagnosis.outcomes.outcome_diagnosis import diagnose_outcomes
from housner.scenarios.diagnosis.outcomes.outcome_results import OutcomeDiagnosisResult
from housner.scenarios.execution.options import RunOptions

trimesh = pytest.importorskip("trimesh")
pytestmark = pytest.mark.skipif(importlib.util.find_spec("mujoco") is None, reason="mujoco is not installed")

DT = 0.005
N = 24


def _pulses() -> list[np.ndarray]:
    """One-sine pulses, 1.5-3 Hz, 0.15-0.9 g, then 1.5 s of rest: about half of them topple the box."""
    rng = np.random.default_rng(5)
    out = []
    for _ in range(N):
        f, amp = rng.uniform(1.5, 3.0), rng.uniform(0.15, 0.9) * 9.80665
        t = np.arange(0.0, 1.0 / f, DT)
        out.append(np.concatenate((amp * np.sin(2 * np.pi * f * t), np.zeros(int(1.5 / DT)))))
    return out


@pytest.fixture(scope="module")
def box_campaign(tmp_path_factory):
    """A 0.2 x 0.4 x 1.0 m box's mesh and N pulses, each outcome MuJoCo 3D's own at azimuth 0 (the truth)."""
    root = tmp_path_factory.mktemp("box_campaign")
    (root / "records").mkdir()
    mesh = trimesh.creation.box(extents=(0.2, 0.4, 1.0))
    mesh.apply_translation((0.0, 0.0, 0.5))
    mesh.export(root / "box.obj")
    spec = specimen_from_mesh(root / "box.obj").specimen()
    eng = get_engine("mujoco-3d", mesh=str(root / "box.obj"))
    accs = _pulses()
    y = [eng.simulate(spec, GroundMotion(acc=a, dt=DT, name=f"t{i}")).overturned for i, a in enumerate(accs)]
    recs = []
    for i, (a, o) in enumerate(zip(accs, y, strict=True)):
        rows = "\n".join(f"{k * DT:.3f},{v:.8g}" for k, v in enumerate(a))
        (root / "records" / f"t{i}.csv").write_text("time,ground_acc\n" + rows + "\n")
        recs.append(
            f'[[record]]\nid = "t{i}"\nkind = "ground_motion"\nfile = "records/t{i}.csv"\n'
            f'overturned = {"true" if o else "false"}\ngroup = "g{i // 2}"\n'
        )
    (root / "campaign.toml").write_text(
        'name = "box"\n[specimen]\nmesh = "box.obj"\nazimuth = 0.0\ncontact = "hull"\ndensity = 2700.0\n'
        + "".join(recs)
    )
    return root, np.array(y)


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    """One result cache for the module: the four-azimuth ensemble reads back the azimuth-0 runs."""
    return tmp_path_factory.mktemp("cache")


def _diagnose(root, cache, **ensemble):
    c = load_campaign(root)
    ens = engine_ensemble(c, "mujoco-3d", **ensemble)
    opts = RunOptions(jobs=1, cache_dir=cache, progress=False)
    return diagnose_outcomes(c, folds=3, repeats=2, effects=[], engine_model=ens, run_options=opts)


def test_the_engines_own_outcomes_are_predicted_by_its_ensemble(box_campaign, tmp_path_factory):
    root, y = box_campaign
    assert 6 <= y.sum() <= N - 6  # both outcomes, so that the folds and the scores mean something
    d = _diagnose(root, tmp_path_factory.mktemp("cache"), azimuths=1)
    e = d.engine_model
    # the ensemble of one member at the campaign's azimuth is the run that made the outcomes: the scoring reads
    # the same records in the same order and fits only a lapse, so every held-out prediction is right
    assert e.member_overturns == (int(y.sum()),) and e.flip_share == 0.0 and e.failed_runs == 0
    assert e.over_seeds["accuracy"].low == 1.0
    assert e.scores.log_loss < 0.01  # the smallest lapse, 5e-4, costs 2.5e-4 nats a record
    assert e.against_final.n_groups == N // 2  # paired on the same records, clustered by their groups
    text = engine_model_text(e)
    assert "3D engine mujoco-3d: 1 runs per record" in text and "accuracy 1.000" in text
    back = OutcomeDiagnosisResult.from_json(d.result().to_json())
    assert back == d.result() and back.engine_model == e


def test_an_ensemble_over_azimuths_spreads_where_the_box_is_wider(box_campaign, cache):
    root, _y = box_campaign
    d = _diagnose(root, cache, azimuths=4)
    e = d.engine_model
    assert e.ensemble.azimuths == (0.0, 90.0, 180.0, 270.0)
    assert e.ensemble.member_azimuths == tuple(m["azimuth"] for m in e.ensemble.members())
    # the box is symmetric: 180 deg is the same rock (to the engine's round-off), 90 and 270 deg rock about the
    # 0.4 m side (alpha 0.38 against 0.20 rad), so they topple under fewer pulses
    at = dict(zip(e.ensemble.azimuths, e.member_overturns, strict=True))
    assert abs(at[0.0] - at[180.0]) <= 1 and at[90.0] < at[0.0] and at[270.0] < at[0.0]
    assert 0.0 < e.flip_share < 1.0
    # the outcomes are the box's at azimuth 0: the orientation fit finds it (or 180 deg, the same box), and
    # predicts better than the ensemble that weighs the wide orientations alike
    assert set(e.azimuths) <= {0.0, 180.0}
    assert e.over_seeds["log_loss"].mean < e.uniform_over_seeds["log_loss"].mean
    assert e.uniform_against_final.n_groups == N // 2
    from housner.reports.diagnosis.outcomes import render_outcome_report

    page = render_outcome_report(d)
    section = page[page.index('<section id="engine">') :]
    assert "<img" in section[: section.index("</section>")]  # the azimuth figure drew


def test_engine_model_options_are_checked_before_the_work(box_campaign, tmp_path, capsys):
    root, _y = box_campaign
    assert main(["diagnose", str(root), "--engine-model", "mujoco", "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--engine-model" in err[0] and "3D scan-mesh engine" in err[0]
    assert main(["diagnose", str(root), "--engine-model", "mujoco-3d", "--engine-amplitudes", "0.1", "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--engine-amplitudes" in err[0] and "[0.5, 2]" in err[0]
    plain = tmp_path / "plain"
    (plain / "records").mkdir(parents=True)
    (plain / "records" / "a.csv").write_text("time,ground_acc\n" + "".join(f"{k * DT:.3f},0.5\n" for k in range(40)))
    (plain / "campaign.toml").write_text(
        'name = "plain"\n[specimen]\nheight = 0.6\nwidth = 0.06\ndepth = 0.3\nmass = 50.0\n'
        '[[record]]\nid = "a"\nkind = "ground_motion"\nfile = "records/a.csv"\noverturned = true\n'
    )
    assert main(["diagnose", str(plain), "--engine-model", "mujoco-3d", "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--engine-model" in err[0] and "mesh" in err[0]
