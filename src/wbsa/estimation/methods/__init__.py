"""Estimation methods: one question (WBSA of a segmented, measured subject) behind one interface.

``base``        :class:`Subject`, :class:`Request`, :class:`Prediction`, the :class:`Predictor` interface
``view``        the view every method shares (mirror-equivalent azimuth, the view used, the stated-view check)
``dispatch``    :func:`predictors_for`, the one place a method is picked (``predictor_for`` deprecated)
``regression``  the estimator model (and a ``wbsa fit`` model file's per-view fits)
``body_fit``    anny fitted to the view and measured at rest

A new method is a package here with a :class:`Predictor`, its name in :data:`wbsa.typing.METHODS` and one branch
in :func:`predictors_for`. Names are imported lazily.
"""

from __future__ import annotations

from wbsa.lazy import lazy_exports

_EXPORTS = {
    "Subject": "wbsa.estimation.methods.base",
    "Request": "wbsa.estimation.methods.base",
    "Prediction": "wbsa.estimation.methods.base",
    "Predictor": "wbsa.estimation.methods.base",
    "check_method": "wbsa.estimation.methods.dispatch",
    "predictor_for": "wbsa.estimation.methods.dispatch",
    "predictors_for": "wbsa.estimation.methods.dispatch",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
