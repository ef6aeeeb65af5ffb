"""The scan folder: chunk plan, Parquet parts, resume state and the final table.

::

    DIR/settings.json        settings, population fingerprint and their hash (written first)
    DIR/intrinsics.json      camera intrinsics, Open3D format
    DIR/parts/part-<first>-<last>.parquet   one finished chunk (subject ids, zero-padded), written atomically
    DIR/scan.parquet         all parts, sorted by (subject_id, azimuth_deg, elevation_deg, distance_m)

A part exists only when its chunk finished (``wbsa.io.atomic_path`` renames it into place), so a
killed run leaves finished parts and at most some ``.part-*.part`` temporary files, which the
next run deletes before it scans the missing chunks.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from wbsa.errors import WbsaError
from wbsa.io import write_json

SETTINGS_FILE = "settings.json"
INTRINSICS_FILE = "intrinsics.json"
TABLE_FILE = "scan.parquet"
PARTS_DIR = "parts"

#: Row order of the final table.
SORT_COLUMNS = ("subject_id", "azimuth_deg", "elevation_deg", "distance_m")


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
        raise WbsaError(f"--out {out_dir} is a file; give a folder for the scan")
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
                            f"(hash {old_hash} != {settings_doc['settings_hash']}); use another --out")
    else:
        parts = out_dir / PARTS_DIR
        if parts.is_dir() and any(parts.glob("part-*.parquet")):
            raise WbsaError(f"{out_dir} holds scan parts but no {SETTINGS_FILE}, so it cannot be resumed safely; "
                            "use another --out")
        write_json(settings_doc, settings_path)
    (out_dir / PARTS_DIR).mkdir(parents=True, exist_ok=True)
    return chunk_size


def remove_stale_temporaries(out_dir: Path) -> int:
    """Delete temporary files that an interrupted run left (``.part-*.part``, ``.scan.parquet.*.part``).

    Returns
    -------
    int
        Number of files removed.
    """
    stale = list((out_dir / PARTS_DIR).glob(".part-*.part")) + list(out_dir.glob(f".{TABLE_FILE}.*.part"))
    for path in stale:
        path.unlink(missing_ok=True)
    return len(stale)


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
