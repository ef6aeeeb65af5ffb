"""Mixed ("flying") pixels: returns at a depth edge that lie between the two surfaces, snapped to one of them.

A time-of-flight camera (Kinect v2, Azure Kinect, a phone LiDAR) whose pixel straddles an occluding edge
receives light from both surfaces and returns a depth between them; stereo cameras smear edges the same
way. Such returns float in the gap behind the body's silhouette: they join the body to the wall behind it
(one cluster), and the surface meshed through them has steep strips that are not skin. Before anything
else the estimator therefore checks every return against its eight neighbours:

- a return *agrees* with a neighbour when their depths differ by at most ``max(4 σ(z), tan 80° · z / f)``
  (times √2 on the diagonals): four times the depth noise (:func:`wbsa.estimation.subject.cloud.depth_noise_m`),
  or a surface inclined 80° to the ray;
- a return that agrees with fewer than :data:`MIN_AGREEING` of its neighbours, and has both a nearer and
  a farther neighbour it does not agree with, lies between two surfaces: it is *mixed*. It takes the
  depth of the neighbour it is closest to in depth among those that are not mixed (the surface it mostly
  saw), or is dropped when there is none.

On a smooth surface every return agrees with five to eight neighbours. Returns left alone by holes and
dropout, and a silhouette's ragged returns, have no surface on one of the two sides and stay as they
are. The same step runs on every training capture, so the model sees what it will see.
"""

from __future__ import annotations

import numpy as np

from wbsa.estimation.subject.cloud import depth_noise_m
from wbsa.sensor.technology import SensorModel

#: Fewer agreeing neighbours than this (of eight) can make a return mixed.
MIN_AGREEING = 4
#: Steepest surface (degrees between its normal and the ray) whose neighbouring returns still agree.
MAX_SLOPE_DEG = 80.0
#: Depth-noise multiple within which neighbouring returns agree.
NOISE_MULTIPLE = 4.0

_NEIGHBOURS = tuple((dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dy, dx) != (0, 0))


def _shifted(a: np.ndarray, dy: int, dx: int, fill: float | None) -> np.ndarray:
    """``a`` seen from each pixel's neighbour at offset (dy, dx); beyond the border ``fill``, or the
    border pixel itself when ``fill`` is None (the surface goes on out of the image)."""
    h, w = a.shape
    r = max(abs(dy), abs(dx))
    padded = np.pad(a, r, mode="edge") if fill is None else np.pad(a, r, constant_values=fill)
    return padded[r + dy:r + dy + h, r + dx:r + dx + w]


def _returns(depth_m: np.ndarray) -> np.ndarray:
    """(h, w) float64 depth with every non-return (0, negative, NaN, infinite) set to 0."""
    z = np.asarray(depth_m, dtype=np.float64)
    return np.where(np.isfinite(z) & (z > 0), z, 0.0)


def mixed_pixels(depth_m: np.ndarray, fx: float, sensor: SensorModel | None = None) -> np.ndarray:
    """Which returns are mixed (see the module doc).

    Parameters
    ----------
    depth_m : (h, w) float
        z-depth in metres, 0 (or NaN) = no return.
    fx : float
        Focal length in pixels (the pixel pitch is z / fx).
    sensor : SensorModel, optional
        The camera's depth-noise envelope (:func:`wbsa.sensor.technology.envelope_model`); None: that of a camera
        without a preset.

    Returns
    -------
    (h, w) bool
        Beyond the image border the border's own returns stand in for the missing neighbours (so a
        return in an image corner is never found mixed).
    """
    z = _returns(depth_m)
    tol = np.maximum(NOISE_MULTIPLE * depth_noise_m(z, sensor), np.tan(np.deg2rad(MAX_SLOPE_DEG)) * z / float(fx))
    agreeing = np.zeros(z.shape, np.int8)
    nearer = np.zeros(z.shape, bool)
    farther = np.zeros(z.shape, bool)
    for dy, dx in _NEIGHBOURS:
        zn = _shifted(z, dy, dx, None)
        limit = tol * (np.sqrt(2.0) if dy and dx else 1.0)
        returned = zn > 0
        agreeing += (returned & (np.abs(zn - z) <= limit)).astype(np.int8)
        nearer |= returned & (zn < z - limit)
        farther |= returned & (zn > z + limit)
    return (z > 0) & (agreeing < MIN_AGREEING) & nearer & farther


