"""Where the runner's records run on a Dask cluster: the connection to its scheduler, and the chunks sent to it.

The chunks are those of the process pool (:class:`~housner.scenarios.execution.workers.Chunk`),
run by :func:`~housner.scenarios.execution.chunks.run_chunk` on the cluster's workers; the
results come back in bulk, one packed set per chunk, and the caller stores the cache entries.
"""

from __future__ import annotations

import asyncio
from typing import Any

from housner.scenarios.execution.chunks import run_chunk, unpack
from housner.scenarios.execution.workers import Chunk, failed_record
from housner.specimen import Specimen

__all__ = ["SCHEDULER_TIMEOUT_S", "SchedulerError", "connect_scheduler", "run_dask"]


class SchedulerError(ConnectionError):
    """The Dask scheduler cannot be reached (the message names its address)."""


#: Seconds to wait for a Dask scheduler to answer before giving up.
SCHEDULER_TIMEOUT_S = 5.0


def connect_scheduler(address: str, timeout: float = SCHEDULER_TIMEOUT_S):
    """Connect to the Dask distributed scheduler at ``address``.

    Parameters
    ----------
    address : str
        Scheduler address, e.g. ``tcp://host:8786``.
    timeout : float
        Seconds to wait for the connection.

    Returns
    -------
    distributed.Client

    Raises
    ------
    SchedulerError
        No scheduler answered within ``timeout`` (the message names the address).
    """
    _probe_scheduler(address, timeout)
    from distributed import Client

    try:
        return Client(address, timeout=timeout, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as e:
        detail = str(e).splitlines()[0] if str(e) else type(e).__name__
        if isinstance(e, TimeoutError) or "timed out" in detail.lower():
            detail = f"no answer within {timeout:g} s; is a scheduler running there?"
        raise SchedulerError(f"cannot reach the Dask scheduler at {address}: {detail}") from None


_SCHEMES = ("tcp", "tls", "inproc", "ucx", "ws", "wss")


def _probe_scheduler(address: str, timeout: float) -> None:
    """Refuse an unknown scheme, and a TCP address where nothing listens, at once (a
    Client would retry until its timeout, and leave a traceback behind on a bad scheme)."""
    import socket
    from urllib.parse import urlsplit

    scheme, sep, _rest = address.partition("://")
    if not sep:
        scheme, address_url = "tcp", f"tcp://{address}"
    else:
        address_url = address
    if scheme not in _SCHEMES:
        raise SchedulerError(
            f"cannot reach the Dask scheduler at {address}: unknown scheme {scheme!r} (known: {', '.join(_SCHEMES)})"
        )
    if scheme not in ("tcp", "tls"):
        return
    try:
        parts = urlsplit(address_url)
        host, port = parts.hostname, parts.port or 8786
    except ValueError as e:
        raise SchedulerError(f"cannot reach the Dask scheduler at {address}: malformed address ({e})") from None
    if not host:
        raise SchedulerError(f"cannot reach the Dask scheduler at {address}: no host in the address")
    try:
        socket.create_connection((host, port), timeout=timeout).close()
    except TimeoutError:
        raise SchedulerError(f"cannot reach the Dask scheduler at {address}: no answer within {timeout:g} s") from None
    except OSError as e:
        raise SchedulerError(
            f"cannot reach the Dask scheduler at {address}: {e.strerror or e}; is a scheduler running there?"
        ) from None
    try:  # something listens: ask it who it is, in a loop of our own (no half-built Client left behind)
        kind = asyncio.run(_identity(address_url, timeout))
    except Exception as e:
        kind = f"no Dask reply: {type(e).__name__}"
    if kind != "Scheduler":
        raise SchedulerError(
            f"cannot use {address}: it does not answer like a Dask scheduler ({kind}); check the address and port"
        )


async def _identity(address: str, timeout: float) -> str:
    from distributed.comm import connect

    comm = await connect(address, timeout=timeout)
    try:
        await comm.write({"op": "identity", "reply": True})
        reply = await asyncio.wait_for(comm.read(), timeout)
    finally:
        await comm.close()
    return reply.get("type", "no type") if isinstance(reply, dict) else type(reply).__name__


def run_dask(chunks: list[Chunk], specimen: Specimen, scheduler: Any, on_record: Any) -> None:
    """Run ``chunks`` on a Dask cluster; a task that fails twice (Dask retries it once) fails its records.

    ``scheduler`` is a connected client, used as it is (never the process's default client, which a
    command-line run has none of), or an address, connected to here and closed after. A worker that dies
    is the scheduler's to handle: its tasks are run again on the others (up to the scheduler's
    ``allowed-failures``, then they fail with ``KilledWorker`` and their records are listed as failed).
    The results (histories included) come back in bulk, one packed set per chunk; the caller stores the
    cache entries (a cluster's workers need not see this machine's cache)."""
    from distributed import Client, KilledWorker, as_completed

    client = scheduler if isinstance(scheduler, Client) else connect_scheduler(scheduler)
    futs: dict[Any, Chunk] = {}
    try:
        for c in chunks:
            f = client.submit(
                run_chunk, c.engine, c.settings, specimen, c.items, c.effects, c.batched, pure=False, retries=1
            )
            futs[f] = c
        # Without a loop, as_completed takes the default client's, and a command-line run has no default client.
        for f in as_completed(futs, loop=client.loop):
            c = futs[f]
            try:
                res = unpack(f.result())
            except KilledWorker as e:  # the workers running it died, as often as the scheduler allows
                n = e.allowed_failures
                msg = (
                    f"KilledWorker: the Dask workers running it died {n + 1} time(s), all that the scheduler "
                    f"allows (distributed.scheduler.allowed-failures = {n}); see the workers' logs"
                )
                res = [failed_record(i, msg) for i, _ in c.items]
            except Exception as e:  # the task raised, or could not run, twice
                res = [failed_record(i, f"Dask task failed twice: {type(e).__name__}: {e}") for i, _ in c.items]
            for r in res:
                on_record(c.engine, r)
    except BaseException:
        client.cancel(list(futs))
        raise
    finally:
        if not isinstance(scheduler, Client):
            client.close(timeout=2)
