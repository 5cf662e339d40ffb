"""Studies ([study] scenarios): the table's checks, the stripes' scaling, a small study end to end, its assertion."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid

from housner import G, simulate
from housner.reports.assertions import assert_fragility_agreement
from housner.reports.assertions.studies import FragilityAgreementError
from housner.scenarios.catalogue import ScenarioError
from housner.scenarios.catalogue.scenario import load_scenario
from housner.scenarios.motions.build import build_motions
from housner.scenarios.motions.elastic import response_spectrum
from housner.scenarios.studies.study import StudyResult, intensity_measure, load_study, run_study, study_motions

HEAD = """name = "tiny-study"
[specimen]
preset = "bachmann2017"
[motions]
source = "{source}"
record = "elcentro"
model = "matched"
n = {n}
seed = 5
prototype_height = 5.0
[engines]
names = {names}
"""


def scenario_file(tmp_path, study: str, *, n: int = 6, names: str = '["housner"]', source: str = "rdk"):
    p = tmp_path / "tiny-study.toml"
    p.write_text(HEAD.format(n=n, names=names, source=source) + "[study]\n" + study)
    return p


@pytest.mark.parametrize(
    "study, says",
    [
        ('intensity = "pgaa"\nlevels = [1.0]\n', ["line 14", "unknown intensity 'pgaa'", "did you mean 'pga'"]),
        ('intensity = "pga"\n', ["needs `levels`"]),
        ("levels = [1.0, 0.5]\n", ["line 14", "'levels' must increase"]),
        ("levels = [1.0, -2]\n", ["line 14", "non-empty list of positive numbers"]),
        ('intensity = "sa"\nlevels = [1.0]\n', ['intensity "sa" needs `period`']),
        ('intensity = "pga"\nlevels = [1.0]\nperiod = 1.0\n', ["line 16", '`period` belongs to intensity "sa"']),
        ("levels = [1.0]\nS = [5]\nprototype_heights = [2.5]\n", ["not both"]),
        ("levels = [1.0]\nbootstrap = 5\n", ["line 15", "`bootstrap` must lie in [100, 100000]"]),
        ("levels = [1.0]\nsizes = [1]\n", ["line 15", "unknown key [study] 'sizes'"]),
    ],
)
def test_a_bad_study_table_is_refused_naming_file_line_and_key(tmp_path, study, says):
    with pytest.raises(ScenarioError) as e:
        load_scenario(scenario_file(tmp_path, study))
    msg = str(e.value)
    assert msg.startswith(str(tmp_path / "tiny-study.toml"))
    for s in says:
        assert s in msg, (s, msg)


def test_a_study_needs_ground_motions(tmp_path):
    p = tmp_path / "fv.toml"
    p.write_text(
        '[specimen]\npreset = "bachmann2017"\n[motions]\nsource = "free_vibration"\ntheta0_over_alpha = [0.5]\n'
        "[study]\nlevels = [1.0]\n"
    )
    with pytest.raises(ScenarioError, match="a \\[study\\] scales ground motions"):
        load_scenario(p)


def test_stripes_scale_each_motion_to_its_target_at_each_size(tmp_path):
    scen = load_scenario(scenario_file(tmp_path, "levels = [1.0]\nprototype_heights = [2.5, 10.0]\n", n=3))
    base, _ = build_motions(scen)
    spec = scen.specimen
    g_tan = G * math.tan(spec.alpha)
    for kind, levels, period in (
        ("amplitude", [0.5, 2.0], None),
        ("pga", [1.5, 3.0], None),
        ("pgv", [0.8], None),
        ("sa", [2.0], 0.8),
    ):
        st = scen.study.__class__(kind, tuple(levels), scen.study.S, scen.study.prototype_heights, period=period)
        for k, S in enumerate(st.S):
            motions, factors = study_motions(st, base, scen.S, k, spec)
            assert len(motions) == len(levels) * len(base)
            for j, level in enumerate(levels):
                for i, b in enumerate(base):
                    m = motions[j * len(base) + i]
                    # time: a prototype S times the model's size, seen at model scale (seed eq. 9)
                    assert m.dt == pytest.approx(b.dt * math.sqrt(scen.S / S), rel=1e-12)
                    if kind == "amplitude":
                        np.testing.assert_allclose(m.acc, level * b.acc, rtol=1e-12)
                        continue
                    # each measure recomputed independently of housner.scenarios.studies.study
                    if kind == "pga":
                        im = np.max(np.abs(m.acc)) / g_tan
                    elif kind == "pgv":
                        v = cumulative_trapezoid(m.acc, dx=m.dt, initial=0.0)
                        im = np.max(np.abs(v)) * spec.frequency_parameter / g_tan
                    else:
                        im = response_spectrum(m, [period / math.sqrt(S)])[0][0] / g_tan
                    assert im == pytest.approx(level, rel=1e-9), (kind, S, i)
                    assert factors[j, i] == pytest.approx(
                        level
                        / intensity_measure(
                            b.scaled(time=math.sqrt(scen.S / S)),
                            kind,
                            spec,
                            None if period is None else period / math.sqrt(S),
                        ),
                        rel=1e-12,
                    )


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """A small study on the analytic model and MuJoCo: 6 motions x 3 stripes x 2 sizes."""
    tmp = tmp_path_factory.mktemp("study")
    p = scenario_file(
        tmp,
        "levels = [1.5, 2.5, 4.0]\nprototype_heights = [2.5, 10.0]\nbootstrap = 200\n",
        names='["housner", "mujoco"]',
    )
    res = run_study(p, out=tmp / "out", jobs=1, cache_dir=tmp / "cache", progress=False)
    return p, tmp, res


def test_a_study_runs_every_record_and_writes_its_directory(tiny):
    p, tmp, res = tiny
    assert isinstance(res, StudyResult)
    # every (engine, size, stripe, motion) once, all ok
    assert len(res.results) == 2 * 2 * 3 * 6 and (res.results["status"] == "ok").all()
    assert not res.results.duplicated(["engine", "size", "stripe", "motion_id"]).any()
    for name in ("results.parquet", "fragility.parquet", "exceedance.parquet", "fragility.json", "study.json"):
        assert (tmp / "out" / name).is_file()
    assert list(res.fragility.columns[:10]) == [
        "engine",
        "size",
        "S",
        "stripe",
        "intensity",
        "n",
        "n_overturned",
        "p",
        "p_low",
        "p_high",
    ]
    assert len(res.fits) == 4 and len(res.comparisons) == 2  # (engine, size); mujoco against housner per size
    # histories are off by default: none kept
    assert res.histories == {}
    back = load_study(tmp / "out")
    assert len(back.fits) == 4
    for a, b in zip(back.fits, res.fits, strict=True):
        for x, y in ((a.median, b.median), (a.beta, b.beta), (a.median_low, b.median_low), (a.beta_high, b.beta_high)):
            assert x == pytest.approx(y, nan_ok=True)


def test_study_records_are_the_analytic_model_of_the_scaled_motion(tiny):
    p, _, res = tiny
    scen = load_scenario(p)
    base, _ = build_motions(scen)
    d = res.results[(res.results.engine == "housner") & (res.results["size"] == 10.0) & (res.results.stripe == 2)]
    for row in d.itertuples():
        m = base[row.motion_id].scaled(time=math.sqrt(scen.S / 20.0)).scaled(amplitude=4.0)
        direct = simulate(scen.specimen, m)
        assert row.overturned == direct.overturned
        if not direct.overturned:
            assert row.theta_max_over_alpha == pytest.approx(direct.theta_max_over_alpha, rel=1e-12)


def test_the_stripe_table_counts_the_records(tiny):
    _, _, res = tiny
    r = res.results
    for row in res.fragility.itertuples():
        d = r[(r.engine == row.engine) & (r["size"] == row.size) & (r.stripe == row.stripe)]
        assert row.n == len(d) and row.n_overturned == int(d.overturned.sum())
        assert row.p_low <= row.p <= row.p_high
    for row in res.exceedance.itertuples():
        d = r[(r.engine == row.engine) & (r["size"] == row.size) & (r.stripe == row.stripe)]
        k = int((d.overturned | (d.theta_max_over_alpha >= row.threshold)).sum())
        assert row.k == k


def test_a_larger_block_overturns_less_under_the_same_stripes(tiny):
    # Housner's size effect (seed section 4): the 10 m prototype sees the motions sqrt(4) slower than the
    # 2.5 m one relative to its own p, and overturns on fewer records at every stripe, in every engine
    _, _, res = tiny
    f = res.fragility
    for e in ("housner", "mujoco"):
        small = f[(f.engine == e) & (f["size"] == 2.5)].n_overturned.to_numpy()
        large = f[(f.engine == e) & (f["size"] == 10.0)].n_overturned.to_numpy()
        assert large.sum() < small.sum(), e


def test_a_study_is_deterministic_and_cached(tiny):
    p, tmp, res = tiny
    again = run_study(p, out=tmp / "again", jobs=1, cache_dir=tmp / "cache", progress=False)
    assert again.results["cached"].all()
    a = json.loads((tmp / "out" / "fragility.json").read_text())
    b = json.loads((tmp / "again" / "fragility.json").read_text())
    assert a == b


def test_fragility_assertion_reports_every_size_and_fails_honestly(tiny):
    _, tmp, res = tiny
    c = res.comparison("mujoco", 2.5)
    fits_ok = all(f.ok for f in res.fits)
    if fits_ok:
        # a tolerance just above / below the measured figures decides the verdict, both ways
        rtol = max(abs(res.comparison("mujoco", h).median_ratio - 1) for h in (2.5, 10.0))
        atol = max(abs(res.comparison("mujoco", h).beta_diff) for h in (2.5, 10.0))
        ok = assert_fragility_agreement(
            tmp / "out", "mujoco", "housner", median_rtol=rtol + 1e-9, beta_atol=atol + 1e-9
        )
        assert ok.passed and len(ok.criteria) == 2 + 2 * 2
        with pytest.raises(FragilityAgreementError) as e:
            assert_fragility_agreement(res, "mujoco", "housner", median_rtol=rtol / 2, beta_atol=10.0)
        assert "median ratio at H =" in str(e.value) and "interval" in str(e.value)
    else:  # a degenerate fit never passes
        with pytest.raises(FragilityAgreementError, match="no fit"):
            assert_fragility_agreement(res, "mujoco", "housner", median_rtol=10.0, beta_atol=10.0)
    assert math.isfinite(c.median_ratio) or not fits_ok
    with pytest.raises(ValueError, match="engine 'drake' is not in the study"):
        assert_fragility_agreement(res, "drake", "housner")
    with pytest.raises(ValueError, match="comparisons are against 'housner'"):
        assert_fragility_agreement(res, "mujoco", "pybullet")


def test_a_worker_that_dies_loses_one_record_labelled_and_the_study_goes_on(tmp_path, monkeypatch):
    from housner.scenarios.execution.chunks import CRASH_ENV

    p = scenario_file(tmp_path, "levels = [1.5, 3.0]\nprototype_heights = [2.5, 10.0]\nbootstrap = 100\n", n=5)
    monkeypatch.setenv(CRASH_ENV, "housner:6:SEGV")  # record 6 of each size's batch: stripe 1, motion 1
    res = run_study(p, out=tmp_path / "out", jobs=2, cache_dir=tmp_path / "cache", progress=False)
    bad = res.results[res.results.status != "ok"]
    assert len(res.results) == 2 * 2 * 5 and len(bad) == 2  # one per size, every other record kept
    assert set(bad.stripe) == {1} and set(bad.motion_id) == {1} and set(bad["size"]) == {2.5, 10.0}
    assert bad.error.str.contains("SIGSEGV").all()
    f = res.fragility
    assert f[f.stripe == 1].n.tolist() == [4, 4] and f[f.stripe == 0].n.tolist() == [5, 5]


def test_housner_run_on_a_study_prints_the_fits_and_writes_the_report(tmp_path, capsys):
    from housner.cli import main

    p = scenario_file(tmp_path, "levels = [1.5, 2.5, 4.0]\nbootstrap = 100\n", n=8)
    assert main(["run", str(p), "--out", str(tmp_path / "cli"), "-q", "--jobs", "1"]) == 0
    out = capsys.readouterr().out
    assert "fragility (amplitude factor on the ensemble [-]; median and beta with 95% bootstrap intervals):" in out
    assert "housner   H = 5 m: " in out
    assert (tmp_path / "cli" / "report.html").is_file()
    # the report command re-renders a study directory as a study
    assert main(["report", str(tmp_path / "cli")]) == 0


def test_a_study_on_dask_gives_the_same_fragility(tiny):
    import distributed

    p, tmp, res = tiny
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as lc:
        with distributed.Client(lc) as client:
            dask = run_study(p, out=tmp / "dask", scheduler=client, use_cache=False, progress=False)
    a = json.loads((tmp / "out" / "fragility.json").read_text())
    b = json.loads((tmp / "dask" / "fragility.json").read_text())
    assert a == b and not dask.results["cached"].any()


def test_histories_are_kept_only_when_asked(tmp_path):
    p = scenario_file(tmp_path, "levels = [1.0, 2.0]\nbootstrap = 100\nhistories = true\n", n=3)
    res = run_study(p, out=tmp_path / "out", jobs=1, cache_dir=tmp_path / "cache", progress=False)
    assert sorted(res.histories) == [("housner", 0, i) for i in range(6)]  # (engine, size, record of the size)
    assert all(h.dtype == np.float32 and h.size > 100 for h in res.histories.values())
