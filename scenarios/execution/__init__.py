"""Running engines on motions: plan -> execute -> table, cached, parallel, fault-tolerant; it never sees a scenario."""

from housner.scenarios.execution.cache import cache_key, default_cache_dir
from housner.scenarios.execution.options import RunOptions
from housner.scenarios.execution.rundir import RESULT_COLUMNS, RUN_FILES, load_results, provenance, write_run
from housner.scenarios.execution.runner import run_engines
from housner.scenarios.execution.tables import compare_engines, percentile_table
from housner.scenarios.execution.workers import CRASH_ENV, RunInterrupted, SchedulerError, connect_scheduler

__all__ = [
    "CRASH_ENV",
    "RESULT_COLUMNS",
    "RUN_FILES",
    "RunInterrupted",
    "RunOptions",
    "SchedulerError",
    "cache_key",
    "compare_engines",
    "connect_scheduler",
    "default_cache_dir",
    "load_results",
    "percentile_table",
    "provenance",
    "run_engines",
    "write_run",
]
