"""Plane cross-sections of a triangle mesh and their tape-measure perimeter."""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError


def plane_section_points(vertices: np.ndarray, faces: np.ndarray, point: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Points where the mesh edges cross a plane.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (m, 3) int
        The triangles to cut (a body part or the whole mesh).
    point : (3,) float64
        A point on the plane.
    normal : (3,) float64
        The plane normal (need not be unit length).

    Returns
    -------
    (k, 3) float64
        Crossing points of every (unique) edge with one end on each side of the plane.
    """
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    return edge_plane_crossings(vertices, np.unique(np.sort(edges, axis=1), axis=0), point, normal)


def edge_plane_crossings(vertices: np.ndarray, edges: np.ndarray, point: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Points where ``edges`` (e, 2) int cross the plane through ``point`` (3,) with ``normal`` (3,).

    Returns
    -------
    (k, 3) float64
        One point per edge with one end on each side of the plane.
    """
    normal = np.asarray(normal, dtype=np.float64)
    normal = normal / np.linalg.norm(normal)
    d = (vertices - point) @ normal
    da, db = d[edges[:, 0]], d[edges[:, 1]]
    cross = (da < 0) != (db < 0)
    a, b = edges[cross, 0], edges[cross, 1]
    t = (da[cross] / (da[cross] - db[cross]))[:, None]
    return vertices[a] + t * (vertices[b] - vertices[a])


class HorizontalSlicer:
    """Horizontal sections of one set of edges at many heights, gathering edge heights once.

    Parameters
    ----------
    vertices : (n, 3) float64
    edges : (e, 2) int
    """

    def __init__(self, vertices: np.ndarray, edges: np.ndarray):
        self.vertices = vertices
        self.edges = edges
        self.za = vertices[edges[:, 0], 2]
        self.zb = vertices[edges[:, 1], 2]

    def points(self, z: float) -> np.ndarray:
        """(k, 3) crossings of the edges with the plane at height ``z``; same as :func:`edge_plane_crossings`."""
        cross = (self.za < z) != (self.zb < z)
        za, zb = self.za[cross], self.zb[cross]
        a, b = self.vertices[self.edges[cross, 0]], self.vertices[self.edges[cross, 1]]
        t = ((z - za) / (zb - za))[:, None]
        return a + t * (b - a)


def tape_perimeter_m(points: np.ndarray, normal: np.ndarray) -> float:
    """Perimeter of the convex hull of planar points: a tape pulled around the section.

    Parameters
    ----------
    points : (k, 3) float64
        Points on one plane (from :func:`plane_section_points`).
    normal : (3,) float64
        The plane normal.

    Returns
    -------
    float
        Perimeter in metres; NaN if fewer than three points or a degenerate section.
    """
    uv = _plane_coordinates(points, normal)
    if len(uv) < 3:
        return float("nan")
    try:
        return float(ConvexHull(uv).area)  # in 2-D, qhull's "area" is the perimeter
    except QhullError:
        return float("nan")


def width_along_m(points: np.ndarray, axis: np.ndarray) -> float:
    """Extent of ``points`` (k, 3) along a unit ``axis`` (3,), in metres; NaN if empty."""
    if len(points) == 0:
        return float("nan")
    s = points @ np.asarray(axis, dtype=np.float64)
    return float(s.max() - s.min())


def _plane_coordinates(points: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """2-D coordinates of ``points`` (k, 3) in an orthonormal basis of the plane."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    if abs(n[2]) > 1 - 1e-12:  # horizontal plane: x and y already are such a basis
        return points[:, :2]
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = _cross3(n, helper)
    u /= np.linalg.norm(u)
    v = _cross3(n, u)
    return np.stack([points @ u, points @ v], axis=1)


def _cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product of two (3,) vectors (np.cross has a large fixed overhead)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])
