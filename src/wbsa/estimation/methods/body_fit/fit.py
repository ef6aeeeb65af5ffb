"""Fit a whole anny body to one segmented depth view and measure it: :func:`fit_body`.

Steps: the subject's returns become points in a floor-aligned view frame (:mod:`.observation`); a small
render-and-compare grid over sex, arms and azimuth gives the starts (:mod:`.init`); a batched Adam fit moves
phenotypes, local changes, the ten posture angles and the body's placement so that the posed body explains
the points, stays inside the silhouette and hides no seen surface (:mod:`.objective`, :mod:`.optimize`); the
best body is rebuilt on anny's whole mesh and measured at rest as the population is (:mod:`.measures`).
"""

from __future__ import annotations

import functools
import math
import time

import numpy as np

from wbsa.estimation.methods.body_fit.result import BodyFit
from wbsa.estimation.methods.body_fit.settings import ANGLE_LIMITS_DEG, BodyFitSettings
from wbsa.errors import WbsaError, Worded

#: Phenotypes whose value at 0 or 1 flags ``outside_model_range`` (the others are not measured by the view).
_RANGE_CHECKED = ("p_age", "p_muscle", "p_weight", "p_height", "p_proportions")
#: Residual (m) and inlier share beyond which ``poor_fit`` is flagged on a clean frame; on a noisy one
#: (:func:`poor_fit_detail`) the residual may reach :data:`POOR_NOISE_K` times the depth noise measured on the
#: subject, and the share within 3 cm is taken against the share such noise leaves there.
POOR_RESIDUAL_M = 0.015
POOR_INLIER_SHARE = 0.85
POOR_NOISE_K = 1.5
#: Distance (m) of a point from the fitted surface within which it counts as explained.
INLIER_M = 0.03


def poor_fit_detail(residual_m: float, inlier_share: float, noise_m: float) -> str | None:
    """The ``poor_fit`` flag's detail, or None when the fitted surface explains the points as well as their noise
    allows.

    A perfect fit to returns of depth noise σ leaves a residual of about σ and a share erf(3 cm / σ√2) of them
    within 3 cm; a frame three times noisier than Kinect v2's model (σ 3–9 cm) leaves 20–50 mm whatever the body,
    which is the camera's noise, not a poor fit.

    Parameters
    ----------
    residual_m : float
        Robust RMS distance of the points to the fitted surface (m).
    inlier_share : float
        Share of the points within :data:`INLIER_M` of it.
    noise_m : float
        Depth noise measured on the subject (m; :func:`wbsa.estimation.subject.measure.measured_depth_noise`).

    Returns
    -------
    str or None

    Examples
    --------
    >>> poor_fit_detail(0.030, 0.60, 0.002) is not None, poor_fit_detail(0.030, 0.60, 0.040) is None
    (True, True)
    """
    limit_m = max(POOR_RESIDUAL_M, POOR_NOISE_K * noise_m)
    expected = math.erf(INLIER_M / (noise_m * math.sqrt(2.0))) if noise_m > 0 else 1.0
    if residual_m <= limit_m and inlier_share >= POOR_INLIER_SHARE * expected:
        return None
    noise = f" against {1000 * noise_m:.1f} mm of depth noise" if POOR_NOISE_K * noise_m > POOR_RESIDUAL_M else ""
    return f"residual {1000 * residual_m:.1f} mm{noise}, {100 * inlier_share:.0f} % of points within 3 cm"


@functools.lru_cache(maxsize=2)
def _models(spacing_m: float):
    """(BodyModel, FitBody, Anthropometer), built once per process and vertex spacing."""
    import torch

    from wbsa.bodies.anthropometry import Anthropometer
    from wbsa.bodies.body_model import BodyModel
    from wbsa.estimation.methods.body_fit.model import FitBody

    body_model = BodyModel()
    return body_model, FitBody(body_model, spacing_m), Anthropometer(body_model)


