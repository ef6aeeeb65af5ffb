"""The plain renderer and the seen surface: the same geometry as the project's renderer, and an area that
holes, dropped returns and noise hardly move."""

from __future__ import annotations

import numpy as np
import pytest

from wbsa.camera import MeshScene, View, preset, render
from wbsa.camera.extrinsics import pose_from_view
from wbsa.estimation.subject.seen_surface import MAX_INCIDENCE_DEG, fill_gaps, seen_surface
from wbsa.testing.plain_render import level_camera, plain_depth, plain_noise_sigma_m
from helpers.shapes import box, icosphere

KINECT_V2 = preset("kinect-v2")


def plain(mesh, pose, camera=KINECT_V2, rng=None):
    return plain_depth(mesh.vertices, mesh.faces, width=camera.width, height=camera.height, fx=camera.fx,
                       fy=camera.fy, cx=camera.cx, cy=camera.cy, rotation=pose.R, center_m=pose.camera_center, rng=rng)


@pytest.fixture(scope="module")
def sphere():
    return icosphere(0.3, 5)


@pytest.fixture(scope="module")
def sphere_pose():
    return pose_from_view(View(20.0, 10.0, 2.0), np.zeros(3))


def test_plain_renderer_sees_what_the_project_renderer_sees(sphere, sphere_pose):
    """Same mesh, camera and pose: the same pixels, the same depth to the millimetre (noise off)."""
    ours = render(MeshScene(sphere), KINECT_V2, sphere_pose)
    depth, tri = plain(sphere, sphere_pose)
    seen_ours, seen_plain = ours.depth_m > 0, depth > 0
    assert (seen_ours != seen_plain).sum() <= 0.003 * seen_ours.sum()
    both = seen_ours & seen_plain
    assert np.abs(depth[both] - ours.depth_m[both]).max() <= 0.0005 + 1e-9
    assert np.all(tri[seen_plain] >= 0) and np.all(tri[~seen_plain] == -1)


def test_plain_noise_has_its_own_sigma():
    """A wall facing a level camera 2 m away reads z = 2 m with σ = 1.2 mm + 1.9 mm·(z − 0.4)²."""
    wall = box((0.01, 3.0, 3.0), center=np.array([0.0, 0.0, 1.5]))
    rotation, center = level_camera(np.zeros(3), np.array([-1.0, 0.0, 0.0]), 2.005, 1.0)
    clean, _ = plain_depth(wall.vertices, wall.faces, width=64, height=48, fx=60.0, fy=60.0, cx=31.5, cy=23.5,
                           rotation=rotation, center_m=center, rng=None)
    noisy, _ = plain_depth(wall.vertices, wall.faces, width=64, height=48, fx=60.0, fy=60.0, cx=31.5, cy=23.5,
                           rotation=rotation, center_m=center, rng=np.random.default_rng(3))
    assert np.all(clean == 2.0)
    assert np.allclose(noisy * 1000, np.round(noisy * 1000), atol=1e-6)  # whole millimetres
    assert np.std(noisy - clean) == pytest.approx(plain_noise_sigma_m(2.0), rel=0.06)


def _wall(tilt_deg: float, distance_m: float = 2.0):
    """A 1 m × 1 m wall ``distance_m`` in front of a level camera, turned ``tilt_deg`` about the vertical."""
    from wbsa.training.room import tiled_rectangle

    t = np.radians(tilt_deg)
    u = np.array([np.cos(t), np.sin(t), 0.0])
    mesh = tiled_rectangle(np.array([0.0, distance_m, 1.0]) - 0.5 * u - np.array([0, 0, 0.5]), u,
                           np.array([0.0, 0.0, 1.0]), tile_m=0.05)
    rotation, center = level_camera(np.array([0.0, distance_m, 1.0]), np.array([0.0, -1.0, 0.0]), distance_m, 1.0)
    return mesh, rotation, center


@pytest.mark.parametrize("tilt_deg, tolerance", [(0.0, 0.01), (MAX_INCIDENCE_DEG - 5.0, 0.02)])
def test_seen_area_of_a_wall_is_its_area(tilt_deg, tolerance):
    """A 1 m² wall, facing the camera or turned to 5° inside the cap, reads 1 m²."""
    mesh, rotation, center = _wall(tilt_deg)
    depth, tri = plain_depth(mesh.vertices, mesh.faces, width=KINECT_V2.width, height=KINECT_V2.height,
                             fx=KINECT_V2.fx, fy=KINECT_V2.fy, cx=KINECT_V2.cx, cy=KINECT_V2.cy, rotation=rotation,
                             center_m=center, rng=None)
    assert seen_surface(depth, depth > 0, KINECT_V2).area_m2 == pytest.approx(1.0, rel=tolerance)


def test_seen_area_does_not_follow_dropped_returns(sphere, sphere_pose):
    """3 % of the returns dropped at random: the grid's area loses more than 3 %, the seen area under 0.5 %."""
    from wbsa.core.backproject import frame_from_depth_image
    from wbsa.surface import reconstruct

    depth, _ = plain(sphere, sphere_pose)
    mask = depth > 0
    dropped = mask & (np.random.default_rng(0).random(mask.shape) >= 0.03)
    grid = [reconstruct(frame_from_depth_image(np.where(m, depth, 0.0), KINECT_V2, normals=False)).area_m2
            for m in (mask, dropped)]
    seen = [seen_surface(depth, m, KINECT_V2).area_m2 for m in (mask, dropped)]
    assert grid[1] / grid[0] - 1 < -0.03
    assert abs(seen[1] / seen[0] - 1) < 0.005


def test_seen_area_does_not_follow_the_noise(sphere, sphere_pose):
    """The plain renderer's noise at 2 m (about 6 mm, 1.1 pixel pitches): the seen area moves under 1.5 %."""
    clean, _ = plain(sphere, sphere_pose)
    noisy, _ = plain(sphere, sphere_pose, rng=np.random.default_rng(1))
    a0 = seen_surface(clean, clean > 0, KINECT_V2).area_m2
    a1 = seen_surface(noisy, noisy > 0, KINECT_V2).area_m2
    assert abs(a1 / a0 - 1) < 0.015


def test_fill_gaps_fills_holes_and_outline_dropouts_only():
    """An enclosed hole and a dropped outline pixel are filled with their neighbours' depth; the background,
    a notch open to it and a hole larger than the limit are not."""
    depth = np.zeros((40, 40))
    mask = np.zeros((40, 40), bool)
    mask[5:35, 5:35] = True
    depth[mask] = 2.0
    mask[10, 10] = False          # a one-pixel hole
    mask[5, 20] = False           # a dropped outline pixel (5 neighbours on the subject)
    mask[15:25, 15:25] = False    # a 100-pixel hole: a gap between limbs, not a dropout
    filled_depth, filled = fill_gaps(depth, mask)
    assert filled[10, 10] and filled[5, 20] and filled_depth[10, 10] == 2.0
    assert not filled[20, 20] and not filled[0, 0] and filled_depth[0, 0] == 0.0
