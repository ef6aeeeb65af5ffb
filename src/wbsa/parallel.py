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
from dataclasses import dataclass
from typing import Any, Callable, Iterator, Sequence

from wbsa.errors import WbsaError, check_field
from wbsa.settings_io import check_types

SCHEDULER_ENV = "DASK_SCHEDULER_ADDRESS"
CONNECT_TIMEOUT_S = 20


def default_workers() -> int:
    """Number of CPU cores this process may use (the default ``--workers``)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def resolve_workers(workers: int | None) -> int:
    """The worker count of a ``--workers`` value: None or 0 = all cores (:func:`default_workers`), else itself.

    Raises
    ------
    WbsaError
        If ``workers`` is negative or not a whole number.
    """
    if workers is None:
        return default_workers()
    try:
        n = int(workers)
    except (TypeError, ValueError):
        raise WbsaError(f"workers must be a whole number (0 = all cores), got {workers!r}") from None
    if n != workers or n < 0:
        raise WbsaError(f"workers must be 0 (all cores) or more, got {workers}")
    return default_workers() if n == 0 else n


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
        raise WbsaError(f"workers must be at least 1, got {workers}")
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



def map_chunks(fn: Callable[..., Any], args: Sequence[tuple], *, workers: int, tag: str,
               on_result: Callable[[Any], None] | None = None) -> list[Any]:
    """``[fn(*a) for a in args]``, on a local dask cluster when ``workers`` > 1 and there are several chunks.

    Results come back in ``args`` order whatever order the workers finish in; ``on_result`` (e.g. a progress
    bar's update) is called with each result as it arrives.
    """
    results: dict[int, Any] = {}
    if workers > 1 and len(args) > 1:
        with dask_client(min(workers, len(args))) as client:
            for i, result in map_unordered(client, fn, args, tag=tag):
                results[i] = result
                if on_result is not None:
                    on_result(result)
    else:
        for i, a in enumerate(args):
            results[i] = fn(*a)
            if on_result is not None:
                on_result(results[i])
    return [results[i] for i in range(len(args))]


_MALLOC_TUNED = False


def keep_large_allocations() -> None:
    """Let glibc serve per-task arrays (a few MB) from the heap instead of fresh ``mmap`` pages.

    dask starts its workers with ``MALLOC_TRIM_THRESHOLD_=65536``, which also switches off glibc's
    adaptive mmap threshold: every array over 128 kB then comes from new zeroed pages and goes back to
    the system when freed, about 300-600 page faults and 10 % more CPU per view. Raising the mmap and
    trim thresholds (32 MB, 128 MB) once per process restores reuse. No effect off glibc.
    """
    global _MALLOC_TUNED
    if _MALLOC_TUNED:
        return
    _MALLOC_TUNED = True
    import ctypes
    import ctypes.util

    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return
    m_trim_threshold, m_mmap_threshold = -1, -3
    mallopt(m_mmap_threshold, 32 << 20)  # glibc caps it at 32 MB on 64-bit
    mallopt(m_trim_threshold, 128 << 20)


@contextmanager
def torch_threads(n: int | None) -> Iterator[None]:
    """``n`` torch intra-op threads inside the block (None: as the process has it), restored after.

    torch's thread count is the process's, not the thread's: only code that owns the process (a command, a
    worker process) may change it. The server sets it once at its start and gives its fits ``None``.

    Parameters
    ----------
    n : int or None
    """
    import torch

    if n is None:
        yield
        return
    before = torch.get_num_threads()
    torch.set_num_threads(n)
    try:
        yield
    finally:
        torch.set_num_threads(before)


@contextmanager
def single_threaded_math() -> Iterator[None]:
    """One torch thread and one BLAS thread inside the block, as in a dask worker.

    Multi-threaded torch and BLAS kernels add in another order than single-threaded ones, so the last
    bit of a vertex or an area would depend on whether a chunk ran in a worker (one thread each, dask's
    default) or in this process. Every chunk of work (population, scan) runs inside this block.
    """
    from threadpoolctl import threadpool_limits

    with torch_threads(1), threadpool_limits(limits=1, user_api="blas"):
        yield


#: Subjects per scan chunk by default (one Parquet part, one dask task, the unit of resuming).
DEFAULT_CHUNK_SIZE = 25


@dataclass(frozen=True)
class RunSettings:
    """How to run (``[run]`` of a study): never changes a result, so never part of a cache key.

    Attributes
    ----------
    workers : int
        Worker processes of the population and scan stages; 0 = all cores, 1 = in this process (no dask).
    scheduler : str or None
        Address of an existing dask scheduler (None: ``$DASK_SCHEDULER_ADDRESS`` or a local cluster).
    chunk_size : int
        Subjects per scan chunk: the unit of parallel work and of resuming.
    progress : bool or None
        Progress bars on stderr (None: when stderr is a terminal).
    """

    workers: int = 0
    scheduler: str | None = None
    chunk_size: int = DEFAULT_CHUNK_SIZE
    progress: bool | None = None

    def __post_init__(self) -> None:
        check_types(self)
        if self.scheduler == "":  # the empty string of older study files
            object.__setattr__(self, "scheduler", None)
        check_field(self.workers >= 0, "workers", f"must be 0 (all cores) or more, got {self.workers}")
        check_field(self.chunk_size >= 1, "chunk_size", f"must be at least 1 subject, got {self.chunk_size}")

    @property
    def n_workers(self) -> int:
        """``workers`` with 0 resolved to the cores this process may use."""
        return resolve_workers(self.workers)
