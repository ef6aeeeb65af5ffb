"""Sensor simulation: Nguyen 2012 noise statistics, quantisation, holes, determinism, depth PNG."""

from __future__ import annotations

import argparse
import dataclasses
import math

import numpy as np
import pytest

from wbsa.camera import MeshScene, Pose, preset, render
from helpers.shapes import box, icosphere
from wbsa.errors import WbsaError
from wbsa.core.mesh import TriangleMesh
from wbsa.core import frame_from_depth_image
from wbsa.core.depth_image import depth_to_png_mm, png_mm_to_depth, read_depth_png, write_depth_png
from wbsa.sensor import SensorSettings, apply_sensor, axial_sigma_m, lateral_sigma_px
from wbsa.sensor.cli import add_sensor_arguments, sensor_settings_from_args
from wbsa.sensor.measure import view_rng

K = preset("kinect-v1")
CAMERA = Pose(np.eye(3), np.zeros(3))  # camera at the origin looking along +Z


def plane_frame(distance_m: float, tilt_deg: float, half_size_m: float = 3.0, n: int = 1, camera=K):
    """A square plane at ``distance_m`` on the optical axis, turned by ``tilt_deg`` about the image's
    vertical axis, split into ``2·n²`` triangles, rendered by the camera stage."""
    t = math.radians(tilt_deg)
    s = np.linspace(-half_size_m, half_size_m, n + 1)
    a, b = np.meshgrid(s, s, indexing="ij")
    u_axis = np.array([math.cos(t), 0.0, math.sin(t)])   # in-plane, tilted towards the camera's z
    v_axis = np.array([0.0, 1.0, 0.0])
    verts = (np.array([0.0, 0.0, distance_m]) + a[..., None] * u_axis + b[..., None] * v_axis).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    v00 = i * (n + 1) + j
    faces = np.concatenate([np.stack([v00, v00 + 1, v00 + n + 2], -1).reshape(-1, 3),
                            np.stack([v00, v00 + n + 2, v00 + n + 1], -1).reshape(-1, 3)])
    return render(MeshScene(TriangleMesh(verts, faces.astype(np.int32))), camera, CAMERA)


def interior(valid: np.ndarray, px: int = 3) -> np.ndarray:
    """Pixels at least ``px`` pixels away from any pixel without return or the image border."""
    from scipy import ndimage

    return ndimage.binary_erosion(valid, iterations=px, border_value=0)


def incidence(frame) -> np.ndarray:
    """(h, w) angle between normal and ray at every pixel (radians)."""
    rays = np.nan_to_num(frame.points_cam.astype(np.float64))
    rays /= np.maximum(np.linalg.norm(rays, axis=-1, keepdims=True), 1e-12)
    cos = np.abs(np.einsum("...k,...k->...", np.nan_to_num(frame.normals_cam.astype(np.float64)), rays))
    return np.arccos(np.clip(cos, 0, 1))


# -- the published model ---------------------------------------------------------------------------

def test_nguyen_sigmas_known_values():
    # σz = 0.0012 + 0.0019 (z - 0.4)² below 60°; ≈ 3 cm at the paper's 4.3 m
    # (Nguyen et al. 2012; docs/references.md)
    assert axial_sigma_m(1.0, 0.0) == pytest.approx(0.0012 + 0.0019 * 0.36)
    assert axial_sigma_m(4.3, math.radians(30)) == pytest.approx(0.030099, abs=1e-6)
    # above 60° the angular term 0.0001/√z · θ²/(π/2 − θ)² is added
    th = math.radians(70)
    steep = 0.0001 / math.sqrt(2) * th**2 / (math.pi / 2 - th) ** 2
    assert axial_sigma_m(2.0, th) == pytest.approx(0.0012 + 0.0019 * 1.6**2 + steep)
    # σL = 0.8 + 0.035 θ/(π/2 − θ) px: 0.8 px face-on, 0.835 px at 45°
    assert lateral_sigma_px(0.0) == pytest.approx(0.8)
    assert lateral_sigma_px(math.pi / 4) == pytest.approx(0.835)


