"""``wbsa view`` on a population subject with the simulated sensor and reconstruction."""

from __future__ import annotations

import json

import pytest

from wbsa.cli import main


@pytest.fixture(scope="module")
def population(tmp_path_factory, body_model):
    path = tmp_path_factory.mktemp("pop") / "pop.parquet"
    assert main(["population", "--kind", "random", "--n", "2", "--seed", "5", "--out", str(path),
                 "--workers", "1"]) == 0
    return path


def _view(capsys, *argv) -> dict:
    assert main(["view", *argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_noisy_view_is_seeded_and_recorded(population, tmp_path, capsys):
    base = ["--population", str(population), "--subject", "1", "--noise", "nguyen2012", "--holes", "0.1"]
    a = _view(capsys, *base, "--sensor-seed", "3", "--reconstruct", "grid", "--out", str(tmp_path / "a"))
    b = _view(capsys, *base, "--sensor-seed", "3")
    c = _view(capsys, *base, "--sensor-seed", "4")
    clean = _view(capsys, "--population", str(population), "--subject", "1")
    assert a["vbsa_visible_sensor_m2"] == b["vbsa_visible_sensor_m2"] and a["n_pixels_sensor"] == b["n_pixels_sensor"]
    assert a["n_pixels_sensor"] != c["n_pixels_sensor"]
    assert a["n_pixels"] == clean["n_pixels"]  # the plain columns stay those of the ideal camera, as in wbsa scan
    assert a["n_pixels_sensor"] < 0.95 * clean["n_pixels"]  # 10 % of the visible triangles dropped, plus grazing
    assert a["sensor_noise"] == "nguyen2012" and a["sensor_holes_fraction"] == 0.1
    assert (tmp_path / "a" / "recon_grid.ply").exists()
    import open3d as o3d

    surface = o3d.io.read_triangle_mesh(str(tmp_path / "a" / "recon_grid.ply"))
    assert surface.get_surface_area() == pytest.approx(a["vbsa_recon_grid_m2"], rel=1e-6)


def test_view_needs_exactly_one_target(population, capsys, tmp_path):
    (tmp_path / "x.ply").write_text("ply\n")
    for argv in ([], ["--population", str(population), str(tmp_path / "x.ply")]):
        assert main(["view", *argv]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error:") and "\n" not in err
