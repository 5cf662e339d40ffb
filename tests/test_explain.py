"""`housner explain`: an engine's own responses diagnosed as a campaign, and set beside the floor.

The control is the analytic engine explained by itself: a correct model of its own responses, so the
diagnosis must find no effect and the agreement must reach the floor. The command runs on MuJoCo with
a few motions and two candidate effects (the whole library on 8 motions takes a minute); a bad engine
name is refused in one line before any work.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from housner.cli import main
from housner.reports.explain_text import maps_remains_text, remains_text
from housner.scenarios.campaigns.campaign import load_campaign
from housner.scenarios.execution.options import RunOptions
from housner.scenarios.runs.explain import AMPLITUDES, REACH_MARGIN, Explanation, explain_engine


@pytest.fixture(scope="module")
def control(tmp_path_factory):
    work = tmp_path_factory.mktemp("explain")
    opts = RunOptions(jobs=1, progress=False)
    return explain_engine("housner", "elcentro", n_motions=12, workdir=work, options=opts), work


def test_the_analytic_engine_explains_itself(control):
    expl, _work = control
    # the truth is the model: no effect, or only one that changes no record (the agreement stays whole)
    assert not expl.effects or expl.agreement == 1.0, expl.effects
    # the engine and the reference are one deterministic solver on the same motions: exactly equal peaks
    assert expl.agreement_plain == 1.0
    # the same peaks give the same distribution: KS distance 0 before (and, with peaks unchanged, after)
    assert expl.ks.plain == 0.0 and (expl.effects or expl.ks.with_effects == 0.0)
    # the criterion: at the floor within REACH_MARGIN (5 points)
    assert expl.agreement >= expl.floor - REACH_MARGIN and expl.reaches_floor
    # the time histories: white noise at EXPLAIN_SIGMA on the model's own samples is what a correct model leaves
    assert expl.diagnosis.status == "no_misfit", remains_text(expl)
    # the chaos floor of an engine without r and p errors is whole (its p error is the sampled crossing, ~1e-11);
    # the model-form floor is not: a 0.1 % amplitude or a held input moves most records' peaks by more than 3 %
    assert expl.floor_parts.chaos == 1.0
    assert 0.0 < expl.floor_parts.model_form < 1.0 and expl.floor == expl.floor_parts.model_form
    assert expl.details.model_form_floor.shares["substeps x2"] == 1.0  # the analytic solver is converged
    assert expl.n_records == 12 and "Nothing beyond the floor" in remains_text(expl)
    d = expl.to_dict()
    assert json.loads(json.dumps(d))["effects"] == [] and set(d["floor_parts"]) == {"chaos", "model_form"}
    # the explain JSON is the explanation written: read back, it is the explanation, and writes the same JSON
    back = Explanation.from_json(json.loads(json.dumps(d)))
    assert back == expl and back.to_dict() == d
    # the analytic engine's measured maps are Housner's own (ratio 1 to 1e-6, the impact-map tests' tolerance),
    # so Housner + its maps is the model itself: every record agrees, none parts
    m = expl.maps
    assert m.agreement == 1.0 and m.reaches_floor and m.departures.n == 0
    # its measured scatter (spread ~1e-11) moves no record by 3 %: the scatter floor is whole
    assert m.scatter_floor.share == 1.0 and m.reaches_scatter_floor
    ratios = np.asarray(m.maps.impacts["ratio_median"], float)
    assert np.all(np.abs(ratios[np.isfinite(ratios)] - 1.0) < 1e-6)
    # the maps' rounding (ratios 1 +- 1e-11) moves the peaks by ~1e-10: the two-sample KS distance, a step function
    # of the ordering, then reads one record's step (1/12) where two equal samples read 0
    assert expl.ks.with_maps <= 1.0 / expl.n_records + 1e-12
    assert "explained by what was measured" in maps_remains_text(expl)


def test_the_campaign_orders_and_flags_its_records(control):
    expl, work = control
    camp = load_campaign(expl.details.campaign)
    ids = [r.id for r in camp.records]
    kinds = [r.kind for r in camp.records]
    assert len(camp.free_vibration) == len(AMPLITUDES) and len(camp.ground_motion) == 12 and not camp.skipped
    # free vibrations first, in the middle and last (a third of the releases each), ground motions in between
    fv_at = [i for i, k in enumerate(kinds) if k == "free_vibration"]
    assert fv_at == [0, 1, 2, 9, 10, 17, 18] and ids[3] == "gm001" and ids[-3] == "gm012"
    # releases at the amplitudes, alternately on both pivots, fitted back from the samples to 0.1 %
    alpha = camp.specimen.alpha
    got = sorted(abs(r.motion.theta0) / alpha for r in camp.free_vibration)
    assert np.allclose(got, sorted(AMPLITUDES), rtol=1e-3)
    assert {np.sign(r.motion.theta0) for r in camp.free_vibration} == {-1.0, 1.0}
    # an overturned record says so, as the campaign format asks
    assert sum(r.overturned for r in camp.ground_motion) == expl.details.overturned.engine


def test_cli_on_mujoco_writes_the_figures(tmp_path, capsys):
    out = tmp_path / "mujoco.json"
    fig = tmp_path / "maps.png"
    rc = main(
        [
            "explain",
            "mujoco",
            "--n-motions",
            "4",
            "--effects",
            "restitution,time_lag",
            "--json",
            str(out),
            "--figure",
            str(fig),
            "--jobs",
            "1",
            "-q",
        ]
    )
    assert rc == 0
    text = capsys.readouterr().out
    assert "agreement with mujoco" in text and "floor" in text and "remains:" in text
    assert "measured impact and flight maps" in text and fig.read_bytes()[:4] == b"\x89PNG"
    d = json.loads(out.read_text())
    for key in ("agreement", "agreement_plain", "floor"):
        assert 0.0 <= d[key] <= 1.0, key
    assert all(0.0 <= v <= 1.0 for v in d["floor_parts"].values())
    assert isinstance(d["effects"], list) and isinstance(d["reaches_floor"], bool)
    assert d["diagnosis"]["status"] and d["remains"]
    # Housner + MuJoCo's measured maps, compared record by record; where they disagree, the phase is named
    m = d["maps"]
    assert 0.0 <= m["agreement"] <= 1.0 and isinstance(m["reaches_floor"], bool) and m["remains"]
    assert sum(m["departures"]["by_phase"].values()) == m["departures"]["n"] <= 4
    assert len(m["scatter_floor"]["shares"]) == 3 and 0.0 <= m["scatter_floor"]["share"] <= 1.0
    assert m["maps"]["engine"] == "mujoco" and len(m["maps"]["impact_points"]["x"]) > 50


def test_cli_figure_needs_the_maps_and_a_known_format(tmp_path, capsys):
    for extra, words in (
        (["--no-maps", "--figure", str(tmp_path / "m.png")], "--no-maps"),
        (["--figure", str(tmp_path / "m.pdf")], "PNG or SVG"),
    ):
        assert main(["explain", "mujoco", *extra]) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and words in err


def test_cli_refuses_an_unknown_engine_in_one_line(tmp_path, capsys):
    out = tmp_path / "never.json"
    assert main(["explain", "mujocco", "--json", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "unknown engine 'mujocco'" in err and "did you mean 'mujoco'" in err
    assert not out.exists()
