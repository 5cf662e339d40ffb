"""Scenario files: the shipped catalogue loads; bad files get helpful errors."""

import pytest

from housner.cli import main
from housner.scenarios.catalogue import ScenarioError
from housner.scenarios.catalogue.scenario import SCENARIOS, load_scenario


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_shipped_scenarios_load(name):
    s = load_scenario(name)
    assert s.name == name
    assert s.n_motions > 0
    assert s.engines


def test_elcentro_is_the_seed_study():
    s = load_scenario("elcentro")
    assert s.specimen.p == pytest.approx(4.8883)
    assert s.S == pytest.approx(10.0)  # 5 m prototype / 0.5 m model (seed section 4)
    assert s.n_motions == 100
    assert s.seed is not None


def write(tmp_path, text):
    p = tmp_path / "s.toml"
    p.write_text(text)
    return p


BASE = """
name = "x"
[specimen]
preset = "bachmann2017"
[motions]
source = "free_vibration"
theta0_over_alpha = [0.5]
"""


def test_unknown_key_suggests_closest(tmp_path):
    p = write(tmp_path, BASE.replace("[motions]", "[motions]\nduraton = 3.0"))
    with pytest.raises(ScenarioError, match=r"unknown key \[motions\] 'duraton'; did you mean 'duration'\?"):
        load_scenario(p)


def test_unknown_engine_lists_choices(tmp_path):
    p = write(tmp_path, BASE + '[engines]\nnames = ["mujoko"]\n')
    with pytest.raises(ScenarioError, match=r"unknown engine 'mujoko'; did you mean 'mujoco'\?.*choices:.*housner"):
        load_scenario(p)


def test_bad_values_named(tmp_path):
    with pytest.raises(ScenarioError, match=r"theta0_over_alpha.*\(0, 1\)"):
        load_scenario(write(tmp_path, BASE.replace("[0.5]", "[1.5]")))
    with pytest.raises(ScenarioError, match=r"\[specimen\] `mass` must be positive"):
        load_scenario(write(tmp_path, BASE.replace('preset = "bachmann2017"', "height=1\nwidth=0.2\ndepth=1\nmass=-1")))
    with pytest.raises(ScenarioError, match=r"unknown source 'rdkk'; did you mean 'rdk'\?"):
        load_scenario(write(tmp_path, BASE.replace('"free_vibration"', '"rdkk"')))
    with pytest.raises(ScenarioError, match="invalid TOML"):
        load_scenario(write(tmp_path, "name = "))


def test_cli_unknown_scenario(capsys):
    assert main(["run", "elcentr"]) == 2
    err = capsys.readouterr().err
    assert "did you mean 'elcentro'?" in err


def test_cli_lists_scenarios(capsys):
    assert main(["scenarios"]) == 0
    out = capsys.readouterr().out
    for name in SCENARIOS:
        assert name in out
