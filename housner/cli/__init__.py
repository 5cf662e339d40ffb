"""The ``housner`` command line: the top layer, above scenarios, engines and reports.

Errors are one line on stderr, ``housner: error: ...``, naming the file, line,
key or argument at fault; ``--debug`` (or ``HOUSNER_DEBUG=1``) adds the
traceback. Inputs and output paths are checked before any simulation.

Exit status: 0 done; 1 a runtime failure (``run``: a record failed, unless
``--allow-failures``; ``tune``: target not met; an unreachable Dask
scheduler; an unexpected error); 2 bad input (arguments, scenario, campaign
or record files, output paths); 130 interrupted by Ctrl-C; 143 terminated (SIGTERM).

Modules: one per subcommand, each with its ``SUMMARY``, its ``add_parser`` and its ``run``
(:mod:`~housner.cli.scenarios`, :mod:`~housner.cli.run`, :mod:`~housner.cli.report`,
:mod:`~housner.cli.tune`, :mod:`~housner.cli.diagnose`, :mod:`~housner.cli.explain`,
:mod:`~housner.cli.frontier`, :mod:`~housner.cli.specimen`, :mod:`~housner.cli.campaign`);
what they share: :mod:`~housner.cli.args` (argument types, input checks, exit statuses),
:mod:`~housner.cli.command` (a subcommand's parser, the exit-status help, ``--plugin``, and what ``explain``
and ``frontier`` share);
:mod:`~housner.cli.app` (the parser, assembling the subcommands in order, and ``main``: plugins, signals,
errors).

This package's own import is light on purpose: the ``housner`` script imports :func:`main` from
here, and every worker process that a run spawns imports the script again (Python's spawn start
method re-imports the main module), so the layers below load when the command runs, not when a
worker starts.
"""

import os

__all__ = ["main"]

# One BLAS thread per process, unless the user asked otherwise, set before numpy loads OpenBLAS. The suite's
# matrices have a few rows and its parallelism is its worker processes and numba's kernels; once numba's
# OpenMP threads exist, OpenBLAS's own threads fight them for the cores, and scipy's expm of 300 4 x 4
# matrices (the report's response spectra, the run's band check) took 2.3 s instead of 1 ms on 2 cores.
# Same numbers either way (checked bit for bit on the spectra's coefficients and a run's results).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``housner`` command; returns the exit status (see :mod:`housner.cli.app`)."""
    from housner.cli.app import main as run  # lazy: spawned workers re-import the entry point (see above)

    return run(argv)
