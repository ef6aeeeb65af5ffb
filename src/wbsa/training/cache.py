"""Where ``wbsa train`` keeps what it makes when no ``--out`` is given: ``$WBSA_CACHE_DIR``, else
``~/.cache/wbsa``, one folder per training-settings hash (its renders, for resuming, and its model)."""

from __future__ import annotations

import os
from pathlib import Path

CACHE_ENV = "WBSA_CACHE_DIR"


def cache_dir() -> Path:
    """``$WBSA_CACHE_DIR``, else ``~/.cache/wbsa``."""
    env = os.environ.get(CACHE_ENV)
    return Path(env).expanduser() if env else Path.home() / ".cache" / "wbsa"


def training_folder(settings_hash: str) -> Path:
    """The cache folder of a training run with these settings (``train-<hash>``)."""
    return cache_dir() / f"train-{settings_hash}"
