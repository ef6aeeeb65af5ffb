"""The scan folder: chunk plan, Parquet parts, resume state and the final table.

::

    DIR/settings.json        settings, population fingerprint and their hash (written first)
    DIR/intrinsics.json      camera intrinsics, Open3D format
    DIR/parts/part-<first>-<last>.parquet   one finished chunk (subject ids, zero-padded), written atomically
    DIR/scan.parquet         all parts, sorted by (subject_id, azimuth_deg, elevation_deg, distance_m)
    DIR/.wbsa.lock           the folder's write lock (:mod:`wbsa.folder_lock`)

A part exists only when its chunk finished (``wbsa.atomic.atomic_path`` renames it into place), so a
killed run leaves finished parts and at most some ``.part-*.part`` temporary files, which the
next run deletes before it scans the missing chunks. Every part carries in its Parquet metadata
(key ``wbsa.scan_part``) the scan's settings hash, its chunk (first and last subject id, subject
count), its row count and a hash of its rows; :func:`check_parts` reads every part before any
scanning starts and refuses, naming the file, a part of another scan, an edited part, a part of
another chunking and a corrupt part.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from wbsa.errors import WbsaError
from wbsa.io import atomic_path, parquet_verifier, remove_stale_temporaries as remove_temporaries, write_json

SETTINGS_FILE = "settings.json"
INTRINSICS_FILE = "intrinsics.json"
TABLE_FILE = "scan.parquet"
PARTS_DIR = "parts"

#: Row order of the final table.
SORT_COLUMNS = ("subject_id", "azimuth_deg", "elevation_deg", "distance_m")
#: Parquet metadata key of a part's identity (settings hash, chunk, rows).
PART_METADATA_KEY = b"wbsa.scan_part"


@dataclass(frozen=True)
class Chunk:
    """A run of consecutive subjects (in subject-id order) scanned and written together.

    Attributes
    ----------
    start, stop : int
        Row range of the chunk in the population sorted by subject id.
    first_id, last_id : int
        Subject ids of its first and last subject.
    """

    start: int
    stop: int
    first_id: int
    last_id: int

    @property
    def n_subjects(self) -> int:
        """Number of subjects in the chunk."""
        return self.stop - self.start

    @property
    def part_name(self) -> str:
        """File name of the chunk's Parquet part, e.g. ``part-00000000-00000049.parquet``."""
        return f"part-{self.first_id:08d}-{self.last_id:08d}.parquet"


def plan_chunks(subject_ids: np.ndarray, chunk_size: int) -> list[Chunk]:
    """Split sorted subject ids into chunks of ``chunk_size`` (the last one may be shorter).

    Parameters
    ----------
    subject_ids : (n,) int64
        Sorted, unique subject ids.
    chunk_size : int
    """
    ids = np.asarray(subject_ids, dtype=np.int64)
    return [Chunk(start, min(start + chunk_size, len(ids)), int(ids[start]), int(ids[min(start + chunk_size, len(ids)) - 1]))
            for start in range(0, len(ids), chunk_size)]


def open_scan_folder(out_dir: Path, settings_doc: dict) -> int:
    """Create ``out_dir`` for a scan, or check that it holds a scan with the same settings hash.

    Parameters
    ----------
    out_dir : Path
    settings_doc : dict
        The content of ``settings.json``; must contain ``settings_hash`` and ``chunk_size``.

    Returns
    -------
    int
        The folder's chunk size: the one recorded when the folder was started (its parts follow that
        plan), else ``settings_doc['chunk_size']``.

    Raises
    ------
    WbsaError
        If ``out_dir`` holds a scan with other settings or population (or parts without settings).
    """
    if out_dir.exists() and not out_dir.is_dir():
        raise WbsaError(f"scan folder {out_dir} is a file; give a folder for the scan")
    settings_path = out_dir / SETTINGS_FILE
    chunk_size = int(settings_doc["chunk_size"])
    if settings_path.exists():
        try:
            old = json.loads(settings_path.read_text())
            old_hash = old.get("settings_hash")
            chunk_size = int(old.get("chunk_size", chunk_size))
        except (OSError, ValueError, TypeError, AttributeError):
            old_hash = None
        if old_hash != settings_doc["settings_hash"]:
            raise WbsaError(f"{out_dir} holds a scan made with other settings or another population "
                            f"(hash {old_hash} != {settings_doc['settings_hash']}); use another output folder")
    else:
        parts = out_dir / PARTS_DIR
        if parts.is_dir() and any(parts.glob("part-*.parquet")):
            raise WbsaError(f"{out_dir} holds scan parts but no {SETTINGS_FILE}, so it cannot be resumed safely; "
                            "use another output folder")
        write_json(settings_doc, settings_path)
    (out_dir / PARTS_DIR).mkdir(parents=True, exist_ok=True)
    return chunk_size


def remove_stale_temporaries(out_dir: Path) -> int:
    """Delete temporary files that an interrupted run left (in ``DIR`` and ``DIR/parts``).

    Call it only while holding the folder's lock: every temporary file there is then stale.

    Returns
    -------
    int
        Number of files removed.
    """
    return remove_temporaries(out_dir, all_of_them=True) + remove_temporaries(out_dir / PARTS_DIR, all_of_them=True)


