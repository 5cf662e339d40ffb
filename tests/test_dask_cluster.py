"""``housner run --scheduler`` against a real Dask cluster, started from the command line on loopback.

A scheduler and two single-thread workers are started as a user starts them (``dask scheduler``,
``dask worker``, each worker with its nanny and in a session of its own, so that a whole worker can be
killed at once). ``housner run`` then runs as a user runs it, in a process of its own: it has no
default client, which the in-process tests (``test_runner``, ``test_study``) cannot see, since they
open one. The cluster's results must equal a local run of the same command: the same code runs the
same record, so ``ATOL`` allows only for another machine's arithmetic, not for another method.
"""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from shared import run_command

distributed = pytest.importorskip("distributed", reason="the Dask cluster tests need dask[distributed]")
pytest.importorskip("distributed.cli.dask_scheduler", reason="no `dask scheduler` command (distributed.cli)")

N_MOTIONS = 12
#: theta_max/alpha of a record on the cluster against the same record run locally [dimensionless].
ATOL = 1e-12
#: Seconds for the cluster to start, and for one `housner run` to finish.
START_S, RUN_S = 60, 120
COLUMNS = ["engine", "motion_id", "motion_name", "status", "theta_max_over_alpha", "overturned", "n_impacts"]


def _cmd(out: Path, scheduler: str | None = None) -> list[str]:
    cmd = run_command(out, "housner", N_MOTIONS, "--no-cache", "--no-report")
    return cmd + (["--scheduler", scheduler] if scheduler else [])


def _env(tmp: Path, **extra: str) -> dict:
    return dict(os.environ, HOUSNER_CACHE_DIR=str(tmp / "cache"), DASK_TEMPORARY_DIRECTORY=str(tmp / "dask"), **extra)


def _timed_run(cmd: list[str], tmp: Path) -> tuple[subprocess.CompletedProcess, float]:
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=_env(tmp), cwd=tmp, capture_output=True, text=True, timeout=RUN_S)
    return proc, time.perf_counter() - t0


def _results(out: Path) -> pd.DataFrame:
    return pd.read_parquet(out / "results.parquet")[COLUMNS]


def _elapsed(out: Path) -> float:
    """The simulation's own wall time [s] (run.json): without the command's start and its writing."""
    return json.loads((out / "run.json").read_text())["engines"]["housner"]["elapsed_s"]


def _assert_equal_runs(got: pd.DataFrame, ref: pd.DataFrame) -> None:
    assert list(got.motion_id) == list(range(N_MOTIONS))  # every record, once
    assert (got.status == "ok").all(), got[got.status != "ok"].to_string()
    pd.testing.assert_frame_equal(got.drop(columns="theta_max_over_alpha"), ref.drop(columns="theta_max_over_alpha"))
    np.testing.assert_allclose(got.theta_max_over_alpha, ref.theta_max_over_alpha, rtol=0, atol=ATOL)


@pytest.fixture(scope="module")
def local_run(tmp_path_factory):
    """The same command without a scheduler (worker processes on this machine): the reference, and its times."""
    tmp = tmp_path_factory.mktemp("local")
    proc, wall = _timed_run(_cmd(tmp / "run"), tmp)
    assert proc.returncode == 0, proc.stderr
    return _results(tmp / "run"), wall, _elapsed(tmp / "run")


