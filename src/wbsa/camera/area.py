"""Visible skin area of one view, two ways (docs/camera.md explains why they differ).

``vbsa_hit_m2``
    The paper's method (section 2.4): the summed area of the unique triangles hit by at least one ray.
    A triangle counts whole when any part of it is hit, and not at all when it falls between rays, so the
    result depends on the ratio of triangle size to pixel footprint (at Kinect v1 resolution and 4.3 m
    it misses about a third of a body's visible skin).
``vbsa_visible_m2``
    A resolution-independent estimate of the area truly visible. Each hit pixel adds the area of its
    footprint on the surface: a pixel at off-axis angle α spans the solid angle ``cos³α / (fx·fy)``; at
    range ``r = z / cos α`` on a surface whose normal makes the angle θ with the ray that is
    ``cos³α / (fx·fy) · r² / cos θ = z² · cos α / (fx · fy · cos θ)``.
    Near a silhouette 1/cos θ diverges: a pixel centre that lands just inside the limb counts a huge
    area and the pixels just outside count none, so point sampling of that band is unbiased only on
    average and in practice falls short by 1–5 % (more for small or thin objects). Given the scene, the
    band of grazing triangles (cos θ < ``GRAZING_COS`` seen from the camera) is therefore measured in
    object space instead: each such front-facing triangle whose centroid lies in the image and is not
    occluded (one ray to the centroid) counts whole, and pixels that hit a grazing triangle add nothing.
"""

from __future__ import annotations

import math

import numpy as np

from wbsa.camera.extrinsics import Pose
from wbsa.camera.frame import DepthFrame
from wbsa.camera.intrinsics import Intrinsics, pixel_rays

#: Triangles seen at cos θ below this (θ > 72.5°) are measured in object space, not by pixel footprints.
GRAZING_COS = 0.3
#: Lower clip of cos θ in a pixel footprint (θ ≤ 88.85°), a guard against near-tangent hits; clipping at
#: c removes about c/2 of a smooth convex cap, so it matters only in the frame-only estimate.
FOOTPRINT_COS_MIN = 0.02
#: A grazing triangle is visible when nothing lies on the ray to its centroid before this fraction of the way.
_CENTROID_T_TOL = 1e-4


def pixel_footprint_m2(z_m: np.ndarray, n_dot_d: np.ndarray, d_dot_d: np.ndarray, intrinsics: Intrinsics,
                       cos_min: float = FOOTPRINT_COS_MIN) -> np.ndarray:
    """Surface area seen by each pixel, ``z² · cos α / (fx · fy · max(cos θ, cos_min))``.

    Parameters
    ----------
    z_m : (k,) float
        z-depth of the hit (m).
    n_dot_d : (k,) float
        ``|n · d|`` with n the unit surface normal and d the pixel's ray ``K^-1 [u, v, 1]`` (unit z).
    d_dot_d : (k,) float
        ``|d|² = 1 / cos² α``.
    intrinsics : Intrinsics
    cos_min : float
        Lower clip of cos θ.

    Returns
    -------
    (k,) float64
    """
    z = np.asarray(z_m, dtype=np.float64)
    cos_alpha = 1.0 / np.sqrt(np.asarray(d_dot_d, dtype=np.float64))
    cos_theta = np.maximum(np.asarray(n_dot_d, dtype=np.float64) * cos_alpha, cos_min)
    return z * z * cos_alpha / ((intrinsics.fx * intrinsics.fy) * cos_theta)


def hit_area_m2(triangle_ids: np.ndarray, triangle_areas: np.ndarray) -> float:
    """Summed area of the unique triangles among ``triangle_ids`` (k,) int; ids < 0 are ignored."""
    return float(np.einsum("i,i->", triangle_areas, hit_mask(triangle_ids, triangle_areas.shape[0])))


