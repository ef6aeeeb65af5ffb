"""``wbsa view`` end to end on a mesh file written in the test, and its bad-input messages."""

from __future__ import annotations

import json

import numpy as np
import pytest

o3d = pytest.importorskip("open3d")

from wbsa.camera import MeshScene, View, measure_view, preset  # noqa: E402
from helpers.shapes import icosphere  # noqa: E402
from wbsa.cli import main  # noqa: E402


@pytest.fixture(scope="module")
def sphere_ply(tmp_path_factory):
    """A sphere of radius 0.3 m standing on z = 0, written as PLY."""
    s = icosphere(0.3, 4, center=np.array([0.0, 0.0, 0.3]))
    path = tmp_path_factory.mktemp("mesh") / "ball.ply"
    mesh = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(s.vertices), o3d.utility.Vector3iVector(s.faces))
    assert o3d.io.write_triangle_mesh(str(path), mesh)
    return path, s


def run(argv, capfd):
    code = main([str(a) for a in argv])
    out, err = capfd.readouterr()
    return code, out, err


def test_view_prints_json_matching_the_api(sphere_ply, capfd):
    path, mesh = sphere_ply
    code, out, err = run(["view", path, "--azimuth", "30", "--elevation", "-20", "--distance", "2", "--json"], capfd)
    assert code == 0, err
    row = json.loads(out)
    expected, _ = measure_view(MeshScene(mesh), preset("kinect-v1"), View(30, -20, 2.0), return_frame=False)
    for key in ("vbsa_hit_m2", "vbsa_visible_m2", "n_pixels", "azimuth_deg", "elevation_deg", "distance_m"):
        assert row[key] == pytest.approx(expected[key], rel=1e-6), key
    assert row["vbsa_visible_m2"] == pytest.approx(2 * np.pi * 0.09 * (1 - 0.3 / 2.0), rel=0.01)


def test_view_writes_its_files(sphere_ply, tmp_path, capfd):
    path, _ = sphere_ply
    out_dir = tmp_path / "out"
    code, out, err = run(["view", path, "--distance", "1.5", "--camera", "tum", "--out", out_dir], capfd)
    assert code == 0, err
    assert "vbsa" not in err and "visible" in out
    for name in ("depth.png", "points.ply", "visible_triangles.txt", "triangle_id.npy", "intrinsics.json",
                 "extrinsics.json", "preview.png", "view.json"):
        assert (out_dir / name).is_file(), name
    # the depth PNG is 16-bit millimetres, 0 = no return, readable by Open3D
    depth = np.asarray(o3d.io.read_image(str(out_dir / "depth.png")))
    assert depth.dtype == np.uint16 and depth.shape == (480, 640)
    ids = np.load(out_dir / "triangle_id.npy")
    np.testing.assert_array_equal(depth > 0, ids >= 0)
    front = depth[depth > 0].min() / 1000.0
    assert front == pytest.approx(1.5 - 0.3, abs=0.002)  # nearest point of the ball
    # intrinsics JSON is Open3D's own format
    k = o3d.io.read_pinhole_camera_intrinsic(str(out_dir / "intrinsics.json"))
    np.testing.assert_allclose(k.intrinsic_matrix, preset("tum").K)
    # the point cloud goes to the world frame with the stored extrinsics and lands on the sphere
    g = json.loads((out_dir / "extrinsics.json").read_text())
    cloud = np.asarray(o3d.io.read_point_cloud(str(out_dir / "points.ply")).points)
    world = cloud @ np.asarray(g["camera_to_world"])[:3, :3].T + np.asarray(g["camera_to_world"])[:3, 3]
    np.testing.assert_allclose(np.linalg.norm(world - [0, 0, 0.3], axis=1), 0.3, atol=2e-3)
    summary = json.loads((out_dir / "view.json").read_text())
    assert summary["n_pixels"] == int((ids >= 0).sum()) == len(cloud)
    visible = np.loadtxt(out_dir / "visible_triangles.txt", dtype=np.int64)
    np.testing.assert_array_equal(visible, np.unique(ids[ids >= 0]))


def test_view_several_views_and_custom_camera(sphere_ply, tmp_path, capfd):
    path, _ = sphere_ply
    # eq. 9 treats the subject as flat; a ball's limb is nearer, so it needs a margin to fit (0.08 here)
    code, out, err = run(["view", path, "--views", "paper", "--distance", "fit", "--margin", "0.1", "--width", "320",
                          "--height", "240", "--fx", "300", "--fy", "300", "--json"], capfd)
    assert code == 0, err
    rows = json.loads(out)
    assert len(rows) == 65 and all(r["camera"] == "custom" for r in rows)
    assert all(r["fits_in_frame"] for r in rows)
    code, out, err = run(["view", path, "--azimuths", "0,90", "--elevations", "60", "--out", tmp_path / "many"],
                         capfd)
    assert code == 0, err
    assert (tmp_path / "many" / "views.csv").is_file() and (tmp_path / "many" / "az90_el+60" / "depth.png").is_file()


@pytest.mark.parametrize("argv_tail, match", [
    (["--camera", "kinect-v9"], "unknown camera preset"),
    (["--fx", "-5"], "focal"),
    (["--cx", "5000"], "principal point"),
    (["--views", "papr"], "unknown view set"),
    (["--distance", "0.05"], "inside the body"),
    (["--distance", "far"], "--distance"),
    (["--azimuth", "north"], "azimuths"),
])
def test_bad_options_exit_2_with_one_line(sphere_ply, argv_tail, match, capfd):
    path, _ = sphere_ply
    code, out, err = run(["view", path, *argv_tail], capfd)
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("error: ") and match in err, err


@pytest.mark.parametrize("content, suffix, match", [
    (b"hello, not a mesh\n", ".ply", "not a readable"),
    (b"", ".obj", "not a readable"),
    (b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
     b"0 0 0\n1 0 0\n0 1 0\n", ".ply", "no triangles"),
    (b"solid x\nendsolid x\n", ".txt", "mesh file ending"),
])
def test_bad_mesh_files_exit_2_with_one_line(tmp_path, content, suffix, match, capfd):
    path = tmp_path / f"thing{suffix}"
    path.write_bytes(content)
    code, out, err = run(["view", path], capfd)
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("error: ") and match in err, err


def test_missing_mesh_file(tmp_path, capfd):
    code, out, err = run(["view", tmp_path / "nope.ply"], capfd)
    assert code == 2 and "does not exist" in err and err.count("\n") == 1
