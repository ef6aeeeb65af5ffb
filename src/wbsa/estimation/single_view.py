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

from wbsa.errors import WbsaError, Worded, worded
from wbsa.estimation.clothes import UNSTATED, Clothes, widened
from wbsa.estimation.flags import CLOTHES_UNSTATED, FLAGS
from wbsa.estimation.methods.base import Prediction, Request, Subject
from wbsa.estimation.methods.dispatch import predictors_for
from wbsa.estimation.methods.view import ViewEstimate, view_flags
from wbsa.estimation.request import EstimateRequest
from wbsa.estimation.subject import checks
from wbsa.estimation.subject.measure import SubjectMeasures, measure_subject
from wbsa.estimation.subject.mixed_pixels import repair_mixed_pixels
from wbsa.estimation.subject.people import feet_shape_unseen, feet_unseen, open_feet
from wbsa.estimation.subject.segment import SegmentSettings, segment_subject
from wbsa.estimation.subject.unseen import UnseenLegs, unseen_legs
from wbsa.estimation.subject.unseen import widened as unseen_widened
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
        JSON (:func:`wbsa.strict_json.json_text`). Each quantity is said once: the fitted body's area and
        interval are its route's (the top level with ``body-fit``, ``routes["body-fit"]`` with ``both``), so
        ``body`` holds its other measures, and its ``seconds`` is the time of every fit the route ran.
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
            out["body"] = {k: v for k, v in self.body.to_dict().items() if k not in _ROUTE_NUMBERS}
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


#: A fitted body's numbers that its route states (:meth:`Estimate.to_dict` says them there only).
_ROUTE_NUMBERS = ("wbsa_m2", "wbsa_lo_m2", "wbsa_hi_m2", "level")


def _depth_array(depth, depth_scale: float | None) -> np.ndarray:
    if isinstance(depth, (str, os.PathLike)):
        from wbsa.core.depth_image import read_depth

        return read_depth(depth, depth_scale=depth_scale)
    from wbsa.core.depth_image import metres_from_units

    raw = np.asarray(depth) if not isinstance(depth, np.ndarray) else depth
    if raw.dtype.kind not in "iuf":
        raise WbsaError(f"depth must be a path or a 2-D array of real numbers (metres), got a {raw.dtype} "
                        f"{type(depth).__name__}" + ("; give the real part (depth.real) if that is the depth"
                                                     if raw.dtype.kind == "c" else ""))
    if depth_scale is None:
        return raw.astype(np.float64)
    if not (checks.is_real_number(depth_scale) and np.isfinite(depth_scale) and depth_scale > 0):
        raise WbsaError(f"depth_scale must be a positive number of units per metre, e.g. 1000, got {depth_scale!r}")
    return metres_from_units(raw, float(depth_scale)).astype(np.float64)