def test_axial_noise_matches_sigma_z_face_on():
    frame = plane_frame(2.0, 0.0)
    model = SensorSettings(noise="nguyen2012", lateral_noise=False)
    noisy = apply_sensor(frame, model, np.random.default_rng(1))
    both = interior(frame.valid) & noisy.valid
    err = (noisy.depth_m[both] - frame.depth_m[both]).astype(np.float64)
    sigma = axial_sigma_m(frame.depth_m[both], incidence(frame)[both])
    z = err / sigma
    n = z.size
    assert n > 250_000
    assert abs(z.mean()) < 4 / math.sqrt(n)
    assert z.std() == pytest.approx(1.0, abs=4 / math.sqrt(2 * n))
    # points follow the noisy depth along each pixel's own ray
    np.testing.assert_allclose(noisy.points_cam[both][:, 2], noisy.depth_m[both], rtol=1e-6)


def test_noise_scale_multiplies_both_sigmas_and_is_recorded_only_off_one():
    """On a plane at 45° the lateral jitter moves the depth along the slope: the depth error with both
    effects, and its lateral part (with minus without the jitter, same streams), halve at 0.5."""
    frame = plane_frame(2.0, 45.0)
    inner = interior(frame.valid)
    whole, lateral = {}, {}
    for scale in (1.0, 0.5, 0.0):
        noisy = apply_sensor(frame, SensorSettings(noise="nguyen2012", noise_scale=scale), np.random.default_rng(1))
        axial = apply_sensor(frame, SensorSettings(noise="nguyen2012", lateral_noise=False, noise_scale=scale),
                             np.random.default_rng(1))
        both = inner & noisy.valid & axial.valid
        whole[scale] = float(np.std((noisy.depth_m - frame.depth_m)[both]))
        lateral[scale] = float(np.std((noisy.depth_m - axial.depth_m)[both]))
    assert lateral[1.0] > 0.003 and lateral[0.5] / lateral[1.0] == pytest.approx(0.5, rel=0.01)
    assert whole[0.5] / whole[1.0] == pytest.approx(0.5, rel=0.01) and whole[0.0] == lateral[0.0] == 0.0
    ramp = SensorSettings(noise="nguyen2012", noise_scale=0.5)
    assert ramp.to_dict()["noise_scale"] == 0.5 and "noise_scale" not in SensorSettings(noise="nguyen2012").to_dict()
    with pytest.raises(WbsaError, match="noise_scale"):
        SensorSettings(noise="nguyen2012", noise_scale=-0.5)


def test_axial_noise_steep_term_at_70_degrees():
    frame = plane_frame(2.0, 70.0, half_size_m=1.5)
    noisy = apply_sensor(frame, SensorSettings(noise="nguyen2012", lateral_noise=False), np.random.default_rng(2))
    both = frame.valid & noisy.valid & (incidence(frame) > math.radians(62))
    assert np.count_nonzero(both) > 50_000
    err = (noisy.depth_m[both] - frame.depth_m[both]).astype(np.float64)
    theta = incidence(frame)[both]
    z = err / axial_sigma_m(frame.depth_m[both], theta)
    assert z.std() == pytest.approx(1.0, abs=4 / math.sqrt(2 * z.size))
    # without the steep term the errors would be too large for the flat-angle σz
    flat = 0.0012 + 0.0019 * (frame.depth_m[both] - 0.4) ** 2
    assert (err / flat).std() > 1.05


