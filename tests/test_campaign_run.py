"""``housner run CAMPAIGN``: the engines on a measured campaign's records and specimen, scored on its outcomes."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import ClassVar

import numpy as np
import pandas as pd
import pytest
import trimesh

from housner import GroundMotion, Specimen
from housner.cli import main
from housner.effects import AsymmetricPivots
from housner.engines import ENGINES, register_engine
from housner.engines.analytic import HousnerEngine
from housner.scenarios.campaigns import load_campaign
from housner.scenarios.diagnosis.outcomes.outcome_scores import outcome_scores
from housner.scenarios.runs.campaign_run import P_CLIP, campaign_input, run_campaign
from housner.scenarios.runs.view import Run

DT = 0.01  # [s]
N = 10  # records of the small campaigns


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    """The result cache of these runs in the test's folder, not the user's."""
    monkeypatch.setenv("HOUSNER_CACHE_DIR", str(tmp_path / "cache"))


def _pulses(n: int, seed: int, scale: float = 1.0) -> list[np.ndarray]:
    """``n`` one-sine pulses (2-6 Hz, 0.05-0.35 g times ``scale``), then 3 s of rest."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        f, amp = rng.uniform(2.0, 6.0), scale * rng.uniform(0.05, 0.35) * 9.80665
        t = np.arange(0.0, 1.0 / f, DT)
        out.append(np.concatenate((amp * np.sin(2 * np.pi * f * t), np.zeros(int(3.0 / DT)))))
    return out


def _write_campaign(root: Path, specimen: str, accs, observed) -> Path:
    """A campaign of outcome records (``observed`` True/False per record) with the ``[specimen]`` table given."""
    (root / "records").mkdir(parents=True)
    recs = ""
    for i, (a, o) in enumerate(zip(accs, observed, strict=True)):
        rows = "\n".join(f"{k * DT:.3f},{x:.6g}" for k, x in enumerate(a))
        (root / "records" / f"r{i:02d}.csv").write_text(f"time,ground_acc\n{rows}\n")
        recs += (
            f'[[record]]\nid = "r{i:02d}"\nkind = "ground_motion"\nfile = "records/r{i:02d}.csv"\n'
            f"overturned = {'true' if o else 'false'}\n"
        )
    (root / "campaign.toml").write_text(f'name = "small"\n[specimen]\n{specimen}\n{recs}')
    return root


BLOCK = "height = 0.6\nwidth = 0.06\ndepth = 0.3\nmass = 50.0"  # alpha = 0.0997 rad


@pytest.fixture
def block(tmp_path) -> Path:
    """A plain block campaign: 10 pulses; the outcomes alternate (they need not be the model's)."""
    return _write_campaign(tmp_path / "block", BLOCK, _pulses(N, seed=5), [i % 3 == 0 for i in range(N)])


@pytest.fixture
def scan(tmp_path) -> Path:
    """A scan-mesh campaign: a prism whose trapezoid section (0.2 m base, 0.1 m top flush with -x, 0.5 m high)
    puts the centre of mass toward -x, so b+ > b-."""
    base = [(x, y, 0.0) for x in (-0.1, 0.1) for y in (-0.1, 0.1)]
    pts = base + [(x, y, 0.5) for x in (-0.1, 0.0) for y in (-0.1, 0.1)]
    root = tmp_path / "scan"
    root.mkdir()
    trimesh.convex.convex_hull(np.array(pts)).export(root / "rock.obj")
    accs = _pulses(N, seed=7, scale=2.0)
    return _write_campaign(root, 'mesh = "rock.obj"\ndensity = 2600.0', accs, [i % 2 == 0 for i in range(N)])


def _free_vibration(root: Path) -> None:
    """Add a free-vibration record of the BLOCK (released at theta0 = alpha/2, sensor noise 0.1 mrad) to the
    campaign in root."""
    spec = Specimen(height=0.6, width=0.06, depth=0.3, mass=50.0)
    dt = 0.002
    theta = HousnerEngine().simulate(spec, GroundMotion(np.zeros(1500), dt, theta0=0.5 * spec.alpha)).theta
    theta = theta + np.random.default_rng(0).normal(0.0, 1e-4, theta.size)
    (root / "records").mkdir(exist_ok=True)
    rows = "\n".join(f"{k * dt:.4f},0,{x:.6g}" for k, x in enumerate(theta))
    (root / "records" / "fv.csv").write_text(f"time,ground_acc,theta\n{rows}\n")
    with open(root / "campaign.toml", "a") as f:
        f.write('[[record]]\nid = "fv"\nkind = "free_vibration"\nfile = "records/fv.csv"\n')


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("housner: error:") and "Traceback" not in err[0], err
    return err[0]


