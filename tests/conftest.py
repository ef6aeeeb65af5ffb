"""Shared fixtures: the anny body model is built once per test run (about 60 s on a fresh cache)."""

from __future__ import annotations

import os

import pytest

os.environ.setdefault("WBSA_PROGRESS", "0")
# One thread for OpenMP (scikit-learn's gradient-boosted trees, torch) and BLAS, in this process and the ones it
# starts (set before any of them is loaded; a value in the environment wins). The suite's target machine has
# two cores, one of them kept busy by another job: two OpenMP threads then wait on each other at every barrier,
# and tests/test_estimate.py's out-of-fold view test (six small boosted models) took over 300 s instead of
# 11 s of CPU at one thread. Results do not depend on it; the suite's processes run side by side instead.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")


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
def small_training_run(tmp_path_factory):
    """A small training run of ``wbsa.train`` (``helpers.training.small_training_settings``), once per test run
    (about 100 s on two busy cores, most of it the 64 renders): its folder, with its renders and ``model.npz``."""
    from helpers.training import small_training_settings
    from wbsa.training.run import train

    folder = tmp_path_factory.mktemp("small-training") / "run"
    train(small_training_settings(), folder, workers=1, show_progress=False)
    return folder


@pytest.fixture(scope="session")
def small_estimator_model(small_training_run):
    """The path of the small training run's model: quick, and still a bagged model with a calibrated interval."""
    return small_training_run / "model.npz"


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


@pytest.fixture(scope="session")
def dask_cluster():
    """The scheduler address of one two-process dask cluster on loopback for the whole run: the tests that
    compare work on worker processes with the in-process path share it, so its workers start (and load the
    body model) once, not once per test."""
    import logging

    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=":0",
                      silence_logs=logging.ERROR) as cluster:
        yield cluster.scheduler_address
