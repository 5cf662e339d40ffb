"""Running engines on motions: plan -> execute -> table, cached, parallel, fault-tolerant; it never sees a scenario."""

import importlib

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
    "CRASH_ENV": "workers",
    "RunInterrupted": "workers",
    "SchedulerError": "workers",
    "connect_scheduler": "workers",
}


def __getattr__(name: str):
    """A public name, imported from its module on first use."""
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))


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
