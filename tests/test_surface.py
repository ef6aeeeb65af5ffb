"""Surface reconstruction from one depth view: known areas, depth-only operation, denoising."""

from __future__ import annotations

import argparse
import math

import numpy as np
import pytest

from wbsa.camera import MeshScene, Pose, preset, render, sphere_cap_area_m2
from helpers.shapes import icosphere
from wbsa.errors import WbsaError
from wbsa.core.mesh import TriangleMesh
from wbsa.sensor import SensorSettings, apply_sensor
from wbsa.core import frame_from_depth_image
from wbsa.surface import ReconstructionSettings, denoise_depth, grid_mesh, reconstruct, recon_column, vbsa_recon_m2
from wbsa.core.backproject import backproject_depth, organised_normals
from wbsa.surface.cli import add_reconstruct_arguments, reconstruction_settings_from_args
from wbsa.surface.grid import contour_arc_pitches

K = preset("kinect-v1")
CAMERA = Pose(np.eye(3), np.zeros(3))


def square(center, u_axis, v_axis, half_m: float) -> TriangleMesh:
    """A square of side 2·half_m spanned by unit vectors u_axis, v_axis (normal u × v)."""
    c, u, v = (np.asarray(x, dtype=np.float64) for x in (center, u_axis, v_axis))
    verts = np.stack([c - half_m * u - half_m * v, c + half_m * u - half_m * v,
                      c + half_m * u + half_m * v, c - half_m * u + half_m * v])
    return TriangleMesh(verts, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32))


def plane(distance_m: float, tilt_deg: float = 0.0, half_m: float = 0.5):
    t = math.radians(tilt_deg)
    mesh = square([0.02, 0.013, distance_m], [math.cos(t), 0, math.sin(t)], [0, 1, 0], half_m)
    return mesh, render(MeshScene(mesh), K, CAMERA)


FOOTPRINT = ReconstructionSettings(boundary="footprint", denoise="none")
BARE = ReconstructionSettings(boundary="none", denoise="none")


# -- grid ------------------------------------------------------------------------------------------

def test_plane_face_on_reconstructs_to_its_area():
    mesh, frame = plane(2.0)
    pitch = 2.0 / K.fx
    # the bare grid spans pixel centre to pixel centre: one pixel less in each direction
    rows = np.flatnonzero(frame.valid.any(axis=1))
    cols = np.flatnonzero(frame.valid.any(axis=0))
    assert vbsa_recon_m2(frame, "grid", BARE) == pytest.approx((len(rows) - 1) * (len(cols) - 1) * pitch**2, rel=1e-4)
    # with the footprint skirt every pixel counts whole: the plane's area up to the pixel quantisation
    assert vbsa_recon_m2(frame, "grid", FOOTPRINT) == pytest.approx(mesh.area_m2, rel=0.005)


def test_tilted_plane_area_is_independent_of_the_tilt():
    for tilt in (30.0, 60.0):
        mesh, frame = plane(2.5, tilt, half_m=0.4)
        assert vbsa_recon_m2(frame, "grid", FOOTPRINT) == pytest.approx(mesh.area_m2, rel=0.01)


def test_grid_faces_point_to_the_camera():
    _, frame = plane(2.0, 40.0)
    mesh = reconstruct(frame, "grid", ReconstructionSettings(denoise="none"))
    v = mesh.vertices[mesh.faces]
    normals = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    facing = np.einsum("ij,ij->i", normals, v.mean(axis=1))
    assert np.all(facing[mesh.triangle_areas_m2 > 1e-12] < 0)


def test_depth_jump_is_not_bridged():
    near = square([-0.3, 0.0, 2.0], [1, 0, 0], [0, 1, 0], 0.3)
    far = square([0.3, 0.0, 2.6], [1, 0, 0], [0, 1, 0], 0.3)
    both = TriangleMesh(np.concatenate([near.vertices, far.vertices]), np.concatenate([near.faces, far.faces + 4]))
    frame = render(MeshScene(both), K, CAMERA)
    areas = [vbsa_recon_m2(render(MeshScene(m), K, CAMERA), "grid", BARE) for m in (near, far)]
    # the far square is partly hidden by the near one only along their shared image edge
    assert vbsa_recon_m2(frame, "grid", BARE) == pytest.approx(sum(areas), rel=0.01)
    bridged = vbsa_recon_m2(frame, "grid", ReconstructionSettings(boundary="none", denoise="none", max_angle_deg=89.9))
    assert bridged > sum(areas) + 0.5 * 0.6 * 0.9  # a 0.6 m strip joining the two depths


