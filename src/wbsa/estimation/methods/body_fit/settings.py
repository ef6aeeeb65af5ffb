"""Settings of the whole-body fit to one depth view (:func:`wbsa.estimation.methods.body_fit.fit_body`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from wbsa.bodies.composition import CompositionSettings
from wbsa.errors import SettingsError, check_field
from wbsa.typing import DataTerm, RobustLoss
from wbsa.settings_io import check_types

#: Box of each posture motion (degrees, change from anny's rest A-pose; :data:`wbsa.bodies.posing.JOINT_MOTIONS`
#: order): wide enough for every named standing posture with its jitter (:data:`wbsa.bodies.posture.POSTURES`)
#: and settling, narrow enough to keep a limb from folding through the body.
ANGLE_LIMITS_DEG = ((-50.0, 40.0), (-35.0, 35.0), (-30.0, 110.0), (-60.0, 75.0), (-15.0, 15.0))


@dataclass(frozen=True)
class BodyFitSettings:
    """How a body is fitted to one depth view.

    Attributes
    ----------
    vertex_spacing_m : float
        Spacing of the model vertices the fit moves (:func:`wbsa.estimation.methods.body_fit.model.even_vertex_subset`); the
        measures are always taken on the whole mesh.
    n_points : int
        Observed points kept (a seeded, even subsample of the subject's returns).
    restarts : int
        Starting points fitted together in one batch; the best fit is kept.
    prune_at, keep_restarts : float, int
        After this share of the steps only the ``keep_restarts`` restarts with the lowest loss go on.
    child_starts : bool
        Make a third of the starts (from a stature of 1.3 m up) children stretched to the stature
        (:data:`wbsa.estimation.methods.body_fit.init.CHILD_AGE`), as anny's random population has; off, a tall person is an adult.
    steps : int
        Most optimiser steps.
    refresh_every : int
        Steps between updates of the point-to-vertex correspondences and the model normals.
    learning_rate : float
        Adam's step for the phenotypes (the others scale from it).
    data_term : {'along-ray', 'closest-point'}
        How the observed points are compared with the body: each depth against the model surface its camera
        ray meets, over the camera's σ(z, θ) (:mod:`wbsa.estimation.methods.body_fit.rays`; points whose ray misses the
        body fall back to the closest point), or each point against its closest model surface point (biased
        inward by depth noise).
    robust_loss : {'geman-mcclure', 'huber'}
    robust_scale_m : float
        Scale of the robust penalty of the point-to-surface residuals.
    silhouette_tolerance_px : float
        Pixels a model vertex may project outside the subject's mask before it is penalised.
    silhouette_weight, contour_weight, free_space_weight : float
        Weights of the silhouette term (no body where the image shows none), the contour term (the body's
        outline on the subject's) and the free-space term (no body in front of a seen surface), against the
        point-to-surface term. The contour term is off by default: sensors drop returns near grazing angles, so
        the outline seen lies inside the body's, and it pulled a body started at its truth 1.4 % smaller.
    phenotype_prior_weight, local_change_prior_weight : float
        Weak quadratic pulls of the phenotypes towards their start (SD 0.5) and of the local changes towards 0.
    age_prior_sd : float
        SD of the pull of anny's age parameter towards its start, the typical age of the measured stature
        (:func:`wbsa.estimation.methods.body_fit.init.age_for_stature`): one view tells a child from a short adult poorly.
    local_changes : bool
        Fit anny's four local changes (waist, hips, belly, buttocks) besides the phenotypes.
    time_budget_s : float
        A wall-clock safety stop (s), not the fit's budget: ``steps`` is the budget, so the same image gives the
        same body on any machine. Past it no further step starts and the fit returns its best body so far,
        flagged ``time_budget`` (at least one step always runs).
    tolerance : float
        Convergence: the best loss fell by less than this fraction over the last ``refresh_every`` steps.
    composition : CompositionSettings
        Body composition for mass and BMI (:mod:`wbsa.bodies.composition`, its equation's value: no residual);
        the default is how the population tables' ``mass_kg`` is made by default.
    threads : int or None
        torch threads during the fit (restored after; :func:`wbsa.parallel.torch_threads`). The fit is thousands
        of small operations: one thread is fastest, and far faster than two on a busy machine (measured: 18 ms
        against up to 1 s a step). None: the count the process has (``wbsa serve`` sets it once at its start,
        as torch's count is the whole process's and its estimates run in threads).
    """

    vertex_spacing_m: float = 0.035
    n_points: int = 1500
    restarts: int = 6
    prune_at: float = 0.25
    keep_restarts: int = 2
    child_starts: bool = False
    steps: int = 200
    refresh_every: int = 10
    learning_rate: float = 0.05
    data_term: DataTerm = "along-ray"
    robust_loss: RobustLoss = "geman-mcclure"
    robust_scale_m: float = 0.015
    silhouette_tolerance_px: float = 1.0
    silhouette_weight: float = 1.0
    contour_weight: float = 0.0
    free_space_weight: float = 1.0
    phenotype_prior_weight: float = 0.01
    local_change_prior_weight: float = 0.01
    age_prior_sd: float = 0.1
    local_changes: bool = True
    time_budget_s: float = 300.0
    tolerance: float = 0.0005
    composition: CompositionSettings = CompositionSettings()
    threads: int | None = 1

    def __post_init__(self) -> None:
        check_types(self)
        for name in ("age_prior_sd", "vertex_spacing_m", "learning_rate", "robust_scale_m", "time_budget_s", "tolerance"):
            value = getattr(self, name)
            check_field(math.isfinite(value) and value > 0, name, f"must be a positive number, got {value!r}")
        for name in ("n_points", "restarts", "keep_restarts", "steps", "refresh_every", "threads"):
            value = getattr(self, name)
            check_field(value is None or value >= 1, name, f"must be a whole number of at least 1, got {value!r}")
        for name in ("silhouette_tolerance_px", "silhouette_weight", "contour_weight", "free_space_weight", "phenotype_prior_weight",
                     "local_change_prior_weight"):
            value = getattr(self, name)
            check_field(math.isfinite(value) and value >= 0, name, f"must be 0 or more, got {value!r}")
        if not 0.005 <= self.vertex_spacing_m <= 0.2:
            raise SettingsError("vertex_spacing_m", f"must be 0.005–0.2 m, got {self.vertex_spacing_m}")
        if not 0.0 <= self.prune_at <= 1.0:
            raise SettingsError("prune_at", f"must be a share of the steps in [0, 1], got {self.prune_at}")
