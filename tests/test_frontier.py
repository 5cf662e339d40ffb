"""The accuracy-cost frontier (housner.scenarios.runs.frontier): its points, its knee, a real sweep, its CLI
and its report section."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from housner.cli import main
from housner.engines.base import engine_class
from housner.reports.run.sections import tuning as tuning_section
from housner.reports.run.sections.engines_explained import engines_explained
from housner.scenarios.execution.options import RunOptions
from housner.scenarios.runs.frontier import (
    KNEE_Z,
    Frontier,
    FrontierPoint,
    _points,
    engine_frontier,
    frontier_axes,
    knee,
    knee_reason,
    unmet_everywhere,
)
from housner.scenarios.runs.view import Run

ENGINES = ("mujoco", "pybullet", "dart", "opensees", "drake")


def point(agreement, cost, met=True, n=100, axis="timestep", error="", failed="", **measured):
    return FrontierPoint(
        axis,
        {"timestep": cost},
        agreement=agreement,
        n_records=n,
        checks_met=met,
        failed=failed or ("" if met else "decay"),
        cpu_per_sim_second=cost,
        error=error,
        **measured,
    )


def test_knee_is_the_cheapest_point_not_significantly_below_the_best():
    # best 0.40 at n = 100: SE of a difference with 0.30 is sqrt(.4*.6/100 + .3*.7/100) = 0.067, so 0.30 is
    # within 1.96 SE (0.13) and 0.20 is not (0.20 > 0.13)
    pts = [point(0.40, 1.0), point(0.30, 0.5), point(0.20, 0.1)]
    assert knee(pts) == 1
    # costs within COST_TIE (15 %) are equal: the defaults (the first point) stay, else the more accurate
    assert knee([point(0.30, 1.0), point(0.32, 0.9)]) == 0
    assert knee([point(0.40, 1.0), point(0.30, 0.5), point(0.33, 0.55)]) == 2
    se = math.hypot(pts[0].agreement_se(), pts[2].agreement_se())
    assert 0.40 - 0.20 > KNEE_Z * se


def test_knee_trades_no_checked_accuracy_for_time():
    # MuJoCo's sweep: 0.3 ms meets every check at 0.84x the cost, but scores 0.86 against the defaults' 0.57
    d, coarse = point(0.28, 0.0171, score=0.571), point(0.28, 0.0144, score=0.858)
    assert knee([d, coarse]) == 0
    coarse = replace(coarse, score=0.5)  # as well checked: the cheaper step is the knee
    assert knee([d, coarse]) == 1


def test_knee_keeps_the_reports_distribution_verdict():
    # DART's sweep on elcentro (2026-11-27): 1/8 ms checks as well as 1/10 ms at 0.80x the CPU time, but its
    # KS 0.19 would fail the run report's criterion (0.15) that the defaults pass at 0.13
    d, coarse = point(0.35, 0.0707, score=0.55, ks=0.13), point(0.36, 0.0564, score=0.46, ks=0.19)
    assert knee([d, coarse]) == 0
    f = Frontier(
        engine="dart",
        scenario="elcentro",
        n_motions=100,
        defaults={"timestep": 1e-4},
        axes={"timestep": [1.25e-4]},
        points=[d, coarse],
        knee=0,
        default=0,
        model_form_floor=0.5,
    )
    assert "fail the run report's KS criterion" in knee_reason(f)
    coarse = replace(coarse, ks=0.15)  # at the criterion: kept
    assert knee([d, coarse]) == 1
    # defaults that already fail it: a point no worse than theirs may still be chosen
    d, coarse = replace(d, ks=0.16), replace(coarse, ks=0.16)
    assert knee([d, coarse]) == 1
    coarse = replace(coarse, ks=0.17)
    assert knee([d, coarse]) == 0
    # a sweep where no point ran still says why (it raised on an empty min() before)
    f = replace(f, points=(point(math.nan, 0.07, error="diverged"),))
    assert knee(f.points) == 0 and "within 1.96 standard errors" in knee_reason(f)


def test_knee_needs_the_tuner_checks_and_skips_failed_points():
    pts = [point(0.40, 1.0), point(0.40, 0.5, met=False), point(math.nan, 0.1, error="diverged")]
    assert knee(pts) == 0  # the cheaper point fails a check; the cheapest did not run
    # no point meets the decay check: it decides nothing, the others still do
    never = [point(0.30, 1.0, met=False), point(0.30, 0.2, met=False, failed="decay, r"), point(0.3, 0.5, met=False)]
    assert unmet_everywhere(never) == {"decay"}
    assert knee(never) == 2


def test_points_are_the_defaults_then_each_axis():
    pts = _points({"timestep": 2e-4, "stiffness": 1e6}, {"timestep": (1e-4, 2e-4, 4e-4), "stiffness": (1e5, 1e6)})
    assert [p.label for p in pts] == ["defaults", "timestep=0.0001", "timestep=0.0004", "stiffness=100000"]
    # a tuple-valued setting: the engine reports its default as a (JSON) list, the axis as tuples
    pts = _points({"solref": [4e-4, 1.0]}, {"solref": ((4e-4, 1.0), (6e-4, 1.0))})
    assert [p.label for p in pts] == ["defaults", "solref=(0.0006, 1)"]
    with pytest.raises(ValueError, match="frontier axis 'stifness' is not a setting"):
        _points({"timestep": 2e-4}, {"stifness": (1.0,)})


@pytest.mark.parametrize("engine", ENGINES)
def test_each_engine_declares_a_step_and_a_contact_setting_of_three_to_five_values(engine):
    """The step and the main contact setting, 3-5 numbers each (the issue); then, where the engine offers more
    than one solver or contact element, each such choice, every value it offers a point."""
    axes = frontier_axes(engine)
    names = list(axes)
    assert names[0] == "timestep" and len(axes) in (2, 3, 4)
    cls = engine_class(engine)
    for name in names[:2]:
        assert 3 <= len(axes[name]) <= 5, name  # the issue's 3-5 points per setting
        assert any(np.allclose(v, cls.DEFAULTS[name]) for v in axes[name]), f"{name}: the default is a point"
    for choice in names[2:]:
        assert cls.DEFAULTS[choice] in axes[choice] and set(axes[choice]) <= set(cls.CHOICES[choice])


def test_a_real_sweep_marks_a_coarser_step_that_fails_the_checks(tmp_path):
    """MuJoCo at 2.5x its step: r off by more than the tuner's 0.5 % (measured 0.72 %), so the knee stays."""
    fr = engine_frontier(
        "mujoco",
        "elcentro",
        n_motions=4,
        axes={"timestep": (2e-4, 5e-4)},
        options=RunOptions(jobs=1, progress=False, cache_dir=tmp_path),
    )
    assert [p.label for p in fr.points] == ["defaults", "timestep=0.0005"]
    d, coarse = fr.points
    assert d.checks_met and abs(d.r_error) <= 0.005
    assert not coarse.checks_met and abs(coarse.r_error) > 0.005
    assert fr.knee == fr.default == 0
    for p in fr.points:
        assert p.n_records == 4 and 0.0 <= p.agreement <= 1.0 and 0.0 <= p.ks <= 1.0
        assert 0.0 < p.floor <= 1.0 and p.floor == min(p.floor_parts.chaos, p.floor_parts.model_form)
    back = Frontier.from_dict(json.loads(json.dumps(fr.to_dict())))
    assert back.to_dict() == fr.to_dict() and back == fr
    assert "knee" in fr.summary() and "timestep=0.0005" in fr.summary()