def estimate(depth, camera, model=None, method: Method = "regression", *, azimuth_deg: float | None = None,
             elevation_deg: float | None = None, clothes: str | None = None, clothing_m: float | None = None,
             stature_m: float | None = None, level: float = 0.95,
             depth_scale: float | None = None, segment: SegmentSettings | None = SegmentSettings(),
             body_fit: BodyFitSettings | None = None, progress: Callable[[str, int, int], None] | None = None,
             clothing: str | None = None) -> Estimate:
    """Estimate WBSA from one depth image of a standing person (the arguments checked once, as an
    :class:`~wbsa.estimation.request.EstimateRequest`, which :func:`estimate_request` runs).

    Parameters
    ----------
    depth : (h, w) float array (metres, 0 = no return) or path
        A path is read with :func:`wbsa.core.read_depth` (16-bit PNG, .npy, .tiff, .exr). A ``.pcd`` or ``.ply``
        point cloud (camera frame, metres) is read with :func:`wbsa.core.point_cloud.point_cloud_depth`: an
        organised ``.pcd`` brings its own camera, recovered from its points.
    camera : str, path, wbsa.camera.Intrinsics or wbsa.camera.CameraRecord
        A preset name (``kinect-v2``, ...), an Open3D intrinsics JSON (its technology unknown: Kinect v1's depth
        noise is assumed), or ``auto``: the preset of the image's size, flagged ``camera_assumed``. An organised
        ``.pcd``'s recovered camera is used under ``auto``; a ``.ply`` or unorganised ``.pcd`` needs a stated one.
    model : EstimatorModel, path or None
        None: the model shipped with wbsa. A path: an estimator model file (``.npz``, e.g. from ``wbsa train``)
        or a ``wbsa fit`` model file (``.json``).
    method : {'regression', 'body-fit', 'both'}
        The route (:mod:`wbsa.estimation.methods`): the regression on the image's measures, the whole body fitted
        to the view (seconds), or both (the regression's number leads; ``routes`` holds both).
    azimuth_deg, elevation_deg : float, optional
        A stated view; it is used for the prediction and checked against the estimated one.
    clothes : str, optional
        The clothes by name (:data:`wbsa.estimation.clothes.CLOTHES`): a layer with its own uncertainty, which
        widens the interval. The camera sees the clothes' outside (a 1 cm layer not stated reads +8.6 %).
    clothing_m : float, optional
        Or an explicit layer (m, 0–0.05: :data:`wbsa.estimation.limits.LIMITS`) over the trunk, upper arms, legs
        and feet. Neither given: taken as 0, flagged ``clothes_unstated``.
    stature_m : float, optional
        The stature (m), stated: always used in place of the measured one (flagged `stature_disagrees` beyond
        5 cm); needed where the feet are not seen, whose unseen legs are then completed
        (:mod:`wbsa.estimation.subject.unseen`).
    level : float
        Coverage of the prediction interval, in (0, 1).
    depth_scale : float, optional
        Units per metre of the depth values (files: see :func:`wbsa.core.read_depth`; arrays: default 1).
    segment : SegmentSettings or None
        How to find the subject in a room; None: every return is the subject.
    body_fit : BodyFitSettings or None
        With ``method="body-fit"`` or ``"both"``: how the body is fitted (None: the defaults).
    progress : callable, optional
        ``progress(stage, done, total)``: ``("subject", 0, 1)``, then ``(route, 0, 1)`` as each route starts, the
        body fit also ``("body-fit", step, steps)``. The estimate is the same with or without it.
    clothing : str, optional
        The old name of ``clothes`` (deprecated: a :class:`DeprecationWarning`).

    Returns
    -------
    Estimate

    Raises
    ------
    WbsaError
        Unreadable input, an image not of the camera's size, no or several people without a pick, a height that
        is not human, a broken model, or an argument out of its range (one line naming it).
    """
    request = EstimateRequest.build(camera, method, azimuth_deg=azimuth_deg, elevation_deg=elevation_deg,
                                    clothes=_clothes_named(clothes, clothing), clothing_m=clothing_m,
                                    stature_m=stature_m, level=level, segment=segment, body_fit=body_fit)
    return estimate_request(request, depth, model, depth_scale=depth_scale, progress=progress)


def estimate_request(request: EstimateRequest, depth, model=None, *, depth_scale: float | None = None,
                     progress: Callable[[str, int, int], None] | None = None) -> Estimate:
    """The estimate of a checked request (:class:`~wbsa.estimation.request.EstimateRequest`): the image is read
    and checked against the camera, the subject found and measured, the routes run, and the answer assembled.

    Parameters
    ----------
    request : EstimateRequest
    depth, model, depth_scale, progress
        As for :func:`estimate`.

    Returns
    -------
    Estimate
    """
    depth_m, request = _read(request, depth, depth_scale)
    predictors = list(predictors_for(request.method, model, request.body_fit))  # a model is read (and refused) first
    depth_m, mixed = repair_mixed_pixels(depth_m, request.camera.intrinsics.fx, request.sensor)
    asked = request.method_request(progress)
    predictors, flags = _servable(predictors, asked)
    _report(progress, "subject")
    subject, subject_flags = measure(depth_m, mixed, request)
    flags.update(subject_flags)
    prediction, routes, route_flags = run_routes(predictors, subject, asked, request.clothes, progress)
    flags.update(route_flags)
    return assemble(request, subject, prediction, routes, flags)


def _read(request: EstimateRequest, depth, depth_scale: float | None) -> tuple[np.ndarray, EstimateRequest]:
    """The depth image (metres) and the request for it: a point cloud's camera (recovered from an organised
    ``.pcd``'s grid, or the stated one it is projected through) is the request's camera."""
    from wbsa.camera.presets import record_of
    from wbsa.core.point_cloud import is_point_cloud_path, point_cloud_depth

    if not is_point_cloud_path(depth):
        depth_m = _depth_array(depth, depth_scale)
        return depth_m, request.for_image(depth_m)
    stated = None if request.camera is None else request.camera.intrinsics
    depth_m, intrinsics = point_cloud_depth(depth, stated, units_per_m=depth_scale)
    if stated is None or intrinsics != stated:
        request = request.with_camera(record_of(intrinsics))
    return depth_m, request.for_image(depth_m)


