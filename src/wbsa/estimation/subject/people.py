"""Which objects of a depth image are people, and which person a pick chooses.

An object (a 3-D cluster, :mod:`wbsa.estimation.subject.segment`) is a person when it is person-sized (0.45–2.6 m
tall, at most 2.6 m wide and 0.9 m at the hips) and, with a floor seen:

* its top stands at most 2.6 m over the floor, and the frame's top does not cut it (a head is seen);
* its lower half is seen: its lowest return is at most half its top's height over the floor (a head or a
  lamp seen over other people is not a person to measure);
* it has a head: its top :data:`HEAD_BAND_M` spans at most :data:`HEAD_MAX_WIDTH_M` across the floor;
* it is not flat: its returns lie off their best plane by at least :data:`FLAT_MIN_M` (:func:`relief_m`: RMS
  over windows of pixels, its depth noise taken out in quadrature: the noise measured on it,
  :func:`~wbsa.estimation.subject.measure.measured_depth_noise`, or where quantised depth reads none, the
  noise envelope at its distance, :func:`~wbsa.estimation.subject.cloud.depth_noise_m`): a board, a door or a
  piece of wall is flat.

Measured on PCL's ``five_people.pcd`` (tests/fixtures): the five people are 2.0–2.8 m away, heads 0.21–0.32 m
wide, 4.5–9.3 cm off their plane beyond the noise; the room's pieces that passed the size test stand 2.6–3.8 m
tall over the floor, or show only their top, or span 0.4–1.6 m at the top, or lie 0.7 cm off a plane, or are
seen between two nearer people (:func:`seen_past`).

People standing side by side who touch form one object; :func:`split_touching` splits it at the valleys
between their heads (:func:`~wbsa.estimation.subject.clusters.split_people`) when every part is a person.
Which person a pick chooses is :mod:`~wbsa.estimation.subject.pick`.

"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wbsa.estimation.subject.cloud import Plane, depth_noise_m
from wbsa.estimation.subject.clusters import MAX_FOOTPRINT_M, footprint_m, split_people
from wbsa.estimation.subject.frame import Frame, image_frame
from wbsa.estimation.subject.measure import measured_depth_noise

#: Top of an object (m, along the floor's normal; at most this share of its height) where its head is ...
HEAD_BAND_M = 0.2
HEAD_BAND_SHARE = 0.12
#: ... which spans at most this across the floor (m): a head 0.16 m wide, with hair and mixed returns.
HEAD_MAX_WIDTH_M = 0.5
#: A person's returns lie off their best plane (:func:`relief_m`, less its depth noise) by at least this (m):
#: rendered people 2.2–6.7 cm (three adults and a child of 0.82 m in a room, 0°, 90° and 135°, Kinect v2; the
#: child 2.2 cm from the front), people at 3× the noise models' σ 2.2–5.0 cm (seed 2000's renders, Kinect v2
#: and phone LiDAR at 3.5–4.2 m), PCL's five people 4.5–9.3 cm; a board and a wall piece 0 cm, a post
#: 0.9 cm, the cabinet of five_people 0.7 cm.
FLAT_MIN_M = 0.018
#: Side of the window of pixels over which :func:`relief_m` averages an object's distance from its plane.
RELIEF_WINDOW_PX = 3
#: The lowest return of a person is at most this share of its top's height over the floor.
LOWER_HALF = 0.5
#: A person standing on a seen floor has returns this close to it (m): the feet.
FLOOR_CONTACT_M = 0.15
#: An object inside a nearer one's bounding box in the image (or boxes side by side) and this much farther (m)
#: is seen past it.
#: The wall stands 0.5 m or more behind a subject's back; a body's own parts join it within 0.8 m of depth
#: when they touch in the image (:func:`~wbsa.estimation.subject.clusters.merge_occluding`) and are larger.
SEEN_PAST_M = 0.4


@dataclass(frozen=True)
class Cluster:
    """One object found in the image (a candidate subject).

    Attributes
    ----------
    label : int
        The object's label among the image's returns.
    n_pixels : int
    pixel_xy : (int, int)
        Its middle pixel (median column and row).
    distance_m : float
        Median range of its returns.
    height_m, width_m : float
        Extent along the floor's normal (or its long axis) and across it.
    footprint_m : float
        Width at the hips (:func:`~wbsa.estimation.subject.clusters.footprint_m`).
    bbox_px : (int, int, int, int)
        Bounding box in the image, ``(x0, y0, x1, y1)``, inclusive.
    top_m, bottom_m : float
        Its highest and lowest returns over the floor (NaN without a floor).
    head_width_m : float
        Width of its top :data:`HEAD_BAND_M` across the floor (NaN without a floor).
    off_plane_m, noise_m : float
        RMS distance of its returns from their best plane averaged over windows of pixels, and the depth noise
        left in that average (its noise measured on it, or the envelope at its distance where quantised depth
        reads none) (m; :func:`relief_m`).
    top_cut, bottom_cut : bool
        Its top reaches the frame's top border; its lowest returns reach the frame's bottom border (the
        image's, or a band without returns along it: :mod:`~wbsa.estimation.subject.frame`).
    """

    label: int
    n_pixels: int
    pixel_xy: tuple[int, int]
    distance_m: float
    height_m: float
    width_m: float
    footprint_m: float
    bbox_px: tuple[int, int, int, int]
    top_m: float = math.nan
    bottom_m: float = math.nan
    head_width_m: float = math.nan
    off_plane_m: float = math.nan
    noise_m: float = math.nan
    top_cut: bool = False
    bottom_cut: bool = False

    def describe(self, page: bool = False) -> str:
        """``1.72 m tall at pixel (312, 240), 2.9 m away`` for messages.

        Parameters
        ----------
        page : bool
            In the page's words: ``at (312, 240) in the picture``.
        """
        x, y = self.pixel_xy
        where = f"at ({x}, {y}) in the picture" if page else f"at pixel ({x}, {y})"
        return f"{self.height_m:.2f} m tall {where}, {self.distance_m:.1f} m away"


def describe_clusters(pixel_label: np.ndarray, pix: np.ndarray, points: np.ndarray, shape: tuple[int, int],
                      floor: Plane | None, frame: Frame, labels: np.ndarray | None = None) -> list[Cluster]:
    """Size, place, distance and person cues of every cluster (of those ``labels``) with at least 50 pixels.

    Parameters
    ----------
    pixel_label : (k,) int
        Cluster of every return (−1: none); ``pix`` (k,) int its flat pixel index in an image of ``shape``
        (h, w), ``points`` (k, 3) float64 its camera-frame point.
    floor : Plane or None
    frame : Frame
        The image's frame (:func:`~wbsa.estimation.subject.frame.image_frame`).
    labels : (n,) int, optional
        The clusters to describe (default: all).

    Returns
    -------
    list of Cluster
    """
    h, w = shape
    if labels is None:
        labels = np.unique(pixel_label[pixel_label >= 0])
    out = []
    for lab in labels:
        sel = pixel_label == lab
        n = int(np.count_nonzero(sel))
        if n < 50:
            continue
        p = points[sel]
        if floor is not None:
            up = floor.normal
        else:
            q = p[:: max(1, len(p) // 2000)] - p.mean(axis=0)
            up = np.linalg.svd(q, full_matrices=False)[2][0]
        along = p @ up
        height = float(np.quantile(along, 0.999) - np.quantile(along, 0.001))
        flat = p - np.outer(along, up)
        centre = np.median(flat, axis=0)
        width_m = 2.0 * float(np.quantile(np.linalg.norm(flat - centre, axis=1), 0.995))
        rows, cols = np.divmod(pix[sel], w)
        distance = float(np.median(np.linalg.norm(p, axis=1)))
        cues = {}
        if floor is not None:
            over = floor.height(p)
            top, bottom = float(np.quantile(over, 0.998)), float(np.quantile(over, 0.002))
            cues = dict(top_m=top, bottom_m=bottom,
                        head_width_m=_across(p[over > top - min(HEAD_BAND_M, HEAD_BAND_SHARE * (top - bottom))], up))
        noise_m = _own_noise_m(rows, cols, p[:, 2]) or float(depth_noise_m(np.median(p[:, 2])))
        cues["off_plane_m"], cues["noise_m"] = relief_m(rows, cols, p, noise_m)
        out.append(Cluster(int(lab), n, (int(np.median(cols)), int(np.median(rows))), distance, height, width_m,
                           footprint_m(p, up if up @ np.array([0.0, -1.0, 0.0]) >= 0 else -up,
                                       None if floor is None else floor.height(p)),
                           (int(cols.min()), int(rows.min()), int(cols.max()), int(rows.max())),
                           top_cut=bool(frame.at_top(rows.min())),
                           bottom_cut=bool(frame.at_bottom(rows.max())), **cues))
    return out


def _own_noise_m(rows: np.ndarray, cols: np.ndarray, z: np.ndarray) -> float:
    """Depth noise (m) measured on an object's pixels (rows, cols: (n,) int; z: (n,) float64 their depth)."""
    r0, c0 = rows.min(), cols.min()
    depth = np.zeros((rows.max() - r0 + 1, cols.max() - c0 + 1))
    depth[rows - r0, cols - c0] = z
    return measured_depth_noise(depth, depth > 0)


def relief_m(rows: np.ndarray, cols: np.ndarray, points: np.ndarray, noise_m: float) -> tuple[float, float]:
    """How far an object's surface lies off its best plane, averaged over windows of pixels, and the depth
    noise left in that average.

    Each return's distance from the best plane of the returns is averaged over the
    :data:`RELIEF_WINDOW_PX` × :data:`RELIEF_WINDOW_PX` window around it (windows at least half covered by the
    object): a body's relief spans many pixels and survives the average, independent depth noise of σ falls to
    σ / √k over k returns. So a person stays a person under a noise as large as its relief (Kinect v2's noise
    model at 3× its σ reads 6.6 cm at 3.5 m, where a body lies 4–6 cm off its plane), and a board stays flat.

    Parameters
    ----------
    rows, cols : (n,) int
        The object's pixels.
    points : (n, 3) float64
        Their returns in the camera frame (m).
    noise_m : float
        The depth noise of one return (m).

    Returns
    -------
    off_plane_m : float
        RMS of the window averages of the distances from the plane (m).
    noise_m : float
        The noise left in it, σ · √(mean of 1 / k) (m).
    """
    from scipy import ndimage

    sub = points[:: max(1, len(points) // 3000)]
    centre = sub.mean(axis=0)
    normal = np.linalg.svd(sub - centre, full_matrices=False)[2][2]
    r0, c0 = rows.min(), cols.min()
    grid = (rows.max() - r0 + 1, cols.max() - c0 + 1)
    distance = (points - centre) @ normal
    off = np.zeros(grid)
    seen = np.zeros(grid)
    off[rows - r0, cols - c0] = distance
    seen[rows - r0, cols - c0] = 1.0
    k = RELIEF_WINDOW_PX
    total = ndimage.uniform_filter(off, k, mode="constant") * k * k
    count = np.rint(ndimage.uniform_filter(seen, k, mode="constant") * k * k)
    ok = (seen > 0) & (count >= k * k / 2)
    if not ok.any():
        return float(np.sqrt(np.mean(distance ** 2))), float(noise_m)
    mean = total[ok] / count[ok]
    return float(np.sqrt(np.mean(mean ** 2))), float(noise_m * np.sqrt(np.mean(1.0 / count[ok])))


def _across(points: np.ndarray, up: np.ndarray) -> float:
    """Horizontal extent (m, bounding-box diagonal of the 2–98 % quantiles) of (k, 3) points across ``up``."""
    if len(points) < 3:
        return 0.0
    e1 = np.array([1.0, 0.0, 0.0]) - up[0] * up
    e1 /= np.linalg.norm(e1)
    q = np.stack([points @ e1, points @ np.cross(up, e1)], axis=1)
    return float(np.hypot(*(np.quantile(q, 0.98, axis=0) - np.quantile(q, 0.02, axis=0))))


def why_not_a_person(c: Cluster, min_height_m: float, max_height_m: float, max_width_m: float) -> str | None:
    """Why an object is not a person (a clause for messages), or None when it is one (see the module doc).

    Parameters
    ----------
    c : Cluster
    min_height_m, max_height_m, max_width_m : float
        Least and greatest height and greatest width of a person (m).

    Returns
    -------
    str or None
    """
    if not min_height_m <= c.height_m <= max_height_m:
        return f"it is {c.height_m:.2f} m tall, a person {min_height_m:g}–{max_height_m:g} m"
    if c.width_m > max_width_m:
        return f"it is {c.width_m:.1f} m wide, a person at most {max_width_m:g} m"
    if c.footprint_m > MAX_FOOTPRINT_M:
        return f"it is {c.footprint_m:.1f} m wide at the hips, a person at most {MAX_FOOTPRINT_M:g} m"
    if c.top_cut:
        return "the top of the frame cuts it off (no head seen)"
    if math.isnan(c.top_m):
        return None
    if c.top_m > max_height_m:
        return f"its top is {c.top_m:.1f} m over the floor"
    if c.bottom_m > LOWER_HALF * c.top_m:
        return f"only its top is seen ({c.bottom_m:.1f}–{c.top_m:.1f} m over the floor)"
    if c.head_width_m > HEAD_MAX_WIDTH_M:
        return f"it has no head: its top is {c.head_width_m:.1f} m wide"
    shape_m = math.sqrt(max(c.off_plane_m ** 2 - c.noise_m ** 2, 0.0))
    if shape_m < FLAT_MIN_M:
        return (f"it is flat ({100 * shape_m:.1f} cm off a plane beyond its depth noise, a person at least "
                f"{100 * FLAT_MIN_M:g} cm): a board, a door or a wall")
    return None


#: What is found when a subject's lowest returns touch the bottom edge of the frame.
FEET_AT_EDGE = "the feet touch the bottom edge of the picture: they may be cut off"


def feet_unseen(c: Cluster, floor: Plane | None) -> str | None:
    """Why a person's feet are not seen (a clause), or None when they stand on the seen floor.

    The feet are not seen when the lowest returns touch the frame's bottom edge (the image's, or a band
    without returns along it: ``bottom_cut``), even on a seen floor (one rule for every frame: they may be cut
    off), or stand more than :data:`FLOOR_CONTACT_M` over a seen floor (hidden). Without a floor and with the
    feet inside the frame the returns say nothing (:func:`feet_shape_unseen` looks at the shape).

    Parameters
    ----------
    c : Cluster
        The subject.
    floor : Plane or None

    Returns
    -------
    str or None
    """
    if c.bottom_cut:
        return FEET_AT_EDGE + (f" ({c.bottom_m:.2f} m over the floor)" if floor is not None else " (no floor seen)")
    if floor is not None and c.bottom_m <= FLOOR_CONTACT_M:
        return None
    if floor is not None:
        return f"its lowest returns are {c.bottom_m:.2f} m over the floor (the feet are hidden)"
    return None


#: The lowest band of a standing body (0–5 % of its height) reaches wider or deeper than the band two above it
#: (10–15 %) by at least this factor where it ends in feet: toes point forward and feet are longer than shins
#: are thick. Measured on seed 2000's bodies alone (no floor), 30 whole and 29 cut from 12 to 42 % of their
#: height: every whole body 1.24 or more (median 1.5), 27 of the cut 1.2 or less (median 0.45).
FEET_SPREAD = 1.2


def feet_shape_unseen(shape: np.ndarray) -> str | None:
    """Why a body seen with no floor does not end in feet (a clause), or None when it does.

    Without a floor nothing says where the feet are, and a frame cut above the floor (the legs end over
    nothing) reads as a shorter person. Feet are told by their shape: the lowest band of the body is wider
    or deeper than the legs above it by :data:`FEET_SPREAD`.

    Parameters
    ----------
    shape : (40,) float
        The body's shape bands (:func:`wbsa.estimation.subject.measure.shape_bands`): 20 widths then 20
        thicknesses, from the lowest up.

    Returns
    -------
    str or None
    """
    n = len(shape) // 2
    width, thickness = np.asarray(shape[:n], dtype=np.float64), np.asarray(shape[n:], dtype=np.float64)
    if width[2] <= 0 or thickness[2] <= 0:
        return None
    spread = max(width[0] / width[2], thickness[0] / thickness[2])
    if spread >= FEET_SPREAD:
        return None
    return ("its lowest part is no wider or deeper than the legs above it (no feet), with no floor seen: the legs "
            "may end over nothing, cut off by the picture")


def open_feet(mask: np.ndarray) -> str | None:
    """:func:`feet_unseen` of a subject that is every return of the image (no segmentation, no floor): its
    lowest returns reach the image's bottom border (a clause), or None.

    Parameters
    ----------
    mask : (h, w) bool
        The subject's pixels.

    Returns
    -------
    str or None
    """
    rows = np.flatnonzero(mask.any(axis=1))
    if len(rows) and image_frame(mask).at_bottom(rows[-1]):
        return FEET_AT_EDGE + " (no floor seen)"
    return None


def seen_past(clusters: list[Cluster]) -> set[int]:
    """Labels of the clusters seen past nearer, larger objects: inside their bounding boxes in the image (one
    box, or boxes side by side that each span its rows) and at least :data:`SEEN_PAST_M` farther away (the wall
    between a subject's legs or inside a bent arm, the room between two people).

    Such a piece can be person-sized, and lie under the image's centre, where the operator aimed at the
    subject; it is never the subject. Any larger object may hide one, person-sized or not: two people
    touching form one object too wide at the hips, and the wall between their legs must not then be
    taken for a person.

    Parameters
    ----------
    clusters : list of Cluster
        Every object in the image.

    Returns
    -------
    set of int
        The labels of the clusters seen past another.
    """
    return {c.label for c in clusters if seen_past_object(c, clusters) is not None}


def seen_past_object(c: Cluster, clusters: list[Cluster]) -> Cluster | None:
    """The nearer, larger object ``c`` is seen past (see :func:`seen_past`), or None: of several side by side,
    the nearest whose box spans ``c``'s middle column.

    Parameters
    ----------
    c : Cluster
    clusters : list of Cluster
        Every object in the image.

    Returns
    -------
    Cluster or None
    """
    x0, y0, x1, y1 = c.bbox_px
    nearer = sorted((o for o in clusters
                     if o.n_pixels > c.n_pixels and c.distance_m > o.distance_m + SEEN_PAST_M
                     and o.bbox_px[1] <= y0 and y1 <= o.bbox_px[3] and o.bbox_px[0] <= x1 and o.bbox_px[2] >= x0),
                    key=lambda o: o.bbox_px[0])
    reach = x0 - 1
    for o in nearer:
        if o.bbox_px[0] > reach + 1:
            break
        reach = max(reach, o.bbox_px[2])
    if not nearer or reach < x1:
        return None
    middle = c.pixel_xy[0]
    return min(nearer, key=lambda o: (not o.bbox_px[0] <= middle <= o.bbox_px[2], o.distance_m))


def split_touching(clusters: list[Cluster], pixel_label: np.ndarray, pix: np.ndarray, points: np.ndarray,
                   shape: tuple[int, int], floor: Plane, frame: Frame,
                   limits: tuple[float, float, float]) -> tuple[np.ndarray, list[Cluster]]:
    """Objects that are not one person, split into the people they hold
    (:func:`~wbsa.estimation.subject.clusters.split_people`) when every part is a person
    (:func:`why_not_a_person` with ``limits``: least and greatest height, greatest width, m).

    Parameters
    ----------
    clusters : list of Cluster
        Every object described (:func:`describe_clusters`).
    pixel_label : (k,) int
        The object of every return; ``pix`` (k,) int its flat pixel index in an image of ``shape`` (h, w),
        ``points`` (k, 3) float64 its camera-frame point.
    floor : Plane
    frame : Frame
    limits : (float, float, float)

    Returns
    -------
    (k,) int, list of Cluster
        The labels of every return and the clusters, the parts under new labels.
    """
    out, kept = pixel_label, []
    for c in clusters:
        if c.height_m < limits[0] or why_not_a_person(c, *limits) is None:
            kept.append(c)
            continue
        sel = np.flatnonzero(out == c.label)
        person = split_people(points[sel], floor, limits[0])
        if person.max() == 0:
            kept.append(c)
            continue
        trial = out.copy()
        trial[sel] = out.max() + 1 + person
        parts = describe_clusters(trial, pix, points, shape, floor, frame, labels=np.unique(trial[sel]))
        if len(parts) > 1 and all(why_not_a_person(p, *limits) is None for p in parts):
            out = trial
            kept.extend(parts)
        else:
            kept.append(c)
    return out, kept
