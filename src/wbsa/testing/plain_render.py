"""A second, plain depth renderer, independent of wbsa's scan engine and sensor models.

It checks that the estimator reads a body the same way whoever draws it: Open3D's ray casting of a mesh
through a pinhole, z-depth along the optical axis, i.i.d. axial Gaussian noise of its own
(σ = 1.2 mm + 1.9 mm·(z − 0.4 m)², about Kinect v1's level), depth rounded to whole millimetres, no edge
effects, no holes, no dropout, no range limits. It shares nothing with :mod:`wbsa.camera` or
:mod:`wbsa.sensor` but the numbers it is given (a camera's focal lengths and principal point, its centre and
rotation), so a disagreement between the two renderers lies in the project's renderer or in what the
estimator has learned of it.
"""

from __future__ import annotations

import numpy as np

#: The plain renderer's noise: σ(z) = A + B·(z − Z0)², metres.
NOISE_A_M, NOISE_B_PER_M, NOISE_Z0_M = 0.0012, 0.0019, 0.4


def plain_noise_sigma_m(z_m: np.ndarray) -> np.ndarray:
    """(…) float64: the plain renderer's axial noise σ (m) at depth ``z_m`` (m)."""
    z = np.asarray(z_m, dtype=np.float64)
    return NOISE_A_M + NOISE_B_PER_M * (z - NOISE_Z0_M) ** 2


def plain_depth(vertices: np.ndarray, faces: np.ndarray, *, width: int, height: int, fx: float, fy: float,
                cx: float, cy: float, rotation: np.ndarray, center_m: np.ndarray,
                rng: np.random.Generator | None) -> tuple[np.ndarray, np.ndarray]:
    """Ray-cast a mesh through a pinhole camera with Open3D, with the plain noise.

    Parameters
    ----------
    vertices : (n, 3) float64
        The scene, metres (world frame).
    faces : (m, 3) int
    width, height : int
        Image size, pixels.
    fx, fy, cx, cy : float
        Pinhole focal lengths and principal point, pixels (pixel centres at whole coordinates).
    rotation : (3, 3) float64
        World-to-camera rotation; its rows are the camera's x (right), y (down) and z (forward) axes.
    center_m : (3,) float64
        The camera centre in the world, metres.
    rng : numpy.random.Generator or None
        The noise's stream; None: no noise (depth still in whole millimetres).

    Returns
    -------
    depth_m : (height, width) float64
        z-depth in whole millimetres, 0 where the ray meets nothing.
    triangle_id : (height, width) int64
        The face each pixel sees, −1 where none.
    """
    import open3d as o3d

    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(np.asarray(vertices, dtype=np.float32)),
                        o3d.core.Tensor(np.asarray(faces, dtype=np.uint32)))
    v, u = np.mgrid[0:height, 0:width].astype(np.float64)
    d_cam = np.stack([(u - cx) / fx, (v - cy) / fy, np.ones_like(u)], axis=-1)  # z = 1: the hit distance is z
    d_world = d_cam @ np.asarray(rotation, dtype=np.float64)
    origin = np.broadcast_to(np.asarray(center_m, dtype=np.float64), d_world.shape)
    rays = o3d.core.Tensor(np.concatenate([origin, d_world], axis=-1).astype(np.float32))
    hit = scene.cast_rays(rays)
    z = hit["t_hit"].numpy().astype(np.float64)
    tri = hit["primitive_ids"].numpy().astype(np.int64)
    seen = np.isfinite(z)
    tri = np.where(seen, tri, -1)
    z = np.where(seen, z, 0.0)
    if rng is not None:
        z = np.where(seen, z + rng.standard_normal(z.shape) * plain_noise_sigma_m(z), 0.0)
    return np.round(z * 1000.0) / 1000.0, tri


def level_camera(subject_center_m: np.ndarray, to_camera: np.ndarray, distance_m: float,
                 height_m: float) -> tuple[np.ndarray, np.ndarray]:
    """A camera looking level (optical axis horizontal) at a standing subject from ``distance_m`` away.

    Parameters
    ----------
    subject_center_m : (3,) float64
        The subject's centre; the camera stands ``distance_m`` from it horizontally.
    to_camera : (3,) float64
        Horizontal direction from the subject towards the camera.
    distance_m, height_m : float
        Horizontal distance and the camera's height over the floor (z = 0).

    Returns
    -------
    rotation : (3, 3) float64
        World-to-camera rotation (rows: right, down, forward).
    center_m : (3,) float64
    """
    t = np.asarray(to_camera, dtype=np.float64) * np.array([1.0, 1.0, 0.0])
    t /= np.linalg.norm(t)
    forward = -t
    down = np.array([0.0, 0.0, -1.0])
    right = np.cross(down, forward)
    center = np.asarray(subject_center_m, dtype=np.float64) * np.array([1.0, 1.0, 0.0]) + distance_m * t
    center[2] = height_m
    return np.stack([right, down, forward]), center
