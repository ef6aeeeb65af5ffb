"""``wbsa scan --backend``: the back end reaches the scan; the default keeps the settings hash of earlier versions."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

pytest.importorskip("warp")

from wbsa.camera import paper_views, preset  # noqa: E402
from wbsa.cli import main  # noqa: E402
from wbsa.errors import WbsaError  # noqa: E402
from wbsa.scan import worker  # noqa: E402
from wbsa.scan.layout import SETTINGS_FILE, TABLE_FILE  # noqa: E402
from wbsa.scan.settings import ScanJob, settings_hash  # noqa: E402


@pytest.fixture(scope="module")
def population(body_model, tmp_path_factory):
    from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters
    from wbsa.bodies.table import measure_population

    params = sample_random_parameters(RandomPopulationSettings(n=3, seed=5))
    path = tmp_path_factory.mktemp("pop") / "pop.parquet"
    measure_population(params, model=body_model).to_parquet(path, index=False)
    return path


@pytest.fixture(autouse=True)
def shared_model(body_model, monkeypatch):
    monkeypatch.setattr(worker, "_BODY_MODEL", body_model)


def test_default_backend_leaves_the_settings_hash_alone():
    views = tuple(paper_views())
    default = ScanJob(camera=preset("kinect-v1"), views=views)
    assert default.backend == "open3d" and "backend" not in default.to_dict()
    explicit = ScanJob(camera=preset("kinect-v1"), views=views, backend="open3d")
    assert settings_hash(explicit, "p") == settings_hash(default, "p")
    warp = ScanJob(camera=preset("kinect-v1"), views=views, backend="warp")
    assert warp.to_dict()["backend"] == "warp" and settings_hash(warp, "p") != settings_hash(default, "p")
    assert ScanJob(camera=preset("kinect-v1"), views=views, backend="auto").backend in ("open3d", "warp")
    with pytest.raises(WbsaError, match="backend must be one of"):
        ScanJob(camera=preset("kinect-v1"), views=views, backend="embree")


def test_scan_with_warp_matches_open3d(population, tmp_path, capsys):
    common = ["--azimuths", "0,60,135,270", "--elevations=-30,0,45", "--workers", "1", "--chunk-size", "2",
              "--no-progress"]
    assert main(["scan", str(population), "--out", str(tmp_path / "o3d"), *common]) == 0
    assert main(["scan", str(population), "--out", str(tmp_path / "warp"), "--backend", "warp", *common]) == 0
    ref = pd.read_parquet(tmp_path / "o3d" / TABLE_FILE)
    got = pd.read_parquet(tmp_path / "warp" / TABLE_FILE)
    assert list(got.columns) == list(ref.columns) and len(got) == len(ref) == 36
    np.testing.assert_allclose(got["vbsa_visible_m2"], ref["vbsa_visible_m2"], rtol=3e-4)
    assert (got["n_pixels"] - ref["n_pixels"]).abs().max() <= 2
    assert (got["fits_in_frame"] == ref["fits_in_frame"]).all()
    assert json.loads((tmp_path / "warp" / SETTINGS_FILE).read_text())["settings"]["backend"] == "warp"
    assert "backend" not in json.loads((tmp_path / "o3d" / SETTINGS_FILE).read_text())["settings"]
    # a folder scanned with one back end is not resumed with another
    capsys.readouterr()
    assert main(["scan", str(population), "--out", str(tmp_path / "o3d"), "--backend", "warp", *common]) == 2
    assert "use another output folder" in capsys.readouterr().err
