"""NVIDIA Warp kernels of the Warp back end: every view of one body in a few compiled passes (CPU or CUDA).

(About 950 lines, above the project's ~400: the passes, their shared structs and device functions stay one
Warp module, compiled and cached as one unit; about 400 of the lines are the functions' Parameters sections.)

One ray per pixel centre through ``K⁻¹ [u, v, 1]`` finds the nearest triangle whose projection holds
that centre, so for a view with the whole mesh in front of the camera the pixel rays are answered by
*rasterizing* the triangles: each triangle visits the pixel centres inside its projected bounding box,
tests them with three edge functions (float64) and keeps the nearest z-depth per pixel with one atomic
minimum on a 64-bit key (quantized depth, triangle id), which gives the same answer in any order (the
same bits on CPU and GPU threads). The grazing triangles' visibility rays that the depth buffer cannot
decide are any-hit queries to Warp's BVH (rasterizing them as well costs more: near a silhouette many
thin triangles overlap each point).

Passes, each launched over (view, item) for a batch of views of one body:

1. :func:`project_vertices` — camera coordinates and pixel coordinates of every vertex, per-view bounds;
2. :func:`hole_boxes`, :func:`raster_triangles` — the grazing triangles and how finely to sample each;
   the nearest triangle per pixel (keys);
3. :func:`resolve_pixels` — per grid row: depth, pixel count, footprint sum ``z³ / h``, border pixels,
   the triangles hit;
4. (``warp.utils.array_scan``) the first slot of every grazing triangle's points;
5. :func:`grazing_points` — their points (centroids, or sub-triangle centroids of large triangles)
   decided from the depth buffer, each in a slot of its own (an exclusive scan of the points per view and
   triangle), the undecided ones with their any-hit ray; :func:`anyhit_queries` — those rays through Warp's
   BVH (on a GPU);
6. :func:`reduce_triangles` — per chunk of triangles: hit area, triangles hit, and the grazing triangles'
   visible area (area × visible share).

Sums are taken per row or per chunk in a fixed order and added up on the host, so the results do not
depend on thread scheduling. Importing this module imports Warp (and compiles the kernels on first use,
cached in Warp's kernel cache).
"""

from __future__ import annotations

import warp as wp

# No adjoints; no fused multiply-adds, so float32 sums round as numpy's (same order, same bits).
wp.set_module_options({"enable_backward": False, "fuse_fp": False})

f64 = wp.float64

#: Key of a pixel no triangle covers.
EMPTY_KEY = wp.constant(wp.uint64(0xFFFFFFFFFFFFFFFF))
#: Depth quantization of the keys: z · 2^24 in 32 bits (6e-8 m steps up to 256 m).
DEPTH_SCALE = wp.constant(wp.float64(16777216.0))
DEPTH_KEY_MAX = wp.constant(wp.float64(4294967295.0))


@wp.struct
class Camera:
    """Pinhole intrinsics (pixels) and the grazing-triangle settings shared by a batch of views."""

    fx: wp.float64
    fy: wp.float64
    cx: wp.float64
    cy: wp.float64
    skew: wp.float64
    width: int
    height: int
    grazing_cos: wp.float32    # as the reference compares its float32 cosines
    split_px: wp.float64       # < 0: never split
    sample_px: wp.float64
    max_split: int
    clear_px: wp.float32
    hidden_px: wp.float32
    footprint: wp.float32      # float32(√(fx · fy)): a pixel footprint at depth z is z / footprint
    t_tol: wp.float64
    one_sided: int
    sign: wp.float64           # orientation sign: sign · (e01 × e02) points outward
    cull: int                  # 1: skip back faces away from holes in a one-sided scene (exact); 0: raster all


@wp.func
def to_pixel(cam: Camera, X: wp.vec3d):
    """Image coordinates (u, v) of a camera-frame point with X[2] > 0.

    Parameters
    ----------
    cam : Camera
        The batch's intrinsics and grazing settings.
    X : wp.vec3d
        Camera-frame point, metres.

    Returns
    -------
    (wp.float64, wp.float64)
        u, v in pixels.
    """
    y = X[1] / X[2]
    return cam.fx * X[0] / X[2] + cam.skew * y + cam.cx, cam.fy * y + cam.cy


@wp.func
def ray_depth(cam: Camera, n: wp.vec3d, w: wp.float64, px: wp.float64, py: wp.float64):
    """z-depth at which the ray of pixel (px, py) meets the plane n · X = w.

    Parameters
    ----------
    cam : Camera
        The batch's intrinsics and grazing settings.
    n : wp.vec3d
        Normal of the plane (any length), camera frame.
    w : wp.float64
        n · X of any point X of the plane.
    px, py : wp.float64
        Pixel coordinates (u, v).

    Returns
    -------
    wp.float64
        z in metres (not finite where the ray is parallel to the plane).
    """
    yn = (py - cam.cy) / cam.fy
    xn = (px - cam.cx - cam.skew * yn) / cam.fx
    return w / (n[0] * xn + n[1] * yn + n[2])


@wp.func
def depth_key(z: wp.float64, tri: int):
    """Key of a hit of triangle ``tri`` at depth z: the depth quantized to z · 2^24 (clamped to [0, 2^32 − 1])
    in the high 32 bits, the triangle in the low 32, so the smallest key is the nearest hit (ties: the lowest id).

    Parameters
    ----------
    z : wp.float64
        z-depth, metres.
    tri : int
        Triangle index (< 2^32).

    Returns
    -------
    wp.uint64
    """
    q = wp.min(wp.max(z * DEPTH_SCALE, f64(0.0)), DEPTH_KEY_MAX)
    return (wp.uint64(q) << wp.uint64(32)) | wp.uint64(tri)


