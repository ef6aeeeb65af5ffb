"""The whole-body fit to one depth view (``wbsa.estimation.methods.body_fit``, issue 28)."""

from __future__ import annotations

import numpy as np
import pytest

from wbsa.errors import SettingsError, WbsaError

#: Settings small enough for the test suite (the fit's defaults use more restarts and steps).
FAST = dict(restarts=3, steps=120)


@pytest.fixture(scope="module")
def render(body_model):
    """A noise-free Kinect v2 render (azimuth 25°, 2.6 m) of a known anny woman with arms down, on a floor.

    Returns (depth, mask, camera, floor Plane, truth measures).
    """
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
    return depth, mask, camera, floor, truth


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
        fit_body(depth, mask, camera, floor, clothing_m=0.01)


def test_settings_refuse_bad_values():
    from wbsa.estimation.methods.body_fit import BodyFitSettings

    for bad in (dict(steps=0), dict(restarts=1.5), dict(robust_loss="l2"), dict(time_budget_s=-1.0),
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
