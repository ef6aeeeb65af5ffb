"""Independent visible areas of scenes of convex solids, for tests and accuracy benchmarks.

The visible-area estimate of :mod:`wbsa.camera.area` works on pixels, a depth buffer and ray casting. This
module answers the same question without any of them: surface points are drawn area-weighted on the
solids' faces (a stratified Monte Carlo sample, so many per face in proportion to its area) and a point
counts as visible when its face turns towards the camera, it projects into the image and no *other*
solid meets the segment from the camera centre to it (exact segment–convex-polyhedron clipping in
float64). A point on a front-facing face of a convex solid cannot be hidden by its own solid, so no
mesh of the solid is ray cast. The solids must not overlap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wbsa.camera.extrinsics import Pose
from wbsa.camera.intrinsics import Intrinsics
from helpers.shapes import box, icosphere, merge
from wbsa.core.mesh import TriangleMesh


@dataclass(frozen=True, eq=False)
class ConvexSolid:
    """A closed convex triangle mesh and its face planes.

    Attributes
    ----------
    mesh : TriangleMesh
        Counter-clockwise seen from outside.
    normals : (k, 3) float64
        Unit outward normals of the distinct face planes.
    offsets : (k,) float64
        Plane offsets: the solid is ``{x : normals @ x <= offsets}``.
    """

    mesh: TriangleMesh
    normals: np.ndarray
    offsets: np.ndarray


def convex_solid(mesh: TriangleMesh) -> ConvexSolid:
    """The :class:`ConvexSolid` of a closed convex mesh (faces counter-clockwise seen from outside)."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    f = np.asarray(mesh.faces, dtype=np.intp)
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    d = np.einsum("ij,ij->i", n, v[f[:, 0]])
    planes = np.unique(np.round(np.column_stack([n, d]), 12), axis=0)
    return ConvexSolid(mesh, planes[:, :3], planes[:, 3])


def box_solid(size_m: tuple[float, float, float], center: tuple[float, float, float]) -> ConvexSolid:
    """An axis-aligned box of two triangles per face."""
    return convex_solid(box(size_m, np.asarray(center, dtype=np.float64)))


def sphere_solid(radius_m: float, center: tuple[float, float, float], subdivisions: int = 1) -> ConvexSolid:
    """A geodesic sphere (``20 · 4**subdivisions`` flat faces)."""
    return convex_solid(icosphere(radius_m, subdivisions, np.asarray(center, dtype=np.float64)))


def scene_mesh(solids: list[ConvexSolid]) -> TriangleMesh:
    """All the solids' meshes as one mesh (the input of :class:`~wbsa.camera.scene.MeshScene`)."""
    return merge([s.mesh for s in solids])


