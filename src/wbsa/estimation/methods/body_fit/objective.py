"""The losses of the body fit: depth along each ray, point-to-surface, silhouette, free space, priors (torch,
batched over restarts).

Every term is a mean of robust penalties of residuals in units of a scale, so the weights compare like with like:

* **along the ray** (:mod:`wbsa.estimation.methods.body_fit.rays`, the default data term): each observed depth against
  the model surface its camera ray meets, over the sensor's σ(z, θ); points whose ray misses the body use
  the point-to-surface residual;
* **point-to-surface** (:meth:`Objective.data`): each observed point against its corresponding model vertex
  (the nearest camera-facing one, refreshed every few steps), along that vertex's normal plus a tenth of
  the tangential offset (point-to-plane ICP; the model vertices are ~3 cm apart, so point-to-point would
  not settle), under a robust penalty of scale ``robust_scale_m`` or 1.5 times the depth noise measured on
  the subject, whichever is more (Geman–McClure: a stray return costs at most 1; a scale under the noise
  would treat good returns as strays and leave the body short of them);
* **silhouette** (:meth:`Objective.silhouette`): how far each model vertex projects outside the subject's
  mask beyond a tolerance (pixels turned into metres at the vertex's depth), Huber with scale 1 cm: no body
  where the image shows none; not below the floor band, where the image cannot tell the feet from the floor
  and the mask may end above them;
* **contour** (:meth:`Objective.contour`): each outline pixel of the subject against the projection of its
  nearest model vertex on the body's outline (a vertex whose normal is near perpendicular to its viewing
  ray), beyond the silhouette tolerance, in metres at the pixel's depth, Geman–McClure with scale 1 cm: body wherever the image shows the
  subject, measured across the outline, where the image is sharper (about a pixel, 5 mm at 3.5 m) than the
  depth (2 cm of noise at 3.5 m);
* **free space** (:meth:`Objective.free_space`): a camera-facing vertex in front of the surface seen at its
  pixel by more than 1 cm plus twice the camera's face-on depth noise (:func:`wbsa.sensor.technology.envelope_m`,
  quantisation included) would hide it;
  Huber with scale 1 cm;
* **priors**: the phenotypes stay near their start (weakly), the local changes near 0.
"""

from __future__ import annotations

import numpy as np

from wbsa.estimation.methods.body_fit.observation import Observation
from wbsa.sensor.technology import envelope_m, unknown_camera_model

#: Scale (m) of the silhouette and free-space residuals; depth tolerance of the free-space term (m), to which
#: :data:`FREE_SPACE_NOISE_K` times the depth-noise envelope at the vertex's depth is added
#: (:func:`wbsa.sensor.technology.envelope_m` of the observation's sensor, in torch; 2 cm at 3.5 m for Kinect v1),
#: so that noise does not push the body back.
SURFACE_SCALE_M = 0.01
FREE_SPACE_TOLERANCE_M = 0.01
FREE_SPACE_NOISE_K = 2.0
#: The point-to-surface scale is at least this many times the depth noise measured on the subject.
NOISE_SCALE_K = 1.5
#: A model vertex is on the body's outline when the cosine between its normal and its viewing ray is below this.
OUTLINE_COS = 0.3
#: Weight of the tangential part of a point-to-vertex offset against its normal part.
TANGENTIAL_WEIGHT = 0.1


def _huber(r):
    """Huber's penalty of residuals ``r`` (≥ 0) in units of their scale: r²/2 up to 1, then r − 1/2."""
    import torch

    return torch.where(r <= 1.0, 0.5 * r * r, r - 0.5)


