"""WBSA from one depth image: find the subject, measure it, estimate the view, predict with an interval.

:func:`estimate` is the library entry point (``wbsa.estimate`` calls it). Every number it returns carries
its flags (:data:`wbsa.estimation.flags.FLAGS`); what cannot be measured raises a one-line
:class:`~wbsa.errors.WbsaError`.
"""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable

import numpy as np

from wbsa.errors import WbsaError
from wbsa.estimation.clothes import UNSTATED, Clothes
from wbsa.estimation.methods.view import ViewEstimate
from wbsa.estimation.subject.segment import SegmentSettings
from wbsa.typing import Method

if TYPE_CHECKING:  # pragma: no cover
    from wbsa.estimation.methods.body_fit.settings import BodyFitSettings


@dataclass(frozen=True)
class Estimate:
    """One single-view WBSA estimate (SI units, angles in degrees).

    Attributes
    ----------
    wbsa_m2, wbsa_lo_m2, wbsa_hi_m2 : float
        Estimate and prediction interval of the whole body surface area.
    level : float
        Coverage of the interval.
    vbsa_m2, stature_m, distance_m : float
        Visible surface area, height and distance of the subject measured on the point cloud.
    n_pixels : int
    view : ViewEstimate
        The view estimated from the image.
    view_used : (float, float)
        Azimuth and elevation the prediction used (the stated ones where given).
    flags : dict of str to str
        Named warnings (see :data:`wbsa.estimation.flags.FLAGS`); empty when all checks passed.
    clothing_m : float
        The layer of clothes the estimate allows for (m; 0: none or tight-fitting, or nothing stated).
    method, model, camera : str
    mask : (h, w) bool
        The subject's pixels (the segmentation: returns on the floor and walls excluded, the feet down to
        the floor included).
    measured_mask : (h, w) bool
        The pixels measured: ``mask`` less the strip of the feet within the depth noise of the floor,
        which the measures cut in training too (the VBSA is that of these pixels).
    surface : wbsa.core.TriangleMesh
        The reconstructed visible surface (camera frame, metres).
    body : wbsa.estimation.methods.body_fit.BodyFit or None
        With ``method="body-fit"`` or ``"both"``: the whole body fitted to the image (its meshes, stature, mass,
        posture).
    routes : dict of str to Prediction
        With ``method="both"``: each route's own prediction (``regression``, ``body-fit``); the estimate's numbers
        are the first's.
    clothes : wbsa.estimation.clothes.Clothes
        What was stated of the clothes (a named layer with its uncertainty, an explicit layer, or nothing).
    stature_stated_m : float or None
        The stature the user stated, if any (used in place of the measured one where the feet are not seen).
    """

    wbsa_m2: float
    wbsa_lo_m2: float
    wbsa_hi_m2: float
    level: float
    vbsa_m2: float
    stature_m: float
    distance_m: float
    n_pixels: int
    view: ViewEstimate
    view_used: tuple[float, float]
    flags: dict[str, str]
    method: str
    model: str
    camera: str
    clothing_m: float
    mask: np.ndarray = field(repr=False, compare=False)
    surface: object = field(repr=False, compare=False)
    measured_mask: np.ndarray = field(repr=False, compare=False, default=None)
    body: object = field(repr=False, compare=False, default=None)
    routes: dict = field(repr=False, compare=False, default_factory=dict)
    clothes: Clothes = UNSTATED
    stature_stated_m: float | None = None

    def __repr__(self) -> str:
        flags = f", flags: {', '.join(self.flags)}" if self.flags else ""
        return (f"Estimate(WBSA {self.wbsa_m2:.3f} m² [{self.wbsa_lo_m2:.3f}–{self.wbsa_hi_m2:.3f}, "
                f"{100 * self.level:.0f} %], {self.view_text()}, {self.distance_m:.2f} m{flags})")

    def view_text(self) -> str:
        """The view in words: the estimated one with its spread (a fitted body's without one)."""
        v = self.view
        if np.isfinite(v.azimuth_deg) and not np.isfinite(v.azimuth_sd_deg):  # a fitted body's view
            return f"azimuth {v.azimuth_deg:.0f}° (mirror-equivalent), elevation {v.elevation_deg:.0f}° (fitted)"
        return (f"azimuth {v.azimuth_deg:.0f}° ± {v.azimuth_sd_deg:.0f}° (mirror-equivalent), elevation "
                f"{v.elevation_deg:.0f}° ± {v.elevation_sd_deg:.0f}°")

    def to_dict(self) -> dict:
        """JSON-ready estimate, view and flags (without the mask and the surface).

        A number that was not estimated (the spread of a fitted body's azimuth) is NaN here and ``null`` in the
        JSON (:func:`wbsa.strict_json.json_text`).
        """
        out = {k: getattr(self, k) for k in ("wbsa_m2", "wbsa_lo_m2", "wbsa_hi_m2", "level", "vbsa_m2", "stature_m",
                                             "distance_m", "n_pixels", "clothing_m", "method", "model", "camera")}
        out = {k: (round(v, 5) if isinstance(v, float) else v) for k, v in out.items()}
        out["view"] = self.view.to_dict()
        out["view_used"] = {"azimuth_deg": self.view_used[0], "elevation_deg": self.view_used[1]}
        out.update(self.clothes.to_dict())
        out["stature_stated_m"] = self.stature_stated_m
        out["flags"] = dict(self.flags)
        if self.body is not None:
            out["body"] = self.body.to_dict()
        if self.routes:
            out["routes"] = {name: {"wbsa_m2": round(p.wbsa_m2, 5), "wbsa_lo_m2": round(p.wbsa_lo_m2, 5),
                                    "wbsa_hi_m2": round(p.wbsa_hi_m2, 5), "model": p.model_name, "flags": dict(p.flags)}
                             for name, p in self.routes.items()}
        return out

    def method_text(self) -> str:
        """One sentence on how the number was obtained (FHIR ``Observation.method.text``)."""
        stature = (f"stature {self.stature_m:.2f} m stated (the feet were not seen)" if "feet_not_seen" in self.flags
                   else f"stature {self.stature_m:.2f} m")
        return (f"wbsa {self.method}: one depth image ({self.camera}), visible body surface area "
                f"{self.vbsa_m2:.3f} m2 and {stature} measured on the point cloud, view "
                f"azimuth {self.view_used[0]:.0f} deg / elevation {self.view_used[1]:.0f} deg, model {self.model}; "
                f"{self.clothes.text()}")


