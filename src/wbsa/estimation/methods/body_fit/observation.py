"""One segmented depth view as the body fit sees it: points, silhouette and depth in a floor-aligned frame.

The fit works in a *view frame* F attached to the floor and the camera (:func:`view_frame`): +Z is the
floor's normal (up), the camera lies on −Y (so a body facing −Y in F faces the camera, azimuth 0), +X
completes a right-handed frame, and the origin is on the floor under the subject. A body in anny's world
frame (standing on z = 0, facing −Y) is placed in F by a turn about +Z by ``yaw = −azimuth`` and a shift.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wbsa.errors import WbsaError

#: Reach (pixels) of the nearest-surface depth map of the free-space term.
_FREE_REACH_PX = 2
#: Most outline pixels kept for the contour term.
MAX_CONTOUR = 800
#: The subject's lowest returns, as this quantile of their heights, give the floor band (:attr:`Observation.floor_band_m`).
FEET_QUANTILE = 0.02
#: Pixels of margin kept around the subject's mask in the silhouette's distance map.
_PAD_PX = 24


@dataclass(frozen=True)
class Observation:
    """What the fit compares a body with.

    Attributes
    ----------
    points : (p, 3) float64
        The subject's returns above the floor (a seeded even subsample), view frame, metres.
    basis : (3, 3) float64
        Rows: the view frame's axes in camera coordinates (``p_F = basis (p_cam − origin)``).
    origin : (3,) float64
        The view frame's origin in camera coordinates (on the floor under the subject).
    camera_position : (3,) float64
        The camera centre in the view frame.
    intrinsics : (4,) float64
        fx, fy, cx, cy.
    skew : float
    outside_px : (h', w') float32
        Distance (pixels) from each pixel of a crop around the mask to the nearest subject pixel, its small gaps
        filled (:func:`wbsa.estimation.subject.seen_surface.fill_gaps`); 0 on it.
    depth : (h', w') float32
        The nearest subject depth (gaps filled) within 2 pixels of each subject pixel of the same crop
        (metres), +inf off the subject.
    crop : (int, int)
        Row and column of the crop's first pixel in the image.
    top_m : float
        Height of the top of the subject's points above the floor (0.998 quantile).
    floor_seen : bool
    n_returns : int
        The subject's returns before subsampling (floor cut applied).
    noise_m : float
        The depth noise measured on the subject (:func:`wbsa.estimation.subject.measure.measured_depth_noise`), metres.
    contour_px : (c, 2) float64
        Crop (row, col) of the subject's outline pixels that border the background (not an occluder in front,
        not the image border), a seeded subsample of at most :data:`MAX_CONTOUR`.
    contour_depth : (c,) float64
        Their depth (m).
    sensor : SensorModel or None
        The camera's depth-noise envelope (:func:`wbsa.sensor.technology.envelope_model`); None: that of a camera
        without a preset.
    floor_band_m : float
        Height above the floor (m) below which a return cannot be told from the floor: the segmentation's floor
        cut (:meth:`wbsa.estimation.subject.cloud.Plane.tolerance`, the floor's measured noise) at the subject's
        lowest returns; 0 without a floor. The mask may lack the feet there, so the silhouette does not
        count the vertices below it.
    """

    points: np.ndarray
    basis: np.ndarray
    origin: np.ndarray
    camera_position: np.ndarray
    intrinsics: np.ndarray
    skew: float
    outside_px: np.ndarray
    depth: np.ndarray
    crop: tuple[int, int]
    top_m: float
    floor_seen: bool
    n_returns: int
    noise_m: float = 0.0
    contour_px: np.ndarray = None
    contour_depth: np.ndarray = None
    sensor: object = None
    floor_band_m: float = 0.0

    def to_camera(self, points_f: np.ndarray) -> np.ndarray:
        """(k, 3) view-frame points in camera coordinates.

        Parameters
        ----------
        points_f : (k, 3) float64
            Points in the view frame, metres.

        Returns
        -------
        (k, 3) float64
            The same points in camera coordinates, metres.
        """
        return np.asarray(points_f, dtype=np.float64) @ self.basis + self.origin

    def elevation_deg(self, centre_f: np.ndarray) -> float:
        """Angle of the camera above the horizontal through ``centre_f`` (view frame), degrees.

        Parameters
        ----------
        centre_f : (3,) float64
            A point in the view frame, metres.
        """
        d = self.camera_position - centre_f
        return float(np.degrees(np.arcsin(d[2] / np.linalg.norm(d))))


def check_inputs(depth_m: np.ndarray, mask: np.ndarray, camera) -> tuple[np.ndarray, np.ndarray]:
    """``depth_m`` as (h, w) float64 and ``mask`` as (h, w) bool, or a one-line :class:`WbsaError`.

    Parameters
    ----------
    depth_m : (h, w) array_like of float
        Depth image, metres in front of the camera; 0 for no return.
    mask : (h, w) bool
        The subject's pixels.
    camera : wbsa.camera.Intrinsics
        The camera that took the image (its ``width`` × ``height`` must match).

    Raises
    ------
    WbsaError
        A shape, dtype or size mismatch, non-finite or negative depths, or no subject pixel with a return.
    """
    try:
        depth = np.asarray(depth_m, dtype=np.float64)
    except (TypeError, ValueError):
        raise WbsaError(f"depth_m must be a 2-D array of metres, got {type(depth_m).__name__}") from None
    m = np.asarray(mask)
    if depth.ndim != 2:
        raise WbsaError(f"depth_m must be a 2-D (h, w) array of metres, got shape {depth.shape}")
    if m.shape != depth.shape:
        raise WbsaError(f"mask shape {m.shape} differs from depth_m shape {depth.shape}")
    if m.dtype != bool:
        raise WbsaError(f"mask must be a boolean (h, w) array, got {m.dtype}")
    if depth.shape != (camera.height, camera.width):
        raise WbsaError(f"depth image is {depth.shape[1]}×{depth.shape[0]} but the camera {camera.name} is "
                        f"{camera.width}×{camera.height}; give the camera that took it")
    bad = ~np.isfinite(depth)
    if bad.any():
        raise WbsaError(f"depth_m has {int(bad.sum())} values that are not finite (NaN or inf); use 0 for "
                        "'no return'")
    if (depth < 0).any():
        raise WbsaError("depth_m has negative values; depth is metres in front of the camera, 0 for 'no return'")
    if not (m & (depth > 0)).any():
        raise WbsaError("the mask holds no pixel with a depth return; nothing to fit")
    return depth, m


def view_frame(points_cam: np.ndarray, floor) -> tuple[np.ndarray, np.ndarray]:
    """The view frame (basis rows, origin) of a subject's (k, 3) camera-frame points (see the module docstring).

    Parameters
    ----------
    points_cam : (k, 3) float64
        The subject's points in camera coordinates, metres.
    floor : Plane or None
        The floor plane in camera coordinates (:func:`wbsa.estimation.subject.cloud.body_frame`).

    Returns
    -------
    basis : (3, 3) float64
        Rows: the view frame's axes in camera coordinates.
    origin : (3,) float64
        The view frame's origin in camera coordinates, metres.
    """
    from wbsa.estimation.subject.cloud import body_frame

    frame = body_frame(points_cam, floor)
    ez = frame.up
    ey = -frame.toward
    ex = np.cross(ey, ez)
    ex /= np.linalg.norm(ex)
    return np.stack([ex, ey, ez]), frame.base


def observe(depth_m: np.ndarray, mask: np.ndarray, camera, floor, n_points: int,
            rng: np.random.Generator, sensor=None) -> Observation:
    """The :class:`Observation` of a checked depth image and subject mask (:func:`check_inputs`).

    Returns on the floor (within its noise, :func:`wbsa.estimation.subject.cloud.above_floor`) are dropped from
    the points; the silhouette keeps every subject pixel (the feet reach the floor).

    Parameters
    ----------
    depth_m : (h, w) float64
        Depth image, metres; 0 for no return.
    mask : (h, w) bool
        The subject's pixels.
    camera : wbsa.camera.Intrinsics
        The camera that took the image.
    floor : Plane or None
        The floor plane in camera coordinates.
    n_points : int
        Most points kept (a seeded even subsample beyond it).
    rng : numpy.random.Generator
        Draws the point and outline subsamples.
    sensor : SensorModel, optional
        The camera's depth-noise model (:func:`wbsa.sensor.technology.envelope_model`); None: that of a camera
        whose technology is unknown.

    Raises
    ------
    WbsaError
        Fewer than 200 returns above the floor (too little of a person to fit).
    """
    from scipy import ndimage

    from wbsa.core.backproject import ray_directions
    from wbsa.estimation.subject.cloud import above_floor
    from wbsa.estimation.subject.measure import measured_depth_noise
    from wbsa.estimation.subject.seen_surface import fill_gaps

    valid = mask & (depth_m > 0)
    rows, cols = np.nonzero(valid)
    points = ray_directions(camera, rows, cols) * depth_m[rows, cols][:, None]
    keep = above_floor(points, floor)
    floor_band = 0.0
    if floor is not None:
        height = floor.height(points)
        floor_band = float(np.median(floor.tolerance(points[height <= np.quantile(height, FEET_QUANTILE)])))
    points = points[keep]
    if len(points) < 200:
        raise WbsaError(f"only {len(points)} subject returns above the floor; too few to fit a body (move closer "
                        "or check the segmentation)")
    basis, origin = view_frame(points, floor)
    pts_f = (points - origin) @ basis.T
    n_returns = len(pts_f)
    if n_returns > n_points:
        pts_f = pts_f[np.sort(rng.choice(n_returns, n_points, replace=False))]
    r0, r1 = max(rows.min() - _PAD_PX, 0), min(rows.max() + _PAD_PX + 1, depth_m.shape[0])
    c0, c1 = max(cols.min() - _PAD_PX, 0), min(cols.max() + _PAD_PX + 1, depth_m.shape[1])
    # the silhouette and the free space with the subject's small gaps filled (holes, dropped outline returns),
    # as the regression's seen surface: a camera's dropout is not a smaller body
    filled_depth, filled = fill_gaps(np.where(valid, depth_m, 0.0)[r0:r1, c0:c1], valid[r0:r1, c0:c1])
    outside = ndimage.distance_transform_edt(~filled).astype(np.float32)
    # the nearest surface within 2 pixels: a vertex on an arm's outline that rounds onto the trunk behind it
    # (or onto the floor) must not count as hiding it
    depth = ndimage.maximum_filter(np.where(filled, -filled_depth, -np.inf), size=2 * _FREE_REACH_PX + 1)
    depth = np.where(filled, -depth, np.inf).astype(np.float32)
    top = float(np.quantile(pts_f[:, 2], 0.998))
    contour_px, contour_depth = outline(depth_m[r0:r1, c0:c1], valid[r0:r1, c0:c1], (r0, c0), depth_m.shape, rng)
    return Observation(points=pts_f, basis=basis, origin=origin, camera_position=-basis @ origin,
                       intrinsics=np.array([camera.fx, camera.fy, camera.cx, camera.cy], dtype=np.float64),
                       skew=float(getattr(camera, "skew", 0.0) or 0.0), outside_px=outside, depth=depth,
                       crop=(int(r0), int(c0)), top_m=top, floor_seen=floor is not None, n_returns=n_returns,
                       noise_m=measured_depth_noise(depth_m, valid), contour_px=contour_px,
                       contour_depth=contour_depth, sensor=sensor, floor_band_m=floor_band)


def outline(depth: np.ndarray, sub: np.ndarray, corner: tuple[int, int], shape: tuple[int, int],
            rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """The subject's outline pixels on a crop that border background, and their depths.

    An outline pixel (a subject pixel with a non-subject 4-neighbour) is kept when none of its non-subject
    neighbours is nearer the camera than it by more than 5 cm (an occluder: the outline there is not the
    body's) and it is not on the image border (the body may go on beyond it).

    Parameters
    ----------
    depth : (h', w') float64
        The depth image's crop, metres; 0 for no return.
    sub : (h', w') bool
        The subject's pixels in the crop.
    corner : (int, int)
        Image row and column of the crop's first pixel.
    shape : (int, int)
        The whole image's (h, w).
    rng : numpy.random.Generator
        Draws the subsample of at most :data:`MAX_CONTOUR` pixels.

    Returns
    -------
    pixels : (c, 2) float64
        Crop (row, col) of the kept outline pixels.
    depth : (c,) float64
        Their depth, metres.
    """
    from scipy import ndimage

    h, w = sub.shape
    edge = sub & ~ndimage.binary_erosion(sub)
    near = np.zeros_like(sub)
    for dr, dc in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        shifted_sub = np.zeros_like(sub)
        shifted_depth = np.zeros_like(depth)
        rs, rd = (slice(dr, None), slice(None, h - dr)) if dr >= 0 else (slice(None, h + dr), slice(-dr, None))
        cs, cd = (slice(dc, None), slice(None, w - dc)) if dc >= 0 else (slice(None, w + dc), slice(-dc, None))
        shifted_sub[rd, cd] = sub[rs, cs]
        shifted_depth[rd, cd] = depth[rs, cs]
        occluder = ~shifted_sub & (shifted_depth > 0) & (shifted_depth < depth - 0.05)
        near |= occluder
    rows, cols = np.nonzero(edge & ~near)
    r_img, c_img = rows + corner[0], cols + corner[1]
    inside = (r_img > 0) & (c_img > 0) & (r_img < shape[0] - 1) & (c_img < shape[1] - 1)
    rows, cols = rows[inside], cols[inside]
    if len(rows) > MAX_CONTOUR:
        keep = np.sort(rng.choice(len(rows), MAX_CONTOUR, replace=False))
        rows, cols = rows[keep], cols[keep]
    return np.stack([rows, cols], axis=1).astype(np.float64), depth[rows, cols].astype(np.float64)
