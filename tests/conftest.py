"""Shared fixtures: the anny body model is built once per test run (about 60 s on a fresh cache)."""

from __future__ import annotations

import os

import pytest

os.environ.setdefault("WBSA_PROGRESS", "0")


@pytest.fixture(scope="session")
def body_model():
    """One :class:`wbsa.bodies.body_model.BodyModel` for the whole run."""
    from wbsa.bodies.body_model import BodyModel

    return BodyModel()


@pytest.fixture(scope="session")
def anthropometer(body_model):
    """One :class:`wbsa.bodies.anthropometry.Anthropometer` for the whole run."""
    from wbsa.bodies.anthropometry import Anthropometer

    return Anthropometer(body_model)


@pytest.fixture(scope="session")
def small_estimator_model(tmp_path_factory):
    """The path of a small estimator model (32 bodies, 2 views each), trained once per run (about 75 s on two
    busy cores): quick, and still a bagged model with a calibrated interval."""
    from wbsa.training.pipeline import train_model
    from wbsa.training.settings import RenderSettings
    from wbsa.training.settings import TrainSettings

    model = train_model(TrainSettings(n_random=32, n_survey=0, render=RenderSettings(views_per_subject=2),
                                      calibration_fraction=0.5, tree_iterations=200, tree_bags=2, seed=5))
    path = tmp_path_factory.mktemp("model") / "small.npz"
    model.save(path)
    return path


@pytest.fixture(scope="session")
def default_report(tmp_path_factory):
    """The report of ``wbsa run`` with the embedded default study at 24 subjects (the paper's 65 views, Kinect v1
    at 4.3 m, every figure family but reconstruction and distance): its path. About 30 s on two busy cores."""
    import contextlib
    import io

    from wbsa.cli import main

    out = tmp_path_factory.mktemp("default-study") / "run"
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = main(["run", "--n", "24", "--out", str(out), "--no-progress"])
    assert code == 0, err.getvalue()
    return out / "report.html"
