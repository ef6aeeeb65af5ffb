"""Progress bars for long work, shown on stderr only when it is a terminal or asked for."""

from __future__ import annotations

import os
import sys
from typing import Iterable, TypeVar

from tqdm.auto import tqdm

T = TypeVar("T")


def progress(iterable: Iterable[T] | None = None, *, total: int | None = None, desc: str = "", unit: str = "it",
             enabled: bool | None = None) -> tqdm:
    """A tqdm bar with rate and ETA on stderr.

    ``enabled=None`` shows it when stderr is a terminal, or when ``WBSA_PROGRESS=1``;
    ``WBSA_PROGRESS=0`` hides it everywhere.
    """
    if enabled is None:
        env = os.environ.get("WBSA_PROGRESS")
        enabled = (env == "1") if env in ("0", "1") else sys.stderr.isatty()
    return tqdm(iterable, total=total, desc=desc, unit=unit, disable=not enabled, file=sys.stderr,
                dynamic_ncols=True, smoothing=0.1)