@wp.func
def key_triangle(key: wp.uint64):
    """The triangle index of a key (its low 32 bits; :func:`depth_key`).

    Parameters
    ----------
    key : wp.uint64
        A key other than ``EMPTY_KEY``.

    Returns
    -------
    int
    """
    return int(key & wp.uint64(0xFFFFFFFF))


@wp.func
def inside_triangle(ax: wp.float64, ay: wp.float64, bx: wp.float64, by: wp.float64, cx: wp.float64,
                    cy: wp.float64, area: wp.float64, px: wp.float64, py: wp.float64):
    """Whether (px, py) lies in the projected triangle (edges included), either orientation.

    Parameters
    ----------
    ax, ay, bx, by, cx, cy : wp.float64
        The projected vertices a, b, c, pixels.
    area : wp.float64
        (b − a) × (c − a): twice the signed projected area, pixels²; its sign gives the orientation.
    px, py : wp.float64
        The pixel centre, pixels.

    Returns
    -------
    bool
    """
    e0 = (cx - bx) * (py - by) - (cy - by) * (px - bx)
    e1 = (ax - cx) * (py - cy) - (ay - cy) * (px - cx)
    e2 = (bx - ax) * (py - ay) - (by - ay) * (px - ax)
    zero = f64(0.0)
    if area > zero:
        return e0 >= zero and e1 >= zero and e2 >= zero
    return e0 <= zero and e1 <= zero and e2 <= zero


#: Columns of the per-view float32 terms ``vt`` (host: :func:`wbsa.camera.backends.warp_backend._view_terms`):
#: C − centre (0–2), −2 (C − centre) (3–5), |C − centre|² (6), K·R row-major (7–15), K·(R·centre + T) (16–18).
N_VIEW_TERMS = 19


@wp.func
def facing_height(vt: wp.array2d(dtype=wp.float32), b: int, soa: wp.array2d(dtype=wp.float32), tri: int):
    """h = n · (C − c) of a triangle, float32, operation for operation as
    :func:`wbsa.camera.area.triangle_view_terms` (``soa``: the scene's per-triangle float32 columns).

    Parameters
    ----------
    vt : (B, 19) wp.array2d(dtype=wp.float32)
        Per-view terms (columns: :data:`N_VIEW_TERMS`).
    b : int
        View index.
    soa : (8, m) wp.array2d(dtype=wp.float32)
        Per-triangle columns, relative to the scene centre: outward normal n (0–2), centroid c (3–5), n · c (6),
        |c|² (7).
    tri : int
        Triangle index.

    Returns
    -------
    wp.float32
        h in metres (n unit, outward; C the camera centre).
    """
    h = vt[b, 0] * soa[0, tri]
    h = h + vt[b, 1] * soa[1, tri]
    h = h + vt[b, 2] * soa[2, tri]
    return h - soa[6, tri]


@wp.func
def facing_dist2(vt: wp.array2d(dtype=wp.float32), b: int, soa: wp.array2d(dtype=wp.float32), tri: int):
    """d = max(|C − c|², 1e-30) of a triangle, float32, as :func:`wbsa.camera.area.triangle_view_terms`;
    the triangle's cos θ is h / √d (:func:`below_grazing`).

    Parameters
    ----------
    vt, b, soa, tri
        As in :func:`facing_height`.

    Returns
    -------
    wp.float32
        d in m².
    """
    d = vt[b, 3] * soa[3, tri]
    d = d + vt[b, 4] * soa[4, tri]
    d = d + vt[b, 5] * soa[5, tri]
    d = d + soa[7, tri]
    d = d + vt[b, 6]
    return wp.max(d, wp.float32(1.0e-30))


@wp.func
def facing(vt: wp.array2d(dtype=wp.float32), b: int, soa: wp.array2d(dtype=wp.float32), tri: int):
    """(h, d) of a triangle (:func:`facing_height`, :func:`facing_dist2`).

    Parameters
    ----------
    vt, b, soa, tri
        As in :func:`facing_height`.

    Returns
    -------
    (wp.float32, wp.float32)
    """
    return facing_height(vt, b, soa, tri), facing_dist2(vt, b, soa, tri)


@wp.func
def below_grazing(cam: Camera, h: wp.float32, d: wp.float32):
    """|cos θ| < g for cos θ = h / √d rounded in float32 as the reference does; the root and the division
    are taken only within 2 % of the threshold (elsewhere h² against g² d decides: the same answer).

    Parameters
    ----------
    cam : Camera
        Its ``grazing_cos`` is g.
    h : wp.float32
        n · (C − c) of the triangle (:func:`facing_height`).
    d : wp.float32
        max(|C − c|², 1e-30) of the triangle (:func:`facing_dist2`).

    Returns
    -------
    bool
    """
    hh = f64(h) * f64(h)
    gg = f64(cam.grazing_cos) * f64(cam.grazing_cos) * f64(d)
    if hh < f64(0.98) * gg:
        return True
    if hh > f64(1.02) * gg:
        return False
    return wp.abs(h / wp.sqrt(d)) < cam.grazing_cos


@wp.func
def is_grazing(cam: Camera, h: wp.float32, d: wp.float32):
    """One-sided scene: 0 < cos θ < g; otherwise |cos θ| < g (as :func:`wbsa.camera.grazing.grazing_area_m2`).

    Parameters
    ----------
    cam : Camera
        Its ``one_sided`` and ``grazing_cos`` (g).
    h : wp.float32
        n · (C − c) of the triangle (:func:`facing_height`).
    d : wp.float32
        max(|C − c|², 1e-30) of the triangle (:func:`facing_dist2`).

    Returns
    -------
    bool
    """
    if cam.one_sided != 0:
        return h > wp.float32(0.0) and below_grazing(cam, h, d)
    return below_grazing(cam, h, d)


