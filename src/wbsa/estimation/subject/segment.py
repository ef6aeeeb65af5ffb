"""Find the subject in a depth image of a room: floor, walls behind, 3-D clusters, the person-sized one.

1. Returns within the depth range are back-projected and thinned to one point per voxel.
2. Room surfaces: the largest planes (RANSAC, inliers within the depth noise along the normal) that have
   (almost) nothing behind them as seen from the camera and run out of the image (reach its border): a
   floor or a wall does both; a body's chest has its sides behind it, and a body alone in the image (no
   room), which a plane fits loosely, is inside the frame.
   The floor is the room surface whose normal is closest to the image's up (within 75°); the others are
   walls. Returns on or below the floor (within its noise) and on or behind a wall are background.
3. What is left is clustered in 3-D: voxels closer than ``cluster_gap_m`` (or three pixel pitches at that
   depth) are one object. Voxels in a band over the floor (10 cm, or twice the floor's noise) only join the
   object they touch, so stray floor returns cannot chain objects together. Objects that touch in the image
   (or lie one pixel apart with no return between) with less than 0.8 m between them in depth (a body's
   near and far sides, an arm in front of the waist), or a far arm up to 1.2 m behind, are one object if
   together they are still person-sized (:func:`~wbsa.estimation.subject.clusters.merge_occluding`).
   The subject's feet are then taken down to the floor (:mod:`wbsa.estimation.subject.feet`).
4. A cluster is person-sized if it is 0.45–2.6 m tall (along the floor normal, or its long axis), at
   most 2.6 m wide and 0.9 m at the hips, and not seen past a nearer, larger object (inside its bounding box
   in the image and 0.4 m or more behind it: the wall between the legs; :func:`seen_past`); with several,
   ``pick`` chooses (``nearest``, ``largest``, ``center`` of the image, or an ``(x, y)`` pixel: the object
   under that pixel, else the one whose middle pixel is nearest to it), else a
   :class:`~wbsa.errors.WbsaError` lists them. With none, people side by side and touching (up to 2.5 m
   at the hips) get an error that says so.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from wbsa.errors import WbsaError
from wbsa.estimation.subject.cloud import Plane
from wbsa.estimation.subject.clusters import MAX_FOOTPRINT_M, attach_low, footprint_m, merge_occluding
from wbsa.estimation.subject.feet import grow_feet
from wbsa.estimation.subject.room import find_room
from wbsa.estimation.subject.settings import SegmentSettings, is_pixel

#: Height over the floor below which returns are not used to link objects (only to extend them).
LOW_BAND_M = 0.10
#: An object inside a nearer one's bounding box in the image and this much farther (m) is seen past it.
#: The wall stands 0.5 m or more behind a subject's back; a body's own parts join it within 0.8 m of depth
#: when they touch in the image (:func:`~wbsa.estimation.subject.clusters.merge_occluding`) and are larger.
SEEN_PAST_M = 0.4
#: People standing side by side and touching span at most this at the hips (m; one person at most
#: :data:`~wbsa.estimation.subject.clusters.MAX_FOOTPRINT_M`); a wall spans more.
TOUCHING_FOOTPRINT_M = 2.5


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
    """

    label: int
    n_pixels: int
    pixel_xy: tuple[int, int]
    distance_m: float
    height_m: float
    width_m: float
    footprint_m: float
    bbox_px: tuple[int, int, int, int]

    def describe(self) -> str:
        """``1.72 m tall at pixel (312, 240), 2.9 m away`` for messages."""
        return (f"{self.height_m:.2f} m tall at pixel ({self.pixel_xy[0]}, {self.pixel_xy[1]}), "
                f"{self.distance_m:.1f} m away")


@dataclass(frozen=True)
class Segmentation:
    """The subject's pixels and what was learned about the room.

    Attributes
    ----------
    mask : (h, w) bool
        The subject's pixels (returns on the floor excluded).
    floor : Plane or None
        The floor (camera frame), if one was seen.
    walls : tuple of Plane
    subject : Cluster
    others : tuple of Cluster
        Other person-sized objects (when ``pick`` chose among several).
    """

    mask: np.ndarray
    floor: Plane | None
    walls: tuple[Plane, ...]
    subject: Cluster
    others: tuple[Cluster, ...] = field(default_factory=tuple)


