"""pytest plugin: hand a run's results table to users' tests.

Installed with the package (entry point ``pytest11``), it adds

* the command-line option ``--housner-results PATH`` (a run directory or its
  ``results.parquet``), also read from the ``HOUSNER_RESULTS`` environment
  variable or the ``housner_results`` ini option, in that order of precedence;
* the fixture ``housner_results``: the results table as a pandas DataFrame
  (see :func:`housner.reports.assertions.runs.load_results`), a fresh copy for every test;
  a test that uses it is skipped, with a message saying how to give a path,
  when no path is given;
* the fixture ``housner_results_factory``: a function ``load(path=None)``
  that loads any results table (cached for the session), for tests that
  compare several runs.

Example::

    # test_engines.py, run with: pytest --housner-results runs/elcentro
    from housner.reports.assertions import assert_cdf_agreement

    def test_mujoco(housner_results):
        assert_cdf_agreement(housner_results, "mujoco", "housner", percentiles={50: 0.1})

The plugin is loaded by every pytest session of a user who installs the
package, so importing it costs nothing: pandas and the statistics are imported
only when a fixture is used.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

__all__ = ["ENV_VAR", "OPTION", "configured_path"]

#: Environment variable naming the results to load.
ENV_VAR = "HOUSNER_RESULTS"
#: Command-line option naming the results to load.
OPTION = "--housner-results"
_INI = "housner_results"


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("housner", "housner: results of engine runs for tolerance assertions")
    group.addoption(
        OPTION,
        action="store",
        dest="housner_results",
        default=None,
        metavar="PATH",
        help=f"run directory or results.parquet for the `housner_results` fixture (else ${ENV_VAR}).",
    )
    parser.addini(_INI, help="default run directory or results.parquet for the `housner_results` fixture.")


def configured_path(config: pytest.Config) -> Path | None:
    """The results path given to this session (option, then environment, then ini), or None.

    Relative paths on the command line or in the environment are taken from
    the directory pytest was invoked in; in the ini file, from the rootdir.
    """
    value = config.getoption("housner_results", default=None)
    base = Path(config.invocation_params.dir)
    if not value:
        value = os.environ.get(ENV_VAR) or None
    if not value:
        value = config.getini(_INI) or None
        base = Path(config.rootpath)
    if not value:
        return None
    path = Path(str(value)).expanduser()
    return path if path.is_absolute() else base / path


def pytest_report_header(config: pytest.Config) -> str | None:
    path = configured_path(config)
    return f"housner results: {path}" if path is not None else None


class _Loader:
    """Loads results tables once per session."""

    def __init__(self, default: Path | None):
        self.default = default
        self._cache: dict[Path, object] = {}

    def __call__(self, path: str | os.PathLike | None = None):
        """The results table at ``path`` (default: the session's), a fresh copy each call."""
        if path is None:
            if self.default is None:
                _skip_no_path()
            path = self.default
        from housner.scenarios.execution.rundir import load_results  # lazy: this plugin loads in every pytest session

        key = Path(path).expanduser().resolve()
        if key not in self._cache:
            self._cache[key] = load_results(key)
        return self._cache[key].copy()


def _skip_no_path() -> None:
    pytest.skip(
        f"no housner results given: pass {OPTION} PATH (a run directory or its results.parquet), "
        f"or set {ENV_VAR}=PATH, or `{_INI} = PATH` in the pytest ini options"
    )


@pytest.fixture(scope="session")
def housner_results_factory(pytestconfig: pytest.Config) -> _Loader:
    """A function ``load(path=None) -> DataFrame`` for results tables; ``None`` loads the session's."""
    return _Loader(configured_path(pytestconfig))


@pytest.fixture
def housner_results(housner_results_factory: _Loader):
    """The results table given by ``--housner-results`` / ``$HOUSNER_RESULTS``, as a DataFrame.

    Skips the test when no path was given; a path that does not exist or is
    not a results table is an error (``housner.errors.DataFileError``).
    """
    return housner_results_factory()
