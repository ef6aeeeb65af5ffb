"""Settings of the simulated depth sensor (``[sensor]`` of a study): which non-ideal effects to apply."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from wbsa.errors import check_field
from wbsa.sensor.technology import TECHNOLOGIES, SensorModel, preset_record, sensor_model
from wbsa.typing import DEPTH_TECHNOLOGIES, NOISE_MODELS, DepthTechnology, NoiseModel
from wbsa.settings_io import check_types

#: Returns closer than this to grazing are dropped by default when Nguyen noise is on: its σ diverges at grazing,
#: and implementations of the model drop them (Nguyen et al. 2012; docs/references.md).
NGUYEN_GRAZING_DROPOUT_DEG = TECHNOLOGIES["structured-light"].grazing_dropout_deg
#: Kinect v1 projector–camera baseline (metres) and disparity resolution (pixels): its camera record's
#: (``wbsa.camera.presets.CAMERAS["kinect-v1"].disparity``, tested equal; not imported, to keep the CLI cheap).
KINECT_V1_BASELINE_M = 0.075
KINECT_V1_DISPARITY_STEP_PX = 1.0 / 8.0


@dataclass(frozen=True)
class SensorSettings:
    """What a simulated depth sensor does to an ideal ray-cast frame. Every effect is optional.

    With the defaults the sensor is ideal and :func:`~wbsa.sensor.apply_sensor` returns the frame's
    pixels unchanged. Effects are applied in a fixed order (see :func:`~wbsa.sensor.apply_sensor`),
    each from its own random stream, so switching one on does not change the draws of another.

    Attributes
    ----------
    noise : {'none', 'nguyen2012', 'camera'}
        Depth noise: ``nguyen2012`` = Nguyen et al. 2012 Kinect v1 axial σz(z, θ) and lateral σL(θ), whatever
        the camera (the paper's); ``camera`` = the model of the camera's own technology
        (:data:`wbsa.sensor.technology.TECHNOLOGIES`): ``technology``, or the camera preset's.
    lateral_noise : bool
        With a noise model: also move each pixel's sample point by the lateral σL.
    noise_scale : float
        With a noise model: multiply σz and σL by this (1 = the model's own level).
    quantise : bool
        Quantise disparity f·b/z to ``disparity_step_px`` (structured light and stereo). With
        ``noise='camera'`` and no ``technology``, the preset's own baseline and step (none: no quantisation).
    baseline_m, disparity_step_px : float
        Projector–camera baseline and disparity resolution used by ``quantise`` (and, with
        ``technology='active-stereo'``, by its depth RMS error).
    technology : {'structured-light', 'time-of-flight', 'active-stereo', 'lidar'} or None
        With ``noise='camera'``: the technology whose model is used; None = the camera preset's own (a
        camera without a preset record then needs one).
    holes_fraction : float
        The paper's holes: this fraction of the visible triangles is dropped with all their pixels.
    pixel_dropout : float
        Probability that any returned pixel is lost (independent per pixel).
    grazing_dropout_deg : float or None
        Drop returns whose angle between surface normal and ray is within this many degrees of 90°.
        None: the noise model's (8° for Nguyen's, whose σ diverges at grazing), 0 (off) without one.
    range_limits : bool
        Drop returns outside the camera's ``[min_range_m, max_range_m]`` depth range.
    """

    noise: NoiseModel = "none"
    lateral_noise: bool = True
    noise_scale: float = 1.0
    quantise: bool = False
    baseline_m: float = KINECT_V1_BASELINE_M
    disparity_step_px: float = KINECT_V1_DISPARITY_STEP_PX
    holes_fraction: float = 0.0
    pixel_dropout: float = 0.0
    grazing_dropout_deg: float | None = None
    range_limits: bool = False
    technology: DepthTechnology | None = None

    def __post_init__(self) -> None:
        check_types(self)
        check_field(self.noise in NOISE_MODELS, "noise", f"must be one of {', '.join(NOISE_MODELS)}, got {self.noise!r}")
        for name in ("holes_fraction", "pixel_dropout"):
            value = getattr(self, name)
            check_field(0.0 <= value <= 1.0, name, f"must be a fraction in [0, 1], got {value:g}")
        check_field(self.grazing_dropout_deg is None or 0.0 <= self.grazing_dropout_deg < 90.0, "grazing_dropout_deg",
                    f"must be degrees in [0, 90) (or left out: the noise model's default), got {self.grazing_dropout_deg}")
        check_field(0.0 <= self.noise_scale <= 10.0, "noise_scale",
                    f"must be a factor on the noise model's sigma in [0, 10], got {self.noise_scale:g}")
        check_field(self.baseline_m > 0 and math.isfinite(self.baseline_m), "baseline_m",
                    f"must be positive metres, got {self.baseline_m}")
        check_field(self.disparity_step_px > 0 and math.isfinite(self.disparity_step_px), "disparity_step_px",
                    f"must be positive pixels, got {self.disparity_step_px}")
        check_field(self.technology is None or self.technology in DEPTH_TECHNOLOGIES, "technology",
                    f"must be one of {', '.join(DEPTH_TECHNOLOGIES)}, got {self.technology!r}")
        check_field(self.technology is None or self.noise == "camera", "technology",
                    f"selects the model of noise 'camera'; with noise {self.noise!r} leave it out")

    def check_camera(self, camera) -> None:
        """Check that ``camera`` suits these settings: ``range_limits`` needs a finite working range, noise
        ``camera`` without a ``technology`` a camera preset.

        Parameters
        ----------
        camera : wbsa.camera.Intrinsics

        Raises
        ------
        SettingsError
            ``range_limits`` with a camera that has no working range; noise ``camera`` of a camera without
            a preset record and no ``technology``.
        """
        if self.noise == "camera" and self.technology is None:
            check_field(preset_record(camera) is not None, "noise",
                        f"'camera' needs a camera preset to know its technology; camera "
                        f"{getattr(camera, 'name', 'custom')} is none (use a preset, or noise 'nguyen2012')")
        if self.range_limits:
            lo, hi = float(getattr(camera, "min_range_m", 0.0)), float(getattr(camera, "max_range_m", math.inf))
            check_field(lo > 0.0 or hi != math.inf, "range_limits",
                        f"needs a camera with a working range; camera {getattr(camera, 'name', 'custom')} has none "
                        "(set min_range_m/max_range_m in its JSON or use a preset)")

    @property
    def effective_grazing_dropout_deg(self) -> float | None:
        """The grazing dropout actually applied (resolves None, see the class doc); None when it is the
        camera preset's technology's, known only with the camera (:meth:`model_for`)."""
        if self.grazing_dropout_deg is not None:
            return float(self.grazing_dropout_deg)
        if self.noise == "nguyen2012":
            return NGUYEN_GRAZING_DROPOUT_DEG
        if self.noise == "camera":
            return TECHNOLOGIES[self.technology].grazing_dropout_deg if self.technology else None
        return 0.0

    def model_for(self, camera) -> tuple[SensorModel | None, tuple[float, float] | None]:
        """The noise model these settings give ``camera``, and the disparity its ``quantise`` uses.

        Parameters
        ----------
        camera : wbsa.camera.Intrinsics
            The frame's camera (a preset's intrinsics, for noise ``camera`` without ``technology``).

        Returns
        -------
        SensorModel or None, (float, float) or None
            The model (None without noise) and the (baseline m, step px) of the quantisation (None: the
            camera has no disparity).

        Raises
        ------
        SettingsError
            Noise ``camera`` without ``technology`` on a camera that is no preset.
        """
        disparity = (self.baseline_m, self.disparity_step_px)
        if self.noise == "none":
            return None, disparity
        if self.noise == "nguyen2012":
            from wbsa.sensor.nguyen2012 import MODEL

            return MODEL, disparity
        fx = float(camera.fx)
        if self.technology is not None:
            has_disparity = self.technology in ("structured-light", "active-stereo")
            disparity = disparity if has_disparity else None
            return sensor_model(self.technology, fx, disparity), disparity
        self.check_camera(camera)
        record = preset_record(camera)
        return sensor_model(record.technology, fx, record.disparity), record.disparity

    @property
    def effective_noise_scale(self) -> float:
        """The factor on the noise model's σ actually applied (0 without a noise model)."""
        return float(self.noise_scale) if self.noise != "none" else 0.0

    @property
    def is_ideal(self) -> bool:
        """True when the sensor changes nothing."""
        return (self.noise == "none" and not self.quantise and self.holes_fraction == 0.0
                and self.pixel_dropout == 0.0 and self.effective_grazing_dropout_deg == 0.0
                and not self.range_limits)

    def to_dict(self) -> dict:
        """Plain settings for recording in outputs (the grazing dropout resolved).

        ``noise_scale`` is recorded only when it is not 1 and ``technology`` only when set, so that tables
        and study fingerprints written before they existed still read the same.
        """
        d = asdict(self)
        d["grazing_dropout_deg"] = self.effective_grazing_dropout_deg
        if d["noise_scale"] == 1.0:
            del d["noise_scale"]
        if d["technology"] is None:
            del d["technology"]
        return d

