"""A scenario names its users' effects files (``plugins``) and its records carry extra channels.

The vertical-table example reads ``ground_acc_vertical`` from the motion: a scenario whose record CSV
has that column runs it on the analytic engine exactly as a direct simulation with the same effect,
and a scenario whose motions lack it is refused by name when it is loaded, before any work.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from housner import GroundMotion
from housner.effects import make_effect
from housner.engines import get_engine
from housner.scenarios import load_scenario, run_scenario
from housner.scenarios.catalogue import ScenarioError
from housner.scenarios.motions import build_motions

ROOT = Path(__file__).resolve().parents[1]
DT = 0.005  # [s] at prototype scale


def _record(path: Path, vertical: bool) -> None:
    t = np.arange(1200) * DT
    env = np.sin(np.pi * t / t[-1]) ** 2
    h = 2.5 * env * np.sin(2 * np.pi * 1.3 * t)  # [m/s^2]: rocks the 0.5 m block, S = 10 below
    v = 4.0 * env * np.sin(2 * np.pi * 2.1 * t + 0.4)  # [m/s^2]: a strong vertical table
    cols = ["time [s]", "ground_acc [m/s^2]"] + (["ground_acc_vertical [m/s^2]"] if vertical else [])
    rows = [f"{a:.4f},{b:.6f}" + (f",{c:.6f}" if vertical else "") for a, b, c in zip(t, h, v, strict=True)]
    path.write_text(",".join(cols) + "\n" + "\n".join(rows) + "\n")


@pytest.fixture(scope="module")
def plugin(tmp_path_factory) -> Path:
    """One copy of the example for the module: another file registering the same effect name is refused."""
    folder = tmp_path_factory.mktemp("plugin")
    shutil.copy(ROOT / "examples" / "effects" / "vertical_table.py", folder / "vertical_table.py")
    return folder / "vertical_table.py"


def _scenario(folder: Path, record: str, plugin: Path | str) -> Path:
    text = f"""name = "vertical"
plugins = ["{plugin}"]

[specimen]
preset = "bachmann2017"

[motions]
source = "record"
record = "{record}"
S = 10

[engines]
names = ["housner"]

[[effects]]
name = "vertical_table"
gain = 1.0
"""
    path = folder / "vertical.toml"
    path.write_text(text)
    return path


def test_a_scenario_runs_a_plugins_effect_on_its_records_channel(tmp_path, plugin):
    _record(tmp_path / "rec.csv", vertical=True)
    scen = load_scenario(_scenario(tmp_path, "rec.csv", plugin))
    (motion,), meta = build_motions(scen)
    assert set(motion.channels) == {"ground_acc_vertical"}
    assert meta["record"]["channels"] == ["ground_acc_vertical"]
    res = run_scenario(scen, out=tmp_path / "run", jobs=1, progress=False, use_cache=False).results
    row = res[res["engine"] == "housner + vertical_table(gain=1)"].iloc[0]
    plain = res[res["engine"] == "housner"].iloc[0]
    direct = get_engine("housner").simulate(scen.specimen, motion, effects=(make_effect("vertical_table", gain=1.0),))
    # the run is the same computation as the direct call: equal to rounding
    assert row["theta_max_over_alpha"] == pytest.approx(direct.theta_max_over_alpha, rel=1e-12)
    # and the channel matters (4 m/s^2 vertically changes the rocking by far more than 1 %)
    assert abs(row["theta_max_over_alpha"] - plain["theta_max_over_alpha"]) > 0.01 * plain["theta_max_over_alpha"]


def test_motions_without_the_channel_are_refused_by_name_at_load(tmp_path, plugin):
    _record(tmp_path / "plain.csv", vertical=False)
    with pytest.raises(
        ScenarioError,
        match=r"effect 'vertical_table' reads the channel 'ground_acc_vertical', "
        r"which record 'plain' does not carry",
    ):
        load_scenario(_scenario(tmp_path, "plain.csv", plugin))
    text = (
        _scenario(tmp_path, "plain.csv", plugin)
        .read_text()
        .replace('source = "record"\nrecord = "plain.csv"', 'source = "rdk"\nn = 2')
    )
    (tmp_path / "rdk.toml").write_text(text)
    with pytest.raises(ScenarioError, match=r"which motions of source 'rdk' do not carry"):
        load_scenario(tmp_path / "rdk.toml")


def test_a_missing_plugin_file_is_one_line_naming_the_scenarios_line(tmp_path):
    _record(tmp_path / "rec.csv", vertical=True)
    (tmp_path / "effects").mkdir()
    path = _scenario(tmp_path, "rec.csv", "effects/nothing_here.py")
    with pytest.raises(ScenarioError) as e:
        load_scenario(path)
    msg = str(e.value)
    assert "\n" not in msg and f"{path} line 2" in msg and "nothing_here.py" in msg


def test_a_csv_records_extra_channels_are_read_in_si(tmp_path):
    p = tmp_path / "r.csv"
    p.write_text(
        "time [s],ground_acc [g],ground_acc_vertical [cm/s^2]\n0,0.1,50\n0.01,0.2,-50\n0.02,0,0\n"
        + "".join(f"{0.01 * k:.2f},0,0\n" for k in range(3, 20))
    )
    g = GroundMotion.from_csv(p)
    assert g.acc[1] == pytest.approx(0.2 * 9.80665)
    assert g.channels["ground_acc_vertical"][:2] == pytest.approx([0.5, -0.5])  # cm/s^2 -> m/s^2


def test_a_copy_of_a_loaded_plugin_replaces_it_and_another_file_may_not_take_its_name(tmp_path, plugin):
    from housner.effects import EFFECTS, load_plugin

    load_plugin(ROOT / "examples" / "effects" / "vertical_table.py")
    assert load_plugin(plugin) == ("vertical_table",)  # byte-identical: the same effect, now from the copy
    assert EFFECTS["vertical_table"].__module__.startswith("housner_plugin_vertical_table_")
    other = tmp_path / "other.py"
    other.write_text(plugin.read_text().replace("share of the recorded", "a share of the recorded"))
    with pytest.raises(ValueError, match="effect name 'vertical_table' is already registered"):
        load_plugin(other)
    assert load_plugin(plugin) == ("vertical_table",)  # the registry was left as it was
