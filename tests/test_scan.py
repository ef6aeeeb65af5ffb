"""``wbsa scan`` with real anny bodies and the real camera (and sensor / reconstruction when asked)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from wbsa.cli import main
from wbsa.scan import worker
from wbsa.scan.layout import INTRINSICS_FILE, PARTS_DIR, SETTINGS_FILE, TABLE_FILE

PINNED_COLUMNS = ("subject_id", "azimuth_deg", "elevation_deg", "distance_m", "camera", "vbsa_hit_m2",
                  "vbsa_visible_m2", "n_pixels", "fits_in_frame")


@pytest.fixture(scope="module")
def population(body_model, tmp_path_factory):
    """A 3-subject population table, rows shuffled, written as Parquet."""
    from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters
    from wbsa.bodies.table import measure_population

    params = sample_random_parameters(RandomPopulationSettings(n=3, seed=11))
    table = measure_population(params, model=body_model).iloc[[2, 0, 1]]
    path = tmp_path_factory.mktemp("pop") / "pop.parquet"
    table.to_parquet(path, index=False)
    return path, table


@pytest.fixture(autouse=True)
def shared_model(body_model, monkeypatch):
    """The worker's per-process model is the session's model (anny is built once per test run)."""
    monkeypatch.setattr(worker, "_BODY_MODEL", body_model)


def _scan(pop_path, out, *extra, azimuths="0,90,180,270", elevations="0,45"):
    return main(["scan", str(pop_path), "--azimuths", azimuths, "--elevations", elevations, "--out", str(out),
                 "--workers", "1", "--chunk-size", "2", "--no-progress", *extra])


def test_scan_cli_writes_table_intrinsics_and_settings(population, tmp_path, capsys):
    import open3d as o3d

    from wbsa.camera import preset

    pop_path, pop = population
    assert _scan(pop_path, tmp_path / "out") == 0
    assert "scanned 3 subjects x 8 views = 24 rows" in capsys.readouterr().out
    table = pd.read_parquet(tmp_path / "out" / TABLE_FILE)
    assert all(c in table.columns for c in PINNED_COLUMNS)
    assert len(table) == 24 and (table["camera"] == "kinect-v1").all() and (table["distance_m"] == 4.3).all()
    assert table["subject_id"].tolist() == sorted(table["subject_id"].tolist())
    assert sorted(p.name for p in (tmp_path / "out" / PARTS_DIR).iterdir()) == [
        "part-00000000-00000001.parquet", "part-00000002-00000002.parquet"]

    # Open3D reads the intrinsics back as the Kinect v1 matrix.
    k = o3d.io.read_pinhole_camera_intrinsic(str(tmp_path / "out" / INTRINSICS_FILE))
    assert np.allclose(np.asarray(k.intrinsic_matrix), preset("kinect-v1").K)
    doc = json.loads((tmp_path / "out" / SETTINGS_FILE).read_text())
    assert len(doc["settings_hash"]) == 16 and len(doc["settings"]["views"]) == 8 and doc["settings"]["sensor"] is None

    # Physical sense: hit-triangle VBSA < visible VBSA < whole-body skin area; the body fits the frame at 4.3 m.
    merged = table.merge(pop[["subject_id", "wbsa_m2"]], on="subject_id")
    assert (merged["vbsa_hit_m2"] < merged["vbsa_visible_m2"]).all()
    assert (merged["vbsa_visible_m2"] < 0.6 * merged["wbsa_m2"]).all()
    front = merged[(merged["azimuth_deg"] == 0) & (merged["elevation_deg"] == 0)]
    assert ((front["vbsa_visible_m2"] / front["wbsa_m2"]).between(0.3, 0.5)).all()
    assert table["fits_in_frame"].all()
    # Left and right sides of a near-symmetric body show about the same skin.
    side = table[table["elevation_deg"] == 0].pivot(index="subject_id", columns="azimuth_deg", values="vbsa_visible_m2")
    assert np.allclose(side[90.0], side[270.0], rtol=0.05)


def test_rows_belong_to_their_subject(population, body_model, tmp_path):
    """Each row is that subject's body (chunking and the shuffled table do not mix subjects up)."""
    from wbsa.camera import MeshScene, View, measure_view, preset

    pop_path, pop = population
    assert _scan(pop_path, tmp_path / "out") == 0
    table = pd.read_parquet(tmp_path / "out" / TABLE_FILE)
    subject = pop[pop["subject_id"] == 2]
    scene = MeshScene(body_model.skin_meshes(subject)[0])
    row, _ = measure_view(scene, preset("kinect-v1"), View(90.0, 45.0, 4.3), return_frame=False)
    got = table[(table["subject_id"] == 2) & (table["azimuth_deg"] == 90) & (table["elevation_deg"] == 45)]
    assert got["vbsa_visible_m2"].item() == pytest.approx(row["vbsa_visible_m2"], rel=1e-12)
    assert got["n_pixels"].item() == row["n_pixels"]


