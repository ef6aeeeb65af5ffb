"""Estimation methods: one question (WBSA of a segmented, measured subject) behind one interface.

Modelled on the ray-casting back ends (:mod:`wbsa.camera.backends`): every method is a :class:`Predictor`
in a module of its own, and :func:`predictor_for` is the one place that picks it.

``regression`` (:mod:`.regression`)
    The estimator model (:class:`~wbsa.estimation.model.EstimatorModel`): the subject's measures and the view
    estimated from the image through a ridge regression and residual trees, with a split-conformal interval.
    The shipped default model (:mod:`wbsa.estimation.default_model`) or a model file ``wbsa train`` wrote.
``regression`` with a ``wbsa fit`` model file (:mod:`.per_view`)
    The paper's per-view regressions at one camera and distance: the nearest fitted view is used and any
    difference in camera, distance or view is flagged ``model_mismatch``.
``body-fit`` (:mod:`.body_fit`)
    anny fitted to the view (shape, posture, camera pose; :func:`wbsa.estimation.bodyfit.fit_body`) and its rest-pose
    skin measured; the fitted body comes with the estimate.
``both``
    The regression and the body fit side by side (:func:`predictors_for`): the regression's number leads,
    the body fit's is reported beside it, and intervals that do not overlap are flagged ``methods_disagree``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

import numpy as np

from wbsa.errors import WbsaError
from wbsa.typing import METHODS, Method

if TYPE_CHECKING:  # pragma: no cover
    from wbsa.camera.intrinsics import Intrinsics
    from wbsa.estimation.cloud import Plane
    from wbsa.estimation.measure import SubjectMeasures
    from wbsa.estimation.view import ViewEstimate


@dataclass(frozen=True)
class Subject:
    """The subject of one depth image, segmented and measured: what every method starts from.

    Attributes
    ----------
    depth_m : (h, w) float64
        The depth image (metres, 0 = no return), mixed returns repaired.
    mask : (h, w) bool
        The subject's pixels (the segmentation).
    camera : Intrinsics
    floor : Plane or None
        The detected floor in the camera frame.
    measures : SubjectMeasures
    """

    depth_m: np.ndarray
    mask: np.ndarray
    camera: Intrinsics
    floor: Plane | None
    measures: SubjectMeasures


@dataclass(frozen=True)
class Request:
    """What the user states beside the image: the view (degrees, None = estimate it), the layer of clothes
    (m) and the interval's level."""

    azimuth_deg: float | None = None
    elevation_deg: float | None = None
    clothing_m: float = 0.0
    level: float = 0.95


@dataclass(frozen=True)
class Prediction:
    """WBSA and its interval (m²), the view estimated and the view used (degrees), the model's name, its flags and,
    for a method that fits a whole body, the fitted body."""

    wbsa_m2: float
    lo_m2: float
    hi_m2: float
    view: ViewEstimate
    view_used: tuple[float, float]
    model_name: str
    flags: dict[str, str] = field(default_factory=dict)
    body: object = None


class Predictor(Protocol):
    """What a method does: predict WBSA of one subject."""

    name: str

    def check_request(self, request: Request) -> None:
        """Raise :class:`WbsaError` for a request this predictor cannot serve (before the image is measured)."""

    def predict(self, subject: Subject, request: Request) -> Prediction:
        """WBSA of ``subject`` with its interval and flags."""


def check_method(method: str) -> Method:
    """``method`` if it is a method name, else a one-line :class:`WbsaError`."""
    if not isinstance(method, str) or method not in METHODS:
        raise WbsaError(f"estimation method {method!r} is unknown; use one of {', '.join(METHODS)}")
    return method  # type: ignore[return-value]


def predictors_for(method: Method, model=None) -> tuple[Predictor, ...]:
    """The predictors of ``method``: one, or for ``both`` the regression's then the body fit's."""
    check_method(method)
    if method == "both":
        return predictor_for("regression", model), predictor_for("body-fit")
    return (predictor_for(method, model),)


def predictor_for(method: Method, model=None) -> Predictor:
    """The predictor of one method with ``model`` (the one dispatch point).

    Parameters
    ----------
    method : {'regression', 'body-fit'}
    model : EstimatorModel, WbsaModel, path or None
        The regression's model (the body fit has its own).
        None: the shipped default model. A path: an estimator model file (``.npz``) or a ``wbsa fit`` model
        file (``.json``), read and checked at once.

    Returns
    -------
    Predictor
    """
    from wbsa.estimation.default_model import load_model
    from wbsa.estimation.model import EstimatorModel

    check_method(method)
    if method == "both":
        raise WbsaError("predictor_for takes one method; use predictors_for for both")
    if method == "body-fit":
        from wbsa.estimation.methods.body_fit import BodyFitPredictor

        if model is not None:
            raise WbsaError("the body fit uses no estimator model; drop the model (or use method both to run the "
                            "regression with it beside the body fit)")
        return BodyFitPredictor()
    loaded = load_model(model)
    if isinstance(loaded, EstimatorModel):
        from wbsa.estimation.methods.regression import RegressionPredictor

        return RegressionPredictor(loaded)
    from wbsa.estimation.methods.per_view import PerViewPredictor  # a wbsa fit model (load_model checked it)

    return PerViewPredictor(loaded)


__all__ = ["Prediction", "Predictor", "Request", "Subject", "check_method", "predictor_for", "predictors_for"]