def _clothes_named(clothes: str | None, clothing: str | None) -> str | None:
    """``clothes``, or the deprecated ``clothing`` with a :class:`DeprecationWarning`."""
    if clothing is None:
        return clothes
    import warnings

    warnings.warn("estimate(clothing=...) is deprecated; use clothes=...", DeprecationWarning, stacklevel=3)
    if clothes is not None:
        raise WbsaError("give the clothes once, as clothes (clothing is its old name)")
    return clothing


def _report(progress, stage: str) -> None:
    if progress is not None:
        progress(stage, 0, 1)


def _servable(predictors: list, request: Request) -> tuple[list, dict[str, str]]:
    """The predictors that can serve ``request`` (a second route that cannot is None, flagged
    ``body_fit_failed``; the first one's refusal is raised)."""
    flags: dict[str, str] = {}
    out = list(predictors)
    for k, predictor in enumerate(predictors):
        try:
            predictor.check_request(request)
        except WbsaError as exc:
            if k == 0:
                raise
            flags["body_fit_failed"] = worded(exc)  # both: the second route cannot serve this request
            out[k] = None
    return out, flags


def measure(depth_m: np.ndarray, mixed: np.ndarray, request: EstimateRequest) -> tuple[Subject, dict[str, str]]:
    """The subject of a repaired depth image (segmented and measured) and the flags of the image's checks.

    Parameters
    ----------
    depth_m : (h, w) float64
        The depth image (metres), mixed returns repaired (:func:`repair_mixed_pixels`).
    mixed : (h, w) bool
        The repaired returns.
    request : EstimateRequest
        Checked and resolved for this image (:meth:`EstimateRequest.for_image`).

    Returns
    -------
    subject : Subject
    flags : dict of str to str

    Raises
    ------
    WbsaError
        No returns, no or several people without a pick, feet not seen without a stated stature, a height
        that is not human.
    """
    camera, stature_m, flags = request.camera, request.stature_m, {}
    if request.segment is None:
        mask, floor = np.isfinite(depth_m) & (depth_m > 0), None
        if not mask.any():
            raise WbsaError("the depth image has no returns; check the depth scale and the file")
        feet = open_feet(mask)
    else:
        seg = segment_subject(depth_m, camera.intrinsics, request.segment, sensor=request.sensor)
        mask, floor = seg.mask, seg.floor
        if seg.others:
            pick = request.segment.pick
            flags["several_people"] = Worded(
                f"picked {seg.subject.describe()} ({pick}); others: " + "; ".join(c.describe() for c in seg.others),
                f"picked {seg.subject.describe(True)} ({pick}); others: "
                + "; ".join(c.describe(True) for c in seg.others))
        feet = feet_unseen(seg.subject, floor)
    if feet is not None and stature_m is None:  # refused before the measures, which it does not need
        raise _feet_not_seen(feet)
    m = measure_subject(depth_m, mask, camera.intrinsics, floor, mixed)
    if feet is None and floor is None:
        feet = feet_shape_unseen(m.shape)
        if feet is not None and stature_m is None:
            raise _feet_not_seen(feet)
    unseen = None
    if stature_m is not None:
        bottom_m = None if request.segment is None or floor is None else seg.subject.bottom_m
        m, unseen, stated_flags = stated_stature(m, stature_m, feet, bottom_m)
        flags.update(stated_flags)
    checks.check_height(m.stature_m)
    flags.update(checks.person_shape_flags(m.stature_m, m.width_m, m.silhouette_m2))
    flags.update(checks.mixed_pixel_flags(m.mixed_share))
    if m.touches_border:
        flags["cut_off"] = "subject pixels on the image border; step back or re-aim the camera"
    if floor is None:
        flags["no_floor"] = FLAGS["no_floor"]
    flags.update(checks.working_range_flags(m.distance_m, camera))
    flags.update(checks.feet_flags(m.distance_m, camera))
    return Subject(depth_m, mask, camera, floor, m, request.sensor, unseen), flags


