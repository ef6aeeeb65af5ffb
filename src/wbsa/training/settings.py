"""What an estimator model is trained on: :class:`TrainSettings` (subjects, captures, trees, seed)."""

from __future__ import annotations

from dataclasses import dataclass, field

from wbsa.errors import WbsaError
from wbsa.training.renders import RenderSettings


@dataclass(frozen=True)
class TrainSettings:
    """What the default model is trained on (see the module doc).

    Attributes
    ----------
    n_random, n_survey : int
        Random and survey-matched subjects.
    age_years : (float, float)
        Ages of the random subjects, uniform in years.
    calibration_fraction : float
        Share of subjects kept for the interval's calibration (never fitted on).
    render : RenderSettings
        How each subject is captured: views per subject, cameras, distances and sensor
        (:class:`~wbsa.training.capture.CaptureSettings`), postures, rooms, scan renders and clothes. The fit
        subjects' captures draw from ``seed``, the calibration subjects' from ``seed + 7919``.
    folds : int
        Folds of the out-of-fold view estimates and residuals.
    tree_iterations, tree_leaves : int
        Boosting rounds and leaves per tree of the residual trees (learning rate 0.05).
    tree_l2 : float
        L2 penalty on the trees' leaf values.
    tree_bags : int
        Boosted models averaged, each fitted on a random :data:`BAG_SUBJECT_SHARE` of the subjects (1: one
        model on all): a bag steadies estimates that a refit on slightly different captures would move.
    seed : int
    """

    n_random: int = 900
    n_survey: int = 480
    age_years: tuple[float, float] = (3.0, 80.0)
    calibration_fraction: float = 0.25
    render: RenderSettings = field(default_factory=RenderSettings)
    folds: int = 3
    tree_iterations: int = 800
    tree_leaves: int = 31
    tree_l2: float = 0.1
    tree_bags: int = 5
    seed: int = 0

    def __post_init__(self) -> None:
        if self.n_random < 0 or self.n_survey < 0 or self.n_random + self.n_survey < 8:
            raise WbsaError("n_random + n_survey must be at least 8 subjects")
        if not 0.05 <= self.calibration_fraction <= 0.5:
            raise WbsaError(f"calibration_fraction {self.calibration_fraction} must lie in [0.05, 0.5]")
        if not isinstance(self.render, RenderSettings):
            raise WbsaError(f"render must be a RenderSettings, got {type(self.render).__name__}")
        if not isinstance(self.folds, int) or self.folds < 2:
            raise WbsaError(f"folds must be an integer >= 2, got {self.folds!r}")
        counts_ok = all(isinstance(v, int) for v in (self.tree_iterations, self.tree_leaves, self.tree_bags))
        if not (counts_ok and self.tree_iterations >= 1 and self.tree_leaves >= 2 and self.tree_l2 >= 0
                and self.tree_bags >= 1):
            raise WbsaError(f"tree_iterations ({self.tree_iterations!r}) must be an integer >= 1, tree_leaves "
                            f"({self.tree_leaves!r}) an integer >= 2, tree_bags ({self.tree_bags!r}) an integer "
                            f">= 1 and tree_l2 ({self.tree_l2!r}) a number >= 0")