@wp.func
def project32(vt: wp.array2d(dtype=wp.float32), b: int, P: wp.vec3):
    """(u, v, z) float32 of a point relative to the scene centre, as :func:`wbsa.camera.roi.homogeneous_pixels`.

    Parameters
    ----------
    vt : (B, 19) wp.array2d(dtype=wp.float32)
        Per-view terms (columns: :data:`N_VIEW_TERMS`).
    b : int
        View index.
    P : wp.vec3
        Point relative to the scene centre, metres, float32.

    Returns
    -------
    (wp.float32, wp.float32, wp.float32)
        u, v in pixels, z in metres.
    """
    uz = vt[b, 7] * P[0]
    uz = uz + vt[b, 8] * P[1]
    uz = uz + vt[b, 9] * P[2]
    uz = uz + vt[b, 16]
    vz = vt[b, 10] * P[0]
    vz = vz + vt[b, 11] * P[1]
    vz = vz + vt[b, 12] * P[2]
    vz = vz + vt[b, 17]
    z = vt[b, 13] * P[0]
    z = z + vt[b, 14] * P[1]
    z = z + vt[b, 15] * P[2]
    z = z + vt[b, 18]
    return uz / z, vz / z, z


@wp.kernel
def project_vertices(verts: wp.array(dtype=wp.vec3f), rot: wp.array(dtype=wp.mat33d), trans: wp.array(dtype=wp.vec3d),
                     cam: Camera, xyz: wp.array2d(dtype=wp.vec3d), uv: wp.array2d(dtype=wp.vec2d),
                     lo: wp.array2d(dtype=wp.float64), hi: wp.array2d(dtype=wp.float64),
                     behind: wp.array(dtype=int), chunk: int):
    """Camera coordinates and pixel coordinates of every vertex in every view (``chunk`` vertices per
    thread); per-view pixel bounds (atomic minimum and maximum of each chunk's). Launched over
    (B, ⌈n / chunk⌉).

    Parameters
    ----------
    verts : (n,) wp.array(dtype=wp.vec3f)
        Vertices relative to the scene centre, metres, float32.
    rot : (B,) wp.array(dtype=wp.mat33d)
        World-to-camera rotation R of each view.
    trans : (B,) wp.array(dtype=wp.vec3d)
        R · centre + T of each view, metres: R · p + trans is the camera-frame point of a point p relative to
        the scene centre.
    cam : Camera
        The batch's intrinsics and grazing settings.
    xyz : (B, n) wp.array2d(dtype=wp.vec3d)
        Out: camera-frame vertices, metres.
    uv : (B, n) wp.array2d(dtype=wp.vec2d)
        Out: pixel coordinates (u, v); (0, 0) for a vertex with z ≤ 1e-6 m.
    lo : (B, 2) wp.array2d(dtype=wp.float64)
        In/out: smallest (u, v) of the view's vertices in front of the camera (start at +inf).
    hi : (B, 2) wp.array2d(dtype=wp.float64)
        In/out: largest (u, v) (start at −inf).
    behind : (B,) wp.array(dtype=int)
        In/out: set to 1 for a view with a vertex at z ≤ 1e-6 m (start at 0).
    chunk : int
        Vertices per thread.
    """
    b, k = wp.tid()
    n = verts.shape[0]
    inf = f64(wp.inf)
    umin = inf
    vmin = inf
    umax = -inf
    vmax = -inf
    back = int(0)
    for i in range(k * chunk, wp.min(k * chunk + chunk, n)):
        X = rot[b] * wp.vec3d(verts[i]) + trans[b]
        xyz[b, i] = X
        if X[2] <= f64(1.0e-6):
            back = 1
            uv[b, i] = wp.vec2d(f64(0.0), f64(0.0))
        else:
            u, v = to_pixel(cam, X)
            uv[b, i] = wp.vec2d(u, v)
            umin = wp.min(umin, u)
            vmin = wp.min(vmin, v)
            umax = wp.max(umax, u)
            vmax = wp.max(vmax, v)
    if back != 0:
        wp.atomic_max(behind, b, 1)
    wp.atomic_min(lo, b, 0, umin)
    wp.atomic_min(lo, b, 1, vmin)
    wp.atomic_max(hi, b, 0, umax)
    wp.atomic_max(hi, b, 1, vmax)


