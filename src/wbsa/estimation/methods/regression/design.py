"""What the estimator model reads of a subject's measures: its design matrices, one function per matrix.

:func:`design` (the ridge regression's columns), :func:`tree_features` (the residual trees'),
:func:`spread_design` (the interval's spread s(x)), :func:`range_values` (the values whose training range is
checked) and :func:`with_clothing` (the stated layer of clothes added to the measures). Pure functions of the
measures (:meth:`~wbsa.estimation.subject.measure.SubjectMeasures.features`) and the view, shared by the run-time
prediction (:class:`~wbsa.estimation.methods.regression.model.EstimatorModel`) and the fit (:mod:`wbsa.training.fit`).
"""

from __future__ import annotations

import numpy as np

from wbsa.errors import WbsaError

#: Values whose training range is recorded and checked (flag ``out_of_training_range``; :func:`range_values`).
RANGE_KEYS = ("seen_area_m2", "stature_m", "distance_m", "elevation_deg", "depth_noise_px", "clothing_m")
_BASE = ("seen_area_m2", "stature_m", "silhouette_m2", "width_m", "thickness_m")
#: How the camera treated the subject's outline (:func:`wbsa.estimation.subject.mixed_pixels.outline_shares`).
_OUTLINE = ("mixed_share", "gap_share", "edge_gap_share")
#: How the image was taken besides: its depth noise (taken per pixel pitch) and whether a floor was seen.
_SCENE = ("depth_noise_m", "floor_seen")
#: What the user states: the thickness of the layer of clothes (m; 0: none or tight-fitting). It is not measured
#: on the image (:func:`with_clothing` adds it to the measures).
_STATED = ("clothing_m",)
#: Columns of :func:`design`: the log measures × 5 view terms, 4 view terms, distance, pitch, capture terms.
DESIGN_TERMS = 5 * len(_BASE) + 4 + 2 + len(_OUTLINE) + len(_SCENE) + 2
#: Columns of :func:`spread_design`.
SPREAD_TERMS = 7 + len(_OUTLINE) + len(_SCENE) + 2


def check_measures(features: dict[str, np.ndarray]) -> None:
    """Raise if a measure the model reads is missing (an image measured by another wbsa).

    Parameters
    ----------
    features : dict of str to (n,) float64
        The subjects' measures (:meth:`SubjectMeasures.features`).
    """
    missing = [k for k in (*_BASE, "distance_m", "pitch_m", *_OUTLINE, *_SCENE, *_STATED) if k not in features]
    if missing:
        raise WbsaError(f"measures {', '.join(missing)} are missing; measure the image with this wbsa "
                        "(wbsa.estimation.measure_subject) or re-render the training samples")


def with_clothing(features: dict[str, np.ndarray], clothing_m) -> dict[str, np.ndarray]:
    """The measures with the stated layer of clothes (``clothing_m``, (n,) float64 metres) added.

    Parameters
    ----------
    features : dict of (n,) float64
        The measures (:meth:`SubjectMeasures.features`).
    clothing_m : float or (n,) float64
        Thickness of the clothes over the trunk, upper arms, legs and feet (0: none or tight-fitting).

    Returns
    -------
    dict of (n,) float64
    """
    n = len(np.asarray(features["vbsa_m2"]))
    return {**features, "clothing_m": np.broadcast_to(np.asarray(clothing_m, dtype=np.float64), (n,)).copy()}


