"""The regression method with a ``wbsa fit`` model file: the paper's per-view regressions of WBSA on VBSA.

Such a model was fitted at one camera and distance on a grid of views: the nearest fitted view is used and
any difference in camera, distance or view is flagged ``model_mismatch``. The azimuth is estimated by the
shipped default model's view model (a ``wbsa fit`` model has none).
"""

from __future__ import annotations

from wbsa.errors import WbsaError
from wbsa.estimation.methods.base import Prediction, Request, Subject
from wbsa.estimation.methods.view import azimuth_error_deg, view_used


class PerViewPredictor:
    """:class:`~wbsa.estimation.methods.Predictor` of a ``wbsa fit`` :class:`~wbsa.analysis.model_file.WbsaModel`."""

    name = "regression"

    def __init__(self, model) -> None:
        self.model = model

    def check_request(self, request: Request) -> None:
        """Refuse stated clothes: the per-view fits know nothing of them.

        Parameters
        ----------
        request : Request
            As for :meth:`~wbsa.estimation.methods.base.Predictor.check_request`.
        """
        if request.clothing_m > 0:
            raise WbsaError("a wbsa fit model allows for no clothes; state none (--clothing-cm 0) or use the default "
                            "estimator model", field="clothing_m", value=request.clothing_m,
                            page="a wbsa fit model allows for no clothes; choose no clothes or use the default "
                                 "estimator model")

    def predict(self, subject: Subject, request: Request) -> Prediction:
        """WBSA from the nearest fitted view; flags ``model_mismatch`` and ``uncertain_view``.

        Parameters
        ----------
        subject, request : Subject, Request
            As for :meth:`~wbsa.estimation.methods.base.Predictor.predict`.
        """
        from wbsa.estimation.methods.regression.default_model import default_model

        measures, camera = subject.measures, subject.camera
        view = default_model().view.estimate(measures)
        (az, el), flags = view_used(view, request.azimuth_deg, request.elevation_deg)
        usable = [e for e in self.model.entries if e["vbsa_column"] != "vbsa_hit_m2" and e["model"] == "linear"
                  and not e["predictors"] and e["group"] == "all"]
        if not usable:
            raise WbsaError("the wbsa fit model holds no linear VBSA-only fit of group all on a measurable VBSA "
                            "column; refit with wbsa fit --vbsa vbsa_recon_m2:grid")
        dist = measures.distance_m
        best = min(usable, key=lambda e: (abs(float(e["distance_m"]) - dist) / dist,
                                          float(azimuth_error_deg(e["azimuth_deg"], az))
                                          + abs(e["elevation_deg"] - el)))
        off = float(azimuth_error_deg(best["azimuth_deg"], az)) + abs(best["elevation_deg"] - el)
        problems = []
        if str(best["camera"]) != camera.name:
            problems.append(f"fitted for camera {best['camera']}, image from {camera.name}")
        if abs(float(best["distance_m"]) - dist) > 0.25 * dist:
            problems.append(f"fitted at {float(best['distance_m']):g} m, subject at {dist:.2f} m")
        if off > 10.0:
            problems.append(f"nearest fitted view azimuth {best['azimuth_deg']:g}, elevation "
                            f"{best['elevation_deg']:g} is {off:.0f}° from the view used")
        if best["vbsa_column"] == "vbsa_visible_m2":
            problems.append("fitted on the ideal visible area, not on a reconstruction from a sensor")
        if problems:
            flags["model_mismatch"] = "; ".join(problems)
        w, lo, hi = self.model.predict(best["azimuth_deg"], best["elevation_deg"], measures.vbsa_m2, None, "all",
                                       model="linear", level=request.level, vbsa_column=best["vbsa_column"],
                                       camera=str(best["camera"]), distance_m=float(best["distance_m"]))
        return Prediction(float(w[0]), float(lo[0]), float(hi[0]), view, (az, el), "wbsa fit model", flags)
