"""The whole-body fit to one depth view (``wbsa.estimation.methods.body_fit``, issue 28)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from wbsa.errors import SettingsError, WbsaError

#: Settings small enough for the test suite (the fit's defaults use more restarts and steps).
FAST = dict(restarts=3, steps=120)


@pytest.fixture(scope="module")
def render(render_with_body):
    """A noise-free Kinect v2 render (azimuth 25°, 2.6 m) of a known anny woman with arms down, on a floor.

    Returns (depth, mask, camera, floor Plane, truth measures).
    """
    return render_with_body[:5]


@pytest.fixture(scope="module")
def render_with_body(body_model):
    """:func:`render`'s five, and the woman's posed vertices (n, 3) in the camera frame."""
    from wbsa.bodies.anthropometry import Anthropometer, reference_adult
    from wbsa.bodies.posing import pose_vertices
    from wbsa.bodies.posture import POSTURES
    from wbsa.camera import MeshScene, View, preset
    from wbsa.camera.extrinsics import pose_from_view
    from wbsa.estimation.subject.cloud import Plane
    from wbsa.training.room import compose_room
    from wbsa.simulate import simulate_view

    row = reference_adult(1.0)
    row["p_weight"] = 0.7
    rest = body_model.rest_bodies(row)
    spec = POSTURES["arms-down"]
    angles = np.array([spec.nominal(m) for m in ("shoulder_abduction", "shoulder_flexion", "shoulder_rotation",
                                                 "elbow_flexion", "hip_abduction")] * 2)
    posed = pose_vertices(rest.vertices[0], rest.bone_heads[0], angles, body_model.rig)
    truth = Anthropometer(body_model).measure_one(rest.vertices[0], rest.bone_heads[0])
    room = compose_room(body_model.skin_mesh(posed), 25.0, wall_behind_m=None)
    camera, view = preset("kinect-v2"), View(25.0, 8.0, 2.6)
    frame = simulate_view(MeshScene(room.mesh, surroundings=True), camera, view, keep_frame=True,
                          target=room.subject_center).frame
    depth = frame.depth_m.astype(np.float64)
    mask = room.is_subject(frame.triangle_id) & (depth > 0)
    pose = pose_from_view(view, room.subject_center)
    normal = pose.R @ np.array([0.0, 0.0, 1.0])
    floor = Plane(normal, float(normal @ pose.T))
    return depth, mask, camera, floor, truth, pose.apply(posed)


@pytest.fixture(scope="module")
def dressed_render(body_model, render):
    """The woman of ``render`` in a 1.5 cm layer of clothes (trunk, upper arms, legs, feet), the same view.

    Returns (depth, mask, camera, floor Plane, truth measures of the bare body).
    """
    from wbsa.bodies.anthropometry import reference_adult
    from wbsa.bodies.clothing import COVERED_BONES, dressed_vertices
    from wbsa.bodies.posing import pose_vertices
    from wbsa.bodies.posture import POSTURES
    from wbsa.camera import MeshScene, View
    from wbsa.simulate import simulate_view
    from wbsa.training.room import compose_room

    _, _, camera, floor, truth = render
    row = reference_adult(1.0)
    row["p_weight"] = 0.7
    rest = body_model.rest_bodies(row)
    spec = POSTURES["arms-down"]
    angles = np.array([spec.nominal(m) for m in ("shoulder_abduction", "shoulder_flexion", "shoulder_rotation",
                                                 "elbow_flexion", "hip_abduction")] * 2)
    posed = pose_vertices(rest.vertices[0], rest.bone_heads[0], angles, body_model.rig)
    dressed = dressed_vertices(posed, body_model.skin_faces, body_model.vertices_of_bones(COVERED_BONES), 0.015)
    room = compose_room(body_model.skin_mesh(dressed), 25.0, wall_behind_m=None)
    room = dataclasses.replace(room, subject_center=body_model.skin_mesh(posed).bbox_center)  # aimed as at the bare body
    frame = simulate_view(MeshScene(room.mesh, surroundings=True), camera, View(25.0, 8.0, 2.6), keep_frame=True,
                          target=room.subject_center).frame
    depth = frame.depth_m.astype(np.float64)
    return depth, room.is_subject(frame.triangle_id) & (depth > 0), camera, floor, truth


def test_torch_posing_matches_the_project_posing(body_model):
    """The fit's differentiable skinning is :func:`wbsa.bodies.posing.pose_vertices` on its vertex subset."""
    import torch

    from wbsa.bodies.anthropometry import reference_adult
    from wbsa.bodies.body_model import body_parameter_array
    from wbsa.bodies.posing import pose_vertices
    from wbsa.bodies.posture import draw_angles
    from wbsa.estimation.methods.body_fit.model import FitBody

    fit_body = FitBody(body_model, 0.05)
    row = reference_adult(0.0)
    row["l_waist_circ"] = 0.4
    rest = body_model.rest_bodies(row)
    for name in ("hands-on-hips", "arms-wide", "feet-apart"):
        angles = draw_angles(name, np.random.default_rng(3))
        expected = pose_vertices(rest.vertices[0], rest.bone_heads[0], angles, body_model.rig)[fit_body.index]
        v, j = fit_body.rest(torch.as_tensor(body_parameter_array(row)))
        got = fit_body.pose(v, j, torch.as_tensor(np.radians(angles))[None])[0].numpy()
        assert np.abs(got - expected).max() < 1e-4, name