def _feet_not_seen(feet: str) -> WbsaError:
    """The one-line refusal of a subject whose feet are not seen (``feet``: why) and whose stature is not stated."""
    why = (f"feet not seen: {feet}; without the feet the WBSA is not measured (a cut-off adult would read as a "
           "child): capture the whole person, feet on the floor, or state the stature")
    return WbsaError(f"{why} (--stature-cm, stature_m)", code="feet_not_seen", field="stature_m",
                     page=f"{why} (type the height in cm under Height)")


def stated_stature(m: SubjectMeasures, stature_m: float, feet: str | None,
                   bottom_m: float | None) -> tuple[SubjectMeasures, UnseenLegs | None, dict[str, str]]:
    """The measures at a stated stature, the legs left unseen and the flags: a stated stature is always used.

    Where the feet are not seen (``feet``), the body below its lowest returns (``bottom_m`` over a seen floor;
    without a floor, the stated stature less the seen body's height) is unseen (flag ``feet_not_seen``).
    Without a floor and with the feet not judged, a seen body more than
    :data:`~wbsa.estimation.subject.checks.STATURE_TOLERANCE_M` shorter than stated is taken as cut off there
    too (the legs may end over nothing: a frame cut above the floor). Otherwise a stature that differs from the
    measured one by more than that is flagged ``stature_disagrees``.

    Parameters
    ----------
    m : SubjectMeasures
    stature_m : float
        The stated stature (metres).
    feet : str or None
        Why the feet are not seen (:func:`~wbsa.estimation.subject.people.feet_unseen`), or None.
    bottom_m : float or None
        Height of the subject's lowest returns over the seen floor (None: no floor seen).
    """
    measured = m.stature_m
    short = stature_m - measured
    flags: dict[str, str] = {}
    unseen = None
    if feet is not None or (bottom_m is None and short > checks.STATURE_TOLERANCE_M):
        seen_from = bottom_m if bottom_m is not None else short
        unseen = unseen_legs(stature_m, seen_from)
        why = feet or (f"the body seen is {measured:.2f} m tall, {100 * short:.0f} cm less than the stated "
                       f"{stature_m:.2f} m, with no floor seen: the legs may end over nothing (cut off by the picture)")
        flags["feet_not_seen"] = (f"{why}; the stated stature {stature_m:.2f} m is used"
                                  + (f"; {unseen.describe()}" if unseen is not None else ""))
    elif abs(short) > checks.STATURE_TOLERANCE_M:
        flags["stature_disagrees"] = (f"the stated stature {stature_m:.2f} m is used; {measured:.2f} m was measured "
                                      f"({100 * short:+.0f} cm): check the value typed and that the person stands "
                                      "straight")
    return dataclasses.replace(m, stature_m=stature_m), unseen, flags


def run_routes(predictors: list, subject: Subject, request: Request, clothes: Clothes,
               progress: Callable[[str, int, int], None] | None = None) -> tuple[Prediction, dict, dict[str, str]]:
    """Every route's prediction of ``subject``, their intervals widened by the clothes' uncertainty.

    Parameters
    ----------
    predictors : list of Predictor or None
        The lead route first; a second that cannot serve the request is None (:func:`_servable`).
    subject : Subject
    request : Request
    clothes : Clothes
    progress : callable, optional
        As for :func:`estimate`.

    Returns
    -------
    prediction : Prediction
        The lead route's.
    routes : dict of str to Prediction
        With two routes, each one's by name (else empty).
    flags : dict of str to str
        ``body_fit_failed`` when the second route fails.

    Raises
    ------
    WbsaError
        The lead route fails, or a route gives no finite estimate.
    """
    flags: dict[str, str] = {}
    _report(progress, predictors[0].name)
    prediction = predictors[0].predict(subject, request)
    routes = {predictors[0].name: prediction} if len(predictors) > 1 else {}
    for predictor in predictors[1:]:
        if predictor is None:
            continue
        _report(progress, predictor.name)
        try:  # both: a body fit that fails leaves the regression's answer standing, flagged
            routes[predictor.name] = predictor.predict(subject, request)
        except WbsaError as exc:
            flags["body_fit_failed"] = worded(exc)
    for route in (prediction, *list(routes.values())[1:]):
        if not all(np.isfinite(v) for v in (route.wbsa_m2, route.wbsa_lo_m2, route.wbsa_hi_m2)):
            raise WbsaError(f"the {route.model_name} model gave no finite estimate ({route.wbsa_m2}); check the "
                            "model file, or rebuild it")
    if clothes.sd_m > 0:  # the layer's own uncertainty widens every route's interval that can take it
        prediction, routes = _clothes_widened(prediction, routes, predictors, subject, request, clothes)
    if subject.unseen is not None:  # so does the spread of the unseen legs' share
        def wider(route: Prediction) -> Prediction:
            lo, hi = unseen_widened(route.wbsa_lo_m2, route.wbsa_hi_m2, route.wbsa_m2, subject.unseen, request.level)
            return dataclasses.replace(route, wbsa_lo_m2=lo, wbsa_hi_m2=hi)

        prediction, routes = wider(prediction), {name: wider(route) for name, route in routes.items()}
    return prediction, routes, flags


