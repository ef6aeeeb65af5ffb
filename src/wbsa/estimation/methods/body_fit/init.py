"""The first guess of a body fit: a small render-and-compare grid over sex, arms and azimuth.

The subject's stature is read from the floor and the top of its points; for each sex a body of anny's
middle build is sized to it (``p_height`` interpolated on a grid, an age from the stature), posed in each of
:data:`ARM_STARTS` and turned to each of :data:`YAW_STARTS`, slid so that its camera-facing side sits over
the observed points, and scored by how far the observed points lie from its camera-facing vertices and how
far it projects outside the mask. The best few (all different) start the fit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wbsa.bodies.body_model import PHENOTYPE_COLUMNS, LOCAL_CHANGE_COLUMNS

#: Arm postures tried (shoulder abduction, flexion, rotation, elbow flexion; degrees from the rest A-pose).
ARM_STARTS = {"a-pose": (0.0, 0.0, 0.0, 0.0), "arms-down": (-32.0, 0.0, 0.0, -35.0),
              "arms-wide": (18.0, 0.0, 0.0, -10.0), "hands-on-hips": (-10.0, -10.0, 85.0, 30.0),
              "elbows-bent": (-25.0, 0.0, 10.0, 45.0)}
#: Azimuths tried (degrees).
YAW_STARTS = np.arange(0.0, 360.0, 30.0)
#: anny's age parameter of the child starts (about 9 years): the random population stretches children to adult
#: statures, and a child's head and limbs differ from an adult's of the same height.
CHILD_AGE = 0.38
#: anny's age parameter of the adult starts (about 30 years).
ADULT_AGE = 0.8
#: Truncation (m) of the observed-to-model distances in the score.
_TRUNCATE_M = 0.10


@dataclass(frozen=True)
class Starts:
    """Starting points of a batched fit.

    Attributes
    ----------
    params : (b, 15) float64
        Phenotypes and local changes (:data:`wbsa.bodies.body_model.BODY_PARAMETER_COLUMNS`).
    angles_rad : (b, 10) float64
    yaw_rad : (b,) float64
        Turn of the body about +Z in the view frame (azimuth = −yaw).
    shift_m : (b, 3) float64
    score : (b,) float64
    label : tuple of str
    """

    params: np.ndarray
    angles_rad: np.ndarray
    yaw_rad: np.ndarray
    shift_m: np.ndarray
    score: np.ndarray
    label: tuple[str, ...]


def age_for_stature(stature_m: float) -> float:
    """anny's age parameter of a typical person of this stature (adult from 1.55 m; children by height).

    Parameters
    ----------
    stature_m : float
    """
    return float(np.interp(stature_m, [0.9, 1.1, 1.3, 1.45, 1.55], [0.2, 0.3, 0.4, 0.55, 0.8]))


def start_ages(stature_m: float, child_starts: bool = False) -> list[float]:
    """anny age parameters to start from: the stature's typical age, and an adult's (0.8) from 1.2 m up (a short
    adult and a child of the same stature differ in shape; one view tells them apart only by fitting both);
    with ``child_starts`` also a child (:data:`CHILD_AGE`) stretched to an adult stature.

    Parameters
    ----------
    stature_m : float
    child_starts : bool
        Also a child stretched to the stature.
    """
    ages = [age_for_stature(stature_m)]
    if stature_m >= 1.2 and ages[0] < ADULT_AGE:
        ages.append(ADULT_AGE)
    if child_starts and stature_m >= 1.3 and all(abs(a - CHILD_AGE) > 0.1 for a in ages):
        ages.append(CHILD_AGE)
    return ages


def base_params(gender: float, age: float, p_height: np.ndarray) -> np.ndarray:
    """(g, 15) parameters of middle-build bodies of one sex and age at each ``p_height``.

    Parameters
    ----------
    gender, age : float
        anny's gender and age parameters.
    p_height : (g,) float64
        anny's height parameter of each body.
    """
    row = dict.fromkeys(PHENOTYPE_COLUMNS, 0.5)
    row.update(p_gender=gender, p_age=age, p_african=1 / 3, p_asian=1 / 3, p_caucasian=1 / 3)
    base = np.array([row[c] for c in PHENOTYPE_COLUMNS] + [0.0] * len(LOCAL_CHANGE_COLUMNS))
    out = np.repeat(base[None], len(p_height), axis=0)
    out[:, PHENOTYPE_COLUMNS.index("p_height")] = p_height
    return out


def first_guesses(fit_body, objective, n: int, azimuth_deg: float | None = None, child_starts: bool = False) -> Starts:
    """The ``n`` best starts of the grid (see the module docstring); a stated azimuth keeps them within 45° of it.

    Parameters
    ----------
    fit_body : FitBody
    objective : Objective
        The fit's objective on the observed points.
    n : int
        Starts kept (the restarts).
    azimuth_deg : float or None
        A stated azimuth (degrees).
    child_starts : bool
        Also start from children (:attr:`BodyFitSettings.child_starts`).
    """
    import torch
    from scipy.spatial import cKDTree

    from wbsa.estimation.methods.body_fit.model import subset_rest_normals, yaw_matrix

    obs = objective.obs
    stature = obs.top_m + 0.01  # the crown is rarely seen from below head height
    ages = start_ages(stature, child_starts)
    grid = np.linspace(0.0, 1.0, 11)

    def sized(gender: float, age_param: float) -> np.ndarray:
        v, _ = fit_body.rest(torch.as_tensor(base_params(gender, age_param, grid)))
        heights = (v[..., 2].max(1).values - v[..., 2].min(1).values).numpy()
        return base_params(gender, age_param, [float(np.interp(stature, heights, grid))])[0]

    with torch.no_grad():
        kinds = [(g, a) for a in ages for g in (0.0, 1.0)]  # (gender, age) of each start body
        params = torch.as_tensor(np.stack([sized(g, a) for g, a in kinds]))
        rest, joints = fit_body.rest(params)
        normals_rest = subset_rest_normals(fit_body, params)
        names = list(ARM_STARTS)
        angles = np.zeros((len(names), 10))
        for i, name in enumerate(names):
            angles[i, [0, 1, 2, 3]] = np.radians(ARM_STARTS[name])
            angles[i, [5, 6, 7, 8]] = np.radians(ARM_STARTS[name])
        sex_i, arm_i = np.meshgrid(np.arange(len(kinds)), np.arange(len(names)), indexing="ij")
        sex_i, arm_i = sex_i.ravel(), arm_i.ravel()
        posed, rot = fit_body.pose(rest[sex_i], joints[sex_i], torch.as_tensor(angles[arm_i]), rotations=True)
        normals = torch.einsum("bkij,bkj->bki", rot, torch.as_tensor(normals_rest[sex_i], dtype=torch.float32))
        labels, scores, shifts, combos = [], [], [], []
        mean_xy = obs.points[:, :2].mean(0)
        yaw_r = torch.as_tensor(np.radians(-YAW_STARTS), dtype=torch.float32)
        rz = yaw_matrix(yaw_r)
        for c in range(len(sex_i)):
            vf = torch.einsum("yij,kj->yki", rz, posed[c])
            nf = torch.einsum("yij,kj->yki", rz, normals[c])
            facing = ((torch.as_tensor(obs.camera_position, dtype=torch.float32) - vf) * nf).sum(-1) > 0
            for y in range(len(YAW_STARTS)):
                vis = vf[y][facing[y]].numpy()
                shift = np.zeros(3)
                shift[:2] = mean_xy - vis[:, :2].mean(0)
                d, _ = cKDTree(vis + shift).query(obs.points, workers=1)
                data = float(np.mean(np.minimum(d, _TRUNCATE_M) ** 2))
                sil = float(objective.silhouette((vf[y] + torch.as_tensor(shift, dtype=torch.float32))[None])[0])
                scores.append(data / objective.scale**2 + sil)
                shifts.append(shift)
                combos.append((c, y))
                gender, age = kinds[sex_i[c]]
                labels.append(f"{'male' if gender == 0 else 'female'} (age {age:.2f}), {names[arm_i[c]]}, azimuth "
                              f"{YAW_STARTS[y]:.0f}°")
    scores = np.asarray(scores)
    if azimuth_deg is not None:
        off = np.abs((YAW_STARTS[[y for _, y in combos]] - azimuth_deg + 180.0) % 360.0 - 180.0)
        scores = np.where(off <= 45.0, scores, np.inf)
    ranked = np.argsort(scores, kind="stable")
    # starts of every body in turn (sex and age differ most on the unseen side; the grid cannot tell them apart)
    by_kind = [[i for i in ranked if sex_i[combos[i][0]] == k and np.isfinite(scores[i])] for k in range(len(kinds))]
    order = []
    for j in range(n):
        for k in range(len(kinds)):
            queue = by_kind[(j + k) % len(kinds)]
            if queue:
                order.append(queue.pop(0))
                break
    order = sorted(order, key=lambda i: scores[i])
    picks = [(i, params.numpy()[sex_i[combos[i][0]]], labels[i]) for i in order]
    return Starts(params=np.stack([p for _, p, _ in picks]),
                  angles_rad=angles[[arm_i[combos[i][0]] for i, _, _ in picks]],
                  yaw_rad=np.radians(-YAW_STARTS[[combos[i][1] for i, _, _ in picks]]),
                  shift_m=np.stack([shifts[i] for i, _, _ in picks]), score=scores[[i for i, _, _ in picks]],
                  label=tuple(label for _, _, label in picks))
