"""The small training run the tests share (tests/conftest.py, ``small_training_run``)."""

from __future__ import annotations


def small_training_settings():
    """The settings of the run's small estimator model: 24 bodies, 2 views each, half kept for calibration, in a
    narrower sensor world than the default's (noise 0.2–1.5× each camera's model, its own grazing dropout): so few
    renders cannot fit the default's 0–3× and 0–2× (its clothes term then moved an estimate by more than the
    estimate, and a widened interval went below 0)."""
    from wbsa.training.capture import CaptureSettings
    from wbsa.training.settings import RenderSettings, TrainSettings

    capture = CaptureSettings(noise_scale=(0.2, 1.5), grazing_dropout_scale=(1.0, 1.0))
    return TrainSettings(n_random=24, n_survey=0, render=RenderSettings(views_per_subject=2, capture=capture),
                         calibration_fraction=0.5, tree_iterations=200, tree_bags=2, seed=5)
