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
    others cast one any-hit ray to the centroid.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from wbsa.camera.extrinsics import Pose
from wbsa.camera.frame import DepthFrame
from wbsa.camera.intrinsics import Intrinsics, pixel_rays
from wbsa.camera.roi import PixelGrid, homogeneous_pixels

#: Triangles seen at cos θ below this (θ > 72.5°) are measured in object space, not by pixel footprints.
GRAZING_COS = 0.3
#: Lower clip of cos θ in a pixel footprint (θ ≤ 88.85°), a guard against near-tangent hits; clipping at
#: c removes about c/2 of a smooth convex cap, so it matters only in the frame-only estimate.
FOOTPRINT_COS_MIN = 0.02
#: A grazing triangle is visible when nothing lies on the ray to its centroid before this fraction of the way.
_CENTROID_T_TOL = 1e-4
#: Depth-buffer decisions about a grazing triangle's centroid at depth Z, in pixel footprints Z / √(fx·fy):
#: visible when none of the 4 pixels around it has a return nearer than Z − CLEAR; hidden when all of
#: them have one nearer than Z − HIDDEN; otherwise a ray decides.
CENTROID_CLEAR_PX = 1.0
CENTROID_HIDDEN_PX = 10.0
#: Grazing triangles that may look larger than this (pixels) are judged by sub-triangles, not by their
#: centroid alone. Anny bodies never reach it at the paper's distances (longest edge 71 mm: at most 12 px
#: with a Kinect v1 at 3.4 m from the nearest vertex), so their results do not depend on it.
GRAZING_SPLIT_PX = 16.0
#: Size (pixels) of the sub-triangles of a split grazing triangle.
GRAZING_SAMPLE_PX = 2.0
#: At most this many sub-triangles per side (s² per triangle).
GRAZING_MAX_SPLIT = 128


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


