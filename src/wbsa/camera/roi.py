"""Which pixels need a ray: conservative regions of interest of a mesh in an image.

Both regions are exact in the sense that matters: every pixel whose ray can hit the mesh is inside,
so casting only them gives the same hits as casting the full frame.

``projected_roi``
    The pixel rectangle around the 8 projected corners of the mesh's bounding box.
``silhouette_blocks``
    Square blocks of pixels around the projected vertices: a triangle's image lies within its
    longest projected edge of each of its vertices, so marking the vertices' blocks and growing the
    marks by one block covers every triangle whose projected edges are shorter than a block; the
    few longer triangles mark the blocks of their whole bounding box. On a body in an A-pose this
    casts about half as many rays as the rectangle.
"""

from __future__ import annotations

import math

import numpy as np

from wbsa.camera.extrinsics import Pose
from wbsa.camera.intrinsics import Intrinsics

#: Block edge (pixels) of the silhouette mask.
BLOCK_PX = 8
#: Give up the block mask (use the rectangle) when more triangles than this fraction are longer than a block.
_MAX_LONG_FRACTION = 0.25


def projected_roi(scene, intrinsics: Intrinsics, pose: Pose) -> tuple[int, int, int, int]:
    """Pixel rectangle that contains every pixel whose ray can meet the mesh's bounding box.

    The 8 bounding-box corners are projected; the box is convex, so its image lies in their convex hull
    and hence inside the corners' pixel range. One pixel of slack absorbs float32 rounding of the rays.
    If a corner is at or behind the camera plane, the whole frame is returned.

    Returns
    -------
    (v0, v1, u0, u1) : int
        Rows v0..v1-1 and columns u0..u1-1; empty when v0 >= v1 or u0 >= u1.
    """
    k = intrinsics
    X = np.einsum("ij,kj->ik", scene.bbox_corners, pose.R) + pose.T
    z = X[:, 2]
    if np.any(z <= 1e-9):
        return 0, k.height, 0, k.width
    x, y = X[:, 0] / z, X[:, 1] / z
    u = k.fx * x + k.skew * y + k.cx
    v = k.fy * y + k.cy
    u0 = min(k.width, max(0, math.floor(u.min()) - 1))
    u1 = max(0, min(k.width, math.ceil(u.max()) + 2))
    v0 = min(k.height, max(0, math.floor(v.min()) - 1))
    v1 = max(0, min(k.height, math.ceil(v.max()) + 2))
    return v0, v1, u0, u1


def silhouette_blocks(scene, intrinsics: Intrinsics, pose: Pose,
                      block_px: int = BLOCK_PX) -> tuple[np.ndarray, np.ndarray] | None:
    """Blocks of ``block_px`` × ``block_px`` pixels that the mesh may cover.

    Parameters
    ----------
    scene : MeshScene
    intrinsics : Intrinsics
    pose : Pose
    block_px : int
        Block edge in pixels.

    Returns
    -------
    (block_rows, block_cols) : (nb,) int64 each, or None
        Block coordinates (pixel row ``block_rows · block_px``, column ``block_cols · block_px``); None when
        the mask cannot be built cheaply (a vertex at or behind the camera plane, or too many triangles
        longer than a block on screen): then use :func:`projected_roi`.
    """
    k = intrinsics
    B = int(block_px)
    # Homogeneous image coordinates of the vertices, K (R (x_local + centre) + T), from the stored columns.
    P = pose.R
    t = P @ scene.center + pose.T
    Lx, Ly, Lz = scene._local_vertices_t
    z = Lx * P[2, 0]
    z += Ly * P[2, 1]
    z += Lz * P[2, 2]
    z += t[2]
    z_min = float(z.min())
    if z_min <= 1e-6:
        return None
    x = Lx * P[0, 0]
    x += Ly * P[0, 1]
    x += Lz * P[0, 2]
    x += t[0]
    x /= z
    y = Lx * P[1, 0]
    y += Ly * P[1, 1]
    y += Lz * P[1, 2]
    y += t[1]
    y /= z
    # Longest possible projected edge per metre of 3D edge: |Δ(X/Z)| ≤ √(1 + t²)·L / z_min with t = max |X/Z|.
    sx = math.sqrt(1.0 + max(float(x.max()), -float(x.min())) ** 2)
    sy = math.sqrt(1.0 + max(float(y.max()), -float(y.min())) ** 2)
    px_per_m = max(k.fx * sx + abs(k.skew) * sy, k.fy * sy) / z_min
    long_tris = np.flatnonzero(scene._max_edge > (B - 1) / px_per_m)
    if long_tris.size > _MAX_LONG_FRACTION * scene._max_edge.size:
        return None
    nbu, nbv = -(-k.width // B), -(-k.height // B)
    # Block grid with a ring of one block around the image; vertices further out are clamped onto the ring
    # (a triangle reaching into the image has all its vertices within one block of it, or is "long").
    # Clipping to [0, nb + 1] before the cast makes truncation equal to floor.
    u = x * (k.fx / B)
    u += y * (k.skew / B)
    u += k.cx / B + 1.0
    v = y * (k.fy / B)
    v += k.cy / B + 1.0
    bu = np.clip(u, 0.0, nbu + 1.0, out=u).astype(np.intp)
    bv = np.clip(v, 0.0, nbv + 1.0, out=v).astype(np.intp)
    stride = nbu + 2
    grid = np.zeros((nbv + 2) * stride, dtype=bool)
    grid[bv * stride + bu] = True
    grid = grid.reshape(nbv + 2, stride)
    if long_tris.size:
        f0, f1, f2 = (f[long_tris] for f in scene._faces_t)
        a, b, c = bu[f0], bu[f1], bu[f2]
        u0, u1 = np.minimum(np.minimum(a, b), c), np.maximum(np.maximum(a, b), c)
        a, b, c = bv[f0], bv[f1], bv[f2]
        v0, v1 = np.minimum(np.minimum(a, b), c), np.maximum(np.maximum(a, b), c)
        span_u, span_v = int((u1 - u0).max()), int((v1 - v0).max())
        if (span_u + 1) * (span_v + 1) > 64:  # huge triangles on screen: the rectangle is as good and cheaper
            return None
        for i in range(span_v + 1):
            rows = np.minimum(v0 + i, v1)
            for j in range(span_u + 1):
                grid[rows, np.minimum(u0 + j, u1)] = True
    # Grow by one block (8-neighbourhood), then drop the ring.
    grown = grid.copy()
    grown[1:] |= grid[:-1]
    grown[:-1] |= grid[1:]
    grid = grown.copy()
    grid[:, 1:] |= grown[:, :-1]
    grid[:, :-1] |= grown[:, 1:]
    by, bx = np.nonzero(grid[1:-1, 1:-1])
    return by, bx
