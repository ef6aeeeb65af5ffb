"""Render one subject's point cloud with the camera API, for the snapshot figure (paper Fig 8)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from wbsa.errors import WbsaError
from wbsa.report.data import nearest_view, select


@dataclass(frozen=True)
class Snapshot:
    """What one camera sees of one subject.

    Attributes
    ----------
    subject_id : int
    points_world : (k, 3) float64
        Returns in world coordinates, metres.
    depth_m : (h, w) float32
        The depth image (0 = no return).
    body_vertices : (n, 3) float64
        The whole skin mesh's vertices.
    """

    subject_id: int
    points_world: np.ndarray
    depth_m: np.ndarray
    body_vertices: np.ndarray


def snapshot_intrinsics(scan_paths: tuple[Path, ...], camera: str):
    """The scan's camera: ``intrinsics.json`` beside the scan table, else the preset named ``camera``.

    Raises
    ------
    WbsaError
        Neither is available (a custom camera whose JSON was not kept).
    """
    from wbsa.camera.intrinsics import Intrinsics
    from wbsa.camera.presets import PRESETS

    for p in scan_paths:
        js = Path(p).parent / "intrinsics.json"
        if js.is_file():
            k = Intrinsics.from_open3d_json(js)
            if k.name == camera or camera not in PRESETS:
                return k
    if camera in PRESETS:
        return PRESETS[camera]
    raise WbsaError(f"camera {camera!r} is not a preset and no intrinsics.json lies beside the scan")


def pick_subject(population: pd.DataFrame, subject_id: int | None = None) -> int:
    """``subject_id`` if given, else the subject whose WBSA is the median."""
    if subject_id is not None:
        if not (population["subject_id"] == subject_id).any():
            raise WbsaError(f"snapshot subject {subject_id} is not in the population; set [report] snapshot_subject")
        return int(subject_id)
    w = population["wbsa_m2"].to_numpy(float)
    i = int(np.argmin(np.abs(w - np.nanmedian(w))))
    return int(population["subject_id"].iloc[i])


def scanned_view(scan: pd.DataFrame, asked: tuple[float, float], *, distance_m: float,
                 camera: str | None = None) -> tuple[float, float]:
    """The view the study scanned nearest to ``asked`` (angular distance), at this distance and camera.

    The snapshot figure re-renders one subject, so it could show any view; it shows only one the study
    scanned, so that its point cloud is one of the study's measurements.

    Parameters
    ----------
    scan : DataFrame
        The scan table: ``azimuth_deg``, ``elevation_deg``, ``distance_m`` and optionally ``camera``.
    asked : (float, float)
        (azimuth, elevation) in degrees, e.g. ``[report] snapshot_view_deg``.
    distance_m : float
        The camera distance of the figure.
    camera : str, optional
        Keep only this camera's rows (where the table has a ``camera`` column).

    Returns
    -------
    (float, float)
        (azimuth, elevation) of a scanned view, in degrees.

    Raises
    ------
    WbsaError
        The scan has no view at this distance and camera.
    """
    rows = select(scan, distance_m=float(distance_m), camera=camera if "camera" in scan.columns else None)
    if rows.empty:
        raise WbsaError(f"the scan has no view at D = {float(distance_m):g} m" + (f" ({camera})" if camera else ""))
    return nearest_view(rows, float(asked[0]), float(asked[1]))


def render_snapshot(population: pd.DataFrame, subject_id: int, intrinsics, azimuth_deg: float, elevation_deg: float,
                    distance_m: float) -> Snapshot:
    """Rebuild the subject's body, ray-cast the view and return its points in world coordinates."""
    from wbsa.bodies.subject import subject_mesh
    from wbsa.camera import MeshScene, View
    from wbsa.simulate.view import points_world, simulate_view

    mesh = subject_mesh(population, subject_id)
    frame = simulate_view(MeshScene(mesh), intrinsics, View(azimuth_deg, elevation_deg, distance_m),
                          keep_frame=True).frame
    return Snapshot(subject_id=subject_id, points_world=points_world(frame), depth_m=frame.depth_m,
                    body_vertices=np.asarray(mesh.vertices, dtype=np.float64))