def _depth_array(depth, depth_scale: float | None) -> np.ndarray:
    if isinstance(depth, (str, os.PathLike)):
        from wbsa.core.depth_image import read_depth

        return read_depth(depth, depth_scale=depth_scale)
    from wbsa.core.depth_image import metres_from_units
    from wbsa.estimation.subject.checks import is_real_number

    raw = np.asarray(depth) if not isinstance(depth, np.ndarray) else depth
    if raw.dtype.kind not in "iuf":
        raise WbsaError(f"depth must be a path or a 2-D array of real numbers (metres), got a {raw.dtype} "
                        f"{type(depth).__name__}" + ("; give the real part (depth.real) if that is the depth"
                                                     if raw.dtype.kind == "c" else ""))
    if depth_scale is None:
        return raw.astype(np.float64)
    if not (is_real_number(depth_scale) and np.isfinite(depth_scale) and depth_scale > 0):
        raise WbsaError(f"depth_scale must be a positive number of units per metre, e.g. 1000, got {depth_scale!r}")
    return metres_from_units(raw, float(depth_scale)).astype(np.float64)


def estimate(depth, camera, model=None, method: Method = "regression", *, azimuth_deg: float | None = None,
             elevation_deg: float | None = None, clothing: str | None = None, clothing_m: float | None = None,
             stature_m: float | None = None, level: float = 0.95,
             depth_scale: float | None = None, segment: SegmentSettings | None = SegmentSettings(),
             body_fit: BodyFitSettings | None = None, show_progress: bool | None = None,
             progress: Callable[[str, int, int], None] | None = None) -> Estimate:
    """Estimate WBSA from one depth image of a standing person.

    Parameters
    ----------
    depth : (h, w) float array (metres, 0 = no return) or path
        A path is read with :func:`wbsa.core.read_depth` (16-bit PNG, .npy, .tiff, .exr). A ``.pcd`` or ``.ply``
        point cloud (camera frame, metres) is read with :func:`wbsa.core.point_cloud.point_cloud_depth`: an
        organised ``.pcd`` brings its own camera, recovered from its points.
    camera : str, path or wbsa.camera.Intrinsics
        A preset name (``kinect-v2``, ``realsense-d435``, ...), an Open3D intrinsics JSON, or ``auto``: the preset
        of the image's size (:func:`wbsa.camera.presets.camera_for_image`), flagged ``camera_assumed``. An organised
        ``.pcd``'s recovered camera is used under ``auto``; a ``.ply`` or unorganised ``.pcd`` needs a stated one.
    model : EstimatorModel, path or None
        None: the model shipped with wbsa (:func:`wbsa.estimation.methods.regression.default_model.default_model`). A path: an
        estimator model file (``.npz``, e.g. from ``wbsa train``) or a ``wbsa fit`` model file (``.json``).
    method : {'regression', 'body-fit', 'both'}
        The estimation route (:mod:`wbsa.estimation.methods`): the regression on the image's measures (the
        default), the whole body fitted to the view (seconds, not milliseconds; a stated layer of clothes is taken
        off the fitted body as an offset), or both side by
        side (the regression's number leads; ``routes`` holds both).
    azimuth_deg, elevation_deg : float, optional
        A stated view; it is used for the prediction and checked against the estimated one.
    clothing : str, optional
        The clothes by name (:data:`wbsa.estimation.clothes.CLOTHES`: ``underwear``, ``thin-gown``, ``light``,
        ``street``): a layer with its own uncertainty, which widens the interval. The camera sees the clothes'
        outside, which encloses more area than the skin (a 1 cm layer read +8.6 % when not stated).
    clothing_m : float, optional
        Or the clothes as an explicit thickness over the trunk, upper arms, legs and feet (m): how far their
        outside stands off the skin, on average (0: none or tight-fitting); the default model was trained on
        layers of 0–1.5 cm. Neither given: taken as 0, ``clothing_stated`` false and flagged
        ``clothes_unstated``.
    stature_m : float, optional
        The subject's stature (m), stated. A subject whose feet are not seen (its lowest returns end at the
        frame's bottom or over a band without returns, or stand over a seen floor) is refused
        (``feet_not_seen``) unless it is given; then it takes the measured stature's place, flagged.
    level : float
        Coverage of the prediction interval, in (0, 1).
    depth_scale : float, optional
        Units per metre of the depth values (files: see :func:`wbsa.core.read_depth`; arrays: default 1).
    segment : SegmentSettings or None
        How to find the subject in a room; None: every return is the subject.
    body_fit : BodyFitSettings or None
        With ``method="body-fit"`` or ``"both"``: how the body is fitted (None: the defaults).
    progress : callable, optional
        Called as ``progress(stage, done, total)`` as the work goes on: ``("subject", 0, 1)`` before the subject
        is found and measured, then for each route ``(route, 0, 1)`` as it starts (``regression``, ``body-fit``),
        the body fit also ``("body-fit", step, steps)`` after each of its steps (a fit that settles stops
        early). For a page or a log; the estimate is the same with or without it.

    Returns
    -------
    Estimate

    Raises
    ------
    WbsaError
        Unreadable input, an image that is not the camera's size, no or several people without a pick,
        a height that is not human (wrong depth scale), a broken model, an unknown method, unknown clothes or
        a stated layer that is not 0–0.05 m (or one stated to a ``wbsa fit`` model), a stated stature that is
        not a human height, or feet not seen without a stated stature.
    """
    from wbsa.camera.presets import AUTO_CAMERA, resolve_camera
    from wbsa.camera.views import check_angle
    from wbsa.core.point_cloud import is_point_cloud_path, point_cloud_depth
    from wbsa.estimation.flags import FLAGS
    from wbsa.estimation.subject import checks
    from wbsa.estimation.subject.measure import measure_subject
    from wbsa.estimation.methods.base import Request, Subject
    from wbsa.estimation.methods.dispatch import check_method, predictors_for
    from wbsa.estimation.methods.view import view_flags
    from wbsa.estimation.subject.mixed_pixels import repair_mixed_pixels
    from wbsa.estimation.clothes import stated_clothes
    from wbsa.estimation.subject.people import feet_unseen, open_feet
    from wbsa.estimation.subject.segment import segment_subject
    from wbsa.sensor.technology import envelope_model

    check_method(method)
    if not (checks.is_real_number(level) and 0 < level < 1):
        raise WbsaError(f"interval level {level!r} must be a number in (0, 1), e.g. 0.95")
    if segment is not None and not isinstance(segment, SegmentSettings):
        raise WbsaError(f"segment must be SegmentSettings or None, got {type(segment).__name__}")
    if azimuth_deg is not None:
        azimuth_deg = check_angle(azimuth_deg, "azimuth", "azimuth_deg")
    if elevation_deg is not None:
        elevation_deg = check_angle(elevation_deg, "elevation", "elevation_deg")
    clothes = stated_clothes(clothing, clothing_m)
    if stature_m is not None:
        stature_m = checks.check_stated_stature(stature_m)
    request = Request(azimuth_deg, elevation_deg, clothes.layer_m, level,
                      progress=None if progress is None else lambda step, steps: progress("body-fit", step, steps))
    auto = isinstance(camera, str) and camera == AUTO_CAMERA
    intrinsics = None if auto else resolve_camera(camera)  # a bad camera is refused before the image is read
    if is_point_cloud_path(depth):  # its camera: recovered from an organised cloud's grid, or the stated one
        depth_m, intrinsics = point_cloud_depth(depth, intrinsics, units_per_m=depth_scale)
        auto = False
    else:
        depth_m = _depth_array(depth, depth_scale)
    if auto:
        checks.check_two_dimensional(depth_m)
        intrinsics = resolve_camera(camera, depth_m.shape)
    checks.check_image_size(depth_m, intrinsics)
    predictors = list(predictors_for(method, model, body_fit))  # a model is read (and refused) before any measure
    depth_m, mixed = repair_mixed_pixels(depth_m, intrinsics.fx, envelope_model(intrinsics))
    flags: dict[str, str] = {}
    for k, predictor in enumerate(predictors):
        try:
            predictor.check_request(request)
        except WbsaError as exc:
            if k == 0:
                raise
            flags["body_fit_failed"] = str(exc)  # both: the second route cannot serve this request
            predictors[k] = None
    if progress is not None:
        progress("subject", 0, 1)
    if segment is None:
        mask, floor = np.isfinite(depth_m) & (depth_m > 0), None
        if not mask.any():
            raise WbsaError("the depth image has no returns; check the depth scale and the file")
        feet = open_feet(mask)
    else:
        seg = segment_subject(depth_m, intrinsics, segment)
        mask, floor = seg.mask, seg.floor
        if seg.others:
            flags["several_people"] = (f"picked {seg.subject.describe()} ({segment.pick}); others: "
                                       + "; ".join(c.describe() for c in seg.others))
        feet = feet_unseen(seg.subject, floor)
    if feet is not None and stature_m is None:
        raise WbsaError(f"feet not seen: {feet}; without the feet the WBSA is not measured (a cut-off adult would "
                        "read as a child): capture the whole person, feet on the floor, or state the stature "
                        "(--stature-cm, stature_m)")
    m = measure_subject(depth_m, mask, intrinsics, floor, mixed)
    if feet is not None:
        flags["feet_not_seen"] = (f"{feet}; the stated stature {stature_m:.2f} m is used (measured "
                                  f"{m.stature_m:.2f} m); the legs' area is not seen, so the estimate may read low")
        m = dataclasses.replace(m, stature_m=stature_m)
    checks.check_height(m.stature_m)
    flags.update(checks.person_shape_flags(m.stature_m, m.width_m, m.silhouette_m2))
    flags.update(checks.mixed_pixel_flags(m.mixed_share))
    if m.touches_border:
        flags["cut_off"] = "subject pixels on the image border; step back or re-aim the camera"
    if floor is None:
        flags["no_floor"] = FLAGS["no_floor"]
    flags.update(checks.working_range_flags(m.distance_m, intrinsics))
    flags.update(checks.feet_flags(m.distance_m, intrinsics))
    subject = Subject(depth_m, mask, intrinsics, floor, m)
    if progress is not None:
        progress(predictors[0].name, 0, 1)
    prediction = predictors[0].predict(subject, request)
    routes = {predictors[0].name: prediction} if len(predictors) > 1 else {}
    for predictor in predictors[1:]:
        if predictor is None:
            continue
        if progress is not None:
            progress(predictor.name, 0, 1)
        try:  # both: a body fit that fails leaves the regression's answer standing, flagged
            routes[predictor.name] = predictor.predict(subject, request)
        except WbsaError as exc:
            flags["body_fit_failed"] = str(exc)
    for route in (prediction, *list(routes.values())[1:]):
        if not all(np.isfinite(v) for v in (route.wbsa_m2, route.wbsa_lo_m2, route.wbsa_hi_m2)):
            raise WbsaError(f"the {route.model_name} model gave no finite estimate ({route.wbsa_m2}); check the "
                            "model file, or rebuild it")
    if clothes.sd_m > 0:  # the layer's own uncertainty widens every route's interval that can take it
        prediction, routes = _clothes_widened(prediction, routes, predictors, subject, request, clothes)
    if not clothes.stated:
        flags["clothes_unstated"] = FLAGS["clothes_unstated"]
    view = prediction.view
    flags.update(view_flags((azimuth_deg, elevation_deg), view))
    for name, text in prediction.flags.items():  # the image's own checks keep their wording
        flags.setdefault(name, text)
    for name, text in _agreement_flags(routes).items():
        flags.setdefault(name, text)
    if auto:
        flags["camera_assumed"] = (f"no camera was given; the {intrinsics.name} preset fits the image size "
                                   f"({depth_m.shape[1]} x {depth_m.shape[0]})")
    return Estimate(wbsa_m2=prediction.wbsa_m2, wbsa_lo_m2=prediction.wbsa_lo_m2, wbsa_hi_m2=prediction.wbsa_hi_m2,
                    level=level, vbsa_m2=m.vbsa_m2, stature_m=m.stature_m, distance_m=m.distance_m, n_pixels=m.n_pixels,
                    view=view, view_used=prediction.view_used, flags=flags, method=method, model=prediction.model_name,
                    camera=intrinsics.name, clothing_m=clothes.layer_m, clothes=clothes, stature_stated_m=stature_m,
                    mask=mask & np.isfinite(depth_m) & (depth_m > 0), surface=m.surface, measured_mask=m.mask,
                    body=next((p.body for p in (prediction, *routes.values()) if p.body is not None), None),
                    routes=routes)


