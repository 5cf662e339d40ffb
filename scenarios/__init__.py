"""Scenarios: what to run (the catalogue), on which motions, how (execution), and what it means.

The public entry points of the layer; each sub-package's ``__init__`` is its own face:

- :mod:`~housner.scenarios.catalogue`: scenario files and their schema (declarative: runs nothing);
- :mod:`~housner.scenarios.motions`: records, RDK and matched models, bands, elastic spectra;
- :mod:`~housner.scenarios.execution`: ``run_engines`` (plan, execute, table), workers, cache, run directory;
- :mod:`~housner.scenarios.runs`: a scenario's run and its analyses (Table 2 spread, chaos floor);
- :mod:`~housner.scenarios.studies`: stripes x sizes x engines -> fragility with intervals;
- :mod:`~housner.scenarios.campaigns`: measured data: the format, the records, the ASU importer;
- :mod:`~housner.scenarios.diagnosis`: comparison, localisation, forward selection, verdict, outcome scoring.
"""

if __name__ != "housner.scenarios":  # this folder imported by its own name, from a checkout's root
    raise ImportError(f"`{__name__}` is not an import name of this project: import `housner.scenarios`")

from housner._lazy import lazy_exports

#: Each public name -> the sub-package that defines it. They are imported when first used (PEP 562), not
#: with the package: a worker process that runs records needs ``execution`` only, and importing
#: ``diagnosis`` with it cost each worker 1.4 of its 1.5 s of imports.
_EXPORTS = {
    "Campaign": "campaigns",
    "compare": "diagnosis",
    "diagnose": "diagnosis",
    "load_campaign": "campaigns",
    "Scenario": "catalogue",
    "list_scenarios": "catalogue",
    "load_scenario": "catalogue",
    "RunOptions": "execution",
    "compare_engines": "execution",
    "load_results": "execution",
    "run_engines": "execution",
    "RunResult": "runs",
    "run_scenario": "runs",
    "load_study": "studies",
    "run_study": "studies",
}


__getattr__, __dir__ = lazy_exports(
    __name__,
    _EXPORTS,
    globals(),
    submodules=("campaigns", "catalogue", "diagnosis", "execution", "motions", "runs", "studies"),
)

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
