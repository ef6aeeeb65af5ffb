"""From a depth image to 3D points: pinhole back-projection and organised-grid normals.

Pixel (row i, column j) looks along the ray K⁻¹ [j, i, 1]ᵀ (OpenCV convention: pixel centres at
integer coordinates), so a pixel with z-depth z sees the point z · K⁻¹ [j, i, 1]ᵀ in the camera frame.
"""

from __future__ import annotations

import numpy as np

from wbsa.core.frame import DepthFrame
from wbsa.errors import WbsaError


def ray_directions(intrinsics, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Viewing rays of the given pixels, scaled to unit z (so ``point = depth · ray``).

    Parameters
    ----------
    intrinsics : wbsa.camera.Intrinsics
        Needs ``fx, fy, cx, cy`` and optionally ``skew``.
    rows, cols : (...) int or float
        Pixel coordinates (row i = v, column j = u).

    Returns
    -------
    (..., 3) float64
    """
    fx, fy, cx, cy = (float(getattr(intrinsics, a)) for a in ("fx", "fy", "cx", "cy"))
    skew = float(getattr(intrinsics, "skew", 0.0) or 0.0)
    v = np.asarray(rows, dtype=np.float64)
    u = np.asarray(cols, dtype=np.float64)
    y = (v - cy) / fy
    x = (u - cx - skew * y) / fx
    x, y = np.broadcast_arrays(x, y)
    return np.stack([x, y, np.ones_like(x)], axis=-1)


def backproject_depth(depth_m: np.ndarray, intrinsics) -> np.ndarray:
    """Camera-frame points of every pixel of a depth image.

    Parameters
    ----------
    depth_m : (h, w) float
        z-depth in metres; 0 (or non-finite) = no return.
    intrinsics : wbsa.camera.Intrinsics

    Returns
    -------
    (h, w, 3) float32
        Points in metres; NaN where there is no return.
    """
    z = np.asarray(depth_m, dtype=np.float64)
    h, w = z.shape
    rays = ray_directions(intrinsics, np.arange(h)[:, None], np.arange(w)[None, :])
    ok = np.isfinite(z) & (z > 0)
    points = rays * np.where(ok, z, np.nan)[..., None]
    return points.astype(np.float32)


def organised_normals(points_cam: np.ndarray, valid: np.ndarray, *, max_jump_ratio: float = 0.05,
                      window_px: int = 1) -> np.ndarray:
    """Unit normals of an organised point cloud from its pixel-grid neighbours.

    The tangents along rows and columns are central differences where both neighbours are on the
    same surface (relative depth difference at most ``max_jump_ratio``), one-sided differences
    otherwise. With ``window_px > 1`` the tangents are averaged over a ``window_px`` square (the
    integral-image normals of Holzer et al. 2012 used by the paper). Normals face the camera; a
    pixel without any usable neighbour gets the reversed viewing ray.

    Parameters
    ----------
    points_cam : (h, w, 3) float
    valid : (h, w) bool
    max_jump_ratio : float
        Neighbours whose depths differ by more than this fraction are on different surfaces.
    window_px : int
        Side of the averaging window (odd; 1 = no averaging).

    Returns
    -------
    (h, w, 3) float32
        NaN where ``valid`` is False.
    """
    p = np.where(valid[..., None], np.asarray(points_cam, dtype=np.float64), 0.0)
    z = p[..., 2]
    du = _tangent(p, z, valid, axis=1, max_jump_ratio=max_jump_ratio)
    dv = _tangent(p, z, valid, axis=0, max_jump_ratio=max_jump_ratio)
    if window_px > 1:
        du = _box_mean(du, window_px)
        dv = _box_mean(dv, window_px)
    n = np.cross(du, dv)
    norm = np.linalg.norm(n, axis=-1, keepdims=True)
    ray = p / np.maximum(np.linalg.norm(p, axis=-1, keepdims=True), 1e-12)
    with np.errstate(invalid="ignore", divide="ignore"):
        n = np.where(norm > 0, n / norm, -ray)
    flip = np.einsum("...k,...k->...", n, p) > 0
    n[flip] *= -1.0
    n[~valid] = np.nan
    return n.astype(np.float32)


def _tangent(p: np.ndarray, z: np.ndarray, valid: np.ndarray, *, axis: int, max_jump_ratio: float) -> np.ndarray:
    """Finite-difference tangent along ``axis`` (per pixel step), 0 where none is usable."""
    fwd = np.zeros_like(p)
    ok_fwd = np.zeros(valid.shape, dtype=bool)
    sl_a = [slice(None)] * 2
    sl_b = [slice(None)] * 2
    sl_a[axis] = slice(0, -1)
    sl_b[axis] = slice(1, None)
    a, b = tuple(sl_a), tuple(sl_b)
    close = valid[a] & valid[b] & (np.abs(z[b] - z[a]) <= max_jump_ratio * np.minimum(z[a], z[b]))
    fwd[a] = np.where(close[..., None], p[b] - p[a], 0.0)
    ok_fwd[a] = close
    bwd = np.zeros_like(p)
    ok_bwd = np.zeros(valid.shape, dtype=bool)
    bwd[b] = fwd[a]
    ok_bwd[b] = close
    both = ok_fwd & ok_bwd
    t = np.where(both[..., None], 0.5 * (fwd + bwd), np.where(ok_fwd[..., None], fwd, bwd))
    return t


def _box_mean(a: np.ndarray, size: int) -> np.ndarray:
    """Sum of ``a`` over a ``size`` square around each pixel (integral image); scale does not matter."""
    r = size // 2
    h, w = a.shape[:2]
    c = np.zeros((h + 1, w + 1) + a.shape[2:], dtype=np.float64)
    c[1:, 1:] = a.cumsum(0).cumsum(1)
    i0 = np.clip(np.arange(h) - r, 0, h)
    i1 = np.clip(np.arange(h) + r + 1, 0, h)
    j0 = np.clip(np.arange(w) - r, 0, w)
    j1 = np.clip(np.arange(w) + r + 1, 0, w)
    return c[i1][:, j1] - c[i0][:, j1] - c[i1][:, j0] + c[i0][:, j0]


def frame_from_depth_image(depth_m: np.ndarray, intrinsics, *, pose=None, settings: dict | None = None,
                           normals: bool = True) -> DepthFrame:
    """A :class:`~wbsa.core.frame.DepthFrame` from a depth image alone (synthetic or from a real sensor).

    Points are back-projected with the intrinsics and normals estimated from the pixel grid
    (:func:`organised_normals`). There is no mesh behind a depth image, so ``triangle_id`` is -1
    everywhere; validity is ``depth_m > 0``.

    Parameters
    ----------
    depth_m : (h, w) float
        z-depth in metres, 0 or non-finite = no return (e.g. from :func:`wbsa.core.read_depth_png`).
    intrinsics : wbsa.camera.Intrinsics
        Its ``width`` and ``height`` must match the image.
    pose : wbsa.camera.Pose, optional
        World-to-camera transform if known (None = unknown).
    settings : dict, optional
        Recorded in the frame's settings, beside ``{"source": "depth_image"}``.
    normals : bool
        Estimate normals (False leaves them NaN: surface reconstruction reads only the depth, and the
        normals of a full image cost about 0.2 s).

    Raises
    ------
    WbsaError
        If the image is not 2-D or its size differs from the intrinsics.
    """
    depth = np.asarray(depth_m, dtype=np.float64)
    if depth.ndim != 2:
        raise WbsaError(f"a depth image must be 2-D (h, w), got shape {depth.shape}; give a single-channel image")
    h, w = depth.shape
    iw, ih = getattr(intrinsics, "width", w), getattr(intrinsics, "height", h)
    if (int(iw), int(ih)) != (w, h):
        raise WbsaError(f"depth image is {w}x{h} but the camera intrinsics are {iw}x{ih}; give the camera that took the image")
    depth = np.where(np.isfinite(depth) & (depth > 0), depth, 0.0).astype(np.float32)
    valid = depth > 0
    points = backproject_depth(depth, intrinsics)
    return DepthFrame(
        depth_m=depth,
        points_cam=points,
        normals_cam=organised_normals(points, valid) if normals else np.full((h, w, 3), np.nan, np.float32),
        triangle_id=np.full((h, w), -1, dtype=np.int64),
        intrinsics=intrinsics,
        pose=pose,
        settings={"source": "depth_image", **(settings or {})},
    )
