"""The scenario catalogue: the shipped scenario files, their schema and the scenario object (runs nothing)."""

from housner.scenarios.catalogue.scenario import Scenario, list_scenarios, load_scenario
from housner.scenarios.catalogue.schema import ScenarioError, effects_label

__all__ = ["Scenario", "ScenarioError", "effects_label", "list_scenarios", "load_scenario"]
