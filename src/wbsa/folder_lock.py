"""One writer per output folder: an advisory file lock (``fcntl.flock``) on ``DIR/.wbsa.lock``.

``wbsa scan`` and ``wbsa run`` hold the lock of their folder for the whole run. A second process
that wants to write the same folder does not wait: it stops at once with a one-line error naming
the folder and the process that holds it, before it has read or written anything there. (Waiting
would let two studies with different settings take turns on one folder, each replacing the other's
top-level files; refusing makes the clash visible.) The lock is released by the operating system
when the holder exits, however it exits (``kill -9`` included), so a crashed run never leaves a
folder locked; the lock file itself stays and is harmless.

The lock is advisory and local: it protects against other wbsa processes on this machine (and on
network file systems that support ``flock``), not against other programs.
"""

from __future__ import annotations

import errno
import os
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from wbsa.errors import WbsaError

#: Name of the lock file inside a locked folder.
LOCK_FILE = ".wbsa.lock"

#: Folders this process holds (path -> depth), so a nested lock of the same folder does not deadlock.
_HELD: dict[str, int] = {}


def _holder(path: Path) -> str:
    try:
        text = path.read_text().strip()
    except OSError:
        return ""
    return f" ({text})" if text else ""


@contextmanager
def folder_lock(folder: str | os.PathLike, what: str = "output folder") -> Iterator[Path]:
    """Hold the write lock of ``folder`` (created if missing) for the duration of the block.

    Parameters
    ----------
    folder : path-like
    what : str
        How the folder is called in the error message (``scan folder``, ``study folder``).

    Raises
    ------
    WbsaError
        If another process holds the lock, or the folder cannot be created.
    """
    from wbsa.atomic import os_error_message

    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise WbsaError(f"{what} {folder} is a file; give a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise WbsaError(os_error_message(exc, folder, "create folder")) from None
    key = str(folder.resolve())
    if key in _HELD:
        _HELD[key] += 1
        try:
            yield folder
        finally:
            _HELD[key] -= 1
        return
    path = folder / LOCK_FILE
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    except OSError as exc:
        raise WbsaError(os_error_message(exc, folder)) from None
    try:
        _acquire(fd, folder, path, what)
        try:
            os.ftruncate(fd, 0)
            os.write(fd, f"pid {os.getpid()}, since {time.strftime('%Y-%m-%d %H:%M:%S')}\n".encode())
        except OSError:  # the description is only for the message of a second process
            pass
        _HELD[key] = 1
        try:
            yield folder
        finally:
            del _HELD[key]
    finally:
        os.close(fd)  # releases the lock


def _acquire(fd: int, folder: Path, path: Path, what: str) -> None:
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not on POSIX: no locking
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        raise WbsaError(f"{what} {folder} is being written by another wbsa process{_holder(path)}; wait for it "
                        "to finish or choose another output folder") from None
    except OSError as exc:
        if exc.errno in (errno.ENOLCK, errno.EOPNOTSUPP, errno.ENOSYS):
            return  # a file system without locks: go on unprotected, as before
        raise