@wp.kernel
def hole_boxes(hole_vertices: wp.array(dtype=int), hole_start: wp.array(dtype=int),
               hole_centroids: wp.array(dtype=wp.vec3d), uv: wp.array2d(dtype=wp.vec2d), rot: wp.array(dtype=wp.mat33d),
               trans: wp.array(dtype=wp.vec3d), cam: Camera, boxes: wp.array2d(dtype=wp.vec4d)):
    """Pixel box (u_min, u_max, v_min, v_max) of each hole's cap in each view: its boundary vertices and the
    centroid of the fan that closes it (the whole image if the centroid is behind the camera). Launched over
    (B, n_holes).

    Parameters
    ----------
    hole_vertices : (n_boundary,) wp.array(dtype=int)
        Indices of the boundary vertices of every hole, one hole after another.
    hole_start : (n_holes + 1,) wp.array(dtype=int)
        Where each hole's vertices start in ``hole_vertices`` (and the end).
    hole_centroids : (n_holes,) wp.array(dtype=wp.vec3d)
        Mean of each hole's boundary vertices, relative to the scene centre, metres.
    uv : (B, n) wp.array2d(dtype=wp.vec2d)
        Pixel coordinates (u, v) of the vertices (:func:`project_vertices`).
    rot : (B,) wp.array(dtype=wp.mat33d)
        World-to-camera rotation R of each view.
    trans : (B,) wp.array(dtype=wp.vec3d)
        R · centre + T of each view, metres: R · p + trans is the camera-frame point of a point p relative to
        the scene centre.
    cam : Camera
        The batch's intrinsics and grazing settings.
    boxes : (B, n_holes) wp.array2d(dtype=wp.vec4d)
        Out: the boxes, pixels.
    """
    b, h = wp.tid()
    X = rot[b] * hole_centroids[h] + trans[b]
    if X[2] <= f64(1.0e-6):
        boxes[b, h] = wp.vec4d(f64(-1.0e30), f64(1.0e30), f64(-1.0e30), f64(1.0e30))
        return
    u0, v0 = to_pixel(cam, X)
    box = wp.vec4d(u0, u0, v0, v0)
    for k in range(hole_start[h], hole_start[h + 1]):
        p = uv[b, hole_vertices[k]]
        box = wp.vec4d(wp.min(box[0], p[0]), wp.max(box[1], p[0]), wp.min(box[2], p[1]), wp.max(box[3], p[1]))
    boxes[b, h] = box


@wp.func
def raster_triangle(faces: wp.array(dtype=wp.vec3i), xyz: wp.array2d(dtype=wp.vec3d), uv: wp.array2d(dtype=wp.vec2d),
                     soa: wp.array2d(dtype=wp.float32), edges: wp.array(dtype=wp.float64),
                     vt: wp.array2d(dtype=wp.float32), cam: Camera, grids: wp.array(dtype=wp.vec4i),
                     offsets: wp.array(dtype=int), boxes: wp.array2d(dtype=wp.vec4d), keys: wp.array(dtype=wp.uint64),
                     split: wp.array2d(dtype=int), n_points: wp.array(dtype=wp.int64), b: int, tri: int):
    """Triangle ``tri`` of view ``b`` (:func:`raster_triangles`).

    Parameters
    ----------
    faces, xyz, uv, soa, edges, vt, cam, grids, offsets, boxes, keys, split, n_points
        As in :func:`raster_triangles`.
    b : int
        View index.
    tri : int
        Triangle index.
    """
    height = facing_height(vt, b, soa, tri)
    s = int(0)
    # (in a one-sided scene a back face is never grazing: its distance need not be computed)
    if (cam.one_sided == 0 or height > wp.float32(0.0)) and is_grazing(cam, height, facing_dist2(vt, b, soa, tri)):
        s = 1
        if cam.split_px >= f64(0.0):  # as wbsa.camera.grazing.split_counts
            u, v, zc = project32(vt, b, wp.vec3(soa[3, tri], soa[4, tri], soa[5, tri]))
            nearest = f64(zc) - edges[tri]
            if nearest <= f64(0.0):
                s = cam.max_split
            else:
                size = wp.max(cam.fx, cam.fy) * edges[tri] / nearest
                if size > cam.split_px:
                    s = wp.min(int(wp.ceil(wp.min(size, f64(1.0e9)) / cam.sample_px)), cam.max_split)
    split[b, tri] = s
    n_points[b * split.shape[1] + tri] = wp.int64(s * s)
    g = grids[b]
    if g[3] <= 2:
        return
    f = faces[tri]
    a = uv[b, f[0]]
    p = uv[b, f[1]]
    q = uv[b, f[2]]
    umin = wp.min(a[0], wp.min(p[0], q[0]))
    umax = wp.max(a[0], wp.max(p[0], q[0]))
    c0 = wp.max(int(wp.ceil(umin)), g[1] + 1)
    c1 = wp.min(int(wp.floor(umax)), g[1] + g[2] - 2)
    if c1 < c0:
        return
    vmin = wp.min(a[1], wp.min(p[1], q[1]))
    vmax = wp.max(a[1], wp.max(p[1], q[1]))
    r0 = wp.max(int(wp.ceil(vmin)), g[0] + 1)
    r1 = wp.min(int(wp.floor(vmax)), g[0] + g[3] - 2)
    if r1 < r0:
        return
    if cam.cull != 0 and cam.one_sided != 0 and height <= wp.float32(0.0):
        near_hole = int(0)
        for h in range(boxes.shape[1]):
            box = boxes[b, h]
            if umax >= box[0] and umin <= box[1] and vmax >= box[2] and vmin <= box[3]:
                near_hole = 1
        if near_hole == 0:
            return
    area = (p[0] - a[0]) * (q[1] - a[1]) - (p[1] - a[1]) * (q[0] - a[0])
    if area == f64(0.0):
        return
    X0 = xyz[b, f[0]]
    n = wp.cross(xyz[b, f[1]] - X0, xyz[b, f[2]] - X0)
    w = wp.dot(n, X0)
    base = offsets[b]
    for row in range(r0, r1 + 1):
        py = f64(row)
        for col in range(c0, c1 + 1):
            px = f64(col)
            if inside_triangle(a[0], a[1], p[0], p[1], q[0], q[1], area, px, py):
                z = ray_depth(cam, n, w, px, py)
                if z > f64(0.0):
                    cell = base + (row - g[0]) * g[2] + (col - g[1])
                    wp.atomic_min(keys, cell, depth_key(z, tri))


