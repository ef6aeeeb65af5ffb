"""Find the subject in a depth image of a room: floor, walls behind, 3-D clusters, the people, the one picked.

1. Returns within the depth range are back-projected and thinned to one point per voxel.
2. Room surfaces: the largest planes (RANSAC, inliers within the depth noise along the normal) that have
   (almost) nothing behind them as seen from the camera and run out of the image (reach its frame's border,
   :mod:`~wbsa.estimation.subject.frame`: the image less the bands without returns along its edges): a
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
4. The people (:mod:`~wbsa.estimation.subject.people`): person-sized objects (0.45–2.6 m tall, at most
   2.6 m wide and 0.9 m at the hips) with a head, their lower half seen, not flat, not cut by the frame's
   top, and not seen past a nearer, larger object (the wall between the legs); an object that is not one
   person is split into the people it holds, told apart by their heads. :func:`find_people` stops here.
5. ``pick`` chooses (``nearest``, ``largest``, ``center`` of the image, or an ``(x, y)`` pixel: the person
   under it or within 5 pixels, else a one-line refusal); without a pick several people are listed in a
   :class:`~wbsa.errors.WbsaError`. With none, people side by side and touching who cannot be told apart
   (up to 2.5 m at the hips) get an error that says so. The subject's feet are then taken down to the floor
   (:mod:`wbsa.estimation.subject.feet`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from wbsa.errors import WbsaError
from wbsa.estimation.subject.checks import millimetres_refusal
from wbsa.estimation.subject.cloud import Plane
from wbsa.estimation.subject.clusters import MAX_FOOTPRINT_M, attach_low, merge_occluding
from wbsa.estimation.subject.feet import grow_feet
from wbsa.estimation.subject.frame import Frame, image_frame
from wbsa.estimation.subject.people import Cluster, describe_clusters, seen_past, split_touching, why_not_a_person
from wbsa.estimation.subject.pick import choose
from wbsa.estimation.subject.room import find_room
from wbsa.estimation.subject.settings import SegmentSettings, is_pixel

#: Height over the floor below which returns are not used to link objects (only to extend them).
LOW_BAND_M = 0.10
#: People standing side by side and touching span at most this at the hips (m; one person at most
#: :data:`~wbsa.estimation.subject.clusters.MAX_FOOTPRINT_M`); a wall spans more.
TOUCHING_FOOTPRINT_M = 2.5


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
        The other people (when ``pick`` chose among several).
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


def segment_subject(depth_m: np.ndarray, intrinsics, settings: SegmentSettings = SegmentSettings(), *,
                    sensor=None) -> Segmentation:
    """Find the subject in a depth image (see the module doc): the people (:func:`find_people`), the one
    ``settings.pick`` chooses (:func:`~wbsa.estimation.subject.pick.choose`), its feet down to the floor.

    Parameters
    ----------
    depth_m : (h, w) float
        z-depth in metres, 0 = no return.
    intrinsics : wbsa.camera.Intrinsics
    settings : SegmentSettings
    sensor : SensorModel, optional
        The camera's depth-noise model (:func:`wbsa.sensor.technology.envelope_model`, as the estimate's request
        resolved it); None: that of a camera whose technology is unknown.

    Returns
    -------
    Segmentation

    Raises
    ------
    WbsaError
        No returns in the depth range, no person, several without a ``pick``, or a pick on no person.
    """
    scene = find_people(depth_m, intrinsics, settings, sensor=sensor)
    chosen = choose(scene.people, scene.clusters, settings.pick, scene.image_label, scene.limits)
    h, w = scene.image_label.shape
    mask = np.zeros(h * w, dtype=bool)
    mask[scene.pix[scene.pixel_label == chosen.label]] = True
    mask = grow_feet(mask.reshape(h, w), scene.pix, scene.points, scene.pixel_label, scene.floor, list(scene.walls),
                     float(intrinsics.fx))
    others = tuple(c for c in scene.people if c.label != chosen.label)
    return Segmentation(mask, scene.floor, scene.walls, chosen, others)


@dataclass(frozen=True)
class Scene:
    """The objects of a depth image and which of them are people (:func:`find_people`).

    Attributes
    ----------
    floor : Plane or None
    walls : tuple of Plane
    frame : Frame
        The image's frame (:mod:`wbsa.estimation.subject.frame`).
    clusters : tuple of Cluster
        Every object of at least 50 pixels.
    people : tuple of Cluster
        Those that are people (at least one).
    image_label : (h, w) int
        The object of every pixel (−1: none).
    pix : (k,) int
        Flat pixel index of every return in the depth range; ``points`` (k, 3) float64 its camera-frame point,
        ``pixel_label`` (k,) int its object.
    limits : (float, float, float)
        Least and greatest height and greatest width of a person (m).
    """

    floor: Plane | None
    walls: tuple[Plane, ...]
    frame: Frame
    clusters: tuple[Cluster, ...]
    people: tuple[Cluster, ...]
    image_label: np.ndarray = field(repr=False)
    pix: np.ndarray = field(repr=False)
    points: np.ndarray = field(repr=False)
    pixel_label: np.ndarray = field(repr=False)
    limits: tuple[float, float, float] = (0.45, 2.6, 2.6)


def find_people(depth_m: np.ndarray, intrinsics, settings: SegmentSettings = SegmentSettings(), *,
                sensor=None) -> Scene:
    """The room, the objects and the people of a depth image (steps 1–4 of the module doc).

    Parameters
    ----------
    depth_m : (h, w) float
        z-depth in metres, 0 = no return.
    intrinsics : wbsa.camera.Intrinsics
    settings : SegmentSettings
        Its ``pick`` is not used here.
    sensor : SensorModel, optional
        The camera's depth-noise model (:func:`wbsa.sensor.technology.envelope_model`, as the estimate's request
        resolved it); None: that of a camera whose technology is unknown.

    Returns
    -------
    Scene

    Raises
    ------
    WbsaError
        No returns in the depth range, or no person.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    from wbsa.core.backproject import backproject_depth

    depth = np.asarray(depth_m, dtype=np.float64)
    h, w = depth.shape
    ok = np.isfinite(depth) & (depth >= settings.min_depth_m) & (depth <= settings.max_depth_m)
    if np.count_nonzero(ok) < 100:
        said = (f"the depth image has {np.count_nonzero(ok)} returns between {settings.min_depth_m:g} and "
                f"{settings.max_depth_m:g} m")
        returns = depth[np.isfinite(depth) & (depth > 0)]
        if returns.size:
            median = float(np.median(returns))
            refusal = millimetres_refusal(f"{said}; its returns lie {median:.0f} m away (median)", median,
                                          (settings.min_depth_m, settings.max_depth_m))
            if refusal is not None:
                raise refusal
        raise WbsaError(f"{said}; check the depth scale (units per metre) and the depth range")
    pix = np.flatnonzero(ok.ravel())
    points = backproject_depth(np.where(ok, depth, 0.0), intrinsics).reshape(-1, 3)[pix].astype(np.float64)
    cloud, voxel_of = _voxelise(points, settings.voxel_m)
    frame = image_frame(ok)
    floor, walls = find_room(cloud, settings, intrinsics, frame, sensor)
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
    clusters = describe_clusters(pixel_label, pix, points, (h, w), floor, frame)
    limits = (settings.min_person_height_m, settings.max_person_height_m, settings.max_person_width_m)
    if floor is not None:
        pixel_label, clusters = split_touching(clusters, pixel_label, pix, points, (h, w), floor, frame, limits)
    behind = seen_past(clusters)
    people = [c for c in clusters if c.label not in behind and why_not_a_person(c, *limits) is None]
    if not people:
        front = [c for c in clusters if c.label not in behind]
        touching = [c for c in front if settings.min_person_height_m <= c.height_m <= settings.max_person_height_m
                    and MAX_FOOTPRINT_M < c.footprint_m <= TOUCHING_FOOTPRINT_M]
        if touching:
            big = max(touching, key=lambda c: c.n_pixels)
            raise WbsaError(f"an object, {big.describe()}, is {big.footprint_m:.1f} m wide at the hips: "
                            "people touching each other? capture the subject standing apart")
        big = max(front, key=lambda c: c.n_pixels) if front else None
        what = (f"the largest object, {big.describe()}, is not one: {why_not_a_person(big, *limits)}" if big
                else "no object is left after the floor and walls")
        raise WbsaError(f"no person in the depth image ({settings.min_person_height_m:g}–"
                        f"{settings.max_person_height_m:g} m tall); {what}: check the depth scale (units per metre), "
                        "the camera, and that the whole person is in the frame")
    image_label = np.full(h * w, -1)
    image_label[pix] = pixel_label
    return Scene(floor, tuple(walls), frame, tuple(clusters), tuple(people), image_label.reshape(h, w), pix, points,
                 pixel_label, limits)
