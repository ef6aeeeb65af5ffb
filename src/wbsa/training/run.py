"""Training a model for your own camera, distance range or population: :func:`train` (``wbsa train``).

A run keeps its renders in ``<folder>/renders`` as they finish (a run killed half-way resumes), holds the
folder's lock while it works (a second run on the same folder stops at once) and writes the model last,
atomically, as ``<folder>/model.npz``: give that file to ``wbsa estimate --model``.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path

from wbsa.errors import WbsaError
from wbsa.estimation.methods.regression.model import EstimatorModel
from wbsa.training.settings import TrainSettings

#: The install command of what training needs beyond the run-time estimator.
TRAIN_EXTRA = "pip install 'wbsa[train]'"


def check_training_dependencies() -> None:
    """Raise a one-line :class:`WbsaError` naming the install command if scikit-learn is missing."""
    try:
        import sklearn  # noqa: F401
    except ImportError:
        raise WbsaError(f"training needs scikit-learn, which is not installed; run: {TRAIN_EXTRA}") from None


@dataclass(frozen=True)
class TrainedModel:
    """A trained estimator model and where it lies.

    Attributes
    ----------
    model : EstimatorModel
    path : Path
        The model file (``model.npz``).
    folder : Path
        The run's folder (renders, model).
    settings_hash : str
    seconds : float
        Wall time of the run.
    """

    model: EstimatorModel
    path: Path
    folder: Path
    settings_hash: str
    seconds: float

    def __repr__(self) -> str:
        c = self.model.meta.get("calibration", {})
        return (f"TrainedModel({self.path}: calibration MAPE {c.get('wbsa_mape_pct', float('nan')):.2f} %, "
                f"{self.model.meta.get('n_fit')} fit / {self.model.meta.get('n_calibration')} calibration captures)")

    def summary(self) -> str:
        """The calibration figures in a few lines (held-out calibration subjects)."""
        m = self.model.meta
        c = m.get("calibration", {})
        return "\n".join([
            f"model {self.path} (settings {self.settings_hash}, {self.seconds / 60:.1f} min)",
            f"trained on {m.get('n_fit')} captures; calibrated on {m.get('n_calibration')} captures of "
            f"{m.get('n_calibration_subjects')} held-out subjects",
            f"calibration: WBSA MAPE {c.get('wbsa_mape_pct', float('nan')):.2f} %, bias "
            f"{c.get('wbsa_bias_pct', float('nan')):+.2f} %, azimuth error median "
            f"{c.get('azimuth_error_median_deg', float('nan')):.1f}° (95th percentile "
            f"{c.get('azimuth_error_p95_deg', float('nan')):.0f}°)",
            f"use it: wbsa estimate DEPTH --model {self.path}",
        ])


def train(settings: TrainSettings = TrainSettings(), out: str | os.PathLike | None = None, *,
          workers: int | None = None, show_progress: bool | None = None) -> TrainedModel:
    """Train an estimator model with ``settings`` (renders, fit, calibration), resumably.

    Parameters
    ----------
    settings : TrainSettings
        E.g. ``TrainSettings(render=RenderSettings(capture=CaptureSettings(cameras=("realsense-d455",),
        distance_m=(2.0, 5.0))))`` for one camera at 2–5 m.
    out : path-like, optional
        The run's folder; default ``~/.cache/wbsa/train-<settings hash>`` (:mod:`wbsa.training.cache`).
    workers : int, optional
        Local worker processes for the renders (default: the cores); the model does not depend on it.
    show_progress : bool, optional
        A progress bar (None: on a terminal; log lines every 30 s otherwise).

    Returns
    -------
    TrainedModel

    Raises
    ------
    WbsaError
        scikit-learn missing (before any work), a folder another run holds or that holds renders of other
        settings, a disk that fills (nothing half-written is left as a finished file).
    """
    from wbsa.folder_lock import folder_lock
    from wbsa.parallel import default_workers
    from wbsa.training.cache import training_folder
    from wbsa.training.recipe import MODEL_REVISION, settings_hash
    from wbsa.training.pipeline import train_model

    check_training_dependencies()
    if not isinstance(settings, TrainSettings):
        raise WbsaError(f"settings must be a TrainSettings, got {type(settings).__name__}")
    key = settings_hash(settings)
    folder = Path(out) if out is not None else training_folder(key)
    if folder.exists() and not folder.is_dir():
        raise WbsaError(f"{folder} is a file; give a folder for the training run")
    start = time.monotonic()
    with folder_lock(folder, "training folder"):
        model = train_model(settings, workers=workers or default_workers(), folder=folder / "renders",
                            show_progress=show_progress, log_lines=True)
        model.meta.update(name=f"trained-{key}", revision=MODEL_REVISION, settings_hash=key)
        path = model.save(folder / "model.npz")
    return TrainedModel(model, path, folder, key, time.monotonic() - start)


def rebuild_default_model(out=None, *, workers: int | None = None) -> tuple[Path, Path]:
    """Train ``TrainSettings()`` (resumably, in ``out`` or the cache) and write it as the shipped default model
    into the package's data folder (a checkout's ``src/wbsa/data`` with an editable install)."""
    from importlib import resources

    from wbsa.training.recipe import write_default_model

    settings = TrainSettings()
    result = train(settings, out, workers=workers)
    return write_default_model(result.model, settings, Path(str(resources.files("wbsa") / "data")))
