"""Depth noise of each depth-camera technology: one table of constants, one formula for numpy and torch.

How a camera measures depth (its record's ``technology``, :data:`wbsa.camera.presets.CAMERAS`) sets its noise.
θ is the angle between surface normal and viewing ray, z the depth (m), f the focal length (px), and
(b, s) the baseline (m) and disparity step (px) of a camera that measures disparity.

- axial σz(z, θ) = a + g·(z − z0)² [+ z²·s/(f·b)] m for θ ≤ 60°, plus k/√z · θ²/(π/2 − θ)² m above 60°;
- lateral σL(θ) = l0 + l1·θ/(π/2 − θ) pixels;
- quantisation (a camera with a disparity): depth in steps of z²·s/(f·b) m;
- grazing dropout: returns within ``grazing_dropout_deg`` of grazing are lost.

The constants (:data:`TECHNOLOGIES`, sources in docs/references.md):

- structured light, Kinect v1 (Nguyen, Izadi & Lovell 2012): a = 0.0012 m, g = 0.0019 m⁻¹, z0 = 0.4 m,
  k = 0.0001 m^1.5, l0 = 0.8 px, l1 = 0.035 px, dropout 8°; disparity b = 0.075 m, s = 1/8 px
  (Khoshelham & Elberink 2012, on the camera record);
- active stereo, RealSense D400: σz = z²·s/(f·b), Intel's depth RMS error relation, with s the camera record's
  subpixel disparity (1/12 px, Intel's D400 datasheet); its angle, lateral and dropout terms are Kinect v1's
  (a stand-in: no figure for them is checked in this repository);
- time of flight (Kinect v2, Azure Kinect) and phone LiDAR: **stand-ins**, Kinect v1's model without its
  disparity (what every camera was given before); no published characterisation of these cameras is checked
  in this repository (docs/sensor_and_surface.md says which papers to read).

Every function takes numpy arrays (computed in float64) or torch tensors (computed in their own dtype and
differentiable) and returns the same kind, from the same expression. numpy is imported when first needed, so
that the sensor's settings stay cheap to import for the command line.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass, replace

from wbsa.errors import WbsaError
from wbsa.typing import DEPTH_TECHNOLOGIES, DepthTechnology


@dataclass(frozen=True)
class TechnologyNoise:
    """The noise constants of one depth technology (see the module doc for the formulas).

    Attributes
    ----------
    technology : {'structured-light', 'time-of-flight', 'active-stereo', 'lidar'}
    axial_m, axial_growth_per_m, axial_offset_m : float
        a, g and z0 of the axial σz = a + g·(z − z0)² (metres, 1/metres, metres).
    disparity_rms : bool
        Whether σz also holds z²·s/(f·b), the depth error of an RMS disparity error of s pixels (stereo).
    grazing_m : float
        k of the grazing term k/√z · θ²/(π/2 − θ)² (m^1.5), added above ``grazing_knee_deg``.
    grazing_knee_deg : float
        Angle between normal and ray above which the grazing term is added (degrees).
    lateral_px, lateral_grazing_px : float
        l0 and l1 of the lateral σL = l0 + l1·θ/(π/2 − θ) (pixels).
    grazing_dropout_deg : float
        Returns within this many degrees of grazing are lost.
    source : str
        Where the figures come from (docs/references.md).
    stand_in : str
        Which figures are stand-ins, not published for this technology ('' when none).
    """

    technology: DepthTechnology
    axial_m: float
    axial_growth_per_m: float
    axial_offset_m: float
    disparity_rms: bool
    grazing_m: float
    grazing_knee_deg: float
    lateral_px: float
    lateral_grazing_px: float
    grazing_dropout_deg: float
    source: str
    stand_in: str = ""


_KINECT_V1 = TechnologyNoise(
    "structured-light", axial_m=0.0012, axial_growth_per_m=0.0019, axial_offset_m=0.4, disparity_rms=False,
    grazing_m=0.0001, grazing_knee_deg=60.0, lateral_px=0.8, lateral_grazing_px=0.035, grazing_dropout_deg=8.0,
    source="Nguyen, Izadi & Lovell 2012 (Kinect v1); disparity: Khoshelham & Elberink 2012")
_NO_SOURCE = ("stand-in: Kinect v1's model (Nguyen et al. 2012) without its disparity; no published "
              "characterisation of this technology is checked in this repository")

#: The noise constants of every depth technology, one record each (the order of DepthTechnology).
TECHNOLOGIES: dict[str, TechnologyNoise] = {t.technology: t for t in (
    _KINECT_V1,
    replace(_KINECT_V1, technology="time-of-flight", source="none checked (Kinect v2, Azure Kinect)",
            stand_in=_NO_SOURCE),
    replace(_KINECT_V1, technology="active-stereo", axial_m=0.0, axial_growth_per_m=0.0, axial_offset_m=0.0,
            disparity_rms=True,
            source="Intel D400 depth RMS error = z²·subpixel/(f·baseline) (Grunnet-Jepsen et al.); subpixel: "
                   "the camera record's (Intel D400 datasheet)",
            stand_in="stand-ins: the grazing term, lateral σ and grazing dropout are Kinect v1's (Nguyen et al. 2012)"),
    replace(_KINECT_V1, technology="lidar", source="none checked (iPad Pro / iPhone LiDAR)", stand_in=_NO_SOURCE),
)}
assert tuple(TECHNOLOGIES) == DEPTH_TECHNOLOGIES, "one noise record per wbsa.typing.DepthTechnology, in its order"


@dataclass(frozen=True)
class SensorModel:
    """A technology's noise on one camera: its constants and the camera's depth step per z².

    Attributes
    ----------
    noise : TechnologyNoise
    depth_step_per_m : float
        s/(f·b) in 1/m: the depth step (and, with ``noise.disparity_rms``, the RMS depth error) at depth z
        is ``depth_step_per_m · z²``; 0 for a camera without a disparity.
    """

    noise: TechnologyNoise
    depth_step_per_m: float = 0.0

    @property
    def quantised(self) -> bool:
        """Whether the camera measures depth in disparity steps."""
        return self.depth_step_per_m > 0.0


def sensor_model(technology: DepthTechnology, fx_px: float | None = None,
                 disparity: tuple[float, float] | None = None) -> SensorModel:
    """The noise model of a technology on a camera of focal length ``fx_px`` and disparity ``disparity``.

    Parameters
    ----------
    technology : {'structured-light', 'time-of-flight', 'active-stereo', 'lidar'}
    fx_px : float, optional
        Focal length in pixels; needed with a disparity.
    disparity : (float, float), optional
        Baseline (m) and disparity step (px) of a structured-light or stereo camera.

    Returns
    -------
    SensorModel

    Raises
    ------
    WbsaError
        An unknown technology, or a disparity without a focal length.
    """
    if technology not in TECHNOLOGIES:
        raise WbsaError(f"depth technology {technology!r} is unknown; use one of {', '.join(TECHNOLOGIES)}")
    if disparity is None:
        return SensorModel(TECHNOLOGIES[technology])
    if fx_px is None:
        raise WbsaError("a camera's disparity needs its focal length (fx_px)")
    baseline_m, step_px = (float(v) for v in disparity)
    return SensorModel(TECHNOLOGIES[technology], step_px / (float(fx_px) * baseline_m))


def camera_model(camera) -> SensorModel:
    """The noise model of a camera record (its technology, focal length and disparity).

    Parameters
    ----------
    camera : wbsa.camera.presets.CameraRecord or str
        A record, or the name of a preset.

    Returns
    -------
    SensorModel
    """
    from wbsa.camera.presets import camera_record

    record = camera_record(camera) if isinstance(camera, str) else camera
    return sensor_model(record.technology, record.intrinsics.fx, record.disparity)


def preset_record(camera):
    """The preset record whose intrinsics ``camera`` is, or None (a custom camera).

    Parameters
    ----------
    camera : wbsa.camera.Intrinsics

    Returns
    -------
    wbsa.camera.presets.CameraRecord or None
    """
    from wbsa.camera.presets import CAMERAS

    record = CAMERAS.get(getattr(camera, "name", None))
    return record if record is not None and record.intrinsics == camera else None


def envelope_model(camera) -> SensorModel:
    """The model whose :func:`envelope_m` the estimator assumes for a depth image of ``camera``: the camera's
    own (:func:`camera_model` of its record), or Kinect v1's for a camera whose technology is unknown (one of the
    user's own calibration, or None).

    Parameters
    ----------
    camera : wbsa.camera.presets.CameraRecord, wbsa.camera.Intrinsics or None
        A record (as :func:`wbsa.camera.presets.resolve_record` gives it), or intrinsics: a preset's if they are
        one's (:func:`wbsa.camera.presets.record_of`).

    Returns
    -------
    SensorModel
    """
    from wbsa.camera.presets import CameraRecord, record_of

    record = None
    if isinstance(camera, CameraRecord):
        record = camera
    elif camera is not None:
        record = record_of(camera)
    return camera_model(record) if record is not None and record.technology is not None else unknown_camera_model()


def unknown_camera_model() -> SensorModel:
    """The model assumed for a camera whose technology is unknown: Kinect v1's (:func:`camera_model`)."""
    return camera_model("kinect-v1")


