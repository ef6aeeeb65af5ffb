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
    (about 30 s, most of it the 48 renders): its folder, with its renders and ``model.npz``."""
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
def readme_example(tmp_path_factory):
    """The README's "From Python" block, saved as ``script.py`` and run once with ``python script.py`` (dask's
    worker processes import the script again: the example must work as written): (its code, the finished
    ``subprocess.CompletedProcess``, the folder it ran in). It runs the embedded default study at 12 subjects
    in 2 worker processes, so its ``runs/demo/report.html`` is also the default report the browser test reads."""
    import re
    import subprocess
    import sys
    from pathlib import Path

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    section = readme[readme.index("## From Python"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    folder = tmp_path_factory.mktemp("readme-example")
    (folder / "script.py").write_text(code)
    done = subprocess.run([sys.executable, "script.py"], cwd=folder, capture_output=True, text=True, timeout=900)
    return code, done, folder


@pytest.fixture(scope="session")
def default_report(readme_example):
    """The report of the embedded default study (the paper's 65 views, Kinect v1 at 4.3 m, every figure family
    but reconstruction and distance) at 12 subjects, as the README's Python example writes it: its path."""
    _, done, folder = readme_example
    assert done.returncode == 0, done.stderr[-2000:]
    return folder / "runs" / "demo" / "report.html"


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