def test_lateral_noise_matches_sigma_l_on_a_depth_ramp():
    # On a plane tilted 70° the depth changes by g = ∂z/∂u per pixel, so a lateral shift of N(0, σL) px
    # adds (g σL)² to the axial variance; the measured variance must match σz² + σL² (gu² + gv²).
    frame = plane_frame(2.0, 70.0, half_size_m=1.5)
    noisy = apply_sensor(frame, SensorSettings(noise="nguyen2012"), np.random.default_rng(3))
    d = frame.depth_m.astype(np.float64)
    gu = np.zeros_like(d)
    gv = np.zeros_like(d)
    gu[:, 1:-1] = 0.5 * (d[:, 2:] - d[:, :-2])
    gv[1:-1] = 0.5 * (d[2:] - d[:-2])
    inner = interior(frame.valid) & noisy.valid
    theta = incidence(frame)[inner]
    var_axial = axial_sigma_m(d[inner], theta) ** 2
    var_lateral = lateral_sigma_px(theta) ** 2 * (gu[inner] ** 2 + gv[inner] ** 2)
    err = noisy.depth_m[inner] - d[inner]
    assert np.mean(var_lateral) > np.mean(var_axial)  # the test is sensitive to σL
    z = err / np.sqrt(var_axial + var_lateral)
    assert z.std() == pytest.approx(1.0, abs=0.02)
    assert (err / np.sqrt(var_axial)).std() > 1.3


def test_same_seed_same_image_and_independent_effects():
    frame = render(MeshScene(icosphere(0.3, 4, center=np.array([0.0, 0.0, 2.5]))), K, CAMERA)
    model = SensorSettings(noise="nguyen2012", holes_fraction=0.1, pixel_dropout=0.05, quantise=True)
    a = apply_sensor(frame, model, np.random.default_rng(7))
    b = apply_sensor(frame, model, np.random.default_rng(7))
    c = apply_sensor(frame, model, np.random.default_rng(8))
    for name in ("depth_m", "triangle_id"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    np.testing.assert_array_equal(a.points_cam, b.points_cam)
    assert not np.array_equal(a.depth_m, c.depth_m)
    assert a.settings["sensor"] == model.to_dict()
    # switching pixel dropout off leaves the noise draws of the other effects unchanged
    d = apply_sensor(frame, dataclasses.replace(model, pixel_dropout=0.0), np.random.default_rng(7))
    both = a.valid & d.valid
    np.testing.assert_array_equal(a.depth_m[both], d.depth_m[both])
    assert np.count_nonzero(d.valid) > np.count_nonzero(a.valid)


def test_ideal_model_changes_nothing():
    frame = render(MeshScene(icosphere(0.3, 3, center=np.array([0.0, 0.0, 2.5]))), K, CAMERA)
    out = apply_sensor(frame, SensorSettings(), np.random.default_rng(0))
    assert SensorSettings().is_ideal
    np.testing.assert_array_equal(out.depth_m, frame.depth_m)
    np.testing.assert_array_equal(out.triangle_id, frame.triangle_id)
    assert out.settings["sensor"]["noise"] == "none"


def test_triangle_holes_fraction_is_honoured():
    frame = plane_frame(2.0, 20.0, half_size_m=0.5, n=40)  # 3,200 triangles, about 25 pixels each
    ids_before = np.unique(frame.triangle_id[frame.valid])
    out = apply_sensor(frame, SensorSettings(holes_fraction=0.3), np.random.default_rng(5))
    ids_after = np.unique(out.triangle_id[out.valid])
    assert len(ids_after) == len(ids_before) - round(0.3 * len(ids_before))
    dropped = np.setdiff1d(ids_before, ids_after)
    # every pixel of a dropped triangle is gone, every other pixel is untouched
    gone = np.isin(frame.triangle_id, dropped)
    assert not np.any(out.valid & gone)
    keep = frame.valid & ~gone
    np.testing.assert_array_equal(out.depth_m[keep], frame.depth_m[keep])
    assert np.all(out.triangle_id[~out.valid] == -1)
    assert np.all(np.isnan(out.points_cam[~out.valid]))
    # dropping 30 % of the triangles drops about 30 % of the pixels
    assert 1 - out.n_pixels / frame.n_pixels == pytest.approx(0.3, abs=0.03)


def test_pixel_dropout_is_binomial():
    frame = plane_frame(2.0, 0.0)
    out = apply_sensor(frame, SensorSettings(pixel_dropout=0.2), np.random.default_rng(6))
    n = frame.n_pixels
    lost = 1 - out.n_pixels / n
    assert lost == pytest.approx(0.2, abs=4 * math.sqrt(0.2 * 0.8 / n))


def test_grazing_dropout_cuts_at_the_angle():
    frame = render(MeshScene(icosphere(0.4, 5, center=np.array([0.0, 0.0, 2.5]))), K, CAMERA)
    out = apply_sensor(frame, SensorSettings(grazing_dropout_deg=20.0), np.random.default_rng(0))
    theta = np.degrees(incidence(frame))
    assert np.all(theta[out.valid] <= 70.0 + 1e-6)
    assert not np.any(out.valid & (theta > 70.0 + 1e-6))
    assert np.all(out.valid[frame.valid & (theta < 69.9)])
    # the Nguyen model drops the last 8° by default
    assert SensorSettings(noise="nguyen2012").effective_grazing_dropout_deg == 8.0
    assert SensorSettings().effective_grazing_dropout_deg == 0.0


def test_disparity_quantisation_kinect_v1():
    frame = plane_frame(3.0, 40.0)
    out = apply_sensor(frame, SensorSettings(quantise=True), np.random.default_rng(0))
    fb = K.fx * 0.075
    z = out.depth_m[out.valid].astype(np.float64)
    steps = fb / z / 0.125
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-3)  # disparity on the 1/8 px grid
    # the disparity error is at most half a step, so |z - z0| = f b |d - d0| / (d d0) <= z z0 q / (2 f b)
    z0 = frame.depth_m[out.valid].astype(np.float64)
    assert np.all(np.abs(z - z0) <= z * z0 * 0.125 / (2 * fb) * 1.001 + 1e-6)
    # at 4.3 m a step is about 5 cm
    assert 4.3**2 * 0.125 / fb == pytest.approx(0.0535, abs=5e-4)


