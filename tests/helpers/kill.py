"""Kill a running ``wbsa`` process at a point of its work, not of the clock."""

from __future__ import annotations

import os
import signal
import subprocess
import time
from typing import Callable


def kill_when(proc: subprocess.Popen, done: Callable[[], int], at: int) -> None:
    """Wait until ``done()`` (a count of the work the process has written) reaches ``at``, then kill -9 its
    process group (started with ``start_new_session=True``); a process that ends first is left as it ended.
    Its pipes are drained."""
    while proc.poll() is None and done() < at:
        time.sleep(0.01)
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    proc.communicate()