def _voxelise(points: np.ndarray, voxel_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Voxel centroids (v, 3) of (k, 3) points and the voxel of each point (k,)."""
    keys = np.floor(points / voxel_m).astype(np.int64)
    keys -= keys.min(axis=0)
    size = keys.max(axis=0) + 1
    flat = (keys[:, 0] * size[1] + keys[:, 1]) * size[2] + keys[:, 2]  # lexicographic order kept: same voxels
    _, inverse, counts = np.unique(flat, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    sums = np.zeros((len(counts), 3))
    np.add.at(sums, inverse, points)
    return sums / counts[:, None], inverse


def segment_subject(depth_m: np.ndarray, intrinsics, settings: SegmentSettings = SegmentSettings()) -> Segmentation:
    """Find the subject in a depth image (see the module doc).

    Parameters
    ----------
    depth_m : (h, w) float
        z-depth in metres, 0 = no return.
    intrinsics : wbsa.camera.Intrinsics
    settings : SegmentSettings

    Returns
    -------
    Segmentation

    Raises
    ------
    WbsaError
        No returns in the depth range, no person-sized object, or several without a ``pick``.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    from wbsa.core.backproject import backproject_depth

    depth = np.asarray(depth_m, dtype=np.float64)
    h, w = depth.shape
    ok = np.isfinite(depth) & (depth >= settings.min_depth_m) & (depth <= settings.max_depth_m)
    if np.count_nonzero(ok) < 100:
        raise WbsaError(f"the depth image has {np.count_nonzero(ok)} returns between {settings.min_depth_m:g} and "
                        f"{settings.max_depth_m:g} m; check the depth scale (units per metre) and the depth range")
    pix = np.flatnonzero(ok.ravel())
    points = backproject_depth(np.where(ok, depth, 0.0), intrinsics).reshape(-1, 3)[pix].astype(np.float64)
    cloud, voxel_of = _voxelise(points, settings.voxel_m)
    floor, walls = find_room(cloud, settings, intrinsics, (h, w))
    keep = np.ones(len(cloud), dtype=bool) if floor is None else floor.height(cloud) > floor.tolerance(cloud)
    for wall in walls:
        keep &= wall.height(cloud) > wall.tolerance(cloud)
    # objects are clustered above a band over the floor, where the floor's noisy returns cannot link them;
    # returns in the band join the object they touch (feet), or nothing (stray floor returns)
    core = keep.copy()
    if floor is not None:
        core &= floor.height(cloud) > np.maximum(LOW_BAND_M, 2.0 * floor.tolerance(cloud))
    idx = np.flatnonzero(core)
    if len(idx) == 0:
        raise WbsaError("the depth image holds only floor and walls; no subject found")
    pts = cloud[idx]
    pitch = float(np.max(pts[:, 2])) / min(float(intrinsics.fx), float(intrinsics.fy))
    gap = max(settings.cluster_gap_m, 3.0 * pitch)
    tree = cKDTree(pts)
    pairs = tree.query_pairs(gap, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(pts), len(pts)))
    _, labels = connected_components(graph, directed=False)
    voxel_label = np.full(len(cloud), -1)
    voxel_label[idx] = labels
    low = np.flatnonzero(keep & ~core)
    if len(low):
        voxel_label[low] = attach_low(cloud[low], tree, labels, gap)
    pixel_label = voxel_label[voxel_of]
    pixel_label[~keep[voxel_of]] = -1
    pixel_label = merge_occluding(pixel_label, pix, points, (h, w), floor, settings.max_person_height_m,
                                  settings.max_person_width_m)
    clusters = _describe(pixel_label, pix, points, w, floor)
    behind = seen_past(clusters)
    clusters = [c for c in clusters if c.label not in behind]
    people = [c for c in clusters if _person_sized(c, settings)]
    if not people:
        touching = [c for c in clusters if settings.min_person_height_m <= c.height_m <= settings.max_person_height_m
                    and MAX_FOOTPRINT_M < c.footprint_m <= TOUCHING_FOOTPRINT_M]
        if touching:
            big = max(touching, key=lambda c: c.n_pixels)
            raise WbsaError(f"an object, {big.describe()}, is {big.footprint_m:.1f} m wide at the hips: "
                            "people touching each other? capture the subject standing apart")
        big = max(clusters, key=lambda c: c.n_pixels) if clusters else None
        what = f"the largest object is {big.describe()}" if big else "no object is left after the floor and walls"
        raise WbsaError(f"no person-sized object ({settings.min_person_height_m:g}–{settings.max_person_height_m:g} m "
                        f"tall) in the depth image; {what}: check the depth scale (units per metre) and the camera")
    chosen = _choose(people, settings.pick, (w, h), pixel_label, pix)
    mask = np.zeros(h * w, dtype=bool)
    mask[pix[pixel_label == chosen.label]] = True
    mask = grow_feet(mask.reshape(h, w), pix, points, pixel_label, floor, walls, float(intrinsics.fx))
    others = tuple(c for c in people if c.label != chosen.label)
    return Segmentation(mask, floor, tuple(walls), chosen, others)


