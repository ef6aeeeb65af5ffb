"""The estimator model shipped with wbsa, and the one place a model argument is resolved.

The default model is package data: ``wbsa/data/estimator-default.npz`` (numbers only, no pickle) with its model
card ``estimator-default.card.json`` beside it (revision, training-settings hash, what it was trained on, its
held-out figures and trained ranges). ``wbsa train --default`` rebuilds both (:mod:`wbsa.training.recipe`).
"""

from __future__ import annotations

import json
import os
from functools import lru_cache
from importlib import resources
from pathlib import Path

from wbsa.errors import WbsaError
from wbsa.estimation.methods.regression.model import EstimatorModel

#: File names of the shipped model and its card, in ``wbsa/data``.
DEFAULT_MODEL_FILE = "estimator-default.npz"
DEFAULT_CARD_FILE = "estimator-default.card.json"


def default_model_path() -> Path:
    """Where the shipped default model lies (inside the installed package)."""
    return Path(str(resources.files("wbsa") / "data" / DEFAULT_MODEL_FILE))


@lru_cache(maxsize=1)
def default_model() -> EstimatorModel:
    """The shipped default estimator model (read once per process)."""
    path = default_model_path()
    if not path.is_file():
        raise WbsaError(f"the default estimator model {path} is missing from this install; reinstall wbsa, or "
                        "rebuild it with wbsa train --default")
    model = EstimatorModel.load(path)
    model.meta["name"] = "default"
    return model


def model_card() -> dict:
    """The shipped model's card (JSON): revision, settings hash, training world, held-out figures, ranges."""
    path = default_model_path().with_name(DEFAULT_CARD_FILE)
    try:
        return json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise WbsaError(f"the default model's card {path} is unreadable ({type(exc).__name__}); reinstall wbsa") \
            from None


def load_model(model=None):
    """An :class:`EstimatorModel` or a ``wbsa fit`` :class:`~wbsa.analysis.model_file.WbsaModel`.

    ``None`` gives the shipped default model; a path ending in ``.npz`` an estimator model (e.g. one
    ``wbsa train`` wrote); ``.json`` a ``wbsa fit`` model file; a model object is returned as it is; anything else
    is refused in one line.

    Parameters
    ----------
    model : EstimatorModel, WbsaModel, path or None
    """
    if model is None:
        return default_model()
    if isinstance(model, (str, os.PathLike)):
        path = Path(model)
        if path.suffix.lower() == ".npz":
            return EstimatorModel.load(path)
        if path.suffix.lower() == ".json":
            from wbsa.analysis.model_file import WbsaModel

            legacy = WbsaModel.load(path)
            _check_legacy_finite(legacy, path)
            return legacy
        raise WbsaError(f"model {path.name} is neither an estimator model (.npz) nor a wbsa fit model (.json)")
    from wbsa.analysis.model_file import WbsaModel

    if not isinstance(model, (EstimatorModel, WbsaModel)):
        raise WbsaError(f"model must be None (the default model), a model file path (.npz or .json), an "
                        f"EstimatorModel or a WbsaModel, got {type(model).__name__}")
    return model


def _check_legacy_finite(model, path) -> None:
    import numpy as np

    for e in model.entries:
        for key in ("coef", "cov_unscaled", "scale"):
            if not np.all(np.isfinite(np.asarray(e[key], dtype=float))):
                raise WbsaError(f"model {path} holds non-finite numbers ({key} of the {e['model']} fit at azimuth "
                                f"{e['azimuth_deg']:g}, elevation {e['elevation_deg']:g}); refit with wbsa fit")
