"""Stature, mass, waist, hip (and the NHANES limb measures) of anny bodies in torch, batched, with exact derivatives.

The survey matcher fits phenotype parameters by Gauss–Newton steps, which need these four
measures *and* their derivatives for hundreds of bodies at once (seven with the NHANES limb
measures of :mod:`~wbsa.bodies.survey_limb_measures`). The definitions are the
same as :class:`~wbsa.bodies.anthropometry.Anthropometer`'s, so a fitted body measures
back to the same numbers in the population table:

* stature = max z − min z over all vertices;
* mass = volume of the closed shell (divergence theorem) × density;
* waist, hip = perimeter of the convex hull of the trunk edges' crossings with the horizontal
  plane at the mean height of anny's waist ring (waist) or at the hip landmark vertex (hip).

The convex hull's *combinatorics* (which crossing points lie on the hull, in which order) is
found with scipy; the perimeter is then a sum of segment lengths in torch, exact and
differentiable almost everywhere (hull points are interpolated edge crossings, which move
smoothly with the vertices and the plane height).

Layout: bodies are held coordinate-major, ``(3, n, b)``, so that the blendshape product is one
matrix product, ``(3n, k) @ (k, b)``, and gathering a face's vertices reads contiguous rows.
Derivatives are taken with respect to the ``k`` blendshape coefficients: the volume gradient
is dense and projected with one more matrix product; stature and girths touch a few hundred
vertices and are projected through a sparse matrix.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from wbsa.bodies.anthropometry import Anthropometer
from wbsa.bodies.body_model import BodyModel
from wbsa.bodies.survey_limb_measures import LIMB_MEASURES
from wbsa.typing import SurveyMeasures

#: The trunk measures this module computes, in column order of :meth:`TorchMeasurer.evaluate`.
TRUNK_MEASURES = ("stature_m", "mass_kg", "waist_circ_m", "hip_circ_m")
#: Every fit measure, in column order: the trunk's, then the NHANES limb measures.
FIT_MEASURES = (*TRUNK_MEASURES, *LIMB_MEASURES)


def fit_measures(measures: SurveyMeasures) -> tuple[str, ...]:
    """The fit measures of a choice: ``four`` (:data:`TRUNK_MEASURES`) or ``seven`` (:data:`FIT_MEASURES`)."""
    return TRUNK_MEASURES if measures == "four" else FIT_MEASURES

_FACE_CHUNK = 4096


@dataclass(frozen=True)
class Evaluation:
    """Measures of a batch of bodies and, optionally, their coefficient gradients.

    Attributes
    ----------
    values : (b, m) float64 tensor
        The measurer's measures (:func:`fit_measures`, m = 4 or 7) of every body; a girth is NaN where
        its section is degenerate.
    grad : (b, m, k) float64 tensor or None
        d(measure)/d(blendshape coefficient); zero rows where the value is NaN.
    """

    values: object
    grad: object | None


class TorchMeasurer:
    """The fit measures of a :class:`BodyModel`'s bodies, batched, with exact gradients.

    Parameters
    ----------
    model
        The body model (its torch anny model is used directly).
    meter
        The exact measurer whose landmarks and density are reproduced.
    measures
        ``seven`` (default: the trunk measures and the NHANES limb measures) or ``four`` (the trunk's).
    """

    def __init__(self, model: BodyModel, meter: Anthropometer, measures: SurveyMeasures = "seven"):
        import torch

        from wbsa.bodies.survey_limb_measures import TorchLimbMeasurer

        self.torch = torch
        self.model = model
        anny = model.anny
        self.dtype = anny.dtype
        self.density_kg_m3 = meter.density_kg_m3
        lm = meter.landmarks
        n_blend, n_vert = anny.blendshapes.shape[:2]
        self.n_vertices = int(n_vert)
        #: (3n, k) blendshape basis, coordinate-major rows ``coordinate * n + vertex``
        self.basis_t = anny.blendshapes.detach().permute(2, 1, 0).reshape(-1, n_blend).contiguous()
        self.template = anny.template_vertices.detach().T.reshape(-1, 1)
        self.closed_faces = torch.as_tensor(model.closed_faces, dtype=torch.long)
        ids = np.asarray(lm.trunk_edges.vertex_ids)
        self.edge_a = torch.as_tensor(ids[lm.trunk_edges.edges[:, 0]], dtype=torch.long)
        self.edge_b = torch.as_tensor(ids[lm.trunk_edges.edges[:, 1]], dtype=torch.long)
        self.waist_ring = torch.as_tensor(np.asarray(lm.waist_ring), dtype=torch.long)
        self.hip_ring = torch.as_tensor([int(lm.hip)], dtype=torch.long)
        #: the measures :meth:`evaluate` returns, in column order
        self.names = fit_measures(measures)
        self.limbs = TorchLimbMeasurer(model, meter) if measures == "seven" else None

    # -- body model ---------------------------------------------------------------------
    def coefficients(self, params):
        """Blendshape coefficients ``(b, k)`` of body parameters ``(b, 11)`` or ``(b, 15)`` (differentiable).

        Phenotypes, optionally followed by the local changes (see :meth:`BodyModel.coefficients`).
        """
        return self.model.coefficients(params)

    def vertices(self, coefficients):
        """Rest vertices, coordinate-major ``(3, n, b)``, of coefficients ``(b, k)`` (no gradient)."""
        with self.torch.no_grad():
            flat = self.template + self.basis_t @ coefficients.detach().T
        return flat.reshape(3, self.n_vertices, -1)

    # -- measures -----------------------------------------------------------------------
    def evaluate(self, x, gradient: bool = False, density_kg_m3=None, coefficients=None,
                 trunk_only: bool = False) -> Evaluation:
        """Measures of bodies ``x`` (3, n, b) and, if asked, their coefficient gradients.

        ``density_kg_m3`` : (b,) float64 tensor, optional
            Each body's density for its mass (default: the measurer's one density).
        ``coefficients`` : (b, k) float64 tensor
            The bodies' blendshape coefficients; needed for the limb measures (their joints).
        ``trunk_only`` : bool
            Only the four :data:`TRUNK_MEASURES` (the start table needs no more).
        """
        torch = self.torch
        density = self.density_kg_m3 if density_kg_m3 is None else density_kg_m3
        n, b = self.n_vertices, x.shape[2]
        z = x[2]
        top, bottom = z.argmax(dim=0), z.argmin(dim=0)
        cols = torch.arange(b)
        stature = z[top, cols] - z[bottom, cols]
        signed, gvol = self._volume(x, gradient)
        mass = signed.abs() * density
        girths, sparse = [], []
        for ring, measure in ((self.waist_ring, 2), (self.hip_ring, 3)):
            value, entries = self._girth(x, ring, measure, gradient)
            girths.append(value)
            sparse.append(entries)
        values = torch.stack([stature, mass, *girths], dim=1)
        limb_grad = None
        if self.limbs is not None and not trunk_only:
            if coefficients is None:
                raise ValueError("the limb measures need the bodies' blendshape coefficients")
            limb_values, limb_grad = self.limbs.evaluate(x, coefficients, gradient)
            values = torch.cat([values, limb_values], dim=1)
        if not gradient:
            return Evaluation(values, None)

        k = self.basis_t.shape[1]
        grad = torch.zeros((b, values.shape[1], k), dtype=self.dtype)
        # stature: +z of the top vertex, -z of the lowest
        grad[:, 0] = self.basis_t[2 * n + top] - self.basis_t[2 * n + bottom]
        # mass: dense volume gradient, one product with the basis
        scale = (torch.sign(signed) * density)[:, None]
        grad[:, 1] = (gvol.reshape(3 * n, b).T @ self.basis_t) * scale
        # girths: few vertices each, a sparse product
        rows = torch.cat([e[0] for e in sparse])
        vcols = torch.cat([e[1] for e in sparse])
        vals = torch.cat([e[2] for e in sparse])
        s = torch.sparse_coo_tensor(torch.stack([rows, vcols]), vals, (4 * b, 3 * n),
                                    check_invariants=False).coalesce()
        g = torch.sparse.mm(s, self.basis_t).reshape(4, b, k)
        grad[:, 2] = g[2]
        grad[:, 3] = g[3]
        if limb_grad is not None:
            grad[:, 4:] = limb_grad
        grad = torch.where(torch.isfinite(values)[..., None], grad, torch.zeros_like(grad))
        return Evaluation(values, grad)

    def _volume(self, x, gradient: bool):
        """Signed volume ``(b,)`` and, if asked, its vertex gradient ``(3, n, b)``."""
        torch = self.torch
        f = self.closed_faces
        total = torch.zeros(x.shape[2], dtype=self.dtype)
        grad = torch.zeros_like(x) if gradient else None
        for start in range(0, len(f), _FACE_CHUNK):
            fc = f[start:start + _FACE_CHUNK]
            (ax, ay, az), (bx, by, bz), (cx, cy, cz) = (x[:, fc[:, i]] for i in range(3))
            # b x c, c x a, a x b, each per coordinate, (faces, b)
            bc = (by * cz - bz * cy, bz * cx - bx * cz, bx * cy - by * cx)
            total += (ax * bc[0] + ay * bc[1] + az * bc[2]).sum(dim=0)
            if gradient:
                ca = (cy * az - cz * ay, cz * ax - cx * az, cx * ay - cy * ax)
                ab = (ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx)
                for i, part in enumerate((bc, ca, ab)):
                    for axis in range(3):
                        grad[axis].index_add_(0, fc[:, i], part[axis])
        if gradient:
            grad /= 6.0
        return total / 6.0, grad

    def _girth(self, x, ring, measure: int, gradient: bool):
        """Tape girth ``(b,)`` at the mean height of ``ring`` vertices, and its sparse gradient.

        Returns the girth and, with ``gradient``, ``(rows, columns, values)`` of
        d(girth)/d(vertex coordinate): rows ``measure * b + body``, columns ``axis * n + vertex``.
        """
        torch = self.torch
        n, b = self.n_vertices, x.shape[2]
        with torch.no_grad():
            hull, valid = self._hull_plan(x, x[2, ring].mean(dim=0))
        va, vb = self.edge_a[hull], self.edge_b[hull]  # (b, h)
        body = torch.arange(b)[:, None]
        pa = x[:, va, body].clone().requires_grad_(gradient)  # (3, b, h)
        pb = x[:, vb, body].clone().requires_grad_(gradient)
        rz = x[2, ring].T.clone().requires_grad_(gradient)  # (b, r)
        with torch.set_grad_enabled(gradient):
            plane_z = rz.mean(dim=1)[:, None]
            da = pa[2] - plane_z
            db = pb[2] - plane_z
            denom = da - db
            t = da / torch.where(denom == 0, torch.ones_like(denom), denom)
            pts = pa[:2] + t * (pb[:2] - pa[:2])  # (2, b, h)
            seg = torch.roll(pts, -1, dims=2) - pts
            sq = (seg**2).sum(dim=0)
            nonzero = sq > 0
            safe = torch.where(nonzero, sq, torch.ones_like(sq))
            perimeter = torch.where(nonzero, torch.sqrt(safe), torch.zeros_like(sq)).sum(dim=1)
        value = torch.where(valid, perimeter.detach(), torch.full_like(perimeter, float("nan")))
        if not gradient:
            return value, None
        ga, gb, gr = torch.autograd.grad(perimeter.sum(), (pa, pb, rz))
        axis = torch.arange(3)[:, None, None] * n
        rows = measure * b + torch.cat([
            body.expand_as(va)[None].expand(3, -1, -1).reshape(3, b, -1),
            body.expand_as(vb)[None].expand(3, -1, -1),
        ], dim=2)
        cols = torch.cat([axis + va, axis + vb], dim=2)
        vals = torch.cat([ga, gb], dim=2)
        ring_rows = (measure * b + body).expand(b, len(ring))
        ring_cols = (2 * n + ring)[None].expand(b, len(ring))
        return value, (torch.cat([rows.reshape(-1), ring_rows.reshape(-1)]),
                       torch.cat([cols.reshape(-1), ring_cols.reshape(-1)]),
                       torch.cat([vals.reshape(-1), gr.reshape(-1)]))

    def _hull_plan(self, x, plane):
        """Trunk-edge indices ``(b, h)`` of each section's convex hull, in order, and validity ``(b,)``.

        Rows shorter than ``h`` repeat their last index (zero-length segments).
        """
        torch = self.torch
        za = x[2, self.edge_a] - plane  # (e, b)
        zb = x[2, self.edge_b] - plane
        cross = ((za < 0) != (zb < 0)).T  # (b, e)
        body, edge = torch.nonzero(cross, as_tuple=True)
        da, db = za[edge, body], zb[edge, body]
        t = da / (da - db)
        ea, eb = self.edge_a[edge], self.edge_b[edge]
        px = x[0, ea, body] + t * (x[0, eb, body] - x[0, ea, body])
        py = x[1, ea, body] + t * (x[1, eb, body] - x[1, ea, body])
        pts = torch.stack([px, py], dim=1).numpy()
        counts = torch.bincount(body, minlength=x.shape[2]).numpy()
        edge = edge.numpy()
        rows, valid = [], []
        start = 0
        for count in counts:
            e, p = edge[start:start + count], pts[start:start + count]
            start += count
            order = None
            if count >= 3:
                try:
                    order = e[ConvexHull(p).vertices]
                except QhullError:
                    order = None
            valid.append(order is not None)
            rows.append(order if order is not None else np.zeros(1, dtype=np.int64))
        width = max((len(r) for r in rows), default=1)
        index = np.stack([np.concatenate([r, np.full(width - len(r), r[-1])]) for r in rows]) if rows \
            else np.zeros((0, 1), dtype=np.int64)
        return torch.as_tensor(index, dtype=torch.long), torch.as_tensor(valid, dtype=torch.bool)
