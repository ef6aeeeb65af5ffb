"""estimation stage: WBSA of a person from one depth image, with the view found and the input checked.

``mixed_pixels`` returns between two surfaces at a depth edge, snapped to one (:func:`repair_mixed_pixels`)
``segment``      the subject in a room: floor, walls behind, 3-D clusters (:func:`segment_subject`)
``measure``      VBSA, stature, size and view cues of the subject's pixels (:func:`measure_subject`)
``view``         azimuth (mirror-equivalent) and elevation from the image (:class:`ViewModel`)
``trees``        boosted trees as plain arrays (no pickle, no scikit-learn at run time)
``model``        the estimator model file: WBSA continuous in view and distance, calibrated interval
``default_model`` the model shipped with wbsa (package data) and its card; resolves a ``model`` argument
``methods``      the method slot: one :class:`Predictor` per route (``regression``), one dispatch point
``checks``       one-line errors and named flags; ``fhir``: the FHIR R4 Observation
``single_view``  :func:`estimate`, the entry point (``wbsa.estimate`` calls it)
``command``      ``wbsa estimate``

This is the run-time path (image → :class:`Estimate`): it imports nothing from :mod:`wbsa.training`, where
models are trained. Names are imported lazily.
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
    "Predictor": "wbsa.estimation.methods",
    "predictor_for": "wbsa.estimation.methods",
    "default_model": "wbsa.estimation.default_model",
    "default_model_path": "wbsa.estimation.default_model",
    "model_card": "wbsa.estimation.default_model",
    "fhir_observation": "wbsa.estimation.fhir",
    "FLAGS": "wbsa.estimation.checks",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
