"""The organised-grid mesh: two triangles per square of four neighbouring pixels, plus a boundary skirt.

This is the fast reconstruction the paper suggests for depth sensors (section 4.4; PCL's
OrganizedFastMesh): every 2×2 square of returns becomes two triangles, split along the diagonal
with the smaller depth difference; a square with three returns gives one triangle. A triangle is
kept only if each of its edges joins two pixels on one surface: an edge is cut where the depth
jumps by more than a surface inclined at ``max_angle_deg`` to the viewing ray would allow
(occlusion boundaries, e.g. an arm in front of the trunk).

A mesh over pixel *centres* stops half a pixel short of every boundary, and at an occluding
contour (the body's outline, where the surface turns away from the camera) the surface beyond
the last pixel centre is steep: at 4.3 m a 7.5 mm pixel can hide 2-3 cm of skin. On a body seen
at Kinect resolution the bare grid misses 16–26 % of the visible area. ``boundary`` adds a
skirt of two triangles on every boundary edge of the mesh:

- ``'footprint'``: extend the surface half a pixel along its local slope (the mesh then covers
  each pixel's footprint, like a per-pixel area sum);
- ``'contour'``: at occluding contours (the pixel beyond the edge is background or farther away)
  complete the surface with a circular arc that ends perpendicular to the viewing ray, as the
  surface of a smooth closed body does at its outline; its length is the mean arc length from the
  edge to the contour predicted from the depth step across the last pixel
  (:func:`contour_arc_pitches`); elsewhere (occluded edges, small holes, the image border) as
  ``'footprint'``.

Everything is vectorised over pixels.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from scipy import ndimage

from wbsa.core.mesh import TriangleMesh
from wbsa.surface.settings import BoundaryModel

_SQRT2 = math.sqrt(2.0)


def grid_mesh(points_cam: np.ndarray, valid: np.ndarray, focal_px: float, *, max_angle_deg: float = 85.0,
              min_jump_m: float = 0.0, boundary: BoundaryModel = "contour", hole_max_px: int = 16) -> TriangleMesh:
    """Triangulate an organised point cloud over its pixel grid.

    Parameters
    ----------
    points_cam : (h, w, 3) float
        Camera-frame points of each pixel (z = depth), metres; ignored where ``valid`` is False.
    valid : (h, w) bool
        Pixels with a return.
    focal_px : float
        Focal length in pixels (sets how far apart neighbouring pixels are at a given depth).
    max_angle_deg : float
        Neighbours are joined when the surface between them is inclined less than this to the ray,
        i.e. when |Δz| ≤ tan(max_angle) · z · d / f for neighbours ``d`` pixels apart.
    min_jump_m : float
        Never cut an edge whose depth difference is below this (tolerates noise on raw depth).
    boundary : {'none', 'footprint', 'contour'}
        Skirt added along the mesh boundary (see the module doc).
    hole_max_px : int
        Enclosed regions without returns up to this many pixels are holes in the surface (sensor
        dropout), not background: their edges get the ``'footprint'`` skirt.

    Returns
    -------
    TriangleMesh
        The valid pixels' points (row-major) then the skirt vertices, (n, 3) float64; faces (m, 3)
        int32 oriented towards the camera.
    """
    valid = np.asarray(valid, dtype=bool)
    h_img, w_img = valid.shape
    rows = np.flatnonzero(valid.any(axis=1))
    cols = np.flatnonzero(valid.any(axis=0))
    if rows.size == 0:
        return TriangleMesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int32))
    # crop to the returns plus a one-pixel ring (cells of the ring outside the image are "off image")
    r0, r1, c0, c1 = rows[0] - 1, rows[-1] + 2, cols[0] - 1, cols[-1] + 2
    h, w = r1 - r0, c1 - c0
    ok = np.zeros((h, w), dtype=bool)
    p = np.full((h, w, 3), np.nan)
    src = (slice(max(r0, 0), min(r1, h_img)), slice(max(c0, 0), min(c1, w_img)))
    dst = (slice(src[0].start - r0, src[0].stop - r0), slice(src[1].start - c0, src[1].stop - c0))
    ok[dst] = valid[src]
    p[dst] = np.asarray(points_cam[src], dtype=np.float64)
    p[~ok] = np.nan
    off_image = np.ones((h, w), dtype=bool)
    off_image[dst] = False
    z = p[..., 2]

    slope = math.tan(math.radians(max_angle_deg)) / float(focal_px)

    def joined(z1: np.ndarray, z2: np.ndarray, d_px: float) -> np.ndarray:
        with np.errstate(invalid="ignore"):
            limit = np.fmin(z1, z2)
            limit *= slope * d_px
            if min_jump_m > 0:
                np.maximum(limit, min_jump_m, out=limit)
            return np.abs(z1 - z2) <= limit  # False where either is NaN

    za, zb, zc, zd = z[:-1, :-1], z[:-1, 1:], z[1:, :-1], z[1:, 1:]  # square corners: a b / c d
    ab, cd = joined(za, zb, 1.0), joined(zc, zd, 1.0)
    ac, bd = joined(za, zc, 1.0), joined(zb, zd, 1.0)
    ad, bc = joined(za, zd, _SQRT2), joined(zb, zc, _SQRT2)
    with np.errstate(invalid="ignore"):
        use_ad = np.abs(za - zd) < np.abs(zb - zc)  # split along the flatter diagonal
    t_acb, t_bcd = ac & bc & ab, bc & cd & bd
    t_acd, t_adb = ac & cd & ad, ad & bd & ab
    split_bc_any = t_acb | t_bcd
    split_ad_any = t_acd | t_adb
    # preferred split; if it lost both triangles (a missing corner), the other split's survivor
    k_acb = t_acb & (~use_ad | ~split_ad_any)
    k_bcd = t_bcd & (~use_ad | ~split_ad_any)
    k_acd = t_acd & (use_ad | ~split_bc_any)
    k_adb = t_adb & (use_ad | ~split_bc_any)

    lin = np.arange(h * w).reshape(h, w)
    corner_a = lin[:-1, :-1].ravel()

    def triangles(keep: np.ndarray, *corners: int) -> np.ndarray:
        # corners as offsets from the square's top-left pixel a: b = +1, c = +w, d = +w+1
        a = corner_a[np.flatnonzero(keep)]
        return a[:, None] + np.array(corners)[None, :]

    faces = np.concatenate([triangles(k_acb, 0, w, 1), triangles(k_bcd, 1, w, w + 1),
                            triangles(k_acd, 0, w, w + 1), triangles(k_adb, 0, w + 1, 1)])
    vertices = p.reshape(-1, 3)
    if boundary != "none":
        edges = _boundary_edges(k_acb, k_bcd, k_acd, k_adb, lin)
        if edges[0].size:
            sk_vertices, sk_faces = _skirt(edges, p, ok, off_image, z, focal_px, boundary, hole_max_px, h * w)
            vertices = np.concatenate([vertices, sk_vertices])
            faces = np.concatenate([faces, sk_faces])
    # compact: keep used vertices only
    used = np.zeros(len(vertices), dtype=bool)
    used[faces.ravel()] = True
    used[: h * w] |= ok.ravel()
    remap = np.cumsum(used) - 1
    return TriangleMesh(vertices[used], remap[faces].astype(np.int32))


def _boundary_edges(k_acb, k_bcd, k_acd, k_adb, lin):
    """Edges used by exactly one kept triangle.

    Returns
    -------
    v1, v2, v3 : (e,) int64
        Edge endpoints in the order of their triangle (counter-clockwise seen from the camera) and
        the triangle's third (inner) vertex, as linear indices of the padded crop.
    out1, out2 : (e,) int64
        The pixel(s) just beyond the edge (equal for diagonal edges).
    d_px : (e,) float64
        Distance from the inner vertex to the edge line, pixels (1 for axis edges, 1/√2 diagonal).
    """
    w = lin.shape[1]
    f = lambda m: m.astype(np.int8)  # noqa: E731
    pad_top = np.zeros((1, k_acb.shape[1]), np.int8)
    pad_left = np.zeros((k_acb.shape[0], 1), np.int8)
    # usage counts of horizontal edges (rows 0..h-1, cols 0..w-2) from the square below and above
    top_use = f(k_acb) + f(k_adb)            # edge a-b of square (i, j) is the top edge
    bottom_use = f(k_bcd) + f(k_acd)         # edge c-d of square (i, j) is the bottom edge
    h_count = np.concatenate([top_use, pad_top]) + np.concatenate([pad_top, bottom_use])
    left_use = f(k_acb) + f(k_acd)           # edge a-c of square (i, j)
    right_use = f(k_bcd) + f(k_adb)          # edge b-d of square (i, j)
    v_count = np.concatenate([left_use, pad_left], axis=1) + np.concatenate([pad_left, right_use], axis=1)
    d1_count = f(k_acd) + f(k_adb)
    d2_count = f(k_acb) + f(k_bcd)

    # corners of square (i, j) as offsets from its top-left pixel a: b = a + 1, c = a + w, d = a + w + 1
    ia, ib, ic, id_ = 0, 1, w, w + 1
    up, down, left, right = -w, w, -1, 1
    corner_a = lin[:-1, :-1].ravel()
    parts = []

    def add(mask, v1, v2, v3, o1, o2, d_px):
        a = corner_a[np.flatnonzero(mask)]
        parts.append(tuple(a + x for x in (v1, v2, v3, o1, o2)) + (np.full(a.size, d_px),))

    hb_top = h_count[:-1] == 1     # top edge of square (i, j) on the boundary
    hb_bottom = h_count[1:] == 1   # bottom edge of square (i, j)
    vb_left = v_count[:, :-1] == 1
    vb_right = v_count[:, 1:] == 1
    # triangle (a, c, b): edges a→c (left), c→b (diagonal b-c), b→a (top)
    add(k_acb & hb_top, ib, ia, ic, ia + up, ib + up, 1.0)
    add(k_acb & vb_left, ia, ic, ib, ia + left, ic + left, 1.0)
    add(k_acb & (d2_count == 1), ic, ib, ia, id_, id_, 1 / _SQRT2)
    # triangle (b, c, d): edges b→c (diagonal), c→d (bottom), d→b (right)
    add(k_bcd & hb_bottom, ic, id_, ib, ic + down, id_ + down, 1.0)
    add(k_bcd & vb_right, id_, ib, ic, id_ + right, ib + right, 1.0)
    add(k_bcd & (d2_count == 1), ib, ic, id_, ia, ia, 1 / _SQRT2)
    # triangle (a, c, d): edges a→c (left), c→d (bottom), d→a (diagonal a-d)
    add(k_acd & vb_left, ia, ic, id_, ia + left, ic + left, 1.0)
    add(k_acd & hb_bottom, ic, id_, ia, ic + down, id_ + down, 1.0)
    add(k_acd & (d1_count == 1), id_, ia, ic, ib, ib, 1 / _SQRT2)
    # triangle (a, d, b): edges a→d (diagonal), d→b (right), b→a (top)
    add(k_adb & (d1_count == 1), ia, id_, ib, ic, ic, 1 / _SQRT2)
    add(k_adb & vb_right, id_, ib, ia, id_ + right, ib + right, 1.0)
    add(k_adb & hb_top, ib, ia, id_, ia + up, ib + up, 1.0)
    return tuple(np.concatenate([part[k] for part in parts]) for k in range(6))


def _skirt(edges, p, ok, off_image, z, focal_px, boundary, hole_max_px, n_pixels):
    """Skirt vertices (2 per edge) and faces (2 per edge) beyond the boundary edges."""
    v1, v2, v3, o1, o2, d_px = edges
    pf = p.reshape(-1, 3)
    zf = z.ravel()
    okf = ok.ravel()
    mid = 0.5 * (pf[v1] + pf[v2])
    inner = pf[v3]
    step = mid - inner                       # from the inner vertex to the edge, across the edge
    z_mid = mid[:, 2]
    pitch_m = d_px * z_mid / focal_px        # metric distance inner vertex -> edge line
    # footprint skirt: the surface continued along its slope up to the pixel footprints' border
    # (half a pixel beyond an axis edge; a quarter of the step beyond a diagonal one)
    k_planar = np.where(d_px == 1.0, 0.5, 0.25)
    offset = step * k_planar[:, None]
    if boundary == "contour":
        holes = _small_holes(ok, off_image, hole_max_px).ravel()
        offf = off_image.ravel()
        state_far = np.zeros(len(v1), dtype=bool)
        state_block = np.zeros(len(v1), dtype=bool)
        for o in (o1, o2):
            background = ~okf[o] & ~holes[o] & ~offf[o]
            with np.errstate(invalid="ignore"):
                farther = okf[o] & (zf[o] > z_mid)
            state_far |= background | farther
            state_block |= holes[o] | offf[o] | (okf[o] & ~farther)
        contour = state_far & ~state_block
        if contour.any():
            dz = np.maximum(step[contour, 2], 0.0)
            length = pitch_m[contour] * contour_arc_pitches(dz / pitch_m[contour])
            ray = mid[contour] / np.linalg.norm(mid[contour], axis=1, keepdims=True)
            lateral = step[contour] - np.einsum("ij,ij->i", step[contour], ray)[:, None] * ray
            lateral /= np.maximum(np.linalg.norm(lateral, axis=1, keepdims=True), 1e-12)
            # chord towards the contour: half the pitch sideways (its expected position), the rest back
            side = np.minimum(0.5 * pitch_m[contour], length)
            back = np.sqrt(np.maximum(length**2 - side**2, 0.0))
            offset[contour] = lateral * side[:, None] + ray * back[:, None]
    n = len(v1)
    outer1 = pf[v1] + offset
    outer2 = pf[v2] + offset
    new = np.concatenate([outer1, outer2])
    i1 = n_pixels + np.arange(n)
    i2 = n_pixels + n + np.arange(n)
    faces = np.concatenate([np.stack([v2, v1, i1], axis=1), np.stack([v2, i1, i2], axis=1)])
    return new, faces


def _small_holes(ok: np.ndarray, off_image: np.ndarray, hole_max_px: int) -> np.ndarray:
    """(h, w) bool: pixels without return in enclosed regions of at most ``hole_max_px`` pixels."""
    if hole_max_px <= 0:
        return np.zeros_like(ok)
    labels, n = ndimage.label(~ok)
    if n == 0:
        return np.zeros_like(ok)
    sizes = np.bincount(labels.ravel(), minlength=n + 1)
    touching = np.zeros(n + 1, dtype=bool)
    border = np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1], labels[off_image]])
    touching[border] = True
    small = (sizes <= hole_max_px) & ~touching
    small[0] = False
    return small[labels]


@lru_cache(maxsize=1)
def _contour_table() -> tuple[np.ndarray, np.ndarray]:
    """Mean depth step across the last pixel and mean hidden arc length, both in pitches, for
    circular profiles of radius 1..10⁶ pitches with the contour uniformly placed within a pitch."""
    e = (np.arange(1024) + 0.5) / 1024.0
    radius = np.geomspace(1.0, 1e6, 400)[:, None]
    dz = (np.sqrt(np.maximum(2 * radius * (e + 1) - (e + 1) ** 2, 0.0))
          - np.sqrt(np.maximum(2 * radius * e - e * e, 0.0))).mean(axis=1)
    arc = (radius * np.arccos(1.0 - e / radius)).mean(axis=1)
    return dz, arc


def contour_arc_pitches(depth_step_pitches: np.ndarray) -> np.ndarray:
    """Expected surface length between the last pixel and an occluding contour.

    Model: the surface across the contour is a circular arc of unknown radius that ends
    perpendicular to the viewing ray, and the contour lies anywhere within one pixel pitch beyond
    the last pixel. Averaged over that position, the depth step from the inner pixel to the last
    one and the hidden arc length both grow with the radius; this inverts one into the other.
    For steep contours the arc is ≈ 1.207 × the depth step; for a flat step it is 1 pitch.

    Parameters
    ----------
    depth_step_pitches : (n,) float
        Depth increase from the inner pixel to the boundary pixel, in units of their lateral distance.

    Returns
    -------
    (n,) float64
        Arc length beyond the boundary pixel, in the same units.
    """
    dz, arc = _contour_table()
    x = np.maximum(np.asarray(depth_step_pitches, dtype=np.float64), 0.0)
    out = np.interp(x, dz, arc)
    steep = x > dz[-1]
    out[steep] = x[steep] * (arc[-1] / dz[-1])
    return out