def triangle_view_terms(scene, camera_center: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per triangle: the camera's height above its plane and the cosine of the view angle.

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
    """
    return triangle_view_terms(scene, camera_center)[1]


def depth_lookup(grid: PixelGrid, depth_m: np.ndarray, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nearest and farthest return among the 2 × 2 pixels around image points.

    Parameters
    ----------
    grid : PixelGrid
        The cast pixels (:class:`wbsa.camera.roi.PixelGrid`); its rectangle must hold the points' 2 × 2
        pixels or their empty border (true for points inside the image and inside the mesh's projection).
    depth_m : (grid.n_rows · grid.stride,) float32
        z-depth per grid cell, inf where a pixel has no return or was not cast (the border included).
    u, v : (k,) float
        Image coordinates (pixel centres at integers).

    Returns
    -------
    nearest, farthest : (k,) float32
        inf where the pixels see nothing.
    """
    cell = np.floor(v).astype(np.intp)
    cell -= grid.v0
    cell *= grid.stride
    cell += np.floor(u).astype(np.intp)
    cell -= grid.u0
    d = [depth_m.take(cell)]
    for step in (1, grid.stride - 1, 1):
        cell += step
        d.append(depth_m.take(cell))
    near = np.minimum(d[0], d[1])
    np.minimum(near, d[2], out=near)
    np.minimum(near, d[3], out=near)
    far = np.maximum(d[0], d[1])
    np.maximum(far, d[2], out=far)
    np.maximum(far, d[3], out=far)
    return near, far


def grazing_area_m2(scene, intrinsics: Intrinsics, pose: Pose, cos_t: np.ndarray, grid: PixelGrid,
                    depth_m: np.ndarray, grazing_cos: float = GRAZING_COS,
                    split_px: float | None = GRAZING_SPLIT_PX) -> float:
    """Area of the grazing triangles (``|cos θ| < grazing_cos``) that the camera sees.

    A triangle counts when its centroid projects into the image and nothing lies on the ray from the
    camera centre to the centroid. The depth already cast decides where the 2 × 2 pixels around the
    centroid agree: none of them has a return nearer than ``CENTROID_CLEAR_PX`` pixel footprints in front
    of it (visible), or all of them have one more than ``CENTROID_HIDDEN_PX`` footprints in front (hidden);
    the others (about two thirds on a body, mostly where the surface next to the centroid turns towards
    the camera) cast one any-hit ray to the centroid. In a one-sided scene (closed, outward-oriented
    surface) only front faces (cos θ > 0) are candidates; back faces are hidden anyway. (Whether a pixel
    happened to hit the triangle is deliberately not used: that would make the result grow with the
    resolution.)

    A triangle that may look larger than ``split_px`` pixels (:func:`split_counts`) is cut into s × s
    equal sub-triangles, ``s = ceil(size / GRAZING_SAMPLE_PX)``, whose centroids are decided the same way:
    it counts in proportion to its visible sub-triangles, so a large, partly hidden triangle of a coarse
    mesh counts its visible part (:func:`split_area_m2`).

    Parameters
    ----------
    scene : MeshScene
    intrinsics : Intrinsics
    pose : Pose
    cos_t : (m,) float
        :func:`triangle_view_cosines` of the view.
    grid : PixelGrid
        The cast pixels.
    depth_m : (grid.n_rows · grid.stride,) float32
        Their z-depth, inf for no return (and on the grid's border).
    grazing_cos : float
    split_px : float or None
        Size above which a grazing triangle is sub-sampled; None: never (every triangle by its centroid).
    """
    if scene.one_sided:
        cand = np.flatnonzero((cos_t > 0.0) & (cos_t < grazing_cos))
    else:
        cand = np.flatnonzero(np.abs(cos_t) < grazing_cos)
    if cand.size == 0:
        return 0.0
    # Homogeneous image coordinates K (R c + T) of the centroids, from the float32 columns relative to the centre.
    k = intrinsics
    cols = np.take(scene._soa[3:6], cand, axis=1)
    u, v, z = homogeneous_pixels(k, pose, scene.center, cols)
    with np.errstate(divide="ignore", invalid="ignore"):
        u /= z
        v /= z
    extra = None
    split = split_counts(scene, k, cand, z, split_px)
    if split is not None:  # the large triangles by their sub-triangles, the others by their centroids below
        big = split > 1
        extra = split_area_m2(scene, k, pose, grid, depth_m, cand[big], split[big],
                              None if scene.one_sided else cos_t.take(cand[big]) > 0)
        small = np.flatnonzero(~big)
        cand, cols, z, u, v = cand[small], cols[:, small], z[small], u[small], v[small]
        if cand.size == 0:
            return extra
    if not grid.mesh_in_image:
        inside = (z > 0) & (u >= -0.5) & (u < k.width - 0.5) & (v >= -0.5) & (v < k.height - 0.5)
        if not inside.all():
            keep = np.flatnonzero(inside)
            if keep.size == 0:
                return 0.0 if extra is None else extra
            cand, cols, z, u, v = cand[keep], cols[:, keep], z[keep], u[keep], v[keep]
    visible = points_visible(scene, k, pose, grid, depth_m, cols, z, u, v,
                             None if scene.one_sided else cos_t.take(cand) > 0)
    area = float(np.einsum("i,i->", scene.triangle_areas_m2.take(cand), visible.astype(np.float64)))
    return area if extra is None else area + extra


def points_visible(scene, intrinsics: Intrinsics, pose: Pose, grid: PixelGrid, depth_m: np.ndarray,
                   cols: np.ndarray, z: np.ndarray, u: np.ndarray, v: np.ndarray,
                   front: np.ndarray | None = None) -> np.ndarray:
    """Whether the camera sees surface points that project into the image (the grazing triangles' test).

    Parameters
    ----------
    scene, intrinsics, pose, grid, depth_m
        As :func:`grazing_area_m2`.
    cols : (3, n) float32
        The points relative to ``scene.center``.
    z, u, v : (n,) float32
        Their z-depth and image coordinates (inside the image).
    front : (n,) bool, optional
        Whether each point's triangle faces the camera (default: all do, as in a one-sided scene).

    Returns
    -------
    (n,) bool
        Visible when none of the 2 × 2 pixels around the point has a return more than
        ``CENTROID_CLEAR_PX`` footprints in front of it (only for points on front faces: a back face lies
        behind the front face next to it, however close), hidden when all of them have one more than
        ``CENTROID_HIDDEN_PX`` footprints in front, otherwise by an any-hit ray from the camera to the point.
    """
    k = intrinsics
    near, far = depth_lookup(grid, depth_m, u, v)
    footprint = z / np.float32(math.sqrt(k.fx * k.fy))
    visible = near >= z - np.float32(CENTROID_CLEAR_PX) * footprint
    if front is not None:
        visible &= front
    ask = np.flatnonzero(~visible & (far >= z - np.float32(CENTROID_HIDDEN_PX) * footprint))
    if ask.size:
        # Rays from the camera centre C to the points c: direction c − C = c_local − (C − centre), t = 1 at c.
        offset = pose.camera_center - scene.center
        rays = np.empty((ask.size, 6), dtype=np.float32)
        for j in range(3):
            rays[:, j] = pose.camera_center[j]
            np.subtract(cols[j].take(ask), np.float32(offset[j]), out=rays[:, 3 + j])
        # Any hit strictly before the point (t < 1) hides it: an any-hit query, cheaper than a closest hit.
        visible[ask] = ~scene.occluded(rays, 1.0 - _CENTROID_T_TOL)
    return visible


def split_counts(scene, intrinsics: Intrinsics, triangles: np.ndarray, z: np.ndarray,
                 split_px: float | None = GRAZING_SPLIT_PX, sample_px: float = GRAZING_SAMPLE_PX) -> np.ndarray | None:
    """Sub-triangles per side of grazing triangles that may look larger than ``split_px`` pixels.

    A triangle with longest edge L whose centroid lies at z-depth z has no vertex nearer than z − L, so
    it spans at most about ``f · L / (z − L)`` pixels (f the larger focal length; unbounded when
    z ≤ L). Those above ``split_px`` get ``s = ceil(size / sample_px)`` (at most ``GRAZING_MAX_SPLIT``).

    Parameters
    ----------
    scene : MeshScene
    intrinsics : Intrinsics
    triangles : (n,) int
    z : (n,) float
        z-depth of their centroids.
    split_px : float or None
    sample_px : float

    Returns
    -------
    (n,) int64 or None
        s per triangle (1: not split); None when no triangle is split (always for ``split_px`` None).
    """
    if split_px is None or z.size == 0:
        return None
    f = max(intrinsics.fx, intrinsics.fy)
    z_min = float(z.min())
    if z_min > scene.max_edge_m and f * scene.max_edge_m <= split_px * (z_min - scene.max_edge_m):
        return None  # no triangle of the scene can look that large: the common case of a fine mesh
    edge = scene.longest_edges_m.take(triangles)
    nearest = z.astype(np.float64) - edge
    with np.errstate(divide="ignore", invalid="ignore"):
        size = np.where(nearest > 0, f * edge / nearest, np.inf)
    big = size > split_px
    if not big.any():
        return None
    s = np.ones(triangles.size, dtype=np.int64)
    s[big] = np.minimum(np.ceil(np.minimum(size[big], 1e9) / sample_px), GRAZING_MAX_SPLIT).astype(np.int64)
    return s


@lru_cache(maxsize=64)
def subtriangle_centroids(s: int) -> np.ndarray:
    """(3, s²) float64 barycentric weights of the centroids of a triangle cut into s × s equal sub-triangles.

    Each side is cut into s; the s(s + 1)/2 sub-triangles that point like the triangle have centroids at
    ((i + ⅓)/s, (j + ⅓)/s), the s(s − 1)/2 others at ((i + ⅔)/s, (j + ⅔)/s) (weights of vertices 1 and 2).
    """
    i, j = np.meshgrid(np.arange(s), np.arange(s), indexing="ij")
    up, down = i + j <= s - 1, i + j <= s - 2
    a = np.concatenate([i[up] + 1.0 / 3.0, i[down] + 2.0 / 3.0]) / s
    b = np.concatenate([j[up] + 1.0 / 3.0, j[down] + 2.0 / 3.0]) / s
    out = np.stack([1.0 - a - b, a, b])
    out.setflags(write=False)
    return out


def split_area_m2(scene, intrinsics: Intrinsics, pose: Pose, grid: PixelGrid, depth_m: np.ndarray,
                  triangles: np.ndarray, s: np.ndarray, front: np.ndarray | None = None) -> float:
    """Visible area of large grazing triangles, each cut into ``s × s`` sub-triangles judged by their centroids.

    Parameters
    ----------
    scene, intrinsics, pose, grid, depth_m
        As :func:`grazing_area_m2`.
    triangles : (n,) int
    s : (n,) int
        Sub-triangles per side (:func:`split_counts`).
    front : (n,) bool, optional
        Whether each triangle faces the camera (:func:`points_visible`; default: all do).

    Returns
    -------
    float
        Σ area · (visible sub-triangles whose centroid projects into the image) / s².
    """
    k = intrinsics
    faces = np.asarray(scene.mesh.faces)
    verts = scene._local_vertices_f32.astype(np.float64)
    total = 0.0
    for n in np.unique(s):
        group = s == n
        tris = triangles[group]
        w = subtriangle_centroids(int(n))                                   # (3, n²)
        corners = [verts[:, faces[tris, c]] for c in range(3)]              # 3 × (3, t)
        points = sum(c[:, :, None] * w[i][None, None, :] for i, c in enumerate(corners))  # (3, t, n²)
        cols = np.ascontiguousarray(points.reshape(3, -1), dtype=np.float32)
        u, v, z = homogeneous_pixels(k, pose, scene.center, cols)
        with np.errstate(divide="ignore", invalid="ignore"):
            u /= z
            v /= z
        inside = np.flatnonzero((z > 0) & (u >= -0.5) & (u < k.width - 0.5) & (v >= -0.5) & (v < k.height - 0.5))
        seen = np.zeros(cols.shape[1], dtype=bool)
        if inside.size:
            facing = None if front is None else np.repeat(front[group], n * n)[inside]
            seen[inside] = points_visible(scene, k, pose, grid, depth_m, cols[:, inside], z[inside], u[inside],
                                          v[inside], facing)
        fraction = seen.reshape(tris.size, -1).mean(axis=1)
        total += float(np.einsum("i,i->", scene.triangle_areas_m2.take(tris), fraction))
    return total


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
    """Area of a sphere visible from a point at ``distance_m`` from its centre: 2πr²(1 − r/d)."""
    if distance_m <= radius_m:
        return 0.0
    return 2.0 * math.pi * radius_m**2 * (1.0 - radius_m / distance_m)
