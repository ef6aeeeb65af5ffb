"""The along-ray data term: each observed depth against the model surface its own camera ray meets.

A depth camera measures, for each pixel, how far along that pixel's ray the surface lies; its noise moves a
return along the ray (axial σz(z, θ)) and its quantisation rounds that distance. So each observed point is
compared with the model where its ray meets it: the first model triangle the ray hits (found on the whole
posed skin, refreshed with the other correspondences), and the residual is the difference of the two depths
along the ray, differentiable through the intersection of the ray with that triangle's plane,

    t_model = n·(a − c) / n·d,   r = (t_obs − t_model) · d_z,

(``c`` the camera centre, ``d`` the ray's unit direction, ``a`` a corner and ``n`` the normal of the triangle,
``d_z`` the ray's cosine with the optical axis, so ``r`` is a z-depth difference), in units of the σ(z, θ) of a
reading of the camera's sensor model (:func:`reading_sigma_m`; θ the angle between the triangle's normal and the
ray). Noise that scatters returns along their rays leaves this residual centred on the true surface; the
closest-point residual is not (the closest surface point of a return scattered behind a convex body lies
inside it, so that term's minimum moves inward as the noise grows). Points whose ray meets no model triangle
are left to the closest-point term.
"""

from __future__ import annotations

import numpy as np

#: The robust scale of the along-ray residual, in units of the point's σ(z, θ).
SIGMA_SCALE_K = 3.0
#: The robust scale is at least this (m): the sensor model's σ is a model, and the body model is not exact.
MIN_SCALE_M = 0.005
#: Angles between normal and ray are capped here (degrees): σ diverges at grazing.
MAX_THETA_DEG = 85.0
#: |cos| between a triangle's normal and the ray below which the intersection is held at this value.
MIN_COS = 0.1


def reading_sigma_m(sensor, depth_m: np.ndarray, theta_rad: np.ndarray) -> np.ndarray:
    """(...) float64 σ (m) of one depth reading: the sensor's axial σz(z, θ) widened by its quantisation,
    √(σz² + step²/12), the step ``depth_step_per_m · z²`` of a camera that measures disparity (0 for the others).

    Parameters
    ----------
    sensor : wbsa.sensor.technology.SensorModel
    depth_m, theta_rad : (...) float64
        z-depth (m) and angle between the surface normal and the ray (radians).
    """
    from wbsa.sensor.technology import axial_sigma_m

    z = np.asarray(depth_m, dtype=np.float64)
    step = sensor.depth_step_per_m * z * z
    return np.sqrt(axial_sigma_m(sensor, z, theta_rad) ** 2 + step**2 / 12.0)


