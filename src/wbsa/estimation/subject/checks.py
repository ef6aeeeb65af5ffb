"""Input checks of a depth-image estimate: one-line errors for what cannot be measured, named flags for the rest.

Errors (:class:`~wbsa.errors.WbsaError`, the CLI exits 2): an image whose size is not the camera's, a
subject whose height from the point cloud is not a human height (wrong depth scale or units), a model with
non-finite numbers. Flags (a name and a sentence, in ``Estimate.flags``; ``warning:`` lines on the terminal)
for an estimate that is given but may be off: see :data:`wbsa.estimation.flags.FLAGS`.
"""

from __future__ import annotations

import math

import numpy as np

from wbsa.errors import WbsaError, Worded
from wbsa.estimation.limits import HUMAN_HEIGHT_M

#: The silhouette of a standing person (:func:`person_shape_flags`): the share of its bounding box
#: (width × stature) it fills, and its width per metre of stature. Measured on rendered bodies in a room
#: (Kinect v2, 3 m, 12° elevation; A-pose and arms-down adults and teenagers of 1.35–2.07 m, azimuths 0–180°):
#: fill 0.22–0.63, width/stature 0.14–0.68; a 1.69 × 0.45 m board fills 0.93–0.94 (0.03 of its stature wide
#: edge-on), a 1.7 m post of 0.12 m 0.82–0.84 (width 0.08 of its stature), a wall piece edge-on 0.06.
PERSON_MAX_FILL = 0.75
PERSON_MIN_WIDTH_PER_STATURE = 0.10
#: A stated stature that differs from the measured one by more than this (m) is flagged, or, with no floor
#: seen, taken as legs cut off (:func:`wbsa.estimation.single_view.stated_stature`); the measured stature's
#: 90th percentile of error on straight postures is 1.2 cm (docs/estimate.md), a bent knee a few.
STATURE_TOLERANCE_M = 0.05
#: Mixed returns beside the subject per pixel of its outline above which the estimate is flagged: on the
#: benchmark's clean images (edges kept) 1 of 299 is above; with 10 % of the depth edges mixed the median
#: is about 0.09, with all of them 0.5 (docs/estimate.md, "Depth edges").
MIXED_PER_OUTLINE_PIXEL = 0.1


def check_two_dimensional(depth: np.ndarray) -> None:
    """Raise if the depth image is not 2-D.

    Parameters
    ----------
    depth : array
        The depth image, (h, w) when right.
    """
    if np.ndim(depth) != 2:
        raise WbsaError(f"a depth image must be 2-D (h, w), got shape {np.shape(depth)}; give a single-channel image")


def check_image_size(depth: np.ndarray, camera) -> None:
    """Raise if the depth image is not 2-D or not the camera's size.

    Parameters
    ----------
    depth : (h, w) float64
    camera : Intrinsics
    """
    check_two_dimensional(depth)
    h, w = np.shape(depth)
    if (w, h) != (camera.width, camera.height):
        what = f"the depth image is {w}x{h} but camera {camera.name} is {camera.width}x{camera.height}"
        raise WbsaError(f"{what}; give the camera that took it (--camera PRESET or an intrinsics JSON)",
                        code="camera_size", field="camera", value=camera.name,
                        page=f"{what}; give the camera that took it (choose it under Camera, or add its intrinsics "
                             "file)")


def person_shape_flags(stature_m: float, width_m: float, silhouette_m2: float) -> dict[str, str]:
    """``{"not_a_person": ...}`` if the segmented object's silhouette is not a standing person's.

    Parameters
    ----------
    stature_m, width_m, silhouette_m2 : float
        The object's height, width across the image and projected area (``SubjectMeasures``).

    Returns
    -------
    dict
        Empty for a person's shape; else the flag with the measures and the ranges of people.
    """
    if not (stature_m > 0 and width_m > 0):
        return {}
    fill = silhouette_m2 / (width_m * stature_m)
    ratio = width_m / stature_m
    if fill <= PERSON_MAX_FILL and ratio >= PERSON_MIN_WIDTH_PER_STATURE:
        return {}
    what = (f"fills {100 * fill:.0f} % of its {width_m:.2f} x {stature_m:.2f} m outline (a person at most "
            f"{100 * PERSON_MAX_FILL:.0f} %)" if fill > PERSON_MAX_FILL else
            f"is {width_m:.2f} m wide for {stature_m:.2f} m tall (a person at least {PERSON_MIN_WIDTH_PER_STATURE:g} "
            "of the height)")
    said = f"the object {what}: a board, post or wall? the estimate is not a person's"
    return {"not_a_person": Worded(f"{said}; check the segmentation (the estimate's mask) and pick the subject "
                                   "(segment=SegmentSettings(pick=(x, y)), a pixel of the person)",
                                   f"{said}; check the white outline in the depth picture and click on the person",
                                   command=f"{said}; check the segmentation (--mask-out) and pick the subject "
                                           "(--pick X,Y)")}


#: Why lengths 1000 times too long are millimetres read as metres, and the fix (command line, Python; the page).
MILLIMETRES_AS_METRES = Worded(
    "millimetres read as metres? A float file (.npy, .tiff, .exr) or array is read as metres: for millimetres add "
    "--depth-scale 1000 (depth_scale=1000 in Python)",
    "millimetres read as metres? A float file (.npy, .tiff, .exr) is read as metres: save the depth in metres, or "
    "as a 16-bit PNG in millimetres")


