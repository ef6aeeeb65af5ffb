"""The learned start's input: a segmented depth view as a fixed-size, normalised picture of the body.

:func:`start_crop` back-projects the subject's returns above the floor, places them in the body fit's view
frame (:func:`~wbsa.estimation.methods.body_fit.observation.view_frame`: +Z up from the floor, the camera on −Y)
and draws them orthographically onto a grid of :data:`CROP_SHAPE` cells looking along +Y: rows run down from
above the subject's top to below its base, columns across, centred on the points' median; one cell is
:data:`SPAN_OF_HEIGHT` × the subject's height / :data:`CROP_SHAPE`\\ [0] on either axis. Each return covers
the cells whose centre lies in its pixel's footprint grown by half a cell on every side
(so the picture's outline lies half a cell outside the body's whatever the camera's sampling and noise) (its depth over the focal length, stretched upwards by
the ray's elevation), the nearest return winning, so a body twice as far, seen by a camera of another
focal length, placed anywhere in the image, or seen from above, gives the same picture up to the sensor's
sampling and noise. Channel 0 is the depth of the nearest return behind the body's median depth, in units
of :data:`DEPTH_SCALE_M` and clipped to ±\\ :data:`DEPTH_CLIP`, 0 off the body; channel 1 the body's cells.
The height itself, which the picture scales away, is kept beside it (:attr:`StartCrop.height_m`).

A render and a real frame go through the same function with the same kind of mask and floor (the
segmentation's, :func:`~wbsa.estimation.subject.segment.segment_subject`): the training crops are made by it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wbsa.errors import WbsaError

#: (rows, columns) of the crop.
CROP_SHAPE = (96, 64)
#: Height the crop's rows span, as a multiple of the subject's height (the rest split above and below).
SPAN_OF_HEIGHT = 1.1
#: Depth (m) of one unit of the depth channel.
DEPTH_SCALE_M = 0.25
#: The depth channel's bound (units of :data:`DEPTH_SCALE_M`).
DEPTH_CLIP = 2.0
#: Quantile of the points' heights read as the subject's top (as the fit's :attr:`Observation.top_m`).
TOP_QUANTILE = 0.998
#: Fewest returns above the floor a crop is made from (as the fit's observation).
MIN_RETURNS = 200
#: A return's footprint over its pixel's size at its depth (neighbouring footprints overlap a little).
_FOOTPRINT = 1.1
#: Most cells one return covers along each axis.
_MAX_CELLS = 3


@dataclass(frozen=True)
class StartCrop:
    """The learned start's input of one view.

    Attributes
    ----------
    image : (2, 96, 64) float32
        Channel 0: depth behind the body's median depth / :data:`DEPTH_SCALE_M`, clipped, 0 off the body;
        channel 1: 1 on the body, 0 off it. Row 0 is the top.
    height_m : float
        Height of the subject's top (:data:`TOP_QUANTILE` of its points) above its base: the floor, or without
        one the lowest return.
    cell_m : float
        Size of one cell, metres.
    floor_seen : bool
        Whether a floor was given (the base is then the floor, and the returns on it are cut).
    """

    image: np.ndarray
    height_m: float
    cell_m: float
    floor_seen: bool


def start_crop(depth_m: np.ndarray, mask: np.ndarray, camera, floor) -> StartCrop:
    """The normalised crop of one segmented depth view (see the module docstring).

    Parameters
    ----------
    depth_m : (h, w) float
        Depth image, metres in front of the camera; 0 for no return.
    mask : (h, w) bool
        The subject's pixels.
    camera : wbsa.camera.Intrinsics
        The camera that took the image (``width`` × ``height`` match the image).
    floor : wbsa.estimation.subject.cloud.Plane or None
        The floor in camera coordinates, if one was found; its returns are cut (within its noise envelope).

    Returns
    -------
    StartCrop

    Raises
    ------
    WbsaError
        Bad inputs (:func:`~wbsa.estimation.methods.body_fit.observation.check_inputs`), or fewer than
        :data:`MIN_RETURNS` returns above the floor.
    """
    from wbsa.core.backproject import ray_directions
    from wbsa.estimation.methods.body_fit.observation import check_inputs, view_frame
    from wbsa.estimation.subject.cloud import above_floor

    depth, m = check_inputs(depth_m, mask, camera)
    rows, cols = np.nonzero(m & (depth > 0))
    points = ray_directions(camera, rows, cols) * depth[rows, cols][:, None]
    keep = above_floor(points, floor)
    points = points[keep]
    if len(points) < MIN_RETURNS:
        raise WbsaError(f"only {len(points)} subject returns above the floor; too few for the learned start (move "
                        "closer or check the segmentation)")
    basis, origin = view_frame(points, floor)
    p = (points - origin) @ basis.T
    height = float(np.quantile(p[:, 2], TOP_QUANTILE))
    if not height > 0.1:
        raise WbsaError(f"the subject's points reach only {height:.2f} m above their base; too flat for the learned "
                        "start (check the segmentation and the floor)")
    n_rows, n_cols = CROP_SHAPE
    cell = SPAN_OF_HEIGHT * height / n_rows
    top = height + 0.5 * (SPAN_OF_HEIGHT - 1.0) * height
    # a return's footprint: its pixel's size at its depth (a tenth more, so that neighbours leave no crack
    # between them), taller where the ray comes from above or below
    size = _FOOTPRINT * points[:, 2] / float(camera.fx)
    ray = p + basis @ origin  # from the camera (at −basis·origin in the frame) to the point
    cos_el = np.hypot(ray[:, 0], ray[:, 1]) / np.linalg.norm(ray, axis=1)
    u = (p[:, 0] - float(np.median(p[:, 0]))) / cell + 0.5 * n_cols  # columns, continuous
    v = (top - p[:, 2]) / cell  # rows, continuous
    # the footprint grown by one cell: every cell within half a cell of the surface seen is covered, however
    # finely the camera samples it and however far the depth noise moves its returns
    half_u = 0.5 * size / cell + 0.5
    half_v = 0.5 * size / np.maximum(cos_el, 0.5) / cell + 0.5
    image = _splat(u, v, half_u, half_v, p[:, 1], CROP_SHAPE)
    on = np.isfinite(image)
    rel = np.where(on, np.clip((image - float(np.median(p[:, 1]))) / DEPTH_SCALE_M, -DEPTH_CLIP, DEPTH_CLIP), 0.0)
    return StartCrop(np.stack([rel, on]).astype(np.float32), height, float(cell), floor is not None)


def _splat(u: np.ndarray, v: np.ndarray, half_u: np.ndarray, half_v: np.ndarray, depth: np.ndarray,
           shape: tuple[int, int]) -> np.ndarray:
    """The nearest depth over each cell whose centre lies in a return's footprint; +inf where none.

    Parameters
    ----------
    u, v : (k,) float64
        Column and row of each return (cell units; cell ``(i, j)`` has its centre at ``(i + 0.5, j + 0.5)``).
    half_u, half_v : (k,) float64
        Half the footprint's width and height, cell units.
    depth : (k,) float64
        Depth of each return along the view (metres).
    shape : (int, int)
        (rows, columns).

    Returns
    -------
    (rows, columns) float64
    """
    n_rows, n_cols = shape
    j0 = np.ceil(u - half_u - 0.5).astype(np.int64)
    j1 = np.minimum(np.floor(u + half_u - 0.5).astype(np.int64), j0 + _MAX_CELLS - 1)
    i0 = np.ceil(v - half_v - 0.5).astype(np.int64)
    i1 = np.minimum(np.floor(v + half_v - 0.5).astype(np.int64), i0 + _MAX_CELLS - 1)
    flat = np.full(n_rows * n_cols, np.inf)
    for di in range(_MAX_CELLS):
        for dj in range(_MAX_CELLS):
            i, j = i0 + di, j0 + dj
            ok = (i <= i1) & (j <= j1) & (i >= 0) & (i < n_rows) & (j >= 0) & (j < n_cols)
            np.minimum.at(flat, i[ok] * n_cols + j[ok], depth[ok])
    return flat.reshape(shape)
