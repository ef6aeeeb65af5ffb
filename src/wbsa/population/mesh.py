"""The triangle mesh every stage passes around."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class TriangleMesh:
    """A triangle mesh in metres.

    Attributes
    ----------
    vertices : (n, 3) float64
        Vertex positions in metres. Bodies use anny's frame shifted to stand on z = 0:
        +Z up, the subject faces -Y, its left side at +X.
    faces : (m, 3) int32
        Vertex indices of each triangle, counter-clockwise seen from outside.
    """

    vertices: np.ndarray
    faces: np.ndarray

    def __repr__(self) -> str:
        v, f = np.asarray(self.vertices), np.asarray(self.faces)
        if v.ndim != 2 or v.shape[1:] != (3,) or f.ndim != 2 or f.shape[1:] != (3,) or not len(v):
            return f"TriangleMesh(vertices {v.shape}, faces {f.shape})"
        size = v.max(axis=0) - v.min(axis=0)
        return (f"TriangleMesh({len(v):,} vertices, {len(f):,} faces, area {self.area_m2:.4g} m², "
                f"bbox {size[0]:.3g} × {size[1]:.3g} × {size[2]:.3g} m)")

    @property
    def triangle_areas_m2(self) -> np.ndarray:
        """(m,) float64 area of every triangle in m²."""
        return triangle_areas_m2(self.vertices, self.faces)

    @property
    def area_m2(self) -> float:
        """Total surface area in m²."""
        return float(self.triangle_areas_m2.sum())

    @property
    def bbox_center(self) -> np.ndarray:
        """(3,) float64 centre of the axis-aligned bounding box (the subject's centre for the camera)."""
        return 0.5 * (self.vertices.min(axis=0) + self.vertices.max(axis=0))


def face_cross_products(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-triangle (b − a) × (c − a) and the first corner a.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int

    Returns
    -------
    cross : (3, m) float64
        Twice the area-weighted normal of each triangle, component-major.
    a : (3, m) float64
        First corner of each triangle, component-major.
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.intp)
    a, b, c = (np.take(v, f[:, k], axis=0).T for k in range(3))  # np.take: ~2x faster than v[f[:, k]]
    u = b - a
    w = c - a
    cross = np.stack([u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]])
    return cross, a


def triangle_areas_m2(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area of each triangle, ½|u × v| (paper eq. 4).

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int

    Returns
    -------
    (m,) float64
    """
    cross, _ = face_cross_products(vertices, faces)
    return 0.5 * np.sqrt((cross * cross).sum(axis=0))
