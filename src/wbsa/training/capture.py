"""Random capture conditions for training and testing the estimator: camera, distance, height, view, sensor.

A :class:`Capture` is what one photograph of a standing person depends on besides the person: which camera
(an intrinsics preset with its sensor model), where it stands (distance to the subject's centre and height
above the floor, hence the elevation) and from which side (azimuth, uniform over the full circle).
:func:`sample_capture` draws one so that the subject fits the frame and lies within the camera's range.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wbsa.camera.presets import TRAINED_CAMERAS, CameraRecord, camera_record
from wbsa.errors import WbsaError
from wbsa.sensor.settings import KINECT_V1_BASELINE_M, KINECT_V1_DISPARITY_STEP_PX, SensorSettings
from wbsa.typing import EDGE_PIXELS, EdgePixels, NoiseModel
from wbsa.settings_io import check_types

#: Camera-to-subject distances (m) a training world may span: nearer, a standing adult does not fit the frame
#: of any preset; farther, beyond every preset's working range.
DISTANCE_LIMITS_M = (0.5, 8.0)


@dataclass(frozen=True)
class CaptureSettings:
    """The range of capture conditions.

    Attributes
    ----------
    cameras : tuple of str or CameraRecord
        Camera presets (:data:`wbsa.camera.presets.CAMERAS`) or records of the user's own cameras, drawn
        uniformly; each brings its intrinsics, working range and disparity quantisation.
    distance_m : (float, float)
        Camera to subject's centre, drawn uniformly, then narrowed to the camera's range and lengthened
        until the subject fits the frame.
    camera_height_m : (float, float)
        Height of the camera above the floor.
    noise : bool
        Sensor noise, disparity quantisation where the camera has one, grazing dropout.
    noise_model : {'camera', 'nguyen2012'}
        With ``noise``: each camera's own technology model (:mod:`wbsa.sensor.technology`: structured light,
        time of flight, active stereo, LiDAR), or Kinect v1's (Nguyen et al. 2012) for every camera.
    noise_scale : (float, float)
        Factor on the noise model's σ, uniform: real cameras are less noisy (time of flight) or noisier
        (stereo at range) than their model, and the estimator must not depend on its exact level. The default
        0–3 spans the sensor sweep of ``benchmarks/bench_estimate.py --noise-scale`` (0, 0.3, 1, 3).
    grazing_dropout_scale : (float, float)
        Factor on the noise model's grazing dropout angle (returns within that angle of grazing are lost),
        uniform: some cameras drop the rim of a body, others return it (noisy or mixed), and the estimator
        meets both. Drawn after the noise scale, and not at all when fixed.
    ideal_share : float
        Share of captures with no sensor effects at all (an ideal render, as of a 3-D body scan).
    max_holes_fraction, max_pixel_dropout : float
        Triangle holes and pixel dropout, each drawn uniformly up to this.
    edge_pixels : tuple of {'kept', 'mixed', 'dropped'}
        What the camera returns for pixels straddling a depth edge, drawn uniformly per capture, with the
        share of edges affected uniform in [0, 1] (:func:`wbsa.sensor.depth_edges.edge_pixels`): cameras
        differ (time-of-flight mixing, a flying-pixel filter, neither), and the estimator meets them all.
    """

    cameras: tuple[str | CameraRecord, ...] = TRAINED_CAMERAS
    distance_m: tuple[float, float] = (1.5, 4.5)
    camera_height_m: tuple[float, float] = (0.8, 2.0)
    noise: bool = True
    noise_model: NoiseModel = "camera"
    noise_scale: tuple[float, float] = (0.0, 3.0)
    grazing_dropout_scale: tuple[float, float] = (0.0, 2.0)
    ideal_share: float = 0.1
    max_holes_fraction: float = 0.03
    max_pixel_dropout: float = 0.02
    edge_pixels: tuple[EdgePixels, ...] = EDGE_PIXELS  # type: ignore[assignment]

    def __post_init__(self) -> None:
        check_types(self)
        if not self.edge_pixels:
            raise WbsaError(f"edge_pixels {self.edge_pixels!r} must be a tuple of some of {', '.join(EDGE_PIXELS)}, "
                            "e.g. ('kept',)")

        if not self.cameras:
            raise WbsaError(f"cameras {self.cameras!r} must be a non-empty tuple of presets or camera records")
        for c in self.cameras:
            if not isinstance(c, CameraRecord):
                camera_record(c)  # a one-line error naming the presets
        lo, hi = self.distance_m
        if not DISTANCE_LIMITS_M[0] <= lo <= hi <= DISTANCE_LIMITS_M[1]:
            raise WbsaError(f"distance_m {tuple(self.distance_m)} must be (low, high) metres within "
                            f"{DISTANCE_LIMITS_M[0]:g}-{DISTANCE_LIMITS_M[1]:g} m, e.g. (1.5, 4.5)")
        lo, hi = self.camera_height_m
        if not 0.0 <= lo <= hi:
            raise WbsaError(f"camera_height_m {self.camera_height_m} must be (low, high) metres with 0 <= low <= high")
        lo, hi = self.noise_scale
        if not 0.0 <= lo <= hi <= 10.0:
            raise WbsaError(f"noise_scale {self.noise_scale} must be (low, high) factors with 0 <= low <= high <= 10")
        lo, hi = self.grazing_dropout_scale
        if not 0.0 <= lo <= hi <= 5.0:
            raise WbsaError(f"grazing_dropout_scale {self.grazing_dropout_scale} must be (low, high) factors with "
                            "0 <= low <= high <= 5")
        if not 0.0 <= self.ideal_share <= 1.0:
            raise WbsaError(f"ideal_share {self.ideal_share} must be a share of the captures in [0, 1]")


@dataclass(frozen=True)
class Capture:
    """One drawn capture: the camera, the view (aimed at the subject's centre) and the sensor, with what it
    returns at depth edges (``edge_pixels`` on ``edge_share`` of them)."""

    camera: object
    view: object
    sensor: object
    camera_height_m: float
    fits: bool
    edge_pixels: EdgePixels = "kept"
    edge_share: float = 0.0


def sensor_for(camera: CameraRecord, rng: np.random.Generator, settings: CaptureSettings):
    """The :class:`~wbsa.sensor.SensorSettings` of a camera with random holes and dropout: depth noise
    (``settings.noise_model``: the camera's own technology, or Nguyen et al. 2012's Kinect v1) and, where the
    camera has one, its disparity quantisation."""

    if not settings.noise:
        return SensorSettings()
    baseline, step = camera.disparity or (KINECT_V1_BASELINE_M, KINECT_V1_DISPARITY_STEP_PX)
    own = settings.noise_model == "camera"
    return SensorSettings(noise=settings.noise_model, technology=camera.technology if own else None,
                          quantise=camera.disparity is not None, baseline_m=baseline, disparity_step_px=step,
                          holes_fraction=float(rng.uniform(0, settings.max_holes_fraction)),
                          pixel_dropout=float(rng.uniform(0, settings.max_pixel_dropout)), range_limits=True)


def fits_frame(vertices: np.ndarray, camera, view, target: np.ndarray, margin_px: float = 3.0) -> bool:
    """Whether every vertex projects inside the image, ``margin_px`` from its border."""
    from wbsa.camera.extrinsics import pose_from_view

    pose = pose_from_view(view, target)
    p = pose.apply(np.asarray(vertices, dtype=np.float64))
    if np.any(p[:, 2] <= 0):
        return False
    u = camera.fx * p[:, 0] / p[:, 2] + camera.skew * p[:, 1] / p[:, 2] + camera.cx
    v = camera.fy * p[:, 1] / p[:, 2] + camera.cy
    return bool(u.min() >= margin_px and v.min() >= margin_px and u.max() <= camera.width - 1 - margin_px
                and v.max() <= camera.height - 1 - margin_px)


def sample_capture(vertices: np.ndarray, rng: np.random.Generator, settings: CaptureSettings = CaptureSettings(),
                   azimuth_deg: float | None = None) -> Capture:
    """Draw a capture of a body standing on z = 0.

    Parameters
    ----------
    vertices : (n, 3) float
        The (posed) body.
    rng : numpy.random.Generator
    settings : CaptureSettings
    azimuth_deg : float, optional
        Fixed azimuth (default: uniform over the circle).

    Returns
    -------
    Capture
        ``fits`` False if the subject could not be framed within the camera's range (it is then cut off).
    """
    from wbsa.camera.views import View

    chosen = settings.cameras[int(rng.integers(len(settings.cameras)))]
    record = chosen if isinstance(chosen, CameraRecord) else camera_record(chosen)
    camera = record.intrinsics
    sensor = sensor_for(record, rng, settings)
    v = np.asarray(vertices, dtype=np.float64)
    target = 0.5 * (v.min(axis=0) + v.max(axis=0))
    az = float(rng.uniform(0.0, 360.0)) if azimuth_deg is None else float(azimuth_deg)
    height = float(rng.uniform(*settings.camera_height_m))
    lo = max(settings.distance_m[0], camera.min_range_m + 0.5)
    hi = min(settings.distance_m[1], camera.max_range_m - 0.4)
    distance = float(rng.uniform(lo, max(lo, hi)))
    fits = False
    for _ in range(20):
        el = math.degrees(math.asin(max(-0.95, min(0.95, (height - target[2]) / distance))))
        view = View(az, el, distance)
        fits = fits_frame(v, camera, view, target)
        if fits or distance >= hi:
            break
        distance = min(hi, distance * 1.08)
    edges = settings.edge_pixels[int(rng.integers(len(settings.edge_pixels)))]  # drawn last: earlier draws unchanged
    share = float(rng.uniform(0.0, 1.0))
    return Capture(camera, view, _noise_level(sensor, rng, settings), height, fits, edges,
                   share if edges != "kept" else 0.0)


def as_scan_render(capture: Capture) -> Capture:
    """``capture`` read as a rendered 3-D body scan is: no sensor effects and the render's own edges.

    A scan rendered to a depth image (``wbsa view``, or any ray caster) has no noise, holes, quantisation,
    range limits or mixed pixels; its camera, view and fit are the capture's.
    """
    import dataclasses

    return dataclasses.replace(capture, sensor=SensorSettings(), edge_pixels="kept", edge_share=0.0)


def _noise_level(sensor: SensorSettings, rng: np.random.Generator, settings: CaptureSettings) -> SensorSettings:
    """``sensor`` made ideal (``ideal_share``), or its noise (``noise_scale``) and grazing dropout
    (``grazing_dropout_scale``) scaled; drawn after every other draw of a capture, and not at all when fixed,
    so fixed settings keep the captures they drew before."""
    import dataclasses

    if not settings.noise:
        return sensor
    if settings.ideal_share > 0.0 and rng.uniform() < settings.ideal_share:
        return SensorSettings()
    lo, hi = settings.noise_scale
    scale = float(rng.uniform(lo, hi)) if hi > lo else lo
    sensor = sensor if scale == 1.0 else dataclasses.replace(sensor, noise_scale=scale)
    lo, hi = settings.grazing_dropout_scale
    grazing = float(rng.uniform(lo, hi)) if hi > lo else lo
    if grazing == 1.0 or sensor.effective_grazing_dropout_deg is None:
        return sensor
    return dataclasses.replace(sensor, grazing_dropout_deg=grazing * sensor.effective_grazing_dropout_deg)
