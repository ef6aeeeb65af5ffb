"""One simulated depth view of one body: camera, sensor, reconstruction (shared by ``view``, ``scan``, the report).

:func:`simulate_view` is the one place where a view of a mesh is rendered, read out through the simulated
sensor and reconstructed; ``wbsa view``, the scan worker and the report's snapshots all call it, so the
same subject, view and seeds give the same numbers everywhere.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from wbsa.errors import WbsaError

if TYPE_CHECKING:  # pragma: no cover - for type hints only
    from wbsa.camera import Intrinsics, MeshScene, View
    from wbsa.core.frame import DepthFrame
    from wbsa.core.mesh import TriangleMesh
    from wbsa.sensor.settings import SensorSettings
    from wbsa.surface.settings import ReconstructionSettings


@dataclass(frozen=True)
class SimulatedView:
    """What one camera placement gives of one body.

    Attributes
    ----------
    row : dict
        The measured columns: those of :func:`wbsa.camera.measure_view` (``azimuth_deg, elevation_deg,
        distance_m, camera, vbsa_hit_m2, vbsa_visible_m2, n_pixels, n_triangles_hit, fits_in_frame``),
        with a sensor also :func:`wbsa.sensor.measure.sense_view`'s (``n_pixels_sensor, vbsa_hit_sensor_m2,
        vbsa_visible_sensor_m2, sensor_<setting>``), and ``vbsa_recon_<method>_m2`` per reconstruction.
    frame : DepthFrame or None
        The frame the reconstructions saw (the sensor's when there is one); :func:`render` always keeps it,
        :func:`simulate_view` only with ``keep_frame``.
    surfaces : dict of str to TriangleMesh
        The reconstructed surfaces by method (camera frame, metres); :func:`render` always keeps them,
        :func:`simulate_view` only with ``keep_surfaces``.
    """

    row: dict[str, Any]
    frame: DepthFrame | None = None
    surfaces: dict[str, TriangleMesh] = field(default_factory=dict)

    @property
    def depth_m(self) -> np.ndarray:
        """(h, w) float32 z-depth image in metres (0 = no return); needs the frame (see ``keep_frame``)."""
        if self.frame is None:
            raise AttributeError("this view was simulated without its frame; pass keep_frame=True")
        return self.frame.depth_m

    def __repr__(self) -> str:
        r = self.row
        return (f"SimulatedView(azimuth {r['azimuth_deg']:g}°, elevation {r['elevation_deg']:g}°, "
                f"{r['distance_m']:.3g} m, {r['n_pixels']} pixels, visible {r['vbsa_visible_m2']:.4f} m²)")


def simulate_view(scene: MeshScene, camera: Intrinsics, view: View, **options: Any) -> SimulatedView:
    """Render one view of a body, read it through the sensor and reconstruct the visible surface.

    :func:`simulate_views` of the one view; ``options`` are its keyword arguments.

    Returns
    -------
    SimulatedView
    """
    return simulate_views(scene, camera, (view,), **options)[0]


def simulate_views(scene: MeshScene, camera: Intrinsics, views: Sequence[View], *, backend: str = "open3d",
                   sensor: SensorSettings | None = None, seed: int = 0, subject_id: int = 0,
                   reconstruct: tuple[str, ...] = (), reconstruction: ReconstructionSettings | None = None,
                   keep_frame: bool = False, keep_surfaces: bool = False,
                   target: np.ndarray | None = None) -> list[SimulatedView]:
    """Render views of one body (all in one go with a compiled back end), sense and reconstruct each.

    Parameters
    ----------
    scene : wbsa.camera.MeshScene
        The body (its bounding-box centre is the camera's target).
    camera : wbsa.camera.Intrinsics
    views : sequence of wbsa.camera.View
    backend : {'open3d', 'warp', 'auto'}
        Ray-casting back end (:mod:`wbsa.camera.backends`): ``open3d`` view by view (the reference), ``warp``
        every view in a few compiled passes, with the same rows within float32 rounding.
    sensor : wbsa.sensor.SensorSettings, optional
        None: the ray-cast frame as it is (an ideal sensor model still adds its columns).
    seed, subject_id : int
        The sensor's random stream is :func:`wbsa.sensor.measure.view_rng` of (seed, subject, view), so it
        does not depend on which other views or subjects are simulated.
    reconstruct : tuple of {'grid', 'ball-pivoting', 'poisson'}
        Reconstruction methods; each adds ``vbsa_recon_<method>_m2``.
    reconstruction : wbsa.surface.ReconstructionSettings, optional
        How to reconstruct (default settings when None).
    keep_frame, keep_surfaces : bool
        Return the frames and the reconstructed surfaces (a scan keeps only the numbers).
    target : (3,) float, optional
        The point the camera aims at; default the scene's bounding-box centre (give the subject's centre
        when the scene also holds a room).

    Returns
    -------
    list of SimulatedView
        One per view, in order.
    """
    from wbsa.camera.backends import iter_measure_views
    from wbsa.core.limits import check_seed

    check_seed(seed, "the sensor seed")
    need_frame = keep_frame or sensor is not None or bool(reconstruct)
    target = scene.center if target is None else np.asarray(target, dtype=np.float64)
    measured = iter_measure_views(scene, camera, views, target, backend=backend, return_frames=need_frame)
    out = []
    for view, (row, frame) in zip(views, measured):
        if sensor is not None:
            from wbsa.sensor.measure import sense_view, view_rng

            frame, sensed = sense_view(frame, scene, sensor, view_rng(seed, subject_id, view))
            row.update(sensed)
        surfaces = {}
        if reconstruct:
            from wbsa.surface import reconstruct as reconstruct_surface
            from wbsa.surface.settings import recon_column

            for method in reconstruct:
                surface = reconstruct_surface(frame, method, reconstruction)
                row[recon_column(method)] = surface.area_m2
                if keep_surfaces:
                    surfaces[method] = surface
        out.append(SimulatedView(row=row, frame=frame if keep_frame else None, surfaces=surfaces))
    return out


def render(mesh: Any, camera: Any = "kinect-v1", view: Any = (0.0, 0.0, 4.3), *, sensor: SensorSettings | None = None,
           reconstruct: tuple[str, ...] = (), seed: int = 0) -> SimulatedView:
    """Look at a mesh with the virtual depth camera: the depth image, the visible areas, the reconstructions.

    Parameters
    ----------
    mesh : TriangleMesh, trimesh.Trimesh, open3d.geometry.TriangleMesh, (vertices, faces) or a mesh file path
        In metres, +Z up, the subject facing −Y (the body model's frame); the camera aims at its bounding-box
        centre.
    camera : str, Intrinsics or open3d.camera.PinholeCameraIntrinsic
        A preset name (``kinect-v1``, ``kinect-v2``, ...), an Open3D intrinsics JSON path or object.
    view : View or (azimuth_deg, elevation_deg) or (azimuth_deg, elevation_deg, distance_m)
        The paper's convention: azimuth 0 = in front, 90 = at the subject's left; elevation +90 = above;
        distance from the camera to the mesh's centre (default 4.3 m).
    sensor : SensorSettings or dict, optional
        The simulated sensor (noise, quantisation, holes), or a dict of its fields; None: the ideal ray cast.
    reconstruct : str or tuple of {'grid', 'ball-pivoting', 'poisson'}
        Surfaces to reconstruct from the (sensed) depth image.
    seed : int
        Seed of the sensor's random stream.

    Returns
    -------
    SimulatedView
        ``.row`` (the measured areas), ``.frame`` / ``.depth_m`` and ``.surfaces``.

    Raises
    ------
    WbsaError
        For a camera, view or sensor of the wrong kind, and a mesh that is not a person's size in metres
        (its longest side outside 0.4–2.8 m: the message names the units it looks like, e.g. millimetres).

    Examples
    --------
    >>> import numpy as np, wbsa
    >>> corners = [[x, y, z] for x in (-0.2, 0.2) for y in (-0.1, 0.1) for z in (0.0, 1.7)]
    >>> faces = [[0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6], [0, 1, 3], [0, 3, 2],
    ...          [4, 6, 7], [4, 7, 5], [1, 5, 7], [1, 7, 3], [0, 2, 6], [0, 6, 4]]
    >>> box = (np.array(corners), np.array(faces))  # 0.4 m wide, 0.2 m deep, 1.7 m tall
    >>> seen = wbsa.render(box, "kinect-v1", (0, 0, 3.0))
    >>> seen.row["n_triangles_hit"], round(seen.row["vbsa_hit_m2"], 3)  # the front face, 0.4 m x 1.7 m
    (2, 0.68)
    >>> seen.depth_m.shape
    (480, 640)
    """
    from collections.abc import Mapping

    from wbsa.camera import MeshScene, View, resolve_camera
    from wbsa.sensor.settings import SensorSettings

    if not (isinstance(camera, str) or hasattr(camera, "__fspath__") or hasattr(camera, "fx")
            or hasattr(camera, "intrinsic_matrix")):
        raise WbsaError(f"camera must be a preset name, an intrinsics JSON path, wbsa Intrinsics or an Open3D "
                        f"PinholeCameraIntrinsic, got {type(camera).__name__}")
    intrinsics = resolve_camera(camera)
    if isinstance(mesh, str) or hasattr(mesh, "__fspath__"):
        from wbsa.core.mesh_io import read_mesh

        mesh = read_mesh(mesh)
    if not isinstance(view, View):
        try:
            numbers = tuple(float(v) for v in view)
            if len(numbers) not in (2, 3):
                raise ValueError
        except (TypeError, ValueError):
            raise WbsaError(f"view must be a View or (azimuth_deg, elevation_deg[, distance_m]) in degrees and "
                            f"metres, got {view!r}") from None
        from wbsa.camera.views import check_angle

        view = View(check_angle(numbers[0], "azimuth", "view azimuth_deg"),
                    check_angle(numbers[1], "elevation", "view elevation_deg"), *numbers[2:])
    if isinstance(reconstruct, str):
        reconstruct = (reconstruct,)
    if isinstance(sensor, Mapping):
        sensor = SensorSettings(**sensor)
    elif sensor is not None and not isinstance(sensor, SensorSettings):
        raise WbsaError(f"sensor must be SensorSettings or a dict of its fields, got {type(sensor).__name__}")
    from wbsa.core.mesh import TriangleMesh
    from wbsa.simulate.target import check_person_size

    mesh = TriangleMesh.from_any(mesh)
    check_person_size(mesh)
    scene = MeshScene(mesh)
    return simulate_view(scene, intrinsics, view, sensor=sensor, seed=seed, reconstruct=tuple(reconstruct),
                         keep_frame=True, keep_surfaces=True)


def points_world(frame: DepthFrame) -> np.ndarray:
    """The returns of a frame in world coordinates.

    Parameters
    ----------
    frame : DepthFrame
        With its ``pose`` (world-to-camera transform).

    Returns
    -------
    (k, 3) float64
        One point per pixel with a return, metres.
    """
    return frame.pose.inverse().apply(frame.points_cam[frame.valid].astype(np.float64))