def test_cli_refuses_the_reference_and_a_scenario_without_ground_motions(capsys):
    assert main(["frontier", "housner"]) == 2
    assert "'housner' is the reference" in capsys.readouterr().err
    assert main(["frontier", "mujoco", "--scenario", "free-vibration"]) == 2
    err = capsys.readouterr().err
    assert "--scenario" in err and len(err.strip().splitlines()) == 1


def _frontier_file() -> dict:
    pts = [point(0.30, 0.016), point(0.33, 0.03), point(0.31, 0.008, met=False)]
    pts = [
        replace(p, r_error=r, small_error=r, decay_error=0.01, pulse_error=r, ks=0.1, floor=0.45)
        for p, r in zip(pts, (0.003, 0.002, 0.007), strict=True)
    ]
    fr = Frontier(
        "beta-engine",
        "elcentro",
        100,
        {"timestep": 0.016},
        {"timestep": [0.008, 0.016, 0.03]},
        pts,
        knee=0,
        default=0,
        model_form_floor=0.45,
        version="1.0",
        date="2026-11-26",
    )
    return fr.to_dict()


def test_report_section_shows_the_decomposition_and_the_frontier(tmp_path, monkeypatch):
    rows = [
        {"engine": e, "motion_id": i, "theta_max_over_alpha": 0.1 + 0.01 * i, "overturned": False, "status": "ok"}
        for e in ("housner", "beta-engine")
        for i in range(5)
    ]
    run_dir = tmp_path / "run"
    run_dir.mkdir()
    pd.DataFrame(rows).to_parquet(run_dir / "results.parquet")
    monkeypatch.setattr(tuning_section, "TUNING_DIR", tmp_path)
    run = Run.load(run_dir)
    assert "No stored explanation or frontier" in engines_explained(run)
    explanation = {
        "engine": "beta-engine",
        "scenario": "elcentro",
        "n_records": 100,
        "agreement_plain": 0.28,
        "agreement": 0.31,
        "floor": 0.49,
        "floor_parts": {"chaos": 0.67, "model_form": 0.49},
        "reaches_floor": False,
        "remains": "18% below the floor",
        "effects": [{"name": "viscous_damping", "params": {"zeta": 0.0012}}],
    }
    (tmp_path / "explain-beta-engine.json").write_text(json.dumps(explanation))
    (tmp_path / "frontier-beta-engine.json").write_text(json.dumps(_frontier_file()))
    html = engines_explained(Run.load(run_dir))
    assert "28% &rarr; 31%" in html and "viscous_damping" in html and "zeta = 0.0012" in html
    assert "chaos floor 67%" in html and "below it" in html
    # what remains, in the page's words from the file's figures (its own "remains" sentence is not read)
    assert "31% of the records, 18 points below the reachable agreement of 49%." in html
    assert "18% below the floor" not in html
    assert "swept from, knee" in html and "data:image/png;base64," in html
    assert "NOT met" in html  # the cheap point that fails a check


