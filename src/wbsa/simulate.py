"""One simulated depth view of one body: camera, sensor, reconstruction (shared by ``view``, ``scan``, the report).

:func:`simulate_view` is the one place where a view of a mesh is rendered, read out through the simulated
sensor and reconstructed; ``wbsa view``, the scan worker and the report's snapshots all call it, so the
same subject, view and seeds give the same numbers everywhere.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover - for type hints only
    from wbsa.camera import Intrinsics, MeshScene, View
    from wbsa.core.frame import DepthFrame
    from wbsa.core.mesh import TriangleMesh
    from wbsa.sensor.model import SensorModel
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
        The frame the reconstructions saw (the sensor's when there is one); None when not asked for and not
        needed.
    surfaces : dict of str to TriangleMesh
        The reconstructed surfaces by method (camera frame, metres), when ``keep_surfaces``.
    """

    row: dict[str, Any]
    frame: DepthFrame | None = None
    surfaces: dict[str, TriangleMesh] = field(default_factory=dict)

    def __repr__(self) -> str:
        r = self.row
        return (f"SimulatedView(azimuth {r['azimuth_deg']:g}°, elevation {r['elevation_deg']:g}°, "
                f"{r['distance_m']:.3g} m, {r['n_pixels']} pixels, visible {r['vbsa_visible_m2']:.4f} m²)")


def simulate_view(scene: MeshScene, camera: Intrinsics, view: View, *, sensor: SensorModel | None = None,
                  seed: int = 0, subject_id: int = 0, reconstruct: tuple[str, ...] = (),
                  reconstruction: ReconstructionSettings | None = None, keep_frame: bool = False,
                  keep_surfaces: bool = False, target: np.ndarray | None = None) -> SimulatedView:
    """Render one view of a body, read it through the sensor and reconstruct the visible surface.

    Parameters
    ----------
    scene : wbsa.camera.MeshScene
        The body (its bounding-box centre is the camera's target).
    camera : wbsa.camera.Intrinsics
    view : wbsa.camera.View
    sensor : wbsa.sensor.SensorModel, optional
        None: the ray-cast frame as it is (an ideal sensor model still adds its columns).
    seed, subject_id : int
        The sensor's random stream is :func:`wbsa.sensor.measure.view_rng` of (seed, subject, view), so it
        does not depend on which other views or subjects are simulated.
    reconstruct : tuple of {'grid', 'ball-pivoting', 'poisson'}
        Reconstruction methods; each adds ``vbsa_recon_<method>_m2``.
    reconstruction : wbsa.surface.ReconstructionSettings, optional
        How to reconstruct (default settings when None).
    keep_frame, keep_surfaces : bool
        Return the frame and the reconstructed surfaces (a scan keeps only the numbers).
    target : (3,) float, optional
        The point the camera aims at; default the scene's bounding-box centre (give the subject's centre
        when the scene also holds a room).

    Returns
    -------
    SimulatedView
    """
    from wbsa.camera.measure import measure_view

    need_frame = keep_frame or sensor is not None or bool(reconstruct)
    target = scene.center if target is None else np.asarray(target, dtype=np.float64)
    row, frame = measure_view(scene, camera, view, target, return_frame=need_frame)
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
    return SimulatedView(row=row, frame=frame if keep_frame else None, surfaces=surfaces)


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