def _segment_hits(solid: ConvexSolid, start: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """(n,) bool: whether the open segments ``start → ends`` (n, 3) meet the solid's interior (Cyrus–Beck).

    Segments that pass farther from the solid's bounding sphere than its radius are answered without clipping.
    """
    verts = np.asarray(solid.mesh.vertices, dtype=np.float64)
    centre = 0.5 * (verts.min(axis=0) + verts.max(axis=0))
    radius = float(np.linalg.norm(verts - centre, axis=1).max())
    d = ends - start                                    # (n, 3)
    s = np.clip(((centre - start) @ d.T) / np.einsum("ij,ij->i", d, d), 0.0, 1.0)
    near = np.flatnonzero(np.linalg.norm(start + s[:, None] * d - centre, axis=1) <= radius * (1 + 1e-9))
    out = np.zeros(len(ends), dtype=bool)
    if near.size:
        out[near] = _clip_segments(solid, start, d[near])
    return out


def _clip_segments(solid: ConvexSolid, start: np.ndarray, d: np.ndarray) -> np.ndarray:
    """(n,) bool: whether ``start + t d``, 0 < t < 1, enters the solid (d: (n, 3))."""
    num = solid.offsets - solid.normals @ start         # (k,): > 0 where start is inside that half-space
    den = d @ solid.normals.T                           # (n, k)
    t_in = np.zeros(len(d))
    t_out = np.ones(len(d))
    with np.errstate(divide="ignore", invalid="ignore"):
        t = num[None, :] / den
    entering = den < 0
    leaving = den > 0
    t_in = np.maximum(t_in, np.max(np.where(entering, t, -np.inf), axis=1))
    t_out = np.minimum(t_out, np.min(np.where(leaving, t, np.inf), axis=1))
    parallel_out = np.any((den == 0) & (num[None, :] <= 0), axis=1)  # parallel to a plane, outside it
    return (t_in < t_out) & ~parallel_out


def monte_carlo_visible_area_m2(solids: list[ConvexSolid], intrinsics: Intrinsics, pose: Pose,
                                n_samples: int = 1_000_000, seed: int = 0) -> tuple[float, float]:
    """Visible area of a scene of non-overlapping convex solids, by stratified Monte Carlo.

    Parameters
    ----------
    solids : list of ConvexSolid
    intrinsics : Intrinsics
        The image: a point counts only if it projects to u in [−0.5, width − 0.5), v in [−0.5, height − 0.5).
    pose : Pose
        World-to-camera transform.
    n_samples : int
        Surface points in all, shared out among the faces in proportion to their areas (at least 16 each).
    seed : int

    Returns
    -------
    area_m2, standard_error_m2 : float
    """
    rng = np.random.default_rng(seed)
    C = pose.camera_center
    k = intrinsics
    total_area = sum(s.mesh.area_m2 for s in solids)
    area = 0.0
    variance = 0.0
    for index, solid in enumerate(solids):
        v = np.asarray(solid.mesh.vertices, dtype=np.float64)
        f = np.asarray(solid.mesh.faces, dtype=np.intp)
        others = [s for j, s in enumerate(solids) if j != index]
        for a, b, c in zip(v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]):
            n = np.cross(b - a, c - a)
            tri_area = 0.5 * float(np.linalg.norm(n))
            if tri_area == 0 or float(n @ (C - (a + b + c) / 3.0)) <= 0:  # back face (planar: all or nothing)
                continue
            m = max(16, int(round(n_samples * tri_area / total_area)))
            r1, r2 = rng.random(m), rng.random(m)
            flip = r1 + r2 > 1
            r1[flip], r2[flip] = 1 - r1[flip], 1 - r2[flip]
            p = a + r1[:, None] * (b - a) + r2[:, None] * (c - a)
            x = pose.apply(p)
            with np.errstate(divide="ignore", invalid="ignore"):
                u = (k.fx * x[:, 0] + k.skew * x[:, 1]) / x[:, 2] + k.cx
                vv = k.fy * x[:, 1] / x[:, 2] + k.cy
            seen = (x[:, 2] > 0) & (u >= -0.5) & (u < k.width - 0.5) & (vv >= -0.5) & (vv < k.height - 0.5)
            for other in others:
                idx = np.flatnonzero(seen)
                if idx.size:
                    seen[idx] &= ~_segment_hits(other, C, p[idx])
            frac = float(seen.mean())
            area += tri_area * frac
            variance += tri_area**2 * frac * (1.0 - frac) / m
    return area, math.sqrt(variance)


def coarse_scenes() -> dict[str, list[ConvexSolid]]:
    """The coarse test scenes of the visible-area checks (tests and ``benchmarks/bench_raycast.py --accuracy``).

    ``boxes``: a 1.0 × 0.4 × 1.6 m box, a 0.3 m cube in front of it, a sphere (80 faces) behind it and a
    2 cm thin wall beside it; ``thin wall``: a 1.2 × 0.03 × 0.9 m wall with a sphere (320 faces) just in
    front of it, so that seen nearly edge-on one grazing face (two triangles) is partly hidden. Two
    triangles per box face.
    """
    return {
        "boxes": [box_solid((1.0, 0.4, 1.6), (0.0, 0.0, 0.0)), box_solid((0.3, 0.3, 0.3), (0.45, -0.45, 0.3)),
                  sphere_solid(0.2, (-0.5, 0.45, -0.4)), box_solid((0.02, 1.0, 0.8), (0.8, 0.1, 0.5))],
        "thin wall": [box_solid((1.2, 0.03, 0.9), (0.0, 0.0, 0.0)), sphere_solid(0.12, (0.2, -0.16, 0.15), 2)],
    }


#: (azimuth, elevation) of the coarse-scene checks: the six axis directions, oblique views, and views
#: that see the thin wall's large faces nearly edge-on.
AXIS_VIEWS = ((0, 0), (90, 0), (180, 0), (270, 0), (0, 90), (0, -90))
OBLIQUE_VIEWS = ((30, 20), (135, -35), (250, 50), (2, 0), (358, 0), (88, 5), (178, -3))
EDGE_ON_VIEWS = ((86, 5), (92, 5), (94, 5), (266, 5), (268, -5), (272, 5), (274, 5), (2, 88), (1, 0),
                 (359, 0))
