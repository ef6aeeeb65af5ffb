"""The band of grazing triangles of the visible-area estimate (docs/camera.md, "Visible area, two ways").

Triangles seen at cos θ < ``GRAZING_COS`` are measured in object space, not by pixel footprints
(:func:`wbsa.camera.area.visible_area_m2`): each counts when its centroid is visible, or, when it may look
larger than ``GRAZING_SPLIT_PX`` pixels, in proportion to its sub-triangles whose centroids are visible.
Whether a point is visible is read from the depth already cast where the 2 × 2 pixels around it agree,
and otherwise decided by one any-hit ray.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from wbsa.camera.extrinsics import Pose
from wbsa.camera.intrinsics import Intrinsics
from wbsa.camera.roi import PixelGrid, homogeneous_pixels

#: Triangles seen at cos θ below this (θ > 72.5°) are measured in object space, not by pixel footprints.
GRAZING_COS = 0.3
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

    Parameters
    ----------
    s : int
        Cuts per side.
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