def test_range_limits_of_the_preset():
    frame = plane_frame(2.0, 75.0)  # the tilted plane spans depths on both sides of 4.0 m
    z = frame.depth_m
    assert z[frame.valid].max() > 4.0
    out = apply_sensor(frame, SensorSettings(range_limits=True), np.random.default_rng(0))
    assert out.depth_m[out.valid].max() <= K.max_range_m
    assert np.all(out.valid == (frame.valid & (z >= K.min_range_m) & (z <= K.max_range_m)))


def test_triangle_holes_need_triangle_ids():
    frame = frame_from_depth_image(plane_frame(2.0, 0.0).depth_m, K)
    with pytest.raises(WbsaError, match="triangle"):
        apply_sensor(frame, SensorSettings(holes_fraction=0.1), np.random.default_rng(0))
    # pixel dropout and noise work on depth images
    out = apply_sensor(frame, SensorSettings(noise="nguyen2012", pixel_dropout=0.1), np.random.default_rng(0))
    assert 0 < out.n_pixels < frame.n_pixels


def test_settings_errors_name_the_field():
    with pytest.raises(WbsaError, match="^noise must be one of 'none', 'nguyen2012', 'camera', got 'kinect'$"):
        SensorSettings(noise="kinect")
    with pytest.raises(WbsaError, match=r"^holes_fraction must be a fraction in \[0, 1\], got 1.5$"):
        SensorSettings(holes_fraction=1.5)
    with pytest.raises(WbsaError, match=r"^grazing_dropout_deg must be degrees in \[0, 90\)"):
        SensorSettings(grazing_dropout_deg=90.0)


# -- one model per technology ----------------------------------------------------------------------

