"""training stage: estimator models trained on virtual captures (``wbsa train``).

``settings``  :class:`TrainSettings`: subjects, captures (composing :class:`RenderSettings`), trees, seed
``capture``   random capture conditions: camera, distance, height, view, sensor (:class:`CaptureSettings`)
``room``      a body standing in a synthetic room: floor, wall, a second person
``renders``   posed bodies rendered and measured by the estimator's own code (:func:`render_samples`)
``store``     finished render chunks on disk, so a killed run resumes (:class:`RenderStore`)
``fit``       the model's fit on rendered samples: view model, regression, trees, spread, scores
``pipeline``  :func:`train_model`: population → renders → fit → calibration
``recipe``    the shipped default model: revision, settings hash, rebuild, model card
``cache``     where ``wbsa train`` keeps its runs without ``--out``
``run``       :func:`train`, the entry point (``wbsa.train`` and ``wbsa train`` call it)

The run-time estimator (:mod:`wbsa.estimation`) imports nothing from here. Names are imported lazily.
"""

from __future__ import annotations

from wbsa.lazy import lazy_exports

_EXPORTS = {
    "TrainSettings": "wbsa.training.settings",
    "RenderSettings": "wbsa.training.settings",
    "CaptureSettings": "wbsa.training.capture",
    "train_model": "wbsa.training.pipeline",
    "training_renders": "wbsa.training.pipeline",
    "train": "wbsa.training.run",
    "TrainedModel": "wbsa.training.run",
    "compose_room": "wbsa.training.room",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
