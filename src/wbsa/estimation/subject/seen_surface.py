"""The seen surface: the subject's returns with small gaps filled and the depth smoothed, and its area.

Cameras differ in what they lose and add: holes, dropped returns, depth noise, grazing returns kept or
dropped. A mesh over the raw returns follows all of them (the grid reconstruction of a Kinect-like frame loses
5–17 % of its area to 2–4 % of dropped returns, since each missing pixel takes up to six triangles with it,
and gains several per cent from the noise), so a model trained on one camera's losses misreads another's.
The seen surface is built to read the same whoever drew the frame:

1. :func:`fill_gaps`: pixels without a return enclosed by the subject (holes of up to
   :data:`GAP_MAX_PX` pixels) or with at least 5 of their 8 neighbours on it (dropped returns along its
   outline) take the median depth of the subject's returns around them;
2. the depth is smoothed by the robust quadratic filter (:func:`wbsa.surface.denoise.denoise_depth`,
   σ = :data:`SMOOTH_SIGMA_PX` pixels), which keeps the curvature of limbs;
3. each pixel's area is that of the smooth surface it sees, ``|∂P/∂u × ∂P/∂v|``, capped at its footprint
   facing the camera over cos :data:`MAX_INCIDENCE_DEG` (the rim, seen at grazing angles, is where cameras
   differ most: some drop it, some return it noisy).

Measured with ``python benchmarks/bench_estimate.py --renderer both`` (docs/estimate.md): the plain renderer
and the project's agree on it within about 1 % where the grid's area differs by 10 %.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Largest enclosed region without returns (pixels) that :func:`fill_gaps` fills.
GAP_MAX_PX = 64
#: Spatial σ (pixels) of the smoothing before the area and the top of the head are read.
SMOOTH_SIGMA_PX = 4.0
#: Angle between the surface and the ray beyond which a pixel's area is capped (degrees). Chosen on seed
#: 2000's captures (20, both renderers; never the held-out seed 1000): the plain renderer read the seen
#: area +2.5 % above the project's with a cap at 60°, +1.0 % at 50°, +0.4 % at 45°, −0.1 % at 40° and
#: −0.9 % with the silhouette alone, since noise and a kept rim add most of their area beyond 45°.
MAX_INCIDENCE_DEG = 45.0
_FILL_ROUNDS = 3


@dataclass(frozen=True)
class SeenSurface:
    """The subject's seen surface.

    Attributes
    ----------
    depth_m : (h, w) float64
        Gap-filled, smoothed z-depth (metres), 0 off the subject.
    mask : (h, w) bool
        Its pixels (the subject's returns and the filled gaps).
    area_m2 : float
        Its area (:func:`seen_area_m2`).
    """

    depth_m: np.ndarray
    mask: np.ndarray
    area_m2: float


def fill_gaps(depth_m: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The subject's depth with its small gaps filled.

    Parameters
    ----------
    depth_m : (h, w) float
        z-depth in metres.
    mask : (h, w) bool
        The subject's returns.

    Returns
    -------
    depth_m : (h, w) float64
        The subject's depth, its gaps given the median depth of the returns in their 5 × 5 window
        (repeated up to three times, inwards), 0 elsewhere.
    mask : (h, w) bool
        The returns and the filled gaps.
    """
    from scipy import ndimage

    from wbsa.estimation.subject.feet import windowed_nanmedian

    mask = np.asarray(mask, dtype=bool)
    z = np.where(mask, np.asarray(depth_m, dtype=np.float64), np.nan)
    labels, n = ndimage.label(ndimage.binary_fill_holes(mask) & ~mask)
    small = np.bincount(labels.ravel(), minlength=n + 1) <= GAP_MAX_PX
    small[0] = False
    neighbours = ndimage.convolve(mask.astype(np.int8), np.ones((3, 3), np.int8), mode="constant") - mask
    gaps = small[labels] | (~mask & (neighbours >= 5))
    for _ in range(_FILL_ROUNDS):
        rows, cols = np.nonzero(gaps & ~np.isfinite(z))
        if len(rows) == 0:
            break
        value = windowed_nanmedian(z, 2, rows, cols)
        ok = np.isfinite(value)
        z[rows[ok], cols[ok]] = value[ok]
    filled = np.isfinite(z)
    return np.where(filled, z, 0.0), filled


def seen_area_m2(depth_m: np.ndarray, mask: np.ndarray, intrinsics) -> float:
    """Area (m²) of the smooth surface a depth image's pixels see, each pixel capped at grazing angles.

    Parameters
    ----------
    depth_m : (h, w) float
        Smoothed z-depth in metres.
    mask : (h, w) bool
        The pixels to count (with depth > 0).
    intrinsics : wbsa.camera.Intrinsics

    Returns
    -------
    float
        Σ over the pixels of ``|∂P/∂u × ∂P/∂v|`` (one-sided differences where a neighbour is missing),
        each at most ``z² / (fx·fy·|r|) / cos(MAX_INCIDENCE_DEG)`` (``r``: the pixel's ray with unit z);
        a pixel with no neighbour along a direction counts at the cap.
    """
    from wbsa.core.backproject import ray_directions

    depth = np.asarray(depth_m, dtype=np.float64)
    mask = np.asarray(mask, dtype=bool) & (depth > 0)
    if not mask.any():
        return 0.0
    rows = np.flatnonzero(mask.any(axis=1))
    cols = np.flatnonzero(mask.any(axis=0))
    r0, r1, c0, c1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
    m = np.pad(mask[r0:r1, c0:c1], 1)
    rays = ray_directions(intrinsics, np.arange(r0 - 1, r1 + 1)[:, None], np.arange(c0 - 1, c1 + 1)[None, :])
    z = np.pad(depth[r0:r1, c0:c1], 1)
    p = rays * np.where(m, z, np.nan)[..., None]
    du, dv = _difference(p, m, axis=1), _difference(p, m, axis=0)
    area = np.linalg.norm(np.cross(du, dv), axis=-1)
    cap = z ** 2 / (float(intrinsics.fx) * float(intrinsics.fy) * np.linalg.norm(rays, axis=-1)) \
        / math.cos(math.radians(MAX_INCIDENCE_DEG))
    area = np.where(np.isfinite(area), np.minimum(area, cap), cap)
    return float(area[m].sum())


def _difference(p: np.ndarray, m: np.ndarray, axis: int) -> np.ndarray:
    """(h, w, 3) per-pixel step of the points ``p`` along ``axis``: central where both neighbours are on the
    mask, one-sided where one is, NaN where neither is (``p`` and ``m`` padded by one pixel)."""
    fwd = np.roll(p, -1, axis=axis) - p
    back = p - np.roll(p, 1, axis=axis)
    has_f = np.roll(m, -1, axis=axis)[..., None]
    has_b = np.roll(m, 1, axis=axis)[..., None]
    return np.where(has_f & has_b, 0.5 * (fwd + back), np.where(has_f, fwd, np.where(has_b, back, np.nan)))


def seen_surface(depth_m: np.ndarray, mask: np.ndarray, intrinsics) -> SeenSurface:
    """The subject's :class:`SeenSurface`: gaps filled, depth smoothed, area measured.

    Parameters
    ----------
    depth_m : (h, w) float
        z-depth in metres.
    mask : (h, w) bool
        The subject's returns.
    intrinsics : wbsa.camera.Intrinsics

    Returns
    -------
    SeenSurface
    """
    from wbsa.surface.denoise import denoise_depth

    depth, filled = fill_gaps(depth_m, mask)
    smooth = denoise_depth(depth, "quadratic", sigma_px=SMOOTH_SIGMA_PX).astype(np.float64)
    filled &= smooth > 0
    smooth = np.where(filled, smooth, 0.0)
    return SeenSurface(smooth, filled, seen_area_m2(smooth, filled, intrinsics))
