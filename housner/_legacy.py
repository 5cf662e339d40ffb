"""The import names of 0.1 (``engines``, ``scenarios``, ``reports``), kept for one release.

Since 0.2 the project installs one import name, ``housner``; its layers are ``housner.engines``,
``housner.scenarios`` and ``housner.reports``, and the scenarios are packages of one concept each.
:func:`install` (run by ``import housner``) puts a finder first on ``sys.meta_path`` that answers
an old module name with the module that now holds it, under a ``FutureWarning`` naming the new
one (``FutureWarning``, not ``DeprecationWarning``, because Python hides the latter in users'
scripts). A package of the same name that a user has on ``sys.path`` wins: the finder only answers
when no other ``engines``, ``scenarios`` or ``reports`` is importable, or when the one found is this
repository's own folder. This module imports nothing of the project, so ``import housner`` stays light.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import sys
import types
import warnings
from pathlib import Path

_S = {
    "catalogue": "catalogue.scenario", "schema": "catalogue.schema",
    "records": "motions.records", "rdk": "motions.rdk", "rdk_envelope": "motions.rdk_envelope",
    "rdk_match": "motions.rdk_match", "bands": "motions.bands", "elastic": "motions.elastic",
    "workers": "execution.workers", "cache": "execution.cache", "rundir": "execution.rundir",
    "tables": "execution.tables", "_outputs": "execution.outputs",
    "analysis": "runs.spread", "chaos": "runs.chaos", "study": "studies.study", "fragility": "studies.fragility",
    "campaign": "campaigns.campaign", "compare": "campaigns.compare", "history_error": "campaigns.history_error",
    "localise": "campaigns.localise", "fitting": "campaigns.fitting", "scoring": "campaigns.scoring",
    "diagnose": "campaigns.diagnose", "verdict": "campaigns.verdict", "model_form": "campaigns.model_form",
    "probes": "campaigns.probes", "diagnosis_results": "campaigns.results",
}  # fmt: skip
_R = {
    "html": "run.page", "run_view": "run.view", "ground_figures": "run.ground_figures", "sections": "run.sections",
    "study_report": "study.page", "study_figures": "study.figures", "assertions": "assertions",
    "study_assertions": "assertions.studies", "pytest_plugin": "pytest_plugin",
}  # fmt: skip

#: 0.1 module -> its 0.2 module (or the modules whose names it gathered, for the split runner).
MOVED: dict[str, str | tuple[str, ...]] = {
    "engines": "housner.engines",
    "scenarios": "housner.scenarios",
    "reports": "housner.reports",
    "reports.cli": "housner.cli",
    "scenarios.runner": (
        "housner.scenarios.execution.runner",
        "housner.scenarios.runs.run",
        "housner.scenarios.execution.workers",
        "housner.scenarios.execution.cache",
        "housner.scenarios.execution.rundir",
    ),
    **{f"scenarios.{k}": f"housner.scenarios.{v}" for k, v in _S.items()},
    **{f"reports.{k}": f"housner.reports.{v}" for k, v in _R.items()},
}
_TOP = ("engines", "scenarios", "reports")
#: A checkout's root (in a wheel: site-packages, which has no such folders).
_REPO = Path(__file__).resolve().parent.parent


def new_name(old: str) -> str | tuple[str, ...] | None:
    """The 0.2 module of a 0.1 module name; None when ``old`` was not one of the project's modules."""
    if old in MOVED:
        return MOVED[old]
    head = old.rpartition(".")[0]
    while head:  # a module under a moved package: reports.sections.tuning -> housner.reports.run.sections.tuning
        if head in MOVED and isinstance(MOVED[head], str):
            return f"{MOVED[head]}.{old[len(head) + 1:]}"
        head = head.rpartition(".")[0]
    return None


def _users_own(name: str) -> bool:
    """True when a package ``name`` that is not this repository's folder is importable from sys.path."""
    spec = importlib.machinery.PathFinder.find_spec(name)
    if spec is None:
        return False
    where = Path(spec.origin or list(spec.submodule_search_locations or [""])[0]).resolve()
    ours = _REPO / name
    return where != ours and ours not in where.parents


def _caller_level() -> int:
    """The stack level of the first frame outside the import machinery (so the warning names the user's line)."""
    f, level = sys._getframe(1), 1
    while f is not None and ("importlib" in f.f_code.co_filename or f.f_code.co_filename == __file__):
        f, level = f.f_back, level + 1
    return level


class _OldNames(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    def find_spec(self, fullname, path=None, target=None):
        if fullname.partition(".")[0] not in _TOP or new_name(fullname) is None:
            return None
        if "." not in fullname and _users_own(fullname):
            return None
        return importlib.util.spec_from_loader(fullname, self)

    def create_module(self, spec):
        new = new_name(spec.name)
        shown = new if isinstance(new, str) else " and ".join(new)
        warnings.warn(
            f"`{spec.name}` is now `{shown}`: the old import name goes in housner 0.3",
            FutureWarning,
            stacklevel=_caller_level(),
        )
        if spec.name in _TOP:
            return _package(spec.name)
        if isinstance(new, str):
            return importlib.import_module(new)
        merged = types.ModuleType(spec.name, f"0.1's {spec.name}, gathered from {shown}")
        for name in new:
            m = importlib.import_module(name)
            merged.__dict__.update({k: v for k, v in vars(m).items() if not k.startswith("__")})
        return merged

    def exec_module(self, module):
        pass  # the module is the 0.2 one, already executed


def _package(name: str) -> types.ModuleType:
    """A 0.1 top-level package: its old submodules by attribute (``from scenarios import rdk``), the rest from 0.2's."""
    new = importlib.import_module(MOVED[name])
    pkg = types.ModuleType(name, new.__doc__)
    pkg.__path__ = []  # a package: its submodules come from the finder

    def __getattr__(attr: str):
        if f"{name}.{attr}" in MOVED:
            return importlib.import_module(f"{name}.{attr}")
        return getattr(new, attr)

    pkg.__getattr__ = __getattr__
    return pkg


_FINDER = _OldNames()


def install() -> None:
    """Answer the 0.1 names (idempotent)."""
    if _FINDER not in sys.meta_path:
        sys.meta_path.insert(0, _FINDER)


def become(name: str) -> None:
    """Called by a checkout's ``engines``/``scenarios``/``reports`` folder imported under its 0.1 top-level name.

    Replaces that module in ``sys.modules`` by its 0.2 package, so that the names resolve to one
    module each, and installs the finder for the submodules.
    """
    install()
    new = new_name(name)
    warnings.warn(f"`{name}` is now `{new}`: the old import name goes in housner 0.3", FutureWarning, stacklevel=3)
    sys.modules[name] = _package(name)
