"""The ray-casting back ends: one interface, the same rows (Warp on the CPU against the Open3D reference)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("open3d")
pytest.importorskip("warp")

from wbsa.camera import Intrinsics, MeshScene, View, measure_view, paper_views, pose_from_view, preset  # noqa: E402
from wbsa.camera.backends import check_backend, get_backend, resolve_backend  # noqa: E402
from wbsa.camera.backends import measure_views  # noqa: E402
from helpers.reference import coarse_scenes, monte_carlo_visible_area_m2, scene_mesh  # noqa: E402
from helpers.shapes import body_like, icosphere  # noqa: E402
from wbsa.errors import WbsaError  # noqa: E402
from wbsa.core.mesh import TriangleMesh  # noqa: E402

KINECT = preset("kinect-v1")


@pytest.fixture(scope="module")
def body():
    return MeshScene(body_like(), nthreads=1)


@pytest.fixture(scope="module")
def warp():
    backend = get_backend("warp")
    assert backend.device == "cpu"  # no GPU on the test machines: the CPU path is what is tested
    return backend


def compare(a: list, b: list) -> dict:
    """Largest differences between two lists of rows."""
    rel = [rb["vbsa_visible_m2"] / ra["vbsa_visible_m2"] - 1 for ra, rb in zip(a, b) if ra["vbsa_visible_m2"] > 0]
    return {
        "visible_max": max((abs(x) for x in rel), default=0.0),
        "visible_mean": float(np.mean(np.abs(rel))) if rel else 0.0,
        "pixels": max(abs(ra["n_pixels"] - rb["n_pixels"]) for ra, rb in zip(a, b)),
        "triangles": max(abs(ra["n_triangles_hit"] - rb["n_triangles_hit"]) for ra, rb in zip(a, b)),
        "hit": max(abs(rb["vbsa_hit_m2"] - ra["vbsa_hit_m2"]) for ra, rb in zip(a, b)),
        "fits": sum(ra["fits_in_frame"] != rb["fits_in_frame"] for ra, rb in zip(a, b)),
        "keys": all(list(ra) == list(rb) for ra, rb in zip(a, b)),
    }


@pytest.mark.parametrize("k", [KINECT, preset("kinect-v2"), Intrinsics(320, 240, 300.0, 290.0, 150.0, 130.0, skew=2.0)])
def test_warp_rows_match_open3d(body, warp, k):
    """Every view's row within float32 rounding: the rasterizer and Embree disagree only about pixel
    centres on a shared edge (a pixel on a grazing/non-grazing edge moves the visible area by ~2e-4)."""
    views = list(paper_views())[::3] + [View(10, 5, 1.6), View(200, -20, 2.0), View(0, 0, 1.2)]  # last: cut by the frame
    ref = [r for r, _ in measure_views(body, k, views, backend="open3d", return_frames=False)]
    got = [r for r, _ in measure_views(body, k, views, backend="warp", return_frames=False)]
    d = compare(ref, got)
    assert d["keys"] and d["fits"] == 0
    assert d["visible_max"] < 3e-4 and d["visible_mean"] < 3e-5, d
    assert d["pixels"] <= 2 and d["triangles"] <= 2, d  # pixel centres exactly on a silhouette edge
    assert d["hit"] <= 2 * body.triangle_areas_m2.max(), d
    assert [r["azimuth_deg"] for r in got] == [v.azimuth_deg for v in views]


def test_warp_frames_match_open3d(body, warp):
    for view in (View(30, 20, 4.3), View(90, 0, 2.0)):
        (r1, f1), = measure_views(body, KINECT, [view], backend="open3d")
        (r2, f2), = measure_views(body, KINECT, [view], backend="warp")
        same = f1.triangle_id == f2.triangle_id
        assert np.count_nonzero(~same) <= 3
        both = (f1.depth_m > 0) & (f2.depth_m > 0)
        np.testing.assert_allclose(f2.depth_m[both], f1.depth_m[both], rtol=1e-5)
        np.testing.assert_allclose(f2.points_cam[same & both], f1.points_cam[same & both], rtol=1e-5, atol=1e-6)
        np.testing.assert_allclose(f2.normals_cam[same & both], f1.normals_cam[same & both], atol=2e-4)  # float32 normals
        assert f2.settings["azimuth_deg"] == view.azimuth_deg and f2.n_pixels == r2["n_pixels"]


def test_back_faces_seen_through_a_hole(warp, monkeypatch):
    """Back faces are rasterized only near holes of a closed surface; a sphere with a hole shows its inside."""
    sphere = icosphere(0.5, 4)
    keep = np.ones(len(sphere.faces), dtype=bool)
    centroids = sphere.vertices[sphere.faces].mean(axis=1)
    keep[np.argsort(centroids[:, 1])[:12]] = False  # a hole facing −Y (the camera at azimuth 0)
    scene = MeshScene(TriangleMesh(sphere.vertices, sphere.faces[keep]))
    assert scene.one_sided
    views = [View(0, 0, 2.0), View(10, 5, 1.5), View(180, 0, 2.0)]
    ref = [r for r, _ in measure_views(scene, KINECT, views, backend="open3d", return_frames=False)]
    got = [r for r, _ in measure_views(scene, KINECT, views, backend="warp", return_frames=False)]
    import wbsa.camera.backends.warp_backend as wb

    monkeypatch.setattr(wb, "CULL_BACK_FACES", False)
    full = [r for r, _ in measure_views(scene, KINECT, views, backend="warp", return_frames=False)]
    assert got == full  # skipping back faces away from the hole changes nothing
    d = compare(ref, got)
    assert d["pixels"] <= 1 and d["visible_max"] < 3e-4, d
    (row, frame), = measure_views(scene, KINECT, views[:1], backend="warp")
    inside = scene.face_normals[frame.triangle_id[frame.triangle_id >= 0]] @ pose_from_view(views[0], scene.center).R[2]
    assert np.count_nonzero(inside > 0) > 50  # pixels on inner (back) faces, seen through the hole


def test_coarse_scene_with_warp():
    solids = coarse_scenes()["thin wall"]
    scene = MeshScene(scene_mesh(solids))
    views = [View(86, 5, 4.3), View(88, 5, 4.3), View(30, 20, 4.3)]
    ref = [r for r, _ in measure_views(scene, KINECT, views, backend="open3d", return_frames=False)]
    got = [r for r, _ in measure_views(scene, KINECT, views, backend="warp", return_frames=False)]
    for view, a, b in zip(views, ref, got):
        truth, _ = monte_carlo_visible_area_m2(solids, KINECT, pose_from_view(view, scene.center), 200_000)
        assert b["vbsa_visible_m2"] == pytest.approx(truth, rel=0.01)
        assert b["vbsa_visible_m2"] == pytest.approx(a["vbsa_visible_m2"], rel=2e-3)


def test_views_with_the_mesh_behind_the_camera_fall_back_to_open3d(warp):
    """A vertex at or behind the camera plane cannot be rasterized: such views are the reference's rows."""
    wall = MeshScene(TriangleMesh(np.array([[-5.0, 0, -5], [5, 0, -5], [5, 0, 5], [-5, 0, 5]]),
                                  np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32)))
    views = [View(80, 0, 1.0), View(0, 0, 3.0)]
    ref = [r for r, _ in measure_views(wall, KINECT, views, backend="open3d", return_frames=False)]
    got = [r for r, _ in measure_views(wall, KINECT, views, backend="warp", return_frames=False)]
    assert got[0] == ref[0]
    assert compare(ref[1:], got[1:])["visible_max"] < 1e-5