def hit_mask(triangle_ids: np.ndarray, n_triangles: int) -> np.ndarray:
    """(m,) float64 indicator (0/1) of the triangles hit at least once; ids < 0 are ignored.

    A float mask, so that sums over it are cheap dot products (numpy's bool matmul is a slow loop).
    """
    ids = np.asarray(triangle_ids)
    if ids.size and ids.dtype.kind == "i":
        ids = ids[ids >= 0]
    seen = np.zeros(n_triangles, dtype=np.float64)
    seen[ids] = 1.0
    return seen


def triangle_view_cosines(scene, camera_center: np.ndarray) -> np.ndarray:
    """(m,) float32 cosine between each face normal and the direction from its centroid to the camera.

    Positive for triangles that face the camera, negative for back faces (normals made outward for a
    one-sided scene, by vertex order otherwise).
    """
    C = np.asarray(camera_center, dtype=np.float64) - scene.center
    nx, ny, nz, cx, cy, cz, n_dot_c, c_sq = scene._soa
    dot = nx * np.float32(C[0])
    dot += ny * np.float32(C[1])
    dot += nz * np.float32(C[2])
    dot -= n_dot_c
    dist = cx * np.float32(-2.0 * C[0])
    dist += cy * np.float32(-2.0 * C[1])
    dist += cz * np.float32(-2.0 * C[2])
    dist += c_sq
    dist += np.float32(C @ C)
    np.maximum(dist, np.float32(1e-30), out=dist)
    np.sqrt(dist, out=dist)
    dot /= dist
    return dot


def grazing_area_m2(scene, intrinsics: Intrinsics, pose: Pose, cos_t: np.ndarray,
                    grazing_cos: float = GRAZING_COS) -> float:
    """Area of the grazing triangles (``|cos θ| < grazing_cos``) that the camera sees.

    A triangle counts when its centroid projects into the image and nothing lies on the ray from the
    camera centre to the centroid (one any-hit query per candidate). In a one-sided scene (closed,
    outward-oriented surface) only front faces (cos θ > 0) are candidates; back faces are hidden anyway.
    (Whether a pixel happened to hit the triangle is deliberately not used: that would make the result grow
    with the resolution.)
    """
    if scene.one_sided:
        cand = np.flatnonzero((cos_t > 0.0) & (cos_t < grazing_cos))
    else:
        cand = np.flatnonzero(np.abs(cos_t) < grazing_cos)
    if cand.size == 0:
        return 0.0
    # Camera coordinates of the candidates' centroids from the stored float32 columns (relative to the centre).
    cx, cy, cz = (col[cand] for col in scene._soa[3:6])
    R = pose.R
    t = R @ scene.center + pose.T
    X = [cx * np.float32(R[j, 0]) + cy * np.float32(R[j, 1]) + cz * np.float32(R[j, 2]) + np.float32(t[j])
         for j in range(3)]
    k = intrinsics
    z = X[2]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = (X[0] * np.float32(k.fx) + X[1] * np.float32(k.skew)) / z
        v = X[1] * np.float32(k.fy) / z
    inside = ((z > 0) & (u >= -0.5 - k.cx) & (u < k.width - 0.5 - k.cx)
              & (v >= -0.5 - k.cy) & (v < k.height - 0.5 - k.cy))
    idx = np.flatnonzero(inside)
    if idx.size == 0:
        return 0.0
    # Rays from the camera centre C to the centroids c: direction c − C = c_local − (C − centre), so t = 1 at c.
    offset = pose.camera_center - scene.center
    rays = np.empty((idx.size, 6), dtype=np.float32)
    for j, col in enumerate((cx, cy, cz)):
        rays[:, j] = pose.camera_center[j]
        np.subtract(col[idx], np.float32(offset[j]), out=rays[:, 3 + j])
    # Any hit strictly before the centroid (t < 1) hides it: an any-hit query, cheaper than a closest hit.
    occluded = scene.occluded(rays, 1.0 - _CENTROID_T_TOL)
    return float(scene.triangle_areas_m2[cand[idx[~occluded]]].sum())