def _namespace(*xs):
    """(module, arrays): torch and the tensors as given if any is a tensor, else numpy and float64 arrays."""
    import numpy as np

    if any(type(x).__module__.split(".")[0] == "torch" for x in xs):
        import torch

        return torch, tuple(x if isinstance(x, torch.Tensor) else torch.as_tensor(x) for x in xs)
    return np, tuple(np.asarray(x, dtype=np.float64) for x in xs)


def _np():
    """numpy (imported when first needed)."""
    import numpy as np

    return np


def _quiet(xp):
    """numpy's divide-by-zero warnings off (σ is inf at grazing by design); nothing for torch."""
    import numpy as np

    return np.errstate(divide="ignore", invalid="ignore") if xp is np else contextlib.nullcontext()


def _face_on(model: SensorModel, z):
    """σz at θ = 0 (below the grazing knee), same kind as ``z``."""
    n = model.noise
    base = n.axial_m + n.axial_growth_per_m * (z - n.axial_offset_m) ** 2
    if n.disparity_rms:
        base = base + model.depth_step_per_m * z**2
    return base


def axial_sigma_m(model: SensorModel, depth_m, theta_rad):
    """Standard deviation of the depth error along the optical axis.

    Parameters
    ----------
    model : SensorModel
    depth_m : (...) float array or tensor
        z-depth in metres (> 0).
    theta_rad : (...) float array or tensor
        Angle between surface normal and viewing ray, radians in [0, π/2).

    Returns
    -------
    (...) float64 array, or a tensor of the inputs' dtype
        σz in metres; ``inf`` at θ = π/2.
    """
    xp, (z, theta) = _namespace(depth_m, theta_rad)
    n = model.noise
    base = _face_on(model, z)
    with _quiet(xp):
        steep = n.grazing_m / xp.sqrt(z) * theta**2 / (math.pi / 2 - theta) ** 2
    return xp.where(theta > math.radians(n.grazing_knee_deg), base + steep, base)


