"""One view of one subject: pose, ray cast, visible areas (the unit of work of a scan)."""

from __future__ import annotations

import numpy as np

from wbsa.camera.area import GRAZING_COS, GRAZING_SPLIT_PX
from wbsa.camera.extrinsics import pose_from_view
from wbsa.core.frame import DepthFrame
from wbsa.camera.intrinsics import Intrinsics
from wbsa.camera.raycast import MeshScene, RoiMode, cast
from wbsa.camera.views import View


def measure_view(scene: MeshScene, intrinsics: Intrinsics, view: View, target: np.ndarray | None = None, *,
                 roi: bool | RoiMode = True, return_frame: bool = True,
                 grazing_cos: float = GRAZING_COS,
                 grazing_split_px: float | None = GRAZING_SPLIT_PX) -> tuple[dict, DepthFrame | None]:
    """Render ``view`` of ``scene`` and measure the visible areas.

    Parameters
    ----------
    scene : MeshScene
    intrinsics : Intrinsics
    view : View
    target : (3,) float, optional
        Point the camera aims at; default the mesh's bounding-box centre (``scene.center``).
    roi : bool or {'silhouette', 'bbox', 'full'}
        Which pixels to cast (:func:`~wbsa.camera.raycast.cast`); the numbers are the same either way.
    return_frame : bool
        Also build the full-image :class:`DepthFrame`; pass False in scans that only need the numbers
        (the areas are computed from the compact ROI arrays either way).
    grazing_cos : float
        Triangles seen at cos θ below this are measured in object space for ``vbsa_visible_m2``
        (:func:`wbsa.camera.area.visible_area_m2`); 0.2 casts about two thirds as many visibility rays and
        stays within 1 % on the tested spheres and bodies; 0 gives the plain pixel sum (fastest, 1–5 % low).
    grazing_split_px : float or None
        Grazing triangles that may look larger than this many pixels count in proportion to their visible
        sub-triangles (:func:`wbsa.camera.area.grazing_area_m2`); None: by their centroid alone.

    Returns
    -------
    row : dict
        ``azimuth_deg, elevation_deg, distance_m, camera, vbsa_hit_m2, vbsa_visible_m2, n_pixels,
        n_triangles_hit, fits_in_frame`` (fits = no pixel on the image border sees the body).
    frame : DepthFrame or None
    """
    target = scene.center if target is None else np.asarray(target, dtype=np.float64)
    pose = pose_from_view(view, target)
    hits = cast(scene, intrinsics, pose, roi=roi)
    seen = np.zeros(scene.n_triangles, dtype=bool)
    seen[hits.hit_ids] = True
    row = {
        "azimuth_deg": view.azimuth_deg,
        "elevation_deg": view.elevation_deg,
        "distance_m": view.distance_m,
        "camera": intrinsics.name,
        "vbsa_hit_m2": float(np.einsum("i,i->", scene.triangle_areas_m2, seen)),
        "vbsa_visible_m2": hits.visible_area_m2(scene, grazing_cos, grazing_split_px),
        "n_pixels": hits.n_pixels,
        "n_triangles_hit": int(np.count_nonzero(seen)),
        "fits_in_frame": not hits.touches_border,
    }
    frame = None
    if return_frame:
        frame = hits.to_frame({"azimuth_deg": view.azimuth_deg, "elevation_deg": view.elevation_deg,
                               "distance_m": view.distance_m, "target_m": [float(x) for x in target]})
    return row, frame