def fit_body(depth_m: np.ndarray, mask: np.ndarray, camera, floor, *, clothing_m: float = 0.0,
             azimuth_deg: float | None = None, settings: BodyFitSettings = BodyFitSettings(),
             seed: int = 0, start=None, progress=None, sensor=None) -> BodyFit:
    """Fit anny to one depth view of a standing person and measure the fitted body.

    Parameters
    ----------
    depth_m : (h, w) float64
        z-depth in metres, 0 = no return.
    mask : (h, w) bool
        The subject's pixels (:func:`wbsa.estimation.subject.segment.segment_subject`).
    camera : wbsa.camera.Intrinsics
    floor : wbsa.estimation.subject.cloud.Plane or None
        The floor in the camera frame (returns within its noise are not fitted; the body stands on it).
    clothing_m : float
        A stated layer of clothes (m) over the trunk, upper arms, legs and feet
        (:data:`wbsa.bodies.clothing.COVERED_BONES`): the observation is compared with the fitted body dressed in
        it (an offset of that thickness along the skin's normals there), and the bare body is measured.
    azimuth_deg : float, optional
        A stated view: the starts keep to within 45° of it.
    settings : BodyFitSettings
    seed : int
        Seeds the subsample of the observed points.
    start : callable, optional
        ``start(observation, fit_model) -> Starts``: fit from these starts (:class:`wbsa.estimation.methods.body_fit.init.Starts`,
        in the observation's view frame) instead of the render-and-compare grid; e.g. a known body, to measure
        how far the fit drifts from it.
    progress : callable or None
        Called as ``progress(step, steps)`` after each optimiser step (:func:`optimise`).
    sensor : SensorModel, optional
        The camera's depth-noise model (:func:`wbsa.sensor.technology.envelope_model`): the data term weighs each
        reading by it. None: that of a camera whose technology is unknown.

    Returns
    -------
    BodyFit

    Raises
    ------
    WbsaError
        A depth image that is not (h, w) finite metres of the camera's size, an empty mask, fewer than 200
        returns above the floor, a layer of clothes that is not 0 to 5 cm.
    """
    from wbsa.estimation.clothes import check_clothing
    from wbsa.estimation.methods.body_fit.observation import check_inputs
    from wbsa.parallel import torch_threads

    check_clothing(clothing_m)
    if azimuth_deg is not None and not math.isfinite(azimuth_deg):
        raise WbsaError(f"azimuth_deg must be a finite number of degrees, got {azimuth_deg!r}")
    depth, mask = check_inputs(depth_m, mask, camera)
    body_model, fit_model, meter = _models(settings.vertex_spacing_m)  # once per process, not timed
    with torch_threads(settings.threads):
        return _fit(depth, mask, camera, floor, azimuth_deg, settings, seed, body_model, fit_model, meter, start,
                    float(clothing_m), progress, sensor)


def model_edge_detail(parameters) -> Worded | None:
    """The ``outside_model_range`` detail of a fitted body: its phenotypes within 0.01 of 0 or 1
    (:data:`_RANGE_CHECKED`) and its local changes beyond ±0.99, as ``p_weight = 1.00`` (the page's words:
    ``weight at the body model's highest``); None when none is.

    Parameters
    ----------
    parameters : pandas.Series
        The fitted body's anny parameters by name.
    """
    at_edge = [(f"{k} = {parameters[k]:.2f}",
                f"{k[2:]} at the body model's {'lowest' if parameters[k] < 0.5 else 'highest'}")
               for k in _RANGE_CHECKED if min(parameters[k], 1.0 - parameters[k]) < 0.01]
    at_edge += [(f"{k} = {parameters[k]:+.2f}", f"{k[2:]} at the body model's {'least' if parameters[k] < 0 else 'most'}")
                for k in parameters.index if k.startswith("l_") and abs(parameters[k]) > 0.99]
    if not at_edge:
        return None
    return Worded(", ".join(c for c, _ in at_edge), ", ".join(p for _, p in at_edge))


