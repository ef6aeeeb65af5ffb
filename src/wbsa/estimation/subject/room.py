"""The room around the subject: its floor and walls among the largest planes of the image's cloud.

A room surface is a large plane (RANSAC, inliers within the depth noise along the normal) with (almost) nothing
behind it as seen from the camera that runs out of the image (reaches its frame's border,
:mod:`wbsa.estimation.subject.frame`); the floor is the one whose
normal is nearest the image's up (:func:`find_room`, used by :func:`wbsa.estimation.subject.segment.segment_subject`).
"""

from __future__ import annotations

import numpy as np

from wbsa.estimation.subject.cloud import Plane, ransac_plane
from wbsa.estimation.subject.frame import Frame
from wbsa.estimation.subject.settings import SegmentSettings
from wbsa.sensor.technology import SensorModel

#: The floor's normal lies within this angle of the image's up. A camera looking down by ε sees it ε away,
#: a wall behind the subject 90° + ε and a side wall 90° (plus the camera's roll); at 50° a camera 2 m up
#: and 1.5 m from a child lost the floor.
FLOOR_MAX_TILT_DEG = 75.0


def find_room(cloud: np.ndarray, settings: SegmentSettings, intrinsics, frame: Frame,
              sensor: SensorModel | None = None) -> tuple[Plane | None, list[Plane]]:
    """Floor and walls among the largest planes of a thinned (v, 3) cloud of an image with this frame (see the
    module doc).

    Parameters
    ----------
    cloud : (v, 3) float64
        The thinned cloud (camera frame, m).
    settings : SegmentSettings
    intrinsics : Intrinsics
    frame : Frame
        The image's frame (:func:`wbsa.estimation.subject.frame.image_frame`): its border moved in past bands
        without returns.
    sensor : SensorModel, optional
        The camera's depth-noise model (:func:`wbsa.sensor.technology.envelope_model`); None: that of a camera
        whose technology is unknown.

    Returns
    -------
    floor : Plane or None
    walls : list of Plane
    """
    rng = np.random.default_rng(settings.seed)
    free = np.ones(len(cloud), dtype=bool)
    surfaces: list[Plane] = []
    for _ in range(settings.max_planes):
        idx = np.flatnonzero(free)
        if len(idx) < max(50, settings.min_plane_fraction * len(cloud)):
            break
        found = ransac_plane(cloud[idx], rng, sensor=sensor)
        if found is None:
            break
        plane, inliers = found
        if inliers.sum() < settings.min_plane_fraction * len(cloud):
            break
        free[idx[inliers]] = False
        h = plane.height(cloud)
        behind = np.count_nonzero(h < -plane.tolerance(cloud) - 0.05)
        if behind <= settings.behind_fraction * len(cloud) and _meets_border(cloud[idx[inliers]], intrinsics, frame):
            surfaces.append(plane)
    up = np.array([0.0, -1.0, 0.0])
    floor = None
    cands = [p for p in surfaces if p.normal @ up > np.cos(np.radians(FLOOR_MAX_TILT_DEG))]
    if cands:
        floor = max(cands, key=lambda p: p.normal @ up)
    walls = [p for p in surfaces if p is not floor and (floor is None or abs(p.normal @ floor.normal) < 0.5)]
    return floor, walls


def _meets_border(points: np.ndarray, intrinsics, frame: Frame) -> bool:
    """Whether (k, 3) camera-frame points reach within :data:`~wbsa.estimation.subject.frame.BORDER_PX` pixels of the
    frame's border (:mod:`wbsa.estimation.subject.frame`)."""
    z = np.maximum(points[:, 2], 1e-9)
    u = float(intrinsics.fx) * points[:, 0] / z + float(intrinsics.cx)
    v = float(intrinsics.fy) * points[:, 1] / z + float(intrinsics.cy)
    return bool(np.any(frame.at_border(v, u)))
