"""The subject's feet down to the floor: the lowest returns, hidden in the floor's depth noise.

The floor cut of the clustering (2.5 σ of the depth noise) hides the lowest centimetres of the feet, where
no threshold on one return's height tells a foot from the floor. :func:`grow_feet` adds them back with
three rules (the returns must be in no other object, not on or behind a wall, and 8-connected to the
subject in the image):

* **soles** (:func:`sole_pixels`): down each image column, from the end of every run of subject
  returns near the floor, a change point between "the foot goes on" and "the floor in front";
* **toes and heels across the image** (:func:`raised_pixels`): in side views, floor-level returns whose
  neighbourhood, by its median height, stands above what the same median reaches on the bare floor;
* **elsewhere**: returns above the measures' floor cut and the floor's own measured noise.

The measures (:func:`~wbsa.estimation.subject.measure.measure_subject`) cut the floor strip again, as in training,
so these rules shape the subject's mask far more than its VBSA.

Every function is pure numpy on the returns of one depth image: ``pix`` (k,) int flat pixel indices of an
(h, w) image and ``points`` (k, 3) float64 their camera-frame points (metres).
"""

from __future__ import annotations

import numpy as np

from wbsa.estimation.subject.cloud import Plane, above_floor

#: Subject returns this close to the floor (m) end the runs the soles are looked for under.
FEET_BAND_M = 0.12
#: Width of the window of the median height at the feet (m); 5 or 7 pixels, else no window is taken.
RAISED_WINDOW_M = 0.04
#: Floor returns at least this far from the subject (m at the feet) give the floor's own median heights ...
RAISED_AWAY_M = 0.25
#: ... and this quantile of them is the highest the bare floor reaches ...
RAISED_QUANTILE = 0.999
#: ... but never less than this (m).
RAISED_MIN_M = 0.005
#: Medians are taken this many windows at a time (bounds the memory to about 20 MB).
_CHUNK = 50_000


def grow_feet(mask: np.ndarray, pix: np.ndarray, points: np.ndarray, pixel_label: np.ndarray,
              floor: Plane | None, walls: list[Plane], fx: float) -> np.ndarray:
    """The subject's mask with the lowest returns of its feet added (see the module doc).

    Parameters
    ----------
    mask : (h, w) bool
        The subject's pixels from the clustering.
    pix : (k,) int
        Flat pixel index of every return.
    points : (k, 3) float64
        Camera-frame point of every return (m).
    pixel_label : (k,) int
        Object of every return (−1: none).
    floor : Plane or None
        Without a floor, ``mask`` is returned as it is.
    walls : list of Plane
    fx : float
        Focal length in pixels (for the pixel pitch at the feet).

    Returns
    -------
    (h, w) bool
    """
    from scipy import ndimage

    if floor is None:
        return mask
    height_m = floor.height(points)
    free = pixel_label < 0
    for wall in walls:
        free &= wall.height(points) > wall.tolerance(points)
    looked, sole = sole_pixels(mask, pix, points, floor, free, height_m)
    clear = above_floor(points, floor) & (height_m > floor.tolerance(points))
    raised = raised_pixels(mask, pix, points, height_m, free, fx)
    cand = free & (np.where(looked, sole, clear) | raised)
    grow = np.zeros(mask.size, dtype=bool)
    grow[pix[cand]] = True
    both = mask | grow.reshape(mask.shape)
    labels, _ = ndimage.label(both, structure=np.ones((3, 3), dtype=bool))
    touching = np.unique(labels[mask])
    return np.isin(labels, touching[touching > 0])


