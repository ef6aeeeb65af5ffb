"""What the learned start is trained on and how: :class:`StartSettings` (light to import: ``wbsa train-start --help``)."""

from __future__ import annotations

from dataclasses import dataclass, field

from wbsa.errors import SettingsError
from wbsa.settings_io import check_types
from wbsa.training.settings import RenderSettings
from wbsa.typing import SurveyMeasures

#: Seeds the held-out benchmark (1000) and the interval's calibration (2000) draw from: never trained on.
HELD_OUT_SEEDS = (1000, 2000)


@dataclass(frozen=True)
class StartSettings:
    """The learned start's data and training.

    Attributes
    ----------
    n_random, n_survey : int
        Random and survey-matched bodies (:func:`wbsa.training.pipeline.training_population`, as ``wbsa train``
        draws them). With the default seed and 480 survey bodies these are the NHANES people the shipped
        regression model was trained on, whom every held-out benchmark leaves out
        (:func:`wbsa.testing.testset.held_out_population`); other counts or seeds may draw people a benchmark
        draws (``benchmarks/bench_start.py`` drops them from its figures).
    survey_measures : {'seven', 'four'}
        The NHANES measures the survey bodies are matched to.
    age_years : (float, float)
        Ages of the random bodies, uniform in years.
    render : RenderSettings
        How each body is captured (views, cameras, distances, sensors, postures, rooms, clothes): the
        captures of ``wbsa train``, cropped by :func:`~wbsa.estimation.methods.body_fit.start_crop.start_crop`
        instead of measured.
    validation_fraction : float
        Share of the bodies kept out of the training, whose captures give the card's figures.
    epochs : int
        Passes over the training crops.
    batch : int
        Crops per step.
    learning_rate : float
        Adam's step size (cosine decay to zero over the epochs).
    weight_decay : float
        AdamW's weight decay.
    chunk_subjects : int
        Bodies per stored chunk of crops (a killed run resumes from the finished chunks).
    seed : int
        Seed of the population, the captures (``SeedSequence([seed, sample])``), the split, the network's
        weights and the batches; never a held-out seed (:data:`HELD_OUT_SEEDS`).
    """

    n_random: int = 1520
    n_survey: int = 480
    survey_measures: SurveyMeasures = "seven"
    age_years: tuple[float, float] = (3.0, 80.0)
    render: RenderSettings = field(default_factory=lambda: RenderSettings(views_per_subject=8))
    validation_fraction: float = 0.1
    epochs: int = 30
    batch: int = 64
    learning_rate: float = 2e-3
    weight_decay: float = 1e-4
    chunk_subjects: int = 20
    seed: int = 0

    def __post_init__(self) -> None:
        check_types(self)
        if self.n_random < 0 or self.n_survey < 0 or self.n_random + self.n_survey < 8:
            raise SettingsError("n_random", "+ n_survey must be at least 8 bodies")
        if not 0.0 < self.validation_fraction <= 0.5:
            raise SettingsError("validation_fraction", f"{self.validation_fraction} must lie in (0, 0.5]")
        if self.epochs < 1 or self.batch < 2 or self.chunk_subjects < 1:
            raise SettingsError("epochs", f"({self.epochs!r}) must be >= 1, batch ({self.batch!r}) >= 2 and "
                                          f"chunk_subjects ({self.chunk_subjects!r}) >= 1")
        if not (self.learning_rate > 0 and self.weight_decay >= 0):
            raise SettingsError("learning_rate", f"({self.learning_rate!r}) must be > 0 and weight_decay "
                                                 f"({self.weight_decay!r}) >= 0")
        for s in (self.seed, self.seed + 1):  # the survey people are drawn from seed + 1
            if s in HELD_OUT_SEEDS:
                raise SettingsError("seed", f"{self.seed} draws from the held-out seed {s} (the benchmark's or the "
                                            "calibration's); use another, e.g. 0")
