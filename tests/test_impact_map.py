"""The impact and flight maps (housner.scenarios.runs.impact_map): the method checked on the analytic engine, PyBullet's
small-speed impact loss, the JSON round trip, the figure and ``housner impact-map``'s one-line errors."""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np
import pytest
from shared import optional_engine

from housner.cli import app
from housner.cli import impact_map as impact_map_cli
from housner.cli.app import build_parser
from housner.scenarios.runs.impact_map import EngineMaps, measure_maps


@pytest.fixture(scope="module")
def analytic_maps() -> EngineMaps:
    return measure_maps("analytic")  # the default grid: ~110 impacts from x = 0.05 to 1, ~1 s


def test_the_analytic_engines_maps_are_flat(analytic_maps):
    """Measured on Housner's own solution, the method must return Housner: ratio 1, c = 0, no drift, no contact.

    The fit is exact for Housner's flight (the energy integral, 16-node Gauss-Legendre to ~1e-12, least
    squares to xtol 1e-14); what is left is the event-accurate solver's own error (~1e-10 in theta). Measured:
    |ratio - 1| < 4e-11, |c| < 8e-10 1/s, |drift| < 4e-11 over every point. The tolerances, 1e-6, are a thousand
    times that and a thousand times finer than the 0.1 % asked of the method, and far below the engines'
    departures (1e-3 to 7e-2 in ratio).
    """
    m = analytic_maps
    x, ratio = m.impact_table()
    _, c = m.flight_table()
    assert x.min() < 0.06 and x.max() > 0.85  # the grid covers small rocking to near-overturning impacts
    assert sum(m.impacts["n"]) >= 100 and sum(m.flights["n"]) >= 90
    assert np.all(np.abs(ratio - 1.0) < 1e-6), ratio
    every_impact = np.asarray(m.impact_points["ratio_to_housner"])
    assert np.all(np.abs(every_impact - 1.0) < 1e-6)  # every impact, not only the bins' medians
    assert np.all(np.abs(c) < 1e-6), c
    assert np.all(np.abs(np.asarray(m.flights["period_drift_median"])) < 1e-6)
    assert np.all(np.asarray(m.impact_points["contact_s"]) == 0.0)  # a rigid impact: within one sample interval
    # x is |w-| / (p alpha): the first impact of a release from rest at theta0 lies at sqrt(2 E) / (p alpha), with
    # E = p^2 (cos(alpha - theta0) - cos(alpha)), so at sqrt(2 (cos(alpha - theta0) - cos(alpha))) / alpha
    alpha, a0 = m.specimen.alpha_rad, m.amplitudes[-1]
    x0 = np.sqrt(2 * (np.cos(alpha - a0 * alpha) - np.cos(alpha))) / alpha
    pts = m.impact_points
    first = [
        x
        for x, rel, k in zip(pts["x"], pts["release"], pts["k"], strict=True)
        if rel == len(m.amplitudes) - 1 and k == 1
    ]
    assert first == pytest.approx([x0], rel=1e-9)


@pytest.mark.parametrize("name", [optional_engine("pybullet")])
def test_pybullets_small_impacts_lose_more_than_its_large_ones(name):
    """PyBullet at its defaults keeps less than Housner's r at small impact speeds: here the median of 5 impacts at
    x = 0.055-0.077 is 0.949 r_housner (the full map: 0.93 at x = 0.05, 0.97 at 0.07, 0.99 at 0.2), and Housner's r
    within 0.03 % at x = 0.9 (5 impacts). Asked: small below large by more than 2 % (the loss at the first
    impact from 0.005 alpha measured by hand from the peaks, 2.7 %, folds in two quarter-flights), 3 points under
    the measured gap; the engine is deterministic, so the margin is for other PyBullet versions and platforms."""
    m = measure_maps(name, amplitudes=(0.0015, 0.003, 0.9), n_impacts=5)
    x = np.asarray(m.impact_points["x"])
    ratio = np.asarray(m.impact_points["ratio_to_housner"])
    small, large = ratio[x < 0.08], ratio[x > 0.5]
    assert small.size >= 5 and large.size >= 4
    assert np.median(small) < np.median(large) - 0.02, (np.median(small), np.median(large))
    assert abs(np.median(large) - 1.0) < 0.005  # large impacts: Housner's r (measured: 3e-4; spread there 1.6e-3)