def _describe(pixel_label: np.ndarray, pix: np.ndarray, points: np.ndarray, width: int,
              floor: Plane | None) -> list[Cluster]:
    """Size, place and distance of every cluster with at least 50 pixels."""
    labels, counts = np.unique(pixel_label[pixel_label >= 0], return_counts=True)
    out = []
    for lab, n in zip(labels, counts):
        if n < 50:
            continue
        sel = pixel_label == lab
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
        rows, cols = np.divmod(pix[sel], width)
        out.append(Cluster(int(lab), int(n), (int(np.median(cols)), int(np.median(rows))),
                           float(np.median(np.linalg.norm(p, axis=1))), height, width_m,
                           footprint_m(p, up if up @ np.array([0.0, -1.0, 0.0]) >= 0 else -up),
                           (int(cols.min()), int(rows.min()), int(cols.max()), int(rows.max()))))
    return out


def _person_sized(c: Cluster, settings: SegmentSettings) -> bool:
    """Whether a cluster is person-sized: tall, wide and wide at the hips within the settings' bounds."""
    return (settings.min_person_height_m <= c.height_m <= settings.max_person_height_m
            and c.width_m <= settings.max_person_width_m and c.footprint_m <= MAX_FOOTPRINT_M)


def seen_past(clusters: list[Cluster]) -> set[int]:
    """Labels of the clusters seen past a nearer, larger object: inside its bounding box in the image and at
    least :data:`SEEN_PAST_M` farther away (the wall between a subject's legs or inside a bent arm).

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
    out = set()
    for c in clusters:
        x0, y0, x1, y1 = c.bbox_px
        for o in clusters:
            ox0, oy0, ox1, oy1 = o.bbox_px
            if (o.n_pixels > c.n_pixels and c.distance_m > o.distance_m + SEEN_PAST_M
                    and ox0 <= x0 and x1 <= ox1 and oy0 <= y0 and y1 <= oy1):
                out.add(c.label)
                break
    return out


def _choose(people: list[Cluster], pick, size: tuple[int, int], pixel_label: np.ndarray, pix: np.ndarray) -> Cluster:
    w, h = size
    if is_pixel(pick) and not (0 <= pick[0] < w and 0 <= pick[1] < h):  # refused with one person in view too
        raise WbsaError(f"pick pixel ({pick[0]}, {pick[1]}) lies outside the {w} x {h} depth image; "
                        "give x,y of a pixel on the subject")
    if len(people) == 1:
        return people[0]
    if pick is None:
        listing = "; ".join(f"{i + 1}: {c.describe()}" for i, c in enumerate(sorted(people, key=lambda c: c.pixel_xy)))
        raise WbsaError(f"{len(people)} person-sized objects in the depth image ({listing}); "
                        "choose one with pick nearest, largest, center or x,y")
    if pick == "nearest":
        return min(people, key=lambda c: c.distance_m)
    if pick == "largest":
        return max(people, key=lambda c: c.n_pixels)
    x, y = ((w - 1) / 2, (h - 1) / 2) if pick == "center" else pick
    # the object under the pixel (the operator aims at the subject), else the one whose middle is nearest
    hit = pixel_label[pix == int(round(y)) * w + int(round(x))]
    for c in people:
        if hit.size and c.label == hit[0]:
            return c
    return min(people, key=lambda c: (c.pixel_xy[0] - x) ** 2 + (c.pixel_xy[1] - y) ** 2)