class Objective:
    """Losses of posed view-frame vertices against one :class:`Observation`.

    Parameters
    ----------
    obs : Observation
    robust_loss : {'geman-mcclure', 'huber'}
    robust_scale_m, silhouette_tolerance_px : float
    reading : wbsa.sensor.technology.SensorModel, optional
        The camera technology's noise model, whose σ(z, θ) weighs the along-ray residuals (the request's,
        :func:`wbsa.sensor.technology.envelope_model`; default that of a camera whose technology is unknown).
    """

    def __init__(self, obs: Observation, robust_loss: str, robust_scale_m: float, silhouette_tolerance_px: float,
                 reading=None):
        import torch

        from wbsa.estimation.methods.body_fit.rays import RayTerm
        self.torch = torch
        f32 = torch.float32
        self.obs = obs
        self.sensor = unknown_camera_model() if obs.sensor is None else obs.sensor
        self.points = torch.as_tensor(obs.points, dtype=f32)
        self.basis = torch.as_tensor(obs.basis, dtype=f32)
        self.origin = torch.as_tensor(obs.origin, dtype=f32)
        self.camera = torch.as_tensor(obs.camera_position, dtype=f32)
        self.fx, self.fy, self.cx, self.cy = (float(x) for x in obs.intrinsics)
        self.skew = obs.skew
        self.outside = torch.as_tensor(obs.outside_px)
        self.depth = torch.as_tensor(obs.depth)
        self.robust_loss = robust_loss
        self.contour_px = torch.as_tensor(obs.contour_px if obs.contour_px is not None else np.zeros((0, 2)), dtype=f32)
        self.contour_depth = torch.as_tensor(obs.contour_depth if obs.contour_depth is not None else np.zeros(0),
                                             dtype=f32)
        #: the robust scale: the settings', or 1.5 times the depth noise measured on the subject if more
        self.scale = max(float(robust_scale_m), NOISE_SCALE_K * obs.noise_m)
        self.tolerance_px = float(silhouette_tolerance_px)
        #: the along-ray term of the observed points
        self.rays = RayTerm(obs.points, obs.camera_position, obs.basis[:, 2],
                            unknown_camera_model() if reading is None else reading)

    # -- geometry ---------------------------------------------------------------------------
    def project(self, v):
        """Crop pixel coordinates (row, col) and camera z of view-frame vertices ``(b, k, 3)``.

        Parameters
        ----------
        v : (b, k, 3) float32 tensor
            Vertices, view frame, metres.

        Returns
        -------
        row, col : (b, k) float32 tensors
            Pixel coordinates in the observation's crop.
        z : (b, k) float32 tensor
            Camera depth (m), clamped to at least 5 cm.
        """
        p = v @ self.basis + self.origin
        z = p[..., 2].clamp(min=0.05)
        y = p[..., 1] / z
        col = self.fx * p[..., 0] / z + self.skew * y + self.cx - self.obs.crop[1]
        row = self.fy * y + self.cy - self.obs.crop[0]
        return row, col, z

    def _bilinear(self, image, row, col):
        """``image`` at fractional (row, col) inside it (clamped), and the distance (px) the points lay outside."""
        torch = self.torch
        h, w = image.shape
        r = row.clamp(0, h - 1.001)
        c = col.clamp(0, w - 1.001)
        beyond = (row - r).abs() + (col - c).abs()
        r0, c0 = r.floor().long(), c.floor().long()
        fr, fc = r - r0, c - c0
        flat = image.reshape(-1)
        i00 = flat[r0 * w + c0]
        i01 = flat[r0 * w + c0 + 1]
        i10 = flat[(r0 + 1) * w + c0]
        i11 = flat[(r0 + 1) * w + c0 + 1]
        top = i00 + fc * (i01 - i00)
        bottom = i10 + fc * (i11 - i10)
        return top + fr * (bottom - top), beyond

    # -- terms --------------------------------------------------------------------------------
    def robust(self, r2):
        """Robust penalty of squared residuals in units of the scale (each point's cost).

        Parameters
        ----------
        r2 : float32 tensor, any shape
            Squared residuals divided by the squared scale (dimensionless).

        Returns
        -------
        float32 tensor, shape of ``r2``
            Geman–McClure ``r2 / (1 + r2)`` (at most 1), or Huber when the objective's loss is ``'huber'``.
        """
        if self.robust_loss == "huber":
            r = r2.clamp(min=1e-12).sqrt()
            return self.torch.where(r <= 1.0, 0.5 * r2, r - 0.5)
        return r2 / (1.0 + r2)

    def surface_points(self, v_all, tri, bary):
        """The matched surface points ``(b, p, 3)`` and their unit triangle normals of vertices ``v_all (b, m, 3)``,
        triangles ``tri (b, p, 3)`` (positions in ``v_all``) and barycentric weights ``bary (b, p, 3)``.

        Parameters
        ----------
        v_all : (b, m, 3) float32 tensor
            Vertices of the selection, view frame, metres.
        tri : (b, p, 3) int64 tensor
            Each observed point's triangle (positions in ``v_all``).
        bary : (b, p, 3) float32 tensor
            Barycentric weights of each point in its triangle.

        Returns
        -------
        point : (b, p, 3) float32 tensor
            The surface points, view frame, metres.
        normal : (b, p, 3) float32 tensor
            Unit normals of their triangles.
        """
        torch = self.torch
        b, p = tri.shape[:2]
        corners = torch.gather(v_all, 1, tri.reshape(b, -1, 1).expand(-1, -1, 3)).reshape(b, p, 3, 3)
        point = (bary[..., None] * corners).sum(2)
        n = torch.linalg.cross(corners[:, :, 1] - corners[:, :, 0], corners[:, :, 2] - corners[:, :, 0])
        return point, n / n.norm(dim=-1, keepdim=True).clamp(min=1e-12)

    def data(self, v_all, tri, bary, scale_m: float | None = None):
        """(b,) mean robust point-to-surface cost of the observed points against their closest surface points.

        ``scale_m`` overrides the robust scale (the fit anneals it from coarse to fine, so that points far from
        a poor start still pull on it).

        Parameters
        ----------
        v_all : (b, m, 3) float32 tensor
            Vertices of the selection, view frame, metres.
        tri, bary : (b, p, 3) tensors
            Each point's triangle (int64, positions in ``v_all``) and float32 barycentric weights.
        scale_m : float, optional
            The robust scale, metres (default the objective's).
        """
        return self.data_points(v_all, tri, bary, scale_m).mean(1)

    def data_points(self, v_all, tri, bary, scale_m: float | None = None):
        """(b, p) robust point-to-surface cost of each observed point (see :meth:`data`).

        Parameters
        ----------
        v_all : (b, m, 3) float32 tensor
            Vertices of the selection, view frame.
        tri, bary : (b, p, 3) tensors
            Each point's triangle (positions in ``v_all``) and barycentric weights.
        scale_m : float, optional
            The robust scale (default the objective's).
        """
        point, n = self.surface_points(v_all, tri, bary)
        d = self.points[None] - point
        along = (d * n).sum(-1)
        tangential = (d * d).sum(-1) - along * along
        scale = self.scale if scale_m is None else scale_m
        r2 = (along * along + TANGENTIAL_WEIGHT * tangential) / scale**2
        return self.robust(r2)

    def residuals_m(self, v_all, tri, bary):
        """(b, p) point-to-plane distances (m) of the observed points to their closest surface points.

        Parameters
        ----------
        v_all : (b, m, 3) float32 tensor
            Vertices of the selection, view frame, metres.
        tri, bary : (b, p, 3) tensors
            Each point's triangle (int64, positions in ``v_all``) and float32 barycentric weights.
        """
        point, n = self.surface_points(v_all, tri, bary)
        return ((self.points[None] - point) * n).sum(-1)

    def silhouette(self, v):
        """(b,) mean squared distance (in units of 1 cm) by which the vertices project outside the mask; vertices
        lower than the floor band (:attr:`Observation.floor_band_m`) are not counted.

        Parameters
        ----------
        v : (b, k, 3) float32 tensor
            Vertices, view frame, metres.
        """
        row, col, z = self.project(v)
        dist_px, beyond = self._bilinear(self.outside, row, col)
        excess_px = (dist_px + beyond - self.tolerance_px).clamp(min=0.0)
        # below the floor band the mask may lack the feet (the image cannot tell them from the floor)
        excess_px = self.torch.where(v[..., 2] < self.obs.floor_band_m, 0.0, excess_px)
        metres = excess_px * z / self.fx
        return _huber(metres / SURFACE_SCALE_M).mean(1)

    def free_space(self, v, facing):
        """(b,) mean squared depth (units of 1 cm) by which camera-facing vertices ``facing (b, k)`` stand in
        front of the surface seen at their pixel, beyond :data:`FREE_SPACE_TOLERANCE_M`.

        Parameters
        ----------
        v : (b, k, 3) float32 tensor
            Vertices, view frame, metres.
        facing : (b, k) bool tensor
            Vertices facing the camera (the only ones the term counts).
        """
        torch = self.torch
        row, col, z = self.project(v)
        h, w = self.depth.shape
        r = row.detach().round().long().clamp(0, h - 1)
        c = col.detach().round().long().clamp(0, w - 1)
        seen = self.depth[r, c]
        ok = facing & torch.isfinite(seen)
        noise = envelope_m(self.sensor, z.detach())
        tol = FREE_SPACE_TOLERANCE_M + FREE_SPACE_NOISE_K * noise
        ahead = torch.where(ok, (seen - z - tol).clamp(min=0.0), torch.zeros_like(z))
        return _huber(ahead / SURFACE_SCALE_M).sum(1) / facing.sum(1).clamp(min=1)

    def contour(self, v, corr):
        """(b,) mean robust distance (scale 1 cm) of the outline pixels to their outline vertices ``corr (b, c)``,
        beyond the silhouette tolerance (sensors drop the grazing returns at the outline: the outline seen lies
        about a pixel inside the body's).

        Parameters
        ----------
        v : (b, k, 3) float32 tensor
            Vertices, view frame, metres.
        corr : (b, c) int64 tensor or None
            Position in ``v`` of each outline pixel's vertex (:meth:`contour_correspondences`); None or c = 0:
            zeros.
        """
        torch = self.torch
        if corr is None or corr.shape[1] == 0:
            return torch.zeros(v.shape[0])
        row, col, _ = self.project(v)
        idx = corr
        dr = torch.gather(row, 1, idx) - self.contour_px[None, :, 0]
        dc = torch.gather(col, 1, idx) - self.contour_px[None, :, 1]
        px = ((dr.square() + dc.square() + 1e-9).sqrt() - self.tolerance_px).clamp(min=0.0)
        metres = px * self.contour_depth[None] / self.fx
        r2 = (metres / SURFACE_SCALE_M).square()
        return (r2 / (1.0 + r2)).mean(1)

    def contour_correspondences(self, v: np.ndarray, normals: np.ndarray):
        """Nearest outline vertex (in the image) of every outline pixel, per restart: ``(b, c)`` int64 tensor.

        A vertex is on the outline when the cosine between its normal and its viewing ray is below
        :data:`OUTLINE_COS`; with fewer than 10 such vertices in a restart, every vertex is a candidate.

        Parameters
        ----------
        v : (b, k, 3) float64
            Vertices, view frame, metres.
        normals : (b, k, 3) float64
            Their unit normals.

        Returns
        -------
        (b, c) int64 tensor or None
            Position in ``v`` of each outline pixel's vertex; None when the observation has no outline pixels.
        """
        from scipy.spatial import cKDTree

        torch = self.torch
        if self.contour_px.shape[0] == 0:
            return None
        with torch.no_grad():
            row, col, _ = self.project(torch.as_tensor(v, dtype=torch.float32))
        ray = v - self.obs.camera_position[None, None]
        ray /= np.linalg.norm(ray, axis=-1, keepdims=True)
        grazing = np.abs((ray * normals).sum(-1)) < OUTLINE_COS
        corr = np.empty((v.shape[0], self.contour_px.shape[0]), dtype=np.int64)
        pix = self.contour_px.numpy()
        for b in range(v.shape[0]):
            ids = np.flatnonzero(grazing[b])
            if len(ids) < 10:
                ids = np.arange(v.shape[1])
            _, nearest = cKDTree(np.stack([row[b, ids].numpy(), col[b, ids].numpy()], 1)).query(pix, workers=1)
            corr[b] = ids[nearest]
        return torch.as_tensor(corr)

    # -- correspondences ------------------------------------------------------------------------
    def correspondences(self, full: np.ndarray, skin_faces: np.ndarray, closed_faces: np.ndarray,
                        subset: np.ndarray):
        """Closest camera-facing skin point of every observed point on each whole posed body, and the subset's normals.

        Parameters
        ----------
        full : (b, n, 3) float64
            Every vertex of every body, view frame (:meth:`wbsa.estimation.methods.body_fit.model.FitBody.full_posed`).
        skin_faces, closed_faces : (m, 3) int
        subset : (k,) int
            The vertices the fit moves at every step.

        Returns
        -------
        tri : (b, p, 3) int64
            Vertex indices (whole mesh) of each point's triangle.
        bary : (b, p, 3) float32 tensor
            Its barycentric weights.
        normals : (b, k, 3) float64
            Unit normals of the subset vertices.
        facing : (b, k) bool tensor
            Subset vertices facing the camera.
        """
        import open3d as o3d

        from wbsa.estimation.methods.body_fit.model import vertex_normals

        torch = self.torch
        cam = self.obs.camera_position
        normals = vertex_normals(full, closed_faces)[:, subset]
        facing = ((cam[None, None] - full[:, subset]) * normals).sum(-1) > 0
        pts = o3d.core.Tensor(np.ascontiguousarray(self.obs.points, dtype=np.float32))
        tri = np.empty((full.shape[0], len(self.obs.points), 3), dtype=np.int64)
        bary = np.empty((full.shape[0], len(self.obs.points), 3), dtype=np.float32)
        for b in range(full.shape[0]):
            a, e1, e2 = (full[b, skin_faces[:, i]] for i in range(3))
            face_n = np.cross(e1 - a, e2 - a)
            faces = skin_faces[((cam - (a + e1 + e2) / 3.0) * face_n).sum(1) > 0]
            if len(faces) < 100:
                faces = skin_faces
            scene = o3d.t.geometry.RaycastingScene(nthreads=1)
            scene.add_triangles(o3d.core.Tensor(np.ascontiguousarray(full[b], dtype=np.float32)),
                                o3d.core.Tensor(np.ascontiguousarray(faces, dtype=np.uint32)))
            hit = scene.compute_closest_points(pts, nthreads=1)
            tri[b] = faces[hit["primitive_ids"].numpy().astype(np.int64)]
            uv = hit["primitive_uvs"].numpy()
            bary[b] = np.stack([1.0 - uv[:, 0] - uv[:, 1], uv[:, 0], uv[:, 1]], axis=1)
        return tri, torch.as_tensor(bary), normals, torch.as_tensor(facing)
