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
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.intp)
    a, b, c = (np.take(v, f[:, k], axis=0) for k in range(3))  # np.take: ~2x faster than v[f[:, k]]
    u = b - a
    w = c - a
    # explicit cross product: several times faster than np.cross on (m, 3) arrays
    cx = u[:, 1] * w[:, 2] - u[:, 2] * w[:, 1]
    cy = u[:, 2] * w[:, 0] - u[:, 0] * w[:, 2]
    cz = u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0]
    return 0.5 * np.sqrt(cx * cx + cy * cy + cz * cz)
