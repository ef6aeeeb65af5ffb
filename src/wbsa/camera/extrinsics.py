"""Camera pose g = [R | T] (paper eq. 3) from azimuth, elevation and distance."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from wbsa.camera.views import View, view_direction


@dataclass(frozen=True)
class Pose:
    """A rigid transform g = [R | T]; for a camera pose it maps world to camera: x_cam = R · x_world + T.

    Attributes
    ----------
    R : (3, 3) float64
        Rotation; its rows are the camera's x (right), y (down) and z (forward) axes in world coordinates.
    T : (3,) float64
        Translation, ``T = −R · C`` for the camera centre C.
    """

    R: np.ndarray
    T: np.ndarray

    def __post_init__(self) -> None:
        R = np.array(self.R, dtype=np.float64).reshape(3, 3)
        T = np.array(self.T, dtype=np.float64).reshape(3)
        R.setflags(write=False)
        T.setflags(write=False)
        object.__setattr__(self, "R", R)
        object.__setattr__(self, "T", T)
        center = -R.T @ T
        center.setflags(write=False)
        object.__setattr__(self, "_center", center)

    @property
    def matrix(self) -> np.ndarray:
        """(4, 4) float64 homogeneous matrix [[R, T], [0, 1]]."""
        g = np.eye(4)
        g[:3, :3] = self.R
        g[:3, 3] = self.T
        return g

    def inverse(self) -> "Pose":
        """The inverse transform (camera to world for a camera pose): [Rᵀ | −Rᵀ T]."""
        return Pose(self.R.T, -self.R.T @ self.T)

    @property
    def camera_center(self) -> np.ndarray:
        """(3,) float64 camera centre in world coordinates, C = −Rᵀ T (read-only)."""
        return self._center

    def apply(self, points: np.ndarray) -> np.ndarray:
        """Transform points: ``R · p + T``.

        Parameters
        ----------
        points : (..., 3) float
            Points; NaN rows stay NaN.

        Returns
        -------
        (..., 3) same float dtype as ``points`` (float64 for integer input)
        """
        p = np.asarray(points)
        dtype = p.dtype if np.issubdtype(p.dtype, np.floating) else np.float64
        return (np.einsum("...j,kj->...k", p.astype(dtype, copy=False), self.R.astype(dtype))
                + self.T.astype(dtype)).astype(dtype, copy=False)

    def to_dict(self) -> dict:
        """JSON-ready description: R, T, the 4×4 matrices both ways and the camera centre."""
        return {
            "convention": "x_cam = R @ x_world + T; camera frame x right, y down, z forward (OpenCV)",
            "R": self.R.tolist(),
            "T": self.T.tolist(),
            "world_to_camera": self.matrix.tolist(),
            "camera_to_world": self.inverse().matrix.tolist(),
            "camera_center_m": self.camera_center.tolist(),
        }

    @classmethod
    def from_dict(cls, data: dict) -> "Pose":
        """Read the ``R`` and ``T`` written by :meth:`to_dict`.

        Parameters
        ----------
        data : dict
            ``{"R": 3x3 nested list, "T": 3 numbers}``.
        """
        return cls(np.asarray(data["R"], dtype=np.float64), np.asarray(data["T"], dtype=np.float64))


def look_at_rotation(azimuth_deg: float, elevation_deg: float) -> np.ndarray:
    """(3, 3) world-to-camera rotation of a camera at (θ, φ) looking at the subject's centre, without roll.

    The camera's x axis (image right) is the horizontal vector (cos θ, sin θ, 0), its z axis (forward)
    points from the camera to the subject, and y = z × x (image down). The image's up direction is the
    projection of world +Z; at φ = ±90°, where that projection vanishes, the same formula still holds and
    gives the limit of φ → ±90° at that azimuth: looking down from above at θ = 0 the image's up is +Y
    (towards the subject's back), the subject's left (+X) is on the image's right.

    Parameters
    ----------
    azimuth_deg, elevation_deg : float
        The camera's azimuth θ and elevation φ (degrees).
    """
    return _rotation(float(azimuth_deg), float(elevation_deg)).copy()


@lru_cache(maxsize=4096)
def _rotation(azimuth_deg: float, elevation_deg: float) -> np.ndarray:
    """Read-only :func:`look_at_rotation` (cached: a scan uses the same views for every body)."""
    th = math.radians(azimuth_deg)
    x_axis = np.array([math.cos(th), math.sin(th), 0.0])
    z_axis = -view_direction(azimuth_deg, elevation_deg)
    y_axis = np.cross(z_axis, x_axis)
    R = np.stack([x_axis, y_axis, z_axis])
    R.setflags(write=False)
    return R


def pose_from_view(view: View, target: np.ndarray) -> Pose:
    """World-to-camera pose of ``view`` aimed at ``target``.

    Parameters
    ----------
    view : View
        Azimuth, elevation and distance from ``target``.
    target : (3,) float
        The subject's centre (e.g. ``TriangleMesh.bbox_center``), metres.

    Returns
    -------
    Pose
        With camera centre ``target + D · (sin θ cos φ, −cos θ cos φ, sin φ)``.
    """
    target = np.asarray(target, dtype=np.float64).reshape(3)
    R = _rotation(view.azimuth_deg, view.elevation_deg)
    center = target - view.distance_m * R[2]  # R[2], the forward axis, points from the camera to the target
    return Pose(R, -R @ center)
