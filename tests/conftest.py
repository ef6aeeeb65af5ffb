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
