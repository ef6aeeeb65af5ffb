"""core: the types and file formats every stage shares, below all stages.

``mesh``         :class:`TriangleMesh` (from trimesh, Open3D, arrays or a file) and triangle areas
``mesh_io``      :func:`read_mesh`, :func:`write_mesh` (PLY/OBJ, metres)
``frame``        :class:`DepthFrame`: one depth view, the contract between camera, sensor and surface
``depth_image``  depth images as sensors store them (:func:`read_depth`: PNG, .npy, TIFF, EXR; :func:`write_depth_png`)
``backproject``  depth image → points, normals and a :class:`DepthFrame` (:func:`frame_from_depth_image`)
``versions``     :func:`package_versions` recorded with results

Nothing here imports a stage. Names are imported lazily (numpy only until used).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from wbsa.lazy import lazy_exports

if TYPE_CHECKING:  # pragma: no cover - for IDEs and type checkers
    from wbsa.core.backproject import backproject_depth, frame_from_depth_image, organised_normals
    from wbsa.core.depth_image import read_depth, read_depth_png, write_depth_png
    from wbsa.core.frame import DepthFrame
    from wbsa.core.mesh import TriangleMesh, triangle_areas_m2
    from wbsa.core.mesh_io import read_mesh, write_mesh
    from wbsa.core.versions import package_versions

_EXPORTS = {
    "TriangleMesh": "wbsa.core.mesh",
    "triangle_areas_m2": "wbsa.core.mesh",
    "read_mesh": "wbsa.core.mesh_io",
    "write_mesh": "wbsa.core.mesh_io",
    "DepthFrame": "wbsa.core.frame",
    "read_depth": "wbsa.core.depth_image",
    "read_depth_png": "wbsa.core.depth_image",
    "write_depth_png": "wbsa.core.depth_image",
    "backproject_depth": "wbsa.core.backproject",
    "frame_from_depth_image": "wbsa.core.backproject",
    "organised_normals": "wbsa.core.backproject",
    "package_versions": "wbsa.core.versions",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
