"""Run independent chunks of work on a dask.distributed cluster (local or remote).

One place that knows how to open a client: a local cluster of ``workers`` single-threaded
processes on loopback, or an existing scheduler given by address (``--scheduler`` or the
``DASK_SCHEDULER_ADDRESS`` environment variable). Results come back to the caller, which
writes them, so workers need no shared file system.
"""

from __future__ import annotations

import logging
import os
from contextlib import contextmanager
from typing import Any, Callable, Iterator, Sequence

from wbsa.errors import WbsaError

SCHEDULER_ENV = "DASK_SCHEDULER_ADDRESS"
CONNECT_TIMEOUT_S = 20


def default_workers() -> int:
    """Number of CPU cores this process may use (the default ``--workers``)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def resolve_scheduler(scheduler: str | None) -> str | None:
    """The scheduler address to use: ``scheduler``, else ``$DASK_SCHEDULER_ADDRESS``, else None (local)."""
    return scheduler or os.environ.get(SCHEDULER_ENV) or None


@contextmanager
def dask_client(workers: int, scheduler: str | None = None) -> Iterator[Any]:
    """A ``distributed.Client`` on a fresh local cluster, or on ``scheduler`` if given.

    Raises
    ------
    WbsaError
        If the scheduler cannot be reached or ``workers`` < 1.
    """
    from distributed import Client, LocalCluster

    if workers < 1:
        raise WbsaError(f"--workers must be at least 1, got {workers}")
    cluster = None
    if scheduler is None:
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                               dashboard_address=":0", silence_logs=logging.ERROR)
        client = Client(cluster)
    else:
        try:
            client = Client(scheduler, timeout=f"{CONNECT_TIMEOUT_S}s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise WbsaError(f"cannot reach the dask scheduler at {scheduler} ({type(exc).__name__}); "
                            f"check --scheduler or ${SCHEDULER_ENV}") from None
    try:
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def map_unordered(client: Any, fn: Callable[..., Any], args: Sequence[tuple], tag: str) -> Iterator[tuple[int, Any]]:
    """Submit ``fn(*a)`` for every ``a`` in ``args``; yield ``(index, result)`` as each finishes.

    Pending tasks are cancelled if the caller stops early (Ctrl-C, an error).
    """
    from distributed import as_completed

    futures = [client.submit(fn, *a, pure=False, key=f"wbsa-{tag}-{i}-{os.getpid()}-{id(args)}")
               for i, a in enumerate(args)]
    index = {f.key: i for i, f in enumerate(futures)}
    try:
        for fut in as_completed(futures):
            result = fut.result()
            yield index[fut.key], result
            fut.release()
    finally:
        client.cancel(futures)
