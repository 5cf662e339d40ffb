"""A scenario's run and its analyses: the run directory read back with each engine's verdict, the spread of
Table 2 over independent ensembles, the chaos floor, an engine explained by the diagnosis of its own responses,
and its accuracy-cost frontier."""

from housner.scenarios.runs.chaos import chaos_floor
from housner.scenarios.runs.engine_campaign import export_engine_campaign
from housner.scenarios.runs.explain import Explanation, explain_engine
from housner.scenarios.runs.frontier import Frontier, engine_frontier
from housner.scenarios.runs.run import RunResult, effects_series, run_scenario
from housner.scenarios.runs.spread import seed_spread
from housner.scenarios.runs.verdicts import EngineVerdict, engine_verdict
from housner.scenarios.runs.view import Run

__all__ = [
    "EngineVerdict",
    "Explanation",
    "Frontier",
    "Run",
    "RunResult",
    "chaos_floor",
    "effects_series",
    "engine_frontier",
    "engine_verdict",
    "explain_engine",
    "export_engine_campaign",
    "run_scenario",
    "seed_spread",
]
