"""Which method answers: one question (WBSA of a segmented, measured subject) behind one interface.

Modelled on the ray-casting back ends (:mod:`wbsa.camera.backends`): every method is a :class:`Predictor`
in a module of its own, and :func:`predictors_for` is the one place that picks it (:func:`predictor_for`, one
method's, is deprecated).

``regression`` (:mod:`.regression`)
    The estimator model (:class:`~wbsa.estimation.methods.regression.model.EstimatorModel`): the subject's measures and the view
    estimated from the image through a ridge regression and residual trees, with a split-conformal interval.
    The shipped default model (:mod:`wbsa.estimation.methods.regression.default_model`) or a model file ``wbsa train`` wrote.
``regression`` with a ``wbsa fit`` model file (:mod:`.regression.per_view`)
    The paper's per-view regressions at one camera and distance: the nearest fitted view is used and any
    difference in camera, distance or view is flagged ``model_mismatch``.
``body-fit`` (:mod:`.body_fit`)
    anny fitted to the view (shape, posture, camera pose; :func:`wbsa.estimation.methods.body_fit.fit_body`) and its rest-pose
    skin measured; the fitted body comes with the estimate.
``both``
    The regression and the body fit side by side (:func:`predictors_for`): the regression's number leads,
    the body fit's is reported beside it, and intervals that do not overlap are flagged ``methods_disagree``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from wbsa.errors import WbsaError
from wbsa.typing import METHODS, Method

if TYPE_CHECKING:  # pragma: no cover
    from wbsa.estimation.methods.base import Predictor
    from wbsa.estimation.methods.body_fit.settings import BodyFitSettings


def check_method(method: str) -> Method:
    """``method`` if it is a method name, else a one-line :class:`WbsaError`.

    Parameters
    ----------
    method : str
        A name of :data:`wbsa.typing.METHODS`.
    """
    if not isinstance(method, str) or method not in METHODS:
        raise WbsaError(f"estimation method {method!r} is unknown; use one of {', '.join(METHODS)}")
    return method  # type: ignore[return-value]


def predictors_for(method: Method, model=None, body_fit: BodyFitSettings | None = None) -> tuple[Predictor, ...]:
    """The predictors of ``method``: one, or for ``both`` the regression's then the body fit's.

    ``method`` is not checked again here (:func:`wbsa.estimation.estimate` checks it first, with
    :func:`check_method`); a name that is none of the methods still gets that one-line refusal.

    Parameters
    ----------
    method : {'regression', 'body-fit', 'both'}
    model : EstimatorModel, WbsaModel, path or None
        The regression's model (the body fit has its own). None: the shipped default model. A path: an
        estimator model file (``.npz``) or a ``wbsa fit`` model file (``.json``), read and checked at once.
    body_fit : BodyFitSettings or None
        The body fit's settings (None: the defaults); only with ``body-fit`` or ``both``.

    Returns
    -------
    tuple of Predictor
    """
    if method == "both":
        _check_body_fit_settings(body_fit)
        return _predictor("regression", model, None), _predictor("body-fit", None, body_fit)
    return (_predictor(method, model, body_fit),)


def predictor_for(method: Method, model=None, body_fit: BodyFitSettings | None = None) -> Predictor:
    """The predictor of one method with ``model``; deprecated (a :class:`DeprecationWarning`): use
    :func:`predictors_for`, the one dispatch point.

    Parameters
    ----------
    method : {'regression', 'body-fit'}
    model : EstimatorModel, WbsaModel, path or None
        The regression's model (the body fit has its own).
        None: the shipped default model. A path: an estimator model file (``.npz``) or a ``wbsa fit`` model
        file (``.json``), read and checked at once.
    body_fit : BodyFitSettings or None
        The body fit's settings (None: the defaults); only with ``body-fit``.

    Returns
    -------
    Predictor
    """
    import warnings

    warnings.warn("predictor_for is deprecated; use predictors_for(method, model, body_fit)", DeprecationWarning,
                  stacklevel=2)
    check_method(method)
    if method == "both":
        raise WbsaError("predictor_for takes one method; use predictors_for for both")
    return _predictor(method, model, body_fit)


def _check_body_fit_settings(body_fit) -> None:
    from wbsa.estimation.methods.body_fit.settings import BodyFitSettings

    if body_fit is not None and not isinstance(body_fit, BodyFitSettings):
        raise WbsaError(f"body_fit must be BodyFitSettings or None, got {type(body_fit).__name__}")


def _predictor(method: Method, model, body_fit) -> Predictor:
    """The predictor of one method name (the one dispatch; a name that is no method is refused here)."""
    if method == "body-fit":
        from wbsa.estimation.methods.body_fit.predictor import BodyFitPredictor

        if model is not None:
            raise WbsaError("the body fit uses no estimator model; drop the model (or use method both to run the "
                            "regression with it beside the body fit)")
        _check_body_fit_settings(body_fit)
        return BodyFitPredictor(body_fit)
    if method != "regression":
        check_method(method)  # refuses it: "both" is not one method, anything else is none
        raise WbsaError("predictor_for takes one method; use predictors_for for both")
    if body_fit is not None:
        raise WbsaError("body-fit settings go with method body-fit or both; drop them for the regression")
    from wbsa.estimation.methods.regression.default_model import load_model
    from wbsa.estimation.methods.regression.model import EstimatorModel

    loaded = load_model(model)
    if isinstance(loaded, EstimatorModel):
        from wbsa.estimation.methods.regression.predictor import RegressionPredictor

        return RegressionPredictor(loaded)
    from wbsa.estimation.methods.regression.per_view import PerViewPredictor  # a wbsa fit model (load_model checked it)

    return PerViewPredictor(loaded)


__all__ = ["check_method", "predictor_for", "predictors_for"]
