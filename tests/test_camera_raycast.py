"""Ray casting and visible areas against shapes with known answers."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("open3d")

from wbsa.camera import (Intrinsics, MeshScene, View, cast, distance_to_fit, measure_view, paper_views,  # noqa: E402
                         pose_from_view, preset, render, sphere_cap_area_m2, vbsa_hit_m2, vbsa_visible_m2)
from wbsa.camera.area import triangle_view_cosines  # noqa: E402
from helpers.shapes import body_like, box, icosphere  # noqa: E402
from wbsa.errors import WbsaError  # noqa: E402
from wbsa.core.mesh import TriangleMesh  # noqa: E402

KINECT = preset("kinect-v1")


@pytest.fixture(scope="module")
def fine_sphere():
    return MeshScene(icosphere(0.3, 5))  # 20,480 triangles, area within 0.03 % of 4πr²


@pytest.fixture(scope="module")
def body():
    return MeshScene(body_like())


def front_facing_area(scene: MeshScene, camera_center) -> float:
    """Visible area of a convex mesh: the triangles that face the camera."""
    return float(scene.triangle_areas_m2[triangle_view_cosines(scene, camera_center) > 0].sum())


# ---------------------------------------------------------------- known answers

@pytest.mark.parametrize("d", [1.0, 2.0, 3.0, 4.3])
def test_sphere_cap_visible_area(fine_sphere, d):
    """A sphere of radius r seen from distance d shows a cap of area 2πr²(1 − r/d)."""
    cap = sphere_cap_area_m2(0.3, d)
    for view, offset in ((View(0, 0, d), (0.0, 0.0, 0.0)), (View(123, -37, d), (0.0, 0.0, 0.0)),
                         (View(40, 20, d), (0.18 * d, 0.0, 0.12 * d))):  # last: the sphere off-axis in the image
        target = np.asarray(offset)
        row, frame = measure_view(fine_sphere, KINECT, view, target=target)
        # the camera centre stays at distance ≈ d·|(1, offset/d)| from the sphere's centre
        dist = float(np.linalg.norm(pose_from_view(view, target).camera_center))
        expected = sphere_cap_area_m2(0.3, dist)
        assert row["vbsa_visible_m2"] == pytest.approx(expected, rel=0.01), (d, view)
        assert row["fits_in_frame"] and row["n_pixels"] > 0
        # the frame-only estimate (plain pixel footprints) falls short at the limb, but not by much
        assert 0.93 * expected < vbsa_visible_m2(frame) < 1.005 * expected
        # the frame-based and compact computations agree
        assert vbsa_visible_m2(frame, fine_sphere) == pytest.approx(row["vbsa_visible_m2"], rel=1e-5)
        assert vbsa_hit_m2(frame, fine_sphere) == pytest.approx(row["vbsa_hit_m2"], rel=1e-12)
    assert cap < 2 * np.pi * 0.3**2


def test_coarse_sphere_hit_area_is_the_front_facing_triangles():
    """With triangles much larger than pixels every front-facing triangle is hit, and no other."""
    scene = MeshScene(icosphere(0.5, 2))  # 320 triangles
    view = View(20, 10, 1.5)
    pose = pose_from_view(view, np.zeros(3))
    frame = render(scene, KINECT, pose)
    hit = np.unique(frame.triangle_id[frame.triangle_id >= 0])
    front = np.flatnonzero(triangle_view_cosines(scene, pose.camera_center) > 0)
    assert set(hit) <= set(front)
    assert vbsa_hit_m2(frame, scene) >= 0.97 * front_facing_area(scene, pose.camera_center)
    assert vbsa_visible_m2(frame, scene) == pytest.approx(front_facing_area(scene, pose.camera_center), rel=0.01)


@pytest.mark.parametrize("camera", ["kinect-v1", "kinect-v2"])
def test_cube_face_on_shows_exactly_one_face(camera):
    scene = MeshScene(box((1.0, 1.0, 1.0)))  # 2 triangles per face
    k = preset(camera)
    row, frame = measure_view(scene, k, View(0, 0, 2.5), target=np.zeros(3))
    hit = np.unique(frame.triangle_id[frame.triangle_id >= 0])
    normals = scene.face_normals[hit]
    np.testing.assert_allclose(normals, [[0, -1, 0]] * len(hit), atol=1e-12)  # only the face towards −Y
    assert row["vbsa_hit_m2"] == pytest.approx(1.0, rel=1e-12)
    assert row["vbsa_visible_m2"] == pytest.approx(1.0, rel=0.01)
    # the face at depth 2.0 m: every hit pixel's z-depth is 2.0 (planar face parallel to the image)
    np.testing.assert_allclose(frame.depth_m[frame.depth_m > 0], 2.0, rtol=1e-6)


def test_visible_area_does_not_depend_on_resolution(body):
    """The paper's hit area grows with resolution; the visible-area estimate stays put."""
    view = View(30, 0, 4.3)
    hits, visible = [], []
    for scale in (1, 2, 4):
        row, _ = measure_view(body, KINECT.scaled(scale), view, return_frame=False)
        hits.append(row["vbsa_hit_m2"])
        visible.append(row["vbsa_visible_m2"])
    assert hits[0] < 0.8 * hits[2]
    assert max(visible) / min(visible) < 1.01


