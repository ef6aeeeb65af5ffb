"""Geometry of a depth image's point cloud: planes, a depth-noise envelope, the floor cut, the body frame.

Every function here is pure numpy on camera-frame points (OpenCV axes: x right, y down, z forward, metres).
A :class:`Plane` is ``{p : n·p = d}`` with ``n`` a unit normal; its signed height ``n·p − d`` is positive on
the camera's side (the camera, at the origin, has height ``−d > 0``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wbsa.sensor.technology import SensorModel, envelope_m, unknown_camera_model


def depth_noise_m(z: np.ndarray, sensor: SensorModel | None = None) -> np.ndarray:
    """Standard deviation of a depth reading: the sensor model's envelope (:func:`wbsa.sensor.technology.envelope_m`,
    axial σ face-on and the disparity quantisation).

    Parameters
    ----------
    z : (...) float
        z-depth in metres.
    sensor : SensorModel, optional
        The camera's envelope model (:func:`wbsa.sensor.technology.envelope_model`); None: that of a camera
        without a preset.

    Returns
    -------
    (...) float64
        σ in metres.
    """
    return envelope_m(unknown_camera_model() if sensor is None else sensor, z)


@dataclass(frozen=True)
class Plane:
    """A plane ``n·p = d`` in the camera frame, ``n`` unit and pointing to the camera's side.

    ``noise_scale`` (≥ 1) multiplies the depth-noise envelope where the plane's own returns are noisier
    (measured on them by :func:`ransac_plane`; lateral noise on a grazing floor adds to the axial noise).
    ``sensor`` is the envelope's model (:func:`depth_noise_m`; None: that of a camera without a preset).
    """

    normal: np.ndarray
    offset: float
    noise_scale: float = 1.0
    sensor: SensorModel | None = None

    def __post_init__(self) -> None:
        n = np.asarray(self.normal, dtype=np.float64).reshape(3)
        d = float(self.offset)
        object.__setattr__(self, "noise_scale", max(1.0, float(self.noise_scale)))
        n_len = float(np.linalg.norm(n))
        n, d = n / n_len, d / n_len
        if d > 0:  # the camera (origin) must be on the positive side: height -d > 0
            n, d = -n, -d
        object.__setattr__(self, "normal", n)
        object.__setattr__(self, "offset", d)

    def height(self, points: np.ndarray) -> np.ndarray:
        """(k,) float64 signed height of (k, 3) points above the plane (positive on the camera's side).

        Parameters
        ----------
        points : (k, 3) float
            Camera-frame points, metres.

        Returns
        -------
        (k,) float64
            ``n·p − d`` in metres.
        """
        return np.asarray(points, dtype=np.float64) @ self.normal - self.offset

    def tolerance(self, points: np.ndarray, k_sigma: float = 2.5, floor_m: float = 0.02,
                  scaled: bool = True) -> np.ndarray:
        """(k,) float64 how far a return of this plane may stray from it: the depth noise seen along the normal.

        ``scaled`` False uses the envelope alone, without the plane's measured ``noise_scale``.

        Parameters
        ----------
        points : (k, 3) float
            Camera-frame points, metres.
        k_sigma : float
            How many σ of the noise along the normal.
        floor_m : float
            The least tolerance, metres.
        scaled : bool
            Multiply the noise by the plane's ``noise_scale``.

        Returns
        -------
        (k,) float64
            ``max(floor_m, k_sigma · scale · σ_ray · |cos|)`` in metres, with σ_ray from :meth:`unit_noise`
            and cos the cosine between each point's ray and the normal.
        """
        p = np.asarray(points, dtype=np.float64)
        r = np.linalg.norm(p, axis=1)
        cos = np.abs(p @ self.normal) / np.maximum(r, 1e-9)
        # the depth error runs along the ray; its z-noise scales to range by r / z
        scale = self.noise_scale if scaled else 1.0
        return np.maximum(floor_m, k_sigma * scale * self.unit_noise(p) * cos)

    def unit_noise(self, points: np.ndarray) -> np.ndarray:
        """(k,) float64 the envelope's depth noise along each point's ray (before the angle to the plane).

        Parameters
        ----------
        points : (k, 3) float
            Camera-frame points, metres (z > 0).

        Returns
        -------
        (k,) float64
            σ(z) · r / z in metres (:func:`depth_noise_m` of the plane's ``sensor``, r the point's range).
        """
        p = np.asarray(points, dtype=np.float64)
        return depth_noise_m(p[:, 2], self.sensor) * np.linalg.norm(p, axis=1) / np.maximum(p[:, 2], 1e-9)

    def to_dict(self) -> dict:
        """JSON-ready ``{"normal": [...], "offset_m": ...}``."""
        return {"normal": [float(x) for x in self.normal], "offset_m": float(self.offset),
                "noise_scale": float(self.noise_scale)}


def fit_plane(points: np.ndarray, weights: np.ndarray | None = None) -> Plane:
    """Weighted least-squares plane through (k, 3) points (the smallest principal axis).

    Parameters
    ----------
    points : (k, 3) float64
        Camera-frame points, metres.
    weights : (k,) float, optional
        Weight of each point (all 1 when None).

    Returns
    -------
    Plane
        Through the weighted centroid, normal the right singular vector of the smallest singular value of
        the √w-weighted centred points; ``noise_scale`` 1 and no ``sensor``.
    """
    w = np.ones(len(points)) if weights is None else np.asarray(weights, dtype=np.float64)
    c = (w[:, None] * points).sum(axis=0) / w.sum()
    _, _, vt = np.linalg.svd(np.sqrt(w)[:, None] * (points - c), full_matrices=False)
    n = vt[2]
    return Plane(n, float(n @ c))


def _refit(points: np.ndarray, plane: Plane, k_sigma: float) -> tuple[Plane, np.ndarray]:
    """Refit on the inliers, weighted by their inverse noise, and measure the plane's own noise."""
    sensor = plane.sensor
    unit = plane.unit_noise(points)
    inliers = np.abs(plane.height(points)) <= plane.tolerance(points, k_sigma)
    for _ in range(3):
        if inliers.sum() < 3:
            break
        cos = np.abs(points[inliers] @ plane.normal) / np.linalg.norm(points[inliers], axis=1)
        sigma = np.maximum(unit[inliers] * cos, 1e-3)
        plane = fit_plane(points[inliers], 1.0 / sigma**2)
        h = plane.height(points[inliers]) / sigma
        scale = 1.4826 * float(np.median(np.abs(h - np.median(h))))  # robust spread in envelope units
        plane = Plane(plane.normal, plane.offset, noise_scale=scale, sensor=sensor)
        inliers = np.abs(plane.height(points)) <= plane.tolerance(points, k_sigma)
    return plane, inliers


def ransac_plane(points: np.ndarray, rng: np.random.Generator, iterations: int = 200,
                 k_sigma: float = 2.5, sensor: SensorModel | None = None) -> tuple[Plane, np.ndarray] | None:
    """The plane with the most inliers among (k, 3) points, refitted on them.

    Inliers lie within :meth:`Plane.tolerance` (the depth noise along the normal, of the envelope of
    ``sensor``, :func:`depth_noise_m`; the plane keeps it). Deterministic for ``rng``.

    Parameters
    ----------
    points : (k, 3) float64
        Camera-frame points, metres.
    rng : numpy.random.Generator
        Draws the candidate triples (and a subsample of 20 000 points when k > 20 000, on which the
        candidates are counted).
    iterations : int
        Number of candidate planes (point triples).
    k_sigma : float
        Inlier tolerance in σ of the depth noise (:meth:`Plane.tolerance`).
    sensor : SensorModel, optional
        The envelope's model (:func:`depth_noise_m`); None: that of a camera without a preset.

    Returns
    -------
    (Plane, (k,) bool inliers) or None
        None with fewer than 3 points, or when every triple is degenerate.
    """
    k = len(points)
    if k < 3:
        return None
    triples = rng.integers(0, k, size=(iterations, 3))
    sub = points if k <= 20000 else points[rng.choice(k, 20000, replace=False)]
    r = np.linalg.norm(sub, axis=1)
    rays = sub / np.maximum(r, 1e-9)[:, None]
    spread = np.maximum(0.02, k_sigma * depth_noise_m(sub[:, 2], sensor) * r / np.maximum(sub[:, 2], 1e-9))
    a, b, c = points[triples[:, 0]], points[triples[:, 1]], points[triples[:, 2]]
    normals = np.cross(b - a, c - a)
    lengths = np.linalg.norm(normals, axis=1)
    ok = lengths > 1e-9
    if not ok.any():
        return None
    normals = normals[ok] / lengths[ok, None]
    offsets = np.einsum("ij,ij->i", normals, a[ok])
    counts = np.empty(len(normals), dtype=np.int64)
    for i in range(0, len(normals), 16):  # 16 candidate planes at a time
        n = normals[i:i + 16]
        dist = np.abs(sub @ n.T - offsets[i:i + 16])
        tol = np.maximum(0.02, spread[:, None] * np.abs(rays @ n.T))
        counts[i:i + 16] = np.count_nonzero(dist <= tol, axis=0)
    best_i = int(np.argmax(counts))
    return _refit(points, Plane(normals[best_i], float(offsets[best_i]), sensor=sensor), k_sigma)


#: The floor cut keeps returns higher than this above the floor, or than the floor's depth noise if more.
FLOOR_CUT_M = 0.02


def above_floor(points: np.ndarray, floor: Plane | None) -> np.ndarray:
    """(k,) bool: points above the floor by more than the noise envelope; all when no floor.

    This is the floor cut of the measures. It uses the envelope alone (not the floor's measured noise),
    so training renders, whose floor is known, and real images lose the same strip of the feet.

    Parameters
    ----------
    points : (k, 3) float
        Camera-frame points, metres.
    floor : Plane or None
        The floor; None keeps every point.

    Returns
    -------
    (k,) bool
        Height above the floor greater than :meth:`Plane.tolerance` with ``floor_m`` = :data:`FLOOR_CUT_M`
        and ``scaled=False``.
    """
    if floor is None:
        return np.ones(len(points), dtype=bool)
    return floor.height(points) > floor.tolerance(points, floor_m=FLOOR_CUT_M, scaled=False)


@dataclass(frozen=True)
class BodyFrame:
    """Axes attached to a standing subject as the camera sees it (camera frame, unit vectors).

    Attributes
    ----------
    up : (3,) float64
        The floor's normal, or the body's long axis when no floor is seen.
    toward : (3,) float64
        Horizontal (⟂ ``up``) direction from the subject to the camera.
    right : (3,) float64
        ``up × toward`` flipped to agree with the image's right.
    base : (3,) float64
        The point under the subject's centre on the floor (or at its lowest point).
    """

    up: np.ndarray
    toward: np.ndarray
    right: np.ndarray
    base: np.ndarray

    def coordinates(self, points: np.ndarray) -> np.ndarray:
        """(k, 3) float64 (lateral, height, toward-camera) coordinates of camera-frame points, metres.

        Parameters
        ----------
        points : (k, 3) float
            Camera-frame points, metres.

        Returns
        -------
        (k, 3) float64
            ``(p − base)`` projected on ``right``, ``up`` and ``toward``, metres.
        """
        q = np.asarray(points, dtype=np.float64) - self.base
        return np.stack([q @ self.right, q @ self.up, q @ self.toward], axis=1)


def body_frame(points: np.ndarray, floor: Plane | None) -> BodyFrame:
    """The :class:`BodyFrame` of a subject's (k, 3) camera-frame points.

    ``up`` is the floor's normal, or without a floor the principal axis of the points (every
    max(1, ⌊k / 5000⌋)-th one) turned to image up (camera −y); ``toward`` is horizontal, from the points'
    component-wise median to the camera; ``base`` is that median dropped along ``up`` to the floor (without a
    floor, to the height of the lowest point).

    Parameters
    ----------
    points : (k, 3) float
        The subject's camera-frame points, metres (k ≥ 1).
    floor : Plane or None
        The floor, if one was found.

    Returns
    -------
    BodyFrame
    """
    p = np.asarray(points, dtype=np.float64)
    centre = np.median(p, axis=0)
    if floor is not None:
        up = floor.normal
    else:
        q = p[:: max(1, len(p) // 5000)] - centre
        _, _, vt = np.linalg.svd(q, full_matrices=False)
        up = vt[0] if vt[0][1] < 0 else -vt[0]  # image up is camera -y
    horizontal = -(centre - (centre @ up) * up)
    if np.linalg.norm(horizontal) < 1e-6:  # camera straight above or below
        horizontal = np.array([0.0, -1.0, 0.0]) - (-up[1]) * up
    toward = horizontal / np.linalg.norm(horizontal)
    right = np.cross(up, toward)
    if right[0] < 0:
        right = -right
    if floor is not None:
        base = centre - floor.height(centre[None])[0] * up
    else:
        base = centre + (float(np.min((p - centre) @ up))) * up
    return BodyFrame(up, toward, right, base)