# ----------------------------------------------------------------------------
def test_block_campaign_run_scores_the_analytic_model(block, tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", str(block), "--engines", "housner", "--out", str(out), "--jobs", "1", "-q"]) == 0
    printed = capsys.readouterr().out
    res = pd.read_parquet(out / "results.parquet")
    camp = load_campaign(block)
    truth = {o.id: o.overturned for o in camp.outcomes}
    assert list(res["record_id"]) == [f"r{i:02d}" for i in range(N)]
    assert [bool(v) for v in res["observed_overturned"]] == [truth[r] for r in res["record_id"]]
    assert set(res["effects"]) == {""}  # a plain block: no geometry effect
    meta = json.loads((out / "run.json").read_text())
    assert meta["campaign"]["name"] == "small" and meta["campaign"]["path"] == str(block.resolve())
    assert meta["campaign"]["n_outcomes"] == N and meta["campaign"]["mesh"] is None

    # the scores are outcome_scores' on the same arrays: the 0/1 predictions clipped to [0.01, 0.99]
    y = res["observed_overturned"].to_numpy(bool)
    p = np.clip(res["overturned"].to_numpy(float), P_CLIP, 1 - P_CLIP)
    want = outcome_scores(p, y, seed=0).to_dict()
    (row,) = Run.load(out).outcome_scores
    got = row.to_json()
    for k in ("accuracy", "f1", "log_loss", "tp", "fp", "fn", "tn", "n_predicted", "n_overturned"):
        assert got[k] == want[k], k
    assert list(row.accuracy_ci) == want["accuracy_ci"] and row.n_failed == 0
    assert f"accuracy {want['accuracy']:.3f}" in printed and "clipped to [0.01, 0.99]" in printed

    html = (out / "report.html").read_text()
    assert 'id="outcomes"' in html and "How well does each engine predict the measured outcomes?" in html
    assert "clipped to [0.01, 0.99]" in html and "confusion matrix" in html
    assert "reported elsewhere" not in html  # the published row belongs to the ASU SP1 campaign only

    # `housner report` tells a campaign's run too
    assert main(["report", str(out), "--out", str(tmp_path / "again.html")]) == 0
    assert "How well does each engine predict the measured outcomes?" in (tmp_path / "again.html").read_text()


def test_scan_campaign_gives_planar_engines_the_asymmetric_pivots(scan, tmp_path):
    camp = load_campaign(scan)
    inp = campaign_input(camp)
    e = 0.5 * (camp.scan.neg.b - camp.scan.pos.b)
    assert e < 0  # the prism leans toward -x: b- < b+
    (eff,) = inp.geometry
    assert isinstance(eff, AsymmetricPivots) and eff.e == e
    done = run_campaign(camp, engines=["housner"], out=tmp_path / "run", jobs=1, progress=False)
    res = done.results
    assert set(res["effects"]) == {f"asymmetric_pivots(e={e:.4g})"}  # only the rows with the effect
    assert set(res["engine"]) == {"housner"}
    # each row is the analytic engine with the effect on that record (the specimen's geometry is realised)
    eng = HousnerEngine()
    for r in res.itertuples():
        resp = eng.simulate(inp.specimen, inp.motions[r.motion_id], (eff,))
        assert r.overturned == resp.overturned
        # 1e-9 relative: the same kernel on the same record (the cache stores the value as computed)
        assert r.theta_max_over_alpha == pytest.approx(resp.theta_max_over_alpha, rel=1e-9)
    assert 0 < res["overturned"].sum() < N  # the pulses span both outcomes, so the effect is exercised
    meta = done.meta.campaign
    assert [x.to_json() for x in meta.geometry.effects] == [{"name": "asymmetric_pivots", "e": e}]
    assert meta.mesh == {
        "mesh": str((scan / "rock.obj").resolve()),
        "azimuth": 0.0,
        "density": 2600.0,
        "contact": "hull",
    }


class _RecordingMeshEngine(HousnerEngine):
    """A stand-in 3D engine: takes the mesh settings, records them, answers as the analytic model on the block."""

    mesh_engine: ClassVar[bool] = True
    seen: ClassVar[list] = []

    def __init__(self, mesh=None, azimuth=0.0, density=2700.0, contact="hull"):
        super().__init__()
        self.mesh_settings = {"mesh": mesh, "azimuth": azimuth, "density": density, "contact": contact}
        type(self).seen.append(dict(self.mesh_settings))

    def settings(self) -> dict:
        return {**super().settings(), **self.mesh_settings}

    def _simulate(self, specimen, motion, effects):
        assert not effects  # a 3D engine gets the mesh, not the planar block's geometry effect
        return super()._simulate(specimen, motion, effects)


@pytest.fixture
def mesh_engine():
    _RecordingMeshEngine.seen = []
    register_engine("test-mesh")(_RecordingMeshEngine)
    yield _RecordingMeshEngine
    ENGINES.pop("test-mesh", None)


def test_mesh_engine_gets_the_campaign_mesh_settings(scan, tmp_path, mesh_engine):
    out = tmp_path / "run"
    assert main(["run", str(scan), "--engines", "housner,test-mesh", "--out", str(out), "--jobs", "1", "-q"]) == 0
    want = {"mesh": str((scan / "rock.obj").resolve()), "azimuth": 0.0, "density": 2600.0, "contact": "hull"}
    assert mesh_engine.seen and all(s == want for s in mesh_engine.seen)
    meta = json.loads((out / "run.json").read_text())
    assert {k: meta["engines"]["test-mesh"]["settings"][k] for k in want} == want
    res = pd.read_parquet(out / "results.parquet")
    assert set(res.loc[res.engine == "test-mesh", "effects"]) == {""}
    assert res.loc[res.engine == "housner", "effects"].str.startswith("asymmetric_pivots").all()
    view = Run.load(out)
    assert [r.engine for r in view.outcome_scores] == ["housner", "test-mesh"]
    # a 3D engine's theta is not the planar block's: no distribution verdict against it, said on the report
    assert view.mesh_engines == ["test-mesh"] and "test-mesh" not in view.verdicts()
    assert "no distribution verdict against the planar block" in (out / "report.html").read_text()


def test_bad_inputs_fail_in_one_line_before_any_work(block, scan, tmp_path, capsys, mesh_engine):
    out = tmp_path / "never"
    # a 3D engine on a plain block
    assert main(["run", str(block), "--engines", "test-mesh", "--out", str(out)]) == 2
    assert "simulates a scan mesh in 3D" in _one_line_error(capsys) and not mesh_engine.seen
    # no engines named
    assert main(["run", str(block), "--out", str(out)]) == 2
    assert "--engines" in _one_line_error(capsys)
    # an unknown engine (argparse names the choices)
    assert main(["run", str(block), "--engines", "nosuch", "--out", str(out)]) == 2
    assert "nosuch" in capsys.readouterr().err
    # a planar engine that cannot realise the scan's asymmetry
    register_engine("test-plain")(type("Plain", (HousnerEngine,), {"effects_supported": frozenset()}))
    try:
        assert main(["run", str(scan), "--engines", "test-plain", "--out", str(out)]) == 2
        assert "cannot realise effect 'asymmetric_pivots'" in _one_line_error(capsys)
    finally:
        ENGINES.pop("test-plain", None)
    # a campaign without ground-motion records
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "campaign.toml").write_text(f'name = "empty"\n[specimen]\n{BLOCK}\n')
    _free_vibration(empty)
    assert main(["run", str(empty), "--engines", "housner", "--out", str(out)]) == 2
    assert "no ground-motion records" in _one_line_error(capsys)
    # a scenario's ensemble option
    assert main(["run", str(block), "--engines", "housner", "--seed", "3", "--out", str(out)]) == 2
    assert "--seed" in _one_line_error(capsys)
    assert not (out / "results.parquet").exists()  # (--out is checked writable first: it may exist, empty)


