"""From a subject's measures to WBSA: the estimator model, or a ``wbsa fit`` per-view model file.

The default route uses an :class:`~wbsa.estimation.model.EstimatorModel` (continuous in view and
distance, trained on renders measured by the same code). A ``wbsa fit`` model file (the paper's per-view
regressions at one camera and distance) is still accepted: its nearest fitted view is used and any
difference in camera, distance or view is flagged ``model_mismatch``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wbsa.errors import WbsaError
from wbsa.estimation.view import ViewEstimate, azimuth_error_deg, fold_azimuth


@dataclass(frozen=True)
class Prediction:
    """WBSA and its interval, the view estimated and the view used, flags from the model."""

    wbsa_m2: float
    lo_m2: float
    hi_m2: float
    view: ViewEstimate
    view_used: tuple[float, float]
    model_name: str
    flags: dict[str, str] = field(default_factory=dict)


def load_any_model(model, show_progress: bool | None = None):
    """An :class:`EstimatorModel` or a ``wbsa fit`` :class:`~wbsa.analysis.model_file.WbsaModel`.

    ``None`` gives the default model (built and cached on first use); a path ending in ``.npz`` an estimator
    model; ``.json`` a ``wbsa fit`` model file; a model object is returned as it is.
    """
    from wbsa.estimation.model import EstimatorModel

    if model is None:
        from wbsa.estimation.cache import default_model

        return default_model(show_progress=show_progress)
    if isinstance(model, (str, os.PathLike)):
        path = Path(model)
        if path.suffix.lower() == ".npz":
            return EstimatorModel.load(path)
        if path.suffix.lower() == ".json":
            from wbsa.analysis.model_file import WbsaModel

            legacy = WbsaModel.load(path)
            _check_legacy_finite(legacy, path)
            return legacy
        raise WbsaError(f"model {path.name} is neither an estimator model (.npz) nor a wbsa fit model (.json)")
    return model


def check_model_allows_clothing(model, clothing_m: float) -> None:
    """Raise if clothes are stated to a ``wbsa fit`` model (its per-view fits know nothing of clothes)."""
    from wbsa.estimation.model import EstimatorModel

    if clothing_m > 0 and model is not None and not isinstance(model, EstimatorModel):
        raise WbsaError("a wbsa fit model allows for no clothes; state none (--clothing-cm 0) or use the default "
                        "estimator model")


def _check_legacy_finite(model, path) -> None:
    for e in model.entries:
        for key in ("coef", "cov_unscaled", "scale"):
            if not np.all(np.isfinite(np.asarray(e[key], dtype=float))):
                raise WbsaError(f"model {path} holds non-finite numbers ({key} of the {e['model']} fit at azimuth "
                                f"{e['azimuth_deg']:g}, elevation {e['elevation_deg']:g}); refit with wbsa fit")


def _view(model, measures, stated_azimuth: float | None) -> ViewEstimate:
    """The estimated view; a ``wbsa fit`` model borrows the default model's azimuth if it is cached."""
    from wbsa.estimation.model import EstimatorModel
    from wbsa.estimation.view import ELEVATION_SD_DEG

    el_sd = model.view.elevation_sd_deg if isinstance(model, EstimatorModel) else ELEVATION_SD_DEG
    view_model = model.view if isinstance(model, EstimatorModel) else _cached_view_model()
    if view_model is None:
        if stated_azimuth is None:
            raise WbsaError("a wbsa fit model needs the view: give azimuth_deg (and elevation_deg), or build the default "
                            "model once (estimate without a model) so the azimuth can be estimated")
        psi, sd, p = float("nan"), float("nan"), float("nan")
    else:
        psi, sd, p = (float(v[0]) for v in view_model.predict(measures.descriptor[None]))
    return ViewEstimate(psi, sd, measures.elevation_deg, el_sd["floor" if measures.floor_seen else "axis"], p)


def _cached_view_model():
    """The default model's view model if it is cached (None otherwise: nothing is trained for a legacy model)."""
    from wbsa.estimation.cache import default_model, default_model_path

    return default_model().view if default_model_path().is_file() else None


