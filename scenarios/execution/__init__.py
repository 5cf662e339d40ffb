"""Running engines on motions: plan -> execute -> table, cached, parallel, fault-tolerant; it never sees a scenario."""

from housner._lazy import lazy_exports

#: Each public name -> its module, imported on first use (PEP 562): a worker process loads ``chunks``
#: alone (the standard library and numpy), not the runner, the scenario schema and the motion models.
_EXPORTS = {
    "cache_key": "cache",
    "default_cache_dir": "cache",
    "RunOptions": "options",
    "RESULT_COLUMNS": "rundir",
    "RUN_FILES": "rundir",
    "load_results": "rundir",
    "provenance": "rundir",
    "write_run": "rundir",
    "run_engines": "runner",
    "compare_engines": "tables",
    "percentile_table": "tables",
    "CRASH_ENV": "chunks",
    "RunInterrupted": "workers",
    "SchedulerError": "cluster",
    "connect_scheduler": "cluster",
}


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())

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