def test_frontier_figures_are_drawn_once_per_machine(tmp_path, monkeypatch):
    """The figure of a stored frontier is kept in the cache folder and read back; other data, or a damaged
    entry, is drawn again."""
    from housner.reports import page
    from housner.reports.frontier_figure import frontier_figure

    monkeypatch.setenv("HOUSNER_CACHE_DIR", str(tmp_path))
    drawn = []

    def draw(fr):
        drawn.append(fr.engine)
        return frontier_figure(fr)

    d = _frontier_file()
    fr = Frontier.from_dict(d)
    first = page.html_stored_figure(draw, (fr,), d, "caption", "alt")
    (entry,) = (tmp_path / "figures").glob("*.b64")
    assert page.html_stored_figure(draw, (fr,), d, "caption", "alt") == first and len(drawn) == 1
    other = {**d, "date": "another day"}
    page.html_stored_figure(draw, (Frontier.from_dict(other),), other, "caption", "alt")
    assert len(drawn) == 2 and len(list((tmp_path / "figures").glob("*.b64"))) == 2
    entry.write_text("garbage")
    assert page.html_stored_figure(draw, (fr,), d, "caption", "alt") == first and len(drawn) == 3


def test_an_error_that_could_not_be_measured_is_a_dash_not_nan():
    """OpenSees at 1 ms has no first impact in some releases: its r error is NaN, shown as a dash."""
    from housner.reports.run.sections.engines_explained import _signed

    assert _signed(float("nan"), "+.2%") == _signed(None, "+.2%") == _signed(float("inf"), "+.1%") == "&ndash;"
    assert _signed(-0.0123, "+.2%") == "-1.23%"


def test_the_report_marks_the_point_that_is_the_engines_defaults_now():
    from housner.reports.run.sections.engines_explained import current_point

    fr = Frontier.from_dict(_frontier_file())  # swept from timestep 0.016; points 0.016, 0.03, 0.008
    assert current_point(fr, {"timestep": 0.03, "other": 1}) == 1
    assert current_point(fr, {"timestep": 0.016}) == 0
    assert current_point(fr, {"timestep": 0.02}) is None and current_point(fr, {}) is None


@pytest.mark.parametrize("engine", ENGINES)
def test_shipped_defaults_are_the_knee_of_the_shipped_frontier(engine):
    """engines/models/frontier-ENGINE.json: readable, its knee is what the rule gives, and the engine's defaults
    are that knee (the issue: defaults at the knee). A change of defaults or of the rule shows here."""
    from housner.reports.run.sections.engines_explained import current_point
    from housner.reports.run.sections.tuning import model_file

    path = model_file("frontier", engine)
    if not path.is_file():
        pytest.skip(f"no shipped frontier for {engine}")
    fr = Frontier.from_dict(json.loads(path.read_text()))
    assert fr.engine == engine and fr.n_motions >= 50
    assert knee(fr.points) == fr.knee
    assert current_point(fr, engine_class(engine).DEFAULTS) == fr.knee
    explained = json.loads(model_file("explain", engine).read_text())
    assert explained["engine"] == engine and 0.0 <= explained["agreement"] <= 1.0 and 0.0 < explained["floor"] <= 1.0