def test_failed_records_are_counted_and_left_out(block, tmp_path):
    """A record an engine fails on is left out of its scores, and counted."""
    done = run_campaign(block, engines=["housner"], out=tmp_path / "run", jobs=1, progress=False)
    res = done.results.copy()
    res.loc[res.motion_id == 0, ["status", "overturned"]] = ["failed", False]
    from housner.scenarios.runs.campaign_run import outcome_table

    (row,) = outcome_table(res)
    ok = res[res.status == "ok"]
    want = outcome_scores(
        np.clip(ok["overturned"].to_numpy(float), P_CLIP, 1 - P_CLIP), ok["observed_overturned"].to_numpy(bool), seed=0
    ).to_dict()
    assert row.n_failed == 1 and row.n == N - 1 and row.accuracy == want["accuracy"]
    assert math.isfinite(row.log_loss)


def test_free_vibrations_run_from_their_release_without_an_outcome(block, tmp_path):
    _free_vibration(block)
    done = run_campaign(block, engines=["housner"], out=tmp_path / "run", jobs=1, progress=False)
    res = done.results
    assert len(res) == N + 1 and res["record_id"].iloc[-1] == "fv" and pd.isna(res["observed_overturned"].iloc[-1])
    alpha = load_campaign(block).specimen.alpha
    # the release fit finds theta0 within 1 % of alpha/2 (0.1 mrad noise on a 50 mrad release)
    assert done.motions[-1].theta0 == pytest.approx(0.5 * alpha, rel=0.01)
    assert res["status"].eq("ok").all()
    (row,) = Run.load(tmp_path / "run").outcome_scores
    assert row.n == N  # the free vibration has no outcome to score