def _fit(depth, mask, camera, floor, azimuth_deg, settings, seed, body_model, fit_model, meter, start,
         clothing_m, progress, sensor) -> BodyFit:
    """:func:`fit_body` on checked inputs, with anny loaded."""
    import torch

    from wbsa.bodies.clothing import COVERED_BONES
    from wbsa.bodies.posing import pose_vertices
    from wbsa.bodies.posture import ANGLE_COLUMNS
    from wbsa.estimation.methods.body_fit.init import first_guesses
    from wbsa.estimation.methods.body_fit.measures import measure_body
    from wbsa.estimation.methods.body_fit.objective import Objective
    from wbsa.estimation.methods.body_fit.observation import observe
    from wbsa.estimation.methods.body_fit.optimize import optimise

    t0 = time.perf_counter()
    deadline = t0 + settings.time_budget_s
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 0xB0D7]))
    obs = observe(depth, mask, camera, floor, settings.n_points, rng, sensor)
    objective = Objective(obs, settings.robust_loss, settings.robust_scale_m, settings.silhouette_tolerance_px,
                          obs.sensor)
    with torch.no_grad():
        starts = (first_guesses(fit_model, objective, settings.restarts, azimuth_deg, settings.child_starts)
                  if start is None else start(obs, fit_model))
    covered = body_model.vertices_of_bones(COVERED_BONES) if clothing_m > 0 else None
    opt = optimise(fit_model, objective, starts, settings, deadline, clothing_m, covered, progress)

    body = measure_body(meter, opt.params, settings.composition)
    rest = body["rest"]
    angles_deg = np.degrees(opt.angles_rad)
    posed = pose_vertices(rest.vertices[0], rest.bone_heads[0], angles_deg, body_model.rig)
    c, s = math.cos(opt.yaw_rad), math.sin(opt.yaw_rad)
    rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    posed_f = posed @ rz.T + opt.shift_m
    centre = 0.5 * (posed_f.min(0) + posed_f.max(0))
    to_camera = obs.camera_position - centre
    d_body = rz.T @ to_camera
    azimuth = float(np.degrees(np.arctan2(d_body[0], -d_body[1])) % 360.0)
    distance = float(np.linalg.norm(to_camera))
    elevation = obs.elevation_deg(centre)
    res = np.abs(opt.residuals_m)
    kept = np.sort(res)[: max(1, int(0.9 * len(res)))]
    residual = float(np.sqrt(np.mean(kept**2)))
    inliers = float(np.mean(res < INLIER_M))

    flags: dict[str, str] = {}
    if opt.timed_out:
        flags["time_budget"] = (f"stopped after {opt.steps} of {settings.steps} steps at the "
                                f"{settings.time_budget_s:g} s safety stop")
    elif not opt.converged:
        flags["not_converged"] = f"{opt.steps} steps without settling"
    lows = np.array([lo for lo, _ in ANGLE_LIMITS_DEG] * 2)
    highs = np.array([hi for _, hi in ANGLE_LIMITS_DEG] * 2)
    edge = [ANGLE_COLUMNS[i] for i in np.flatnonzero((angles_deg <= lows + 1.0) | (angles_deg >= highs - 1.0))]
    if edge:
        flags["posture_at_limit"] = ", ".join(edge)
    table = body["table"].iloc[0]
    at_edge = model_edge_detail(table)
    if at_edge:
        flags["outside_model_range"] = at_edge
    poor = poor_fit_detail(residual, inliers, obs.noise_m)
    if poor:
        flags["poor_fit"] = poor
    if mask[0].any() or mask[-1].any() or mask[:, 0].any() or mask[:, -1].any():
        flags["cut_off"] = "subject pixels on the image border; part of the body may be missing"
    if floor is None:
        flags["no_floor"] = "no floor given: the body's height and uprightness come from its points alone"
    if abs(elevation) > 45.0:
        flags["steep_view"] = f"elevation {elevation:.0f}°"

    m = body["measures"]
    from wbsa.estimation.methods.body_fit.interval import load

    cal = load()
    lo, hi = cal.interval(float(m["wbsa_m2"])) if cal is not None else (math.nan, math.nan)
    tapes = {k: float(v) for k, v in m.items() if k.endswith("_circ_m") or k.endswith("_width_m")}
    return BodyFit(
        wbsa_m2=float(m["wbsa_m2"]), wbsa_lo_m2=lo, wbsa_hi_m2=hi, level=cal.level if cal is not None else math.nan,
        stature_m=float(m["stature_m"]), volume_m3=float(m["volume_m3"]),
        mass_kg=float(m["mass_kg"]), bmi=float(m["bmi"]), tapes=tapes, sex="male" if body["male"] else "female",
        age_years=body["age_years"], parameters={k: float(v) for k, v in table.items()},
        posture_deg=dict(zip(ANGLE_COLUMNS, angles_deg.tolist())), azimuth_deg=azimuth, elevation_deg=elevation,
        distance_m=distance, residual_m=residual, inlier_share=inliers, loss=opt.loss, converged=opt.converged,
        flags=flags, seconds=time.perf_counter() - t0, steps=opt.steps, restarts=len(starts.label),
        rest_vertices=rest.vertices[0], posed_vertices=obs.to_camera(posed_f), faces=body_model.skin_faces)


