"""The estimator's method slot: one Predictor per route, one dispatch point, the routes side by side."""

from __future__ import annotations

import numpy as np
import pytest

from wbsa.errors import WbsaError


@pytest.fixture(scope="module")
def person_view(body_model):
    """A noisy Kinect v2 view of one adult in a room, 2.5 m away (a floor, a wall 0.8 m behind), and its truth."""
    from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters
    from wbsa.bodies.table import measure_population
    from wbsa.camera import MeshScene, View, preset
    from wbsa.sensor.settings import SensorSettings
    from wbsa.simulate import simulate_view
    from wbsa.training.room import compose_room

    pop = measure_population(sample_random_parameters(RandomPopulationSettings(n=1, seed=11, age_years=(25, 50),
                                                                               age_sampling="years")),
                             show_progress=False)
    mesh = body_model.skin_mesh(body_model.rest_bodies(pop).vertices[0])
    room = compose_room(mesh, 10.0, wall_behind_m=0.8)
    camera = preset("kinect-v2")
    sim = simulate_view(MeshScene(room.mesh, surroundings=True), camera, View(10.0, 8.0, 2.5),
                        sensor=SensorSettings(noise="nguyen2012"), seed=4, keep_frame=True,
                        target=room.subject_center)
    return sim.frame.depth_m, camera, float(pop["wbsa_m2"].iloc[0])


def test_the_dispatch_point_picks_one_predictor_per_method():
    from wbsa.estimation.methods import predictor_for, predictors_for
    from wbsa.estimation.methods.body_fit.predictor import BodyFitPredictor
    from wbsa.estimation.methods.regression.predictor import RegressionPredictor

    (regression,), (body_fit,) = predictors_for("regression"), predictors_for("body-fit")
    assert isinstance(regression, RegressionPredictor) and isinstance(body_fit, BodyFitPredictor)
    assert [p.name for p in predictors_for("both")] == ["regression", "body-fit"]
    with pytest.raises(WbsaError, match="estimation method 'fit' is unknown; use one of regression, body-fit, both"):
        predictors_for("fit")
    with pytest.raises(WbsaError, match="the body fit uses no estimator model"):
        predictors_for("body-fit", "model.npz")
    with pytest.warns(DeprecationWarning, match="use predictors_for"):
        assert isinstance(predictor_for("body-fit"), BodyFitPredictor)  # the old name, for one release


def test_the_regression_route_reads_the_shipped_model(person_view):
    from wbsa.estimation import estimate

    depth, camera, truth = person_view
    est = estimate(depth, camera)
    assert est.method == "regression" and est.model == "default" and est.body is None and not est.routes
    assert est.wbsa_lo_m2 < truth < est.wbsa_hi_m2
    assert abs(est.wbsa_m2 / truth - 1) < 0.06


