"""The regression method: an estimator model's WBSA from the subject's measures and the view found in the image.

See :mod:`wbsa.estimation.methods.regression.model` for what the model reads and how its interval is calibrated.
"""

from __future__ import annotations

import numpy as np

from wbsa.estimation.methods.base import Prediction, Request, Subject
from wbsa.estimation.methods.regression.model import EstimatorModel
from wbsa.estimation.methods.view import view_used


class RegressionPredictor:
    """:class:`~wbsa.estimation.methods.Predictor` of an :class:`EstimatorModel`."""

    name = "regression"

    def __init__(self, model: EstimatorModel) -> None:
        self.model = model

    def check_request(self, request: Request) -> None:
        """Every request is served (a layer of clothes beyond the trained range is flagged, not refused).

        Parameters
        ----------
        request : Request
            As for :meth:`~wbsa.estimation.methods.base.Predictor.check_request`.
        """

    def predict(self, subject: Subject, request: Request) -> Prediction:
        """WBSA of ``subject`` with the model's split-conformal interval; flags ``uncertain_view``,
        ``out_of_training_range`` and ``interval_unsure``. The area measures of a subject whose legs are not
        seen are completed first, and the estimate corrected by the mean error on cut frames
        (:func:`wbsa.estimation.subject.unseen.completed`, :func:`~wbsa.estimation.subject.unseen.corrected`).

        Parameters
        ----------
        subject, request : Subject, Request
            As for :meth:`~wbsa.estimation.methods.base.Predictor.predict`.
        """
        from wbsa.estimation.subject.checks import range_flags
        from wbsa.estimation.methods.regression.design import range_values, with_clothing
        from wbsa.estimation.subject.unseen import completed, corrected

        model, measures = self.model, subject.measures
        view = model.view.estimate(measures)
        (az, el), flags = view_used(view, request.azimuth_deg, request.elevation_deg)
        feats = with_clothing(completed({k: np.array([v]) for k, v in measures.features().items()}, subject.unseen),
                              request.clothing_m)
        # a stated view counts as sure as the surest estimated one: the models never saw a smaller spread
        az_sd = view.azimuth_sd_deg if request.azimuth_deg is None else model.view.axis_sd_deg
        w, lo, hi = (corrected(x, subject.unseen) for x in model.predict(
            feats, measures.shape[None], np.array([az]), np.array([az_sd]), np.array([el]), request.level))
        values = range_values({**feats, "elevation_deg": np.array([el])})
        flags.update(range_flags({k: float(v[0]) for k, v in values.items()}, model.ranges))
        if not model.quantile_is_sure(request.level):
            flags["interval_unsure"] = (f"the model was calibrated on {model.n_calibration_subjects} "
                                        f"subjects, too few to promise {100 * request.level:g} %; its widest score "
                                        "is used")
        return Prediction(float(w[0]), float(lo[0]), float(hi[0]), view, (az, el), model.name, flags)