def repair_mixed_pixels(depth_m: np.ndarray, fx: float,
                        sensor: SensorModel | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Snap mixed returns to the depth of the surface they mostly saw (see the module doc).

    Parameters
    ----------
    depth_m : (h, w) float
        z-depth in metres, 0 (or NaN) = no return.
    fx : float
        Focal length in pixels.
    sensor : SensorModel, optional
        The camera's depth-noise envelope (:func:`wbsa.sensor.technology.envelope_model`); None: that of a camera
        without a preset.

    Returns
    -------
    depth_m : (h, w) float64
        The repaired image (a new array); mixed returns whose neighbours are all mixed or empty become 0.
    mixed : (h, w) bool
        The returns found mixed (snapped or dropped).

    Examples
    --------
    A wall 1 m behind a flat board, with one return between them on the board's edge:

    >>> z = np.full((5, 6), 3.0); z[:, 3:] = 4.0; z[2, 2] = 3.6
    >>> fixed, mixed = repair_mixed_pixels(z, fx=365.0)
    >>> int(mixed.sum()), float(fixed[2, 2])
    (1, 4.0)
    """
    z = _returns(depth_m)
    mixed = mixed_pixels(z, fx, sensor)
    if not mixed.any():
        return z, mixed
    good = np.where((z > 0) & ~mixed, z, np.nan)
    nearest = np.full(z.shape, np.nan)
    gap = np.full(z.shape, np.inf)
    for dy, dx in _NEIGHBOURS:
        zn = _shifted(good, dy, dx, np.nan)
        d = np.abs(zn - z)
        closer = np.isfinite(zn) & (d < gap)
        nearest[closer], gap[closer] = zn[closer], d[closer]
    out = z.copy()
    out[mixed] = np.nan_to_num(nearest[mixed], nan=0.0)
    return out, mixed


def outline_shares(depth_m: np.ndarray, subject: np.ndarray, mixed: np.ndarray | None) -> tuple[float, float, float]:
    """How the camera treated the subject's outline: mixed returns beside it, and gaps along it.

    Parameters
    ----------
    depth_m : (h, w) float
        The (repaired) depth image in metres, 0 = no return.
    subject : (h, w) bool
        The subject's pixels.
    mixed : (h, w) bool or None
        Returns found mixed (:func:`repair_mixed_pixels`); None = none.

    Returns
    -------
    mixed_share : float
        Mixed returns within 2 pixels of the subject per pixel of its outline: 0.01–0.03 on clean frames
        (the benchmark's renders), 0.5–0.8 when every depth edge is mixed.
    gap_share : float
        Share of the outline's outward steps that cross a one-pixel gap without return to a return behind
        the subject, where a camera's flying-pixel filter dropped the pixel on the edge: 0.02–0.05 on clean
        frames, about 0.14 once a filter drops half of them or more: it stops growing there, as two
        dropped pixels side by side make a gap of two.
    edge_gap_share : float
        Share of the outline's depth edges (outward steps to a return behind the subject, directly or
        across a gap of one or two pixels) that cross such a gap: the share of its edges a filter dropped.
        On the benchmark's first 16 images (seed 1000), with
        :data:`~wbsa.sensor.depth_edges.edge_pixels` dropping a share s of the edges, it reads 0.20 ± 0.21
        at s = 0 (holes and dropout), 0.47 ± 0.17 at 0.25, 0.70 ± 0.11 at 0.5 and 1.00 at 1 (mean ±
        standard deviation over the images).
    """
    from scipy import ndimage

    z = _returns(depth_m)
    subject = np.asarray(subject, dtype=bool)
    outline = np.count_nonzero(subject & ~ndimage.binary_erosion(subject))
    if outline == 0:
        return 0.0, 0.0, 0.0
    n_mixed = 0 if mixed is None else np.count_nonzero(mixed & ndimage.binary_dilation(subject, iterations=2))
    inside = np.where(subject, z, 0.0)
    steps = gaps = direct = wide_gaps = 0
    for dy, dx in ((0, 1), (0, -1), (1, 0), (-1, 0)):
        beside = _shifted(z, dy, dx, -1.0)                     # −1 beyond the image
        beyond = _shifted(z, 2 * dy, 2 * dx, -1.0)
        beyond2 = _shifted(z, 3 * dy, 3 * dx, -1.0)
        out = subject & ~_shifted(subject, dy, dx, False) & (beside >= 0)
        one = out & (beside == 0) & (beyond > 1.05 * inside)
        steps += np.count_nonzero(out)
        gaps += np.count_nonzero(one)
        direct += np.count_nonzero(out & (beside > 1.05 * inside))
        wide_gaps += np.count_nonzero(one | (out & (beside == 0) & (beyond == 0) & (beyond2 > 1.05 * inside)))
    return float(n_mixed / outline), float(gaps / max(steps, 1)), float(wide_gaps / max(direct + wide_gaps, 1))
