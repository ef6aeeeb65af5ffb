"""What the estimator measures on the subject's pixels: VBSA, stature, size, distance, view cues.

:func:`measure_subject` is the one code path from (depth image, subject mask, floor) to the numbers the
models use. Training renders go through it exactly as real images do (with the known floor of the render
in place of the detected one), so the VBSA a model is fitted on is the VBSA it is later given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wbsa.core.mesh import TriangleMesh
from wbsa.estimation.subject.cloud import BodyFrame, Plane, above_floor, body_frame

#: Height bins of the view descriptor's profiles (stature units) and half-width of its central strip.
PROFILE_HEIGHT = np.linspace(0.0, 1.04, 41)
PROFILE_STRIP = 0.08
#: Height bands (stature units) of the shape measures: width and thickness of each band, metres.
SHAPE_BANDS = np.linspace(0.0, 1.0, 21)
#: The scalar measures of :class:`SubjectMeasures` (its :meth:`~SubjectMeasures.features`; the models' inputs).
SCALAR_MEASURES = ("vbsa_m2", "seen_area_m2", "stature_m", "silhouette_m2", "width_m", "thickness_m", "distance_m", "elevation_deg",
                   "elevation_axis_deg", "pitch_m", "n_pixels", "mixed_share", "gap_share", "edge_gap_share",
                   "depth_noise_m", "floor_seen")
#: Low pixels (within this of the floor) with fewer subject neighbours than this in their 5×5 window are
#: dropped: noisy floor returns that escaped the floor cut next to the feet.
_LOW_BAND_M = 0.10
_MIN_NEIGHBOURS = 8
#: The crown's radius of curvature as a camera in front of the head sees it (m): a camera below the top of the
#: head at an angle φ sees its highest point about ``CROWN_RADIUS_M · (1 − cos φ)`` below the top. Fitted on
#: 80 renders of seed 2000 (40 by the project's renderer, 40 by the plain one; ``benchmarks/bench_estimate.py``'s
#: subjects, not the held-out seed 1000): 0.12 m on the project's, 0.24 m on the plain one's.
CROWN_RADIUS_M = 0.18
#: The top of the head is the apex of a parabola through the upper profile of the seen surface within this
#: depth of its highest point (:func:`crown_top_m`).
CROWN_PROFILE_M = 0.04


@dataclass(frozen=True)
class SubjectMeasures:
    """Measures of one subject in one depth image (SI units; angles in degrees).

    Attributes
    ----------
    vbsa_m2 : float
        Area of the grid reconstruction of the subject's pixels (paper's VBSA).
    seen_area_m2 : float
        Area of the seen surface (:mod:`wbsa.estimation.subject.seen_surface`: gaps filled, depth smoothed, the
        rim capped): the visible area the models read, which holes, dropped returns and noise hardly move.
    stature_m : float
        Height of the top of the subject above the floor (or its extent along its long axis): the apex of the
        seen surface's upper profile (:func:`crown_top_m`), raised by the part of the crown the camera cannot see
        (:data:`CROWN_RADIUS_M`).
    silhouette_m2 : float
        Σ z² / (fx·fy) over the seen surface's pixels (its gaps filled): the subject's area projected on a plane facing the camera.
    width_m, thickness_m : float
        Extents across (image right) and along (towards the camera) the horizontal plane.
    distance_m : float
        Camera to the subject's centre (half its stature above the floor, mid-width).
    elevation_deg : float
        Angle of the camera above the horizontal through the subject's centre.
    elevation_axis_deg : float
        The same from the body's long axis alone (what is left without a floor).
    pitch_m : float
        Pixel pitch at the subject's distance, ``distance / sqrt(fx·fy)``.
    n_pixels : int
    mixed_share, gap_share, edge_gap_share : float
        How the camera treated the subject's outline: mixed returns beside it, one-pixel gaps along it and
        the share of its depth edges behind a gap (:func:`wbsa.estimation.subject.mixed_pixels.outline_shares`).
    depth_noise_m : float
        The depth noise on the subject (:func:`measured_depth_noise`), metres: the VBSA of a noisy image differs
        from that of a smooth one, and cameras differ in their noise.
    floor_seen : bool
    touches_border : bool
        Subject pixels on the image border: the subject may be cut off.
    mask : (h, w) bool
        The pixels measured (floor cut applied).
    descriptor : (160,) float32
        View cues (:func:`view_descriptor`).
    shape : (40,) float32
        Width then thickness (metres) of 20 height bands of the subject (:func:`shape_bands`).
    surface : TriangleMesh
        The reconstructed visible surface (camera frame).
    frame : BodyFrame
    """

    vbsa_m2: float
    seen_area_m2: float
    stature_m: float
    silhouette_m2: float
    width_m: float
    thickness_m: float
    distance_m: float
    elevation_deg: float
    elevation_axis_deg: float
    pitch_m: float
    n_pixels: int
    mixed_share: float
    gap_share: float
    edge_gap_share: float
    depth_noise_m: float
    floor_seen: bool
    touches_border: bool
    mask: np.ndarray
    descriptor: np.ndarray
    shape: np.ndarray
    surface: TriangleMesh
    frame: BodyFrame

    def features(self) -> dict[str, float]:
        """The scalar measures (:data:`SCALAR_MEASURES`) as a dict (for tables and models)."""
        return {k: float(getattr(self, k)) for k in SCALAR_MEASURES}


def measured_depth_noise(depth_m: np.ndarray, mask: np.ndarray) -> float:
    """Standard deviation of the depth noise on the subject's inner pixels (m), robust to its outline.

    Three pixels in a row (or a column) of a smooth surface have a second difference z₋ − 2z + z₊ near 0
    (a torso's curvature gives about 0.1 mm at Kinect pitches, a limb's a few millimetres on a phone
    LiDAR's 2 cm pixels); independent noise of σ gives it a standard deviation of √6 σ. σ is read from the
    median absolute second difference (× 1.4826) over the triples inside the mask eroded by two pixels,
    rows and columns together. On depth in whole millimetres that median moves in half-millimetre steps,
    so the result does in steps of 0.6 mm (an ideal render reads 0.6 mm, quantised disparity often 0).
    (Not :func:`wbsa.estimation.subject.cloud.depth_noise_m`, the noise envelope assumed for plane fits.)

    Parameters
    ----------
    depth_m : (h, w) float64
    mask : (h, w) bool

    Returns
    -------
    float
        0 with fewer than 50 triples (a subject too small to tell).
    """
    from scipy import ndimage

    inner = ndimage.binary_erosion(mask, iterations=2)
    z = np.where(inner, depth_m, np.nan)
    d2 = np.concatenate([(z[:, :-2] - 2.0 * z[:, 1:-1] + z[:, 2:]).ravel(),
                         (z[:-2] - 2.0 * z[1:-1] + z[2:]).ravel()])
    d2 = d2[np.isfinite(d2)]
    if len(d2) < 50:
        return 0.0
    return float(1.4826 * np.median(np.abs(d2)) / math.sqrt(6.0))


def clean_low_pixels(mask: np.ndarray, height_m: np.ndarray) -> np.ndarray:
    """``mask`` without sparse pixels near the floor (fewer than 8 subject neighbours in a 5×5 window).

    Parameters
    ----------
    mask : (h, w) bool
        The subject's pixels.
    height_m : (h, w) float64
        Height of each pixel's return over the floor (inf where none).
    """
    from scipy import ndimage

    counts = ndimage.convolve(mask.astype(np.int16), np.ones((5, 5), np.int16), mode="constant")
    return mask & ~((height_m < _LOW_BAND_M) & (counts - 1 < _MIN_NEIGHBOURS))


def _crop(mask: np.ndarray, pad: int = 3) -> tuple[slice, slice]:
    rows = np.flatnonzero(mask.any(axis=1))
    cols = np.flatnonzero(mask.any(axis=0))
    h, w = mask.shape
    return (slice(max(rows[0] - pad, 0), min(rows[-1] + pad + 1, h)),
            slice(max(cols[0] - pad, 0), min(cols[-1] + pad + 1, w)))


def crown_top_m(q: np.ndarray, pitch_m: float) -> float:
    """Height of the top of the head: the apex of the seen surface's upper profile, not its highest point.

    The highest of thousands of points rises with the noise of the outline (a camera's lateral noise and its
    mixed returns push single pixels out of the silhouette: on the project's renders at 3× its noise, the
    highest point rose 1.4 cm where the apex rose 1.0 cm, and the plain renderer's, without lateral noise, read
    0.45 cm lower than the project's where the apex reads the same; seed 2000, 20 captures). The profile is the
    highest point of each lateral bin one pixel pitch wide within :data:`CROWN_PROFILE_M` of the top; a
    parabola fitted to it gives the apex (the highest point where fewer than 5 bins or no downward curve).

    Parameters
    ----------
    q : (k, 3) float64
        Body-frame points (lateral, height, toward the camera), metres.
    pitch_m : float
        Lateral size of a pixel at the head, metres.

    Returns
    -------
    float
        Height of the apex (metres, body frame), at most that of the highest point.

    Examples
    --------
    >>> x = np.linspace(-0.1, 0.1, 41)
    >>> q = np.column_stack([x, 1.8 - x ** 2 / 0.2, np.zeros_like(x)])
    >>> q[20, 1] += 0.01  # one pixel pushed out of the outline
    >>> round(crown_top_m(q, 0.005), 4)  # the highest point reads 1.81
    1.8007
    """
    h, x = q[:, 1], q[:, 0]
    k = int(np.argmax(h))
    near = h > h[k] - CROWN_PROFILE_M
    bins = np.round((x[near] - x[k]) / max(float(pitch_m), 1e-6)).astype(np.int64)
    ub, inv = np.unique(bins, return_inverse=True)
    profile = np.full(len(ub), -np.inf)
    np.maximum.at(profile, inv, h[near])
    if len(ub) < 5:
        return float(h[k])
    c2, c1, c0 = np.polyfit(ub * float(pitch_m), profile, 2)
    if c2 >= 0.0:
        return float(h[k])
    return min(float(c0 - c1 * c1 / (4.0 * c2)), float(h[k]))


def seen_top_m(points: np.ndarray, q: np.ndarray, up: np.ndarray, focal_px: float) -> float:
    """Height of the top of the head from the seen surface: its apex (:func:`crown_top_m`, at the pixel pitch
    of the highest point's range) raised by :data:`CROWN_RADIUS_M` · (1 − cos φ), φ the angle of the line of
    sight from the camera up to that point (0 with the camera above it).

    Parameters
    ----------
    points : (k, 3) float64
        The seen surface's points, camera frame (metres).
    q : (k, 3) float64
        The same points as (lateral, height, toward the camera), metres: heights over the floor.
    up : (3,) float64
        The upward unit vector, camera frame.
    focal_px : float
        The camera's focal length, pixels.

    Returns
    -------
    float
        Metres, in the heights of ``q``.
    """
    k = int(np.argmax(q[:, 1]))
    sight = np.asarray(points[k], dtype=np.float64)
    reach = max(float(np.linalg.norm(sight)), 1e-9)
    rise = float(np.clip(sight @ np.asarray(up, dtype=np.float64) / reach, 0.0, 1.0))
    return crown_top_m(q, reach / float(focal_px)) + CROWN_RADIUS_M * (1.0 - math.sqrt(1.0 - rise * rise))


def _elevation(frame: BodyFrame, points: np.ndarray, floor_seen: bool,
               top_points: np.ndarray | None = None, focal_px: float = 1.0) -> tuple[float, float, float, float]:
    """(stature, mid-lateral, distance, elevation°) of a subject's points in a body frame.

    The top is :func:`seen_top_m` of ``top_points`` (the seen surface's; default ``points``' 99.8th
    percentile of height).
    """
    q = frame.coordinates(points)
    if top_points is None:
        top = float(np.quantile(q[:, 1], 0.998))
    else:
        top = seen_top_m(top_points, frame.coordinates(top_points), frame.up, focal_px)
    stature = max(top if floor_seen else top - float(np.quantile(q[:, 1], 0.002)), 1e-3)
    mid_lat = 0.5 * float(np.quantile(q[:, 0], 0.002) + np.quantile(q[:, 0], 0.998))
    centre = frame.base + frame.right * mid_lat + frame.up * (stature / 2.0)
    distance = float(np.linalg.norm(centre))
    elevation = math.degrees(math.asin(float(np.clip(-frame.up @ centre / distance, -1.0, 1.0))))
    return stature, mid_lat, distance, elevation


def measure_subject(depth_m: np.ndarray, mask: np.ndarray, intrinsics, floor: Plane | None,
                    mixed: np.ndarray | None = None) -> SubjectMeasures:
    """Measure the subject's pixels of a depth image.

    Parameters
    ----------
    depth_m : (h, w) float
        z-depth in metres.
    mask : (h, w) bool
        The subject's pixels (from :func:`wbsa.estimation.subject.segment.segment_subject`, or a render's).
    intrinsics : wbsa.camera.Intrinsics
    floor : Plane or None
        The floor in the camera frame; returns within its noise are cut (feet soles), as in training.
    mixed : (h, w) bool, optional
        Returns found mixed before segmentation (:func:`wbsa.estimation.subject.mixed_pixels.repair_mixed_pixels`),
        for ``mixed_share``.

    Returns
    -------
    SubjectMeasures
    """
    from wbsa.core.backproject import frame_from_depth_image, ray_directions
    from wbsa.surface import reconstruct

    from wbsa.estimation.subject.mixed_pixels import outline_shares
    from wbsa.estimation.subject.seen_surface import seen_surface

    depth = np.asarray(depth_m, dtype=np.float64)
    mask = np.asarray(mask, dtype=bool) & np.isfinite(depth) & (depth > 0)
    if not mask.any():
        from wbsa.errors import WbsaError

        raise WbsaError("the subject has no depth returns; check the mask and the depth image")
    mixed_share, gap_share, edge_gap_share = outline_shares(depth, mask, mixed)
    rs, cs = _crop(mask)
    sub_mask = mask[rs, cs].copy()
    sub_depth = depth[rs, cs]
    rows, cols = np.nonzero(sub_mask)
    points = ray_directions(intrinsics, rows + rs.start, cols + cs.start) * sub_depth[rows, cols][:, None]
    if floor is not None:
        keep = above_floor(points, floor)
        height = np.full(sub_mask.shape, np.inf)
        height[rows, cols] = floor.height(points)
        sub_mask[rows[~keep], cols[~keep]] = False
        sub_mask = clean_low_pixels(sub_mask, height)
        keep = sub_mask[rows, cols]
        points, rows, cols = points[keep], rows[keep], cols[keep]
    mask = np.zeros_like(mask)
    mask[rs, cs] = sub_mask
    frame = body_frame(points, floor)
    seen = seen_surface(np.where(mask, depth, 0.0), mask, intrinsics)
    sr, sc = np.nonzero(seen.mask)
    seen_points = ray_directions(intrinsics, sr, sc) * seen.depth_m[sr, sc][:, None]
    focal = math.sqrt(float(intrinsics.fx) * float(intrinsics.fy))
    stature, mid_lat, distance, elevation = _elevation(frame, points, floor is not None, seen_points, focal)
    axis_elevation = elevation if floor is None else _elevation(body_frame(points, None), points, False)[3]
    q = frame.coordinates(points)
    surface = reconstruct(frame_from_depth_image(np.where(mask, depth, 0.0), intrinsics, normals=False), "grid")
    border = bool(mask[0].any() or mask[-1].any() or mask[:, 0].any() or mask[:, -1].any())
    return SubjectMeasures(
        vbsa_m2=surface.area_m2, seen_area_m2=seen.area_m2, stature_m=stature, silhouette_m2=float(np.sum(seen.depth_m[seen.mask] ** 2)) / (intrinsics.fx * intrinsics.fy),
        width_m=float(np.quantile(q[:, 0], 0.998) - np.quantile(q[:, 0], 0.002)),
        thickness_m=float(np.quantile(q[:, 2], 0.998) - np.quantile(q[:, 2], 0.002)),
        distance_m=distance, elevation_deg=elevation, elevation_axis_deg=axis_elevation, pitch_m=distance / focal,
        n_pixels=int(mask.sum()), mixed_share=mixed_share, gap_share=gap_share,
        edge_gap_share=edge_gap_share, depth_noise_m=measured_depth_noise(depth, mask), floor_seen=floor is not None,
        touches_border=border, mask=mask,
        descriptor=view_descriptor(q - np.array([mid_lat, 0.0, 0.0]), stature), shape=shape_bands(q, stature),
        surface=surface, frame=frame)


def _binned(values: np.ndarray, bins: np.ndarray, n: int, how: str) -> np.ndarray:
    """Per-bin max, min or mean of ``values`` (0 for empty bins)."""
    out = np.zeros(n)
    if how == "mean":
        count = np.bincount(bins, minlength=n)
        total = np.bincount(bins, weights=values, minlength=n)
        return np.divide(total, count, out=out, where=count > 0)
    order = np.lexsort((values, bins))
    b, v = bins[order], values[order]
    if len(b) == 0:
        return out
    last = np.r_[np.flatnonzero(b[1:] != b[:-1]), len(b) - 1]
    first = np.r_[0, last[:-1] + 1]
    out[b[last]] = v[last] if how == "max" else v[first]
    return out


def view_descriptor(q: np.ndarray, stature_m: float) -> np.ndarray:
    """View cues of body-frame points: depth and width profiles over height, in stature units.

    Every cue is unchanged by a left/right mirror image, so θ and −θ give the same descriptor.

    Parameters
    ----------
    q : (k, 3) float
        (lateral, height, toward-camera) coordinates, lateral centred on the subject.
    stature_m : float

    Returns
    -------
    (160,) float32
        On 40 height bins (0–1.04 statures): the nearest and the mean depth (relative to the median) of a
        central strip (|lateral| < 0.08 statures), the nearest depth and the lateral extent of the whole
        subject; 0 where a bin is empty.
    """
    a = q[:, 0] / stature_m
    b = q[:, 1] / stature_m
    d = (q[:, 2] - np.median(q[:, 2])) / stature_m
    n_p = len(PROFILE_HEIGHT) - 1
    k = np.clip(np.searchsorted(PROFILE_HEIGHT, b) - 1, 0, n_p - 1)
    strip = np.abs(a) < PROFILE_STRIP
    width = _binned(a, k, n_p, "max") - _binned(a, k, n_p, "min")
    return np.concatenate([_binned(d[strip], k[strip], n_p, "max"), _binned(d[strip], k[strip], n_p, "mean"),
                           _binned(d, k, n_p, "max"), width]).astype(np.float32)


def shape_bands(q: np.ndarray, stature_m: float) -> np.ndarray:
    """Width and thickness (metres, 1–99 % quantile extents) of 20 height bands of body-frame points.

    Parameters
    ----------
    q : (k, 3) float64
        Body-frame points (lateral, height, toward the camera), metres.
    stature_m : float

    Returns
    -------
    (40,) float32
        Widths (across the image) of the bands from the feet up, then thicknesses (towards the camera).
    """
    n = len(SHAPE_BANDS) - 1
    k = np.clip(np.searchsorted(SHAPE_BANDS, q[:, 1] / stature_m) - 1, 0, n - 1)
    out = np.zeros(2 * n)
    for band in range(n):
        sel = q[k == band]
        if len(sel) >= 5:
            lo, hi = np.quantile(sel[:, [0, 2]], [0.01, 0.99], axis=0)
            out[band], out[n + band] = hi - lo
    return out.astype(np.float32)
