"""What an estimator model is trained on: :class:`RenderSettings` (how each subject is captured) and
:class:`TrainSettings` (subjects, the renders, trees, seed), composed; light to import (``wbsa train --help``)."""

from __future__ import annotations

from dataclasses import dataclass, field

from wbsa.errors import SettingsError
from wbsa.training.capture import CaptureSettings
from wbsa.settings_io import check_types
from wbsa.typing import SurveyMeasures

@dataclass(frozen=True)
class RenderSettings:
    """How samples are drawn from a population.

    Attributes
    ----------
    views_per_subject : int
        Captures per body (each with its own posture, camera and view).
    capture : CaptureSettings
    postures : tuple of str or None
        Named postures of :data:`wbsa.bodies.posture.POSTURES` (None = all, with jitter).
    floor_error_m, floor_tilt_deg : float
        Without a room: standard deviation of the error put on the render's floor before the floor cut, as
        a detected floor would have.
    room : bool
        Stand the body on a floor before a wall (``wall_behind_m`` behind it, uniform), store the depth
        in millimetres and find the subject and the floor with
        :func:`~wbsa.estimation.subject.segment.segment_subject`: the measures then see what they see in a real
        image (the segmentation's edges, the detected floor). False: the body alone, its own pixels and
        the render's floor.
    alone_share : float
        With ``room``: share of captures of the body alone (no floor, no wall), as a frame whose room was
        removed or a render of a 3-D body scan is; the measures then find no floor.
    scan_share : float
        Share of the captures of a body alone that are read as a rendered 3-D body scan is: no sensor effects
        (no noise, holes or quantisation) and the render's own edges. The others keep their camera's drawn
        sensor and edges (a frame whose room was removed).
    clothed_share : float
        Share of the captures of a dressed body: a layer of clothes over the trunk, upper arms, legs and feet
        (:func:`~wbsa.bodies.clothing.dressed_vertices`, the shoe soles flattened onto the floor); the camera
        aims at the dressed body's centre, a few millimetres from the bare one's.
    clothing_m : (float, float)
        Range of the layer's thickness (m), uniform.
    """

    views_per_subject: int = 4
    capture: CaptureSettings = field(default_factory=CaptureSettings)
    postures: tuple[str, ...] | None = None
    floor_error_m: float = 0.003
    floor_tilt_deg: float = 0.1
    room: bool = True
    wall_behind_m: tuple[float, float] = (0.5, 1.5)
    alone_share: float = 0.15
    scan_share: float = 0.5
    clothed_share: float = 0.2
    clothing_m: tuple[float, float] = (0.0, 0.015)

    def __post_init__(self) -> None:
        check_types(self)
        check_clothing_settings(self.clothed_share, self.clothing_m)
        if self.views_per_subject < 1:
            raise SettingsError("views_per_subject", f"must be an integer >= 1, got {self.views_per_subject!r}")
        if not 0.0 <= self.alone_share <= 1.0:
            raise SettingsError("alone_share", f"{self.alone_share} must be a share of the captures in [0, 1]")
        if not 0.0 <= self.scan_share <= 1.0:
            raise SettingsError("scan_share", f"{self.scan_share} must be a share of the captures of a body alone in [0, 1]")


def check_clothing_settings(clothed_share: float, clothing_m: tuple[float, float]) -> None:
    """Refuse a share of dressed captures outside [0, 1] or a thickness range outside 0–5 cm (one-line SettingsError)."""
    from wbsa.estimation.limits import MAX_CLOTHING_M

    if not 0.0 <= clothed_share <= 1.0:
        raise SettingsError("clothed_share", f"{clothed_share} must be a share of the captures in [0, 1]")
    lo, hi = (float(v) for v in clothing_m)
    if not 0.0 <= lo <= hi <= MAX_CLOTHING_M:
        raise SettingsError("clothing_m", f"{tuple(clothing_m)} must be a range (low, high) of layers within "
                                          f"0–{MAX_CLOTHING_M:g} m, e.g. (0.0, 0.015)")


@dataclass(frozen=True)
class TrainSettings:
    """What the default model is trained on (see the module doc).

    Attributes
    ----------
    n_random, n_survey : int
        Random and survey-matched subjects.
    survey_measures : {'seven', 'four'}
        The NHANES measures the survey-matched subjects are fitted to (:class:`~wbsa.bodies.survey_match.MatchSettings`):
        all seven (stature, mass, waist, hip, arm circumference, arm and leg length: bodies shaped like the
        measured people, as the held-out benchmark's are) or the first four.
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
    survey_measures: SurveyMeasures = "seven"
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
        check_types(self)
        if self.n_random < 0 or self.n_survey < 0 or self.n_random + self.n_survey < 8:
            raise SettingsError("n_random", "+ n_survey must be at least 8 subjects")
        if not 0.05 <= self.calibration_fraction <= 0.5:
            raise SettingsError("calibration_fraction", f"{self.calibration_fraction} must lie in [0.05, 0.5]")
        if self.folds < 2:
            raise SettingsError("folds", f"must be an integer >= 2, got {self.folds!r}")
        if not (self.tree_iterations >= 1 and self.tree_leaves >= 2 and self.tree_l2 >= 0
                and self.tree_bags >= 1):
            raise SettingsError("tree_iterations",
                                f"({self.tree_iterations!r}) must be an integer >= 1, tree_leaves ({self.tree_leaves!r}) "
                                f"an integer >= 2, tree_bags ({self.tree_bags!r}) an integer >= 1 and tree_l2 "
                                f"({self.tree_l2!r}) a number >= 0")
