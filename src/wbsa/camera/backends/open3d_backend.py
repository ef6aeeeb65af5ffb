"""The reference back end: Open3D's Embree ray casting per view and the numpy visible-area estimate."""

from __future__ import annotations

import numpy as np

from wbsa.camera.area import GRAZING_COS, GRAZING_SPLIT_PX
from wbsa.core.frame import DepthFrame
from wbsa.camera.intrinsics import Intrinsics
from wbsa.camera.scene import MeshScene
from wbsa.camera.views import View


class Open3DBackend:
    """:func:`wbsa.camera.measure.measure_view` for each view in turn (its rows bit for bit)."""

    name = "open3d"

    def measure_views(self, scene: MeshScene, intrinsics: Intrinsics, views: list[View],
                      target: np.ndarray | None = None, *, return_frames: bool = True,
                      grazing_cos: float = GRAZING_COS,
                      grazing_split_px: float | None = GRAZING_SPLIT_PX) -> list[tuple[dict, DepthFrame | None]]:
        """One ``(row, frame)`` per view: :func:`wbsa.camera.measure.measure_view` of each.

        Parameters
        ----------
        scene, intrinsics, views, target, return_frames, grazing_cos, grazing_split_px
            As for :func:`wbsa.camera.backends.measure_views` (without its ``backend``).
        """
        from wbsa.camera.measure import measure_view

        return [measure_view(scene, intrinsics, view, target, return_frame=return_frames, grazing_cos=grazing_cos,
                             grazing_split_px=grazing_split_px) for view in views]
