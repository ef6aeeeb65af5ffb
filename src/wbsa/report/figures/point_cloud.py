"""Paper Fig 8: the point cloud one camera sees of one subject, looked at from four sides."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from wbsa.report.figures.style import FigureUnavailable, new_figure


def point_cloud_snapshots(points_world: np.ndarray, depth_m: np.ndarray, body_vertices: np.ndarray, *,
                          view: tuple[float, float], distance_m: float, subject_id: int, camera: str,
                          dpi: int = 100) -> Figure:
    """The point cloud one camera sees, looked at from other directions (paper Fig 8).

    Parameters
    ----------
    points_world : (k, 3) float
        The camera's returns in world coordinates (metres).
    depth_m : (h, w) float
        The depth image (0 = no return), cropped or whole.
    body_vertices : (n, 3) float
        The whole body (drawn light grey behind the points, so the unseen skin shows).
    view, distance_m, subject_id, camera
        For the titles.
    """
    from wbsa.camera.extrinsics import look_at_rotation

    if len(points_world) == 0:
        raise FigureUnavailable("the camera saw no point of the subject")
    fig = new_figure(14.0, 4.4, dpi)
    axes = fig.subplots(1, 5)
    rows, cols = np.nonzero(depth_m > 0)
    crop = depth_m[rows.min():rows.max() + 1, cols.min():cols.max() + 1].astype(float)
    crop[crop <= 0] = np.nan
    im = axes[0].imshow(crop, cmap="viridis")
    fig.colorbar(im, ax=axes[0], shrink=0.8, label="depth (m)")
    axes[0].set_title(f"depth image, θ = {view[0]:g}°, φ = {view[1]:g}°", fontsize=9)
    axes[0].set_xticks([])
    axes[0].set_yticks([])
    center = 0.5 * (body_vertices.min(axis=0) + body_vertices.max(axis=0))
    rng = np.random.default_rng(0)
    body = body_vertices[rng.permutation(len(body_vertices))[:6000]] - center
    pts = points_world - center
    for ax, (az, name) in zip(axes[1:], ((0.0, "front"), (90.0, "left side"), (180.0, "back"), (270.0, "right side"))):
        R = look_at_rotation(az, 0.0)
        ax.scatter(body @ R[0], -(body @ R[1]), s=0.3, color="0.85", rasterized=True)
        depth_along = pts @ R[2]
        ax.scatter(pts @ R[0], -(pts @ R[1]), s=0.3, c=depth_along, cmap="plasma", rasterized=True)
        ax.set_aspect("equal")
        ax.set_title(f"points seen from the {name}", fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(f"subject {subject_id}: {len(points_world)} points from θ = {view[0]:g}°, φ = {view[1]:g}°, "
                 f"D = {distance_m:g} m ({camera}); grey = skin the camera does not see", fontsize=10)
    return fig

