"""File I/O at the edges of the pipeline: table, JSON and text writers on the one verified write path.

Every writer here goes through :func:`wbsa.atomic.atomic_path` (temporary file, fsync, size and
re-read checks, rename; see that module and docs/reliability.md), re-exported here with the other
pieces of that path so callers need one import. :func:`read_table` reads and validates tables.
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path
from typing import Literal

import pandas as pd

from wbsa.atomic import (TEMP_SUFFIX, atomic_path, default_verifier, os_error_message, parquet_verifier,  # noqa: F401
                         png_verifier, remove_stale_temporaries, staged_files)
from wbsa.errors import WbsaError

TableFormat = Literal["parquet", "csv", "xlsx"]
#: ``df.attrs`` key of run information (timings, hosts) that never goes into a data file.
RUN_LOG_ATTR = "run_log"


def write_bytes(data: bytes, path: str | os.PathLike) -> Path:
    """Write ``data`` atomically (size-checked)."""
    with atomic_path(path, size=len(data)) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text(text: str, path: str | os.PathLike) -> Path:
    """Write ``text`` atomically as UTF-8 (size-checked)."""
    return write_bytes(text.encode("utf-8"), path)


def copy_file(src: str | os.PathLike, dst: str | os.PathLike) -> Path:
    """Copy ``src`` to ``dst`` atomically (size-checked, re-read by the suffix's verifier)."""
    src = Path(src)
    try:
        size = src.stat().st_size
    except OSError as exc:
        raise WbsaError(os_error_message(exc, src, "read")) from None
    with atomic_path(dst, size=size) as tmp:
        shutil.copyfile(src, tmp)
    return Path(dst)


def write_table(df: pd.DataFrame, path: str | os.PathLike, fmt: TableFormat | None = None) -> Path:
    """Write ``df`` atomically as Parquet, CSV or XLSX (format from ``fmt`` or the suffix).

    ``df.attrs`` go into a Parquet file's metadata, except :data:`RUN_LOG_ATTR` (timings): a data file
    holds only what the inputs and settings decide, so the same run gives the same bytes.
    """
    path = Path(path)
    fmt = fmt or _format_from_suffix(path)
    if RUN_LOG_ATTR in df.attrs:
        df = df.copy(deep=False)
        df.attrs = {k: v for k, v in df.attrs.items() if k != RUN_LOG_ATTR}
    if fmt == "parquet":
        with atomic_path(path, verify=parquet_verifier(len(df))) as tmp:
            df.to_parquet(tmp, index=False)
    elif fmt == "csv":
        with atomic_path(path, verify=_nonempty) as tmp:
            df.to_csv(tmp, index=False)
    elif fmt == "xlsx":
        with atomic_path(path, verify=_nonempty) as tmp:
            with pd.ExcelWriter(tmp, engine="openpyxl") as writer:
                df.to_excel(writer, index=False)
            _without_timestamps(tmp)
    else:
        raise WbsaError(f"unknown table format {fmt!r}; use parquet, csv or xlsx")
    return path


def _nonempty(tmp: Path) -> None:
    if tmp.stat().st_size == 0:
        raise WbsaError("the file is empty")


def write_sheets(sheets: dict[str, pd.DataFrame], path: str | os.PathLike) -> Path:
    """Write several tables atomically as one XLSX workbook, one sheet per key."""
    with atomic_path(path, verify=_nonempty) as tmp:
        with pd.ExcelWriter(tmp, engine="openpyxl") as writer:
            for name, df in sheets.items():
                df.to_excel(writer, sheet_name=str(name)[:31], index=False)
        _without_timestamps(tmp)
    return Path(path)


#: The fixed time of every entry of an XLSX file wbsa writes (the ZIP format's epoch).
_ZIP_EPOCH = (1980, 1, 1, 0, 0, 0)
_CORE_TIMES = re.compile(rb"(<dcterms:(created|modified)[^>]*>)[^<]*(</dcterms:\2>)")


def _without_timestamps(path: Path) -> None:
    """Rewrite an XLSX (a ZIP) with fixed entry times and document dates, so equal tables give equal bytes.

    openpyxl stamps the workbook's creation and modification time into ``docProps/core.xml`` and the
    ZIP entries carry the time they were written.
    """
    import zipfile

    with zipfile.ZipFile(path) as zin:
        entries = [(info, zin.read(info.filename)) for info in zin.infolist()]
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zout:
        for info, data in entries:
            if info.filename == "docProps/core.xml":
                data = _CORE_TIMES.sub(rb"\g<1>2000-01-01T00:00:00Z\g<3>", data)
            fixed = zipfile.ZipInfo(info.filename, date_time=_ZIP_EPOCH)
            fixed.compress_type = zipfile.ZIP_DEFLATED
            fixed.external_attr = info.external_attr
            zout.writestr(fixed, data)


def write_npz(arrays: dict, path: str | os.PathLike) -> Path:
    """Write named arrays as a compressed ``.npz`` (what :func:`numpy.load` reads) atomically, with fixed entry
    times, so equal arrays give equal bytes (:func:`numpy.savez_compressed` stamps the time of writing).

    Parameters
    ----------
    arrays : dict of str to array_like
        Entry names (without ``.npy``) and arrays; no object arrays.
    path : path-like
        The ``.npz`` file.
    """
    import io
    import zipfile

    import numpy as np

    path = Path(path)
    with atomic_path(path, keep_suffix=True) as tmp:
        with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zout:
            for name, value in arrays.items():
                buf = io.BytesIO()
                np.lib.format.write_array(buf, np.asanyarray(value), allow_pickle=False)
                info = zipfile.ZipInfo(f"{name}.npy", date_time=_ZIP_EPOCH)
                info.compress_type = zipfile.ZIP_DEFLATED
                zout.writestr(info, buf.getvalue())
    return path


def write_json(obj: object, path: str | os.PathLike) -> Path:
    """Write ``obj`` atomically as indented, strict JSON (a non-finite number as ``null``:
    :func:`wbsa.strict_json.json_text`)."""
    from wbsa.strict_json import json_text

    return write_text(json_text(obj) + "\n", path)


def relative_path(path: str | os.PathLike, start: str | os.PathLike) -> str:
    """``path`` relative to the folder ``start``, with ``/`` separators, for recording inputs in a file.

    A data file never holds an absolute path: a relative one still leads to the input when the whole
    tree is moved or shared. On another drive (Windows) the absolute path is the only answer.
    """
    try:
        return Path(os.path.relpath(Path(path).resolve(), Path(start).resolve())).as_posix()
    except ValueError:
        return str(Path(path).resolve())


def write_run_log(log: dict, data_path: str | os.PathLike) -> Path:
    """Write the run information of a data file (timings) beside it as ``<name>.log.json``."""
    data_path = Path(data_path)
    return write_json(log, data_path.with_name(data_path.name + ".log.json"))


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
    except MemoryError:
        raise WbsaError(f"{path} does not fit in memory; give a smaller {what}") from None
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