def test_every_camera_gets_its_technology_model_and_the_kinect_v1_disparity_is_its_records():
    from wbsa.camera.presets import CAMERAS
    from wbsa.sensor.settings import KINECT_V1_BASELINE_M, KINECT_V1_DISPARITY_STEP_PX
    from wbsa.sensor.technology import TECHNOLOGIES, camera_model

    assert (KINECT_V1_BASELINE_M, KINECT_V1_DISPARITY_STEP_PX) == CAMERAS["kinect-v1"].disparity
    for name, record in CAMERAS.items():
        model = camera_model(name)
        assert model.noise is TECHNOLOGIES[record.technology]
        assert model.quantised == (record.disparity is not None)
    # only Kinect v1's model is published in full; the others say which figures stand in
    assert TECHNOLOGIES["structured-light"].stand_in == ""
    assert all("stand-in" in TECHNOLOGIES[t].stand_in for t in ("time-of-flight", "active-stereo", "lidar"))
    # the depth step of Kinect v1's disparity at 4.3 m: about 5 cm (z² q / (f b))
    assert camera_model("kinect-v1").depth_step_per_m * 4.3**2 == pytest.approx(0.0535, abs=5e-4)


def test_active_stereo_follows_intels_depth_rms_relation():
    """RMS = z² · subpixel / (f · baseline) (Intel's D400 relation): D435 (f 426 px, b 50 mm, 1/12 px) at 2 m
    is 1.56 cm, and the sensor's face-on errors have that spread."""
    from wbsa.sensor.technology import axial_sigma_m, camera_model

    model = camera_model("realsense-d435")
    assert axial_sigma_m(model, 2.0, 0.0) == pytest.approx(2.0**2 * (1 / 12) / (426.0 * 0.050))
    assert axial_sigma_m(camera_model("realsense-d455"), 2.0, 0.0) == pytest.approx(4 * (1 / 12) / (415.0 * 0.095))
    d435 = preset("realsense-d435")
    frame = plane_frame(2.0, 0.0, camera=d435)
    noisy = apply_sensor(frame, SensorSettings(noise="camera", lateral_noise=False), np.random.default_rng(7))
    both = interior(frame.valid) & noisy.valid
    z = ((noisy.depth_m[both] - frame.depth_m[both]) / axial_sigma_m(model, frame.depth_m[both], 0.0))
    assert z.size > 300_000 and z.std() == pytest.approx(1.0, abs=4 / math.sqrt(2 * z.size))
    # with --quantise the stereo camera's own disparity grid (1/12 px, 50 mm), not Kinect v1's
    quantised = apply_sensor(frame, SensorSettings(noise="camera", quantise=True), np.random.default_rng(7))
    steps = d435.fx * 0.050 / quantised.depth_m[quantised.valid].astype(np.float64) * 12
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-3)


def test_noise_camera_reads_the_presets_technology_or_the_one_given():
    from wbsa.camera import Intrinsics
    from wbsa.sensor import nguyen2012

    kinect = plane_frame(2.0, 0.0)
    a = apply_sensor(kinect, SensorSettings(noise="camera"), np.random.default_rng(3))
    b = apply_sensor(kinect, SensorSettings(noise="nguyen2012"), np.random.default_rng(3))
    np.testing.assert_array_equal(a.depth_m, b.depth_m)  # Kinect v1's own model is Nguyen's
    assert nguyen2012.MODEL.noise.technology == "structured-light"
    # a time-of-flight camera is not quantised even when asked: it has no disparity
    v2 = plane_frame(2.0, 30.0, camera=preset("kinect-v2"))
    tof = SensorSettings(noise="camera", quantise=True)
    assert tof.model_for(v2.intrinsics)[1] is None
    assert tof.to_dict()["grazing_dropout_deg"] is None and "technology" not in tof.to_dict()
    # a camera without a preset needs its technology said
    custom = Intrinsics(64, 48, 50, 50, 31.5, 23.5)
    with pytest.raises(WbsaError, match="^noise 'camera' needs a camera preset"):
        SensorSettings(noise="camera").model_for(custom)
    given = SensorSettings(noise="camera", technology="active-stereo", baseline_m=0.05, disparity_step_px=0.1)
    model, disparity = given.model_for(custom)
    assert disparity == (0.05, 0.1) and model.depth_step_per_m == pytest.approx(0.1 / (50 * 0.05))
    assert given.to_dict()["technology"] == "active-stereo" and given.effective_grazing_dropout_deg == 8.0
    with pytest.raises(WbsaError, match="^technology selects the model of noise 'camera'"):
        SensorSettings(noise="nguyen2012", technology="lidar")


