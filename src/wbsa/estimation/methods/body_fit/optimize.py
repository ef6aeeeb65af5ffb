"""The batched fit: Adam over phenotypes, local changes, posture and placement of every start at once.

One batch holds every restart, so a step costs one blendshape product and one skinning for all of them
(the time of a fit is per-operation overhead, not arithmetic). Each restart keeps its own best state;
the correspondences and normals are refreshed every ``refresh_every`` steps. The loop stops when the
best loss stalls (converged) or after ``steps`` steps (not converged): the budget is counted in steps, so the
same image gives the same body on any machine. A wall-clock deadline is only a safety stop: it is checked
after each step, so at least one step always runs, and the fit returns its best body so far (flagged by the
caller). Stopped while the robust scale still anneals, where losses of different steps are not comparable,
the best body is each restart's latest state, compared at that step's scale.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from wbsa.bodies.body_model import PHENOTYPE_COLUMNS
from wbsa.estimation.methods.body_fit.settings import ANGLE_LIMITS_DEG, BodyFitSettings

_N_PH = len(PHENOTYPE_COLUMNS)
_AGE = PHENOTYPE_COLUMNS.index("p_age")
#: The age prior counts as this many observed points' worth of squared residual (in SDs).
_AGE_PRIOR_POINTS = 20.0
#: Standard deviation (m) of the vertical shift of a body that stands on a seen floor.
_FLOOR_SD_M = 0.01
#: Robust scale (m) of the point-to-surface term at the first step; it shrinks geometrically to the settings'
#: ``robust_scale_m`` over the first :data:`_ANNEAL_SHARE` of the steps (graduated non-convexity).
_START_SCALE_M = 0.10
_ANNEAL_SHARE = 0.5


@dataclass(frozen=True)
class Optimum:
    """The best state of a batched fit.

    Attributes
    ----------
    params : (15,) float64
    angles_rad : (10,) float64
    yaw_rad : float
    shift_m : (3,) float64
    loss : float
    restart_losses : (b,) float64
        Each restart's best loss.
    residuals_m : (p,) float64
        Point-to-plane distances of the observed points to the best body.
    vertices : (k, 3) float64
        The best body's subset vertices, view frame.
    steps : int
    converged, timed_out : bool
    """

    params: np.ndarray
    angles_rad: np.ndarray
    yaw_rad: float
    shift_m: np.ndarray
    loss: float
    restart_losses: np.ndarray
    residuals_m: np.ndarray
    vertices: np.ndarray
    steps: int
    converged: bool
    timed_out: bool


def _limits(torch):
    lo = np.radians([lo for lo, _ in ANGLE_LIMITS_DEG] * 2)
    hi = np.radians([hi for _, hi in ANGLE_LIMITS_DEG] * 2)
    return torch.as_tensor(lo, dtype=torch.float32), torch.as_tensor(hi, dtype=torch.float32)


def clothes_layer(full: np.ndarray, closed_faces: np.ndarray, covered: np.ndarray, layer_m: float) -> np.ndarray:
    """Offsets that dress posed bodies in a layer of clothes, the soles kept on the bodies' lowest level (as
    :func:`wbsa.bodies.clothing.dressed_vertices` does).

    Parameters
    ----------
    full : (b, n, 3) float64
        Every vertex of every posed body.
    closed_faces : (m, 3) int
        The closed mesh's triangles (for the vertex normals).
    covered : (n,) bool
        Vertices under the clothes.
    layer_m : float
        Thickness of the layer (m).

    Returns
    -------
    (b, n, 3) float64
        ``layer_m`` along the vertex normals where covered, 0 elsewhere.
    """
    from wbsa.estimation.methods.body_fit.model import vertex_normals

    layer = layer_m * covered[None, :, None] * vertex_normals(full, closed_faces)
    lowest = full[..., 2].min(axis=1, keepdims=True)
    layer[..., 2] = np.maximum(layer[..., 2], lowest - full[..., 2])
    return layer


def optimise(fit_body, objective, starts, settings: BodyFitSettings, deadline: float, clothing_m: float = 0.0,
             covered: np.ndarray | None = None, progress=None) -> Optimum:
    """Fit every start of ``starts`` (:class:`wbsa.estimation.methods.body_fit.init.Starts`) to ``objective``'s observation.

    Parameters
    ----------
    fit_body : wbsa.estimation.methods.body_fit.model.FitBody
    objective : wbsa.estimation.methods.body_fit.objective.Objective
    starts : Starts
    settings : BodyFitSettings
    deadline : float
        ``time.perf_counter()`` value after which no further step starts (a safety stop; ``math.inf`` for none).
        The first step always runs, so there is always a best body to return.
    clothing_m : float
        A stated layer of clothes (m): the observation is compared with the body dressed in it where ``covered``
        (:func:`clothes_layer`, refreshed with the correspondences), and the bare body is what is fitted.
    covered : (n,) bool, optional
        The vertices under the clothes (needed with ``clothing_m`` > 0).
    progress : callable or None
        Called as ``progress(step, steps)`` after each step (``step`` of ``settings.steps`` done).
    """
    import torch

    from wbsa.estimation.methods.body_fit.model import yaw_matrix

    f32, f64 = torch.float32, torch.float64
    phen0 = torch.as_tensor(starts.params[:, :_N_PH], dtype=f64)
    phen = phen0.clone().requires_grad_(True)
    local = torch.as_tensor(starts.params[:, _N_PH:], dtype=f64).clone().requires_grad_(settings.local_changes)
    angles = torch.as_tensor(starts.angles_rad, dtype=f32).clone().requires_grad_(True)
    yaw = torch.as_tensor(starts.yaw_rad, dtype=f32).clone().requires_grad_(True)
    shift = torch.as_tensor(starts.shift_m, dtype=f32).clone().requires_grad_(True)
    lr = settings.learning_rate

    def adam():
        groups = [{"params": [phen], "lr": lr}, {"params": [angles], "lr": 1.5 * lr},
                  {"params": [yaw], "lr": lr}, {"params": [shift], "lr": 0.25 * lr}]
        if settings.local_changes:
            groups.append({"params": [local], "lr": 2 * lr})
        return torch.optim.Adam(groups)

    opt = adam()
    base_lr = [g["lr"] for g in opt.param_groups]
    prune_step = int(round(settings.prune_at * settings.steps / settings.refresh_every)) * settings.refresh_every
    values = None
    lo, hi = _limits(torch)
    floor_seen = objective.obs.floor_seen
    b = phen.shape[0]
    best_loss = np.full(b, np.inf)
    best = [None] * b
    history: list[float] = []
    converged = timed_out = False
    tri = bary = facing = contour_corr = selection = None
    ray_tri = ray_hit = ray_sigma = None
    dressed = None
    along_ray = settings.data_term == "along-ray"
    step = 0

    def body(selection):
        params = torch.cat([phen, local], dim=1)
        rest, joints = fit_body.rest(params, selection)
        posed = fit_body.pose(rest, joints, angles, selection=selection)
        return params, posed @ yaw_matrix(yaw).transpose(1, 2) + shift[:, None]

    k = len(fit_body.subset.index)
    model = fit_body.body_model

    latest_loss = np.full(b, np.inf)
    latest: list = [None] * b
    for step in range(settings.steps):
        if step and time.perf_counter() > deadline:
            timed_out = True
            break
        if step and step == prune_step and len(values) > settings.keep_restarts:
            # the worst starts stop here: later steps and refreshes cost only the survivors
            keep = torch.as_tensor(np.argsort(values, kind="stable")[:settings.keep_restarts])
            with torch.no_grad():
                phen = phen[keep].detach().clone().requires_grad_(True)
                local = local[keep].detach().clone().requires_grad_(settings.local_changes)
                angles, yaw, shift = (x[keep].detach().clone().requires_grad_(True) for x in (angles, yaw, shift))
                phen0 = phen0[keep]
            best_loss = best_loss[keep.numpy()]
            best = [best[i] for i in keep.numpy()]
            latest_loss = latest_loss[keep.numpy()]
            latest = [latest[i] for i in keep.numpy()]
            opt = adam()
        if step % settings.refresh_every == 0:
            with torch.no_grad():
                full = fit_body.full_posed(torch.cat([phen, local], dim=1), angles.detach().numpy(), yaw.detach().numpy(),
                                           shift.detach().numpy().astype(np.float64))
                if clothing_m > 0:
                    layer = clothes_layer(full, model.closed_faces, covered, clothing_m)
                    full = full + layer
                tri_full, bary, n, facing = objective.correspondences(full, model.skin_faces, model.closed_faces,
                                                                     fit_body.subset.index)
                touched = [tri_full]
                if along_ray:
                    ray_full, ray_hit, ray_sigma = objective.rays.correspondences(full, model.skin_faces)
                    touched.append(ray_full[ray_hit.numpy()])
                extra = np.setdiff1d(np.unique(np.concatenate([t.ravel() for t in touched])), fit_body.subset.index)
                selection = fit_body.select(np.concatenate([fit_body.subset.index, extra]))
                lookup = np.zeros(len(full[0]), dtype=np.int64)
                lookup[selection.index] = np.arange(len(selection.index))
                tri = torch.as_tensor(lookup[tri_full])
                if along_ray:
                    ray_tri = torch.as_tensor(lookup[ray_full])
                if clothing_m > 0:
                    dressed = torch.as_tensor(layer[:, selection.index], dtype=f32)
                contour_corr = objective.contour_correspondences(full[:, fit_body.subset.index], n)
            annealed = step >= _ANNEAL_SHARE * settings.steps + 2 * settings.refresh_every
            if annealed and history[-2] - history[-1] < settings.tolerance * abs(history[-2]):
                converged = True
                break
        anneal = min(1.0, step / max(1.0, _ANNEAL_SHARE * settings.steps))
        final = objective.scale
        scale = max(final, _START_SCALE_M * (final / _START_SCALE_M) ** anneal)
        for g, base in zip(opt.param_groups, base_lr):
            g["lr"] = base * (1.0 - 0.8 * step / settings.steps)
        params, v_all = body(selection)
        if dressed is not None:
            v_all = v_all + dressed
        v = v_all[:, :k]
        data = objective.data_points(v_all, tri, bary, scale) * (scale / final) ** 2
        if along_ray:  # points whose ray misses the body keep the closest-point cost
            data = torch.where(ray_hit, objective.rays.cost(v_all, ray_tri, ray_hit, ray_sigma, scale, objective.robust),
                               data)
        loss = (data.mean(1)
                + settings.silhouette_weight * objective.silhouette(v)
                + settings.contour_weight * objective.contour(v, contour_corr)
                + settings.free_space_weight * objective.free_space(v, facing)
                + settings.phenotype_prior_weight * ((phen - phen0) / 0.5).square().sum(1).to(f32)
                + settings.local_change_prior_weight * local.square().sum(1).to(f32)
                + ((phen[:, _AGE] - phen0[:, _AGE]) / settings.age_prior_sd).square().to(f32) / len(objective.obs.points)
                * _AGE_PRIOR_POINTS)
        if floor_seen:
            loss = loss + (shift[:, 2] / _FLOOR_SD_M).square() / len(objective.obs.points)
        values = loss.detach().numpy().astype(np.float64)

        def state(i):
            return (params[i].detach().numpy().copy(), angles[i].detach().numpy().astype(np.float64),
                    float(yaw[i].detach()), shift[i].detach().numpy().astype(np.float64),
                    v_all[i].detach().numpy(), tri[i], bary[i])

        for i in np.flatnonzero(values < best_loss):
            best_loss[i] = values[i]
            best[i] = state(i)
        if step < _ANNEAL_SHARE * settings.steps:
            latest_loss = values.copy()
            latest = [state(i) for i in range(len(values))]
        if step % settings.refresh_every == settings.refresh_every - 1:
            history.append(float(best_loss.min()))
        if step < _ANNEAL_SHARE * settings.steps:  # the scale still changes: losses are not comparable
            best_loss[:] = np.inf
        opt.zero_grad(set_to_none=True)
        loss.sum().backward()
        opt.step()
        with torch.no_grad():
            phen.clamp_(0.0, 1.0)
            phen[:, -3:].clamp_(min=0.02)
            local.clamp_(-1.0, 1.0)
            angles.copy_(torch.maximum(torch.minimum(angles, hi), lo))
        if progress is not None:
            progress(step + 1, settings.steps)
    if not np.isfinite(best_loss).any():  # stopped while the scale annealed: the latest states, at one scale
        best_loss, best = latest_loss, latest
    i = int(np.argmin(best_loss))
    params, ang, yaw_i, shift_i, verts, tri_i, bary_i = best[i]
    with torch.no_grad():
        res = objective.residuals_m(torch.as_tensor(verts, dtype=f32)[None], tri_i[None], bary_i[None])[0]
    return Optimum(params=params, angles_rad=ang, yaw_rad=yaw_i, shift_m=shift_i, loss=float(best_loss[i]),
                   restart_losses=best_loss, residuals_m=res.numpy().astype(np.float64),
                   vertices=verts[:k].astype(np.float64), steps=step + 1 if not (converged or timed_out) else step,
                   converged=converged, timed_out=timed_out)
