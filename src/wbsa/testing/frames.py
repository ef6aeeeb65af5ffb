"""Frames of the real-frame cases (docs/estimate.md, "Real frames"): a render of two people side by side
in a room, and a real organised point cloud (PCD) read into a depth image.

Used by ``benchmarks/bench_real_frames.py`` and the tests.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def posed_skin(body_model, rest, name: str, scale: float = 1.0):
    """The skin mesh of ``rest`` (``BodyModel.rest_bodies``, scaled) in posture ``name`` at its nominal angles,
    standing on z = 0 as populations are."""
    from wbsa.bodies.posing import JOINT_MOTIONS, SIDES, Rig
    from wbsa.bodies.posture import POSTURES, settle_posture

    angles = np.array([POSTURES[name].nominal(m) for _ in SIDES for m in JOINT_MOTIONS])
    vertices = settle_posture(rest.vertices[0] * scale, rest.bone_heads[0] * scale, angles,
                              Rig.from_model(body_model))[1]
    return body_model.skin_mesh(vertices)


def side_by_side(body_model, side_m: float = 1.0, seed: int = 4) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A man in the A-pose and a woman with arms down, ``side_m`` apart, a wall 0.8 m behind, seen by a
    Kinect v2 at 3 m and 10° with Kinect v1's noise model (``seed``).

    Returns
    -------
    depth_m : (424, 512) float64
    man, people : (424, 512) bool
        The man's pixels, and both people's.
    """
    from wbsa.bodies.anthropometry import reference_adult
    from wbsa.camera import MeshScene, View, preset
    from wbsa.sensor.settings import SensorSettings
    from wbsa.simulate import simulate_view
    from wbsa.training.room import compose_room

    man = posed_skin(body_model, body_model.rest_bodies(reference_adult(0.0)), "a-pose")
    woman = posed_skin(body_model, body_model.rest_bodies(reference_adult(1.0)), "arms-down")
    room = compose_room(man, 0.0, wall_behind_m=0.8, others=((woman, side_m),))
    frame = simulate_view(MeshScene(room.mesh, surroundings=True), preset("kinect-v2"), View(0.0, 10.0, 3.0),
                          sensor=SensorSettings(noise="nguyen2012"), seed=seed, keep_frame=True,
                          target=room.subject_center).frame
    t, n = frame.triangle_id, room.n_subject_faces
    return np.asarray(frame.depth_m, dtype=np.float64), (t >= 0) & (t < n), (t >= 0) & (t < n + len(woman.faces))


def read_pcd_depth(path: str | Path) -> np.ndarray:
    """(h, w) float64 depth image (z in metres, 0 = no return) of an organised PCD file
    (:func:`wbsa.core.point_cloud.point_cloud_depth`).

    Parameters
    ----------
    path : str or path
    """
    from wbsa.core.point_cloud import point_cloud_depth

    return point_cloud_depth(path)[0]
