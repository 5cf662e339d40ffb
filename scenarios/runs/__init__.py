"""A scenario's run and its analyses: the spread of Table 2 over independent ensembles, the chaos floor."""

from housner.scenarios.runs.chaos import chaos_floor
from housner.scenarios.runs.run import RunResult, effects_series, run_scenario
from housner.scenarios.runs.spread import seed_spread

__all__ = ["RunResult", "chaos_floor", "effects_series", "run_scenario", "seed_spread"]
