"""The Warp back end: all views of a body in a few compiled passes (:mod:`.warp_kernels`), CPU or CUDA.

It answers the same question as the Open3D back end with the same rules (pixel footprints ``z³ / h`` on
non-grazing triangles, grazing triangles decided from the depth buffer, by sub-triangles when large, and
otherwise by a ray to their point), but casts the pixel rays and the grazing triangles' rays by
rasterizing the triangles, a batch of views per launch. A view with a vertex at or behind the camera
plane cannot be rasterized; it is measured by the Open3D back end (this never happens at scan distances).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from wbsa.camera.grazing import (CENTROID_CLEAR_PX, CENTROID_HIDDEN_PX, GRAZING_COS, GRAZING_MAX_SPLIT,
                                 GRAZING_SAMPLE_PX, GRAZING_SPLIT_PX, _CENTROID_T_TOL)
from wbsa.camera.extrinsics import Pose, pose_from_view
from wbsa.core.frame import DepthFrame
from wbsa.camera.intrinsics import Intrinsics
from wbsa.camera.scene import MeshScene, boundary_loops
from wbsa.camera.views import View
from wbsa.errors import WbsaError

#: Pixel slack of the per-view grid around the projected vertices (as :data:`wbsa.camera.roi.BOX_SLACK_PX`).
GRID_SLACK_PX = 0.05
#: Triangles per partial sum of :func:`~.warp_kernels.reduce_triangles`.
REDUCE_CHUNK = 1024
#: Triangles per thread of :func:`~.warp_kernels.grazing_points` on the CPU (one on a GPU): a thread per
#: triangle would mostly find none of the grazing ones, at a few ns per thread.
GRAZING_CHUNK = 256
#: Vertices or triangles per thread of :func:`~.warp_kernels.project_vertices` and
#: :func:`~.warp_kernels.raster_triangles` on the CPU (one on a GPU): Warp's CPU launch loop spends a few
#: ns per thread (a 2-D thread id costs an integer division).
ITEMS_PER_THREAD = 64
#: Skip back faces that cannot be a first hit (one-sided scenes, away from holes); False only to test that
#: it changes nothing.
CULL_BACK_FACES = True
#: Who answers the grazing points' any-hit rays: ``"auto"`` — Embree through Open3D on the CPU (about 3x
#: faster there than Warp's BVH), Warp's BVH on a GPU; ``"warp"`` — Warp's BVH everywhere (tests).
ANYHIT = "auto"
#: Views per batch of launches on the CPU (all of them on a GPU): keeps the per-view buffers in cache.
CPU_VIEWS_PER_BATCH = 16
_EMPTY = np.uint64(0xFFFFFFFFFFFFFFFF)


@lru_cache(maxsize=1)
def warp_module():
    """``import warp``, initialised quietly (once per process).

    Warp's banner is switched off; its native library prints a warning on stderr when a machine has no
    CUDA driver, which is the normal case here, so stderr is muted while it starts.
    """
    import os
    import sys

    import warp as wp

    wp.config.log_level = wp.LOG_ERROR
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
            wp.init()
    finally:
        os.dup2(saved, 2)
        os.close(saved)
    return wp


@lru_cache(maxsize=1)
def _kernels():
    from wbsa.camera.backends import warp_kernels

    return warp_kernels


class WarpBackend:
    """Measure views with Warp kernels.

    Parameters
    ----------
    device : str, optional
        Warp device (``'cpu'``, ``'cuda'``, ``'cuda:1'``); default the first CUDA device, else the CPU.
    views_per_batch : int, optional
        Views per launch; default all on a GPU, :data:`CPU_VIEWS_PER_BATCH` on the CPU.
    """

    name = "warp"

    def __init__(self, device: str | None = None, views_per_batch: int | None = None) -> None:
        wp = warp_module()
        if device is None:
            device = "cuda" if wp.get_cuda_device_count() > 0 else "cpu"
        self.device = str(wp.get_device(device))
        self.views_per_batch = views_per_batch or (CPU_VIEWS_PER_BATCH if self.device == "cpu" else 1 << 30)

    def measure_views(self, scene: MeshScene, intrinsics: Intrinsics, views: list[View],
                      target: np.ndarray | None = None, *, return_frames: bool = True,
                      grazing_cos: float = GRAZING_COS,
                      grazing_split_px: float | None = GRAZING_SPLIT_PX) -> list[tuple[dict, DepthFrame | None]]:
        """One ``(row, frame)`` per view, as :func:`wbsa.camera.measure.measure_view` returns them.

        ``grazing_cos`` ≤ 0 (the plain pixel sum, with its cos θ clip) is left to the Open3D back end.

        Parameters
        ----------
        scene, intrinsics, views, target, return_frames, grazing_cos, grazing_split_px
            As for :func:`wbsa.camera.backends.measure_views` (without its ``backend``).

        Raises
        ------
        WbsaError
            If the camera centre of a view lies inside the body.
        """
        if grazing_cos <= 0:
            from wbsa.camera.backends.open3d_backend import Open3DBackend

            return Open3DBackend().measure_views(scene, intrinsics, views, target, return_frames=return_frames,
                                                 grazing_cos=grazing_cos, grazing_split_px=grazing_split_px)
        views = list(views)
        target = scene.center if target is None else np.asarray(target, dtype=np.float64)
        poses = [pose_from_view(v, target) for v in views]
        for pose in poses:
            center = pose.camera_center
            if scene.contains(center):
                raise WbsaError(f"the camera (at {np.round(center, 3).tolist()} m) is inside the body; "
                                f"use a larger --distance")
        out: list[tuple[dict, DepthFrame | None] | None] = [None] * len(views)
        data = _MeshData(scene, self.device)
        step = self.views_per_batch
        fallback = []
        for start in range(0, len(views), step):
            idx = list(range(start, min(start + step, len(views))))
            done = _measure_batch(data, intrinsics, [poses[i] for i in idx], grazing_cos, grazing_split_px,
                                  return_frames)
            for i, result in zip(idx, done):
                if result is None:
                    fallback.append(i)
                else:
                    out[i] = result
        if fallback:
            from wbsa.camera.measure import measure_view

            for i in fallback:
                out[i] = measure_view(scene, intrinsics, views[i], target, return_frame=return_frames,
                                      grazing_cos=grazing_cos, grazing_split_px=grazing_split_px)
        rows = []
        for view, (row, frame) in zip(views, out):
            full = {"azimuth_deg": view.azimuth_deg, "elevation_deg": view.elevation_deg,
                    "distance_m": view.distance_m, "camera": intrinsics.name, **row}
            if frame is not None and "azimuth_deg" not in frame.settings:
                frame.settings.update({"azimuth_deg": view.azimuth_deg, "elevation_deg": view.elevation_deg,
                                       "distance_m": view.distance_m, "target_m": [float(x) for x in target]})
            rows.append((full, frame))
        return rows


class _MeshData:
    """A scene's arrays on a Warp device (vertices relative to the scene's centre, float32)."""

    def __init__(self, scene: MeshScene, device: str) -> None:
        wp = warp_module()
        self.scene = scene
        self.device = device
        self.n_vertices = scene._local_vertices_f32.shape[1]
        self.n_triangles = scene.n_triangles
        self.verts = wp.array(np.ascontiguousarray(scene._local_vertices_f32.T), dtype=wp.vec3f, device=device)
        faces = np.ascontiguousarray(scene.mesh.faces, dtype=np.int32)
        self.faces = wp.array(faces, dtype=wp.vec3i, device=device)
        self._indices = wp.array(faces.reshape(-1), dtype=wp.int32, device=device)
        self.areas = wp.array(scene.triangle_areas_m2, dtype=wp.float64, device=device)
        self.edges = wp.array(scene.longest_edges_m, dtype=wp.float64, device=device)
        # The reference's float32 per-triangle columns: outward normal, centroid − centre, n · c, |c|².
        self.soa = wp.array(scene._soa, dtype=wp.float32, device=device)
        # Holes of a one-sided scene (loops of boundary edges): back faces are rasterized only near them.
        loops = boundary_loops(faces.astype(np.int64).tobytes(), self.n_vertices) if scene.one_sided else []
        members = np.concatenate(loops) if loops else np.zeros(0, dtype=np.int32)
        starts = np.concatenate([[0], np.cumsum([len(x) for x in loops])]).astype(np.int32)
        local_vertices = scene._local_vertices_f32.T.astype(np.float64)
        hole_centroids = (np.array([local_vertices[x].mean(axis=0) for x in loops]) if loops
                          else np.zeros((0, 3)))
        self.n_holes = len(loops)
        self.hole_vertices = wp.array(members.astype(np.int32), dtype=int, device=device)
        self.hole_start = wp.array(starts, dtype=int, device=device)
        self.hole_centroids = wp.array(hole_centroids, dtype=wp.vec3d, device=device)
        self._mesh = None

    @property
    def mesh(self):
        """Warp's BVH of the mesh (built on first use: only views with undecided grazing points need it)."""
        if self._mesh is None:
            wp = warp_module()
            world = np.ascontiguousarray(self.scene.mesh.vertices, dtype=np.float32)  # as Open3D's scene
            self._world = wp.array(world, dtype=wp.vec3, device=self.device)
            self._mesh = wp.Mesh(points=self._world, indices=self._indices)
        return self._mesh


