"""What a depth camera returns at depth edges: mixed ("flying") pixels, or none, on a depth image.

A pixel that straddles an occluding edge sees both surfaces. A time-of-flight camera (Kinect v2, Azure
Kinect, a phone LiDAR) returns a depth between them, weighted by the light each surface sends back (its
share of the pixel times 1/z²; equal albedo assumed); cameras with a flying-pixel filter (Azure Kinect's
depth engine, libfreenect2's edge filter) return nothing there instead. The estimator's benchmark uses
this to measure what either does to an estimate (``bench_estimate.py --edge-pixels mixed|dropped``); it
is not a :class:`~wbsa.sensor.SensorSettings` effect (scan outputs do not change).

Model: the pixel grid tiles the image, so an edge between two neighbouring returns on different
surfaces (depths differing by more than 5 %) lies inside exactly one of the two pixels, each with
probability 1/2. The one it lies in sees the near surface over a share ``c`` of its area,
``c ~ U(0.5, 1)`` if its centre saw the near surface, ``U(0, 0.5)`` otherwise, and returns
``w z_near + (1 − w) z_far`` with ``w = (c / z_near²) / (c / z_near² + (1 − c) / z_far²)``, or no return.
"""

from __future__ import annotations

import numpy as np

from wbsa.errors import WbsaError
from wbsa.typing import EDGE_PIXELS, EdgePixels

#: Neighbouring returns whose depths differ by more than this fraction lie on different surfaces.
EDGE_RATIO = 0.05


def edge_pixels(depth_m: np.ndarray, rng: np.random.Generator, effect: EdgePixels = "mixed",
                share: float = 1.0) -> np.ndarray:
    """Depth image with the straddling pixel of its depth edges mixed or dropped (see the module doc).

    Parameters
    ----------
    depth_m : (h, w) float
        z-depth in metres, 0 = no return (an edge against no return is left alone: no light comes back).
    rng : numpy.random.Generator
    effect : {'mixed', 'dropped', 'kept'}
        What the straddling pixel returns: a mixed depth, nothing, or its own depth (the image unchanged).
    share : float
        Fraction of the edges affected, in [0, 1] (a camera's filter may catch only some).

    Returns
    -------
    (h, w) float64
        A new image; pixels on several edges take the last one's mix (rows' edges, then columns').
    """
    if effect not in EDGE_PIXELS:
        raise WbsaError(f"edge pixel effect {effect!r} is unknown; use one of {', '.join(EDGE_PIXELS)}")
    if not 0.0 <= share <= 1.0:
        raise WbsaError(f"share of edges {share} must lie in [0, 1]")
    z = np.asarray(depth_m, dtype=np.float64)
    out = z.copy()
    if effect == "kept":
        return out
    for axis in (1, 0):
        a = z[:, :-1] if axis == 1 else z[:-1, :]
        b = z[:, 1:] if axis == 1 else z[1:, :]
        edge = (a > 0) & (b > 0) & (np.abs(a - b) > EDGE_RATIO * np.minimum(a, b))
        ia, ja = np.nonzero(edge)
        ib, jb = (ia, ja + 1) if axis == 1 else (ia + 1, ja)
        n = ia.size
        hit = rng.random(n) < share
        in_a = rng.random(n) < 0.5                      # the edge lies inside pixel a (else inside b)
        u = rng.random(n)
        za, zb = z[ia, ja], z[ib, jb]
        z_near, z_far = np.minimum(za, zb), np.maximum(za, zb)
        centre_near = in_a == (za < zb)                  # the straddling pixel's centre saw the near surface
        c = np.where(centre_near, 0.5 + 0.5 * u, 0.5 * u)
        w_near = (c / z_near**2) / (c / z_near**2 + (1.0 - c) / z_far**2)
        value = w_near * z_near + (1.0 - w_near) * z_far if effect == "mixed" else np.zeros(n)
        rows = np.where(in_a, ia, ib)[hit]
        cols = np.where(in_a, ja, jb)[hit]
        out[rows, cols] = value[hit]
    return out
