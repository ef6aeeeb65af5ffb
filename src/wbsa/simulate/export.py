"""Files of one rendered view: depth PNG, point cloud, visible triangles, camera JSON, preview.

Every file is written under a temporary name beside its final one, checked (the PLY's size and
counts, the PNGs decoded) and renamed when complete (:func:`wbsa.atomic.atomic_path`), so an interrupted
run or a full disk never leaves a half-written file under a final name. ``view.json`` is written
last: a view folder is complete when it exists.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Literal

import numpy as np

from wbsa.core.frame import DepthFrame
from wbsa.errors import WbsaError
from wbsa.core.mesh_io import quiet_stderr
from wbsa.core.ply import check_ply, empty_point_cloud_ply
from wbsa.io import atomic_path, os_error_message, write_bytes, write_json

#: Largest depth a 16-bit millimetre PNG holds (m); farther returns are written as 0 (no return).

FILES = {
    "depth": "depth.png",
    "points": "points.ply",
    "triangles": "visible_triangles.txt",
    "triangle_id": "triangle_id.npy",
    "intrinsics": "intrinsics.json",
    "extrinsics": "extrinsics.json",
    "preview": "preview.png",
    "summary": "view.json",
}


def write_depth_png(frame: DepthFrame, path: str | os.PathLike) -> Path:
    """16-bit PNG of the z-depth in millimetres (0 = no return), readable by ``open3d.io.read_image``."""
    from wbsa.core.depth_image import write_depth_png as write_png

    return write_png(path, frame.depth_m)


def write_point_cloud(frame: DepthFrame, path: str | os.PathLike,
                      coordinates: Literal["camera", "world"] = "camera") -> Path:
    """Binary PLY of the hit points and their camera-facing normals, in the camera or world frame (metres)."""
    import open3d as o3d

    valid = frame.depth_m > 0
    points = frame.points_cam[valid].astype(np.float64)
    normals = frame.normals_cam[valid].astype(np.float64)
    if coordinates == "world":
        inv = frame.pose.inverse()
        points = inv.apply(points)
        normals = normals @ frame.pose.R  # rotate back: n_world = Rᵀ n_cam
    path = Path(path)
    if len(points) == 0:  # nothing visible: Open3D refuses an empty cloud, so write the empty PLY directly
        return write_bytes(empty_point_cloud_ply(), path)
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    cloud.normals = o3d.utility.Vector3dVector(normals)
    n = len(points)
    with atomic_path(path, keep_suffix=True, verify=lambda tmp: check_ply(tmp, n)) as tmp, quiet_stderr():
        if not o3d.io.write_point_cloud(str(tmp), cloud, write_ascii=False):
            raise WbsaError(f"open3d could not write {path}; check the disk and the folder")
    return path


def visible_triangle_ids(frame: DepthFrame) -> np.ndarray:
    """(k,) int64 sorted unique ids of the triangles hit by at least one pixel."""
    ids = frame.triangle_id[frame.triangle_id >= 0]
    return np.unique(ids)


def write_preview(frame: DepthFrame, path: str | os.PathLike, title: str = "") -> Path:
    """PNG preview (matplotlib, Agg): depth map and shaded surface side by side."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    valid = frame.depth_m > 0
    depth = np.where(valid, frame.depth_m, np.nan)
    # Lambert shading with a light at the camera: |n · ray| on unit rays.
    from wbsa.camera.intrinsics import pixel_rays

    dirs, cos_axis = pixel_rays(frame.intrinsics)
    shade = np.abs(np.einsum("hwc,hwc->hw", np.nan_to_num(frame.normals_cam), dirs)) * cos_axis
    shade = np.where(valid, shade, np.nan)
    h, w = frame.depth_m.shape
    fig, axes = plt.subplots(1, 2, figsize=(10, 10 * h / (2 * w) + 0.9), constrained_layout=True)
    im = axes[0].imshow(depth, cmap="viridis")
    fig.colorbar(im, ax=axes[0], shrink=0.8, label="z-depth (m)")
    axes[0].set_title("depth")
    axes[1].imshow(shade, cmap="gray", vmin=0, vmax=1)
    axes[1].set_title("surface (light at the camera)")
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_facecolor("black")
    if title:
        fig.suptitle(title, fontsize=10)
    path = Path(path)
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png", dpi=100)
    finally:
        plt.close(fig)
    return path


def write_view_outputs(frame: DepthFrame, out_dir: str | os.PathLike, summary: dict, *,
                       coordinates: Literal["camera", "world"] = "camera", title: str = "") -> dict[str, Path]:
    """Write every file of one view into ``out_dir``; returns {kind: path}.

    Files: ``depth.png`` (uint16 mm, 0 = no return), ``points.ply`` (hit points + normals), ``visible_triangles.txt``
    (unique hit triangle ids, one per line), ``triangle_id.npy`` ((h, w) int32, −1 = no return),
    ``intrinsics.json`` (Open3D PinholeCameraIntrinsic), ``extrinsics.json`` (g = [R | T] both ways),
    ``preview.png`` and ``view.json`` (``summary``).
    """
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise WbsaError(os_error_message(exc, out, "create folder")) from None
    paths = {key: out / name for key, name in FILES.items()}
    write_depth_png(frame, paths["depth"])
    write_point_cloud(frame, paths["points"], coordinates)
    with atomic_path(paths["triangles"]) as tmp:
        np.savetxt(tmp, visible_triangle_ids(frame), fmt="%d")
    with atomic_path(paths["triangle_id"]) as tmp:
        with open(tmp, "wb") as fh:
            np.save(fh, frame.triangle_id.astype(np.int32))
    write_json(frame.intrinsics.to_open3d_json(), paths["intrinsics"])
    extrinsics = dict(frame.pose.to_dict())
    for key in ("azimuth_deg", "elevation_deg", "distance_m", "target_m"):
        if key in frame.settings:
            extrinsics[key] = frame.settings[key]
    extrinsics["point_cloud_frame"] = coordinates
    write_json(extrinsics, paths["extrinsics"])
    write_preview(frame, paths["preview"], title)
    write_json(summary, paths["summary"])
    return paths