@wp.kernel
def raster_triangles(faces: wp.array(dtype=wp.vec3i), xyz: wp.array2d(dtype=wp.vec3d), uv: wp.array2d(dtype=wp.vec2d),
                     soa: wp.array2d(dtype=wp.float32), edges: wp.array(dtype=wp.float64),
                     vt: wp.array2d(dtype=wp.float32), cam: Camera, grids: wp.array(dtype=wp.vec4i),
                     offsets: wp.array(dtype=int), boxes: wp.array2d(dtype=wp.vec4d), keys: wp.array(dtype=wp.uint64),
                     split: wp.array2d(dtype=int), n_points: wp.array(dtype=wp.int64), chunk: int):
    """Classify a triangle (grazing: sub-triangles per side in ``split`` and its s² points in ``n_points``,
    flat over (view, triangle); else 0) and write its depth keys at every pixel centre its projection holds
    (atomic minimum); ``chunk`` triangles per thread.

    ``grids[b]`` = (v0, u0, stride, n_rows) of view b's pixel grid (an empty border of one cell on each side).
    In a one-sided scene (closed, outward surface) a back face can be the first hit only of a ray that
    enters through a hole, so back faces outside every hole's cap box (``boxes``) are not rasterized.

    Parameters
    ----------
    faces : (m,) wp.array(dtype=wp.vec3i)
        Vertex indices of each triangle.
    xyz : (B, n) wp.array2d(dtype=wp.vec3d)
        Camera-frame vertices, metres (:func:`project_vertices`).
    uv : (B, n) wp.array2d(dtype=wp.vec2d)
        Pixel coordinates (u, v) of the vertices (:func:`project_vertices`).
    soa : (8, m) wp.array2d(dtype=wp.float32)
        Per-triangle columns, relative to the scene centre: outward normal n (0–2), centroid c (3–5), n · c (6),
        |c|² (7).
    edges : (m,) wp.array(dtype=wp.float64)
        Longest edge of each triangle, metres.
    vt : (B, 19) wp.array2d(dtype=wp.float32)
        Per-view terms (columns: :data:`N_VIEW_TERMS`).
    cam : Camera
        The batch's intrinsics and grazing settings.
    grids : (B,) wp.array(dtype=wp.vec4i)
        (v0, u0, stride, n_rows) of each view's pixel grid.
    offsets : (B,) wp.array(dtype=int)
        First cell of each view's grid in the flat cell arrays (``keys``, ``depth``).
    boxes : (B, n_holes) wp.array2d(dtype=wp.vec4d)
        Pixel box of each hole's cap (:func:`hole_boxes`); no column without holes.
    keys : (n_cells,) wp.array(dtype=wp.uint64)
        Depth key per grid cell of all views (:func:`depth_key`; ``EMPTY_KEY`` where no triangle).
        In/out: atomic minimum of each covered cell.
    split : (B, m) wp.array2d(dtype=int)
        Out: sub-triangles per side s of each grazing triangle, 0 for the others.
    n_points : (B · m,) wp.array(dtype=wp.int64)
        Out: s² points per (view, triangle), flat (index b · m + tri).
    chunk : int
        Triangles per thread; launched over (B, ⌈m / chunk⌉).
    """
    b, k = wp.tid()
    m = faces.shape[0]
    for tri in range(k * chunk, wp.min(k * chunk + chunk, m)):
        raster_triangle(faces, xyz, uv, soa, edges, vt, cam, grids, offsets, boxes, keys, split, n_points, b, tri)


@wp.kernel
def resolve_pixels(soa: wp.array2d(dtype=wp.float32), vt: wp.array2d(dtype=wp.float32), cam: Camera,
                   grids: wp.array(dtype=wp.vec4i), offsets: wp.array(dtype=int), keys: wp.array(dtype=wp.uint64),
                   depth: wp.array(dtype=wp.float32), seen: wp.array2d(dtype=wp.uint8),
                   n_pixels: wp.array2d(dtype=int), footprint: wp.array2d(dtype=wp.float64),
                   border: wp.array2d(dtype=int)):
    """Per grid row of a view: z-depth of each hit pixel (from its key, 6e-8 m steps), pixel count,
    Σ z³ · w over the pixels (w = 1 / |n · (C − c)| in float32 on non-grazing triangles, 0 on grazing ones,
    as :func:`wbsa.camera.area.visible_area_m2`), whether a pixel on the image border is hit; marks the
    triangles hit.

    Launched over (B, max n_rows); the grid's first and last rows (its empty border) and rows past a view's
    ``n_rows`` are not written (the host zeroes them).

    Parameters
    ----------
    soa : (8, m) wp.array2d(dtype=wp.float32)
        Per-triangle columns, relative to the scene centre: outward normal n (0–2), centroid c (3–5), n · c (6),
        |c|² (7).
    vt : (B, 19) wp.array2d(dtype=wp.float32)
        Per-view terms (columns: :data:`N_VIEW_TERMS`).
    cam : Camera
        The batch's intrinsics and grazing settings.
    grids : (B,) wp.array(dtype=wp.vec4i)
        (v0, u0, stride, n_rows) of each view's pixel grid.
    offsets : (B,) wp.array(dtype=int)
        First cell of each view's grid in the flat cell arrays (``keys``, ``depth``).
    keys : (n_cells,) wp.array(dtype=wp.uint64)
        Depth key per grid cell of all views (:func:`depth_key`; ``EMPTY_KEY`` where no triangle).
    depth : (n_cells,) wp.array(dtype=wp.float32)
        Out: z-depth of each hit cell, metres (other cells are left as they are).
    seen : (B, m) wp.array2d(dtype=wp.uint8)
        Out: set to 1 for each triangle hit (other entries are left as they are).
    n_pixels : (B, max n_rows) wp.array2d(dtype=int)
        Out: hit pixels per grid row.
    footprint : (B, max n_rows) wp.array2d(dtype=wp.float64)
        Out: Σ z³ · w per grid row (the host sums a view's rows and divides by fx · fy:
        the non-grazing part of the visible area, m²).
    border : (B, max n_rows) wp.array2d(dtype=int)
        Out: 1 for a grid row with a hit pixel on the image border.
    """
    b, r = wp.tid()
    g = grids[b]
    if r < 1 or r >= g[3] - 1:
        return
    row = g[0] + r
    base = offsets[b] + r * g[2]
    count = int(0)
    total = f64(0.0)
    edge = int(0)
    for j in range(1, g[2] - 1):
        key = keys[base + j]
        if key == EMPTY_KEY:
            continue
        tri = key_triangle(key)
        z = wp.float32((f64(key >> wp.uint64(32)) + f64(0.5)) / DEPTH_SCALE)
        depth[base + j] = z
        seen[b, tri] = wp.uint8(1)
        count += 1
        height, dist2 = facing(vt, b, soa, tri)
        if not below_grazing(cam, height, dist2):
            w = wp.float32(1.0) / wp.max(wp.abs(height), wp.float32(1.0e-30))
            z64 = f64(z)
            total += z64 * z64 * z64 * f64(w)
        col = g[1] + j
        if row == 0 or row == cam.height - 1 or col == 0 or col == cam.width - 1:
            edge = 1
    n_pixels[b, r] = count
    footprint[b, r] = total
    border[b, r] = edge