class Cluster:
    """A scheduler and its workers, each a process group of its own, every server on 127.0.0.1 and a free
    port; ``client`` watches the cluster (never a default client: ``housner run`` must do without one)."""

    def __init__(self, tmp: Path, n_workers: int = 2, **config: str):
        self.tmp = tmp
        self.n_workers = n_workers
        self.config = config  # Dask settings for every process, as DASK_... environment variables
        self.procs: list[subprocess.Popen] = []
        self.workers: list[subprocess.Popen] = []
        self.client = None

    def start(self) -> None:
        """Start the scheduler, then the workers; return once every worker has joined."""
        file = self.tmp / "scheduler.json"
        loopback = ["--host", "127.0.0.1", "--no-dashboard", "--dashboard-address", "127.0.0.1:0"]  # /health too
        scheduler = self._start("scheduler", "dask_scheduler", *loopback, "--port", "0", "--scheduler-file", str(file))
        deadline = time.monotonic() + START_S
        while not file.exists() and scheduler.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        if not file.exists():
            raise RuntimeError(f"the scheduler did not start:\n{self.log('scheduler')}")
        self.address = json.loads(file.read_text())["address"]
        for k in range(self.n_workers):
            self.workers.append(
                self._start(
                    f"worker{k}",
                    "dask_worker",
                    *loopback,
                    "--scheduler-file",
                    str(file),
                    "--nthreads",
                    "1",
                    "--nworkers",
                    "1",
                    "--death-timeout",
                    "60",
                    "--local-directory",
                    str(self.tmp / f"worker{k}"),
                )
            )
        self.client = distributed.Client(self.address, set_as_default=False, timeout=START_S)
        self.client.wait_for_workers(self.n_workers, timeout=START_S)
        self.pids = self.client.run(os.getpid)  # worker address -> its process (the nanny's child)

    def _start(self, name: str, cli: str, *args: str) -> subprocess.Popen:
        with open(self.tmp / f"{name}.log", "w") as log:
            p = subprocess.Popen(
                [sys.executable, "-m", f"distributed.cli.{cli}", *args],
                cwd=self.tmp,
                env=_env(self.tmp, **self.config),
                stdout=log,
                stderr=subprocess.STDOUT,
                start_new_session=True,
            )
        self.procs.append(p)
        return p

    def log(self, name: str) -> str:
        return (self.tmp / f"{name}.log").read_text()

    def worker_of(self, address: str) -> subprocess.Popen:
        """The ``dask worker`` process (its nanny, whose process group holds the worker) serving ``address``."""
        pgid = os.getpgid(self.pids[address])
        return next(p for p in self.workers if p.pid == pgid)

    def kill(self, address: str) -> subprocess.Popen:
        """Kill the worker at ``address``, nanny and all, with SIGKILL: as if its machine went."""
        p = self.worker_of(address)
        os.killpg(p.pid, signal.SIGKILL)
        return p

    def close(self) -> None:
        if self.client is not None:
            self.client.close(timeout=5)
        for p in reversed(self.procs):  # workers first, then the scheduler
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGKILL)
            p.wait(timeout=10)


def _cluster(tmp: Path, **config: str):
    c = Cluster(tmp, **config)
    try:
        try:
            c.start()
        except OSError as e:  # no processes, no loopback sockets: this machine cannot host a cluster
            pytest.skip(f"cannot start a Dask cluster on 127.0.0.1 here: {type(e).__name__}: {e}")
        yield c
    finally:
        c.close()


@pytest.fixture
def cluster(tmp_path):
    """A scheduler with Dask's default settings, and two workers."""
    yield from _cluster(tmp_path)


@pytest.fixture
def unforgiving_cluster(tmp_path):
    """A scheduler that gives a task up the first time a worker dies running it, and two workers."""
    yield from _cluster(tmp_path, DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES="0")


