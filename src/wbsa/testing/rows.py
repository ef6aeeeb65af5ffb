"""A long benchmark's rows kept as they come, so that a stopped run resumes where it stopped.

A benchmark cuts its captures into chunks, each named by its first image, and hands them to
:func:`map_resumable` with a record of how the rows are made (:func:`run_record`: the settings, the model, the
subjects). Each chunk's rows are written to ``<folder>/chunk-<first>.parquet`` as the chunk finishes, atomically
(:func:`wbsa.atomic.atomic_path`), beside ``run.json`` (the record); the same command again reads the chunks
there and runs only the others, so the run can span sessions. A folder written with another record is refused.
``benchmarks/bench_estimate.py`` (through :func:`wbsa.testing.testset.run_room_tests`) and
``benchmarks/bench_body_fit.py`` keep their rows this way.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any, Callable, Sequence

import pandas as pd

from wbsa.errors import WbsaError

#: The record of the run, beside its chunks.
RECORD_NAME = "run.json"


def run_record(population: pd.DataFrame, chunk: int, **fields: Any) -> dict:
    """What a run's rows depend on, as JSON values: ``fields``, the chunk size and a digest of the subjects.

    Parameters
    ----------
    population : pandas.DataFrame
        The run's subjects, one row each (hashed with their order).
    chunk : int
        Images per chunk.
    **fields
        The settings, model and anything else the rows depend on; values that are not JSON are stored as
        their ``str``.

    Returns
    -------
    dict
        ``fields`` with ``chunk``, ``subjects`` (12 hex digits) and ``n`` (the number of subjects).
    """
    subjects = hashlib.sha256(pd.util.hash_pandas_object(population, index=False).values.tobytes()).hexdigest()[:12]
    return json.loads(json.dumps({**fields, "chunk": chunk, "subjects": subjects, "n": len(population)},
                                 default=str))


def read_rows(rows_dir: str | Path, record: dict) -> dict[int, pd.DataFrame]:
    """The chunks already in ``rows_dir`` (first image → rows), after checking they were made as ``record`` says.

    A folder with no record gets ``record`` (written atomically).

    Parameters
    ----------
    rows_dir : str or Path
        The run's folder (made if missing).
    record : dict
        :func:`run_record` of the run.

    Returns
    -------
    dict of int to pandas.DataFrame

    Raises
    ------
    WbsaError
        If the folder holds the rows of a run with another record.
    """
    from wbsa.atomic import atomic_path

    folder = Path(rows_dir)
    meta = folder / RECORD_NAME
    if meta.exists():
        stored = json.loads(meta.read_text())
        if stored != record:
            differ = sorted(k for k in stored.keys() | record.keys() if stored.get(k) != record.get(k))
            raise WbsaError(f"{folder} holds rows of another run (other {', '.join(differ)}); give a new folder or "
                            "remove it")
    else:
        with atomic_path(meta) as tmp:
            tmp.write_text(json.dumps(record, indent=1, sort_keys=True))
    return {int(path.stem.split("-")[1]): pd.read_parquet(path) for path in sorted(folder.glob("chunk-*.parquet"))}


def write_rows(rows_dir: str | Path, first: int, part: pd.DataFrame) -> None:
    """Write one chunk's rows to ``rows_dir/chunk-<first>.parquet``, atomically.

    Parameters
    ----------
    rows_dir : str or Path
    first : int
        The chunk's first image.
    part : pandas.DataFrame
        Its rows.
    """
    from wbsa.atomic import atomic_path

    with atomic_path(chunk_path(rows_dir, first)) as tmp:
        part.to_parquet(tmp, index=False)


def chunk_path(rows_dir: str | Path, first: int) -> Path:
    """Where the rows of the chunk whose first image is ``first`` are kept.

    Parameters
    ----------
    rows_dir : str or Path
    first : int

    Returns
    -------
    Path
        ``rows_dir/chunk-<first, six digits>.parquet``.
    """
    return Path(rows_dir) / f"chunk-{first:06d}.parquet"


def map_resumable(fn: Callable[..., pd.DataFrame], args: Sequence[tuple], starts: Sequence[int], *,
                  rows_dir: str | Path | None, record: dict, workers: int = 1, tag: str,
                  on_result: Callable[[pd.DataFrame], None] | None = None,
                  on_resumed: Callable[[list[int]], None] | None = None) -> list[pd.DataFrame]:
    """``[fn(*a) for a in args]`` (:func:`wbsa.parallel.map_chunks`), each chunk's rows kept in ``rows_dir``.

    The chunks already in ``rows_dir`` (:func:`read_rows`) are read, not run; each chunk run is written there
    (:func:`write_rows`; an empty one is not, and runs again next time) as it comes back.

    Parameters
    ----------
    fn : callable
        ``fn(*args[i])`` gives the rows of chunk ``i`` (a pandas.DataFrame); with ``workers`` > 1 it runs in
        worker processes, so it must pickle.
    args : sequence of tuple
        Each chunk's arguments.
    starts : sequence of int
        Each chunk's first image (its name in ``rows_dir``), as many as ``args``.
    rows_dir : str, Path or None
        The run's folder; None keeps nothing.
    record : dict
        :func:`run_record` of the run (not used without ``rows_dir``).
    workers : int
        Worker processes (1: this process).
    tag : str
        Name of the dask tasks.
    on_result : callable, optional
        Called with each chunk's rows: those read from ``rows_dir`` first, then each run one as it comes back.
    on_resumed : callable, optional
        Called once, before any chunk runs, with the starts of the chunks read from ``rows_dir``.

    Returns
    -------
    list of pandas.DataFrame
        The chunks' rows in the order of ``args``.
    """
    from wbsa.parallel import map_chunks

    if len(args) != len(starts):
        raise WbsaError(f"map_resumable needs one start per chunk: {len(args)} chunks, {len(starts)} starts")
    done = read_rows(rows_dir, record) if rows_dir is not None else {}
    done = {s: done[s] for s in starts if s in done}
    todo = [(s, fn, *a) for s, a in zip(starts, args) if s not in done]

    def keep(result: tuple[int, pd.DataFrame]) -> None:
        first, part = result
        if rows_dir is not None and len(part):
            write_rows(rows_dir, first, part)
        if on_result is not None:
            on_result(part)

    if on_resumed is not None:
        on_resumed(list(done))
    if on_result is not None:
        for part in done.values():
            on_result(part)
    ran = dict(map_chunks(_started, todo, workers=workers, tag=tag, on_result=keep))
    return [done[s] if s in done else ran[s] for s in starts]


def _started(first: int, fn: Callable[..., pd.DataFrame], *args: Any) -> tuple[int, pd.DataFrame]:
    """``(first, fn(*args))``: a chunk's rows with its name, for :func:`map_resumable`'s writer."""
    return first, fn(*args)
