"""One rendered depth view: the contract between the camera, sensor and surface stages."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class DepthFrame:
    """Everything one ray-cast (or one simulated sensor read-out) gives per pixel.

    Pixels with no return have ``depth_m == 0``, ``triangle_id == -1`` and NaN points/normals.

    Attributes
    ----------
    depth_m : (h, w) float32
        z-depth along the optical axis (OpenCV convention, +Z forward), metres; 0 = no return.
    points_cam : (h, w, 3) float32
        Hit points in the camera frame (x right, y down, z forward), metres.
    normals_cam : (h, w, 3) float32
        Unit surface normals at the hits in the camera frame, facing the camera.
    triangle_id : (h, w) int64
        Index of the hit triangle in the mesh's face array; -1 = no return.
    intrinsics : wbsa.camera.intrinsics.Intrinsics
    pose : wbsa.camera.extrinsics.Pose
        World-to-camera transform g = [R | T] of this view.
    """

    depth_m: np.ndarray
    points_cam: np.ndarray
    normals_cam: np.ndarray
    triangle_id: np.ndarray
    intrinsics: object
    pose: object
    settings: dict = field(default_factory=dict)

    def __repr__(self) -> str:
        h, w = np.shape(self.depth_m)[:2]
        valid = self.depth_m > 0
        depth = (f", depth {self.depth_m[valid].min():.3f}–{self.depth_m[valid].max():.3f} m" if valid.any()
                 else "")
        name = getattr(self.intrinsics, "name", None)
        return (f"DepthFrame({w}×{h} px, {int(np.count_nonzero(valid)):,} returns{depth}"
                + (f", camera {name}" if name else "") + ")")

    @property
    def valid(self) -> np.ndarray:
        """(h, w) bool mask of pixels with a return."""
        return self.depth_m > 0

    @property
    def n_pixels(self) -> int:
        """Number of pixels with a return."""
        return int(np.count_nonzero(self.depth_m > 0))
