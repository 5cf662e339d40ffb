"""Effects through the runner: a scenario's [[effects]] run on every engine beside the same engines without them.

The series with the effects must equal the analytic model run directly with
the same physics (an independent call of :func:`housner.simulate` with the
parameter the effect sets), carry the effects in their rows, be cached apart
from the runs without them, survive the process pool, and be refused by name
on an engine that does not realise them, before any work.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from housner import simulate
from housner.reports.run import page as html
from housner.scenarios.catalogue import ScenarioError
from housner.scenarios.catalogue.scenario import load_scenario
from housner.scenarios.execution.cache import cache_key
from housner.scenarios.motions.build import build_motions
from housner.scenarios.runs import run as runner
from housner.scenarios.runs.run import run_scenario

SCEN = """name = "fx"
[specimen]
preset = "bachmann2017"
[motions]
source = "rdk"
record = "elcentro"
n = 6
seed = 11
prototype_height = 5.0
[engines]
names = {names}
{effects}
"""

RESTITUTION = '\n[[effects]]\nname = "restitution"\nr = 0.9532\n'


def scenario(tmp_path, effects=RESTITUTION, names='["housner"]', file="fx.toml"):
    p = tmp_path / file
    p.write_text(SCEN.format(names=names, effects=effects))
    return p


def test_the_effects_series_is_the_engine_with_the_effects_and_the_rows_say_so(tmp_path):
    run = run_scenario(scenario(tmp_path), out=tmp_path / "run", jobs=1, cache_dir=tmp_path / "c", progress=False)
    df = run.results
    label = "restitution(r=0.9532)"
    series = f"housner + {label}"
    assert list(dict.fromkeys(df.engine)) == ["housner", series]
    assert (df[df.engine == "housner"].effects == "").all() and (df[df.engine == series].effects == label).all()
    spec = load_scenario(scenario(tmp_path)).specimen
    # independently: the analytic solver called with r itself (the effect's only action), and without
    for m_id, motion in enumerate(run.motions):
        base = df[(df.engine == "housner") & (df.motion_id == m_id)].theta_max_over_alpha.item()
        with_r = df[(df.engine == series) & (df.motion_id == m_id)].theta_max_over_alpha.item()
        assert base == simulate(spec, motion).theta_max_over_alpha
        assert with_r == simulate(spec, motion, r=0.9532).theta_max_over_alpha
    assert not np.array_equal(
        df[df.engine == "housner"].theta_max_over_alpha.to_numpy(), df[df.engine == series].theta_max_over_alpha
    )
    # run.json and the written table carry them too
    assert run.meta.effects.to_json() == {"label": label, "effects": [{"name": "restitution", "r": 0.9532}]}
    assert run.meta.engines[series].engine == "housner"
    written = pd.read_parquet(tmp_path / "run" / "results.parquet")
    assert set(written.effects) == {"", label}
    assert {k for k, _ in run.histories} == {"housner", series}


def test_effects_are_cached_apart_and_reused(tmp_path):
    kw = dict(jobs=1, cache_dir=tmp_path / "c", progress=False)
    first = run_scenario(scenario(tmp_path), out=tmp_path / "a", **kw).results
    again = run_scenario(scenario(tmp_path), out=tmp_path / "b", **kw).results
    assert again.cached.all()
    pd.testing.assert_series_equal(first.theta_max_over_alpha, again.theta_max_over_alpha)
    # a run without effects reuses the baseline entries, its keys are those of an effect-free run
    plain = run_scenario(scenario(tmp_path, effects=""), out=tmp_path / "p", **kw).results
    assert plain.cached.all() and len(plain) == 6
    scen = load_scenario(scenario(tmp_path))
    m = build_motions(scen)[0][0]
    k0 = cache_key(scen.specimen, m, "housner", {"r": None, "substeps": None}, "v")
    assert k0 == cache_key(scen.specimen, m, "housner", {"r": None, "substeps": None}, "v", ())
    assert k0 != cache_key(scen.specimen, m, "housner", {"r": None, "substeps": None}, "v", scen.effects)


def test_effects_travel_to_pool_workers(tmp_path):
    kw = dict(cache_dir=tmp_path / "c", progress=False, use_cache=False)
    one = run_scenario(scenario(tmp_path), out=tmp_path / "a", jobs=1, **kw).results
    two = run_scenario(scenario(tmp_path), out=tmp_path / "b", jobs=2, **kw).results
    pd.testing.assert_frame_equal(
        one.drop(columns=["wall_s"]).reset_index(drop=True), two.drop(columns=["wall_s"]).reset_index(drop=True)
    )


def test_the_report_gives_an_effect_no_verdict_only_how_far_it_moves(tmp_path):
    run_scenario(scenario(tmp_path), out=tmp_path / "run", jobs=1, cache_dir=tmp_path / "c", progress=False)
    page = html.render_report(tmp_path / "run")
    head = page.split('id="verdict"')[1].split("</section>")[0]
    assert "restitution(r=0.9532)" in head and '<span class="badge na">effect</span>' in head
    lines = head.split('<ul class="verdicts">')[1].split("</ul>")[0]  # the verdict lines (the rule below names all)
    assert "FAIL" not in lines and "AGREES" not in lines and "ENSEMBLE ONLY" not in lines
    assert "against housner without the effects: median" in head


SLIDING = '\n[[effects]]\nname = "sliding"\nmu = 0.3\n'


def test_an_engine_that_does_not_realise_an_effect_is_refused_by_name_before_any_work(tmp_path):
    with pytest.raises(ScenarioError) as e:
        load_scenario(scenario(tmp_path, SLIDING, names='["housner", "mujoco"]'))
    msg = str(e.value)
    assert "engine 'mujoco' cannot realise effect 'sliding'" in msg and "'housner'" in msg
    # an --engines override is checked the same way, before the output directory is touched
    with pytest.raises(ScenarioError, match="cannot realise effect 'sliding'"):
        run_scenario(scenario(tmp_path, SLIDING), engines=["pybullet"], out=tmp_path / "never", progress=False)
    assert not (tmp_path / "never").exists()


def test_an_r_above_the_engines_contact_is_refused_before_any_work(tmp_path):
    # the planar engines realise restitution with their impact law, which only takes energy away:
    # the seed's calibrated r = 0.9532 lies above Housner's 0.9465, out of their reach
    refused = r"fx.toml: \[\[effects\]\] engine 'mujoco' cannot realise restitution r = 0.9532"
    with pytest.raises(ScenarioError, match=refused):
        run_scenario(scenario(tmp_path), engines=["housner", "mujoco"], out=tmp_path / "never", progress=False)
    assert not (tmp_path / "never").exists()


def test_an_r_below_housners_runs_on_an_engine_and_agrees_with_the_analytic_model(tmp_path):
    lower = '\n[[effects]]\nname = "restitution"\nr = 0.9\n'
    run = run_scenario(
        scenario(tmp_path, lower, names='["housner", "mujoco"]'),
        out=tmp_path / "run",
        jobs=1,
        cache_dir=tmp_path / "c",
        progress=False,
    )
    df = run.results.set_index(["engine", "motion_id"]).theta_max_over_alpha
    with_r = df["mujoco + restitution(r=0.9)"].to_numpy()
    analytic = df["housner + restitution(r=0.9)"].to_numpy()
    plain = df["mujoco"].to_numpy()
    # the effect reaches MuJoCo's records (its own series, labelled), and lowers the median
    # theta_max/alpha of these 6 motions as it lowers the analytic model's (more energy lost per impact)
    assert not np.array_equal(with_r, plain)
    assert np.median(with_r) < np.median(plain)
    assert np.median(analytic) < np.median(df["housner"].to_numpy())


@pytest.mark.parametrize(
    "effects, says",
    [
        ('\n[[effects]]\nname = "restitutio"\nr = 0.9\n', ["line 13", "unknown effect 'restitutio'", "restitution"]),
        ('\n[[effects]]\nname = "restitution"\nrr = 0.9\n', ["line 13", "'rr'", "did you mean 'r'"]),
        ('\n[[effects]]\nname = "restitution"\nr = 1.5\n', ["line 13", "`r`", "[0, 1]"]),
        ("\n[[effects]]\nr = 0.9\n", ["line 13", 'needs name = "<effect>"', "rotational_damping"]),
        (RESTITUTION + RESTITUTION, ["lists 'restitution' twice"]),
        ('\n[[effects]]\nname = "sliding"\n', ["line 13", "needs `mu`"]),
    ],
)
def test_bad_effect_tables_are_one_line_errors_with_their_line(tmp_path, effects, says):
    with pytest.raises(ScenarioError) as e:
        load_scenario(scenario(tmp_path, effects=effects))
    msg = str(e.value)
    assert "\n" not in msg and str(tmp_path / "fx.toml") in msg
    for s in says:
        assert s in msg, msg


def test_the_shipped_restitution_scenario_loads_with_its_effect():
    scen = load_scenario("elcentro-restitution")
    assert [e.name for e in scen.effects] == ["restitution"] and math.isclose(scen.effects[0].r, 0.9532)
    assert runner.effects_series("housner", scen.effects) == "housner + restitution(r=0.9532)"