def test_camera_inside_is_refused_by_both(warp):
    scene = MeshScene(icosphere(0.3, 3))
    for backend in ("open3d", "warp"):
        with pytest.raises(WbsaError, match="inside the body"):
            measure_views(scene, KINECT, [View(0, 0, 0.1)], target=np.zeros(3), backend=backend)


def test_open3d_backend_is_measure_view_bit_for_bit(body):
    views = list(paper_views())[::9]
    rows = measure_views(body, KINECT, views, backend="open3d", return_frames=False)
    assert [r for r, _ in rows] == [measure_view(body, KINECT, v, return_frame=False)[0] for v in views]


def test_backend_names():
    assert resolve_backend("open3d") == "open3d" and resolve_backend("warp") == "warp"
    assert resolve_backend("auto") in ("open3d", "warp")
    with pytest.raises(WbsaError, match="backend must be one of auto, open3d, warp"):
        check_backend("embree")


def test_warp_bvh_anyhit_path(body, warp, monkeypatch):
    """The GPU's way of answering the grazing points' rays (Warp's BVH), run on the CPU: the same rows up to
    a rare point that Embree and Warp decide differently (float32 rays grazing a triangle edge)."""
    import wbsa.camera.backends.warp_backend as wb

    views = list(paper_views())[::5]
    embree = [r for r, _ in measure_views(body, KINECT, views, backend="warp", return_frames=False)]
    monkeypatch.setattr(wb, "ANYHIT", "warp")
    bvh = [r for r, _ in measure_views(body, KINECT, views, backend="warp", return_frames=False)]
    d = compare(embree, bvh)
    assert d["pixels"] == 0 and d["triangles"] == 0 and d["visible_max"] < 3e-4, d


@pytest.mark.slow
def test_warp_kernels_compile_for_cuda(tmp_path):
    """No GPU here: at least the kernels must compile for one (PTX for sm_80 and sm_90 through NVRTC)."""
    import wbsa.camera.backends.warp_backend as wb
    from wbsa.camera.backends import warp_kernels

    wp = wb.warp_module()
    try:
        paths = wp.compile_aot_module(warp_kernels, arch=[80, 90], module_dir=tmp_path, use_ptx=True)
    except Exception as exc:  # noqa: BLE001 - no NVRTC in this Warp build
        pytest.skip(f"cannot compile CUDA code here: {exc}")
    assert len(paths) == 2 and all(p.stat().st_size > 10_000 for p in paths)