def test_the_estimators_envelope_is_the_cameras_own():
    from wbsa.camera import Intrinsics
    from wbsa.camera.presets import CAMERAS
    from wbsa.sensor.technology import camera_model, envelope_model

    for name, record in CAMERAS.items():
        assert envelope_model(record.intrinsics) == camera_model(name)
    assert envelope_model(Intrinsics(64, 48, 50, 50, 31.5, 23.5)) == envelope_model(None) == camera_model("kinect-v1")


def test_numpy_and_torch_give_the_same_noise_from_one_definition():
    """Every technology's σz, σL and envelope, on every preset, from numpy (float64) and torch (float64 equal to
    the last bits, float32 to its precision; differentiable)."""
    torch = pytest.importorskip("torch")
    from wbsa.camera.presets import CAMERAS
    from wbsa.sensor.technology import axial_sigma_m, camera_model, envelope_m, lateral_sigma_px

    z = np.linspace(0.25, 8.0, 301)[:, None] * np.ones((1, 40))
    theta = np.linspace(0.0, math.radians(88.0), 40)[None, :] * np.ones((301, 1))
    for name in CAMERAS:
        model = camera_model(name)
        for f, args in ((axial_sigma_m, (z, theta)), (lateral_sigma_px, (theta,)), (envelope_m, (z,))):
            want = f(model, *args)
            assert isinstance(want, np.ndarray) and want.dtype == np.float64 and np.all(want > 0)
            got64 = f(model, *(torch.as_tensor(a) for a in args))
            np.testing.assert_allclose(got64.numpy(), want, rtol=1e-14, atol=0, err_msg=f"{name} {f.__name__}")
            got32 = f(model, *(torch.as_tensor(a, dtype=torch.float32) for a in args))
            assert got32.dtype == torch.float32
            np.testing.assert_allclose(got32.numpy(), want, rtol=1e-5, err_msg=f"{name} {f.__name__}")
    zt = torch.tensor([1.0, 3.0], dtype=torch.float64, requires_grad=True)
    envelope_m(camera_model("realsense-d435"), zt).sum().backward()
    assert torch.all(zt.grad > 0)  # the envelope grows with depth


#: Literals of the depth-noise models; they live in src/wbsa/sensor/ (and a camera's disparity in its record).
_NOISE_CONSTANTS = {
    "Nguyen axial": r"0\.0012|0\.0019",
    "Nguyen grazing term": r"0\.0001\s*/",
    "Nguyen lateral": r"0\.8\s*\+\s*0\.035|0\.035\s*\*\s*th",
    "Kinect v1 focal length": r"575\.8",
    "Kinect v1 disparity": r"(?<![\d.])0\.(?:075|125)(?!\d)",
}
#: Copies of them as they were once written outside the sensor package: each must be caught.
_FORMER_COPIES = ("axial = 0.0012 + 0.0019 * (z - 0.4) ** 2", "_Q_STEP = 0.125 / (575.8 * 0.075)",
                  "noise = ((0.0012 + 0.0019 * (z0 - 0.4).square()).square()",
                  "baseline_m=baseline or 0.075, disparity_step_px=step or 0.125",
                  "steep = 0.0001 / np.sqrt(z) * theta**2", "return 0.8 + 0.035 * theta / (np.pi / 2 - theta)")