def assemble(request: EstimateRequest, subject: Subject, prediction: Prediction, routes: dict,
             flags: dict[str, str]) -> Estimate:
    """The :class:`Estimate`: the lead prediction, the subject's measures and every flag (the image's checks
    first, then the clothes, the view, the routes' own and their agreement, the camera assumed).

    Parameters
    ----------
    request : EstimateRequest
    subject : Subject
    prediction : Prediction
        The lead route's.
    routes : dict of str to Prediction
    flags : dict of str to str
        The flags so far (the image's and the routes'); the estimate's own copy is made here.
    """
    flags = dict(flags)
    if not request.clothes.stated:
        flags["clothes_unstated"] = CLOTHES_UNSTATED
    flags.update(view_flags((request.azimuth_deg, request.elevation_deg), prediction.view))
    for name, text in prediction.flags.items():  # the image's own checks keep their wording
        flags.setdefault(name, text)
    for name, text in _agreement_flags(routes).items():
        flags.setdefault(name, text)
    depth_m, m, camera = subject.depth_m, subject.measures, subject.camera
    if request.camera_assumed:
        flags["camera_assumed"] = (f"no camera was given; the {camera.name} preset fits the image size "
                                   f"({depth_m.shape[1]} x {depth_m.shape[0]})")
    return Estimate(wbsa_m2=prediction.wbsa_m2, wbsa_lo_m2=prediction.wbsa_lo_m2, wbsa_hi_m2=prediction.wbsa_hi_m2,
                    level=request.level, vbsa_m2=m.vbsa_m2, stature_m=m.stature_m, distance_m=m.distance_m,
                    n_pixels=m.n_pixels, view=prediction.view, view_used=prediction.view_used, flags=flags,
                    method=request.method, model=prediction.model_name, camera=camera.name,
                    clothing_m=request.clothes.layer_m, clothes=request.clothes, stature_stated_m=request.stature_m,
                    mask=subject.mask & np.isfinite(depth_m) & (depth_m > 0), surface=m.surface,
                    measured_mask=m.mask,
                    body=next((p.body for p in (prediction, *routes.values()) if p.body is not None), None),
                    routes=routes)


def _clothes_widened(prediction, routes: dict, predictors: list, subject, request, clothes: Clothes):
    """The lead prediction and the routes with their intervals widened by the clothes' uncertainty
    (:func:`wbsa.estimation.clothes.widened`): each predictor predicts again with the layer thicker by it; a
    route that refuses a layer that thick keeps its interval (the body fit takes it: it fits again, dressed thicker;
    that second fit reports no steps, so the progress shown is the answer's own fit). A route's fitted body
    carries the widened interval and the time of both fits, so the body and its route say one thing."""
    thicker = dataclasses.replace(request, clothing_m=clothes.layer_m + clothes.sd_m, progress=None)
    by_name = {p.name: p for p in predictors if p is not None}
    out = {}
    for name, route in ({predictors[0].name: prediction} | routes).items():
        try:
            by_name[name].check_request(thicker)
        except WbsaError:
            out[name] = route
            continue
        again = by_name[name].predict(subject, thicker)
        lo, hi = widened(route.wbsa_lo_m2, route.wbsa_hi_m2, route.wbsa_m2, again.wbsa_m2)
        body = route.body
        if body is not None:
            body = dataclasses.replace(body, wbsa_lo_m2=lo, wbsa_hi_m2=hi,
                                       seconds=body.seconds + getattr(again.body, "seconds", 0.0))
        out[name] = dataclasses.replace(route, wbsa_lo_m2=lo, wbsa_hi_m2=hi, body=body)
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
