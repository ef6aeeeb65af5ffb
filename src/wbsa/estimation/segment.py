"""Isolate the subject in a real depth image: range gate, large planes, largest region."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wbsa.errors import WbsaError


@dataclass(frozen=True)
class SegmentSettings:
    """How the subject is told apart from the room.

    Attributes
    ----------
    min_depth_m, max_depth_m : float
        Returns outside this z-range are background.
    max_planes : int
        Up to this many large planes (floor, wall) are removed by RANSAC.
    plane_threshold_m : float
        RANSAC inlier distance.
    plane_min_extent_m : float
        A plane is background only if its inliers span at least this much along two in-plane axes:
        a floor or a wall is larger than any flat patch of a body (a torso is < 0.6 m wide).
    """

    min_depth_m: float = 0.4
    max_depth_m: float = 8.0
    max_planes: int = 2
    plane_threshold_m: float = 0.02
    plane_min_extent_m: float = 1.0

    def __post_init__(self) -> None:
        if not 0 <= self.min_depth_m < self.max_depth_m:
            raise WbsaError(f"depth range {self.min_depth_m}–{self.max_depth_m} m is empty; "
                            "give --min-depth below --max-depth")


def segment_subject(depth_m: np.ndarray, intrinsics, settings: SegmentSettings = SegmentSettings(),
                    seed: int = 0) -> np.ndarray:
    """Mask of the subject's pixels in a depth image.

    Parameters
    ----------
    depth_m : (h, w) float
        z-depth in metres, 0 = no return.
    intrinsics : wbsa.camera.Intrinsics
    settings : SegmentSettings
    seed : int
        Seed of the RANSAC plane search (the result is deterministic for a seed).

    Returns
    -------
    (h, w) bool
        The largest 8-connected region left after the range gate and plane removal.
    """
    import open3d as o3d
    from scipy import ndimage

    from wbsa.core.backproject import backproject_depth

    depth = np.asarray(depth_m, dtype=np.float64)
    mask = np.isfinite(depth) & (depth >= settings.min_depth_m) & (depth <= settings.max_depth_m) & (depth > 0)
    if not mask.any():
        return mask
    points = backproject_depth(np.where(mask, depth, 0.0), intrinsics)
    o3d.utility.random.seed(seed)
    for _ in range(settings.max_planes):
        idx = np.flatnonzero(mask.ravel())
        if len(idx) < 100:
            break
        cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points.reshape(-1, 3)[idx].astype(np.float64)))
        _, inliers = cloud.segment_plane(settings.plane_threshold_m, 3, 500)
        inliers = np.asarray(inliers)
        if len(inliers) < 100 or not _is_large(points.reshape(-1, 3)[idx[inliers]], settings.plane_min_extent_m):
            break
        flat = mask.ravel().copy()
        flat[idx[inliers]] = False
        mask = flat.reshape(mask.shape)
    labels, n = ndimage.label(mask, structure=np.ones((3, 3), bool))
    if n == 0:
        return mask
    sizes = np.bincount(labels.ravel())[1:]
    return labels == (1 + int(np.argmax(sizes)))


def _is_large(points: np.ndarray, min_extent_m: float) -> bool:
    """Whether planar ``points`` (k, 3) span ``min_extent_m`` along their two main axes."""
    centred = points - points.mean(axis=0)
    _, _, axes = np.linalg.svd(centred[:: max(1, len(centred) // 5000)], full_matrices=False)
    extents = [np.ptp(centred @ axes[i]) for i in range(2)]
    return min(extents) >= min_extent_m
