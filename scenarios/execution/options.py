"""How a run executes: :class:`RunOptions`, the one value :func:`~housner.scenarios.execution.runner.run_engines`,
:func:`~housner.scenarios.runs.run.run_scenario`, :func:`~housner.scenarios.studies.study.run_study` and
:func:`~housner.scenarios.runs.spread.seed_spread` take for their execution settings."""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["RunOptions"]


@dataclass(frozen=True)
class RunOptions:
    """Where and how a run's records are simulated, cached and reported; none of it changes a result.

    Every field has a default, so ``RunOptions(jobs=4)`` names only what differs. The
    functions that take ``options`` also take these fields as keywords (``jobs=4``), which
    override ``options``' fields; an unknown keyword is a ``TypeError`` naming it.

    Attributes
    ----------
    jobs : int or None
        Worker processes [count], a positive integer. None (default): one per CPU, except
        where the function says otherwise (:func:`~housner.scenarios.runs.spread.seed_spread`:
        1). 1 runs every record in the calling process.
    scheduler : str or distributed.Client or None
        A Dask distributed scheduler: its address (``"tcp://host:8786"``) or a connected
        ``Client``. The records then run on that cluster, not in local processes (``jobs``
        only sizes the chunks when the cluster cannot say how many threads it has). None
        (default): local processes.
    cache_dir : Path or None
        Folder of the result cache (one entry per record, reused by any later run of the same
        record). None (default): ``$HOUSNER_CACHE_DIR`` or ``~/.cache/housner``.
    use_cache : bool
        Read the cache before simulating and write every record computed (default True).
        False recomputes every record and writes nothing.
    progress : bool
        A progress bar with the estimated time left, on stderr (default True). (Inside the
        library: also a bar of the caller's that spans several runs, advanced and not closed.)
    chunk_size : int or None
        Records sent to a worker at a time [count], a positive integer. None (default):
        about a quarter of each worker's share, at most 10 for an engine that runs record by
        record and 40 for one that batches (the analytic engine). Larger chunks cost less per
        record; a worker that dies loses (recomputes) at most its chunk.
    """

    jobs: int | None = None
    scheduler: str | Any | None = None
    cache_dir: Path | None = None
    use_cache: bool = True
    progress: bool | Any = True
    chunk_size: int | None = None

    def __post_init__(self) -> None:
        for name in ("jobs", "chunk_size"):
            v = getattr(self, name)
            if v is not None and (not isinstance(v, (int, np.integer)) or isinstance(v, (bool, np.bool_)) or v < 1):
                raise ValueError(f"`{name}` must be a positive integer, got {v!r}")
            if v is not None:
                object.__setattr__(self, name, int(v))
        if self.cache_dir is not None:
            if not isinstance(self.cache_dir, (str, os.PathLike)) or not os.fspath(self.cache_dir):
                raise ValueError(f"`cache_dir` must be a folder path, got {self.cache_dir!r}")
            object.__setattr__(self, "cache_dir", Path(self.cache_dir))
        if not isinstance(self.use_cache, (bool, np.bool_)):
            raise ValueError(f"`use_cache` must be True or False, got {self.use_cache!r}")

    def local_jobs(self) -> int:
        """Worker processes [count] a local run starts: ``jobs``, else one per CPU (1: in the calling process)."""
        return self.jobs or os.cpu_count() or 1

    def cache_folder(self) -> Path | None:
        """The result cache's folder: ``cache_dir``, else ``$HOUSNER_CACHE_DIR`` or ``~/.cache/housner``
        (read now); None when ``use_cache`` is False."""
        if not self.use_cache:
            return None
        from housner.scenarios.execution.cache import default_cache_dir  # the cache's module imports the engines

        return self.cache_dir or default_cache_dir()

    def replace(self, **changes: Any) -> RunOptions:
        """A copy with ``changes`` (option name -> value), checked like a new one."""
        return dataclasses.replace(self, **changes)

    @classmethod
    def fields(cls) -> tuple[str, ...]:
        """The names of the options (the keywords the running functions accept for them)."""
        return tuple(f.name for f in dataclasses.fields(cls))

    @classmethod
    def merged(cls, options: RunOptions | None, keywords: dict, where: str) -> RunOptions:
        """``options`` (or the defaults) with ``keywords`` (a caller's ``**execution``) applied over it.

        Parameters
        ----------
        options : RunOptions or None
        keywords : dict
            Option name -> value; any other name raises.
        where : str
            The function's name, for the error.

        Raises
        ------
        TypeError
            A keyword that is not an option (one line, naming it and the options), or
            ``options`` that is not a RunOptions.
        ValueError
            An option's value out of its range (see the attributes).
        """
        if options is not None and not isinstance(options, RunOptions):
            raise TypeError(f"{where}(): `options` must be a RunOptions, got {type(options).__name__}")
        unknown = [k for k in keywords if k not in cls.fields()]
        if unknown:
            raise TypeError(
                f"{where}() got an unexpected keyword argument {unknown[0]!r} "
                f"(execution options: {', '.join(cls.fields())})"
            )
        base = options if options is not None else cls()
        return base.replace(**keywords) if keywords else base