def test_sphere_with_contour_skirt_matches_the_visible_cap():
    # at Kinect resolution a bare grid misses the band near the outline; the contour skirt restores it
    results = []
    for k, offset in enumerate(np.linspace(0.0, 0.006, 4)):
        center = np.array([offset, -offset, 3.0])
        frame = render(MeshScene(icosphere(0.25, 6, center=center)), K, CAMERA)
        cap = sphere_cap_area_m2(0.25, float(np.linalg.norm(center)))
        results.append([vbsa_recon_m2(frame, "grid", ReconstructionSettings(boundary=b, denoise="none")) / cap
                        for b in ("none", "footprint", "contour")])
        results[-1].append(vbsa_recon_m2(frame, "grid") / cap)  # default: robust quadratic filter first
    bare, footprint, contour, default = np.mean(results, axis=0)
    assert bare < 0.9 and footprint < 0.95
    assert contour == pytest.approx(1.0, abs=0.03)
    assert default == pytest.approx(1.0, abs=0.03)


def test_contour_arc_model_known_values():
    # a circle of radius one pitch: the mean arc acos(1 - e) over e in [0, 1) is exactly one pitch
    assert contour_arc_pitches(np.array([0.0]))[0] == pytest.approx(1.0, abs=1e-4)
    # steep limit: E[√e] / E[√(e+1) − √e] = 1 / (2√2 − 2)
    x = np.array([50.0, 200.0])
    np.testing.assert_allclose(contour_arc_pitches(x) / x, 1 / (2 * math.sqrt(2) - 2), rtol=2e-3)
    assert np.all(np.diff(contour_arc_pitches(np.linspace(0, 30, 100))) > 0)


def test_grid_on_empty_and_tiny_frames():
    empty = np.zeros((5, 6), dtype=bool)
    mesh = grid_mesh(np.zeros((5, 6, 3)), empty, 500.0)
    assert mesh.faces.shape == (0, 3) and mesh.area_m2 == 0.0
    _, frame = plane(2.0)
    dark = frame_from_depth_image(np.zeros_like(frame.depth_m), K)
    assert vbsa_recon_m2(dark, "grid") == 0.0


# -- depth only ------------------------------------------------------------------------------------

def test_frame_from_depth_image_matches_the_rendered_frame():
    frame = render(MeshScene(icosphere(0.3, 5, center=np.array([0.1, 0.0, 2.0]))), K, CAMERA)
    image = frame_from_depth_image(frame.depth_m, K)
    np.testing.assert_array_equal(image.valid, frame.valid)
    np.testing.assert_allclose(image.points_cam[frame.valid], frame.points_cam[frame.valid], atol=2e-6)
    assert np.all(image.triangle_id == -1) and image.settings["source"] == "depth_image"
    # organised normals agree with the mesh normals away from the outline
    from scipy import ndimage

    inner = ndimage.binary_erosion(frame.valid, iterations=2)
    cos = np.einsum("ij,ij->i", image.normals_cam[inner], frame.normals_cam[inner])
    assert np.median(cos) > 0.999
    with pytest.raises(WbsaError, match="intrinsics"):
        frame_from_depth_image(frame.depth_m[:-1], K)


def test_reconstruction_uses_the_depth_image_only():
    frame = render(MeshScene(icosphere(0.3, 5, center=np.array([0.0, 0.1, 2.5]))), K, CAMERA)
    image = frame_from_depth_image(frame.depth_m, K)
    for s in (ReconstructionSettings(), ReconstructionSettings(denoise="none")):
        a, b = reconstruct(frame, "grid", s), reconstruct(image, "grid", s)
        np.testing.assert_array_equal(a.faces, b.faces)
        np.testing.assert_allclose(a.vertices, b.vertices, atol=1e-9)


def test_plane_normals_from_the_pixel_grid():
    _, frame = plane(2.0, 50.0)
    n = organised_normals(backproject_depth(frame.depth_m, K), frame.valid, window_px=5)
    true = np.array([math.sin(math.radians(50)), 0.0, -math.cos(math.radians(50))])
    np.testing.assert_allclose(n[frame.valid] @ true, 1.0, atol=1e-3)


