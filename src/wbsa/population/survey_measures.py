"""Stature, mass, waist and hip of anny bodies in torch, batched and differentiable.

The survey matcher fits phenotype parameters by Gauss–Newton steps, which need these four
measures *and* their derivatives for hundreds of bodies at once. The definitions are the
same as :class:`~wbsa.population.anthropometry.Anthropometer`'s, so a fitted body is measured
back to the same numbers by the population table:

* stature = max z − min z over all vertices;
* mass = volume of the closed shell (divergence theorem) × density;
* waist, hip = perimeter of the convex hull of the trunk edges' crossings with the horizontal
  plane at the mean height of anny's waist ring (waist) or at the hip landmark vertex (hip).

The convex hull's *combinatorics* (which crossing points lie on the hull, in which order) is
found with scipy on detached values; the hull perimeter is then a sum of segment lengths in
torch, so it is exact and differentiable almost everywhere (the hull vertices are
interpolated edge crossings, which move smoothly with the vertices and the plane height).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from wbsa.population.anthropometry import Anthropometer
from wbsa.population.body_model import BodyModel

#: The measures this module computes, in column order of :meth:`TorchMeasurer.measures`.
FIT_MEASURES = ("stature_m", "mass_kg", "waist_circ_m", "hip_circ_m")


@dataclass(frozen=True)
class HullPlan:
    """Which trunk edges make each body's tape polygon, in hull order.

    Attributes
    ----------
    edge_index : (b, h) int64 tensor
        Trunk-edge indices of the hull points, counter-clockwise; rows shorter than ``h``
        repeat their last entry (a zero-length segment).
    valid : (b,) bool tensor
        False where the section has fewer than three points or a degenerate hull.
    """

    edge_index: object
    valid: object


class TorchMeasurer:
    """Differentiable fit measures of a :class:`BodyModel`'s bodies.

    Parameters
    ----------
    model
        The body model (its torch anny model is used directly).
    meter
        The exact measurer whose landmarks and density are reproduced.
    """

    def __init__(self, model: BodyModel, meter: Anthropometer):
        import torch

        self.torch = torch
        self.model = model
        anny = model.anny
        self.dtype = anny.dtype
        self.density_kg_m3 = meter.density_kg_m3
        lm = meter.landmarks
        n_blend = anny.blendshapes.shape[0]
        #: (k, 3n) blendshape basis; vertices = template + coefficients @ basis
        self.basis = anny.blendshapes.detach().reshape(n_blend, -1)
        self.template = anny.template_vertices.detach()
        self.closed_faces = torch.as_tensor(model.closed_faces, dtype=torch.long)
        ids = np.asarray(lm.trunk_edges.vertex_ids)
        self.edge_a = torch.as_tensor(ids[lm.trunk_edges.edges[:, 0]], dtype=torch.long)
        self.edge_b = torch.as_tensor(ids[lm.trunk_edges.edges[:, 1]], dtype=torch.long)
        self.waist_ring = torch.as_tensor(np.asarray(lm.waist_ring), dtype=torch.long)
        self.hip_vertex = int(lm.hip)
        self._empty = None

    # -- body model ---------------------------------------------------------------------
    def coefficients(self, phenotypes):
        """Blendshape coefficients ``(b, k)`` of phenotypes ``(b, 11)`` (differentiable)."""
        torch = self.torch
        empty = torch.empty((phenotypes.shape[0], 0), dtype=self.dtype)
        return self.model.anny._get_phenotype_blendshape_coefficients(phenotypes, empty, empty)

    def vertices(self, coefficients):
        """Rest vertices ``(b, n, 3)`` for coefficients ``(b, k)`` (anny's frame, not floor-shifted)."""
        flat = coefficients @ self.basis
        return self.template[None] + flat.reshape(len(coefficients), -1, 3)

    # -- measures -----------------------------------------------------------------------
    def plan(self, vertices) -> tuple[HullPlan, HullPlan]:
        """Hull combinatorics of the waist and hip sections of ``vertices`` (b, n, 3)."""
        with self.torch.no_grad():
            v = vertices.detach()
            return self._plan(v, self._waist_z(v)), self._plan(v, v[:, self.hip_vertex, 2])

    def measures(self, vertices, plans: tuple[HullPlan, HullPlan] | None = None):
        """Stature (m), mass (kg), waist and hip girths (m) of every body, ``(b, 4)``.

        Parameters
        ----------
        vertices : (b, n, 3) float64 tensor
            Rest vertices (may require grad).
        plans
            Hull combinatorics from :meth:`plan`; computed here when omitted.

        Returns
        -------
        (b, 4) tensor
            Columns :data:`FIT_MEASURES`; a girth is NaN where its section is degenerate.
        """
        torch = self.torch
        waist_plan, hip_plan = plans if plans is not None else self.plan(vertices)
        z = vertices[..., 2]
        stature = z.max(dim=1).values - z.min(dim=1).values
        f = self.closed_faces
        a, b, c = vertices[:, f[:, 0]], vertices[:, f[:, 1]], vertices[:, f[:, 2]]
        volume = (a * torch.linalg.cross(b, c, dim=-1)).sum(dim=(1, 2)).abs() / 6.0
        mass = volume * self.density_kg_m3
        waist = self._girth(vertices, self._waist_z(vertices), waist_plan)
        hip = self._girth(vertices, vertices[:, self.hip_vertex, 2], hip_plan)
        return torch.stack([stature, mass, waist, hip], dim=1)

    def _waist_z(self, vertices):
        return vertices[:, self.waist_ring, 2].mean(dim=1)

    def _crossings(self, vertices, plane_z, edges):
        """Crossing points ``(b, e, 2)`` of trunk edges ``edges`` (b, e) with the planes ``plane_z`` (b,)."""
        torch = self.torch
        rows = torch.arange(len(vertices))[:, None]
        va = vertices[rows, self.edge_a[edges]]
        vb = vertices[rows, self.edge_b[edges]]
        da = va[..., 2] - plane_z[:, None]
        db = vb[..., 2] - plane_z[:, None]
        denom = da - db
        t = da / torch.where(denom == 0, torch.ones_like(denom), denom)
        return va[..., :2] + t[..., None] * (vb[..., :2] - va[..., :2])

    def _plan(self, vertices, plane_z) -> HullPlan:
        torch = self.torch
        da = vertices[:, self.edge_a, 2] - plane_z[:, None]
        db = vertices[:, self.edge_b, 2] - plane_z[:, None]
        cross = (da < 0) != (db < 0)
        rows = []
        valid = []
        for i in range(len(vertices)):
            idx = torch.nonzero(cross[i]).flatten()
            hull = None
            if len(idx) >= 3:
                pts = self._crossings(vertices[i:i + 1], plane_z[i:i + 1], idx[None])[0].numpy()
                try:
                    hull = idx[torch.as_tensor(ConvexHull(pts).vertices, dtype=torch.long)]
                except QhullError:
                    hull = None
            valid.append(hull is not None)
            rows.append(hull if hull is not None else torch.zeros(1, dtype=torch.long))
        width = max(len(r) for r in rows) if rows else 1
        index = torch.stack([torch.cat([r, r[-1:].expand(width - len(r))]) for r in rows]) if rows \
            else torch.zeros((0, 1), dtype=torch.long)
        return HullPlan(index, torch.as_tensor(valid, dtype=torch.bool))

    def _girth(self, vertices, plane_z, plan: HullPlan):
        torch = self.torch
        pts = self._crossings(vertices, plane_z, plan.edge_index)
        seg = torch.roll(pts, -1, dims=1) - pts
        sq = (seg**2).sum(dim=-1)
        nonzero = sq > 0
        length = torch.where(nonzero, torch.sqrt(torch.where(nonzero, sq, torch.ones_like(sq))), torch.zeros_like(sq))
        perimeter = length.sum(dim=1)
        return torch.where(plan.valid, perimeter, torch.full_like(perimeter, float("nan")))
