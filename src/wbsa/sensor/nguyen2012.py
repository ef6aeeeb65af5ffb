"""Kinect v1 depth noise as measured by Nguyen, Izadi & Lovell (3DIMPVT 2012): the structured-light record of
:data:`wbsa.sensor.technology.TECHNOLOGIES`, as functions of depth and angle alone.

θ is the angle between the surface normal and the viewing ray; z is the depth in metres.

- axial: σz(z, θ) = 0.0012 + 0.0019 (z − 0.4)² m for θ ≤ 60°,
  plus 0.0001/√z · θ²/(π/2 − θ)² m above 60°;
- lateral: σL(θ) = 0.8 + 0.035 θ/(π/2 − θ) pixels, i.e. σL · z / fx metres.

Both diverge at grazing incidence; implementations drop returns within about 8° of grazing
(:attr:`wbsa.sensor.SensorSettings.grazing_dropout_deg`).
"""

from __future__ import annotations

import numpy as np

from wbsa.sensor import technology

#: The model (structured light; no disparity term: Nguyen's σz was measured with the quantisation in it).
MODEL = technology.SensorModel(technology.TECHNOLOGIES["structured-light"])


def axial_sigma_m(depth_m: np.ndarray | float, theta_rad: np.ndarray | float) -> np.ndarray:
    """Standard deviation of the depth error along the optical axis.

    Parameters
    ----------
    depth_m : (...) float
        z-depth in metres (> 0).
    theta_rad : (...) float
        Angle between surface normal and viewing ray, radians in [0, π/2).

    Returns
    -------
    (...) float64
        σz in metres; ``inf`` at θ = π/2.
    """
    return technology.axial_sigma_m(MODEL, depth_m, theta_rad)


def lateral_sigma_px(theta_rad: np.ndarray | float) -> np.ndarray:
    """Standard deviation of the lateral (in-image) position error, in pixels.

    Parameters
    ----------
    theta_rad : (...) float
        Angle between surface normal and viewing ray, radians in [0, π/2).

    Returns
    -------
    (...) float64
        σL in pixels (independent of depth); ``inf`` at θ = π/2.
    """
    return technology.lateral_sigma_px(MODEL, theta_rad)


def lateral_sigma_m(depth_m: np.ndarray | float, theta_rad: np.ndarray | float, fx: float) -> np.ndarray:
    """Lateral σL in metres at depth ``depth_m``: σL[px] · z / fx.

    Parameters
    ----------
    depth_m : (...) float
        z-depth in metres.
    theta_rad : (...) float
        Angle between surface normal and viewing ray, radians.
    fx : float
        Focal length in pixels.

    Returns
    -------
    (...) float64
        σL in metres.
    """
    return lateral_sigma_px(theta_rad) * np.asarray(depth_m, dtype=np.float64) / fx
