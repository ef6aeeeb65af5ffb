"""One view of one subject: pose, ray cast, visible areas (the unit of work of a scan)."""

from __future__ import annotations

import numpy as np

from wbsa.camera.area import GRAZING_COS, GRAZING_SPLIT_PX
from wbsa.camera.extrinsics import pose_from_view
from wbsa.camera.frame import DepthFrame
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


def measure_views(scene: MeshScene, intrinsics: Intrinsics, views, target: np.ndarray | None = None, *,
                  backend: str = "open3d", return_frames: bool = True, grazing_cos: float = GRAZING_COS,
                  grazing_split_px: float | None = GRAZING_SPLIT_PX) -> list[tuple[dict, DepthFrame | None]]:
    """Measure several views of one scene with a ray-casting back end (:mod:`wbsa.camera.backends`).

    Parameters
    ----------
    scene : MeshScene
    intrinsics : Intrinsics
    views : sequence of View
    target : (3,) float, optional
        Point the camera aims at; default the mesh's bounding-box centre.
    backend : {'open3d', 'warp', 'auto'}
        ``open3d`` is :func:`measure_view` view by view (the reference); ``warp`` measures the views in a
        few compiled passes on a GPU or the CPU, with the same rows within float32 rounding.
    return_frames, grazing_cos, grazing_split_px
        As :func:`measure_view`.

    Returns
    -------
    list of (row, frame)
        One per view, in order, as :func:`measure_view` returns them.
    """
    from wbsa.camera.backends import get_backend

    return get_backend(backend).measure_views(scene, intrinsics, list(views), target, return_frames=return_frames,
                                              grazing_cos=grazing_cos, grazing_split_px=grazing_split_px)


#: Views per :func:`measure_views` call in :func:`iter_measure_views` when frames are kept (a 640 × 480
#: frame takes about 11 MB).
FRAMES_PER_CALL = 8


def iter_measure_views(scene: MeshScene, intrinsics: Intrinsics, views, target: np.ndarray | None = None, *,
                       backend: str = "open3d", return_frames: bool = True):
    """:func:`measure_views`, one ``(row, frame)`` at a time, in view order.

    Without frames all views go to the back end in one call; with frames, ``FRAMES_PER_CALL`` views per
    call, so that a long view list does not hold all its frames at once.
    """
    views = list(views)
    step = FRAMES_PER_CALL if return_frames else max(1, len(views))
    for start in range(0, len(views), step):
        yield from measure_views(scene, intrinsics, views[start:start + step], target, backend=backend,
                                 return_frames=return_frames)
