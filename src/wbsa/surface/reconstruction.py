"""Reconstruct the visible surface of one view from its depth image, and its area (``vbsa_recon_m2``)."""

from __future__ import annotations

import math

import numpy as np

from wbsa.core.frame import DepthFrame
from wbsa.errors import WbsaError
from wbsa.core.mesh import TriangleMesh
from wbsa.core.backproject import ray_directions
from wbsa.surface.denoise import denoise_depth
from wbsa.surface.grid import grid_mesh
from wbsa.surface.settings import ReconstructionSettings
from wbsa.typing import RECONSTRUCTION_METHODS


def reconstruct(frame: DepthFrame, method: str = "grid",
                settings: ReconstructionSettings | None = None) -> TriangleMesh:
    """Reconstruct the surface seen in one depth view.

    Only the depth image and the intrinsics are used (not the rendered points, normals or triangle
    IDs), so the same code runs on real depth images (:func:`wbsa.core.frame_from_depth_image`).

    Parameters
    ----------
    frame : DepthFrame
    method : {'grid', 'ball-pivoting', 'poisson'}
        ``grid``: organised-grid mesh with boundary skirt (fast, vectorised);
        ``ball-pivoting`` / ``poisson``: Open3D on the back-projected point cloud.
    settings : ReconstructionSettings, optional

    Returns
    -------
    TriangleMesh
        In the camera frame (OpenCV axes), metres.

    Raises
    ------
    WbsaError
        For an unknown method.
    """
    settings = settings or ReconstructionSettings()
    if method not in RECONSTRUCTION_METHODS:
        raise WbsaError(f"unknown reconstruction method {method!r}; use one of {', '.join(RECONSTRUCTION_METHODS)}")
    k = frame.intrinsics
    depth = denoise_depth(frame.depth_m, settings.denoise, sigma_px=settings.denoise_sigma_px,
                          sigma_depth_m=settings.denoise_sigma_depth_m)
    valid = depth > 0
    if not valid.any():
        return TriangleMesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int32))
    h, w = depth.shape
    rows = np.flatnonzero(valid.any(axis=1))
    cols = np.flatnonzero(valid.any(axis=0))
    # the returns plus a one-pixel ring (where the image has one): enough for the grid's edge tests
    r0, r1 = max(rows[0] - 1, 0), min(rows[-1] + 2, h)
    c0, c1 = max(cols[0] - 1, 0), min(cols[-1] + 2, w)
    sub = depth[r0:r1, c0:c1].astype(np.float64)
    sub_valid = sub > 0
    rays = ray_directions(k, np.arange(r0, r1)[:, None], np.arange(c0, c1)[None, :])
    points = rays * np.where(sub_valid, sub, np.nan)[..., None]
    focal = math.sqrt(float(k.fx) * float(k.fy))
    if method == "grid":
        # the ring lies inside the crop except where the image ends, which grid_mesh treats as off-image
        return grid_mesh(points, sub_valid, focal, max_angle_deg=settings.max_angle_deg,
                         boundary=settings.boundary, hole_max_px=settings.hole_max_px)
    from wbsa.surface.pointcloud import point_cloud_mesh

    spacing = float(np.median(sub[sub_valid])) / focal
    return point_cloud_mesh(points[sub_valid], method, spacing, settings)


def vbsa_recon_m2(frame: DepthFrame, method: str = "grid", settings: ReconstructionSettings | None = None) -> float:
    """Area (m²) of the surface reconstructed from one view: :func:`reconstruct` then the triangle-area sum."""
    return reconstruct(frame, method, settings).area_m2