def visible_area_m2(z_m: np.ndarray, n_dot_d: np.ndarray, d_dot_d: np.ndarray, triangle_ids: np.ndarray,
                    scene, intrinsics: Intrinsics, pose: Pose, grazing_cos: float = GRAZING_COS) -> float:
    """Visible area of one view: pixel footprints on non-grazing triangles + visible grazing triangles.

    Parameters
    ----------
    z_m, n_dot_d, d_dot_d : (k,) float
        Per hit pixel, as in :func:`pixel_footprint_m2` (``d_dot_d`` is used only with ``grazing_cos`` 0).
    triangle_ids : (k,) int
        Hit triangle of each pixel.
    scene : MeshScene
    intrinsics : Intrinsics
    pose : Pose
    grazing_cos : float
        Triangles with cos θ below it are measured in object space (0 = pixels only).
    """
    if grazing_cos <= 0:
        return float(pixel_footprint_m2(z_m, n_dot_d, d_dot_d, intrinsics).sum())
    cos_t = triangle_view_cosines(scene, pose.camera_center)
    keep = np.abs(cos_t[np.asarray(triangle_ids, dtype=np.int64)]) >= grazing_cos
    # On these triangles cos θ ≥ grazing_cos, far from the clip, and the footprint z² cos α / (fx fy cos θ)
    # equals z² / (fx fy |n·d|) (d has unit z, so |n·d| = cos θ / cos α).
    z = np.asarray(z_m, dtype=np.float64)
    per_pixel = z * z / np.maximum(np.asarray(n_dot_d, dtype=np.float64), 1e-6)
    pixels = float(np.einsum("i,i->", per_pixel, keep.astype(np.float64))) / (intrinsics.fx * intrinsics.fy)
    return pixels + grazing_area_m2(scene, intrinsics, pose, cos_t, grazing_cos)


def vbsa_hit_m2(frame: DepthFrame, scene) -> float:
    """The paper's VBSA: area of the unique mesh triangles hit by at least one pixel (m²).

    Parameters
    ----------
    frame : DepthFrame
        Rendered (or sensor-degraded) view; pixels with ``triangle_id == -1`` are ignored.
    scene : MeshScene
        The scene the frame was rendered from (for the triangle areas).
    """
    return hit_area_m2(frame.triangle_id, scene.triangle_areas_m2)


def vbsa_visible_m2(frame: DepthFrame, scene=None, grazing_cos: float = GRAZING_COS) -> float:
    """Resolution-independent visible skin area of a frame (m²).

    Parameters
    ----------
    frame : DepthFrame
    scene : MeshScene, optional
        The scene the frame was rendered from. With it, grazing triangles are measured in object space
        (the estimate used by :func:`~wbsa.camera.measure.measure_view`, within about 1 % of the true
        visible area at Kinect v1 resolution); without it, the plain sum of pixel footprints, which falls
        short at silhouettes (1–5 % on spheres and bodies at Kinect v1 resolution).
    grazing_cos : float
        See :func:`visible_area_m2`.
    """
    valid = (frame.depth_m > 0) & np.all(np.isfinite(frame.normals_cam), axis=-1)
    if scene is not None:
        valid &= frame.triangle_id >= 0
    k = frame.intrinsics
    dirs, _ = pixel_rays(k)
    d = dirs[valid].astype(np.float64)
    n = frame.normals_cam[valid].astype(np.float64)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    nd = np.abs(np.einsum("ij,ij->i", n, d))
    dd = np.einsum("ij,ij->i", d, d)
    z = frame.depth_m[valid]
    if scene is None:
        return float(pixel_footprint_m2(z, nd, dd, k).sum())
    return visible_area_m2(z, nd, dd, frame.triangle_id[valid], scene, k, frame.pose, grazing_cos)


def sphere_cap_area_m2(radius_m: float, distance_m: float) -> float:
    """Area of a sphere visible from a point at ``distance_m`` from its centre: 2πr²(1 − r/d)."""
    if distance_m <= radius_m:
        return 0.0
    return 2.0 * math.pi * radius_m**2 * (1.0 - radius_m / distance_m)
