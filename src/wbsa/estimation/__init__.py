"""estimation stage: WBSA of a person from one depth image, with the view found and the input checked.

``mixed_pixels`` returns between two surfaces at a depth edge, snapped to one (:func:`repair_mixed_pixels`)
``segment``      the subject in a room: floor, walls behind, 3-D clusters (:func:`segment_subject`)
``measure``      VBSA, stature, size and view cues of the subject's pixels (:func:`measure_subject`)
``view``         azimuth (mirror-equivalent) and elevation from the image (:class:`ViewModel`)
``model``        the estimator model file: WBSA continuous in view and distance, calibrated interval
``train``        training on virtual captures; ``cache``: the default model, built on first use
``predict``      measures → WBSA with either an estimator model or a ``wbsa fit`` model
``checks``       one-line errors and named flags; ``fhir``: the FHIR R4 Observation
``single_view``  :func:`estimate`, the entry point (``wbsa.estimate`` calls it)
``capture``, ``renders``, ``room``, ``testset``  capture conditions, rendered samples, synthetic rooms, the benchmark

Names are imported lazily.
"""

from __future__ import annotations

from wbsa.lazy import lazy_exports

_EXPORTS = {
    "Estimate": "wbsa.estimation.single_view",
    "estimate": "wbsa.estimation.single_view",
    "repair_mixed_pixels": "wbsa.estimation.mixed_pixels",
    "SegmentSettings": "wbsa.estimation.segment",
    "Segmentation": "wbsa.estimation.segment",
    "segment_subject": "wbsa.estimation.segment",
    "SubjectMeasures": "wbsa.estimation.measure",
    "measure_subject": "wbsa.estimation.measure",
    "ViewEstimate": "wbsa.estimation.view",
    "ViewModel": "wbsa.estimation.view",
    "EstimatorModel": "wbsa.estimation.model",
    "TrainSettings": "wbsa.estimation.train",
    "train_model": "wbsa.estimation.train",
    "default_model": "wbsa.estimation.cache",
    "default_model_path": "wbsa.estimation.cache",
    "fhir_observation": "wbsa.estimation.fhir",
    "compose_room": "wbsa.estimation.room",
    "FLAGS": "wbsa.estimation.checks",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
