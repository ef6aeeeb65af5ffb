"""Ray casting a mesh with Open3D: one ray per pixel through ``K⁻¹ [u, v, 1]``, first hits only.

:func:`cast` casts only the pixels that can see the mesh (see :mod:`wbsa.camera.roi`) and keeps the
results compact (:class:`RayHits`); :func:`render` expands them to a full
:class:`~wbsa.core.frame.DepthFrame`. A pixel's ray is bit-identical whichever set of pixels is
cast, so the region of interest gives exactly the full frame's hits.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Literal

import numpy as np

from wbsa.camera.extrinsics import Pose
from wbsa.core.frame import DepthFrame
from wbsa.camera.intrinsics import Intrinsics, pixel_axes, pixel_rays
from wbsa.camera.roi import PixelGrid, projected_roi, silhouette_pixels
from wbsa.camera.scene import MeshScene
from wbsa.errors import WbsaError

#: Open3D's "no hit" primitive id.
_INVALID_ID = np.uint32(0xFFFFFFFF)

RoiMode = Literal["silhouette", "bbox", "full"]


@dataclass(frozen=True, eq=False)
class RayHits:
    """Compact ray-casting result: one entry per cast pixel.

    Attributes
    ----------
    intrinsics : Intrinsics
    pose : Pose
        World-to-camera transform of the view.
    roi : (v0, v1, u0, u1)
        Rectangle that holds every cast pixel; pixels outside it have no return.
    pixels : (n,) int64 or None
        Flat image index (``row · width + col``) of each cast ray; None when the rays are the whole
        ``roi`` rectangle in row-major order.
    rays : (n, 6) float32
        Camera centre and direction ``Rᵀ K⁻¹ [u, v, 1]`` (world frame, unit z in the camera frame, so the
        hit distance along it is the z-depth).
    t_hit : (n,) float32
        z-depth of each ray's first hit; inf = no hit.
    primitive_ids : (n,) uint32
        Hit triangle; 0xFFFFFFFF = no hit.
    normals_world : (n, 3) float32
        Unit normal of the hit triangle (vertex-order orientation), world frame.
    grid : PixelGrid or None
        The cast pixels on a grid (:class:`~wbsa.camera.roi.PixelGrid`); None when they are the ``roi``
        rectangle.
    """

    intrinsics: Intrinsics
    pose: Pose
    roi: tuple[int, int, int, int]
    pixels: np.ndarray | None
    rays: np.ndarray
    t_hit: np.ndarray
    primitive_ids: np.ndarray
    normals_world: np.ndarray
    grid: PixelGrid | None = None

    @property
    def n_rays(self) -> int:
        """Number of cast rays."""
        return int(self.t_hit.shape[0])

    @cached_property
    def hit_index(self) -> np.ndarray:
        """(k,) int64 positions (into the cast rays) of the rays that hit."""
        return np.flatnonzero(self._hit)

    @property
    def n_pixels(self) -> int:
        """Number of pixels with a return."""
        return int(self.hit_ids.size)

    @property
    def hit_triangles(self) -> np.ndarray:
        """(k,) int64 triangle id of every hit pixel (with repeats)."""
        return self.hit_ids.astype(np.int64, copy=False)

    @cached_property
    def _hit(self) -> np.ndarray:
        """(n,) bool: which cast rays hit."""
        return self.primitive_ids != _INVALID_ID

    @cached_property
    def hit_ids(self) -> np.ndarray:
        """(k,) intp triangle id of every hit pixel (with repeats; read-only, cached)."""
        ids = self.primitive_ids[self._hit].astype(np.intp)
        ids.setflags(write=False)
        return ids

    @cached_property
    def hit_t(self) -> np.ndarray:
        """(k,) float32 z-depth of every hit pixel (read-only, cached)."""
        t = self.t_hit[self._hit]
        t.setflags(write=False)
        return t

    def depth_grid(self) -> tuple[PixelGrid, np.ndarray]:
        """The cast pixels on a grid and their z-depth per grid cell (float32, inf = no return)."""
        if self.grid is not None:
            grid = self.grid
        elif self.n_rays:
            grid = PixelGrid.from_rect(self.roi)
        else:  # nothing cast: an empty grid over the whole image
            k = self.intrinsics
            grid = PixelGrid(np.zeros(0, dtype=np.intp), -1, -1, k.width + 2, k.height + 2)
        depth = np.full(grid.n_rows * grid.stride, np.inf, dtype=np.float32)
        depth[grid.index] = self.t_hit
        return grid, depth

    def hit_pixels(self) -> tuple[np.ndarray, np.ndarray]:
        """(rows, cols) int64 image coordinates of the hit pixels."""
        if self.pixels is None:
            v0, _, u0, u1 = self.roi
            rows, cols = np.divmod(self.hit_index, max(1, u1 - u0))
            return rows + v0, cols + u0
        return np.divmod(self.pixels[self.hit_index], self.intrinsics.width)

    def _footprint_terms(self, with_dd: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """(z, |n·d|, |d|² or None) of every hit pixel, float32."""
        i = self.hit_index
        d = self.rays[i, 3:]
        nd = np.abs(np.einsum("ij,ij->i", self.normals_world[i], d))
        dd = np.einsum("ij,ij->i", d, d) if with_dd else None
        return self.t_hit[i], nd, dd

    def pixel_areas_m2(self) -> np.ndarray:
        """(k,) float64 footprint of every hit pixel (:func:`wbsa.camera.area.pixel_footprint_m2`)."""
        from wbsa.camera.area import pixel_footprint_m2

        return pixel_footprint_m2(*self._footprint_terms(), self.intrinsics)

    def visible_area_m2(self, scene: MeshScene, grazing_cos: float | None = None,
                        split_px: float | None | Literal["default"] = "default") -> float:
        """Visible skin area of this view (m²); see :func:`wbsa.camera.area.visible_area_m2`.

        ``grazing_cos`` 0 gives the plain sum of the pixel footprints (:meth:`pixel_areas_m2`);
        ``split_px`` (default ``GRAZING_SPLIT_PX``; None: never) sub-samples large grazing triangles.
        A view in which no pixel sees the body has no visible area (0).

        Parameters
        ----------
        scene : MeshScene
            The scene the rays were cast into.
        grazing_cos : float or None
            None: the default of :func:`wbsa.camera.area.visible_area_m2`.
        split_px : float, None or 'default'
        """
        from wbsa.camera.area import GRAZING_COS, GRAZING_SPLIT_PX, visible_area_m2

        if self.n_pixels == 0:
            return 0.0
        grazing_cos = GRAZING_COS if grazing_cos is None else grazing_cos
        split_px = GRAZING_SPLIT_PX if split_px == "default" else split_px
        if grazing_cos <= 0:
            return float(self.pixel_areas_m2().sum())
        grid, depth = self.depth_grid()
        return visible_area_m2(self.hit_t, self.hit_ids, scene, self.intrinsics, self.pose, grid, depth, grazing_cos,
                               split_px)

    @property
    def touches_border(self) -> bool:
        """Whether any pixel on the image border has a return (the body is cut by the frame)."""
        k = self.intrinsics
        v0, v1, u0, u1 = self.roi
        if self.n_pixels == 0 or (v0 > 0 and u0 > 0 and v1 < k.height and u1 < k.width):
            return False
        rows, cols = self.hit_pixels()
        return bool(np.any((rows == 0) | (rows == k.height - 1) | (cols == 0) | (cols == k.width - 1)))

    def to_frame(self, settings: dict | None = None) -> DepthFrame:
        """Expand to a full-image :class:`DepthFrame` (points and camera-facing normals in the camera frame).

        Parameters
        ----------
        settings : dict or None
            Stored with the frame (how it was made).
        """
        k = self.intrinsics
        h, w = k.height, k.width
        depth = np.zeros((h, w), dtype=np.float32)
        tri = np.full((h, w), -1, dtype=np.int64)
        points = np.full((h, w, 3), np.nan, dtype=np.float32)
        normals = np.full((h, w, 3), np.nan, dtype=np.float32)
        if self.n_pixels:
            i = self.hit_index
            rows, cols = self.hit_pixels()
            z = self.hit_t
            depth[rows, cols] = z
            tri[rows, cols] = self.hit_ids
            dirs_cam, _ = pixel_rays(k)
            d_cam = dirs_cam[rows, cols]
            points[rows, cols] = z[:, None] * d_cam
            n_cam = np.einsum("ij,kj->ik", self.normals_world[i], self.pose.R.astype(np.float32))
            flip = np.einsum("ij,ij->i", n_cam, d_cam) > 0
            n_cam[flip] *= -1.0
            normals[rows, cols] = n_cam
        info = {"renderer": "open3d-raycasting", "camera": k.name, "roi": list(self.roi), "n_rays": self.n_rays}
        info.update(settings or {})
        return DepthFrame(depth_m=depth, points_cam=points, normals_cam=normals, triangle_id=tri,
                          intrinsics=k, pose=self.pose, settings=info)


def _ray_terms(intrinsics: Intrinsics, pose: Pose, v0: int, v1: int, u0: int, u1: int):
    """Per-row and per-column float32 terms of the ray directions: ``d_j = row_j[v] + col_j[u]``.

    With ``x = xu[u] + shear·yv[v]`` and ``y = yv[v]``, ``Rᵀ (x, y, 1)`` splits into a column part
    ``xu·R[0] + R[2]`` and a row part ``yv·(R[1] + shear·R[0])``, each rounded to float32 element by element
    (rows v0..v1-1 and columns u0..u1-1, which may reach outside the image; a pixel's terms do not depend
    on the range).
    """
    xu, yv, shear = pixel_axes(intrinsics)
    if 0 <= u0 <= u1 <= xu.size and 0 <= v0 <= v1 <= yv.size:
        xu, yv = xu[u0:u1], yv[v0:v1]
    else:
        k = intrinsics
        xu = (np.arange(u0, u1, dtype=np.float64) - k.cx) / k.fx
        yv = (np.arange(v0, v1, dtype=np.float64) - k.cy) / k.fy
    R = pose.R
    cols = [(xu * R[0, j] + R[2, j]).astype(np.float32) for j in range(3)]
    rows = [(yv * (R[1, j] + shear * R[0, j])).astype(np.float32) for j in range(3)]
    return rows, cols


def rect_rays(intrinsics: Intrinsics, pose: Pose, rect: tuple[int, int, int, int]) -> np.ndarray:
    """(n, 6) float32 rays of the pixels in ``rect`` = (v0, v1, u0, u1), row-major.

    Parameters
    ----------
    intrinsics : Intrinsics
    pose : Pose
    rect : (int, int, int, int)
        Rows v0..v1-1 and columns u0..u1-1.
    """
    v0, v1, u0, u1 = rect
    hr, wr = v1 - v0, u1 - u0
    rows, cols = _ray_terms(intrinsics, pose, v0, v1, u0, u1)
    center = pose.camera_center
    rays = np.empty((hr * wr, 6), dtype=np.float32)
    grid = rays.reshape(hr, wr, 6)
    for j in range(3):
        rays[:, j] = center[j]
        np.add(rows[j][:, None], cols[j][None, :], out=grid[:, :, 3 + j])
    return rays


def grid_rays(intrinsics: Intrinsics, pose: Pose, grid: PixelGrid) -> tuple[np.ndarray, np.ndarray]:
    """Rays of the pixels of ``grid`` (:func:`~wbsa.camera.roi.silhouette_pixels`), in raster order.

    Bit-identical to :func:`rect_rays` for the same pixel: the same float32 row and column terms, added
    (the y and z terms as the two halves of one complex64 number, the same float32 additions).

    Parameters
    ----------
    intrinsics : Intrinsics
    pose : Pose
    grid : PixelGrid

    Returns
    -------
    rays : (n, 6) float32
    pixels : (n,) int64
        ``row · width + col`` of each ray, increasing.
    """
    k = intrinsics
    rows, cols = np.divmod(grid.index, grid.stride)  # grid rows and columns
    row_terms, col_terms = _ray_terms(k, pose, grid.v0, grid.v0 + grid.n_rows, grid.u0, grid.u0 + grid.stride)
    row_yz = np.empty(grid.n_rows, dtype=np.complex64)
    row_yz.real, row_yz.imag = row_terms[1], row_terms[2]
    col_yz = np.empty(grid.stride, dtype=np.complex64)
    col_yz.real, col_yz.imag = col_terms[1], col_terms[2]
    rays = np.empty((rows.size, 6), dtype=np.float32)
    for j in range(3):  # column by column: a broadcast of the (3,) centre is several times slower
        rays[:, j] = pose.camera_center[j]
    np.add(row_terms[0].take(rows), col_terms[0].take(cols), out=rays[:, 3])
    np.add(row_yz.take(rows), col_yz.take(cols), out=rays.view(np.complex64)[:, 2])
    rows *= k.width
    rows += cols
    rows += grid.v0 * k.width + grid.u0
    return rays, rows


def cast(scene: MeshScene, intrinsics: Intrinsics, pose: Pose, *, roi: bool | RoiMode = True) -> RayHits:
    """Cast one ray per pixel that can see the mesh; compact result.

    Parameters
    ----------
    scene : MeshScene
    intrinsics : Intrinsics
    pose : Pose
        World-to-camera transform.
    roi : bool or {'silhouette', 'bbox', 'full'}
        ``True``/``'silhouette'``: the pixels inside the projected bounding boxes of small patches of
        triangles (:func:`~wbsa.camera.roi.silhouette_pixels`; falls back to ``'bbox'`` when a vertex is
        at or behind the camera plane); ``'bbox'``: the rectangle of the projected bounding box;
        ``False``/``'full'``: every pixel. All give the same hits.

    Raises
    ------
    WbsaError
        If the camera centre lies inside the body.
    """
    mode = ("silhouette" if roi else "full") if isinstance(roi, bool) else roi
    if mode not in ("silhouette", "bbox", "full"):
        raise WbsaError(f"unknown ROI mode {roi!r}; use silhouette, bbox or full")
    center = pose.camera_center
    if scene.contains(center):
        raise WbsaError(f"the camera (at {np.round(center, 3).tolist()} m) is inside the body; "
                        f"use a larger --distance")
    k = intrinsics
    grid = silhouette_pixels(scene, k, pose) if mode == "silhouette" else None
    if grid is not None:
        if grid.index.size == 0:
            return _empty(k, pose)
        rays, pixels = grid_rays(k, pose, grid)
        rect = grid.rect
    else:
        pixels = None
        rect = projected_roi(scene, k, pose) if mode != "full" else (0, k.height, 0, k.width)
        v0, v1, u0, u1 = rect
        if v1 <= v0 or u1 <= u0:
            return _empty(k, pose)
        rays = rect_rays(k, pose, rect)
    ans = scene.cast_rays(rays)
    return RayHits(k, pose, rect, pixels, rays, ans["t_hit"], ans["primitive_ids"], ans["primitive_normals"], grid)


def _empty(intrinsics: Intrinsics, pose: Pose) -> RayHits:
    """A result with no rays (the mesh projects outside the image)."""
    z3 = np.zeros((0, 3), dtype=np.float32)
    return RayHits(intrinsics, pose, (0, 0, 0, 0), None, np.zeros((0, 6), np.float32), np.zeros(0, np.float32),
                   np.zeros(0, np.uint32), z3)


def render(scene: MeshScene, intrinsics: Intrinsics, pose: Pose, *, roi: bool | RoiMode = True) -> DepthFrame:
    """Ray-cast one view into a full :class:`DepthFrame`.

    Parameters
    ----------
    scene : MeshScene
    intrinsics : Intrinsics
    pose : Pose
        World-to-camera transform (see :func:`wbsa.camera.extrinsics.pose_from_view`).
    roi : bool or {'silhouette', 'bbox', 'full'}
        Which pixels to cast (see :func:`cast`); the frame is the same either way.

    Returns
    -------
    DepthFrame
        z-depth (OpenCV, +Z forward), camera-frame hit points, camera-facing unit normals, triangle ids.
    """
    return cast(scene, intrinsics, pose, roi=roi).to_frame()
