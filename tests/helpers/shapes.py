"""Simple meshes with known areas, for tests, benchmarks and docs (no body model needed)."""

from __future__ import annotations

import numpy as np

from wbsa.core.mesh import TriangleMesh


def icosphere(radius_m: float = 1.0, subdivisions: int = 3, center: np.ndarray | None = None) -> TriangleMesh:
    """A geodesic sphere: an icosahedron split ``subdivisions`` times, vertices pushed onto the sphere.

    It has ``20 · 4**subdivisions`` triangles, counter-clockwise seen from outside.
    """
    t = (1.0 + 5.0**0.5) / 2.0
    v = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
                  [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], dtype=np.float64)
    f = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
                  [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
                  [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]], dtype=np.int64)
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    for _ in range(subdivisions):
        edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
        key = np.sort(edges, axis=1)
        uniq, inverse = np.unique(key, axis=0, return_inverse=True)
        mid = v[uniq[:, 0]] + v[uniq[:, 1]]
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        m = len(f)
        idx = inverse.reshape(-1) + len(v)
        a, b, c = f[:, 0], f[:, 1], f[:, 2]
        ab, bc, ca = idx[:m], idx[m:2 * m], idx[2 * m:]
        f = np.concatenate([np.stack([a, ab, ca], 1), np.stack([b, bc, ab], 1),
                            np.stack([c, ca, bc], 1), np.stack([ab, bc, ca], 1)])
        v = np.concatenate([v, mid])
    center = np.zeros(3) if center is None else np.asarray(center, dtype=np.float64)
    return TriangleMesh(v * radius_m + center, f.astype(np.int32))


def box(size_m: tuple[float, float, float] = (1.0, 1.0, 1.0), center: np.ndarray | None = None,
        subdivisions: int = 0) -> TriangleMesh:
    """An axis-aligned box; each face a grid of ``2**subdivisions`` × ``2**subdivisions`` squares of 2 triangles."""
    n = 2**subdivisions
    s = np.linspace(-0.5, 0.5, n + 1)
    verts, faces = [], []
    # (normal axis, sign): the face's (a, b) axes are chosen so that a × b points outward.
    for axis in range(3):
        for sign in (-1.0, 1.0):
            a_ax, b_ax = (axis + 1) % 3, (axis + 2) % 3
            if sign < 0:
                a_ax, b_ax = b_ax, a_ax
            A, B = np.meshgrid(s, s, indexing="ij")
            p = np.zeros((n + 1, n + 1, 3))
            p[..., axis] = 0.5 * sign
            p[..., a_ax] = A
            p[..., b_ax] = B
            base = sum(len(x) for x in verts)
            verts.append(p.reshape(-1, 3))
            i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
            v00 = base + i * (n + 1) + j
            v10, v01, v11 = v00 + (n + 1), v00 + 1, v00 + n + 2
            faces.append(np.stack([v00, v10, v11], -1).reshape(-1, 3))
            faces.append(np.stack([v00, v11, v01], -1).reshape(-1, 3))
    v = np.concatenate(verts) * np.asarray(size_m, dtype=np.float64)
    center = np.zeros(3) if center is None else np.asarray(center, dtype=np.float64)
    return TriangleMesh(v + center, np.concatenate(faces).astype(np.int32))


def ellipsoid_between(p0: np.ndarray, p1: np.ndarray, radius_m: float, subdivisions: int = 3) -> TriangleMesh:
    """An icosphere stretched into an ellipsoid whose long axis runs from ``p0`` to ``p1`` (a limb segment)."""
    p0, p1 = np.asarray(p0, dtype=np.float64), np.asarray(p1, dtype=np.float64)
    axis = p1 - p0
    half = 0.5 * np.linalg.norm(axis)
    w = axis / (2 * half)
    helper = np.array([1.0, 0.0, 0.0]) if abs(w[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(w, helper)
    u /= np.linalg.norm(u)
    basis = np.stack([u, np.cross(w, u), w])  # rows; right-handed, so winding stays outward
    s = icosphere(1.0, subdivisions)
    local = s.vertices * np.array([radius_m, radius_m, max(half, radius_m)])
    return TriangleMesh(local @ basis + 0.5 * (p0 + p1), s.faces)


def merge(meshes: list[TriangleMesh]) -> TriangleMesh:
    """Concatenate meshes into one (overlaps are kept; rays see the outer surface)."""
    offsets = np.cumsum([0] + [len(m.vertices) for m in meshes[:-1]])
    return TriangleMesh(np.concatenate([m.vertices for m in meshes]),
                        np.concatenate([m.faces + o for m, o in zip(meshes, offsets)]).astype(np.int32))


def body_like(stature_m: float = 1.75) -> TriangleMesh:
    """A crude standing figure of ellipsoids in an A-pose, about 27k triangles, for benchmarks.

    Body-model frame: +Z up, standing on z = 0, facing −Y, its left side at +X. It is an assembly of
    overlapping closed parts (not a single surface), so its total triangle area is not a skin area.
    """
    s = stature_m / 1.75
    parts = [
        ellipsoid_between([0, 0, 1.50], [0, 0, 1.74], 0.095, 4),  # head
        ellipsoid_between([0, 0, 0.95], [0, 0, 1.50], 0.16, 4),  # torso
        ellipsoid_between([0, 0, 0.85], [0, 0, 1.05], 0.17, 3),  # pelvis
    ]
    for side in (-1.0, 1.0):
        parts += [
            ellipsoid_between([side * 0.18, 0, 1.42], [side * 0.30, 0, 1.14], 0.05, 3),  # upper arm
            ellipsoid_between([side * 0.30, 0, 1.14], [side * 0.40, -0.03, 0.88], 0.04, 3),  # forearm
            ellipsoid_between([side * 0.40, -0.03, 0.88], [side * 0.43, -0.04, 0.76], 0.035, 3),  # hand
            ellipsoid_between([side * 0.10, 0, 0.90], [side * 0.12, 0, 0.48], 0.08, 3),  # thigh
            ellipsoid_between([side * 0.12, 0, 0.48], [side * 0.13, 0.01, 0.07], 0.055, 3),  # shin
            ellipsoid_between([side * 0.13, 0.04, 0.0], [side * 0.13, -0.18, 0.06], 0.045, 3),  # foot
        ]
    mesh = merge(parts)
    v = mesh.vertices * s
    v[:, 2] -= v[:, 2].min()
    return TriangleMesh(v, mesh.faces)
