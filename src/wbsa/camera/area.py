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
    ``cos³α / (fx·fy) · r² / cos θ = z² · cos α / (fx · fy · cos θ) = z³ / (fx · fy · h)``, h being the
    distance from the camera centre to the hit triangle's plane (one number per triangle and view).
    Near a silhouette 1/cos θ diverges: a pixel centre that lands just inside the limb counts a huge
    area and the pixels just outside count none, so point sampling of that band is unbiased only on
    average and in practice falls short by 1–5 % (more for small or thin objects). Given the scene, the
    band of grazing triangles (cos θ < ``GRAZING_COS`` seen from the camera) is therefore measured in
    object space instead: each such front-facing triangle whose centroid lies in the image and is not
    occluded counts whole, and pixels that hit a grazing triangle add nothing. Whether a centroid is
    occluded is read from the depth already cast where the 2 × 2 pixels around it agree (all of them see
    nothing in front of it: visible; all of them see something well in front of it: hidden); only the
    others cast one any-hit ray to the centroid. Grazing triangles that may look large (coarse meshes)
    count in proportion to their visible sub-triangles (:mod:`wbsa.camera.grazing`).
"""

from __future__ import annotations

import math

import numpy as np

from wbsa.camera.extrinsics import Pose
from wbsa.core.frame import DepthFrame
from wbsa.camera.intrinsics import Intrinsics, pixel_rays
from wbsa.camera.grazing import (_CENTROID_T_TOL, CENTROID_CLEAR_PX, CENTROID_HIDDEN_PX,  # noqa: F401 (re-exported)
                                 GRAZING_COS, GRAZING_MAX_SPLIT, GRAZING_SAMPLE_PX, GRAZING_SPLIT_PX, depth_lookup,
                                 grazing_area_m2, points_visible, split_area_m2, split_counts, subtriangle_centroids)
from wbsa.camera.roi import PixelGrid

#: Lower clip of cos θ in a pixel footprint (θ ≤ 88.85°), a guard against near-tangent hits; clipping at
#: c removes about c/2 of a smooth convex cap, so it matters only in the frame-only estimate.
FOOTPRINT_COS_MIN = 0.02


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
    """Summed area of the unique triangles among ``triangle_ids`` (k,) int; ids < 0 are ignored.

    Parameters
    ----------
    triangle_ids : (k,) int
        Triangle hit by each pixel, < 0 for none.
    triangle_areas : (m,) float64
        Every triangle's area (m²).
    """
    return float(np.einsum("i,i->", triangle_areas, hit_mask(triangle_ids, triangle_areas.shape[0])))


def hit_mask(triangle_ids: np.ndarray, n_triangles: int) -> np.ndarray:
    """(m,) float64 indicator (0/1) of the triangles hit at least once; ids < 0 are ignored.

    A float mask, so that sums over it are cheap dot products (numpy's bool matmul is a slow loop).

    Parameters
    ----------
    triangle_ids : (k,) int
        Triangle hit by each pixel, < 0 for none.
    n_triangles : int
        m, the mesh's triangle count.
    """
    ids = np.asarray(triangle_ids)
    if ids.size and ids.dtype.kind == "i":
        ids = ids[ids >= 0]
    seen = np.zeros(n_triangles, dtype=np.float64)
    seen[ids] = 1.0
    return seen


def triangle_view_terms(scene, camera_center: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per triangle: the camera's height above its plane and the cosine of the view angle.

    Parameters
    ----------
    scene : MeshScene
    camera_center : (3,) float64
        The camera centre (world frame, m).

    Returns
    -------
    height : (m,) float32
        ``n · (C − c)``: signed distance of the camera centre C from the triangle's plane (c its centroid).
    cos : (m,) float32
        ``n · (C − c) / |C − c|``: cosine between the face normal and the direction to the camera.
        Both are positive for triangles that face the camera, negative for back faces (normals made
        outward for a one-sided scene, by vertex order otherwise).
    """
    # Float32 passes over the scene's per-triangle columns (relative to its centre, n outward):
    # n·(C − c) = n·C − n·c and |C − c|² = |c|² − 2 C·c + |C|² (numpy.einsum, its own loops: a matrix
    # product would wake the BLAS thread pool).
    C = np.asarray(camera_center, dtype=np.float64) - scene.center
    soa = scene._soa
    height = np.einsum("j,jk->k", C.astype(np.float32), soa[:3])
    height -= soa[6]
    dist = np.einsum("j,jk->k", (-2.0 * C).astype(np.float32), soa[3:6])
    dist += soa[7]
    dist += np.float32(C @ C)
    np.maximum(dist, np.float32(1e-30), out=dist)
    np.sqrt(dist, out=dist)
    return height, np.divide(height, dist, out=dist)


def triangle_view_cosines(scene, camera_center: np.ndarray) -> np.ndarray:
    """(m,) float32 cosine between each face normal and the direction from its centroid to the camera.

    Positive for triangles that face the camera, negative for back faces (normals made outward for a
    one-sided scene, by vertex order otherwise).

    Parameters
    ----------
    scene : MeshScene
    camera_center : (3,) float64
        The camera centre (world frame, m).
    """
    return triangle_view_terms(scene, camera_center)[1]


def visible_area_m2(z_m: np.ndarray, triangle_ids: np.ndarray, scene, intrinsics: Intrinsics, pose: Pose,
                    grid: PixelGrid, depth_m: np.ndarray, grazing_cos: float = GRAZING_COS,
                    split_px: float | None = GRAZING_SPLIT_PX) -> float:
    """Visible area of one view: pixel footprints on non-grazing triangles + visible grazing triangles.

    Parameters
    ----------
    z_m : (k,) float
        z-depth of every hit pixel.
    triangle_ids : (k,) int
        Hit triangle of each pixel.
    scene : MeshScene
    intrinsics : Intrinsics
    pose : Pose
    grid, depth_m : PixelGrid, (grid cells,) float32
        The cast pixels and their depth (inf = no return), for the grazing triangles' occlusion
        (:func:`grazing_area_m2`).
    grazing_cos : float
        Triangles with |cos θ| below it are measured in object space (> 0; see
        :func:`pixel_footprint_m2` for the plain pixel sum).
    split_px : float or None
        Grazing triangles that may look larger are sub-sampled (:func:`grazing_area_m2`); None: never.
    """
    height, cos_t = triangle_view_terms(scene, pose.camera_center)
    # Footprint z² cos α / (fx fy cos θ) = z³ / (fx fy h) with h the camera's height above the hit triangle's
    # plane (the hit lies on it at z-depth z along d, d of unit z: h = z |n·d| and |n·d| = cos θ / cos α).
    # Weight 1 / h on the non-grazing triangles (cos θ ≥ grazing_cos, so h is far from zero), 0 on the others.
    h = np.abs(height)
    np.maximum(h, np.float32(1e-30), out=h)  # a triangle edge-on to the camera (h = 0) is grazing: weight 0
    weight = np.divide(np.abs(cos_t) >= grazing_cos, h, dtype=np.float32)
    z = np.asarray(z_m).astype(np.float64)
    z3 = z * z
    z3 *= z
    # (einsum rather than np.dot: OpenBLAS may thread a long dot product.)
    pixels = float(np.einsum("i,i->", z3, weight.take(np.asarray(triangle_ids, dtype=np.intp)).astype(np.float64)))
    pixels /= intrinsics.fx * intrinsics.fy
    return pixels + grazing_area_m2(scene, intrinsics, pose, cos_t, grid, depth_m, grazing_cos, split_px)


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
    k = frame.intrinsics
    valid = (frame.depth_m > 0) & np.all(np.isfinite(frame.normals_cam), axis=-1)
    if scene is not None and grazing_cos > 0:
        valid &= frame.triangle_id >= 0
        grid = PixelGrid.from_rect((0, k.height, 0, k.width))
        depth = np.full((grid.n_rows, grid.stride), np.inf, dtype=np.float32)
        depth[1:-1, 1:-1][valid] = frame.depth_m[valid]
        return visible_area_m2(frame.depth_m[valid], frame.triangle_id[valid], scene, k, frame.pose, grid,
                               depth.reshape(-1), grazing_cos)
    dirs, _ = pixel_rays(k)
    d = dirs[valid].astype(np.float64)
    n = frame.normals_cam[valid].astype(np.float64)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    nd = np.abs(np.einsum("ij,ij->i", n, d))
    dd = np.einsum("ij,ij->i", d, d)
    return float(pixel_footprint_m2(frame.depth_m[valid], nd, dd, k).sum())


def sphere_cap_area_m2(radius_m: float, distance_m: float) -> float:
    """Area of a sphere visible from a point at ``distance_m`` from its centre: 2πr²(1 − r/d).

    Parameters
    ----------
    radius_m : float
    distance_m : float
        From the point to the sphere's centre, more than ``radius_m``.
    """
    if distance_m <= radius_m:
        return 0.0
    return 2.0 * math.pi * radius_m**2 * (1.0 - radius_m / distance_m)