def range_values(features: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The values of :data:`RANGE_KEYS`, (n,) float64 each: four measures, the depth noise over the pixel
    pitch (``depth_noise_px``: a camera noisier than any the model was trained on is flagged) and the stated
    clothes.

    Parameters
    ----------
    features : dict of str to (n,) float64
        The subjects' measures with the stated clothes (:func:`with_clothing`).
    """
    out = {k: np.asarray(features[k], dtype=np.float64) for k in RANGE_KEYS if k != "depth_noise_px"}
    out["depth_noise_px"] = _depth_noise_px(features)
    return out


def _depth_noise_px(features: dict[str, np.ndarray]) -> np.ndarray:
    """(n,) float64: the measured depth noise over the pixel pitch."""
    return np.asarray(features["depth_noise_m"], dtype=np.float64) / np.asarray(features["pitch_m"], dtype=np.float64)


def capture_terms(features: dict[str, np.ndarray]) -> list[np.ndarray]:
    """How the image was taken (:data:`_OUTLINE`, :data:`_SCENE`, :data:`_STATED`), (n,) float64 each: the three
    outline shares, the depth noise over the pixel pitch (Kinect v1's noise model measured on a body at 2.6 m,
    11 mm: about 2.5 on Kinect v1's pixels, 1.6 on Kinect v2's; an ideal render in whole millimetres reads
    about 0.6 mm), whether a floor was seen (1) or not (0), and the stated clothes twice: their thickness in
    centimetres, and that thickness over the body's apparent width (seen area / stature; a layer t over a limb of
    radius r adds about t / r of its area, so thin bodies gain more; the width is the seen area over the stature).

    Parameters
    ----------
    features : dict of str to (n,) float64
        The subjects' measures with the stated clothes (:func:`with_clothing`).
    """
    cols = [np.asarray(features[k], dtype=np.float64) for k in _OUTLINE]
    clothing_m = np.asarray(features["clothing_m"], dtype=np.float64)
    width_m = np.asarray(features["seen_area_m2"], dtype=np.float64) / np.asarray(features["stature_m"],
                                                                                dtype=np.float64)
    return cols + [_depth_noise_px(features), np.asarray(features["floor_seen"], dtype=np.float64),
                   100.0 * clothing_m, clothing_m / width_m]


def design(features: dict[str, np.ndarray], psi_deg: np.ndarray, elevation_deg: np.ndarray) -> np.ndarray:
    """Linear design matrix (n, 38): log measures × view basis, view basis, log distance, pitch/stature, capture.

    Parameters
    ----------
    features : dict of str to (n,) float64
        The subjects' measures with the stated clothes (:func:`with_clothing`).
    psi_deg, elevation_deg : (n,) float64
        The view used: folded azimuth and elevation (degrees).
    """
    check_measures(features)
    r = np.radians(np.asarray(psi_deg, dtype=np.float64))
    s_el = np.sin(np.radians(np.asarray(elevation_deg, dtype=np.float64)))
    view = [np.ones_like(r), np.cos(r), np.cos(2 * r), np.cos(3 * r), s_el]
    cols = [np.log(np.asarray(features[k], dtype=np.float64)) * v for k in _BASE for v in view]
    cols += view[1:]
    cols += [np.log(features["distance_m"]), np.asarray(features["pitch_m"]) / np.asarray(features["stature_m"])]
    return np.column_stack(cols + capture_terms(features))


def tree_features(features: dict[str, np.ndarray], shape: np.ndarray, psi_deg: np.ndarray, psi_sd_deg: np.ndarray,
                  elevation_deg: np.ndarray) -> np.ndarray:
    """Features of the residual trees (n, 56): log measures, view, its spread, distance, bands / stature, capture.

    Parameters
    ----------
    features : dict of str to (n,) float64
        The subjects' measures with the stated clothes (:func:`with_clothing`).
    shape : (n, b) float64
        The subjects' shape bands (:attr:`SubjectMeasures.shape`), metres.
    psi_deg, psi_sd_deg, elevation_deg : (n,) float64
        The view used, its azimuth spread and its elevation (degrees).
    """
    check_measures(features)
    st = np.asarray(features["stature_m"], dtype=np.float64)
    cols = [np.log(np.asarray(features[k], dtype=np.float64)) for k in _BASE]
    cols += [np.asarray(psi_deg, dtype=float), np.asarray(psi_sd_deg, dtype=float), np.asarray(elevation_deg, float),
             np.asarray(features["distance_m"], float)]
    return np.column_stack(cols + [np.asarray(shape, dtype=np.float64) / st[:, None]] + capture_terms(features))


def spread_design(psi_deg: np.ndarray, psi_sd_deg: np.ndarray, features: dict[str, np.ndarray],
                  log_wbsa: np.ndarray) -> np.ndarray:
    """Design of the log residual spread (n, 14).

    Columns: 1, cos 2ψ, view spread / 30°, log pitch, log pixel count, the capture terms
    (:func:`capture_terms`: outline shares, depth noise, floor, stated clothes), and the
    apparent build b = log(predicted WBSA / stature²) with b². A single view tells a very thin or very heavy
    body's build only in part, so the prediction is drawn towards the common build there and the interval
    must widen. Measured on held-out calibration renders (spread and quantile fitted on one half, coverage
    read on the other): bodies with BMI ≥ 35 are covered 0.73 of the time at 95 % without b, 0.83 with it.

    Parameters
    ----------
    psi_deg, psi_sd_deg : (n,) float64
        Folded azimuth and its spread (degrees).
    features : dict of (n,) float64
        The measures and the stated clothes (``pitch_m``, ``n_pixels``, ``stature_m``, ``seen_area_m2``, the
        outline shares, ``depth_noise_m``, ``floor_seen`` and ``clothing_m`` are used).
    log_wbsa : (n,) float64
        The model's predicted log WBSA (m²).

    Returns
    -------
    (n, 14) float64
    """
    check_measures(features)
    r = np.radians(np.asarray(psi_deg, dtype=np.float64))
    build = np.asarray(log_wbsa, dtype=np.float64) - 2.0 * np.log(np.asarray(features["stature_m"], dtype=np.float64))
    return np.column_stack([np.ones_like(r), np.cos(2 * r), np.asarray(psi_sd_deg, float) / 30.0,
                            np.log(features["pitch_m"]), np.log(features["n_pixels"])]
                           + capture_terms(features) + [build, build ** 2])
