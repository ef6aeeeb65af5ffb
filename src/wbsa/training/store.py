"""Rendered training chunks kept on disk, so a training run killed half-way resumes where it stopped.

The renders are the expensive part of training (about 2 captures per second per core). A
:class:`RenderStore` is one folder per part (``fit``, ``calibration``) of one training run: each finished
chunk of :func:`~wbsa.training.renders.render_samples` is written there as ``chunk-<first sample>.npy`` (its
descriptors) then ``chunk-<first sample>.parquet`` (its table, written last: a chunk counts as done once its
table is there), both atomically. ``key.txt`` holds the hash of the settings the chunks were rendered with: a
store made for other settings is refused rather than mixed.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from wbsa.errors import WbsaError


class RenderStore:
    """Finished render chunks of one part of a training run (see the module doc).

    Parameters
    ----------
    folder : path-like
        The part's folder (created).
    key : str
        Hash of the settings behind the chunks.
    """

    def __init__(self, folder, key: str) -> None:
        from wbsa.io import write_text

        self.folder = Path(folder)
        self.key = key
        key_file = self.folder / "key.txt"
        if key_file.is_file():
            found = key_file.read_text().strip()
            if found != key:
                raise WbsaError(f"{self.folder} holds renders of other training settings ({found}, not {key}); "
                                "give another --out folder or delete that one")
        else:
            write_text(key + "\n", key_file)

    def _paths(self, first_sample: int) -> tuple[Path, Path]:
        stem = self.folder / f"chunk-{first_sample:07d}"
        return stem.with_suffix(".parquet"), stem.with_suffix(".npy")

    def read(self, first_sample: int):
        """The chunk starting at ``first_sample`` if it is done, else None."""
        from wbsa.training.samples import Samples

        table_path, desc_path = self._paths(first_sample)
        if not (table_path.is_file() and desc_path.is_file()):
            return None
        try:
            table, desc = pd.read_parquet(table_path), np.load(desc_path, allow_pickle=False)
        except (OSError, ValueError) as exc:
            raise WbsaError(f"render chunk {table_path} is unreadable ({type(exc).__name__}); delete it and run "
                            "again to render it anew") from None
        if len(table) != len(desc):
            raise WbsaError(f"render chunk {table_path} holds {len(table)} rows but {len(desc)} descriptors; "
                            "delete it and run again")
        return Samples(table, desc)

    def write(self, part) -> None:
        """Keep a finished chunk (:class:`~wbsa.training.renders.Samples`, rows from its first ``sample``)."""
        from wbsa.atomic import atomic_path
        from wbsa.io import write_table

        first = int(part.table["sample"].iloc[0])
        table_path, desc_path = self._paths(first)
        with atomic_path(desc_path, keep_suffix=True) as tmp:
            np.save(tmp, part.descriptors, allow_pickle=False)
        write_table(part.table, table_path)