def test_fit_recovers_a_known_body_from_a_noise_free_render(render, tmp_path):
    from wbsa.estimation.methods.body_fit import BodyFitSettings, fit_body
    from wbsa.core.mesh_io import read_mesh

    depth, mask, camera, floor, truth = render
    fit = fit_body(depth, mask, camera, floor, settings=BodyFitSettings(**FAST))
    assert abs(fit.wbsa_m2 / truth["wbsa_m2"] - 1) < 0.03, (fit.wbsa_m2, truth["wbsa_m2"])
    assert abs(fit.stature_m - truth["stature_m"]) < 0.02, (fit.stature_m, truth["stature_m"])
    assert abs((fit.azimuth_deg - 25.0 + 180) % 360 - 180) < 8.0, fit.azimuth_deg
    assert abs(fit.distance_m - 2.6) < 0.1 and abs(fit.elevation_deg - 8.0) < 3.0
    assert fit.residual_m < 0.01 and "poor_fit" not in fit.flags
    assert fit.mass_kg == pytest.approx(fit.volume_m3 * 980.0) and fit.bmi == pytest.approx(fit.mass_kg / fit.stature_m**2)
    assert set(fit.tapes) >= {"waist_circ_m", "hip_circ_m"}
    # the observed-pose mesh lies on the seen points: most camera-frame pixels are within 2 cm of it
    path = fit.write_ply(tmp_path / "fit.ply", pose="observed")
    mesh = read_mesh(path)
    assert len(mesh.vertices) == len(fit.posed_vertices) and np.allclose(mesh.vertices, fit.posed_vertices)
    assert np.isfinite(fit.to_dict()["wbsa_m2"])


def test_feet_lost_in_a_noisy_floor_do_not_pull_the_body_up(render_with_body):
    """Where the floor is noisy the segmentation cannot tell the feet from it and the mask ends above them: the
    silhouette does not count the body's vertices in that band, so the true body costs nothing there (counted,
    those vertices alone give it a cost)."""
    import dataclasses as dc

    import torch

    from wbsa.estimation.methods.body_fit.objective import Objective
    from wbsa.estimation.methods.body_fit.observation import observe
    from wbsa.estimation.subject.cloud import Plane
    from wbsa.core.backproject import backproject_depth

    depth, mask, camera, floor, _, body_cam = render_with_body
    noisy = Plane(floor.normal, floor.offset, noise_scale=6.0)  # a floor 6 times the envelope's noise
    height = floor.height(backproject_depth(depth, camera).reshape(-1, 3)).reshape(depth.shape)
    obs = observe(depth, mask, camera, noisy, 1500, np.random.default_rng(0))
    assert 0.04 < obs.floor_band_m < 0.12, obs.floor_band_m
    cut = mask & (height > obs.floor_band_m)  # what such a floor leaves of the feet
    assert (mask & ~cut).sum() > 100
    obs = observe(depth, cut, camera, noisy, 1500, np.random.default_rng(0))
    body = torch.as_tensor((body_cam - obs.origin) @ obs.basis.T, dtype=torch.float32)[None]
    with_band, without = (float(Objective(dc.replace(obs, floor_band_m=band), "geman-mcclure", 0.015, 1.0)
                                .silhouette(body)[0]) for band in (obs.floor_band_m, 0.0))
    assert with_band < 1e-6 and without > 0.01, (with_band, without)