@wp.func
def lookup(depth: wp.array(dtype=wp.float32), base: int, g: wp.vec4i, row: int, col: int):
    """Depth at image pixel (row, col) of a view's grid; inf outside the grid.

    Parameters
    ----------
    depth : (n_cells,) wp.array(dtype=wp.float32)
        z-depth per grid cell, metres.
    base : int
        First cell of the view's grid in ``depth``.
    g : wp.vec4i
        (v0, u0, stride, n_rows) of the view's grid.
    row, col : int
        Image pixel.

    Returns
    -------
    wp.float32
        Metres.
    """
    r = row - g[0]
    c = col - g[1]
    if r < 0 or r >= g[3] or c < 0 or c >= g[2]:
        return wp.float32(wp.inf)
    return depth[base + r * g[2] + c]


@wp.func
def grazing_point(vt: wp.array2d(dtype=wp.float32), cam: Camera, g: wp.vec4i, base: int,
                  depth: wp.array(dtype=wp.float32), origins: wp.array(dtype=wp.vec3), C: wp.vec3, front: bool,
                  state: wp.array(dtype=int), rays: wp.array2d(dtype=wp.float32), b: int, P: wp.vec3, slot: int):
    """Decide one point P (relative to the scene centre) of a grazing triangle of view b (:func:`grazing_points`).

    Parameters
    ----------
    vt, cam, depth, origins, state, rays
        As in :func:`grazing_points`.
    g : wp.vec4i
        (v0, u0, stride, n_rows) of the view's grid.
    base : int
        First cell of the view's grid in ``depth``.
    C : wp.vec3
        The view's camera centre relative to the scene centre, metres, float32.
    front : bool
        The triangle faces the camera (always in a one-sided scene): only then can the depth buffer alone
        make the point visible.
    b : int
        View index.
    P : wp.vec3
        The point, relative to the scene centre, metres, float32.
    slot : int
        The point's index in ``state`` and ``rays``.
    """
    u, v, z = project32(vt, b, P)
    result = int(0)
    inside = z > wp.float32(0.0)
    inside = inside and u >= wp.float32(-0.5) and u < wp.float32(float(cam.width) - 0.5)
    inside = inside and v >= wp.float32(-0.5) and v < wp.float32(float(cam.height) - 0.5)
    if inside:
        col = int(wp.floor(u))
        row = int(wp.floor(v))
        d0 = lookup(depth, base, g, row, col)
        d1 = lookup(depth, base, g, row, col + 1)
        d2 = lookup(depth, base, g, row + 1, col)
        d3 = lookup(depth, base, g, row + 1, col + 1)
        near = wp.min(wp.min(d0, d1), wp.min(d2, d3))
        far = wp.max(wp.max(d0, d1), wp.max(d2, d3))
        fp = z / cam.footprint
        if front and near >= z - cam.clear_px * fp:
            result = 1
        elif far >= z - cam.hidden_px * fp:
            result = 2
            o = origins[b]
            d = P - C
            rays[slot, 0] = o[0]
            rays[slot, 1] = o[1]
            rays[slot, 2] = o[2]
            rays[slot, 3] = d[0]
            rays[slot, 4] = d[1]
            rays[slot, 5] = d[2]
    state[slot] = result


