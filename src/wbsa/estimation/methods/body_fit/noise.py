"""The depth noise the body fit expects of a camera: axial σz(z, θ) and the disparity quantisation step.

One small adapter between the fit and the sensor model of :mod:`wbsa.sensor`: the fit weighs each observed
depth by the σz of the camera's technology and widens it by the quantisation step where the camera measures
disparity (its record's ``disparity``, :data:`wbsa.camera.presets.CAMERAS`). No noise constant lives here.
A camera that is not a preset (an intrinsics file) is read as a structured-light camera without quantisation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class DepthNoise:
    """σz(z, θ) and the depth step of one camera (numpy, float64; the fit evaluates them on detached values).

    Attributes
    ----------
    camera : str
        The preset's name ('' for a camera given by its intrinsics).
    depth_step_per_m : float
        s/(f·b) in 1/m: a camera that measures disparity returns depth in steps of ``depth_step_per_m · z²``
        (0: not quantised).
    """

    camera: str
    depth_step_per_m: float = 0.0

    def axial_sigma_m(self, depth_m: np.ndarray, theta_rad: np.ndarray) -> np.ndarray:
        """(...) float64 σz (m) at z-depth ``depth_m (...)`` and angle ``theta_rad (...)`` between normal and ray."""
        from wbsa.sensor import nguyen2012

        return nguyen2012.axial_sigma_m(depth_m, theta_rad)

    def step_m(self, depth_m: np.ndarray) -> np.ndarray:
        """(...) float64 quantisation step (m) of the depth at ``depth_m (...)``; 0 without quantisation."""
        z = np.asarray(depth_m, dtype=np.float64)
        return self.depth_step_per_m * z * z

    def sigma_m(self, depth_m: np.ndarray, theta_rad: np.ndarray) -> np.ndarray:
        """(...) float64 σ of a reading: σz(z, θ) widened by the quantisation, √(σz² + step²/12)."""
        return np.sqrt(self.axial_sigma_m(depth_m, theta_rad) ** 2 + self.step_m(depth_m) ** 2 / 12.0)

    def envelope_m(self, depth_m: np.ndarray) -> np.ndarray:
        """(...) float64 σ of a face-on reading (θ = 0), quantisation included."""
        return self.sigma_m(depth_m, np.zeros_like(np.asarray(depth_m, dtype=np.float64)))


def camera_noise(camera) -> DepthNoise:
    """The :class:`DepthNoise` of a camera (:class:`wbsa.camera.Intrinsics` of a preset, or any intrinsics).

    Parameters
    ----------
    camera : wbsa.camera.Intrinsics

    Returns
    -------
    DepthNoise
    """
    from wbsa.camera.presets import CAMERAS

    name = str(getattr(camera, "name", "") or "")
    record = CAMERAS.get(name)
    if record is None or record.disparity is None:
        return DepthNoise(name if record is not None else "")
    baseline_m, step_px = record.disparity
    fx = float(camera.fx)
    if not (math.isfinite(fx) and fx > 0):
        return DepthNoise(name)
    return DepthNoise(name, float(step_px) / (fx * float(baseline_m)))