# -- denoising -------------------------------------------------------------------------------------

def test_quadratic_filter_keeps_a_quadric_exactly():
    h, w = 40, 50
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    depth = 2.0 + 0.003 * u - 0.002 * v + 2e-4 * u * u + 1e-4 * u * v - 3e-4 * v * v
    mask = (u - 25) ** 2 / 400 + (v - 20) ** 2 / 250 < 1  # an ellipse of returns
    depth = np.where(mask, depth, 0.0)
    out = denoise_depth(depth, "quadratic", sigma_px=2.0)
    np.testing.assert_allclose(out[mask], depth[mask], atol=2e-6)  # float32 output
    assert np.all(out[~mask] == 0)


def test_filters_reduce_noise_within_the_mask():
    rng = np.random.default_rng(0)
    depth = np.zeros((60, 80))
    depth[10:50, 10:70] = 3.0
    noisy = np.where(depth > 0, depth + rng.normal(0, 0.03, depth.shape), 0.0)
    for method in ("quadratic", "bilateral", "median"):
        out = denoise_depth(noisy, method, sigma_px=2.0)
        assert np.array_equal(out > 0, depth > 0)
        inner = np.zeros_like(depth, dtype=bool)
        inner[15:45, 15:65] = True
        assert np.std(out[inner] - 3.0) < 0.5 * 0.03
        assert abs(np.mean(out[depth > 0]) - 3.0) < 0.003  # no background bleeding in


def test_noisy_plane_area_after_denoising():
    # at 2 m Kinect v1 noise (σz ≈ 6 mm) is about twice the pixel pitch (3.5 mm)
    mesh, frame = plane(2.0, 20.0, half_m=0.4)
    noisy = apply_sensor(frame, SensorSettings(noise="nguyen2012"), np.random.default_rng(4))
    raw = vbsa_recon_m2(noisy, "grid", ReconstructionSettings(denoise="none", boundary="footprint"))
    assert raw > 1.3 * mesh.area_m2  # jagged
    errors = [vbsa_recon_m2(noisy, "grid", ReconstructionSettings(boundary="footprint", denoise_sigma_px=s))
              / mesh.area_m2 - 1 for s in (1.5, 2.5, 4.0)]
    assert errors[0] > errors[1] > errors[2] > -0.01  # stronger smoothing, less inflation, no flattening
    assert abs(errors[1]) < 0.05


# -- Open3D methods --------------------------------------------------------------------------------

@pytest.mark.parametrize("method", ["ball-pivoting", "poisson"])
def test_point_cloud_methods_on_a_sphere(method):
    center = np.array([0.0, 0.0, 3.0])
    frame = render(MeshScene(icosphere(0.2, 5, center=center)), K, CAMERA)
    cap = sphere_cap_area_m2(0.2, 3.0)
    mesh = reconstruct(frame, method, ReconstructionSettings(denoise="none"))
    assert mesh.faces.shape[0] > 1000
    # single-view reconstructions miss the band at the outline but must not close the surface
    assert 0.7 * cap < mesh.area_m2 < 1.05 * cap
    assert np.all(mesh.vertices[:, 2] < 3.0 + 0.02)  # nothing behind the visible cap's base


def test_unknown_method():
    _, frame = plane(2.0)
    with pytest.raises(WbsaError, match="method"):
        reconstruct(frame, "marching-cubes")


# -- command-line flags ----------------------------------------------------------------------------

def test_reconstruct_flags():
    p = argparse.ArgumentParser()
    add_reconstruct_arguments(p)
    args = p.parse_args(["--reconstruct", "grid,poisson", "--denoise", "median", "--boundary", "footprint",
                         "--voxel-size", "0.01", "--smooth"])
    s = reconstruction_settings_from_args(args)
    assert s.methods == ("grid", "poisson")
    assert (s.denoise, s.boundary, s.voxel_size_m, s.smoothing) == ("median", "footprint", 0.01, "mls")
    assert reconstruction_settings_from_args(p.parse_args([])) == ReconstructionSettings()
    assert reconstruction_settings_from_args(p.parse_args([])).methods == ()
    with pytest.raises(SystemExit):
        p.parse_args(["--reconstruct", "grid,greedy"])
    assert recon_column("ball-pivoting") == "vbsa_recon_ball_pivoting_m2"
    with pytest.raises(WbsaError):
        ReconstructionSettings(denoise="gaussian")