class RayTerm:
    """Rays of the observed points and their along-ray residuals against posed bodies.

    Parameters
    ----------
    points : (p, 3) float64
        Observed points, view frame.
    camera_position : (3,) float64
        The camera centre, view frame.
    optical_axis : (3,) float64
        The camera's +z axis, view frame (unit).
    sensor : wbsa.sensor.technology.SensorModel
        The camera technology's depth noise (:func:`wbsa.sensor.technology.camera_model`).
    """

    def __init__(self, points: np.ndarray, camera_position: np.ndarray, optical_axis: np.ndarray, sensor) -> None:
        import torch

        self.torch = torch
        self.sensor = sensor
        ray = np.asarray(points, dtype=np.float64) - camera_position[None]
        t_obs = np.linalg.norm(ray, axis=1)
        self.direction_np = ray / t_obs[:, None]
        self.cos_axis_np = self.direction_np @ np.asarray(optical_axis, dtype=np.float64)
        self.z_obs_np = t_obs * self.cos_axis_np
        self.camera_np = np.asarray(camera_position, dtype=np.float64)
        f32 = torch.float32
        self.camera = torch.as_tensor(self.camera_np, dtype=f32)
        self.direction = torch.as_tensor(self.direction_np, dtype=f32)
        self.t_obs = torch.as_tensor(t_obs, dtype=f32)
        self.cos_axis = torch.as_tensor(self.cos_axis_np, dtype=f32)

    def correspondences(self, full: np.ndarray, skin_faces: np.ndarray):
        """The first skin triangle each observed point's ray meets on each whole posed body, and its σ.

        Parameters
        ----------
        full : (b, n, 3) float64
            Every vertex of every body, view frame.
        skin_faces : (m, 3) int

        Returns
        -------
        tri : (b, p, 3) int64
            Vertex indices (whole mesh) of the triangle met (any triangle where none is met).
        hit : (b, p) bool tensor
            Whether the ray met the body.
        sigma : (b, p) float32 tensor
            σ(z, θ) of each point's reading (m), z the observed depth, θ the angle of the triangle met.
        """
        import open3d as o3d

        torch = self.torch
        b, p = full.shape[0], len(self.t_obs)
        rays = np.concatenate([np.broadcast_to(self.camera_np, (p, 3)), self.direction_np], axis=1)
        rays = o3d.core.Tensor(np.ascontiguousarray(rays, dtype=np.float32))
        faces = o3d.core.Tensor(np.ascontiguousarray(skin_faces, dtype=np.uint32))
        tri = np.empty((b, p, 3), dtype=np.int64)
        hit = np.empty((b, p), dtype=bool)
        cos = np.empty((b, p), dtype=np.float64)
        for i in range(b):
            scene = o3d.t.geometry.RaycastingScene(nthreads=1)
            scene.add_triangles(o3d.core.Tensor(np.ascontiguousarray(full[i], dtype=np.float32)), faces)
            ans = scene.cast_rays(rays, nthreads=1)
            prim = ans["primitive_ids"].numpy().astype(np.int64)
            hit[i] = np.isfinite(ans["t_hit"].numpy()) & (prim >= 0) & (prim < len(skin_faces))
            tri[i] = skin_faces[np.where(hit[i], prim, 0)]
            a, e1, e2 = (full[i][tri[i][:, k]] for k in range(3))
            n = np.cross(e1 - a, e2 - a)
            n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
            cos[i] = np.abs((n * self.direction_np).sum(1))
        theta = np.minimum(np.arccos(np.clip(cos, 0.0, 1.0)), np.radians(MAX_THETA_DEG))
        sigma = reading_sigma_m(self.sensor, np.broadcast_to(self.z_obs_np, theta.shape), theta)
        return tri, torch.as_tensor(hit), torch.as_tensor(sigma, dtype=torch.float32)

    def residuals_m(self, v_all, tri):
        """(b, p) z-depth differences (m), observed minus model, along each point's ray.

        Parameters
        ----------
        v_all : (b, m, 3) float32 tensor
            Vertices, view frame.
        tri : (b, p, 3) int64 tensor
            Positions in ``v_all`` of each point's triangle.
        """
        torch = self.torch
        b, p = tri.shape[:2]
        corners = torch.gather(v_all, 1, tri.reshape(b, -1, 1).expand(-1, -1, 3)).reshape(b, p, 3, 3)
        a = corners[:, :, 0]
        n = torch.linalg.cross(corners[:, :, 1] - a, corners[:, :, 2] - a)
        n = n / n.norm(dim=-1, keepdim=True).clamp(min=1e-12)
        nd = (n * self.direction[None]).sum(-1)
        nd = torch.where(nd.abs() < MIN_COS, torch.where(nd < 0, -MIN_COS, MIN_COS), nd)
        t_model = (n * (a - self.camera)).sum(-1) / nd
        return (self.t_obs[None] - t_model) * self.cos_axis[None]

    def cost(self, v_all, tri, hit, sigma, scale_m: float, robust) -> "object":
        """(b, p) robust cost of each point's along-ray residual (0 where its ray missed the body).

        The robust scale of a point is ``max(SIGMA_SCALE_K · σ, MIN_SCALE_M)``, or ``scale_m`` while that is larger
        (the fit anneals it from coarse to fine); the cost is scaled by (scale / final scale)² so that it falls
        continuously as the scale shrinks.

        Parameters
        ----------
        v_all : (b, m, 3) float32 tensor
        tri : (b, p, 3) int64 tensor
            As for :meth:`residuals_m`.
        hit : (b, p) bool tensor
        sigma : (b, p) float32 tensor
            From :meth:`correspondences`.
        scale_m : float
            The annealed robust scale (m).
        robust : callable
            The robust penalty of squared residuals in units of the scale
            (:meth:`wbsa.estimation.methods.body_fit.objective.Objective.robust`).
        """
        torch = self.torch
        final = (SIGMA_SCALE_K * sigma).clamp(min=MIN_SCALE_M)
        scale = final.clamp(min=scale_m)
        r = self.residuals_m(v_all, tri)
        c = robust((r / scale).square()) * (scale / final).square()
        return torch.where(hit, c, torch.zeros_like(c))