def test_the_noise_constants_are_written_only_in_the_sensor_package():
    """A second copy of a noise constant anywhere in src/ outside wbsa/sensor/ (and the camera record table)
    fails here: code that needs the noise calls wbsa.sensor.technology. The plain renderer of wbsa.testing is
    the one exception: it is independent of wbsa.sensor on purpose, with noise of its own."""
    import re
    from pathlib import Path

    import wbsa

    caught = {what: [c for c in _FORMER_COPIES if re.search(p, c)] for what, p in _NOISE_CONSTANTS.items()}
    assert all(caught.values()) and all(any(re.search(p, c) for p in _NOISE_CONSTANTS.values())
                                        for c in _FORMER_COPIES), caught
    root = Path(wbsa.__file__).parent
    home = {root / "camera" / "presets.py", root / "testing" / "plain_render.py"}
    copies = []
    for path in sorted(root.rglob("*.py")):
        if path.parent == root / "sensor" or path in home:
            continue
        for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            copies += [f"{path.relative_to(root)}:{i}: {what}: {line.strip()}"
                       for what, pattern in _NOISE_CONSTANTS.items() if re.search(pattern, line)]
    assert not copies, "noise constants copied outside wbsa/sensor/ (call wbsa.sensor.technology):\n" + "\n".join(copies)


# -- depth PNG -------------------------------------------------------------------------------------

def test_depth_png_known_values_and_round_trip(tmp_path):
    depth = np.array([[0.0, 1.0, 1.2346], [4.3, np.nan, -1.0]], dtype=np.float32)
    units = depth_to_png_mm(depth)
    assert units.dtype == np.uint16
    np.testing.assert_array_equal(units, [[0, 1000, 1235], [4300, 0, 0]])
    np.testing.assert_allclose(png_mm_to_depth(units), [[0, 1.0, 1.235], [4.3, 0, 0]], atol=1e-6)

    frame = render(MeshScene(box((0.6, 0.4, 0.3), center=np.array([0.1, 0.0, 2.2]))), K, CAMERA)
    path = write_depth_png(tmp_path / "depth.png", frame.depth_m)
    raw = path.read_bytes()
    assert raw[:8] == b"\x89PNG\r\n\x1a\n"
    assert raw[24] == 16 and raw[25] == 0  # IHDR: 16-bit greyscale
    back = read_depth_png(path)
    assert back.shape == (K.height, K.width) and back.dtype == np.float32
    np.testing.assert_array_equal(back > 0, frame.valid)
    assert np.abs(back - frame.depth_m)[frame.valid].max() <= 0.0005 + 1e-6
    # the same image written again is byte-identical; TUM's 5000 units per metre round-trip too
    assert write_depth_png(tmp_path / "again.png", frame.depth_m).read_bytes() == raw
    tum = read_depth_png(write_depth_png(tmp_path / "tum.png", frame.depth_m, depth_scale=5000), depth_scale=5000)
    assert np.abs(tum - frame.depth_m)[frame.valid].max() <= 0.0001 + 1e-6


def test_depth_png_errors(tmp_path):
    from PIL import Image

    with pytest.raises(WbsaError, match="16-bit"):
        depth_to_png_mm(np.array([[70.0]]))
    Image.fromarray(np.zeros((4, 4), np.uint8)).save(tmp_path / "8bit.png")
    with pytest.raises(WbsaError, match="16-bit"):
        read_depth_png(tmp_path / "8bit.png")
    (tmp_path / "junk.png").write_bytes(b"not a png")
    with pytest.raises(WbsaError, match="not a readable image"):
        read_depth_png(tmp_path / "junk.png")
    with pytest.raises(WbsaError, match="does not exist"):
        read_depth_png(tmp_path / "missing.png")


