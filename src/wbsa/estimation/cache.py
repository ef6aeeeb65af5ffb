"""The default estimator model: trained on first use, then read from a cache.

The cache folder is ``$WBSA_CACHE_DIR`` if set, else ``~/.cache/wbsa``; the file is named after the model
revision and a hash of its training settings (``estimator-r<rev>-<hash>.npz``), so a new wbsa that changes
either trains a new model instead of reading a stale one. Delete the file to retrain.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
from dataclasses import asdict
from functools import lru_cache
from pathlib import Path

from wbsa.estimation.model import EstimatorModel
from wbsa.estimation.train import TrainSettings

CACHE_ENV = "WBSA_CACHE_DIR"
#: Bumped whenever the measures, the renders or the model change what a trained model means.
MODEL_REVISION = 16


def cache_dir() -> Path:
    """``$WBSA_CACHE_DIR``, else ``~/.cache/wbsa``."""
    env = os.environ.get(CACHE_ENV)
    return Path(env).expanduser() if env else Path.home() / ".cache" / "wbsa"


def default_model_path(settings: TrainSettings = TrainSettings()) -> Path:
    """Where the model trained with ``settings`` is cached."""
    key = hashlib.sha256(json.dumps(asdict(settings), sort_keys=True, default=str).encode()).hexdigest()[:12]
    return cache_dir() / f"estimator-r{MODEL_REVISION}-{key}.npz"


@lru_cache(maxsize=2)
def default_model(settings: TrainSettings = TrainSettings(), show_progress: bool | None = None) -> EstimatorModel:
    """The cached default model; trained and written to :func:`default_model_path` if missing.

    Training renders and segments ``(n_random + n_survey) × views_per_subject`` captures, most in rooms (5,520
    by default, at about 3.4 per second on 2 idle cores: some 27 minutes).
    """
    from wbsa.parallel import default_workers

    path = default_model_path(settings)
    if path.is_file():
        model = EstimatorModel.load(path)
    else:
        n = (settings.n_random + settings.n_survey) * settings.views_per_subject
        sys.stderr.write(f"building the default estimator model from {n} virtual captures (first use only); "
                         f"it will be cached at {path}\n")
        model = train_model_cached(settings, path, default_workers(), show_progress)
    model.meta["name"] = "default"
    return model


def train_model_cached(settings: TrainSettings, path: Path, workers: int, show_progress: bool | None) -> EstimatorModel:
    """Train with ``settings`` and write the model to ``path``."""
    from wbsa.estimation.train import train_model

    model = train_model(settings, workers=workers, show_progress=show_progress)
    model.meta["name"] = path.name
    model.save(path)
    return model