def test_a_stated_layer_of_clothes_is_taken_off_the_fitted_body(dressed_render):
    """Seen in 1.5 cm of clothes, the body fit reads the bare skin when told the layer, and more when not."""
    from wbsa.estimation.methods.body_fit import BodyFitSettings, fit_body

    depth, mask, camera, floor, truth = dressed_render
    stated = fit_body(depth, mask, camera, floor, clothing_m=0.015, settings=BodyFitSettings(**FAST))
    unstated = fit_body(depth, mask, camera, floor, settings=BodyFitSettings(**FAST))
    assert abs(stated.wbsa_m2 / truth["wbsa_m2"] - 1) < 0.03, (stated.wbsa_m2, truth["wbsa_m2"])
    assert unstated.wbsa_m2 > stated.wbsa_m2 * 1.03, (unstated.wbsa_m2, stated.wbsa_m2)


def test_a_fit_past_its_safety_stop_returns_its_best_body_flagged(render):
    from wbsa.estimation.methods.body_fit import BodyFitSettings, fit_body

    depth, mask, camera, floor, _ = render
    # a stop that has passed before the first step, whatever the machine's speed: one step runs, its best body returns
    fit = fit_body(depth, mask, camera, floor, settings=BodyFitSettings(restarts=2, steps=500, time_budget_s=1e-9))
    assert "time_budget" in fit.flags and not fit.converged and fit.steps == 1
    assert np.isfinite(fit.loss) and 1.0 < fit.wbsa_m2 < 3.0


def test_the_budget_is_counted_in_steps_and_a_stop_while_annealing_keeps_a_body(render):
    from wbsa.estimation.methods.body_fit import BodyFitSettings, fit_body

    depth, mask, camera, floor, _ = render
    settings = BodyFitSettings(restarts=2, steps=4)  # every step inside the annealing share
    fits = [fit_body(depth, mask, camera, floor, settings=settings) for _ in range(2)]
    for fit in fits:
        assert fit.steps == 4 and "not_converged" in fit.flags and "time_budget" not in fit.flags
        assert np.isfinite(fit.loss) and 1.0 < fit.wbsa_m2 < 3.0
    assert fits[0].wbsa_m2 == fits[1].wbsa_m2 and fits[0].parameters == fits[1].parameters


def test_bad_inputs_give_one_line_errors(render):
    from wbsa.estimation.methods.body_fit import fit_body

    depth, mask, camera, floor, _ = render
    cases = [
        (depth, np.zeros_like(mask), "no pixel with a depth return"),
        (np.where(mask, np.nan, depth), mask, "not finite"),
        (depth[:-1], mask[:-1], "camera"),
        (depth, mask.astype(np.uint8), "boolean"),
        (-depth, mask, "negative"),
    ]
    for d, m, words in cases:
        with pytest.raises(WbsaError, match=words) as info:
            fit_body(d, m, camera, floor)
        assert "\n" not in str(info.value)
    with pytest.raises(WbsaError, match="clothes"):
        fit_body(depth, mask, camera, floor, clothing_m=0.2)


def test_settings_refuse_bad_values():
    from wbsa.estimation.methods.body_fit import BodyFitSettings

    for bad in (dict(steps=0), dict(restarts=1.5), dict(robust_loss="l2"), dict(data_term="closest"), dict(time_budget_s=-1.0),
                dict(composition="constant"), dict(vertex_spacing_m=1.0)):
        with pytest.raises(SettingsError):
            BodyFitSettings(**bad)


