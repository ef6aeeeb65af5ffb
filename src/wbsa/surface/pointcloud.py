"""Unorganised point-cloud reconstruction with Open3D: ball pivoting and screened Poisson.

Both start from the back-projected returns of one depth image with the paper's optional clean-up
(section 4.4): voxel down-sampling and moving-least-squares smoothing, then normals estimated from
the ``neighbours`` nearest points and oriented towards the camera (the origin of the camera frame).
Poisson reconstructs a closed, watertight surface around the one visible side; it is cut back to
the observed surface by density trimming and by keeping only the triangles whose centroid lies
within ``crop_distance_px`` point spacings of a point of the cloud, so that its area estimates the
visible area.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from wbsa.errors import WbsaError
from wbsa.core.mesh import TriangleMesh
from wbsa.surface.settings import ReconstructionSettings


def mls_project(points: np.ndarray, neighbours: int) -> np.ndarray:
    """First-order moving least squares: move each point onto the plane fitted to its neighbours.

    Parameters
    ----------
    points : (n, 3) float
    neighbours : int
        Points per local plane fit (the point itself included).

    Returns
    -------
    (n, 3) float64
    """
    p = np.asarray(points, dtype=np.float64)
    k = min(int(neighbours), len(p))
    if k < 3:
        return p.copy()
    _, idx = cKDTree(p).query(p, k=k)
    nb = p[idx]                                   # (n, k, 3)
    centre = nb.mean(axis=1)
    d = nb - centre[:, None, :]
    cov = np.einsum("nki,nkj->nij", d, d)
    _, vecs = np.linalg.eigh(cov)
    normal = vecs[:, :, 0]                        # smallest eigenvalue
    return p - np.einsum("ni,ni->n", p - centre, normal)[:, None] * normal


def point_cloud_mesh(points: np.ndarray, method: str, spacing_m: float,
                     settings: ReconstructionSettings) -> TriangleMesh:
    """Reconstruct a surface from camera-frame points with Open3D.

    Parameters
    ----------
    points : (n, 3) float
        Returns of one view in the camera frame (metres).
    method : {'ball-pivoting', 'poisson'}
    spacing_m : float
        Typical distance between neighbouring points (the pixel pitch at their depth).
    settings : ReconstructionSettings

    Returns
    -------
    TriangleMesh
        In the camera frame; empty if there are fewer than ``settings.neighbours`` points.
    """
    import open3d as o3d

    p = np.asarray(points, dtype=np.float64)
    if len(p) < max(settings.neighbours, 4):
        return TriangleMesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int32))
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(p))
    spacing = float(spacing_m)
    if settings.voxel_size_m > 0:
        pcd = pcd.voxel_down_sample(settings.voxel_size_m)
        spacing = max(spacing, settings.voxel_size_m)
    if settings.smoothing == "mls":
        pcd.points = o3d.utility.Vector3dVector(mls_project(np.asarray(pcd.points), settings.neighbours))
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(settings.neighbours))
    pcd.orient_normals_towards_camera_location(np.zeros(3))
    cloud = np.asarray(pcd.points)
    if method == "ball-pivoting":
        radii = o3d.utility.DoubleVector([r * spacing for r in settings.bpa_radii_px])
        mesh = o3d.geometry.TriangleMesh.create_from_point_cloud_ball_pivoting(pcd, radii)
        vertices, faces = np.asarray(mesh.vertices), np.asarray(mesh.triangles)
    elif method == "poisson":
        mesh, densities = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(
            pcd, depth=settings.poisson_depth, n_threads=1)
        vertices, faces = np.asarray(mesh.vertices), np.asarray(mesh.triangles)
        keep_vertex = np.ones(len(vertices), dtype=bool)
        if settings.poisson_trim_quantile > 0:
            dens = np.asarray(densities)
            keep_vertex &= dens >= np.quantile(dens, settings.poisson_trim_quantile)
        faces = faces[keep_vertex[faces].all(axis=1)]
        centroids = vertices[faces].mean(axis=1)
        dist, _ = cKDTree(cloud).query(centroids, distance_upper_bound=settings.crop_distance_px * spacing)
        faces = faces[np.isfinite(dist)]
    else:
        raise WbsaError(f"unknown point-cloud method {method!r}; use ball-pivoting or poisson")
    return _compact(vertices, faces)


def _compact(vertices: np.ndarray, faces: np.ndarray) -> TriangleMesh:
    """Drop unreferenced vertices; faces as int32."""
    if len(faces) == 0:
        return TriangleMesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int32))
    used = np.zeros(len(vertices), dtype=bool)
    used[faces.ravel()] = True
    remap = np.cumsum(used) - 1
    return TriangleMesh(np.asarray(vertices[used], dtype=np.float64), remap[faces].astype(np.int32))
