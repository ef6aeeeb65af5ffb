"""The fast per-view paths of the camera: patch ROI, depth-buffer visibility, cached rotations."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("open3d")

from wbsa.camera import MeshScene, View, cast, look_at_rotation, pose_from_view, preset, render  # noqa: E402
from wbsa.camera.area import _CENTROID_T_TOL, GRAZING_COS, grazing_area_m2, triangle_view_cosines  # noqa: E402
from wbsa.camera.roi import silhouette_blocks, silhouette_pixels  # noqa: E402
from wbsa.camera.scene import _patches  # noqa: E402
from helpers.shapes import body_like, icosphere  # noqa: E402
from wbsa.core.mesh import TriangleMesh  # noqa: E402

KINECT = preset("kinect-v1")


@pytest.fixture(scope="module")
def body():
    return MeshScene(body_like())


def test_patches_hold_every_face(body):
    """Each face's three vertices are in one patch, patches have at most 6 vertices, and the table is
    a function of the topology alone."""
    faces = np.asarray(body.mesh.faces, dtype=np.int64)
    table = body._patches
    assert table.shape[0] <= 6 and table.shape[1] < 0.4 * len(faces)
    members = [set(col) for col in table.T.tolist()]
    patch_of = {}
    for j, vertices in enumerate(members):
        for v in vertices:
            patch_of.setdefault(v, set()).add(j)
    for a, b, c in faces.tolist():
        assert patch_of[a] & patch_of[b] & patch_of[c]
    again = _patches.__wrapped__(faces.tobytes(), len(body.mesh.vertices))
    np.testing.assert_array_equal(again, table)


def test_pixel_roi_holds_every_hit_and_little_else(body):
    for view in (View(0, 0, 4.3), View(60, 30, 4.3), View(135, -45, 3.0)):
        pose = pose_from_view(view, body.center)
        full = render(body, KINECT, pose, roi="full")
        hit = np.flatnonzero(full.triangle_id.reshape(-1) >= 0)
        grid = silhouette_pixels(body, KINECT, pose)
        cast_pixels = grid.image_index(KINECT.width)
        assert np.all(np.diff(cast_pixels) > 0)  # raster order
        assert np.isin(hit, cast_pixels).all()
        assert cast_pixels.size < 1.25 * hit.size  # far tighter than blocks or rectangles
        rows, cols = np.divmod(hit, KINECT.width)
        by, bx = silhouette_blocks(body, KINECT, pose)
        blocks = set(zip(by.tolist(), bx.tolist()))
        assert set(zip((rows // 8).tolist(), (cols // 8).tolist())) <= blocks


def test_pixel_roi_sees_back_faces_through_an_opening():
    """An open hemisphere seen from its open side shows its inside (back faces): the ROI still holds
    every pixel the full frame hits."""
    s = icosphere(0.3, 4)
    keep = np.flatnonzero(s.vertices[s.faces].mean(axis=1)[:, 1] > -0.1)  # cut away the side facing −Y
    scene = MeshScene(TriangleMesh(s.vertices, s.faces[keep]))
    pose = pose_from_view(View(0, 10, 1.5), np.zeros(3))
    full = render(scene, KINECT, pose, roi="full")
    roi = render(scene, KINECT, pose, roi="silhouette")
    np.testing.assert_array_equal(roi.triangle_id, full.triangle_id)
    cos_t = triangle_view_cosines(scene, pose.camera_center)
    assert np.any(cos_t[full.triangle_id[full.triangle_id >= 0]] < 0)  # back faces were hit


def _grazing_by_rays(scene, intrinsics, pose) -> float:
    """The grazing band's visible area with one occlusion ray per in-image candidate (no depth buffer)."""
    cos_t = triangle_view_cosines(scene, pose.camera_center)
    cand = np.flatnonzero((cos_t > 0) & (cos_t < GRAZING_COS))
    X = pose.apply(scene.centroids[cand])
    u = intrinsics.fx * X[:, 0] / X[:, 2] + intrinsics.skew * X[:, 1] / X[:, 2] + intrinsics.cx
    v = intrinsics.fy * X[:, 1] / X[:, 2] + intrinsics.cy
    inside = (X[:, 2] > 0) & (u >= -0.5) & (u < intrinsics.width - 0.5) & (v >= -0.5) & (v < intrinsics.height - 0.5)
    cand = cand[inside]
    rays = np.empty((cand.size, 6), dtype=np.float32)
    rays[:, :3] = pose.camera_center
    rays[:, 3:] = scene.centroids[cand] - pose.camera_center
    visible = ~scene.occluded(rays, 1.0 - _CENTROID_T_TOL)
    return float(scene.triangle_areas_m2[cand[visible]].sum())


@pytest.mark.parametrize("view", [View(0, 0, 4.3), View(60, 30, 4.3), View(90, 0, 4.3), View(150, -60, 4.3)])
def test_depth_buffer_visibility_matches_the_rays(body, view):
    """Deciding the grazing centroids from the depth already cast changes the grazing area by a hair,
    and casts far fewer visibility rays than one per candidate."""
    pose = pose_from_view(view, body.center)
    hits = cast(body, KINECT, pose)
    grid, depth = hits.depth_grid()
    cos_t = triangle_view_cosines(body, pose.camera_center)
    asked = []
    bare = body.occluded

    def counting(rays, t_far):
        asked.append(len(rays))
        return bare(rays, t_far)

    body.occluded = counting
    try:
        fast = grazing_area_m2(body, KINECT, pose, cos_t, grid, depth)
    finally:
        del body.occluded  # back to the class's method
    reference = _grazing_by_rays(body, KINECT, pose)
    n_cand = int(np.count_nonzero((cos_t > 0) & (cos_t < GRAZING_COS)))
    assert fast == pytest.approx(reference, rel=0.01)
    assert abs(fast - reference) < 2e-3 * hits.visible_area_m2(body)  # under 0.2 % of the view's visible area
    assert sum(asked) < 0.85 * n_cand


def test_look_at_rotation_is_cached_but_returns_copies():
    R = look_at_rotation(30.0, 45.0)
    R[:] = 0.0
    np.testing.assert_allclose(look_at_rotation(30.0, 45.0) @ look_at_rotation(30.0, 45.0).T, np.eye(3), atol=1e-12)
    pose = pose_from_view(View(30, 45, 2.0), np.array([0.1, 0.2, 1.0]))
    np.testing.assert_allclose(np.linalg.norm(pose.camera_center - [0.1, 0.2, 1.0]), 2.0)