def sole_pixels(mask: np.ndarray, pix: np.ndarray, points: np.ndarray, floor: Plane, free: np.ndarray,
                height_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Returns under the feet that were looked at, and those of them that are the feet's.

    Walking down an image column from the end of a run of subject returns that lies within
    :data:`FEET_BAND_M` of the floor, the returns first continue the foot (range near the foot's) and then
    show the floor in front of it (range near where the ray meets the floor); the split is a change point
    (:func:`walk_columns`). Every run of a column is walked, so the far foot, seen above the near one,
    keeps its sole too. A foot return found so must have a subject or foot return beside it in its row: a
    sole is a strip across the foot, and a lone column of "foot" is the floor's noise.

    Parameters
    ----------
    mask : (h, w) bool
    pix : (k,) int
    points : (k, 3) float64
    floor : Plane
    free : (k,) bool
        Returns in no object and not on or behind a wall (the walks cross only these).
    height_m : (k,) float64
        Height of every return over the floor.

    Returns
    -------
    looked, feet : (k,) bool
    """
    h, w = mask.shape
    rows, cols = np.divmod(pix, w)
    subject = mask.ravel()[pix]
    if not subject.any():
        none = np.zeros(len(pix), dtype=bool)
        return none, none
    range_m = np.linalg.norm(points, axis=1)
    ray_down = -(points @ floor.normal) / np.maximum(range_m, 1e-9)  # cosine between the ray and the floor's normal
    floor_range_m = np.where(ray_down > 1e-6, -floor.offset / np.maximum(ray_down, 1e-6), np.inf)
    sigma_m = floor.unit_noise(points) * floor.noise_scale
    low = height_m < FEET_BAND_M
    looked, feet = walk_columns(cols, rows, subject, low, free & low, (range_m, floor_range_m, sigma_m))
    feet &= height_m > 0.0
    return looked, feet & _beside_in_row(feet | subject, pix, (h, w))


def walk_columns(cols: np.ndarray, rows: np.ndarray, foot: np.ndarray, low: np.ndarray, walkable: np.ndarray,
                 models: tuple[np.ndarray, np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Change points down image columns, from the end of every low run of ``foot`` returns.

    The split after j returns of a walk costs the squared range errors (capped at 3 σ) of its first j
    returns against the foot's range (median of the run's last three) and of the rest against the floor's;
    the cheapest split wins, so one noisy return cannot move it far.

    Parameters
    ----------
    cols, rows : (k,) int
        Image column and row of every return.
    foot : (k,) bool
        Returns known to be the subject's.
    low, walkable : (k,) bool
        Returns near the floor (where runs may end), and those a walk may cross.
    models : ((k,) float64, (k,) float64, (k,) float64)
        Range of every return, the range where its ray meets the floor, and its depth noise (m).

    Returns
    -------
    looked, found : (k,) bool
        Returns walked over, and those of them before a change point (the foot's).
    """
    range_m, floor_range_m, sigma_m = models
    looked, found = np.zeros(len(cols), dtype=bool), np.zeros(len(cols), dtype=bool)
    order = np.lexsort((rows, cols))  # column by column, top to bottom
    o_col, o_foot = cols[order], foot[order]
    same_next = np.r_[o_col[1:] == o_col[:-1], False]
    # a run ends where the next return down the column is not the subject's
    ends = np.flatnonzero(o_foot & np.r_[~o_foot[1:], True] & same_next & low[order])
    # a walk stops before the subject, a return it may not cross, or the next column
    breaks = np.r_[np.flatnonzero(o_foot | ~walkable[order] | ~np.r_[True, same_next[:-1]]), len(order)]
    for e in ends:
        first = e
        while first > 0 and e - first < 2 and o_foot[first - 1] and o_col[first - 1] == o_col[e]:
            first -= 1
        foot_range_m = float(np.median(range_m[order[first:e + 1]]))
        walk = order[e + 1:int(breaks[np.searchsorted(breaks, e + 1)])]
        walk = walk[floor_range_m[walk] > foot_range_m - 3.0 * sigma_m[walk]]
        if len(walk) == 0:
            continue
        cap = (3.0 * sigma_m[walk]) ** 2
        foot_cost = np.minimum((range_m[walk] - foot_range_m) ** 2, cap)
        floor_cost = np.minimum((range_m[walk] - floor_range_m[walk]) ** 2, cap)
        # cost of the split after j returns: the first j are the foot's, the rest the floor's
        total = np.r_[0.0, np.cumsum(foot_cost)] + np.r_[np.cumsum(floor_cost[::-1])[::-1], 0.0]
        j = int(np.argmin(total))
        looked[walk] = True
        found[walk[:j]] = True
    return looked, found


def _beside_in_row(body: np.ndarray, pix: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """(k,) bool: returns with a ``body`` return (k,) bool next to them in their image row."""
    img = np.zeros(shape[0] * shape[1], dtype=bool)
    img[pix[body]] = True
    img = img.reshape(shape)
    near = np.zeros_like(img)
    near[:, 1:] |= img[:, :-1]
    near[:, :-1] |= img[:, 1:]
    return near.ravel()[pix]


def raised_pixels(mask: np.ndarray, pix: np.ndarray, points: np.ndarray, height_m: np.ndarray, free: np.ndarray,
                  fx: float) -> np.ndarray:
    """Floor-level returns near the subject whose neighbourhood, by its median height, stands clear of the floor.

    Toes and heels that point across the image in a side view lie a few centimetres over the floor, inside
    one return's noise. The median height of the floor-level free returns in a square window around a
    return (about :data:`RAISED_WINDOW_M` wide at the feet, 5 or 7 pixels) is far less noisy than the
    return; it stays on the floor beside a foot (the subject's own returns are left out of the window),
    and rises with a toe. A return is raised when that median exceeds the :data:`RAISED_QUANTILE` quantile
    of the same median on the floor more than :data:`RAISED_AWAY_M` from the subject (and at least
    :data:`RAISED_MIN_M`): that quantile measures the floor's correlated errors too, such as a stereo
    camera's disparity terraces, which no per-return noise model sees, and the feet of other people in
    that floor only raise it (fewer toes found, no floor taken). The floor near other objects stays in the
    reference: the floor's stray returns form small objects all over it, and without them the rest is
    cleaner than the floor at the feet (measured on the benchmark: D455 images meeting the segmentation
    target 0.93 with them, 0.49 without). With pixels
    coarser than a 5-pixel window (over about 13 mm at the feet, e.g. the phone LiDAR beyond 2.8 m), or
    under 200 bare-floor windows, nothing is raised.

    Parameters
    ----------
    mask : (h, w) bool
    pix : (k,) int
    points : (k, 3) float64
    height_m : (k,) float64
        Height of every return over the floor.
    free : (k,) bool
        Returns in no object (and not on or behind a wall).
    fx : float
        Focal length in pixels.

    Returns
    -------
    (k,) bool
    """
    from scipy import ndimage

    h, w = mask.shape
    out = np.zeros(len(pix), dtype=bool)
    low = free & (height_m < FEET_BAND_M)
    at_feet = mask.ravel()[pix] & (height_m < FEET_BAND_M)
    if not (at_feet.any() and low.any()):
        return out
    pitch_m = float(np.median(points[at_feet, 2])) / fx
    half_px = min(int(round(0.5 * RAISED_WINDOW_M / pitch_m)), 3)
    if half_px < 2:  # coarse pixels: a median of 9 is too noisy, and a toe is a pixel or two
        return out
    away_px = max(int(round(RAISED_AWAY_M / pitch_m)), 5)
    pad_px = away_px + 2 * half_px + 1
    rows, cols = np.divmod(pix, w)
    mr, mc = np.nonzero(mask)
    r0, r1 = max(int(mr.max()) - 4 * pad_px, 0), min(int(mr.max()) + pad_px, h)
    c0, c1 = max(int(mc.min()) - 2 * pad_px, 0), min(int(mc.max()) + 2 * pad_px, w)
    inside = (rows >= r0) & (rows < r1) & (cols >= c0) & (cols < c1)
    crop = np.full((r1 - r0, c1 - c0), np.nan)
    use = low & inside
    crop[rows[use] - r0, cols[use] - c0] = height_m[use]
    near_subject = ndimage.maximum_filter(mask[r0:r1, c0:c1], size=2 * away_px + 1)
    bare_r, bare_c = np.nonzero(np.isfinite(crop) & ~near_subject)
    floor_median = windowed_nanmedian(crop, half_px, bare_r, bare_c)
    floor_median = floor_median[np.isfinite(floor_median)]
    if len(floor_median) < 200:
        return out
    threshold_m = max(float(np.quantile(floor_median, RAISED_QUANTILE)), RAISED_MIN_M)
    cand = np.flatnonzero(use & (height_m > 0.0))
    out[cand] = windowed_nanmedian(crop, half_px, rows[cand] - r0, cols[cand] - c0) > threshold_m
    return out


def windowed_nanmedian(image: np.ndarray, half_px: int, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Median of the finite values of ``image`` in the (2 half + 1)² window around each pixel.

    Parameters
    ----------
    image : (h, w) float64
        NaN where there is no value.
    half_px : int
    rows, cols : (n,) int
        The window centres.

    Returns
    -------
    (n,) float64
        NaN where fewer than a third of the window holds values.
    """
    size = 2 * half_px + 1
    padded = np.pad(image, half_px, constant_values=np.nan)
    windows = np.lib.stride_tricks.sliding_window_view(padded, (size, size))
    out = np.full(len(rows), np.nan)
    for s in range(0, len(rows), _CHUNK):
        block = windows[rows[s:s + _CHUNK], cols[s:s + _CHUNK]].reshape(-1, size * size)
        enough = np.count_nonzero(np.isfinite(block), axis=1) >= size * size // 3
        if enough.any():
            out[s:s + _CHUNK][enough] = np.nanmedian(block[enough], axis=1)
    return out
