"""Camera model: intrinsics, views, poses, the eq. 9 distance helper (no ray casting here)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from wbsa.camera import (Intrinsics, Pose, View, distance_to_fit, max_stature_m, paper_views, parse_views,
                         pose_from_view, preset, resolve_camera, vertical_half_fov_deg)
from wbsa.camera.views import grid_views, normalise_angles, sphere_views
from wbsa.errors import WbsaError


# ---------------------------------------------------------------- intrinsics

def test_presets_match_published_values():
    k1 = preset("kinect-v1")
    assert (k1.width, k1.height, k1.fx, k1.fy, k1.cx, k1.cy) == (640, 480, 575.8157, 575.8157, 314.5, 235.5)
    assert preset("tum").fx == 525.0 and preset("tum").cx == 319.5
    k2 = preset("kinect-v2")
    assert (k2.width, k2.height, k2.fx, k2.cy) == (512, 424, 365.456, 205.395)
    # published (rounded) fields of view: Kinect v1 58.5° x 45.6°, Kinect v2 70.6° x 60°
    h1, v1 = k1.fov_deg
    h2, v2 = k2.fov_deg
    assert h1 == pytest.approx(58.5, abs=1.0) and v1 == pytest.approx(45.6, abs=1.0)
    assert h2 == pytest.approx(70.6, abs=1.0) and v2 == pytest.approx(60.0, abs=1.0)
    np.testing.assert_array_equal(k1.K, [[575.8157, 0, 314.5], [0, 575.8157, 235.5], [0, 0, 1]])


def test_intrinsics_json_round_trip_through_open3d(tmp_path):
    o3d = pytest.importorskip("open3d")
    k = Intrinsics(800, 600, 612.5, 610.25, 401.0, 297.5, skew=1.5, name="mine", min_range_m=0.3, max_range_m=6.0)
    # ours -> Open3D
    path = tmp_path / "ours.json"
    path.write_text(json.dumps(k.to_open3d_json()))
    o3d_k = o3d.io.read_pinhole_camera_intrinsic(str(path))
    assert (o3d_k.width, o3d_k.height) == (800, 600)
    np.testing.assert_allclose(o3d_k.intrinsic_matrix, k.K)
    # Open3D -> ours
    other = o3d.camera.PinholeCameraIntrinsic(320, 240, 300.0, 301.0, 159.5, 119.5)
    o3d.io.write_pinhole_camera_intrinsic(str(tmp_path / "o3d.json"), other)
    back = Intrinsics.from_open3d_json(tmp_path / "o3d.json")
    np.testing.assert_allclose(back.K, other.intrinsic_matrix)
    assert (back.width, back.height) == (320, 240)
    # and our own extras survive our own round trip
    assert Intrinsics.from_open3d_json(k.to_open3d_json()) == k
    assert resolve_camera(path) == k


def test_scaled_keeps_field_of_view():
    k = preset("kinect-v1")
    k4 = k.scaled(4)
    assert (k4.width, k4.height) == (2560, 1920)
    assert k4.fov_deg == pytest.approx(k.fov_deg, abs=1e-9)
    # the principal ray stays the same: pixel centre cx maps to the same direction
    assert (k4.cx + 0.5) / 4 - 0.5 == pytest.approx(k.cx)


@pytest.mark.parametrize("kwargs, match", [
    (dict(fx=0.0), "focal"), (dict(fy=-3.0), "focal"), (dict(cx=700.0), "principal point"),
    (dict(cy=-1.0), "principal point"), (dict(width=0), "width"), (dict(height=2.5), "height"),
    (dict(min_range_m=5.0, max_range_m=1.0), "range"),
])
def test_invalid_intrinsics_are_refused(kwargs, match):
    base = dict(width=640, height=480, fx=500.0, fy=500.0, cx=319.5, cy=239.5)
    base.update(kwargs)
    with pytest.raises(WbsaError, match=match):
        Intrinsics(**base)


def test_unknown_preset_and_bad_json(tmp_path):
    with pytest.raises(WbsaError, match="unknown camera preset"):
        resolve_camera("kinect-v9")
    bad = tmp_path / "cam.json"
    bad.write_text("{not json")
    with pytest.raises(WbsaError, match="not readable"):
        resolve_camera(bad)
    bad.write_text(json.dumps({"width": 10, "height": 10}))
    with pytest.raises(WbsaError, match="intrinsic_matrix"):
        resolve_camera(bad)
    with pytest.raises(WbsaError, match="does not exist"):
        resolve_camera(tmp_path / "missing.json")


# ---------------------------------------------------------------- views

def test_paper_views_are_the_65_of_the_paper():
    views = paper_views()
    assert len(views) == 65
    assert len({(v.azimuth_deg, v.elevation_deg) for v in views}) == 65
    assert {v.azimuth_deg for v in views} == {0, 30, 45, 60, 90, 120, 135, 150, 180}
    assert {v.elevation_deg for v in views} == {0, 30, -30, 45, -45, 60, -60, 90, -90}
    poles = [v for v in views if abs(v.elevation_deg) == 90]
    assert [(v.azimuth_deg, v.elevation_deg) for v in poles] == [(0, 90), (0, -90)]
    assert all(v.distance_m == 4.3 for v in views)
    assert len(parse_views("paper", distance_m=3.5)) == 65


def test_angles_are_normalised():
    assert normalise_angles(-30, 0) == (330.0, 0.0)
    assert normalise_angles(720, -0.0) == (0.0, 0.0)
    assert normalise_angles(10, 120) == (190.0, 60.0)  # over the top: behind, looking down
    assert normalise_angles(10, -100) == (190.0, -80.0)
    assert normalise_angles(0, 450) == (0.0, 90.0)
    assert View(10, 120, 2.0) == View(190, 60, 2.0)
    # the same camera position either way
    np.testing.assert_allclose(View(10, 120).direction, View(190, 60).direction, atol=1e-12)


def test_parse_views_lists_ranges_and_dense_grids():
    views = parse_views(azimuths="0,30,90", elevations="0,45")
    assert [(v.azimuth_deg, v.elevation_deg) for v in views] == [(0, 0), (30, 0), (90, 0), (0, 45), (30, 45), (90, 45)]
    assert [v.azimuth_deg for v in parse_views(azimuths="0:180:45")] == [0, 45, 90, 135, 180]
    assert [v.azimuth_deg for v in parse_views(azimuths="-90, 270")] == [270]  # duplicates dropped
    sphere = sphere_views(200)
    assert len(sphere) == 200 == len(parse_views("sphere:200"))
    dirs = np.array([v.direction for v in sphere])
    assert np.linalg.norm(dirs.mean(axis=0)) < 0.01  # spread evenly over the sphere
    grid = grid_views(30)
    assert len(grid) == 12 * 5 + 2 == len(parse_views("grid:30"))


@pytest.mark.parametrize("spec, kw, match", [
    ("paperz", {}, "unknown view set"), ("sphere:0", {}, "N >= 1"), ("grid:0", {}, "STEP"),
    (None, dict(azimuths="a,b"), "cannot read azimuths"), ("paper", dict(azimuths="0"), "not both"),
])
def test_bad_view_specs(spec, kw, match):
    with pytest.raises(WbsaError, match=match):
        parse_views(spec, **kw)


def test_bad_distance():
    for d in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(WbsaError, match="distance"):
            View(0, 0, d)


# ---------------------------------------------------------------- poses

def test_azimuth_elevation_convention():
    target = np.array([0.1, -0.2, 0.9])
    front = pose_from_view(View(0, 0, 4.3), target)
    np.testing.assert_allclose(front.camera_center, target + [0, -4.3, 0], atol=1e-12)
    np.testing.assert_allclose(front.R[2], [0, 1, 0], atol=1e-12)  # looks along +Y
    np.testing.assert_allclose(front.R[0], [1, 0, 0], atol=1e-12)  # image right = subject's left (+X)
    np.testing.assert_allclose(front.R[1], [0, 0, -1], atol=1e-12)  # image down = world down
    left = pose_from_view(View(90, 0, 2.0), target)
    np.testing.assert_allclose(left.camera_center, target + [2, 0, 0], atol=1e-12)
    back = pose_from_view(View(180, 0, 2.0), target)
    np.testing.assert_allclose(back.camera_center, target + [0, 2, 0], atol=1e-12)
    above = pose_from_view(View(0, 90, 3.0), target)
    np.testing.assert_allclose(above.camera_center, target + [0, 0, 3], atol=1e-12)
    np.testing.assert_allclose(above.R[2], [0, 0, -1], atol=1e-12)  # looks straight down
    np.testing.assert_allclose(above.R[1], [0, -1, 0], atol=1e-12)  # image up = +Y (the limit from φ < 90°)
    near_pole = pose_from_view(View(0, 89.999, 3.0), target)
    np.testing.assert_allclose(near_pole.R, above.R, atol=1e-4)  # continuous at the pole
    below = pose_from_view(View(0, -90, 3.0), target)
    np.testing.assert_allclose(below.R[2], [0, 0, 1], atol=1e-12)


@pytest.mark.parametrize("az, el", [(0, 0), (37, 21), (135, -60), (300, 90), (0, -90), (181, 89.5)])
def test_pose_round_trip_and_rotation(az, el):
    rng = np.random.default_rng(1)
    target = rng.normal(size=3)
    pose = pose_from_view(View(az, el, 3.3), target)
    R = pose.R
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0)
    world = rng.normal(size=(50, 3))
    cam = pose.apply(world)
    np.testing.assert_allclose(pose.inverse().apply(cam), world, atol=1e-12)
    np.testing.assert_allclose(pose.matrix @ pose.inverse().matrix, np.eye(4), atol=1e-12)
    # the target lies on the optical axis at depth D
    np.testing.assert_allclose(pose.apply(target), [0, 0, 3.3], atol=1e-12)
    back = Pose.from_dict(json.loads(json.dumps(pose.to_dict())))
    np.testing.assert_allclose(back.matrix, pose.matrix)


# ---------------------------------------------------------------- eq. 9

def test_distance_to_fit_is_eq9_with_the_half_angle():
    k = preset("kinect-v1")
    half = vertical_half_fov_deg(k)
    assert half == pytest.approx(math.degrees(math.atan(236 / 575.8157)))  # top edge, the tighter half
    assert distance_to_fit(1.8, k, margin=0.0) == pytest.approx(1.8 / (2 * math.tan(math.radians(half))))
    assert distance_to_fit(1.8, k, margin=0.1) == pytest.approx(1.1 * distance_to_fit(1.8, k, margin=0.0))
    assert max_stature_m(distance_to_fit(2.1, k, margin=0.0), k) == pytest.approx(2.1)
    # the paper's 4.3 m with the Kinect v1 fits a 3.52 m subject with the half-angle reading of eq. 9
    assert max_stature_m(4.3, k) == pytest.approx(3.5247, abs=1e-3)
    with pytest.raises(WbsaError):
        distance_to_fit(0.0, k)