def _clothes_widened(prediction, routes: dict, predictors: list, subject, request, clothes: Clothes):
    """The lead prediction and the routes with their intervals widened by the clothes' uncertainty
    (:func:`wbsa.estimation.clothes.widened`): each predictor predicts again with the layer thicker by it; a
    route that refuses a layer that thick keeps its interval (the body fit takes it: it fits again, dressed thicker;
    that second fit reports no steps, so the progress shown is the answer's own fit)."""
    from wbsa.estimation.clothes import widened

    thicker = dataclasses.replace(request, clothing_m=clothes.layer_m + clothes.sd_m, progress=None)
    by_name = {p.name: p for p in predictors if p is not None}
    out = {}
    for name, route in ({predictors[0].name: prediction} | routes).items():
        try:
            by_name[name].check_request(thicker)
        except WbsaError:
            out[name] = route
            continue
        lo, hi = widened(route.wbsa_lo_m2, route.wbsa_hi_m2, route.wbsa_m2, by_name[name].predict(subject, thicker).wbsa_m2)
        out[name] = dataclasses.replace(route, wbsa_lo_m2=lo, wbsa_hi_m2=hi)
    return out[predictors[0].name], ({k: out[k] for k in routes} if routes else {})


def _agreement_flags(routes: dict) -> dict[str, str]:
    """``methods_disagree`` when two routes' intervals do not overlap (``both``), and the second route's flags
    (a flag's name means the same whichever route raised it)."""
    if len(routes) < 2:
        return {}
    (name_a, a), (name_b, b) = list(routes.items())[:2]
    flags = dict(b.flags)
    if a.wbsa_hi_m2 < b.wbsa_lo_m2 or b.wbsa_hi_m2 < a.wbsa_lo_m2:
        flags["methods_disagree"] = (f"{name_a} {a.wbsa_m2:.3f} m² [{a.wbsa_lo_m2:.3f}–{a.wbsa_hi_m2:.3f}] and {name_b} "
                                     f"{b.wbsa_m2:.3f} m² [{b.wbsa_lo_m2:.3f}–{b.wbsa_hi_m2:.3f}] do not overlap; check the "
                                     "frame (clothes, pose, the person picked)")
    return flags