def lateral_sigma_px(model: SensorModel, theta_rad):
    """Standard deviation of the lateral (in-image) position error, in pixels.

    Parameters
    ----------
    model : SensorModel
    theta_rad : (...) float array or tensor
        Angle between surface normal and viewing ray, radians in [0, π/2).

    Returns
    -------
    (...) float64 array, or a tensor of the input's dtype
        σL in pixels (independent of depth); ``inf`` at θ = π/2.
    """
    xp, (theta,) = _namespace(theta_rad)
    n = model.noise
    with _quiet(xp):
        return n.lateral_px + n.lateral_grazing_px * theta / (math.pi / 2 - theta)


def envelope_m(model: SensorModel, depth_m):
    """Standard deviation of a face-on depth reading: axial σz(z, 0) and the quantisation's step/√12.

    Parameters
    ----------
    model : SensorModel
    depth_m : (...) float array or tensor
        z-depth in metres.

    Returns
    -------
    (...) float64 array, or a tensor of the input's dtype
        σ in metres.
    """
    xp, (z,) = _namespace(depth_m)
    axial = _face_on(model, z)
    # one quantity, (s z² / (f b))² / 12, in two orders that agree to rounding (tested): each keeps the bits
    # the estimator's planes (numpy) and the body fit (torch, float32) were tuned and calibrated with
    if xp is _np():
        quant2 = (model.depth_step_per_m * z * z / math.sqrt(12.0)) ** 2
    else:
        quant2 = (model.depth_step_per_m * z.square()).square() / 12.0
    return xp.sqrt(axial**2 + quant2)