def _rows_hash(table) -> str:
    """SHA-256 (16 hex) of a part's values, as pandas reads them back."""
    values = pd.util.hash_pandas_object(table.to_pandas(), index=False).to_numpy()
    names = "\0".join(table.column_names).encode()
    return hashlib.sha256(names + values.tobytes()).hexdigest()[:16]


def write_part(rows: pd.DataFrame, out_dir: Path, chunk: Chunk, settings_hash: str) -> Path:
    """Write a finished chunk's rows atomically as its Parquet part, with its identity in the metadata."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pandas(rows, preserve_index=False)
    ident = {"settings_hash": settings_hash, "first_id": chunk.first_id, "last_id": chunk.last_id,
             "n_subjects": chunk.n_subjects, "n_rows": table.num_rows, "rows_hash": _rows_hash(table)}
    table = table.replace_schema_metadata({**(table.schema.metadata or {}),
                                           PART_METADATA_KEY: json.dumps(ident, sort_keys=True).encode()})
    path = part_path(out_dir, chunk)
    with atomic_path(path, verify=parquet_verifier(table.num_rows)) as tmp:
        pq.write_table(table, tmp)
    return path


def check_parts(out_dir: Path, chunks: list[Chunk], settings_hash: str) -> int:
    """Check every part in ``DIR/parts`` against this scan before any scanning starts.

    Parameters
    ----------
    out_dir : Path
    chunks : list of Chunk
        The chunk plan of this run.
    settings_hash : str
        This scan's settings hash.

    Returns
    -------
    int
        Number of parts checked (all of them belong to this scan).

    Raises
    ------
    WbsaError
        Naming the first part that is unreadable (corrupt or cut short), lacks wbsa's metadata (written by
        something else, or edited), belongs to another scan, covers subjects that are not one chunk of
        this plan, or whose rows differ from those it was written with.
    """
    import pyarrow.parquet as pq

    planned = {c.part_name: c for c in chunks}
    parts = out_dir / PARTS_DIR
    fix = "delete it and run the same wbsa scan command again, or use another output folder"
    n = 0
    for path in sorted(parts.glob("part-*.parquet")) if parts.is_dir() else []:
        try:
            table = pq.read_table(path)
        except Exception as exc:  # pyarrow raises many types for corrupt files
            raise WbsaError(f"scan part {path} is unreadable, corrupt or cut short ({type(exc).__name__}); "
                            f"{fix}") from None
        raw = (table.schema.metadata or {}).get(PART_METADATA_KEY)
        try:
            ident = json.loads(raw) if raw else None
        except ValueError:
            ident = None
        if not isinstance(ident, dict):
            raise WbsaError(f"scan part {path} was not written by wbsa scan (or was edited since): it lacks the "
                            f"scan's identity; {fix}")
        if ident.get("settings_hash") != settings_hash:
            raise WbsaError(f"scan part {path} belongs to another scan (settings hash {ident.get('settings_hash')}, "
                            f"this scan {settings_hash}); {fix}")
        chunk = planned.get(path.name)
        if chunk is None or (ident.get("first_id"), ident.get("last_id"), ident.get("n_subjects")) != (
                chunk.first_id, chunk.last_id, chunk.n_subjects):
            size = ident.get("n_subjects")
            raise WbsaError(f"scan part {path} covers subjects {ident.get('first_id')}-{ident.get('last_id')}, "
                            f"which is not a chunk of this scan (it was written with {size} subjects per chunk; "
                            f"this run plans {chunks[0].n_subjects}); run with the chunk size of the first run or "
                            "use another output folder")
        if table.num_rows != ident.get("n_rows") or _rows_hash(table) != ident.get("rows_hash"):
            raise WbsaError(f"scan part {path} was changed after it was written (its rows do not match its "
                            f"hash); {fix}")
        n += 1
    return n


def part_path(out_dir: Path, chunk: Chunk) -> Path:
    """Where the chunk's finished Parquet part lives."""
    return out_dir / PARTS_DIR / chunk.part_name


def pending_chunks(out_dir: Path, chunks: list[Chunk]) -> list[Chunk]:
    """The chunks whose part is not on disk yet, in order."""
    return [c for c in chunks if not part_path(out_dir, c).is_file()]


def assemble_table(out_dir: Path, chunks: list[Chunk]) -> pd.DataFrame:
    """Concatenate the parts of ``chunks`` and sort the rows by :data:`SORT_COLUMNS`.

    Raises
    ------
    WbsaError
        If a part is missing or unreadable.
    """
    frames = []
    for chunk in chunks:
        path = part_path(out_dir, chunk)
        try:
            frames.append(pd.read_parquet(path))
        except FileNotFoundError:
            raise WbsaError(f"scan part {path} is missing; run the same wbsa scan command again to finish it") from None
        except Exception as exc:  # pyarrow raises many types for corrupt files
            raise WbsaError(f"scan part {path} is unreadable ({type(exc).__name__}); delete it and run the "
                            "same wbsa scan command again") from None
    table = pd.concat(frames, ignore_index=True)
    return table.sort_values(list(SORT_COLUMNS), kind="mergesort", ignore_index=True)