def test_json_round_trip_and_figure(analytic_maps, tmp_path):
    text = analytic_maps.to_json()
    d = json.loads(text)
    for key in ("engine", "settings", "version", "specimen", "impacts", "flights", "impact_points", "dt_s"):
        assert key in d
    assert {"w_pre_rad_s", "ratio_to_housner", "contact_s"} <= set(d["impact_points"])
    assert {"c_per_s", "e_start_rad2_s2", "period_drift"} <= set(d["flight_points"])
    back = EngineMaps.from_json(text)
    assert back == analytic_maps
    assert back.to_json() == text
    with pytest.raises(ValueError, match="not a housner impact-maps file"):
        EngineMaps.from_json('{"engine": "x"}')

    from housner.reports.impact_map_figure import maps_figure, save_figure

    fig = maps_figure([analytic_maps])
    assert len(fig.axes) == 2
    for name in ("m.png", "m.svg"):
        assert save_figure(fig, tmp_path / name).stat().st_size > 1000
    with pytest.raises(ValueError, match=r"must end in one of \.png, \.svg"):
        save_figure(fig, tmp_path / "m.gif")


# ----------------------------------------------------------------------------
# the command


@pytest.fixture
def cli(monkeypatch):
    """``housner ...`` in this process, with ``impact-map`` added to the parser if the parser does not list it yet."""

    def build(full_help: bool = True):
        p = build_parser(full_help)
        sub = next(a for a in p._actions if isinstance(a, argparse._SubParsersAction))
        if "impact-map" not in sub.choices:
            impact_map_cli.add_parser(sub, {"engines": "", "effects": "", "scenarios": ""})
        return p

    monkeypatch.setattr(app, "build_parser", build)
    return app.main


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["nosuch"], "unknown engine 'nosuch'"),
        (["pybullet", "--settings", "nosuch=1"], "unknown PyBullet setting 'nosuch'"),
        (["pybullet", "--settings", "timestep"], "must be KEY=VALUE"),
        (["analytic", "--settings", "mujoco.timestep=1e-3"], "engine 'mujoco' is not among those named"),
        (["analytic", "--amplitudes", "0.2,1.5"], "--amplitudes"),
        (["analytic", "--n-impacts", "1"], "--n-impacts: must be at least 2"),
        (["analytic", "--out", "{file}/sub"], "--out"),
    ],
)
def test_bad_input_is_one_line(cli, capsys, tmp_path, argv, message):
    (tmp_path / "file").write_text("")
    argv = [a.replace("{file}", str(tmp_path / "file")) for a in argv]
    if "--out" not in argv:
        argv += ["--out", str(tmp_path / "out")]
    assert cli(["impact-map", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("housner: error:") and message in err, err
    assert not (tmp_path / "out").exists()  # refused before any work


def test_an_engine_not_installed_is_one_line(cli, capsys, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "pydrake", None)  # as if drake were not installed
    assert cli(["impact-map", "analytic", "drake", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "engine 'drake' needs the drake package" in err and "pip install" in err, err


def test_the_command_writes_maps_and_figure(cli, capsys, tmp_path):
    out = tmp_path / "maps"
    assert cli(["impact-map", "analytic", "--amplitudes", "0.05,0.5", "--n-impacts", "3", "--out", str(out), "-q"]) == 0
    printed = capsys.readouterr().out
    assert "r/r_housner" in printed and "1.0000" in printed
    assert (out / "impact-maps.png").stat().st_size > 1000
    m = EngineMaps.from_json((out / "maps-analytic.json").read_text())
    assert m.engine == "housner" and m.amplitudes == (0.05, 0.5)