# ---------------------------------------------------------------- ROI == full frame

@pytest.mark.parametrize("k", [
    KINECT, preset("kinect-v2"),
    Intrinsics(100, 75, 90.0, 95.0, 47.0, 40.0, skew=3.0),  # not a multiple of the block size, with skew
])
def test_roi_gives_exactly_the_full_frame(body, k):
    views = paper_views()[::7] + [View(10, 5, 1.2), View(200, -20, 2.0)]
    for view in views:
        pose = pose_from_view(view, body.center)
        full = render(body, k, pose, roi="full")
        for mode in ("silhouette", "bbox"):
            frame = render(body, k, pose, roi=mode)
            np.testing.assert_array_equal(frame.triangle_id, full.triangle_id)
            np.testing.assert_array_equal(frame.depth_m, full.depth_m)
        rows = [measure_view(body, k, view, roi=mode, return_frame=False)[0] for mode in ("silhouette", "full")]
        a, b = rows
        assert a.pop("vbsa_visible_m2") == pytest.approx(b.pop("vbsa_visible_m2"), rel=1e-12)  # summation order
        assert a == b
    # and the silhouette casts far fewer rays than the full frame at the paper's distance
    pose = pose_from_view(View(0, 0, 4.3), body.center)
    assert cast(body, KINECT, pose).n_rays < 0.1 * KINECT.width * KINECT.height


def test_depth_frame_contract(body):
    k = Intrinsics(320, 240, 300.0, 290.0, 150.0, 130.0, skew=2.0)
    row, frame = measure_view(body, k, View(60, 30, 3.0))
    valid = frame.depth_m > 0
    assert frame.depth_m.dtype == np.float32 and frame.points_cam.shape == (240, 320, 3)
    assert frame.triangle_id.dtype == np.int64
    np.testing.assert_array_equal(valid, frame.triangle_id >= 0)
    assert np.all(np.isnan(frame.points_cam[~valid])) and np.all(np.isnan(frame.normals_cam[~valid]))
    assert row["n_pixels"] == frame.n_pixels == int(valid.sum())
    # points project back onto their own pixels through K (skew included) and have z = depth
    v, u = np.nonzero(valid)
    p = frame.points_cam[valid].astype(np.float64)
    uvw = p @ k.K.T
    np.testing.assert_allclose(uvw[:, 0] / uvw[:, 2], u, atol=2e-3)
    np.testing.assert_allclose(uvw[:, 1] / uvw[:, 2], v, atol=2e-3)
    np.testing.assert_allclose(p[:, 2], frame.depth_m[valid], rtol=1e-6)
    # normals are unit and face the camera
    n = frame.normals_cam[valid]
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-5)
    assert np.all(np.einsum("ij,ij->i", n, p) < 0)
    # back to the world: the hit points lie on the mesh's hit triangles' planes
    world = frame.pose.inverse().apply(p)
    tri = frame.triangle_id[valid]
    a = body.mesh.vertices[body.mesh.faces[tri, 0]]
    dist = np.abs(np.einsum("ij,ij->i", world - a, body.face_normals[tri]))
    assert dist.max() < 1e-4


def test_subjects_left_appears_on_the_image_right():
    left_ball = icosphere(0.1, 2, center=np.array([0.5, 0.0, 1.0]))
    right_ball = icosphere(0.2, 2, center=np.array([-0.5, 0.0, 1.0]))
    scene = MeshScene(TriangleMesh(np.vstack([left_ball.vertices, right_ball.vertices]),
                                   np.vstack([left_ball.faces, right_ball.faces + len(left_ball.vertices)])))
    frame = render(scene, KINECT, pose_from_view(View(0, 0, 3.0), scene.center))
    cols_small = np.nonzero(np.isin(frame.triangle_id, np.arange(len(left_ball.faces))))[1]
    cols_big = np.nonzero(frame.triangle_id >= len(left_ball.faces))[1]
    assert cols_small.min() > KINECT.cx > cols_big.max()


# ---------------------------------------------------------------- distance helper, edge cases

