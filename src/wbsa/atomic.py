"""The one atomic, verified write path: temporary file, fsync, check, rename; staged groups; OS errors.

Every artefact wbsa writes goes through :func:`atomic_path`:

1. the writer writes a temporary file ``.<name>.<pid>-<token>.part`` in the target folder;
2. the file is flushed to disk (``fsync``) and checked: it must exist, have the size the writer
   produced (:func:`wbsa.io.write_bytes`) and, for Parquet, PNG and meshes, read back with the expected
   rows / pixels / vertices (a ``verify`` callback; Open3D's writers report success after a failed
   write, so only the re-read is trusted);
3. it is renamed over the final name and the folder entry is flushed.

A crash, a ``kill -9`` or a full disk therefore never leaves a file under a final name that is not
complete; the temporary files it leaves carry the writer's process id and are deleted by the next
writer of that file or folder (:func:`remove_stale_temporaries`) once that process is gone. Files that
only make sense together (the outputs of ``wbsa fit``, the top of a study folder) are written into a
staging folder and moved in as a group with a marker file last (:func:`staged_files`); readers
require the marker. Operating-system errors (disk full, permissions, read-only file systems) become
one-line :class:`~wbsa.errors.WbsaError` messages naming the path and the fix
(:func:`os_error_message`). The table, JSON and text writers on top of it are in :mod:`wbsa.io`.
"""

from __future__ import annotations

import errno
import glob
import os
import re
import secrets
import shutil
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Iterator

from wbsa.errors import WbsaError

#: Suffix of every temporary file and staging folder (``.<name>.<pid>-<token>.part[.ext]``).
TEMP_SUFFIX = ".part"
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


def check_output_file(path: str | os.PathLike, suffixes: tuple[str, ...], what: str) -> Path:
    """Check an output file name before any work: not empty, one of ``suffixes``, not a folder, in a folder
    that is one (or can be made) and can be written.

    Parameters
    ----------
    path : path-like
    suffixes : tuple of str
        Allowed suffixes, lower case with the dot (``('.png',)``).
    what : str
        How the message names the output (a flag, e.g. ``--mask-out``).

    Returns
    -------
    Path

    Raises
    ------
    WbsaError
        One line naming ``what``, the problem and the fix.
    """
    text = os.fspath(path)
    if not str(text).strip():
        raise WbsaError(f"{what} needs a file name, got an empty one; give e.g. out{suffixes[0]}")
    path = Path(text)
    if path.suffix.lower() not in suffixes:
        raise WbsaError(f"{what} {path.name} must end in {' or '.join(suffixes)} (the file is written in that "
                        f"format; give e.g. {path.stem or 'out'}{suffixes[0]})")
    if path.is_dir():
        raise WbsaError(f"{what} {path} is a folder; give a file name")
    parent = path.parent if str(path.parent) else Path(".")
    existing = next((p for p in (parent, *parent.parents) if p.exists()), Path("."))
    if not existing.is_dir():
        raise WbsaError(f"{what} {path}: {existing} is a file, not a folder; give another path")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise WbsaError(f"{what} {path}: the folder {existing} cannot be written (permissions); give another path")
    return path


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