def _camera(intrinsics: Intrinsics, scene: MeshScene, grazing_cos: float, split_px: float | None):
    k = intrinsics
    cam = _kernels().Camera()
    cam.fx, cam.fy, cam.cx, cam.cy, cam.skew = float(k.fx), float(k.fy), float(k.cx), float(k.cy), float(k.skew)
    cam.width, cam.height = int(k.width), int(k.height)
    cam.grazing_cos = float(np.float32(grazing_cos))
    cam.split_px = -1.0 if split_px is None else float(split_px)
    cam.sample_px = float(GRAZING_SAMPLE_PX)
    cam.max_split = int(GRAZING_MAX_SPLIT)
    cam.clear_px = float(np.float32(CENTROID_CLEAR_PX))
    cam.hidden_px = float(np.float32(CENTROID_HIDDEN_PX))
    cam.footprint = float(np.float32(math.sqrt(k.fx * k.fy)))
    cam.t_tol = float(_CENTROID_T_TOL)
    cam.one_sided = int(bool(scene.one_sided))
    cam.sign = float(scene.orientation_sign)
    cam.cull = int(CULL_BACK_FACES)
    return cam


def _view_terms(scene: MeshScene, k: Intrinsics, poses: list[Pose]) -> np.ndarray:
    """(B, 19) float32 per-view terms of :mod:`.warp_kernels` (``N_VIEW_TERMS``), rounded as the reference rounds
    them (:func:`wbsa.camera.area.triangle_view_terms`, :func:`wbsa.camera.roi.homogeneous_pixels`)."""
    out = np.empty((len(poses), 19), dtype=np.float32)
    for b, pose in enumerate(poses):
        C = np.asarray(pose.camera_center, dtype=np.float64) - scene.center
        out[b, 0:3] = C.astype(np.float32)
        out[b, 3:6] = (-2.0 * C).astype(np.float32)
        out[b, 6] = np.float32(C @ C)
        out[b, 7:16] = (k.K @ pose.R).astype(np.float32).reshape(-1)
        out[b, 16:19] = (k.K @ (pose.R @ scene.center + pose.T)).astype(np.float32)
    return out