def _start_run(cluster: Cluster, tmp: Path) -> subprocess.Popen:
    return subprocess.Popen(
        _cmd(tmp / "run", cluster.address),
        env=_env(tmp),
        cwd=tmp,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _kill_a_busy_worker(cluster: Cluster, run: subprocess.Popen) -> tuple[str, list, subprocess.Popen]:
    """Once ``run`` has begun (a worker holds its tasks), kill that worker; its address, the tasks it held
    and its process."""
    deadline, busy = time.monotonic() + RUN_S, {}
    while not busy and run.poll() is None and time.monotonic() < deadline:
        busy = {w: ts for w, ts in cluster.client.processing().items() if ts}
        time.sleep(0.01)
    assert busy and run.poll() is None, "the run ended, or never began, before a worker could be killed"
    address, held = next(iter(busy.items()))
    return address, list(held), cluster.kill(address)


def _finish(run: subprocess.Popen) -> tuple[str, str]:
    try:
        return run.communicate(timeout=RUN_S)
    finally:
        if run.poll() is None:
            run.kill()
            run.wait(timeout=10)


def test_run_on_a_cluster_equals_a_local_run(local_run, cluster, tmp_path):
    ref, local_wall, local_sim = local_run
    times = {}
    for what in ("cold", "warm"):  # the second run finds the engines imported in the workers
        out = tmp_path / what
        proc, wall = _timed_run(_cmd(out, cluster.address), tmp_path)
        assert proc.returncode == 0, proc.stderr
        assert "Traceback" not in proc.stderr
        assert f"{N_MOTIONS}/{N_MOTIONS} ok" in proc.stdout
        _assert_equal_runs(_results(out), ref)
        times[what] = (wall, _elapsed(out))
    # Both workers ran records: the run was spread over the cluster.
    ran = cluster.client.run(lambda dask_worker: dask_worker.state.executed_count)
    assert len(ran) == 2 and all(n > 0 for n in ran.values()), ran
    print(
        f"\n`housner run elcentro --engines housner --n-motions {N_MOTIONS} --no-cache` [s], command (simulation): "
        f"local {local_wall:.2f} ({local_sim:.3f}); 2 Dask workers, cold {times['cold'][0]:.2f} "
        f"({times['cold'][1]:.3f}), warm {times['warm'][0]:.2f} ({times['warm'][1]:.3f})"
    )


def test_a_worker_killed_mid_run_loses_nothing(local_run, cluster, tmp_path):
    with distributed.get_task_stream(client=cluster.client) as stream:  # every task the cluster runs
        run = _start_run(cluster, tmp_path)
        try:
            victim, held, proc = _kill_a_busy_worker(cluster, run)
            t_kill = time.perf_counter()
        finally:
            out, err = _finish(run)
    print(
        f"\nkilled the worker at {victim} holding {len(held)} task(s); the run ended "
        f"{time.perf_counter() - t_kill:.2f} s later; housner's output:\n{out}{err}"
    )
    assert proc.wait(timeout=10) == -signal.SIGKILL
    assert run.returncode == 0, err
    assert "Traceback" not in err
    assert f"{N_MOTIONS}/{N_MOTIONS} ok" in out
    _assert_equal_runs(_results(tmp_path / "run"), local_run[0])
    # The tasks the dead worker held were run to the end by the other one.
    finished = {t["key"]: t["worker"] for t in stream.data if t.get("status") == "OK"}
    assert all(finished.get(k) not in (None, victim) for k in held), (held, finished)
    assert f"Remove worker addr: {victim}" in cluster.log("scheduler")


def test_a_task_whose_workers_die_fails_its_records_by_name(local_run, unforgiving_cluster, tmp_path):
    # With allowed-failures 0 the scheduler gives a task up at its worker's first death: its records are
    # listed as failed, with the reason, and every other record is kept, equal to the local run.
    cluster = unforgiving_cluster
    run = _start_run(cluster, tmp_path)
    try:
        victim, held, _ = _kill_a_busy_worker(cluster, run)
    finally:
        out, err = _finish(run)
    print(f"\nkilled the worker at {victim} holding {len(held)} task(s); housner's output:\n{out}{err}")
    assert run.returncode == 1, err  # records failed, without --allow-failures
    assert "Traceback" not in err
    got = _results(tmp_path / "run").join(pd.read_parquet(tmp_path / "run" / "results.parquet").error)
    assert list(got.motion_id) == list(range(N_MOTIONS))  # every record has its row
    failed, ok = got[got.status != "ok"], got[got.status == "ok"]
    assert len(failed) >= 1
    why = "KilledWorker: the Dask workers running it died 1 time(s), all that the scheduler allows"
    assert failed.error.str.startswith(why).all(), failed.error.tolist()
    for r in failed.itertuples():
        assert f"housner motion {r.motion_id} ({r.motion_name}): KilledWorker" in err
    ref = local_run[0].set_index("motion_id").loc[ok.motion_id]
    np.testing.assert_allclose(ok.theta_max_over_alpha, ref.theta_max_over_alpha, rtol=0, atol=ATOL)