@pytest.mark.slow
def test_both_routes_report_side_by_side_with_the_fitted_body(person_view, tmp_path, capsys):
    """``both``: the regression's number leads, the body fit's is beside it with its fitted body. The CLI's own
    fit, at a budget of 3 steps and 2 restarts (what its options ask, the fit's accuracy being the Python call's),
    writes its body at rest and as seen: the files are the body its JSON describes."""
    import json

    from PIL import Image

    from wbsa.cli import main
    from wbsa.core.mesh_io import read_mesh
    from wbsa.estimation import estimate

    depth, camera, truth = person_view
    est = estimate(depth, camera, method="both")
    assert set(est.routes) == {"regression", "body-fit"}
    assert est.wbsa_m2 == est.routes["regression"].wbsa_m2
    fit = est.body
    assert abs(est.routes["body-fit"].wbsa_m2 / truth - 1) < 0.10 and fit.wbsa_m2 == est.routes["body-fit"].wbsa_m2
    assert abs(fit.stature_m - est.stature_m) < 0.06 and 10 < fit.mass_kg < 200  # the point cloud's stature
    overlap = not (est.routes["regression"].wbsa_hi_m2 < est.routes["body-fit"].wbsa_lo_m2
                   or est.routes["body-fit"].wbsa_hi_m2 < est.routes["regression"].wbsa_lo_m2)
    assert ("methods_disagree" in est.flags) is not overlap
    png = tmp_path / "depth.png"
    Image.fromarray(np.round(depth * 1000).astype(np.uint16)).save(png)
    # the command line's own fit, at the budget its options ask (its writers and options are what is tested)
    assert main(["estimate", str(png), "--camera", "kinect-v2", "--method", "body-fit", "--body-fit-restarts", "2",
                 "--body-fit-steps", "3", "--out-body", str(tmp_path / "body.ply"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["method"] == "body-fit" and out["body"]["restarts"] == 2 and out["body"]["steps"] <= 3
    rest, seen = read_mesh(tmp_path / "body.ply"), read_mesh(tmp_path / "body-observed.ply")
    assert rest.area_m2 == pytest.approx(out["wbsa_m2"], rel=0.05) and len(seen.vertices) == len(rest.vertices)
    assert np.ptp(rest.vertices[:, 2]) == pytest.approx(out["body"]["stature_m"], abs=0.005)  # at rest, +z up


def test_what_a_route_cannot_serve_is_refused_before_any_work(person_view, tmp_path, capsys):
    from wbsa.cli import main
    from wbsa.estimation import estimate

    depth, camera, _ = person_view
    with pytest.raises(WbsaError, match="calibrated at level 0.95 only"):
        estimate(depth, camera, method="body-fit", level=0.8)
    np.save(tmp_path / "d.npy", depth)
    assert main(["estimate", str(tmp_path / "d.npy"), "--camera", "kinect-v2", "--out-body",
                 str(tmp_path / "b.ply")]) == 2
    assert "--out-body writes the fitted body of --method body-fit or both" in capsys.readouterr().err
    assert not (tmp_path / "b.ply").exists()


def test_the_body_fit_reads_its_shipped_interval_and_its_level():
    """The calibration ships in wbsa/data; a level it was not calibrated at is refused in one line."""
    from wbsa.estimation.methods.body_fit.interval import load
    from wbsa.estimation.methods import Request, predictors_for

    calibration = load()
    assert calibration is not None and calibration.level == 0.95 and calibration.error_lo < 0 < calibration.error_hi
    (body_fit,) = predictors_for("body-fit")
    body_fit.check_request(Request(level=0.95))
    with pytest.raises(WbsaError, match="calibrated at level 0.95 only"):
        body_fit.check_request(Request(level=0.8))


def test_both_keeps_the_regression_when_the_body_fit_cannot_serve(person_view):
    """A level the body fit's interval is not calibrated at: the body fit refuses, the regression's answer stands,
    flagged body_fit_failed."""
    from wbsa.estimation import estimate

    depth, camera, _ = person_view
    est = estimate(depth, camera, method="both", level=0.8)
    assert est.body is None and "regression" in est.routes and "body-fit" not in est.routes
    assert "calibrated at level 0.95 only" in est.flags["body_fit_failed"]


def test_every_flag_raised_has_one_record_and_every_record_is_raised():
    """A flag written anywhere in the code (``...flags["name"] = ...``, or a key of a dict built in a ``*_flags``
    check) has its record in :data:`wbsa.estimation.flags.FLAG_RECORDS`, and no record is dead."""
    import ast
    from pathlib import Path

    import wbsa
    from wbsa.estimation.flags import FLAG_RECORDS, FLAGS

    raised = set()
    for path in Path(wbsa.__file__).parent.rglob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if (isinstance(node, ast.Subscript) and isinstance(node.ctx, ast.Store) and isinstance(node.slice, ast.Constant)
                    and ast.unparse(node.value).endswith("flags")):
                raised.add(node.slice.value)
            if isinstance(node, ast.FunctionDef) and node.name.endswith("_flags"):
                raised |= {k.value for d in ast.walk(node) if isinstance(d, ast.Dict)
                           for k in d.keys if isinstance(k, ast.Constant)}
    assert raised == set(FLAG_RECORDS)
    assert FLAGS == {name: flag.meaning for name, flag in FLAG_RECORDS.items()}
    assert all(flag.routes and set(flag.routes) <= {"image", "regression", "body-fit", "both"} and flag.meaning
               and flag.advice for flag in FLAG_RECORDS.values())


def _printed(monkeypatch, tmp_path, est, *options):
    """``wbsa estimate`` of a 512 x 424 frame whose estimate is ``est`` (the printing and the JSON are tested, not
    the measuring): (exit status, stdout, stderr)."""
    from helpers.cli import run_cli

    monkeypatch.setattr("wbsa.estimation.single_view.estimate_request", lambda request, depth, model, **kw: est)
    np.save(tmp_path / "d.npy", np.zeros((424, 512)))
    return run_cli("estimate", tmp_path / "d.npy", "--camera", "kinect-v2", *options)


def test_the_terminal_says_the_fits_flags_in_plain_words_and_the_json_keeps_their_details(monkeypatch, tmp_path):
    """A body fit's flags whose details are its internals (a parameter's name, a joint's, a residual) are said on
    the terminal as the page says them: the meaning and what to do; the JSON keeps the details. A flag whose
    detail is the fix in command-line words keeps it."""
    import json

    from helpers.estimates import estimate_of, fitted_body, route
    from wbsa.estimation.flags import CLOTHES_UNSTATED, FLAG_RECORDS

    internals = {"outside_model_range": "p_muscle = 0.00, p_weight = 1.00", "posture_at_limit": "elbow_l_flexion_deg",
                 "poor_fit": "residual 46.5 mm, 61 % of points within 3 cm", "not_converged": "120 steps without settling"}
    plain = {"several_people": "3 person-sized objects; picked the nearest; give --pick X,Y to choose",
             "clothes_unstated": CLOTHES_UNSTATED}  # Python's words in the estimate, the option's on the terminal
    fit = route(1.8, 1.7, 1.9, "body-fit (anny)", internals, body=fitted_body(flags=internals))
    est = estimate_of(fit, internals | plain, method="body-fit")
    code, out, err = _printed(monkeypatch, tmp_path, est)
    assert code == 0
    for name, detail in internals.items():
        record = FLAG_RECORDS[name]
        assert f"warning: {name}: {record.meaning}. {record.advice}\n" in err and detail not in err
    assert "p_muscle" not in err and "elbow_l" not in err and " mm" not in err.split("fitted body")[0]
    assert f"warning: several_people: {plain['several_people']}\n" in err
    assert "state them (--clothes underwear, thin-gown, light or street)\n" in err and "clothes='" not in err
    code, out, _ = _printed(monkeypatch, tmp_path, est, "--json")
    assert code == 0 and json.loads(out)["flags"] == internals | plain


def test_the_json_says_each_number_once_and_the_body_fits_time_counts_every_fit(monkeypatch, tmp_path):
    """Named clothes widen each route's interval by a second prediction, dressed thicker; the body fit's second
    fit widens its body's interval as its route's and adds its time: the JSON states the area and interval once
    (the route's), and the time printed and in the JSON is that of both fits."""
    import json

    from helpers.estimates import estimate_of, fitted_body, route
    from wbsa.estimation.clothes import CLOTHES
    from wbsa.estimation.methods.base import Request
    from wbsa.estimation.single_view import _clothes_widened

    class Route:
        def __init__(self, name, again, refuses=False):
            self.name, self.again, self.refuses = name, again, refuses

        def check_request(self, request):
            if self.refuses:
                raise WbsaError("this model takes no clothes")

        def predict(self, subject, request):
            assert request.clothing_m == pytest.approx(CLOTHES["street"].layer_m + CLOTHES["street"].sd_m)
            return self.again

    regression = route(1.85, 1.75, 1.95)
    fit = route(1.80, 1.70, 1.90, "body-fit (anny)", body=fitted_body(1.80, 1.70, 1.90, seconds=11.5))
    again = route(1.70, 1.60, 1.80, "body-fit (anny)", body=fitted_body(1.70, 1.60, 1.80, seconds=8.5))
    lead, routes = _clothes_widened(regression, {"regression": regression, "body-fit": fit},
                                    [Route("regression", None, refuses=True), Route("body-fit", again)], None,
                                    Request(clothing_m=CLOTHES["street"].layer_m), CLOTHES["street"])
    widened = routes["body-fit"]
    assert lead == regression and (widened.wbsa_lo_m2, widened.wbsa_hi_m2) == pytest.approx((1.60, 2.00))  # ± 0.1
    assert (widened.body.wbsa_lo_m2, widened.body.wbsa_hi_m2, widened.body.seconds) == (widened.wbsa_lo_m2,
                                                                                       widened.wbsa_hi_m2, 20.0)
    est = estimate_of(lead, {}, routes, method="both")
    code, out, _ = _printed(monkeypatch, tmp_path, est, "--json")
    answer = json.loads(out)
    assert code == 0 and answer["routes"]["body-fit"]["wbsa_lo_m2"] == pytest.approx(1.60)
    assert not {"wbsa_m2", "wbsa_lo_m2", "wbsa_hi_m2", "level"} & set(answer["body"]) and answer["body"]["seconds"] == 20.0
    code, out, _ = _printed(monkeypatch, tmp_path, est)
    assert code == 0 and "body-fit: WBSA 1.800 m² (1.600–2.000 m²)" in out and "fitted in 20.0 s" in out


def test_the_body_fit_settings_reach_the_fit_through_estimate(person_view):
    """``wbsa.estimate(..., body_fit=BodyFitSettings(...))`` is the fit's budget; refused with the regression."""
    import wbsa

    depth, camera, _ = person_view
    est = wbsa.estimate(depth, camera, method="body-fit", body_fit=wbsa.BodyFitSettings(steps=3, restarts=2))
    assert est.body.steps <= 3 and est.body.restarts == 2
    with pytest.raises(WbsaError, match="body-fit settings go with method body-fit or both"):
        wbsa.estimate(depth, camera, body_fit=wbsa.BodyFitSettings(steps=3))
    with pytest.raises(WbsaError, match="body_fit must be BodyFitSettings or None, got dict"):
        wbsa.estimate(depth, camera, method="both", body_fit={"steps": 3})


def test_the_cli_body_fit_options_reach_the_settings_and_are_checked(tmp_path):
    from helpers.cli import assert_one_line_error, run_cli

    depth = tmp_path / "d.npy"
    np.save(depth, np.zeros((424, 512)))
    code, _, err = run_cli("estimate", depth, "--method", "body-fit", "--body-fit-steps", "0")
    assert_one_line_error(code, err, "--body-fit-steps must be a whole number of at least 1, got 0")
    code, _, err = run_cli("estimate", depth, "--body-fit-restarts", "2")
    assert_one_line_error(code, err, "body-fit settings go with method body-fit or both")


def test_auto_camera_is_the_one_preset_of_the_image_size(person_view):
    """``camera="auto"``: the preset of the image's size, flagged; the same estimate as naming it. A size two
    presets share (848 x 480; 640 x 480: tests/test_real_frames.py) is refused in one line naming both."""
    from wbsa.camera.presets import camera_for_image
    from wbsa.estimation import estimate

    depth, camera, _ = person_view
    auto = estimate(depth, "auto")
    named = estimate(depth, camera.name)
    assert auto.camera == "kinect-v2" and "kinect-v2 preset fits the image size (512 x 424)" in auto.flags.pop(
        "camera_assumed")
    assert auto.to_dict() == named.to_dict()
    with pytest.raises(WbsaError, match="848x480 pixels fits 2 cameras .*add --camera realsense-d435 or --camera "
                                        "realsense-d455"):
        camera_for_image((480, 848))
    with pytest.raises(WbsaError, match="a 10x10 depth image fits none of the presets"):
        estimate(np.ones((10, 10)), "auto")
