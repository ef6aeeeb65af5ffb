"""A differentiable anny body on a subset of its vertices, posed as :mod:`wbsa.bodies.posing` poses it.

:class:`FitBody` is what the optimiser moves: phenotypes and local changes give the rest vertices through
anny's linear blendshapes (:meth:`wbsa.bodies.body_model.BodyModel.coefficients`), restricted to a few
thousand skin vertices spread evenly over the body (anny's 318 blendshapes over all 13,718 vertices are
105 MB of float64 read at every step; the subset is a few MB of float32); the ten posture angles of
:data:`wbsa.bodies.posture.ANGLE_COLUMNS` pose them by linear blend skinning with anny's weights, exactly
as :func:`wbsa.bodies.posing.pose_vertices` does (the same pivots, axes and composition; tested against
it), and the body is shifted to stand on z = 0. All in torch, batched over restarts. A :class:`Selection`
adds any other vertices (the fit adds those of the triangles its observed points lie on).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wbsa.bodies.body_model import LOCAL_CHANGE_COLUMNS, PHENOTYPE_COLUMNS, BodyModel
from wbsa.bodies.posing import SEGMENTS

#: Number of phenotypes and of local changes a fit moves.
N_PHENOTYPES = len(PHENOTYPE_COLUMNS)
N_LOCAL = len(LOCAL_CHANGE_COLUMNS)
#: Joints whose heads :class:`FitBody` needs, per side, in this order.
_JOINTS = ("shoulder", "elbow", "wrist", "hip", "ankle")


def even_vertex_subset(vertices: np.ndarray, faces: np.ndarray, spacing_m: float) -> np.ndarray:
    """Indices of the skin vertices nearest to the centres of a ``spacing_m`` voxel grid, plus the soles and crown.

    Parameters
    ----------
    vertices : (n, 3) float64
        A reference body at rest, standing on z = 0.
    faces : (m, 3) int
        Its skin triangles (only their vertices are chosen).
    spacing_m : float

    Returns
    -------
    (k,) intp, sorted
        One vertex per occupied voxel; every vertex within 1 cm of the floor or of the top of the head is
        added, so the lowest and highest points of any posed body are in the subset.
    """
    used = np.unique(np.asarray(faces).ravel())
    p = vertices[used]
    cell = np.floor(p / spacing_m).astype(np.int64)
    centre = (cell + 0.5) * spacing_m
    dist = np.linalg.norm(p - centre, axis=1)
    order = np.lexsort((dist, cell[:, 2], cell[:, 1], cell[:, 0]))
    key = cell[order]
    first = np.ones(len(order), dtype=bool)
    first[1:] = np.any(key[1:] != key[:-1], axis=1)
    chosen = used[order[first]]
    z = vertices[used, 2]
    extremes = used[(z < z.min() + 0.01) | (z > z.max() - 0.01)]
    return np.unique(np.concatenate([chosen, extremes])).astype(np.intp)


class FitBody:
    """anny's rest shape and the project's posing, differentiable, on a vertex subset.

    Parameters
    ----------
    body_model : BodyModel
    spacing_m : float
        Voxel size of :func:`even_vertex_subset` (0.035 m gives about 2,300 vertices).
    """

    def __init__(self, body_model: BodyModel, spacing_m: float = 0.03) -> None:
        import torch

        from wbsa.bodies.anthropometry import reference_adult

        self.torch = torch
        self.body_model = body_model
        anny = body_model.anny
        ref = body_model.rest_bodies(reference_adult(0.0)).vertices[0]
        self.index = even_vertex_subset(ref, body_model.skin_faces, spacing_m)
        self.template_full = anny.template_vertices.to(torch.float32)
        self.basis_full = anny.blendshapes.to(torch.float32)  # (c, n, 3)
        rig = body_model.rig
        joint_ids = [rig.joints[s][j] for s in ("l", "r") for j in _JOINTS]
        self.joint_template = anny.template_bone_heads[joint_ids].to(torch.float32)
        self.joint_basis = anny.bone_heads_blendshapes[:, joint_ids, :].to(torch.float32).reshape(
            anny.bone_heads_blendshapes.shape[0], -1)
        dense = np.zeros((len(body_model.vertex_bone), 2 * len(SEGMENTS)))
        for s, (rows, w) in enumerate(zip(rig.skin.rows, rig.skin.weights)):
            dense[rig.skin.vertices[rows], s] = w
        self.weights_full = torch.as_tensor(dense, dtype=torch.float32)
        #: the vertex subset every step moves
        self.subset = self.select(self.index)

    def select(self, index: np.ndarray) -> "Selection":
        """The blendshapes and skinning weights of the vertices ``index (m,)``.

        Parameters
        ----------
        index : (m,) int
            Vertex indices of anny's mesh.
        """
        idx = self.torch.as_tensor(np.asarray(index, dtype=np.int64))
        return Selection(np.asarray(index), self.template_full[idx],
                         self.basis_full[:, idx, :].reshape(self.basis_full.shape[0], -1), self.weights_full[idx])

    def __len__(self) -> int:
        return len(self.index)

    def full_posed(self, params, angles_rad: np.ndarray, yaw_rad: np.ndarray, shift_m: np.ndarray) -> np.ndarray:
        """(b, n, 3) float64 every vertex of every body, posed (:func:`wbsa.bodies.posing.pose_vertices`) and placed
        (turned by ``yaw_rad (b,)``, shifted by ``shift_m (b, 3)``); no gradient.

        Parameters
        ----------
        params : (b, 15) float64
            Body parameters.
        angles_rad : (b, 10) float64
            Posture angles.
        yaw_rad : (b,) float64
        shift_m : (b, 3) float64
        """
        import anny.skinning.skinning as skinning

        from wbsa.bodies.posing import pose_vertices

        torch = self.torch
        model = self.body_model
        with torch.no_grad():
            coeffs = model.coefficients(params.detach().to(torch.float64))
            rest = model.anny.get_rest_vertices(coeffs).numpy()
            heads = skinning.apply_linear_blendshape(model.anny.template_bone_heads, model.anny.bone_heads_blendshapes,
                                                     coeffs).numpy()
        out = np.empty_like(rest)
        for b in range(len(rest)):
            posed = pose_vertices(rest[b], heads[b], np.degrees(angles_rad[b]), model.rig)
            c, s = np.cos(yaw_rad[b]), np.sin(yaw_rad[b])
            rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
            out[b] = posed @ rz.T + shift_m[b]
        return out

    def rest(self, params, selection: "Selection | None" = None):
        """Rest vertices ``(b, m, 3)`` of a selection (default the subset) and joints ``(b, 10, 3)`` (float32) of
        ``(b, 15)`` float64 body parameters.

        Parameters
        ----------
        params : (b, 15) torch tensor
            Body parameters.
        selection : Selection or None
            The vertices (default the subset).
        """
        sel = self.subset if selection is None else selection
        coeffs = self.body_model.coefficients(params).to(self.torch.float32)
        b = coeffs.shape[0]
        v = sel.template[None] + (coeffs @ sel.basis).reshape(b, -1, 3)
        j = self.joint_template[None] + (coeffs @ self.joint_basis).reshape(b, -1, 3)
        return v, j

    def segment_transforms(self, joints, angles_rad):
        """Every segment's rigid transform, ``R (b, s, 3, 3)`` and ``t (b, s, 3)``.

        Segments in :data:`~wbsa.bodies.posing.SEGMENTS` order, left side then right. Mirrors
        :func:`wbsa.bodies.posing.segment_transforms` (tested against it), with both sides and all seven
        rotations of a side in one batched Rodrigues call (the cost of a step is the number of operations).

        Parameters
        ----------
        joints : (b, 10, 3) torch tensor
        angles_rad : (b, 10) torch tensor
            Posture angles.
        """
        torch = self.torch
        b = joints.shape[0]
        a = angles_rad.to(torch.float32).reshape(2 * b, 5)  # (body, side) pairs
        jt = joints.reshape(2 * b, 5, 3)
        shoulder, elbow_j, wrist, hip_j, ankle = (jt[:, k] for k in range(5))
        sign = torch.tensor([1.0, -1.0]).repeat(b)
        abd, flex, rot, elbow, hip = (a[:, m] for m in range(5))
        upper, fore = elbow_j - shoulder, wrist - elbow_j
        zero = torch.zeros_like(sign)
        fwd = torch.stack([zero, -sign, zero], dim=1)
        back = torch.tensor([-1.0, 0.0, 0.0]).expand(2 * b, 3)
        twist = sign[:, None] * unit(upper)
        hinge = unit(torch.linalg.cross(upper, fore))
        axes = torch.cat([fwd, back, twist, twist, hinge, fwd, fwd])
        angles = torch.cat([abd, flex, rot / 2, rot, elbow, hip, -hip])
        r_abd, r_flex, r_tw1, r_tw2, r_elbow, r_hip, r_foot = rotation(axes, angles).reshape(7, 2 * b, 3, 3)
        base = r_abd @ r_flex
        ua1 = about(shoulder, base @ r_tw1)
        ua2 = about(shoulder, base @ r_tw2)
        forearm = then(ua2, about(elbow_j, r_elbow))
        leg = about(hip_j, r_hip)
        foot = then(leg, about(ankle, r_foot))
        segs = (ua1, ua2, forearm, leg, foot)
        r = torch.stack([s[0] for s in segs], dim=1).reshape(b, 2 * len(segs), 3, 3)
        t = torch.stack([s[1] for s in segs], dim=1).reshape(b, 2 * len(segs), 3)
        return r, t

    def pose(self, rest, joints, angles_rad, rotations: bool = False, selection: "Selection | None" = None):
        """Posed vertices ``(b, k, 3)`` standing on z = 0 (and, with ``rotations``, each vertex's blended
        rotation ``(b, k, 3, 3)``, for its normal).

        Dense linear blend skinning: every segment's transform is applied to every vertex and blended by the
        (mostly zero) weights; at a few thousand vertices this beats gathering the moving ones.

        Parameters
        ----------
        rest : (b, k, 3) torch tensor
            Rest vertices of the selection (:meth:`rest`).
        joints : (b, 10, 3) torch tensor
        angles_rad : (b, 10) torch tensor
            Posture angles.
        rotations : bool
            Also return each vertex's blended rotation.
        selection : Selection or None
            The vertices (default the subset).
        """
        torch = self.torch
        r, t = self.segment_transforms(joints, angles_rad)  # (b, s, 3, 3), (b, s, 3)
        weights = (self.subset if selection is None else selection).weights
        moved = torch.einsum("bsij,bkj->bski", r, rest) + t[:, :, None] - rest[:, None]
        posed = rest + torch.einsum("ks,bski->bki", weights, moved)
        lowest = posed[..., 2].min(dim=1).values
        posed = posed - torch.stack([torch.zeros_like(lowest), torch.zeros_like(lowest), lowest], dim=1)[:, None]
        if not rotations:
            return posed
        blend = torch.eye(3) + torch.einsum("ks,bsij->bkij", weights, r - torch.eye(3))
        return posed, blend


@dataclass(frozen=True)
class Selection:
    """Some vertices of anny's mesh, ready for :meth:`FitBody.rest` and :meth:`FitBody.pose`.

    Attributes
    ----------
    index : (m,) int
    template : (m, 3) float32 tensor
    basis : (c, 3 m) float32 tensor
    weights : (m, s) float32 tensor
        Skinning weights on the posed segments.
    """

    index: np.ndarray
    template: object
    basis: object
    weights: object


def rotation(axis, angle):
    """Rodrigues: ``(b, 3, 3)`` rotations by ``angle (b,)`` about unit ``axis (b, 3)`` (right-hand rule).

    Parameters
    ----------
    axis : (b, 3) torch tensor
        Unit axes.
    angle : (b,) torch tensor
        Radians.
    """
    import torch

    x, y, z = axis[:, 0], axis[:, 1], axis[:, 2]
    zero = torch.zeros_like(x)
    k = torch.stack([zero, -z, y, z, zero, -x, -y, x, zero], dim=1).reshape(-1, 3, 3)
    s, c = torch.sin(angle)[:, None, None], torch.cos(angle)[:, None, None]
    return torch.eye(3, dtype=k.dtype) + s * k + (1.0 - c) * (k @ k)


def unit(v):
    """``v`` over its length along the last axis (torch).

    Parameters
    ----------
    v : (..., 3) torch tensor
    """
    return v / v.norm(dim=-1, keepdim=True)


def about(pivot, rot):
    """``x -> rot x + t`` turning by ``rot (b, 3, 3)`` about ``pivot (b, 3)``.

    Parameters
    ----------
    pivot : (b, 3) torch tensor
    rot : (b, 3, 3) torch tensor
    """
    return rot, pivot - (rot @ pivot[..., None])[..., 0]


def then(outer, inner):
    """``outer ∘ inner`` (inner first).

    Parameters
    ----------
    outer, inner : (R (b, 3, 3), t (b, 3))
        Rigid transforms.
    """
    return outer[0] @ inner[0], (outer[0] @ inner[1][..., None])[..., 0] + outer[1]


def yaw_matrix(yaw):
    """``(b, 3, 3)`` rotations about +Z by ``yaw (b,)`` radians.

    Parameters
    ----------
    yaw : (b,) torch tensor
        Radians.
    """
    import torch

    c, s = torch.cos(yaw), torch.sin(yaw)
    zero, one = torch.zeros_like(c), torch.ones_like(c)
    return torch.stack([c, -s, zero, s, c, zero, zero, zero, one], dim=1).reshape(-1, 3, 3)


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(b, n, 3) unit area-weighted vertex normals of ``(b, n, 3)`` vertices over ``(m, 3)`` faces.

    Parameters
    ----------
    vertices : (b, n, 3) float64
    faces : (m, 3) int
    """
    a, b, c = (vertices[:, faces[:, i]] for i in range(3))
    face_n = np.cross(b - a, c - a)
    out = np.zeros_like(vertices)
    for i in range(3):
        for d in range(3):
            out[:, :, d] += np.stack([np.bincount(faces[:, i], weights=fn[:, d], minlength=vertices.shape[1])
                                      for fn in face_n])
    return out / np.maximum(np.linalg.norm(out, axis=-1, keepdims=True), 1e-12)


def subset_rest_normals(fit_body: FitBody, params) -> np.ndarray:
    """(b, k, 3) rest-pose unit normals of the subset vertices of ``(b, 15)`` body parameters (whole mesh, no grad).

    Parameters
    ----------
    fit_body : FitBody
    params : (b, 15) float64
        Body parameters.
    """
    import torch

    model = fit_body.body_model
    with torch.no_grad():
        full = model.anny.get_rest_vertices(model.coefficients(params.detach().to(torch.float64))).numpy()
    return vertex_normals(full, model.closed_faces)[:, fit_body.index]