def _grid(k: Intrinsics, lo: np.ndarray, hi: np.ndarray) -> tuple[int, int, int, int]:
    """(v0, u0, stride, n_rows) of the pixel grid around projected bounds, with an empty one-cell border."""
    c0 = max(0, math.ceil(lo[0] - GRID_SLACK_PX))
    c1 = min(k.width - 1, math.floor(hi[0] + GRID_SLACK_PX))
    r0 = max(0, math.ceil(lo[1] - GRID_SLACK_PX))
    r1 = min(k.height - 1, math.floor(hi[1] + GRID_SLACK_PX))
    if c1 < c0 or r1 < r0:  # no pixel centre: an empty grid over the whole image (lookups see nothing)
        return -1, -1, k.width + 2, 2
    return r0 - 1, c0 - 1, c1 - c0 + 3, r1 - r0 + 3


def _measure_batch(data: _MeshData, k: Intrinsics, poses: list[Pose], grazing_cos: float,
                   split_px: float | None, return_frames: bool) -> list[tuple[dict, DepthFrame | None] | None]:
    """Measure a batch of views of one body; None for views that must be measured by the Open3D back end."""
    wp = warp_module()
    K = _kernels()
    dev = data.device
    scene = data.scene
    B, n, m = len(poses), data.n_vertices, data.n_triangles
    cam = _camera(k, scene, grazing_cos, split_px)
    rot = wp.array(np.array([p.R for p in poses]), dtype=wp.mat33d, device=dev)
    trans = wp.array(np.array([p.R @ scene.center + p.T for p in poses]), dtype=wp.vec3d, device=dev)
    xyz = wp.empty((B, n), dtype=wp.vec3d, device=dev)
    uv = wp.empty((B, n), dtype=wp.vec2d, device=dev)
    lo = wp.full((B, 2), np.inf, dtype=wp.float64, device=dev)
    hi = wp.full((B, 2), -np.inf, dtype=wp.float64, device=dev)
    behind = wp.zeros(B, dtype=int, device=dev)
    per = ITEMS_PER_THREAD if dev == "cpu" else 1
    wp.launch(K.project_vertices, dim=(B, -(-n // per)),
              inputs=[data.verts, rot, trans, cam, xyz, uv, lo, hi, behind, per], device=dev)

    lo_h, hi_h, behind_h = lo.numpy(), hi.numpy(), behind.numpy()
    grids = np.array([_grid(k, lo_h[b], hi_h[b]) if not behind_h[b] else (-1, -1, 2, 2) for b in range(B)],
                     dtype=np.int32)
    sizes = grids[:, 2].astype(np.int64) * grids[:, 3]
    offsets = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int32)
    n_cells = int(sizes.sum())
    if n_cells >= 2**31:
        raise WbsaError("too many pixels in one batch of views for the warp backend; use fewer views per batch")
    grids_w = wp.array(grids, dtype=wp.vec4i, device=dev)
    offsets_w = wp.array(offsets, dtype=int, device=dev)
    keys = wp.full(n_cells, _EMPTY, dtype=wp.uint64, device=dev)
    depth = wp.full(n_cells, np.inf, dtype=wp.float32, device=dev)
    centers = wp.array(np.array([p.camera_center - scene.center for p in poses]), dtype=wp.vec3d, device=dev)
    vt = wp.array(_view_terms(scene, k, poses), dtype=wp.float32, device=dev)
    boxes = wp.empty((B, data.n_holes), dtype=wp.vec4d, device=dev)
    if data.n_holes:
        wp.launch(K.hole_boxes, dim=(B, data.n_holes),
                  inputs=[data.hole_vertices, data.hole_start, data.hole_centroids, uv, rot, trans, cam, boxes],
                  device=dev)
    split = wp.empty((B, m), dtype=int, device=dev)
    n_points = wp.empty(B * m, dtype=wp.int64, device=dev)
    wp.launch(K.raster_triangles, dim=(B, -(-m // per)),
              inputs=[data.faces, xyz, uv, data.soa, data.edges, vt, cam, grids_w, offsets_w, boxes, keys, split,
                      n_points, per], device=dev)

    rows_max = int(grids[:, 3].max())
    seen = wp.zeros((B, m), dtype=wp.uint8, device=dev)
    n_pix = wp.zeros((B, rows_max), dtype=int, device=dev)
    foot = wp.zeros((B, rows_max), dtype=wp.float64, device=dev)
    border = wp.zeros((B, rows_max), dtype=int, device=dev)
    wp.launch(K.resolve_pixels, dim=(B, rows_max),
              inputs=[data.soa, vt, cam, grids_w, offsets_w, keys, depth, seen, n_pix, foot, border], device=dev)

    slots, state = _grazing(data, cam, vt, centers, grids_w, offsets_w, depth, split, n_points, B)

    chunks = -(-m // REDUCE_CHUNK)
    hit_area = wp.empty((B, chunks), dtype=wp.float64, device=dev)
    n_hit = wp.empty((B, chunks), dtype=int, device=dev)
    graze_parts = wp.empty((B, chunks), dtype=wp.float64, device=dev)
    wp.launch(K.reduce_triangles, dim=(B, chunks),
              inputs=[data.areas, seen, REDUCE_CHUNK, split, slots, state, hit_area, n_hit, graze_parts], device=dev)

    pixels = n_pix.numpy().sum(axis=1)
    footprint = foot.numpy().sum(axis=1)
    touches = border.numpy().any(axis=1)
    hit_m2 = hit_area.numpy().sum(axis=1)
    graze = graze_parts.numpy().sum(axis=1)
    tri_hit = n_hit.numpy().sum(axis=1)
    keys_h = keys.numpy() if return_frames else None
    depth_h = depth.numpy() if return_frames else None
    out: list[tuple[dict, DepthFrame | None] | None] = []
    for b in range(B):
        if behind_h[b]:
            out.append(None)
            continue
        visible = float(footprint[b]) / (k.fx * k.fy) + float(graze[b])
        row = {"vbsa_hit_m2": float(hit_m2[b]), "vbsa_visible_m2": visible, "n_pixels": int(pixels[b]),
               "n_triangles_hit": int(tri_hit[b]), "fits_in_frame": not bool(touches[b])}
        frame = None
        if return_frames:
            view_cells = slice(int(offsets[b]), int(offsets[b] + sizes[b]))
            frame = _frame(scene, k, poses[b], tuple(int(x) for x in grids[b]), keys_h[view_cells], depth_h[view_cells])
        out.append((row, frame))
    return out


def _grazing(data: _MeshData, cam, vt, centers, grids_w, offsets_w, depth, split, n_points, B: int):
    """Decide the points of the grazing triangles of a batch of views: ``(slots, state)``.

    The grazing triangles and their sub-sampling (``split``, and their point counts ``n_points``, from
    :func:`~.warp_kernels.raster_triangles`) get consecutive slots (``slots``, an exclusive scan over (view,
    triangle)); the depth buffer decides most points and an any-hit ray the rest (Embree through Open3D on
    the CPU, Warp's BVH on a GPU). ``state`` holds 1 for a visible point, 0 for a hidden one.
    """
    wp = warp_module()
    K = _kernels()
    dev = data.device
    m = data.n_triangles
    slots = wp.empty(B * m, dtype=wp.int64, device=dev)
    wp.utils.array_scan(n_points, slots, inclusive=False)
    total = int(slots[B * m - 1:].numpy()[0]) + int(n_points[B * m - 1:].numpy()[0])
    if total >= 2**31:
        raise WbsaError("too many grazing sample points in one batch of views for the warp backend")
    state = wp.empty(max(total, 1), dtype=int, device=dev)
    if total == 0:
        return slots, state
    origins = wp.array(np.ascontiguousarray(centers.numpy() + data.scene.center, dtype=np.float32), dtype=wp.vec3,
                       device=dev)
    rays = wp.empty((total, 6), dtype=wp.float32, device=dev)
    chunk = GRAZING_CHUNK if dev == "cpu" else 1
    wp.launch(K.grazing_points, dim=(B, -(-m // chunk)),
              inputs=[split, slots, data.faces, data.verts, data.soa, vt, cam, grids_w, offsets_w, depth, origins,
                      centers, state, rays, chunk], device=dev)
    if dev == "cpu" and ANYHIT == "auto":  # Embree's any-hit rays (Open3D) are about 3x faster than Warp's BVH on a CPU
        state_h = state.numpy()  # views of the same memory: the updates below are seen by the kernels
        ask = np.flatnonzero(state_h == 2)
        if ask.size:
            hidden = data.scene.occluded(rays.numpy()[ask], 1.0 - _CENTROID_T_TOL)
            state_h[ask] = np.where(hidden, 0, 1)
    else:
        wp.launch(K.anyhit_queries, dim=total, inputs=[data.mesh.id, rays, cam, state], device=dev)
    return slots, state


def _frame(scene: MeshScene, k: Intrinsics, pose: Pose, grid: tuple[int, int, int, int], keys: np.ndarray,
           depth: np.ndarray) -> DepthFrame:
    """The full-image :class:`DepthFrame` of one view from its grid of keys and depths."""
    from wbsa.camera.raycast import RayHits, grid_rays
    from wbsa.camera.roi import PixelGrid

    v0, u0, stride, n_rows = grid
    cells = np.flatnonzero(keys != _EMPTY)
    pixel_grid = PixelGrid(cells.astype(np.intp), v0, u0, stride, n_rows)
    tri = (keys[cells] & np.uint64(0xFFFFFFFF)).astype(np.uint32)
    rays, pixels = grid_rays(k, pose, pixel_grid)
    normals = scene.face_normals[tri.astype(np.intp)].astype(np.float32)
    hits = RayHits(k, pose, pixel_grid.rect, pixels, rays, depth[cells].astype(np.float32), tri, normals, pixel_grid)
    frame = hits.to_frame()
    frame.settings["renderer"] = "warp-raster"
    return frame