def millimetres_refusal(said: str, metres: float, expected: tuple[float, float]) -> WbsaError | None:
    """The refusal ``said``, with :data:`MILLIMETRES_AS_METRES`, of a length (m) that is ``expected`` when read
    as millimetres (1000 times too long); None when it is not.

    Parameters
    ----------
    said : str
        What was found, e.g. ``the subject measures 1750.00 m tall``.
    metres : float
        The length as read (m).
    expected : (float, float)
        The range it should lie in (m).
    """
    if not (math.isfinite(metres) and expected[0] <= metres / 1000.0 <= expected[1]):
        return None
    return WbsaError(f"{said}: {MILLIMETRES_AS_METRES}", code="depth_scale", field="depth_scale",
                     page=f"{said}: {MILLIMETRES_AS_METRES.page}")


def check_height(stature_m: float) -> None:
    """Raise if a height measured on the point cloud cannot be a person's.

    Parameters
    ----------
    stature_m : float
        The subject's height over the floor (or along its long axis), metres.
    """
    lo, hi = HUMAN_HEIGHT_M
    if not (math.isfinite(stature_m) and lo <= stature_m <= hi):
        said = f"the subject measures {stature_m:.2f} m tall in the point cloud, outside {lo:g}–{hi:g} m"
        refusal = millimetres_refusal(said, stature_m, HUMAN_HEIGHT_M)
        if refusal is not None:
            raise refusal
        raise WbsaError(f"{said}; the depth scale (units per metre) or the camera intrinsics are probably wrong")


def is_real_number(value: object) -> bool:
    """Whether ``value`` is a real number (int, float or a NumPy real scalar; not a bool, str or complex).

    Parameters
    ----------
    value : object
    """
    return (isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_)))


def check_stated_stature(stature_m: float) -> float:
    """A stated stature (m) as a float, or a one-line error if it is not a human height (:data:`HUMAN_HEIGHT_M`).

    Parameters
    ----------
    stature_m : float
        The stature the user stated (m).

    Returns
    -------
    float
    """
    lo, hi = HUMAN_HEIGHT_M
    if not (is_real_number(stature_m) and math.isfinite(float(stature_m)) and lo <= float(stature_m) <= hi):
        said = f"the stated stature {stature_m!r} m must be a height of {lo:g} to {hi:g} m, e.g. 1.72"
        raise WbsaError(f"{said} (on the command line --stature-cm 172)", code="out_of_range", field="stature_m",
                        value=stature_m, page=said)
    return float(stature_m)


def check_finite_model(arrays: dict, source: str) -> None:
    """Raise if any number of a model is NaN or infinite.

    Parameters
    ----------
    arrays : dict of str to array
        The model's named arrays.
    source : str
        The model's name in the message (its file).
    """
    for name, arr in arrays.items():
        a = np.asarray(arr)
        if a.dtype.kind in "fc" and not np.all(np.isfinite(a)):
            raise WbsaError(f"model {source} holds non-finite numbers in {name}; rebuild or refit the model")


def range_flags(values: dict[str, float], ranges: dict[str, tuple[float, float]]) -> dict[str, str]:
    """``{"out_of_training_range": ...}`` naming every value outside its training range, else ``{}``.

    Parameters
    ----------
    values : dict of str to float
        The subject's measures by name.
    ranges : dict of str to (float, float)
        The training range (low, high) of each checked measure; names not in it are not checked.
    """
    out = []
    for name, value in values.items():
        if name in ranges:
            lo, hi = ranges[name]
            if not lo <= value <= hi:
                out.append(f"{name} {value:.3g} (trained {lo:.3g}–{hi:.3g})")
    return {"out_of_training_range": "; ".join(out)} if out else {}


def working_range_flags(distance_m: float, camera) -> dict[str, str]:
    """``{"beyond_working_range": ...}`` if the subject's distance is outside the camera's working range
    (:attr:`~wbsa.camera.presets.CameraRecord.working_range_m`; an intrinsics file's own range).

    Parameters
    ----------
    distance_m : float
        The subject's distance from the camera (m).
    camera : wbsa.camera.presets.CameraRecord
    """
    lo, hi = (float(v) for v in camera.working_range_m)
    if lo <= distance_m <= hi:
        return {}
    return {"beyond_working_range": f"subject at {distance_m:.2f} m, camera {camera.name} works {lo:g}–{hi:g} m; "
                                    f"stand within that range"}


def feet_flags(distance_m: float, camera) -> dict[str, str]:
    """``{"feet_unsure": ...}`` beyond the distance at which the camera's preset tells the feet from the floor
    (:attr:`~wbsa.camera.presets.CameraRecord.feet_within_m`; none for a camera that is not a preset).

    Parameters
    ----------
    distance_m : float
        The subject's distance from the camera (m).
    camera : wbsa.camera.presets.CameraRecord
    """
    if camera.feet_within_m is None or distance_m <= camera.feet_within_m:
        return {}
    return {"feet_unsure": f"subject at {distance_m:.2f} m; the {camera.name} tells the feet from the floor within "
                           f"{camera.feet_within_m:g} m: step closer"}


def mixed_pixel_flags(mixed_share: float) -> dict[str, str]:
    """``{"mixed_pixels": ...}`` when many returns beside the subject's outline were mixed.

    Parameters
    ----------
    mixed_share : float
        Mixed returns within 2 pixels of the subject per pixel of its outline
        (:func:`wbsa.estimation.subject.mixed_pixels.outline_shares`).
    """
    if not mixed_share > MIXED_PER_OUTLINE_PIXEL:
        return {}
    return {"mixed_pixels": f"returns at the subject's outline ({mixed_share:.0%} of its length) lay between two "
                            "surfaces and were snapped to one; the area may be off by several per cent; turn on the "
                            "camera's flying-pixel filter or keep a plain background well behind the subject"}
