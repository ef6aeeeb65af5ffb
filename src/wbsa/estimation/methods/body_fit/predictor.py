"""The body-fit method: anny fitted to the one depth view (shape, posture, camera pose), its rest-pose skin measured.

The whole body is fitted to the segmented subject's points and silhouette (:func:`wbsa.estimation.methods.body_fit.fit_body`); the
WBSA is the fitted body's skin at rest, with the split-conformal interval of :mod:`wbsa.estimation.methods.body_fit.interval`. The
fitted body (:class:`~wbsa.estimation.methods.body_fit.result.BodyFit`: stature, mass, tapes, posture, meshes) rides along in
:attr:`Prediction.body`.
"""

from __future__ import annotations

import math

from wbsa.errors import WbsaError
from wbsa.estimation.methods.base import Prediction, Request, Subject
from wbsa.estimation.methods.view import ViewEstimate, fold_azimuth


class BodyFitPredictor:
    """:class:`~wbsa.estimation.methods.Predictor` of the body fit."""

    name = "body-fit"

    def __init__(self, settings=None) -> None:
        from wbsa.estimation.methods.body_fit.settings import BodyFitSettings

        self.settings = settings or BodyFitSettings()

    def check_request(self, request: Request) -> None:
        """Refuse an interval level other than the one its interval was calibrated at.

        Parameters
        ----------
        request : Request
            As for :meth:`~wbsa.estimation.methods.base.Predictor.check_request`.
        """
        from wbsa.estimation.methods.body_fit.interval import load

        calibration = load()
        if calibration is not None and abs(request.level - calibration.level) > 1e-9:
            said = f"the body fit's interval is calibrated at level {calibration.level:g} only"
            raise WbsaError(f"{said}; give --level {calibration.level:g} or use --method regression",
                            code="out_of_range", field="level", value=request.level,
                            page=f"{said}; choose the method regression")

    def predict(self, subject: Subject, request: Request) -> Prediction:
        """WBSA of the fitted body at rest; its flags (``not_converged`` ...) become the estimate's.

        Parameters
        ----------
        subject, request : Subject, Request
            As for :meth:`~wbsa.estimation.methods.base.Predictor.predict`.
        """
        from wbsa.estimation.methods.body_fit.fit import fit_body

        fit = fit_body(subject.depth_m, subject.mask, subject.camera.intrinsics, subject.floor,
                       clothing_m=request.clothing_m, azimuth_deg=request.azimuth_deg, settings=self.settings,
                       progress=request.progress, sensor=subject.sensor)
        psi = float(fold_azimuth(fit.azimuth_deg))
        view = ViewEstimate(psi, float("nan"), fit.elevation_deg, float("nan"), float("nan"))
        az = psi if request.azimuth_deg is None else float(fold_azimuth(request.azimuth_deg))
        el = fit.elevation_deg  # the fit places the body itself; a stated elevation is checked against it
        flags = dict(fit.flags)
        lo, hi = fit.wbsa_lo_m2, fit.wbsa_hi_m2
        if not (math.isfinite(lo) and math.isfinite(hi)):
            flags["no_interval"] = "the body fit has no calibrated interval; its bounds are the estimate"
            lo = hi = fit.wbsa_m2
        return Prediction(fit.wbsa_m2, lo, hi, view, (az, el), "body-fit (anny)", flags, body=fit)
