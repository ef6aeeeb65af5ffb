"""Synthetic rooms for testing the estimator: a body, a floor, a wall behind it, maybe a second person.

:func:`compose_room` puts a body mesh on a floor with a wall behind it (as seen from a camera at a given
azimuth) and optionally other people beside it, as one :class:`~wbsa.core.TriangleMesh` whose first
``n_subject_faces`` triangles are the subject's, so every rendered pixel knows whether it is the subject
(its triangle ID). :func:`capture_room` renders it as a millimetre depth image.
The floor and walls are tiled into small squares so that the sensor's triangle holes stay small.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wbsa.core.mesh import TriangleMesh
from wbsa.errors import WbsaError
from wbsa.typing import EdgePixels


@dataclass(frozen=True)
class RoomScene:
    """A composed scene.

    Attributes
    ----------
    mesh : TriangleMesh
        Subject first, then the other people, the floor and the walls.
    n_subject_faces : int
        Triangles ``0 .. n_subject_faces - 1`` are the subject's.
    subject_center : (3,) float64
        The subject's bounding-box centre (the camera's target).
    """

    mesh: TriangleMesh
    n_subject_faces: int
    subject_center: np.ndarray

    def is_subject(self, triangle_id: np.ndarray) -> np.ndarray:
        """Bool array: which triangle IDs (−1 = no return) belong to the subject."""
        t = np.asarray(triangle_id)
        return (t >= 0) & (t < self.n_subject_faces)

    def surface_height_m(self, triangle_id: np.ndarray) -> np.ndarray:
        """Height over the floor (z = 0) of the triangles seen, by their centroids; NaN where no return.

        Parameters
        ----------
        triangle_id : (h, w) int
            Triangle of every pixel (−1 = no return), as in :attr:`wbsa.core.DepthFrame.triangle_id`.

        Returns
        -------
        (h, w) float64
        """
        t = np.asarray(triangle_id)
        centroid_z = self.mesh.vertices[self.mesh.faces].mean(axis=1)[:, 2]
        return np.where(t >= 0, centroid_z[np.maximum(t, 0)], np.nan)


def tiled_rectangle(origin: np.ndarray, edge_u: np.ndarray, edge_v: np.ndarray, tile_m: float = 0.25) -> TriangleMesh:
    """A rectangle ``origin + s·edge_u + t·edge_v`` (s, t in [0, 1]) tiled into squares of about ``tile_m``.

    Its triangles are counter-clockwise seen from the side ``edge_u × edge_v`` points to.
    """
    origin, eu, ev = (np.asarray(a, dtype=np.float64) for a in (origin, edge_u, edge_v))
    nu = max(1, int(np.ceil(np.linalg.norm(eu) / tile_m)))
    nv = max(1, int(np.ceil(np.linalg.norm(ev) / tile_m)))
    s, t = np.meshgrid(np.linspace(0, 1, nu + 1), np.linspace(0, 1, nv + 1), indexing="ij")
    verts = origin + s.reshape(-1, 1) * eu + t.reshape(-1, 1) * ev
    idx = np.arange((nu + 1) * (nv + 1)).reshape(nu + 1, nv + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)]).astype(np.int32)
    return TriangleMesh(verts, faces)


def merge_meshes(*meshes: TriangleMesh) -> TriangleMesh:
    """One mesh holding all ``meshes`` in order (faces re-indexed)."""
    verts, faces, offset = [], [], 0
    for m in meshes:
        verts.append(np.asarray(m.vertices, dtype=np.float64))
        faces.append(np.asarray(m.faces, dtype=np.int64) + offset)
        offset += len(m.vertices)
    return TriangleMesh(np.concatenate(verts), np.concatenate(faces).astype(np.int32))


def turned(mesh: TriangleMesh, yaw_deg: float, offset_m: np.ndarray) -> TriangleMesh:
    """``mesh`` turned by ``yaw_deg`` about the vertical through its centre, then moved by ``offset_m`` (3,)."""
    c, s = np.cos(np.radians(yaw_deg)), np.sin(np.radians(yaw_deg))
    rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    centre = mesh.bbox_center * np.array([1.0, 1.0, 0.0])
    v = (np.asarray(mesh.vertices) - centre) @ rz.T + centre + np.asarray(offset_m, dtype=np.float64)
    return TriangleMesh(v, mesh.faces)


def compose_room(subject: TriangleMesh, camera_azimuth_deg: float, *, wall_behind_m: float | None = 1.0,
                 others: tuple[tuple[TriangleMesh, float], ...] = (), floor: bool = True,
                 room_half_width_m: float = 3.0, wall_height_m: float = 2.6, camera_distance_m: float = 5.0) -> RoomScene:
    """The subject standing on a floor, a wall behind it as seen from the camera, other people beside it.

    Parameters
    ----------
    subject : TriangleMesh
        Standing on z = 0 (anny's frame: facing −Y).
    camera_azimuth_deg : float
        Where the camera will be (paper convention); the wall is placed on the far side.
    wall_behind_m : float or None
        Gap between the subject's back-most point (as seen from the camera) and the wall; None = no wall.
    others : tuple of (TriangleMesh, float)
        Other people and their sideways offset (m, along the image's right) from the subject's centre;
        each stands at the subject's distance from the wall.
    floor : bool
        Add the floor (z = 0).
    room_half_width_m, wall_height_m, camera_distance_m : float
        Size of the floor and wall (the floor reaches ``camera_distance_m`` + 1 m in front of the subject).

    Returns
    -------
    RoomScene
    """
    if wall_behind_m is not None and not wall_behind_m > 0:
        raise WbsaError(f"wall_behind_m must be positive, got {wall_behind_m}")
    th = np.radians(camera_azimuth_deg)
    to_camera = np.array([np.sin(th), -np.cos(th), 0.0])  # horizontal, from the subject towards the camera
    right = np.array([np.cos(th), np.sin(th), 0.0])        # the image's right (the camera's x axis)
    centre = subject.bbox_center
    depth = (np.asarray(subject.vertices) - centre) @ to_camera
    back = float(depth.min())                                 # the subject's far side, along to_camera
    parts = [subject]
    for mesh, side_m in others:
        parts.append(turned(mesh, 0.0, centre * np.array([1.0, 1.0, 0.0]) - mesh.bbox_center * np.array([1, 1, 0])
                            + side_m * right))
    base = centre * np.array([1.0, 1.0, 0.0])
    far = (back - (wall_behind_m if wall_behind_m is not None else 1.0)) * to_camera
    if floor:
        near = (camera_distance_m + 1.0) * to_camera
        # counter-clockwise from above: edge_u × edge_v = +Z
        corner = base + far - room_half_width_m * right
        parts.append(tiled_rectangle(corner, near - far, 2 * room_half_width_m * right))
    if wall_behind_m is not None:
        corner = base + far - room_half_width_m * right
        # facing the camera: edge_u × edge_v = to_camera
        parts.append(tiled_rectangle(corner, 2 * room_half_width_m * right, np.array([0.0, 0.0, wall_height_m])))
    return RoomScene(merge_meshes(*parts), int(len(subject.faces)), centre)


def capture_room(room: RoomScene, capture, *, seed: int, subject_id: int):
    """Render ``room`` as one drawn capture sees it, stored as a millimetre depth image would be.

    The camera aims at the subject's centre and stands in the room (``MeshScene(surroundings=True)``: no
    inside-the-body check); the capture's sensor reads the frame with the stream of ``(seed, subject_id)``.

    Parameters
    ----------
    room : RoomScene
    capture : wbsa.training.capture.Capture
    seed, subject_id : int

    Returns
    -------
    frame : wbsa.core.DepthFrame
        The sensed frame (its ``triangle_id`` tells the subject's pixels, :meth:`RoomScene.is_subject`).
    depth_m : (h, w) float64
        Its depth rounded to whole millimetres.
    """
    from wbsa.camera.scene import MeshScene
    from wbsa.simulate import simulate_view

    scene = MeshScene(room.mesh, nthreads=1, surroundings=True)
    frame = simulate_view(scene, capture.camera, capture.view, sensor=capture.sensor, seed=seed, subject_id=subject_id,
                          keep_frame=True, target=room.subject_center).frame
    return frame, np.round(frame.depth_m.astype(np.float64) * 1000.0) / 1000.0


def with_edge_pixels(depth_m: np.ndarray, effect: EdgePixels, share: float, rng: np.random.Generator) -> np.ndarray:
    """A captured millimetre depth image with its depth edges as a camera returns them, still in millimetres.

    ``effect`` ``'kept'`` returns ``depth_m`` itself; ``'mixed'`` and ``'dropped'`` apply
    :func:`wbsa.sensor.depth_edges.edge_pixels` to ``share`` of the edges.
    """
    from wbsa.sensor.depth_edges import edge_pixels

    if effect == "kept":
        return depth_m
    return np.round(edge_pixels(depth_m, rng, effect, share) * 1000.0) / 1000.0
