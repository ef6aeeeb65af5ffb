"""estimation stage: WBSA of a person from one depth image, with the view found and the input checked.

``subject``      image → measured subject: mixed pixels, segmentation, measures, the input checks
                 (:func:`segment_subject`, :func:`measure_subject`)
``methods``      the method slot: :class:`Predictor` (``methods.base``), one dispatch point (``predictors_for``),
                 the methods ``regression`` (the estimator model, the shipped default model) and ``body_fit``
``request``      :class:`EstimateRequest`: what was asked, checked once (the camera's record, clothes, stature, ...)
``single_view``  :func:`estimate`, the entry point (``wbsa.estimate`` calls it): request → subject → routes → answer
``limits``       the one table of limits (human height, clothing thickness, depth range)
``flags``        every flag: its meaning, the page's advice, the routes that raise it
``clothes``      the clothes a user states: the table of named layers and their uncertainty
``fhir``         the FHIR R4 Observation
``command``      ``wbsa estimate``

This is the run-time path (image → :class:`Estimate`): it imports nothing from :mod:`wbsa.training`, where
models are trained. Names are imported lazily.
"""

from __future__ import annotations

from wbsa.lazy import lazy_exports

_EXPORTS = {
    "Estimate": "wbsa.estimation.single_view",
    "estimate": "wbsa.estimation.single_view",
    "estimate_request": "wbsa.estimation.single_view",
    "EstimateRequest": "wbsa.estimation.request",
    "LIMITS": "wbsa.estimation.limits",
    "repair_mixed_pixels": "wbsa.estimation.subject.mixed_pixels",
    "SegmentSettings": "wbsa.estimation.subject.settings",
    "Segmentation": "wbsa.estimation.subject.segment",
    "segment_subject": "wbsa.estimation.subject.segment",
    "SubjectMeasures": "wbsa.estimation.subject.measure",
    "measure_subject": "wbsa.estimation.subject.measure",
    "ViewEstimate": "wbsa.estimation.methods.view",
    "ViewModel": "wbsa.estimation.methods.regression.view_model",
    "EstimatorModel": "wbsa.estimation.methods.regression.model",
    "Predictor": "wbsa.estimation.methods.base",
    "predictor_for": "wbsa.estimation.methods.dispatch",
    "BodyFitSettings": "wbsa.estimation.methods.body_fit.settings",
    "default_model": "wbsa.estimation.methods.regression.default_model",
    "default_model_path": "wbsa.estimation.methods.regression.default_model",
    "model_card": "wbsa.estimation.methods.regression.default_model",
    "fhir_observation": "wbsa.estimation.fhir",
    "FLAGS": "wbsa.estimation.flags",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