def test_distance_to_fit_frames_a_standing_box():
    stature = 1.9
    scene = MeshScene(box((0.3, 0.2, stature), center=np.array([0, 0, stature / 2]), subdivisions=3))
    d = distance_to_fit(stature, KINECT, margin=0.05)
    row, _ = measure_view(scene, KINECT, View(0, 0, d), return_frame=False)
    assert row["fits_in_frame"]
    row, _ = measure_view(scene, KINECT, View(0, 0, 0.9 * d), return_frame=False)
    assert not row["fits_in_frame"]


def test_a_view_that_sees_nothing_is_a_valid_result(fine_sphere):
    # aim far to the side: the sphere falls outside the image
    row, frame = measure_view(fine_sphere, KINECT, View(0, 0, 2.0), target=np.array([5.0, 0.0, 0.0]))
    assert row["n_pixels"] == 0 and row["vbsa_hit_m2"] == 0.0 and row["vbsa_visible_m2"] == 0.0
    assert row["fits_in_frame"] and frame.n_pixels == 0
    assert vbsa_visible_m2(frame) == 0.0 and vbsa_visible_m2(frame, fine_sphere) == 0.0


def test_camera_inside_the_body_is_refused(fine_sphere):
    with pytest.raises(WbsaError, match="inside the body"):
        measure_view(fine_sphere, KINECT, View(0, 0, 0.1))


@pytest.mark.parametrize("mesh, match", [
    (TriangleMesh(np.zeros((0, 3)), np.zeros((0, 3), np.int32)), "no vertices"),
    (TriangleMesh(np.eye(3), np.zeros((0, 3), np.int32)), "no triangles"),
    (TriangleMesh(np.eye(3), np.array([[0, 1, 5]], np.int32)), "outside"),
    (TriangleMesh(np.array([[0, 0, 0], [1, 0, 0], [np.nan, 0, 0]]), np.array([[0, 1, 2]], np.int32)), "non-finite"),
    (TriangleMesh(np.zeros((3, 3)), np.array([[0, 1, 2]], np.int32)), "zero surface area"),
])
def test_bad_meshes_are_refused(mesh, match):
    with pytest.raises(WbsaError, match=match):
        MeshScene(mesh)


def test_orientation_does_not_change_the_answer():
    """Inward-wound or open meshes give the same areas (the grazing test then checks back faces too)."""
    s = icosphere(0.3, 4)
    out = MeshScene(s)
    inward = MeshScene(TriangleMesh(s.vertices, s.faces[:, ::-1].copy()))
    assert out.one_sided and inward.one_sided
    view = View(10, 10, 2.0)
    a = measure_view(out, KINECT, view, target=np.zeros(3), return_frame=False)[0]
    b = measure_view(inward, KINECT, view, target=np.zeros(3), return_frame=False)[0]
    assert a["vbsa_visible_m2"] == pytest.approx(b["vbsa_visible_m2"], rel=1e-6)
    hemi = np.flatnonzero(s.vertices[s.faces].mean(axis=1)[:, 1] < 0.05)  # the half towards the camera, open
    open_scene = MeshScene(TriangleMesh(s.vertices, s.faces[hemi]))
    assert not open_scene.one_sided
    c = measure_view(open_scene, KINECT, view, target=np.zeros(3), return_frame=False)[0]
    assert c["vbsa_visible_m2"] == pytest.approx(a["vbsa_visible_m2"], rel=0.01)


def test_meshes_scenes_and_frames_print_their_key_numbers(body):
    mesh = box((0.4, 0.3, 1.8))
    # 4 vertices per face; area 2(ab + bc + ca) = 2.76 m²
    assert repr(mesh) == "TriangleMesh(24 vertices, 12 faces, area 2.76 m², bbox 0.4 × 0.3 × 1.8 m)"
    scene = MeshScene(icosphere(0.3, 2, center=np.array([0.0, 0.0, 1.0])))
    assert repr(scene).startswith("MeshScene(320 triangles, area 1.1")  # 4π·0.3² = 1.131 m², a bit less inscribed
    assert "bbox 0.6 × 0.6 × 0.6 m around (0, 0, 1) m, one-sided" in repr(scene)
    k = Intrinsics(320, 240, 300.0, 290.0, 150.0, 130.0)
    frame = measure_view(body, k, View(0, 0, 3.0))[1]
    valid = frame.depth_m[frame.depth_m > 0]
    assert repr(frame) == (f"DepthFrame(320×240 px, {valid.size:,} returns, "
                           f"depth {valid.min():.3f}–{valid.max():.3f} m, camera custom)")
    assert len(repr(body)) < 200 and len(repr(body.mesh)) < 200