def predict_wbsa(model, measures, camera, azimuth_deg: float | None, elevation_deg: float | None,
                 level: float, clothing_m: float = 0.0) -> Prediction:
    """Predict WBSA from measures with either kind of model (see the module doc); ``clothing_m`` is the stated
    layer of clothes (m), which only an estimator model allows for."""
    from wbsa.estimation.checks import range_flags
    from wbsa.estimation.model import EstimatorModel, range_values, with_clothing

    view = _view(model, measures, azimuth_deg)
    az = view.azimuth_deg if azimuth_deg is None else float(fold_azimuth(azimuth_deg))
    el = view.elevation_deg if elevation_deg is None else float(elevation_deg)
    flags: dict[str, str] = {}
    if azimuth_deg is None and not view.azimuth_sd_deg <= 30.0:
        flags["uncertain_view"] = (f"azimuth {view.azimuth_deg:.0f}° ± {view.azimuth_sd_deg:.0f}° (camera in front "
                                   f"with probability {view.p_front:.2f}); give --azimuth if you know it")
    if isinstance(model, EstimatorModel):
        feats = with_clothing({k: np.array([v]) for k, v in measures.features().items()}, clothing_m)
        # a stated view counts as sure as the surest estimated one: the models never saw a smaller spread
        az_sd = view.azimuth_sd_deg if azimuth_deg is None else model.view.axis_sd_deg
        w, lo, hi = model.predict(feats, measures.shape[None], np.array([az]), np.array([az_sd]), np.array([el]), level)
        values = range_values({**feats, "elevation_deg": np.array([el])})
        flags.update(range_flags({k: float(v[0]) for k, v in values.items()}, model.ranges))
        if not model.quantile_is_sure(level):
            flags["interval_unsure"] = (f"the model was calibrated on {model.n_calibration_subjects} "
                                        f"subjects, too few to promise {100 * level:g} %; its widest score "
                                        "is used")
        return Prediction(float(w[0]), float(lo[0]), float(hi[0]), view, (az, el), model.name, flags)
    check_model_allows_clothing(model, clothing_m)
    return _predict_legacy(model, measures, camera, view, az, el, level, flags)


def _predict_legacy(model, measures, camera, view, az, el, level, flags) -> Prediction:
    """A ``wbsa fit`` model: nearest fitted view, its camera and distance; mismatches flagged."""
    usable = [e for e in model.entries if e["vbsa_column"] != "vbsa_hit_m2" and e["model"] == "linear"
              and not e["predictors"] and e["group"] == "all"]
    if not usable:
        raise WbsaError("the wbsa fit model holds no linear VBSA-only fit of group all on a measurable VBSA column; "
                        "refit with wbsa fit --vbsa vbsa_recon_m2:grid")
    dist = measures.distance_m
    best = min(usable, key=lambda e: (abs(float(e["distance_m"]) - dist) / dist,
                                      float(azimuth_error_deg(e["azimuth_deg"], az)) + abs(e["elevation_deg"] - el)))
    off = float(azimuth_error_deg(best["azimuth_deg"], az)) + abs(best["elevation_deg"] - el)
    problems = []
    if str(best["camera"]) != camera.name:
        problems.append(f"fitted for camera {best['camera']}, image from {camera.name}")
    if abs(float(best["distance_m"]) - dist) > 0.25 * dist:
        problems.append(f"fitted at {float(best['distance_m']):g} m, subject at {dist:.2f} m")
    if off > 10.0:
        problems.append(f"nearest fitted view azimuth {best['azimuth_deg']:g}, elevation {best['elevation_deg']:g} "
                        f"is {off:.0f}° from the view used")
    if best["vbsa_column"] == "vbsa_visible_m2":
        problems.append("fitted on the ideal visible area, not on a reconstruction from a sensor")
    if problems:
        flags["model_mismatch"] = "; ".join(problems)
    w, lo, hi = model.predict(best["azimuth_deg"], best["elevation_deg"], measures.vbsa_m2, None, "all",
                              model="linear", level=level, vbsa_column=best["vbsa_column"], camera=str(best["camera"]),
                              distance_m=float(best["distance_m"]))
    return Prediction(float(w[0]), float(lo[0]), float(hi[0]), view, (az, el), "wbsa fit model", flags)