def test_sensor_and_reconstruction_columns_are_seeded(population, tmp_path):
    pop_path, _ = population
    views = {"azimuths": "0,150", "elevations": "0"}
    args = ("--holes", "0.3", "--reconstruct", "grid", "--seed", "4")
    assert _scan(pop_path, tmp_path / "a", *args, **views) == 0
    assert _scan(pop_path, tmp_path / "b", *args, **views) == 0
    assert _scan(pop_path, tmp_path / "c", "--holes", "0.3", "--reconstruct", "grid", "--seed", "5", **views) == 0
    assert _scan(pop_path, tmp_path / "d", "--reconstruct", "grid", **views) == 0
    a, b, c, d = (pd.read_parquet(tmp_path / x / TABLE_FILE) for x in "abcd")
    pd.testing.assert_frame_equal(a, b)
    assert (a["sensor_holes_fraction"] == 0.3).all() and "sensor_holes_fraction" not in d.columns
    # 30 % of the visible triangles are dropped with their pixels.
    ratio = a["vbsa_hit_sensor_m2"] / a["vbsa_hit_m2"]
    assert ratio.between(0.55, 0.85).all() and abs(ratio.mean() - 0.7) < 0.05
    assert (a["n_pixels_sensor"] < a["n_pixels"]).all()
    # Without a sensor the grid reconstruction of the ideal frame is close to the visible skin;
    # with holes it reconstructs the holed frame, which differs.
    assert np.allclose(d["vbsa_recon_grid_m2"], d["vbsa_visible_m2"], rtol=0.15)
    assert not np.allclose(a["vbsa_recon_grid_m2"], d["vbsa_recon_grid_m2"], rtol=1e-6)
    # Another seed draws other holes; the ideal columns stay the same.
    assert not np.allclose(a["vbsa_hit_sensor_m2"], c["vbsa_hit_sensor_m2"])
    pd.testing.assert_series_equal(a["vbsa_visible_m2"], c["vbsa_visible_m2"])


def test_view_noise_does_not_depend_on_the_view_list(population, tmp_path):
    """A view's sensor stream is keyed by the view, so scanning fewer views gives the same rows."""
    pop_path, _ = population
    base = ["--holes", "0.3", "--out"]
    assert main(["scan", str(pop_path), "--azimuths", "0,90", *base, str(tmp_path / "a"), "--workers", "1"]) == 0
    assert main(["scan", str(pop_path), "--azimuths", "90", *base, str(tmp_path / "b"), "--workers", "1"]) == 0
    a = pd.read_parquet(tmp_path / "a" / TABLE_FILE)
    b = pd.read_parquet(tmp_path / "b" / TABLE_FILE)
    pd.testing.assert_frame_equal(a[a["azimuth_deg"] == 90].reset_index(drop=True), b)


def test_body_model_is_built_once_per_process(population, monkeypatch, tmp_path):
    import wbsa.bodies.body_model as bm

    built = []

    class Counting(bm.BodyModel):
        def __init__(self, *a, **kw):
            built.append(1)
            super().__init__(*a, **kw)

    monkeypatch.setattr(bm, "BodyModel", Counting)
    monkeypatch.setattr(worker, "_BODY_MODEL", None)
    pop_path, _ = population
    assert main(["scan", str(pop_path), "--views", "front", "--out", str(tmp_path / "o"), "--workers", "1",
                 "--chunk-size", "1"]) == 0  # three chunks
    assert len(built) == 1 and worker.body_model() is worker.body_model()


@pytest.mark.parametrize("args, message", [
    (["--camera", "kinect-v9"], "unknown camera preset 'kinect-v9'"),
    (["--views", "everything"], "views must be one of paper, sphere:N, grid:STEP, front"),
    (["--distance", "-1"], "distances_m must be positive distances in metres, got -1"),
    (["--chunk-size", "0"], "chunk_size must be at least 1"),
    (["--workers", "-1"], "workers must be 0 (all cores) or more"),
])
def test_bad_settings_are_one_line_errors(population, tmp_path, capsys, args, message):
    pop_path, _ = population
    rc = main(["scan", str(pop_path), "--out", str(tmp_path / "o"), *args])
    err = capsys.readouterr().err
    assert rc == 2 and message in err and err.count("\n") == 1 and err.startswith("error: ")


def test_not_a_population_table_is_a_one_line_error(tmp_path, capsys):
    pd.DataFrame({"subject_id": [0, 1], "height_m": [1.7, 1.8]}).to_parquet(tmp_path / "x.parquet")
    (tmp_path / "text.parquet").write_text("not parquet\n")
    for path, message in ((tmp_path / "x.parquet", "not a wbsa population table"),
                          (tmp_path / "text.parquet", "not a readable Parquet population table"),
                          (tmp_path / "missing.parquet", "does not exist")):
        rc = main(["scan", str(path), "--out", str(tmp_path / "o")])
        err = capsys.readouterr().err
        assert rc == 2 and message in err and err.count("\n") == 1


def test_resume_refuses_other_settings_on_the_cli(population, tmp_path, capsys):
    pop_path, _ = population
    assert _scan(pop_path, tmp_path / "out") == 0
    capsys.readouterr()
    assert _scan(pop_path, tmp_path / "out", "--camera", "kinect-v2") == 2
    err = capsys.readouterr().err
    assert "use another output folder" in err and err.count("\n") == 1


@pytest.mark.slow
def test_real_bodies_on_a_two_worker_cluster_equal_the_in_process_scan(population, tmp_path, dask_cluster):
    """Real anny bodies and ray casting in two dask worker processes: bit-identical to the in-process run."""
    pop_path, _ = population
    assert _scan(pop_path, tmp_path / "local", "--chunk-size", "1", azimuths="0,135", elevations="30") == 0
    assert _scan(pop_path, tmp_path / "dask", "--chunk-size", "1", "--scheduler", dask_cluster,
                 azimuths="0,135", elevations="30") == 0
    local = pd.read_parquet(tmp_path / "local" / TABLE_FILE)
    pd.testing.assert_frame_equal(local, pd.read_parquet(tmp_path / "dask" / TABLE_FILE))
    assert len(local) == 6
