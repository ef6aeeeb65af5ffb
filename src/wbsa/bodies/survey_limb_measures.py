"""The NHANES limb measures of anny bodies in torch, batched, with exact coefficient gradients.

Arm circumference (BMXARMC), upper arm length (BMXARML) and upper leg length (BMXLEG), defined
as :class:`~wbsa.bodies.anthropometry.Anthropometer` defines them (its module docstring: landmarks
from the NHANES Anthropometry Procedures Manual), so a fitted body measures back to the same
numbers in the population table. They touch a few hundred vertices (the right upper arm and four
landmarks) and two joints, so the values are computed with autograd on those alone and the
gradients projected on the blendshape basis with one small dense product per part.

The arm section's hull combinatorics (which edge crossings lie on the hull, in which order) come
from scipy; the perimeter is then a sum of segment lengths in torch, differentiable almost
everywhere, as for the trunk girths (:mod:`~wbsa.bodies.survey_measures`).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from wbsa.bodies.anthropometry import ARM_SECTION_RADIUS, Anthropometer, nhanes_arm
from wbsa.bodies.body_model import BodyModel

#: The measures of :meth:`TorchLimbMeasurer.evaluate`, in column order.
LIMB_MEASURES = ("mid_arm_circ_m", "upper_arm_length_m", "upper_leg_length_m")


class TorchLimbMeasurer:
    """:data:`LIMB_MEASURES` of a batch of bodies and their blendshape-coefficient gradients.

    Parameters
    ----------
    model
        The body model (its torch anny model is used directly).
    meter
        The exact measurer whose landmarks are reproduced.
    """

    def __init__(self, model: BodyModel, meter: Anthropometer):
        import torch

        self.torch = torch
        lm = meter.landmarks
        anny = model.anny
        n = anny.template_vertices.shape[0]
        arm = lm.right_upper_arm_edges
        #: model vertex ids of the part: the four landmarks, then the right upper arm's vertices
        ids = np.concatenate([[lm.acromion, lm.olecranon, lm.inguinal, lm.patella], arm.vertex_ids])
        self.ids = torch.as_tensor(ids, dtype=torch.long)
        self.edge_a = torch.as_tensor(arm.edges[:, 0] + 4, dtype=torch.long)
        self.edge_b = torch.as_tensor(arm.edges[:, 1] + 4, dtype=torch.long)
        k = anny.blendshapes.shape[0]
        basis_t = anny.blendshapes.detach().permute(2, 1, 0).reshape(-1, k)
        #: (3, p, k) blendshape rows of the part's vertices
        self.part_basis = torch.stack([basis_t[c * n + self.ids] for c in range(3)])
        joints = [lm.right_shoulder, lm.right_elbow]
        self.joint_template = anny.template_bone_heads.detach()[joints]  # (2, 3)
        self.joint_basis = anny.bone_heads_blendshapes.detach()[:, joints]  # (k, 2, 3)

    def evaluate(self, x, coefficients, gradient: bool = False):
        """Measures ``(b, 3)`` and, if asked, gradients ``(b, 3, k)`` (else None).

        Parameters
        ----------
        x : (3, n, b) float64 tensor
            Rest vertices, coordinate-major (as :meth:`TorchMeasurer.vertices` gives them).
        coefficients : (b, k) float64 tensor
            The bodies' blendshape coefficients (for the joints).
        """
        torch = self.torch
        b = x.shape[2]
        with torch.no_grad():
            joints = self.joint_template[None] + torch.einsum("kjc,bk->bjc", self.joint_basis, coefficients)
        part = x[:, self.ids, :].permute(2, 1, 0).clone().requires_grad_(gradient)  # (b, p, 3)
        joints = joints.clone().requires_grad_(gradient)
        with torch.set_grad_enabled(gradient):
            acromion, olecranon, inguinal, patella = (part[:, i] for i in range(4))
            tip, axis = nhanes_arm(olecranon, joints[:, 0], joints[:, 1])
            arm_length = ((tip - acromion) ** 2).sum(dim=1).sqrt()
            leg_length = ((patella - inguinal) ** 2).sum(dim=1).sqrt()
            mid = 0.5 * (acromion + tip)
            girth, valid = self._arm_girth(part, mid, axis, arm_length)
            values = torch.stack([girth, arm_length, leg_length], dim=1)
        out = values.detach().clone()
        out[:, 0] = torch.where(valid, out[:, 0], torch.full_like(out[:, 0], float("nan")))
        if not gradient:
            return out, None
        k = self.part_basis.shape[2]
        grad = torch.zeros((b, 3, k), dtype=x.dtype)
        for j in range(3):
            gp, gj = torch.autograd.grad(values[:, j].sum(), (part, joints), retain_graph=j < 2, allow_unused=True)
            g = torch.zeros((b, k), dtype=x.dtype)
            if gp is not None:
                g += torch.einsum("bpc,cpk->bk", gp, self.part_basis)
            if gj is not None:
                g += torch.einsum("bjc,kjc->bk", gj, self.joint_basis)
            grad[:, j] = g
        grad[:, 0] = torch.where(valid[:, None], grad[:, 0], torch.zeros_like(grad[:, 0]))
        return out, grad

    def _arm_girth(self, part, mid, axis, arm_length):
        """Convex-hull perimeter ``(b,)`` of the arm edges' crossings with the mid-arm plane, and validity ``(b,)``."""
        torch = self.torch
        with torch.no_grad():
            index, valid = self._hull_plan(part.detach(), mid.detach(), axis.detach(), arm_length.detach())
        body = torch.arange(part.shape[0])[:, None]
        pa = part[body, self.edge_a[index]]  # (b, h, 3)
        pb = part[body, self.edge_b[index]]
        da = ((pa - mid[:, None]) * axis[:, None]).sum(dim=2)
        db = ((pb - mid[:, None]) * axis[:, None]).sum(dim=2)
        denom = da - db
        t = da / torch.where(denom == 0, torch.ones_like(denom), denom)
        pts = pa + t[..., None] * (pb - pa)
        seg = torch.roll(pts, -1, dims=1) - pts
        sq = (seg**2).sum(dim=2)
        nonzero = sq > 0
        safe = torch.where(nonzero, sq, torch.ones_like(sq))
        return torch.where(nonzero, torch.sqrt(safe), torch.zeros_like(sq)).sum(dim=1), valid

    def _hull_plan(self, part, mid, axis, arm_length):
        """Edge indices ``(b, h)`` of each arm section's convex hull, in order (rows padded by repetition)."""
        torch = self.torch
        da = ((part[:, self.edge_a] - mid[:, None]) * axis[:, None]).sum(dim=2)  # (b, e)
        db = ((part[:, self.edge_b] - mid[:, None]) * axis[:, None]).sum(dim=2)
        cross = (da < 0) != (db < 0)
        rows, valid = [], []
        for i in range(part.shape[0]):
            e = torch.nonzero(cross[i]).flatten()
            a, bb = part[i, self.edge_a[e]], part[i, self.edge_b[e]]
            t = (da[i, e] / (da[i, e] - db[i, e]))[:, None]
            pts = (a + t * (bb - a)).numpy()
            near = np.linalg.norm(pts - mid[i].numpy(), axis=1) < ARM_SECTION_RADIUS * float(arm_length[i])
            e, pts = e.numpy()[near], pts[near]
            order = None
            if len(e) >= 3:
                n = axis[i].numpy()
                helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
                u = np.cross(n, helper)
                u /= np.linalg.norm(u)
                w = np.cross(n, u)
                try:
                    order = e[ConvexHull(np.stack([pts @ u, pts @ w], axis=1)).vertices]
                except QhullError:
                    order = None
            valid.append(order is not None)
            rows.append(order if order is not None else np.zeros(1, dtype=np.int64))
        if not rows:
            return torch.zeros((0, 1), dtype=torch.long), torch.zeros(0, dtype=torch.bool)
        width = max(len(r) for r in rows)
        index = np.stack([np.concatenate([r, np.full(width - len(r), r[-1])]) for r in rows])
        return torch.as_tensor(index, dtype=torch.long), torch.as_tensor(valid, dtype=torch.bool)
