"""Scenarios: what to run (the catalogue), on which motions, how (execution), and what it means.

The public entry points of the layer; each sub-package's ``__init__`` is its own face:

- :mod:`~housner.scenarios.catalogue`: scenario files and their schema (declarative: runs nothing);
- :mod:`~housner.scenarios.motions`: records, RDK and matched models, bands, elastic spectra;
- :mod:`~housner.scenarios.execution`: ``run_engines`` (plan, execute, table), workers, cache, run directory;
- :mod:`~housner.scenarios.runs`: a scenario's run and its analyses (Table 2 spread, chaos floor);
- :mod:`~housner.scenarios.studies`: stripes x sizes x engines -> fragility with intervals;
- :mod:`~housner.scenarios.campaigns`: measured data, comparison, localisation, diagnosis, verdict.
"""

if __name__ != "housner.scenarios":  # this folder imported by its 0.1 name from a checkout
    from housner._legacy import become

    become(__name__)

from housner.scenarios.campaigns import Campaign, compare, diagnose, load_campaign
from housner.scenarios.catalogue import Scenario, list_scenarios, load_scenario
from housner.scenarios.execution import RunOptions, compare_engines, load_results, run_engines
from housner.scenarios.runs import RunResult, run_scenario
from housner.scenarios.studies import load_study, run_study

__all__ = [
    "Campaign",
    "RunResult",
    "RunOptions",
    "Scenario",
    "compare",
    "compare_engines",
    "diagnose",
    "list_scenarios",
    "load_campaign",
    "load_results",
    "load_scenario",
    "load_study",
    "run_engines",
    "run_scenario",
    "run_study",
]
