"""The regression method: WBSA from the subject's measures and the view estimated from the image.

``predictor``     :class:`RegressionPredictor`, the method's :class:`~wbsa.estimation.methods.base.Predictor`
``model``         the estimator model file: WBSA continuous in view and distance, calibrated interval
``design``        the model's design (features, clothes, training ranges)
``trees``         boosted trees as plain arrays (no pickle, no scikit-learn at run time)
``view_model``    azimuth (mirror-equivalent) from the image (:class:`ViewModel`)
``default_model`` the model shipped with wbsa (package data) and its card; resolves a ``model`` argument
``per_view``      :class:`PerViewPredictor`: a ``wbsa fit`` model file's per-view regressions

Names are imported lazily.
"""

from __future__ import annotations

from wbsa.lazy import lazy_exports

_EXPORTS = {
    "RegressionPredictor": "wbsa.estimation.methods.regression.predictor",
    "PerViewPredictor": "wbsa.estimation.methods.regression.per_view",
    "EstimatorModel": "wbsa.estimation.methods.regression.model",
    "ViewModel": "wbsa.estimation.methods.regression.view_model",
    "default_model": "wbsa.estimation.methods.regression.default_model",
    "default_model_path": "wbsa.estimation.methods.regression.default_model",
    "load_model": "wbsa.estimation.methods.regression.default_model",
    "model_card": "wbsa.estimation.methods.regression.default_model",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
