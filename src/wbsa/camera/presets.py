"""The camera presets: one record per depth camera, everything wbsa knows of it in one place.

A :class:`CameraRecord` holds the intrinsics (image size, focal lengths, principal point, working range),
how the camera measures depth (its technology, the disparity quantisation of structured-light and stereo
cameras), whether the default estimator model was trained on it, and where the numbers come from. The
intrinsics, the sensor simulation of the training renders, the working-range check of an estimate and every
``--help`` list of presets read this table; adding a camera is adding a record.

Sources (docs/references.md): Kinect v1: the OpenNI/ROS default calibration and Khoshelham & Elberink (2012)
for its 0.075 m baseline and 1/8-pixel disparity step; Kinect v2: libfreenect2's factory depth intrinsics;
TUM: Sturm et al. (2012); Azure Kinect: Microsoft's hardware specification (NFOV unbinned, WFOV 2×2 binned);
RealSense D435/D455: Intel's datasheet (baselines 50 / 95 mm, about 1/12-pixel subpixel disparity);
phone LiDAR: ARKit's scene-depth map of an iPhone 12 Pro. Values other than Kinect v1/v2 and TUM are typical:
give your own calibration (Open3D JSON) for accurate work.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wbsa.camera.intrinsics import Intrinsics
from wbsa.errors import WbsaError
from wbsa.typing import PRESET_NAMES, DepthTechnology, PresetName


@dataclass(frozen=True)
class CameraRecord:
    """One depth camera.

    Attributes
    ----------
    intrinsics : Intrinsics
        Image size, focal lengths, principal point (pixels) and the nominal working range
        (``min_range_m``, ``max_range_m``).
    technology : {'structured-light', 'time-of-flight', 'active-stereo', 'lidar'} or None
        None: unknown (a camera of the user's own calibration, :func:`own_camera`).
    disparity : (float, float) or None
        Baseline (m) and disparity step (pixels) of a structured-light or stereo camera, whose depth is
        quantised in disparity; None for time of flight and LiDAR.
    trained : bool
        Whether the default estimator model's training renders use this camera.
    note : str
        What the preset is (one line; shown in ``--help``).
    feet_within_m : float or None
        Farthest distance at which the estimator's segmentation tells the feet from the floor in 99 % of the
        benchmark's frames (``benchmarks/bench_estimate.py``, segmentation by camera and band); beyond it an
        estimate is flagged ``feet_unsure``. None: the whole working range.
    """

    intrinsics: Intrinsics
    technology: DepthTechnology | None
    disparity: tuple[float, float] | None
    trained: bool
    note: str
    feet_within_m: float | None = None

    def __post_init__(self) -> None:
        if self.disparity is not None:
            baseline_m, step_px = (float(v) for v in self.disparity)
            if not (math.isfinite(baseline_m) and baseline_m > 0 and math.isfinite(step_px) and step_px > 0):
                raise WbsaError(f"camera {self.name}: disparity must be (baseline m, step px), both positive, "
                                f"got {self.disparity!r}")

    @property
    def name(self) -> str:
        """The preset's name (the intrinsics' ``name``)."""
        return self.intrinsics.name

    @property
    def working_range_m(self) -> tuple[float, float]:
        """(nearest, farthest) distance the camera is specified for (m)."""
        return self.intrinsics.min_range_m, self.intrinsics.max_range_m

    def describe(self) -> str:
        """``name (note, w×h, a–b m)``: one entry of a ``--help`` list."""
        k = self.intrinsics
        return f"{self.name} ({self.note}, {k.width}x{k.height}, {k.min_range_m:g}-{k.max_range_m:g} m)"


def _record(name: str, size: tuple[int, int], focal: tuple[float, float], centre: tuple[float, float],
            range_m: tuple[float, float], technology: DepthTechnology, disparity: tuple[float, float] | None,
            trained: bool, note: str, feet_within_m: float | None = None) -> CameraRecord:
    return CameraRecord(Intrinsics(*size, *focal, *centre, name=name, min_range_m=range_m[0], max_range_m=range_m[1]),
                        technology, disparity, trained, note, feet_within_m)


#: Every camera preset, by name (the order of :data:`wbsa.typing.PresetName`).
CAMERAS: dict[str, CameraRecord] = {r.name: r for r in (
    _record("kinect-v1", (640, 480), (575.8157, 575.8157), (314.5, 235.5), (0.8, 4.0), "structured-light",
            (0.075, 1 / 8), True, "Kinect v1, OpenNI/ROS default, the paper's camera"),
    _record("kinect-v2", (512, 424), (365.456, 365.456), (254.878, 205.395), (0.5, 4.5), "time-of-flight", None, True,
            "Kinect v2 depth camera"),
    _record("tum", (640, 480), (525.0, 525.0), (319.5, 239.5), (0.8, 4.0), "structured-light", (0.075, 1 / 8),
            False, "TUM RGB-D default, a Kinect v1"),
    _record("azure-kinect-nfov", (640, 576), (503.9, 504.0), (332.1, 325.9), (0.5, 3.86), "time-of-flight", None,
            True, "Azure Kinect NFOV unbinned"),
    _record("azure-kinect-wfov", (512, 512), (252.0, 252.0), (261.8, 253.0), (0.25, 2.88), "time-of-flight", None,
            False, "Azure Kinect WFOV 2x2 binned"),
    _record("realsense-d435", (848, 480), (426.0, 426.0), (423.5, 239.5), (0.3, 3.0), "active-stereo",
            (0.050, 1 / 12), True, "Intel RealSense D435"),
    _record("realsense-d455", (848, 480), (415.0, 415.0), (423.5, 239.5), (0.6, 6.0), "active-stereo",
            (0.095, 1 / 12), True, "Intel RealSense D455"),
    # 3 m: the range the segmentation target is judged over for this camera; held-out seed 1000 told
    # the feet from the floor in 32 of 32 frames within 3 m, 17 of 19 at 3-4 m and 3 of 6 at 4-5 m
    _record("phone-lidar", (256, 192), (209.2, 209.2), (124.2, 96.4), (0.25, 5.0), "lidar", None, True,
            "phone LiDAR, ARKit scene depth", feet_within_m=3.0),
)}
assert tuple(CAMERAS) == PRESET_NAMES, "the camera table and wbsa.typing.PresetName must list the same presets"

#: The intrinsics of every preset, by name.
PRESETS: dict[str, Intrinsics] = {name: r.intrinsics for name, r in CAMERAS.items()}
#: The camera argument that asks for the preset of the image's size (:func:`camera_for_image`).
AUTO_CAMERA = "auto"
#: Cameras of the default training world.
TRAINED_CAMERAS: tuple[str, ...] = tuple(name for name, r in CAMERAS.items() if r.trained)


def own_camera(intrinsics: Intrinsics) -> CameraRecord:
    """The record of a camera of the user's own calibration: its intrinsics, its technology unknown.

    Parameters
    ----------
    intrinsics : Intrinsics
    """
    return CameraRecord(intrinsics, None, None, False, "own calibration")


def record_of(intrinsics: Intrinsics) -> CameraRecord:
    """The preset record whose intrinsics ``intrinsics`` is (name and numbers), else :func:`own_camera`.

    Parameters
    ----------
    intrinsics : Intrinsics
    """
    record = CAMERAS.get(getattr(intrinsics, "name", None))
    return record if record is not None and record.intrinsics == intrinsics else own_camera(intrinsics)


def camera_record(name: str) -> CameraRecord:
    """The record of a preset; a one-line :class:`WbsaError` naming the presets otherwise.

    Parameters
    ----------
    name : str
        A preset's name (a key of :data:`CAMERAS`).
    """
    try:
        return CAMERAS[name]
    except (KeyError, TypeError):
        raise WbsaError(f"unknown camera preset {name!r}; use one of {', '.join(CAMERAS)} or a JSON file") from None


def presets_help(default: str | None = None) -> str:
    """The presets as a ``--help`` text: ``preset (one of ...) or Open3D intrinsics JSON``.

    Parameters
    ----------
    default : str or None
        The option's default, said at the end when given.
    """
    tail = f" (default {default})" if default else ""
    return (f"camera preset, one of: {'; '.join(r.describe() for r in CAMERAS.values())}; or an Open3D "
            f"PinholeCameraIntrinsic JSON file{tail}")


def preset(name: PresetName) -> Intrinsics:
    """The intrinsics of a named camera (a key of :data:`~wbsa.camera.presets.CAMERAS`, e.g. ``kinect-v2``).

    Parameters
    ----------
    name : str
        A preset's name (a key of :data:`CAMERAS`).
    """
    return camera_record(name).intrinsics


def camera_for_image(depth_shape: tuple[int, int]) -> Intrinsics:
    """The intrinsics of :func:`record_for_image`.

    Parameters
    ----------
    depth_shape : (int, int)
        The depth image's (h, w).
    """
    return record_for_image(depth_shape).intrinsics


def record_for_image(depth_shape: tuple[int, int]) -> CameraRecord:
    """The one preset whose image is ``depth_shape``.

    A size several presets share (640 × 480: Kinect v1 and TUM's calibration of it; 848 × 480: RealSense D435
    and D455) is refused: their focal lengths differ by up to 10 %, which moves the area by up to 20 %.

    Parameters
    ----------
    depth_shape : (int, int)
        The depth image's (h, w).

    Raises
    ------
    WbsaError
        No preset or several have that size (``code="camera_size"``).
    """
    h, w = depth_shape
    found = [r for r in CAMERAS.values() if (r.intrinsics.width, r.intrinsics.height) == (w, h)]
    if len(found) > 1:
        names = [r.name for r in found]
        focal = ", ".join(f"{r.name} {r.intrinsics.fx:.0f} px" for r in found)
        said = f"a depth image of {w}x{h} pixels fits {len(found)} cameras of different focal lengths ({focal})"
        raise WbsaError(f"{said}, so its camera cannot be told from its size; add "
                        f"{' or '.join(f'--camera {n}' for n in names)} (camera={names[0]!r} in Python), or, for "
                        "another camera of this size, its intrinsics JSON file",
                        code="camera_size", field="camera", value="auto",
                        page=f"{said}; choose the camera under Camera, or add its intrinsics file")
    if not found:
        raise WbsaError(f"a {w}x{h} depth image fits none of the presets; give --camera PRESET or an intrinsics JSON",
                        code="camera_size", field="camera", value="auto",
                        page=f"a {w}x{h} depth image fits none of the presets; choose the camera under Camera, or add "
                             "its intrinsics file")
    return found[0]


def resolve_camera(spec: str | os.PathLike | Intrinsics, depth_shape: tuple[int, int] | None = None) -> Intrinsics:
    """The intrinsics of :func:`resolve_record`.

    Parameters
    ----------
    spec : str, path, Intrinsics, CameraRecord or open3d.camera.PinholeCameraIntrinsic
    depth_shape : (int, int), optional
        The depth image's (h, w), for ``auto``.
    """
    return resolve_record(spec, depth_shape).intrinsics


def resolve_record(spec, depth_shape: tuple[int, int] | None = None) -> CameraRecord:
    """A preset name, the path of an Open3D intrinsics JSON file, an Open3D ``PinholeCameraIntrinsic`` object,
    intrinsics or a record, as the camera's record (a preset's, or :func:`own_camera` for intrinsics that are no
    preset's: :func:`record_of`); ``auto``: the preset of the image's size (:func:`record_for_image` of
    ``depth_shape``).

    Parameters
    ----------
    spec : str, path, Intrinsics, CameraRecord or open3d.camera.PinholeCameraIntrinsic
    depth_shape : (int, int), optional
        The depth image's (h, w), for ``auto``.
    """
    if isinstance(spec, CameraRecord):
        return spec
    if isinstance(spec, str) and spec == AUTO_CAMERA:
        if depth_shape is None:
            raise WbsaError("camera auto is found from the depth image's size; give the image, or a preset")
        return record_for_image(depth_shape)
    if isinstance(spec, Intrinsics):
        return record_of(spec)
    if hasattr(spec, "intrinsic_matrix") and hasattr(spec, "width"):  # open3d.camera.PinholeCameraIntrinsic
        return record_of(Intrinsics.from_open3d_json({
            "width": spec.width, "height": spec.height,
            "intrinsic_matrix": np.asarray(spec.intrinsic_matrix).T.ravel().tolist()}))
    text = str(spec)
    if text in CAMERAS:
        return CAMERAS[text]
    if text.lower().endswith(".json") or os.sep in text or Path(text).exists():
        return record_of(Intrinsics.from_open3d_json(text))
    return camera_record(text)  # raises the "unknown preset" message
