"""The parallel, resumable scan engine: chunks of subjects, one Parquet part per chunk.

The engine knows nothing about bodies or cameras: it calls a *chunk function*
``chunk_fn(subjects: DataFrame, settings: ScanJob) -> DataFrame`` (by default
:func:`wbsa.scan.worker.scan_chunk`) on every unfinished chunk, either in this process
(``workers=1``) or as one ``dask.distributed`` task per chunk on a local cluster or on an
existing one (``scheduler=ADDRESS``), and writes each returned table atomically as its own
part. Rows depend only on the subject and the job, never on the chunking or the workers, so neither
is part of the folder's settings hash; a folder keeps the chunk size it was started with. The default
chunk function builds each body on its own (anny's batched forward pass rounds differently for
different batch sizes, up to 4.4e-16 m on a vertex) and every random stream is keyed by the subject and
the view, so the bytes of ``scan.parquet`` do not depend on ``chunk_size`` or ``workers``.

One process at a time writes a scan folder (:mod:`wbsa.folder_lock`); a second one stops at once with
a one-line error. Before any scanning, every part already in the folder is checked against this scan
(:func:`wbsa.scan.layout.check_parts`): a part of another scan, an edited part, a part of another
chunking or a corrupt part is refused, naming the file.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from wbsa.core.versions import WBSA_VERSION as __version__
from wbsa.errors import WbsaError
from wbsa.folder_lock import folder_lock
from wbsa.io import relative_path, write_json, write_table
from wbsa.parallel import DEFAULT_CHUNK_SIZE, resolve_scheduler, resolve_workers
from wbsa.progress import progress
from wbsa.scan.layout import (INTRINSICS_FILE, SORT_COLUMNS, TABLE_FILE, Chunk, assemble_table, check_parts,
                              open_scan_folder, pending_chunks, plan_chunks, remove_stale_temporaries, write_part)
from wbsa.scan.settings import ScanJob, population_fingerprint, settings_hash

#: ``chunk_fn(subjects, settings) -> rows``: scans the subjects (rows of the population table) at every view.
ChunkFn = Callable[[pd.DataFrame, ScanJob], pd.DataFrame]

@dataclass(frozen=True)
class ScanResult:
    """What :func:`scan_population` did.

    Attributes
    ----------
    table : pandas.DataFrame
        The final scan table (one row per subject x view), as written to ``path``.
    path : Path
        ``DIR/scan.parquet``.
    n_chunks : int
        Chunks in the scan.
    n_resumed : int
        Chunks found already finished (skipped) when the run started.
    n_views_scanned : int
        Rows (subject x view) scanned by this run, not counting resumed chunks.
    seconds : float
        Wall-clock time of this run.
    n_views_invalid : int
        Rows whose camera stood inside the body (``camera_inside``): no areas, left out of fits.
    """

    table: pd.DataFrame
    path: Path
    n_chunks: int
    n_resumed: int
    n_views_scanned: int
    seconds: float
    n_views_invalid: int = 0


def scan_population(population: pd.DataFrame | str | os.PathLike, settings: ScanJob, out_dir: str | os.PathLike,
                    *, workers: int | None = None, scheduler: str | None = None, chunk_size: int | None = None,
                    chunk_fn: ChunkFn | None = None, show_progress: bool | None = None) -> ScanResult:
    """Scan every subject of a population at every view, in parallel, resuming a killed run.

    Parameters
    ----------
    population : DataFrame or path
        Population table (``wbsa.bodies.table.read_population`` format), or its Parquet path.
    settings : ScanJob
        What to scan (from :meth:`wbsa.scan.settings.ScanSettings.job`).
    out_dir : path
        Scan folder (see :mod:`wbsa.scan.layout`). If it holds an unfinished scan with the same
        job and population, the finished chunks are kept and only the others are scanned.
    workers : int, optional
        Local worker processes (default or 0: all cores). ``1`` scans in this process, without dask.
    scheduler : str, optional
        Address of an existing dask scheduler (default: ``$DASK_SCHEDULER_ADDRESS`` if set);
        overrides ``workers``.
    chunk_size : int, optional
        Subjects per chunk (default :data:`wbsa.parallel.DEFAULT_CHUNK_SIZE`). A folder that already holds
        a scan keeps the chunk size it was started with, so changing it never re-scans finished chunks.
    chunk_fn : callable, optional
        ``chunk_fn(subjects, settings) -> DataFrame``; default :func:`wbsa.scan.worker.scan_chunk`.
        It must be importable (or picklable) by the dask workers.
    show_progress : bool, optional
        Progress bar on stderr (default: when stderr is a terminal, see :func:`wbsa.progress.progress`).

    Returns
    -------
    ScanResult

    Raises
    ------
    WbsaError
        Bad population, an ``out_dir`` made with other settings, holding a foreign or corrupt part, or
        being written by another process; an unreachable scheduler; a full disk.
    """
    t0 = time.perf_counter()
    workers = resolve_workers(workers)
    if chunk_size is not None and int(chunk_size) < 1:
        raise WbsaError(f"chunk_size must be at least 1 subject, got {chunk_size}")
    out_dir = Path(out_dir)
    population_path = None
    if not isinstance(population, pd.DataFrame):
        population_path = Path(population)
        population = _read_population(population_path)
    subjects = _checked_subjects(population)
    if chunk_fn is None:
        from wbsa.scan.worker import check_population, scan_chunk

        check_population(subjects)
        chunk_fn = scan_chunk

    fingerprint = population_fingerprint(subjects)
    doc = {
        "settings_hash": settings_hash(settings, fingerprint),
        "settings": settings.to_dict(),
        "population": {"path": relative_path(population_path, out_dir) if population_path else None,
                       "n_subjects": len(subjects), "fingerprint": fingerprint},
        "camera": settings.camera_name,
        "n_views": len(settings.views),
        "chunk_size": int(chunk_size or DEFAULT_CHUNK_SIZE),
        "wbsa_version": __version__,
    }
    with folder_lock(out_dir, "scan folder"):
        chunk_size = open_scan_folder(out_dir, doc)
        if hasattr(settings.camera, "to_open3d_json"):
            write_json(settings.camera.to_open3d_json(), out_dir / INTRINSICS_FILE)
        remove_stale_temporaries(out_dir)

        chunks = plan_chunks(subjects["subject_id"].to_numpy(), chunk_size)
        check_parts(out_dir, chunks, doc["settings_hash"])
        todo = pending_chunks(out_dir, chunks)
        n_views_todo = sum(c.n_subjects for c in todo) * len(settings.views)
        if todo:
            scheduler = resolve_scheduler(scheduler)
            bar = progress(total=n_views_todo, desc="scan", unit="view", enabled=show_progress)
            write = _part_writer(out_dir, doc["settings_hash"], bar)
            try:
                if scheduler is None and (workers == 1 or len(todo) == 1):
                    for chunk in todo:
                        write(chunk, run_chunk(chunk_fn, subjects.iloc[chunk.start:chunk.stop], settings))
                else:
                    _run_dask(subjects, todo, settings, chunk_fn, write, workers=workers, scheduler=scheduler)
            finally:
                bar.close()

        table = assemble_table(out_dir, chunks)
        path = write_table(table, out_dir / TABLE_FILE)
    n_invalid = int(table["camera_inside"].fillna(False).astype(bool).sum()) if "camera_inside" in table else 0
    return ScanResult(table=table, path=path, n_chunks=len(chunks), n_resumed=len(chunks) - len(todo),
                      n_views_scanned=n_views_todo, seconds=time.perf_counter() - t0, n_views_invalid=n_invalid)


def _part_writer(out_dir: Path, settings_hash: str, bar) -> Callable[[Chunk, pd.DataFrame], None]:
    """``write(chunk, rows)``: the chunk's part, with the scan's identity, and the progress bar."""
    def write(chunk: Chunk, rows: pd.DataFrame) -> None:
        write_part(rows, out_dir, chunk, settings_hash)
        bar.update(len(rows))
    return write


def run_chunk(chunk_fn: ChunkFn, subjects: pd.DataFrame, settings: ScanJob) -> pd.DataFrame:
    """Scan one chunk and check the rows (runs on the worker).

    Raises
    ------
    WbsaError
        If ``chunk_fn`` returned no table, lacks a sort column, or scanned other subjects.
    """
    rows = chunk_fn(subjects, settings)
    if not isinstance(rows, pd.DataFrame):
        raise WbsaError(f"chunk function returned {type(rows).__name__}, not a table; fix the scan worker")
    missing = [c for c in SORT_COLUMNS if c not in rows.columns]
    if missing:
        raise WbsaError(f"scan rows lack column(s) {', '.join(missing)}; fix the scan worker")
    if not np.isin(rows["subject_id"].to_numpy(), subjects["subject_id"].to_numpy()).all():
        raise WbsaError("scan rows name subjects outside their chunk; fix the scan worker")
    return rows.reset_index(drop=True)


def _run_dask(subjects: pd.DataFrame, todo: list[Chunk], settings: ScanJob, chunk_fn: ChunkFn,
              write: Callable[[Chunk, pd.DataFrame], None], *, workers: int, scheduler: str | None) -> None:
    """One task per chunk; the parts are written here, so workers need no shared file system."""
    from wbsa.parallel import dask_client, map_unordered

    args = [(chunk_fn, subjects.iloc[c.start:c.stop], settings) for c in todo]
    with dask_client(min(workers, len(todo)), scheduler) as client:
        for i, rows in map_unordered(client, run_chunk, args, tag="scan"):
            write(todo[i], rows)


def _read_population(path: Path) -> pd.DataFrame:
    from wbsa.bodies.table import read_population

    return read_population(path)


def _checked_subjects(population: pd.DataFrame) -> pd.DataFrame:
    """The population sorted by subject id, after checking the ids.

    Raises
    ------
    WbsaError
        Missing, non-integer, negative or duplicate subject ids, or an empty table.
    """
    if "subject_id" not in population.columns:
        raise WbsaError("population table has no subject_id column; make it with wbsa population")
    if len(population) == 0:
        raise WbsaError("population table has no subjects; make a non-empty one with wbsa population")
    ids = population["subject_id"]
    if not pd.api.types.is_integer_dtype(ids):
        raise WbsaError("population subject_id column is not integer; make the table with wbsa population")
    if (ids < 0).any():
        raise WbsaError("population has negative subject ids; subject ids must be 0 or more")
    if ids.duplicated().any():
        raise WbsaError(f"population has duplicate subject id {int(ids[ids.duplicated()].iloc[0])}; ids must be unique")
    return population.sort_values("subject_id", kind="mergesort", ignore_index=True).astype({"subject_id": np.int64})