@wp.func
def grazing_triangle(split: wp.array2d(dtype=int), slots: wp.array(dtype=wp.int64), faces: wp.array(dtype=wp.vec3i),
                     verts: wp.array(dtype=wp.vec3f), soa: wp.array2d(dtype=wp.float32),
                     vt: wp.array2d(dtype=wp.float32), cam: Camera, grids: wp.array(dtype=wp.vec4i),
                     offsets: wp.array(dtype=int), depth: wp.array(dtype=wp.float32), origins: wp.array(dtype=wp.vec3),
                     centers: wp.array(dtype=wp.vec3d), state: wp.array(dtype=int), rays: wp.array2d(dtype=wp.float32),
                     b: int, tri: int, s: int):
    """The points of one grazing triangle of view b (:func:`grazing_points`): its centroid (s = 1), or the
    centroids of its s × s equal sub-triangles (as :func:`wbsa.camera.grazing.subtriangle_centroids` and
    :func:`wbsa.camera.grazing.split_area_m2`, in float64), in slot order.

    Parameters
    ----------
    split, slots, faces, verts, soa, vt, cam, grids, offsets, depth, origins, centers, state, rays
        As in :func:`grazing_points`.
    b : int
        View index.
    tri : int
        Triangle index.
    s : int
        Sub-triangles per side (``split[b, tri]``, > 0).
    """
    slot = int(slots[b * split.shape[1] + tri])
    g = grids[b]
    base = offsets[b]
    front = cam.one_sided != 0
    if not front:
        front = facing_height(vt, b, soa, tri) > wp.float32(0.0)
    C = wp.vec3(centers[b])
    if s == 1:
        grazing_point(vt, cam, g, base, depth, origins, C, front, state, rays, b,
                      wp.vec3(soa[3, tri], soa[4, tri], soa[5, tri]), slot)
        return
    f = faces[tri]
    V0 = wp.vec3d(verts[f[0]])
    V1 = wp.vec3d(verts[f[1]])
    V2 = wp.vec3d(verts[f[2]])
    third = f64(1.0) / f64(3.0)
    for i in range(s):
        for half in range(2):
            # half 0: the s − i sub-triangles pointing like the triangle; half 1: the s − i − 1 others
            for j in range(s - i - half):
                a1 = (f64(i) + third * f64(1 + half)) / f64(s)
                a2 = (f64(j) + third * f64(1 + half)) / f64(s)
                a0 = f64(1.0) - a1 - a2
                grazing_point(vt, cam, g, base, depth, origins, C, front, state, rays, b,
                              wp.vec3(V0 * a0 + V1 * a1 + V2 * a2), slot)
                slot += 1


@wp.kernel
def grazing_points(split: wp.array2d(dtype=int), slots: wp.array(dtype=wp.int64), faces: wp.array(dtype=wp.vec3i),
                   verts: wp.array(dtype=wp.vec3f), soa: wp.array2d(dtype=wp.float32), vt: wp.array2d(dtype=wp.float32),
                   cam: Camera, grids: wp.array(dtype=wp.vec4i), offsets: wp.array(dtype=int),
                   depth: wp.array(dtype=wp.float32), origins: wp.array(dtype=wp.vec3),
                   centers: wp.array(dtype=wp.vec3d), state: wp.array(dtype=int), rays: wp.array2d(dtype=wp.float32),
                   chunk: int):
    """Decide the points of the grazing triangles (``split[b, tri]`` > 0) of a chunk of ``chunk`` triangles of
    a view from the depth buffer: each one's centroid, or the centroids of its s × s equal sub-triangles
    (float32, as :func:`wbsa.camera.grazing.points_visible`), in the slots from ``slots[b · m + tri]`` on (an
    exclusive scan of the points per view and triangle). (A chunk per thread: on a CPU most threads would
    find no grazing triangle; use chunk 1 on a GPU.)

    A point in the image is visible (state 1) when none of the 2 × 2 pixels around it has a return more
    than ``clear_px`` footprints in front of it (front faces only), hidden (0) when all have one more than
    ``hidden_px`` in front, otherwise a query (2) whose any-hit ray is written to ``rays`` as the reference
    casts it: origin the camera centre in world coordinates (``origins``, float32), direction
    (point − centre) − (C − centre) in float32. Points outside the image are 0.

    Parameters
    ----------
    split : (B, m) wp.array2d(dtype=int)
        Sub-triangles per side s of each grazing triangle, 0 for the others (:func:`raster_triangles`).
    slots : (B · m,) wp.array(dtype=wp.int64)
        First slot of each (view, triangle)'s points: the exclusive scan of ``n_points``.
    faces : (m,) wp.array(dtype=wp.vec3i)
        Vertex indices of each triangle.
    verts : (n,) wp.array(dtype=wp.vec3f)
        Vertices relative to the scene centre, metres, float32.
    soa : (8, m) wp.array2d(dtype=wp.float32)
        Per-triangle columns, relative to the scene centre: outward normal n (0–2), centroid c (3–5), n · c (6),
        |c|² (7).
    vt : (B, 19) wp.array2d(dtype=wp.float32)
        Per-view terms (columns: :data:`N_VIEW_TERMS`).
    cam : Camera
        The batch's intrinsics and grazing settings.
    grids : (B,) wp.array(dtype=wp.vec4i)
        (v0, u0, stride, n_rows) of each view's pixel grid.
    offsets : (B,) wp.array(dtype=int)
        First cell of each view's grid in the flat cell arrays (``keys``, ``depth``).
    depth : (n_cells,) wp.array(dtype=wp.float32)
        z-depth per grid cell, metres; inf where no triangle (:func:`resolve_pixels`).
    origins : (B,) wp.array(dtype=wp.vec3)
        Camera centre of each view in world coordinates, metres, float32 (the rays' origins).
    centers : (B,) wp.array(dtype=wp.vec3d)
        Camera centre of each view relative to the scene centre, metres.
    state : (n_slots,) wp.array(dtype=int)
        Out: per point slot, 1 visible, 0 hidden or outside the image, 2 undecided (an any-hit query).
    rays : (n_slots, 6) wp.array2d(dtype=wp.float32)
        Out: the query points' rays, origin (0–2) and direction (3–5); written only for state 2.
    chunk : int
        Triangles per thread; launched over (B, ⌈m / chunk⌉).
    """
    b, k = wp.tid()
    m = split.shape[1]
    for tri in range(k * chunk, wp.min(k * chunk + chunk, m)):
        s = split[b, tri]
        if s != 0:
            grazing_triangle(split, slots, faces, verts, soa, vt, cam, grids, offsets, depth, origins, centers,
                             state, rays, b, tri, s)