def test_conformal_bounds_are_the_order_statistics_and_refuse_too_few():
    from wbsa.estimation.methods.body_fit.interval import calibrate

    errors = np.linspace(-0.05, 0.03, 39)
    cal = calibrate(errors[::-1], 0.95, "cmd")
    assert (cal.error_lo, cal.error_hi, cal.n) == (errors[0], errors[-1], 39)
    lo, hi = cal.interval(2.0)
    assert lo == pytest.approx(2.0 / 1.03) and hi == pytest.approx(2.0 / 0.95)
    cal80 = calibrate(errors, 0.8, "cmd")  # k = floor(40 * 0.1) = 4 and ceil(40 * 0.9) = 36
    assert (cal80.error_lo, cal80.error_hi) == (errors[3], errors[35])
    with pytest.raises(WbsaError, match="too few"):
        calibrate(errors[:10], 0.95, "cmd")


def test_the_shipped_interval_is_calibrated_on_the_shipped_fit():
    """The interval's conformal bounds hold for the fit they were measured on: rebuild them (the command stored in
    the calibration) whenever a setting that shapes the fitted body changes."""
    from wbsa.estimation.methods.body_fit import BodyFitSettings
    from wbsa.estimation.methods.body_fit.interval import fit_fingerprint, load

    cal = load()
    assert cal is not None and cal.n >= 39 and cal.error_lo < 0 < cal.error_hi
    assert cal.fit == fit_fingerprint(BodyFitSettings()), f"recalibrate: {cal.command}"


def test_the_along_ray_residual_is_the_depth_difference_along_each_ray():
    """A plane seen face-on and obliquely: the residual of each point is its z-depth minus the plane's on its own ray,
    and the triangle its ray meets is found; a ray past the body misses."""
    import torch

    from wbsa.estimation.methods.body_fit.rays import RayTerm
    from wbsa.sensor.technology import camera_model

    # a square in the plane y = 2 - 0.5 x (view frame), seen from the origin looking along +y
    corners = np.array([[-1.0, 2.5, -1.0], [1.0, 1.5, -1.0], [1.0, 1.5, 1.0], [-1.0, 2.5, 1.0]])
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    dirs = np.array([[0.0, 1.0, 0.0], [0.2, 1.0, 0.1], [-0.3, 1.0, -0.2], [3.0, 1.0, 0.0]])
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    t_plane = 2.0 / (dirs[:, 1] + 0.5 * dirs[:, 0])  # y + 0.5 x = 2 along t * d
    observed = dirs * (t_plane + np.array([0.03, -0.02, 0.0, 0.0]))[:, None]
    term = RayTerm(observed, np.zeros(3), np.array([0.0, 1.0, 0.0]), camera_model("kinect-v2"))
    tri, hit, sigma = term.correspondences(corners[None], faces)
    assert hit.numpy()[0].tolist() == [True, True, True, False]
    r = term.residuals_m(torch.as_tensor(corners[None], dtype=torch.float32), torch.as_tensor(tri))[0].numpy()
    expected = np.array([0.03, -0.02, 0.0]) * dirs[:3, 1]  # along-ray difference times the cosine to the axis
    assert np.allclose(r[:3], expected, atol=1e-5)
    assert (sigma.numpy()[0, :3] > 0).all()


def test_the_along_ray_term_weighs_each_reading_by_its_camera_s_sigma():
    """A structured-light camera returns depth in disparity steps of z²·s/(f·b) (Kinect v1 at 4 m: 4.6 cm), which
    widen its σ by step/√12; a time-of-flight camera has none; σ grows with depth and towards grazing."""
    from wbsa.estimation.methods.body_fit.rays import reading_sigma_m
    from wbsa.sensor.technology import axial_sigma_m, camera_model

    v1, v2 = camera_model("kinect-v1"), camera_model("kinect-v2")
    step = 16.0 * 0.125 / (575.8157 * 0.075)
    assert v1.depth_step_per_m * 16.0 == pytest.approx(step) and v2.depth_step_per_m == 0.0
    assert reading_sigma_m(v1, 4.0, 0.0) == pytest.approx(np.hypot(axial_sigma_m(v1, 4.0, 0.0), step / np.sqrt(12.0)))
    assert reading_sigma_m(v2, 4.0, 0.0) == pytest.approx(axial_sigma_m(v2, 4.0, 0.0))
    assert reading_sigma_m(v2, 2.0, 0.0) < reading_sigma_m(v2, 4.0, 0.0) < reading_sigma_m(v2, 4.0, np.radians(80.0))
