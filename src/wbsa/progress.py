"""Progress of long work on stderr: a bar on a terminal, or log lines where the output is not one.

A bar is shown when stderr is a terminal, or when ``WBSA_PROGRESS=1``; ``WBSA_PROGRESS=0`` hides it everywhere.
Work long enough to be left running in a log (``wbsa train``) asks for ``log_lines``: where no bar is shown, a
line ``desc: done/total unit (pct %), rate unit/s, about N min left`` is written every ``LOG_EVERY_S`` seconds.
"""

from __future__ import annotations

import os
import sys
import time
from typing import Iterable, TypeVar

from tqdm.auto import tqdm

T = TypeVar("T")

#: Seconds between two log lines of :class:`LogLines`.
LOG_EVERY_S = 30.0


class LogLines:
    """A progress counter written as one line on stderr every ``every_s`` seconds and at the end (the
    ``update``/``close`` subset of tqdm's interface)."""

    def __init__(self, total: int | None, desc: str, unit: str, every_s: float = LOG_EVERY_S) -> None:
        self.total, self.desc, self.unit, self.every_s = total, desc, unit, every_s
        self.n, self._start, self._last = 0, time.monotonic(), time.monotonic()

    def update(self, n: int = 1) -> None:
        """Count ``n`` more; write a line when ``every_s`` have passed since the last."""
        self.n += n
        if time.monotonic() - self._last >= self.every_s:
            self._write()

    def close(self) -> None:
        """Write the last line."""
        self._write()

    def _write(self) -> None:
        self._last = now = time.monotonic()
        rate = self.n / max(now - self._start, 1e-9)
        line = f"{self.desc}: {self.n}"
        if self.total:
            line += f"/{self.total} {self.unit} ({100 * self.n / self.total:.0f} %)"
            if 0 < self.n < self.total and rate > 0:
                line += f", {rate:.2f} {self.unit}/s, about {(self.total - self.n) / rate / 60:.0f} min left"
        else:
            line += f" {self.unit}, {rate:.2f} {self.unit}/s"
        sys.stderr.write(line + "\n")
        sys.stderr.flush()


def progress(iterable: Iterable[T] | None = None, *, total: int | None = None, desc: str = "", unit: str = "it",
             enabled: bool | None = None, log_lines: bool = False) -> tqdm | LogLines:
    """A tqdm bar with rate and ETA on stderr, or :class:`LogLines` (see the module doc).

    ``enabled=None`` shows the bar when stderr is a terminal, or when ``WBSA_PROGRESS=1``;
    ``WBSA_PROGRESS=0`` hides it everywhere. ``log_lines`` (without an iterable): where ``enabled`` is None, the bar is
    not shown and progress is not hidden, log lines instead.
    """
    env = os.environ.get("WBSA_PROGRESS")
    auto = enabled is None
    if auto:
        enabled = (env == "1") if env in ("0", "1") else sys.stderr.isatty()
    if log_lines and auto and not enabled and iterable is None and env != "0":
        return LogLines(total, desc, unit)
    return tqdm(iterable, total=total, desc=desc, unit=unit, disable=not enabled, file=sys.stderr,
                dynamic_ncols=True, smoothing=0.1)
