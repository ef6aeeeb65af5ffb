"""File I/O at the edges of the pipeline: one atomic, verified write path and validated table reads.

Every artefact wbsa writes goes through :func:`atomic_path`:

1. the writer writes a temporary file ``.<name>.<pid>-<token>.part`` in the target folder;
2. the file is flushed to disk (``fsync``) and checked: it must exist, have the size the writer
   produced (:func:`write_bytes`) and, for Parquet, PNG and meshes, read back with the expected
   rows / pixels / vertices (a ``verify`` callback; Open3D's writers report success after a failed
   write, so only the re-read is trusted);
3. it is renamed over the final name and the folder entry is flushed.

A crash, a ``kill -9`` or a full disk therefore never leaves a file under a final name that is not
complete; the temporary files it leaves carry the writer's process id and are deleted by the next
writer of that file or folder (:func:`remove_stale_temporaries`) once that process is gone. Files that only
make sense together (the outputs of ``wbsa fit``, the top of a study folder) are written into a
staging folder and moved in as a group with a marker file last (:func:`staged_files`); readers
require the marker. Operating-system errors (disk full, permissions, read-only file systems) become
one-line :class:`~wbsa.errors.WbsaError` messages naming the path and the fix
(:func:`os_error_message`).
"""

from __future__ import annotations

import errno
import glob
import json
import os
import re
import secrets
import shutil
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Iterator, Literal

import pandas as pd

from wbsa.errors import WbsaError

TableFormat = Literal["parquet", "csv", "xlsx"]

#: Suffix of every temporary file and staging folder (``.<name>.<pid>-<token>.part[.ext]``).
TEMP_SUFFIX = ".part"
#: ``df.attrs`` key of run information (timings, hosts) that never goes into a data file.
RUN_LOG_ATTR = "run_log"

_TEMP_RE = re.compile(r"^\..+\.(\d+)-[0-9a-f]{8}\.part(\.[A-Za-z0-9]+)?$")
_ERRNO_RE = re.compile(r"\[Errno (\d+)\]")

#: errno -> (what happened, what to do), for :func:`os_error_message`.
_REASONS: dict[int, tuple[str, str]] = {
    errno.ENOSPC: ("no space left on the device", "free disk space or write to another disk"),
    errno.EDQUOT: ("disk quota exceeded", "free space in your quota or write to another disk"),
    errno.EFBIG: ("file too large for this file system or the process's file-size limit (ulimit -f)",
                  "raise the limit or write to another disk"),
    errno.EACCES: ("permission denied", "choose a folder you can write to"),
    errno.EPERM: ("operation not permitted", "choose a folder you can write to"),
    errno.EROFS: ("read-only file system", "choose a writable folder"),
    errno.ENOENT: ("no such file or folder", "check the path"),
    errno.ENOTDIR: ("a part of the path is a file, not a folder", "check the path"),
    errno.EISDIR: ("it is a folder", "give a file name"),
    errno.EIO: ("input/output error", "check the disk"),
    errno.ENAMETOOLONG: ("file name too long", "use a shorter path"),
    errno.EMFILE: ("too many open files", "raise the limit (ulimit -n)"),
}


def os_error_message(exc: BaseException, path: str | os.PathLike | None = None, action: str = "write") -> str:
    """One line for an operating-system error: the path, what happened and the fix.

    Parameters
    ----------
    exc : OSError (or an Arrow I/O error, which carries ``[Errno N]`` only in its text)
    path : path-like, optional
        The file or folder concerned (default: the exception's ``filename``).
    action : str
        What wbsa was doing (``write``, ``read``, ``create``).
    """
    code = getattr(exc, "errno", None)
    if code is None:
        m = _ERRNO_RE.search(str(exc))
        code = int(m.group(1)) if m else None
    where = path if path is not None else (getattr(exc, "filename", None) or "a file")
    if code in _REASONS:
        what, fix = _REASONS[code]
    else:
        text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        what = getattr(exc, "strerror", None) or text
        fix = "check the disk and the path"
    return f"cannot {action} {where}: {what}; {fix}"


def _mkdir(folder: Path) -> None:
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise WbsaError(f"cannot create output folder {folder}: a file of that name is in the way; "
                        "choose another output path") from None
    except OSError as exc:
        raise WbsaError(os_error_message(exc, folder, "create folder")) from None


