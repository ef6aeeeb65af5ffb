"""File I/O at the edges of the pipeline: atomic writes and validated table reads."""

from __future__ import annotations

import json
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator, Literal

import pandas as pd

from wbsa.errors import WbsaError

TableFormat = Literal["parquet", "csv", "xlsx"]


@contextmanager
def atomic_path(final: str | os.PathLike, keep_suffix: bool = False) -> Iterator[Path]:
    """Yield a temporary path beside ``final``; rename it to ``final`` only on success.

    Nothing is left under the final name if the body raises, so a crash or a Ctrl-C
    never leaves a half-written file that looks finished. ``keep_suffix`` ends the temporary
    name with ``final``'s suffix, for writers that pick the format by it (Open3D).
    """
    final = Path(final)
    parent = final.parent if str(final.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise WbsaError(f"cannot create output folder {parent}: {exc.strerror}; choose a writable --out") from None
    if final.is_dir():
        raise WbsaError(f"output path {final} is a folder; give a file name")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{final.name}.", suffix=".part" + (final.suffix if keep_suffix else ""),
                                   dir=parent)
    except OSError as exc:
        raise WbsaError(f"cannot write to {parent}: {exc.strerror}; choose a writable --out") from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        if tmp_path.exists():  # mkstemp makes 0600 files; give the result the usual umask mode
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp_path, 0o666 & ~umask)
        os.replace(tmp_path, final)
    except BaseException:
        tmp_path.unlink(missing_ok=True)
        raise


def write_table(df: pd.DataFrame, path: str | os.PathLike, fmt: TableFormat | None = None) -> Path:
    """Write ``df`` atomically as Parquet, CSV or XLSX (format from ``fmt`` or the suffix)."""
    path = Path(path)
    fmt = fmt or _format_from_suffix(path)
    with atomic_path(path) as tmp:
        if fmt == "parquet":
            df.to_parquet(tmp, index=False)
        elif fmt == "csv":
            df.to_csv(tmp, index=False)
        elif fmt == "xlsx":
            with pd.ExcelWriter(tmp, engine="openpyxl") as writer:
                df.to_excel(writer, index=False)
        else:
            raise WbsaError(f"unknown table format {fmt!r}; use parquet, csv or xlsx")
    return path


def write_sheets(sheets: dict[str, pd.DataFrame], path: str | os.PathLike) -> Path:
    """Write several tables atomically as one XLSX workbook, one sheet per key."""
    with atomic_path(path) as tmp:
        with pd.ExcelWriter(tmp, engine="openpyxl") as writer:
            for name, df in sheets.items():
                df.to_excel(writer, sheet_name=str(name)[:31], index=False)
    return Path(path)


def write_json(obj: object, path: str | os.PathLike) -> Path:
    """Write ``obj`` atomically as indented JSON."""
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(obj, indent=2, default=_json_default) + "\n")
    return Path(path)


def _json_default(o: object) -> object:
    import numpy as np

    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def read_table(path: str | os.PathLike, required: list[str] | tuple[str, ...] = (), what: str = "table") -> pd.DataFrame:
    """Read a Parquet (or CSV) table and check that it has the ``required`` columns.

    Raises
    ------
    WbsaError
        If the file is missing, not a readable table, or lacks a required column.
    """
    path = Path(path)
    if not path.exists():
        raise WbsaError(f"{what} file {path} does not exist; check the path")
    if path.is_dir():
        raise WbsaError(f"{what} path {path} is a folder; give a .parquet file")
    try:
        if path.suffix.lower() == ".csv":
            df = pd.read_csv(path)
        else:
            df = pd.read_parquet(path)
    except Exception as exc:  # pyarrow raises many types for corrupt files
        raise WbsaError(f"{path} is not a readable Parquet {what} ({type(exc).__name__}); regenerate it with wbsa") from None
    missing = [c for c in required if c not in df.columns]
    if missing:
        raise WbsaError(f"{path} is not a wbsa {what}: missing column(s) {', '.join(missing)}")
    return df


def _format_from_suffix(path: Path) -> TableFormat:
    suffix = path.suffix.lower().lstrip(".")
    if suffix in ("parquet", "pq"):
        return "parquet"
    if suffix in ("csv", "xlsx"):
        return suffix  # type: ignore[return-value]
    raise WbsaError(f"cannot tell the table format of {path}; use a .parquet, .csv or .xlsx name")