# -- command-line flags ----------------------------------------------------------------------------

def test_sensor_flags():
    p = argparse.ArgumentParser()
    add_sensor_arguments(p, seed=True)
    args = p.parse_args(["--noise", "nguyen2012", "--holes", "0.2", "--pixel-dropout", "0.01", "--quantise",
                         "--grazing-dropout", "10", "--sensor-seed", "3"])
    sensor = sensor_settings_from_args(args, K)
    assert sensor == SensorSettings(noise="nguyen2012", holes_fraction=0.2, pixel_dropout=0.01, quantise=True,
                                    grazing_dropout_deg=10.0)
    assert args.sensor_seed == 3
    assert sensor_settings_from_args(p.parse_args([])).is_ideal
    with pytest.raises(SystemExit):
        p.parse_args(["--holes", "1.5"])
    with pytest.raises(SystemExit):
        p.parse_args(["--noise", "gaussian"])
    from wbsa.camera import Intrinsics

    with pytest.raises(WbsaError, match="range_limits needs a camera with a working range"):
        sensor_settings_from_args(p.parse_args(["--range-limits"]), Intrinsics(64, 48, 50, 50, 31.5, 23.5))
    assert sensor_settings_from_args(p.parse_args(["--noise", "camera"]), preset("phone-lidar")).noise == "camera"
    with pytest.raises(WbsaError, match="^noise 'camera' needs a camera preset to know its technology"):
        sensor_settings_from_args(p.parse_args(["--noise", "camera"]), Intrinsics(64, 48, 50, 50, 31.5, 23.5))


def test_sensor_rng_is_keyed():
    from wbsa.camera import View

    a = view_rng(1, 5, View(30.0, -45.0, 4.3)).random(3)
    np.testing.assert_array_equal(a, view_rng(1, 5, View(30.0, -45.0, 4.3)).random(3))
    assert not np.array_equal(a, view_rng(1, 5, View(45.0, -45.0, 4.3)).random(3))
    assert not np.array_equal(a, view_rng(1, 6, View(30.0, -45.0, 4.3)).random(3))


def test_edge_pixels_are_mixed_between_the_two_surfaces_or_dropped():
    """Time-of-flight mixing: one straddling pixel per edge, its depth between the surfaces, weighted by light."""
    from wbsa.sensor.depth_edges import edge_pixels

    z = np.full((60, 40), 4.0)
    z[:, :20] = 3.0                         # a board 1 m in front of a wall, its edge between columns 19 and 20
    z[:, 38:] = 0.0                         # no return: nothing to mix with
    out = edge_pixels(z, np.random.default_rng(1), "mixed")
    changed = out != z
    assert (changed.sum(axis=1) == 1).all() and set(np.nonzero(changed)[1]) <= {19, 20}
    assert ((out[changed] > 3.0) & (out[changed] < 4.0)).all()
    # a board pixel sees mostly the board, which also sends back (4/3)² more light per area: nearer than the middle
    assert (out[:, 19][changed[:, 19]] < 3.5).all()
    assert 10 < changed[:, 19].sum() < 50  # the edge lies in either pixel with probability 1/2
    dropped = edge_pixels(z, np.random.default_rng(1), "dropped")
    assert np.array_equal(dropped == 0, changed | (z == 0))  # the same draws: the same pixels, now without return
    half = edge_pixels(z, np.random.default_rng(2), "mixed", 0.5)
    assert 10 < (half != z).sum() < 50 and np.array_equal(half, edge_pixels(z, np.random.default_rng(2), "mixed", 0.5))
    assert np.array_equal(edge_pixels(z, np.random.default_rng(1), "kept"), z)
    with pytest.raises(ValueError, match="share"):
        edge_pixels(z, np.random.default_rng(1), "mixed", 1.5)
    with pytest.raises(ValueError, match="blurred"):
        edge_pixels(z, np.random.default_rng(1), "blurred")
