"""The small training run the tests share (tests/conftest.py, ``small_training_run``)."""

from __future__ import annotations


def small_training_settings():
    """The settings of the run's small estimator model: 32 bodies, 2 views each, half kept for calibration."""
    from wbsa.training.settings import RenderSettings, TrainSettings

    return TrainSettings(n_random=32, n_survey=0, render=RenderSettings(views_per_subject=2),
                         calibration_fraction=0.5, tree_iterations=200, tree_bags=2, seed=5)