def _fsync_dir(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:  # some file systems cannot sync a folder; the rename itself is still atomic
        pass
    finally:
        os.close(fd)


def _temp_name(final: Path, keep_suffix: bool) -> Path:
    return final.parent / f".{final.name}.{os.getpid()}-{secrets.token_hex(4)}{TEMP_SUFFIX}" \
                          f"{final.suffix if keep_suffix else ''}"


@contextmanager
def atomic_path(final: str | os.PathLike, keep_suffix: bool = False,
                verify: Callable[[Path], None] | None = None, size: int | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``final``; after the body it is synced, checked and renamed to ``final``.

    Parameters
    ----------
    final : path-like
        The file to write.
    keep_suffix : bool
        End the temporary name with ``final``'s suffix, for writers that pick the format by it (Open3D).
    verify : callable, optional
        ``verify(tmp)`` re-reads the temporary file and raises :class:`~wbsa.errors.WbsaError` (or any
        exception) if it is not what was written; default: :func:`default_verifier` of the suffix.
    size : int, optional
        The exact number of bytes the file must have.

    Raises
    ------
    WbsaError
        The folder cannot be created, the write fails (disk full, permissions: one line naming the
        path and the fix), or the file read back is incomplete. Nothing is left under ``final`` then,
        and an older ``final`` is kept unchanged.
    """
    final = Path(final)
    parent = final.parent if str(final.parent) else Path(".")
    _mkdir(parent)
    if final.is_dir():
        raise WbsaError(f"output path {final} is a folder; give a file name")
    _remove_stale(parent.glob(f".{glob.escape(final.name)}.*{TEMP_SUFFIX}*"))  # left by killed writers of final
    tmp = _temp_name(final, keep_suffix)
    try:
        os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))  # the umask applies, as for open()
    except OSError as exc:
        raise WbsaError(os_error_message(exc, final)) from None
    verify = verify if verify is not None else default_verifier(final)
    try:
        try:
            yield tmp
            _sync(tmp)
        except OSError as exc:
            raise WbsaError(os_error_message(exc, final)) from None
        _check_written(tmp, final, verify, size)
        try:
            os.replace(tmp, final)
        except OSError as exc:
            raise WbsaError(os_error_message(exc, final)) from None
        _fsync_dir(parent)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _sync(tmp: Path) -> None:
    fd = os.open(tmp, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _check_written(tmp: Path, final: Path, verify: Callable[[Path], None] | None, size: int | None) -> None:
    """Raise a one-line WbsaError if ``tmp`` is missing, of the wrong size or does not read back."""
    if not tmp.is_file():
        raise WbsaError(_incomplete(final, "the writer produced no file"))
    if size is not None and tmp.stat().st_size != size:
        raise WbsaError(_incomplete(final, f"{tmp.stat().st_size} of {size} bytes were written"))
    if verify is None:
        return
    try:
        verify(tmp)
    except WbsaError as exc:
        raise WbsaError(_incomplete(final, str(exc))) from None
    except Exception as exc:  # readers raise many types for truncated files
        raise WbsaError(_incomplete(final, f"it does not read back ({type(exc).__name__})")) from None


def _incomplete(final: Path, detail: str) -> str:
    parent = final.parent if str(final.parent) else Path(".")
    try:
        full = shutil.disk_usage(parent).free < 1 << 20
    except OSError:
        full = False
    if full:
        return os_error_message(OSError(errno.ENOSPC, "no space"), final)
    return f"cannot write {final}: {detail}; check the disk (is it full?) and run the command again"


def default_verifier(path: Path) -> Callable[[Path], None] | None:
    """The re-read check of a file type: Parquet (footer and rows) and PNG (decodes); None for others."""
    suffix = path.suffix.lower()
    if suffix in (".parquet", ".pq"):
        return parquet_verifier()
    if suffix == ".png":
        return png_verifier()
    return None


def parquet_verifier(n_rows: int | None = None) -> Callable[[Path], None]:
    """Check that a Parquet file reads back completely (with ``n_rows`` rows, when given)."""
    def verify(tmp: Path) -> None:
        import pyarrow.parquet as pq

        table = pq.read_table(tmp)
        if n_rows is not None and table.num_rows != n_rows:
            raise WbsaError(f"it reads back with {table.num_rows} of {n_rows} rows")
    return verify


def png_verifier(shape: tuple[int, int] | None = None) -> Callable[[Path], None]:
    """Check that a PNG decodes completely (to ``shape`` = (height, width), when given)."""
    def verify(tmp: Path) -> None:
        from PIL import Image

        with Image.open(tmp) as img:
            img.load()
            if shape is not None and (img.height, img.width) != tuple(shape):
                raise WbsaError(f"it reads back as {img.width}x{img.height}, not {shape[1]}x{shape[0]}")
    return verify


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
    return Path(path)


def write_json(obj: object, path: str | os.PathLike) -> Path:
    """Write ``obj`` atomically as indented JSON."""
    return write_text(json.dumps(obj, indent=2, default=_json_default) + "\n", path)


def write_run_log(log: dict, data_path: str | os.PathLike) -> Path:
    """Write the run information of a data file (timings) beside it as ``<name>.log.json``."""
    data_path = Path(data_path)
    return write_json(log, data_path.with_name(data_path.name + ".log.json"))


def _json_default(o: object) -> object:
    import numpy as np

    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # a live process of another user
        return True
    return True


def remove_stale_temporaries(folder: str | os.PathLike, *, all_of_them: bool = False) -> int:
    """Delete the temporary files and staging folders that interrupted writers left in ``folder``.

    A temporary entry is stale when the process whose id it carries is gone (a ``kill -9``, a power
    cut); entries of live processes are kept. ``all_of_them`` also deletes entries of live processes
    (only for a caller that holds the folder's lock, :mod:`wbsa.folder_lock`), and old-style
    temporaries without a process id.

    Returns
    -------
    int
        Number of entries removed.
    """
    folder = Path(folder)
    if not folder.is_dir():
        return 0
    return _remove_stale(folder.iterdir(), all_of_them)


def _remove_stale(entries, all_of_them: bool = False) -> int:
    removed = 0
    for entry in entries:
        name = entry.name
        if not (name.startswith(".") and TEMP_SUFFIX in name):
            continue
        m = _TEMP_RE.match(name)
        if m is not None:
            pid = int(m.group(1))
            stale = not _pid_alive(pid) or (all_of_them and pid != os.getpid())
        else:  # an old-style temporary name without a process id
            stale = all_of_them
        if not stale:
            continue
        try:
            if entry.is_dir() and not entry.is_symlink():
                shutil.rmtree(entry, ignore_errors=True)
            else:
                entry.unlink(missing_ok=True)
        except OSError:  # not ours to delete (permissions): leave it
            continue
        removed += 1
    return removed


@contextmanager
def staged_files(folder: str | os.PathLike, marker: str) -> Iterator[Path]:
    """Write a group of files that become visible together: yield a staging folder inside ``folder``.

    Write every file (with the usual writers) into the yielded folder, the ``marker`` file among them.
    When the body succeeds, the old ``marker`` in ``folder`` is removed first, the other files are
    renamed into ``folder``, and the new marker last; readers that require the marker therefore never
    see a mixed or half-written group. When the body fails (a full disk, an error, Ctrl-C), ``folder``
    is left exactly as it was.

    Raises
    ------
    WbsaError
        If the marker was not written, or the folder cannot be written.
    """
    folder = Path(folder)
    _mkdir(folder)
    remove_stale_temporaries(folder)
    stage = folder / f".staging.{os.getpid()}-{secrets.token_hex(4)}{TEMP_SUFFIX}"
    try:
        stage.mkdir()
    except OSError as exc:
        raise WbsaError(os_error_message(exc, folder)) from None
    try:
        yield stage
        files = sorted(p for p in stage.iterdir() if p.is_file() and not p.name.startswith("."))
        if not (stage / marker).is_file():
            raise WbsaError(f"the outputs written to {folder} lack their marker {marker}; this is a bug in wbsa")
        try:
            (folder / marker).unlink(missing_ok=True)
            _fsync_dir(folder)
            for f in files:
                if f.name != marker:
                    os.replace(f, folder / f.name)
            os.replace(stage / marker, folder / marker)
        except OSError as exc:
            raise WbsaError(os_error_message(exc, folder)) from None
        _fsync_dir(folder)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


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
