"""camera stage: pinhole intrinsics and extrinsics, view grids, ray casting, visible skin area.

Importing this package is cheap (numpy only); Open3D is imported when a :class:`MeshScene` is built.
"""

from wbsa.camera.area import GRAZING_COS, sphere_cap_area_m2, vbsa_hit_m2, vbsa_visible_m2
from wbsa.camera.extrinsics import Pose, look_at_rotation, pose_from_view
from wbsa.camera.fit import distance_to_fit, max_stature_m, vertical_half_fov_deg
from wbsa.camera.intrinsics import Intrinsics
from wbsa.camera.measure import measure_view
from wbsa.camera.presets import CAMERAS, PRESETS, CameraRecord, camera_record, preset, resolve_camera
from wbsa.camera.raycast import RayHits, cast, render
from wbsa.camera.roi import projected_roi, silhouette_blocks
from wbsa.camera.scene import MeshScene
from wbsa.camera.views import View, grid_views, paper_views, parse_views, sphere_views

__all__ = [
    "CAMERAS", "CameraRecord", "GRAZING_COS", "Intrinsics", "MeshScene", "PRESETS", "camera_record", "Pose", "RayHits", "View", "cast",
    "distance_to_fit", "grid_views", "look_at_rotation", "max_stature_m", "measure_view", "paper_views",
    "parse_views", "pose_from_view", "preset", "projected_roi", "render", "resolve_camera", "sphere_cap_area_m2",
    "silhouette_blocks", "sphere_views", "vbsa_hit_m2", "vbsa_visible_m2", "vertical_half_fov_deg",
]
