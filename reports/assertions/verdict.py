"""An engine's one verdict, asserted in users' CI: the same verdict the report's first screen and ``housner run``
give (:mod:`housner.scenarios.runs.verdicts`).

Typical use, in a test file of the user's project::

    from housner.reports.assertions.verdict import assert_verdict

    def test_mujoco_stands_in_for_housner(housner_results):  # fixture of housner.reports.pytest_plugin
        assert_verdict(housner_results, "mujoco", at_least="ensemble")

``at_least="agrees"`` also asks that the engine agree record by record, at the chaos floor.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from housner.errors import unknown_choice
from housner.scenarios.execution.rundir import RESULTS_FILE
from housner.scenarios.runs.verdicts import KINDS, EngineVerdict

__all__ = ["VerdictError", "assert_verdict"]

#: The verdicts an assertion may ask for, the stricter first.
LEVELS = ("agrees", "ensemble")


class VerdictError(AssertionError):
    """An engine's verdict is below the one asked for (an AssertionError: pytest reports it as a failed test).

    Attributes
    ----------
    verdict : EngineVerdict
        The verdict found.
    """

    def __init__(self, message: str, verdict: EngineVerdict):
        self.verdict = verdict
        super().__init__(message)


def _run_dir(results) -> Path:
    """The run directory behind ``results``: a folder, a results.parquet path, the fixture's DataFrame (its
    ``attrs["source"]``) or the runner's RunResult (its ``out``)."""
    if isinstance(results, (str, Path)):
        p = Path(results)
        return p.parent if p.name == RESULTS_FILE else p
    if isinstance(getattr(results, "results", None), pd.DataFrame) and getattr(results, "out", None) is not None:
        return Path(results.out)
    if isinstance(results, pd.DataFrame) and results.attrs.get("source"):
        return Path(results.attrs["source"]).parent
    raise ValueError(
        "`results` must be a run directory, its results.parquet, the housner_results fixture or the runner's "
        f"RunResult (the verdict needs the run's motions for its chaos floor), got {type(results).__name__}"
    )


def assert_verdict(results, engine: str = "mujoco", *, at_least: str = "ensemble") -> EngineVerdict:
    """Assert that ``engine``'s verdict against the run's reference is at least ``at_least``.

    Parameters
    ----------
    results : str, Path, DataFrame or RunResult
        The run: its directory, its ``results.parquet``, the ``housner_results`` fixture's table, or
        :func:`housner.scenarios.runs.run_scenario`'s result.
    engine : str
        The engine judged.
    at_least : {"ensemble", "agrees"}
        ``"ensemble"``: its distribution of peak rotations must agree (verdict ENSEMBLE ONLY or AGREES);
        ``"agrees"``: it must also agree record by record, at the chaos floor (AGREES).

    Returns
    -------
    EngineVerdict
        The verdict, when it holds.

    Raises
    ------
    VerdictError
        The verdict is below ``at_least`` (FAILS, INCONCLUSIVE, NO DATA, or ENSEMBLE ONLY where AGREES was asked);
        the message is the verdict's sentence and every figure behind it.
    ValueError
        ``at_least`` or ``engine`` is not one of the choices, or ``results`` does not lead to a run directory.
    """
    from housner.scenarios.runs.view import Run  # the view reads the whole run: imported when asked

    if at_least not in LEVELS:
        raise unknown_choice("verdict level `at_least`", at_least, LEVELS)
    run = Run.load(_run_dir(results))
    verdicts = run.verdicts()
    if engine not in verdicts:
        raise unknown_choice("engine with a verdict in this run", engine, sorted(verdicts))
    v = verdicts[engine]
    allowed = LEVELS[: LEVELS.index(at_least) + 1]
    if v.kind not in allowed:
        raise VerdictError(
            f"{engine} against {run.reference}: {v.line()} (asked: at least {KINDS[at_least][0]})\n  {v.figures()}",
            v,
        )
    return v
