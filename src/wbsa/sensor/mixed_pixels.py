"""Mixed ("flying") pixels of a time-of-flight camera at depth edges, on a depth image.

A pixel that straddles an occluding edge sees both surfaces; a time-of-flight camera returns a depth
between them, weighted by the light each surface sends back (its share of the pixel times 1/z²; equal
albedo assumed). Kinect v2, Azure Kinect and phone LiDAR frames have such returns at every silhouette
unless the camera's own filter drops them. The estimator's benchmark uses this to test that
:mod:`wbsa.estimation.mixed_pixels` repairs them; it is not a :class:`~wbsa.sensor.SensorSettings`
effect (scan outputs do not change).

Model: the pixel grid tiles the image, so an edge between two neighbouring returns on different
surfaces (depths differing by more than 5 %) lies inside exactly one of the two pixels, each with
probability 1/2. The one it lies in sees the near surface over a share ``c`` of its area,
``c ~ U(0.5, 1)`` if its centre saw the near surface, ``U(0, 0.5)`` otherwise, and returns
``w z_near + (1 − w) z_far`` with ``w = (c / z_near²) / (c / z_near² + (1 − c) / z_far²)``.
"""

from __future__ import annotations

import numpy as np

#: Neighbouring returns whose depths differ by more than this fraction lie on different surfaces.
EDGE_RATIO = 0.05


def mix_edge_pixels(depth_m: np.ndarray, rng: np.random.Generator, share: float = 1.0) -> np.ndarray:
    """Depth image with mixed returns at its depth edges (see the module doc).

    Parameters
    ----------
    depth_m : (h, w) float
        z-depth in metres, 0 = no return (an edge against no return is left alone: no light comes back).
    rng : numpy.random.Generator
    share : float
        Fraction of the edges whose straddling pixel returns a mixed depth (the rest keep their depth, as
        after a camera's own flying-pixel filter), in [0, 1].

    Returns
    -------
    (h, w) float64
        A new image; pixels on several edges take the last one's mix (rows' edges, then columns').
    """
    if not 0.0 <= share <= 1.0:
        raise ValueError(f"share of mixed edges {share} must lie in [0, 1]")
    z = np.asarray(depth_m, dtype=np.float64)
    out = z.copy()
    for axis in (1, 0):
        a = z[:, :-1] if axis == 1 else z[:-1, :]
        b = z[:, 1:] if axis == 1 else z[1:, :]
        edge = (a > 0) & (b > 0) & (np.abs(a - b) > EDGE_RATIO * np.minimum(a, b))
        ia, ja = np.nonzero(edge)
        ib, jb = (ia, ja + 1) if axis == 1 else (ia + 1, ja)
        n = ia.size
        mixed = rng.random(n) < share
        in_a = rng.random(n) < 0.5                      # the edge lies inside pixel a (else inside b)
        u = rng.random(n)
        za, zb = z[ia, ja], z[ib, jb]
        near_is_a = za < zb
        z_near, z_far = np.minimum(za, zb), np.maximum(za, zb)
        centre_near = in_a == near_is_a                  # the straddling pixel's centre saw the near surface
        c = np.where(centre_near, 0.5 + 0.5 * u, 0.5 * u)
        w_near = (c / z_near**2) / (c / z_near**2 + (1.0 - c) / z_far**2)
        value = w_near * z_near + (1.0 - w_near) * z_far
        rows = np.where(in_a, ia, ib)[mixed]
        cols = np.where(in_a, ja, jb)[mixed]
        out[rows, cols] = value[mixed]
    return out