@wp.kernel
def anyhit_queries(mesh: wp.uint64, rays: wp.array2d(dtype=wp.float32), cam: Camera, state: wp.array(dtype=int)):
    """Queries (state 2): visible (1) unless Warp's BVH finds a triangle on the segment from the camera
    centre before ``1 − t_tol`` of the way to the point, hidden (0) otherwise.

    The rays are the reference's (:func:`wbsa.camera.grazing.points_visible`, written by
    :func:`grazing_points`), against the mesh's float32 world coordinates (``mesh``), as Embree sees them.

    Parameters
    ----------
    mesh : wp.uint64
        Id of the Warp mesh (BVH) of the scene's float32 world-coordinate vertices, metres.
    rays : (n_slots, 6) wp.array2d(dtype=wp.float32)
        Origin (0–2) and direction (3–5) of each point's ray, world coordinates (:func:`grazing_points`).
    cam : Camera
        Its ``t_tol``: a hit counts before 1 − t_tol of the way to the point.
    state : (n_slots,) wp.array(dtype=int)
        In/out: each 2 becomes 1 (visible) or 0 (hidden); launched over the n_slots slots.
    """
    k = wp.tid()
    if state[k] != 2:
        return
    o = wp.vec3(rays[k, 0], rays[k, 1], rays[k, 2])
    d = wp.vec3(rays[k, 3], rays[k, 4], rays[k, 5])
    if wp.mesh_query_ray_anyhit(mesh, o, d, float(f64(1.0) - cam.t_tol)):
        state[k] = 0
    else:
        state[k] = 1


@wp.kernel
def reduce_triangles(areas: wp.array(dtype=wp.float64), seen: wp.array2d(dtype=wp.uint8), chunk: int,
                     split: wp.array2d(dtype=int), slots: wp.array(dtype=wp.int64), state: wp.array(dtype=int),
                     hit_area: wp.array2d(dtype=wp.float64), n_hit: wp.array2d(dtype=int),
                     graze: wp.array2d(dtype=wp.float64)):
    """Per view and chunk of triangles, in order: area of the triangles hit, their number, and the visible
    area of the grazing ones (area × share of visible points, ``state`` 1; ``split`` all 0 when there are none).
    Launched over (B, ⌈m / chunk⌉).

    Parameters
    ----------
    areas : (m,) wp.array(dtype=wp.float64)
        Area of each triangle, m².
    seen : (B, m) wp.array2d(dtype=wp.uint8)
        1 for the triangles hit in each view (:func:`resolve_pixels`).
    chunk : int
        Triangles per thread.
    split : (B, m) wp.array2d(dtype=int)
        Sub-triangles per side s of each grazing triangle, 0 for the others (:func:`raster_triangles`).
    slots : (B · m,) wp.array(dtype=wp.int64)
        First slot of each (view, triangle)'s points: the exclusive scan of ``n_points``.
    state : (n_slots,) wp.array(dtype=int)
        1 for a visible point (:func:`grazing_points`, :func:`anyhit_queries`).
    hit_area : (B, ⌈m / chunk⌉) wp.array2d(dtype=wp.float64)
        Out: area of the triangles hit, per chunk, m².
    n_hit : (B, ⌈m / chunk⌉) wp.array2d(dtype=int)
        Out: number of triangles hit, per chunk.
    graze : (B, ⌈m / chunk⌉) wp.array2d(dtype=wp.float64)
        Out: visible area of the grazing triangles, per chunk, m².
    """
    b, k = wp.tid()
    m = areas.shape[0]
    start = k * chunk
    end = wp.min(start + chunk, m)
    hit = f64(0.0)
    count = int(0)
    grazing = f64(0.0)
    for t in range(start, end):
        if seen[b, t] != wp.uint8(0):
            hit += areas[t]
            count += 1
        s = split[b, t]
        if s != 0:
            n = s * s
            first = int(slots[b * m + t])
            visible = int(0)
            for i in range(first, first + n):
                if state[i] == 1:
                    visible += 1
            grazing += areas[t] * f64(visible) / f64(n)
    hit_area[b, k] = hit
    n_hit[b, k] = count
    graze[b, k] = grazing


@wp.kernel
def cast_rays(mesh: wp.uint64, rays: wp.array2d(dtype=wp.float32), t_hit: wp.array(dtype=wp.float32),
              face: wp.array(dtype=int)):
    """Bare closest-hit ray casting with Warp's BVH (origin, direction per row): the Warp ray-casting floor.
    Launched over the k rays.

    Parameters
    ----------
    mesh : wp.uint64
        Id of the Warp mesh (BVH) of the scene's float32 world-coordinate vertices, metres.
    rays : (k, 6) wp.array2d(dtype=wp.float32)
        Origin (0–2) and direction (3–5) of each ray, world coordinates, metres.
    t_hit : (k,) wp.array(dtype=wp.float32)
        Out: ray parameter of the closest hit (metres for a unit direction), inf for a miss.
    face : (k,) wp.array(dtype=int)
        Out: the triangle hit, −1 for a miss.
    """
    i = wp.tid()
    o = wp.vec3(rays[i, 0], rays[i, 1], rays[i, 2])
    d = wp.vec3(rays[i, 3], rays[i, 4], rays[i, 5])
    hit = wp.mesh_query_ray(mesh, o, d, 1.0e9)
    if hit.result:
        t_hit[i] = hit.t
        face[i] = hit.face
    else:
        t_hit[i] = wp.inf
        face[i] = -1
