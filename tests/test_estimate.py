"""WBSA from one depth image: segmentation of a room, VBSA, prediction through a model file."""

from __future__ import annotations

import json

import numpy as np
import pytest

from wbsa.cli import main
from wbsa.bodies.anthropometry import reference_adult
from wbsa.core.mesh import TriangleMesh


def _quad(corners: np.ndarray) -> TriangleMesh:
    return TriangleMesh(np.asarray(corners, float), np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32))


def _merge(*meshes: TriangleMesh) -> TriangleMesh:
    verts, faces, offset = [], [], 0
    for m in meshes:
        verts.append(m.vertices)
        faces.append(m.faces + offset)
        offset += len(m.vertices)
    return TriangleMesh(np.concatenate(verts), np.concatenate(faces).astype(np.int32))


@pytest.fixture(scope="module")
def room_views(body_model):
    """The front view of an adult alone, and the same view with a floor and a back wall."""
    from wbsa.camera import MeshScene, View, pose_from_view, preset, render

    body = body_model.skin_meshes(reference_adult(0.0))[0]
    floor = _quad([[-3, -3, 0], [3, -3, 0], [3, 3, 0], [-3, 3, 0]])  # counter-clockwise from above
    wall = _quad([[-3, 1.0, 0], [-3, 1.0, 3], [3, 1.0, 3], [3, 1.0, 0]])
    intr = preset("kinect-v1")
    pose = pose_from_view(View(0.0, 0.0, 4.3), body.bbox_center)
    alone = render(MeshScene(body), intr, pose)
    room = render(MeshScene(_merge(body, floor, wall)), intr, pose, roi=False)
    return intr, alone, room


@pytest.fixture(scope="module")
def model_file(tmp_path_factory):
    from wbsa.analysis.fit_views import FitSettings, fit_all
    from helpers.synthetic import synthetic_population, synthetic_scan

    pop = synthetic_population(200, seed=1)
    scan = synthetic_scan(pop, [(0.0, 0.0), (90.0, 0.0)], seed=1)
    out = fit_all(pop, scan, FitSettings(models=("linear",), groups=("all",), k=5))
    path = tmp_path_factory.mktemp("model") / "model.json"
    out.model.save(path)
    return path


def test_segmentation_removes_floor_and_wall(room_views):
    from wbsa.estimation import segment_subject

    intr, alone, room = room_views
    assert room.n_pixels > 3 * alone.n_pixels  # the room fills most of the frame
    mask = segment_subject(room.depth_m, intr)
    truth = alone.depth_m > 0
    iou = (mask & truth).sum() / (mask | truth).sum()
    assert iou > 0.97, iou


def test_estimate_measures_the_visible_area_and_predicts_through_the_model(room_views, model_file):
    from wbsa.analysis.model_file import WbsaModel
    from wbsa.camera import vbsa_visible_m2
    from wbsa.estimation import estimate_wbsa

    intr, alone, room = room_views
    model = WbsaModel.load(model_file)
    est, surface = estimate_wbsa(room.depth_m, intr, model, 0.0, 0.0)
    assert est.method == "grid" and est.vbsa_column == "vbsa_visible_m2"
    assert est.vbsa_m2 == pytest.approx(vbsa_visible_m2(alone), rel=0.03)
    assert surface.area_m2 == pytest.approx(est.vbsa_m2)
    wbsa, lo, hi = model.predict(0.0, 0.0, est.vbsa_m2)
    assert est.wbsa_m2 == pytest.approx(wbsa[0]) and est.wbsa_lo_m2 < est.wbsa_m2 < est.wbsa_hi_m2
    with_stature, _ = estimate_wbsa(room.depth_m, intr, model, 0.0, 0.0, stature_m=1.8)
    assert with_stature.wbsa_m2 != pytest.approx(est.wbsa_m2, rel=1e-9)


def test_estimate_command_from_png(tmp_path, room_views, model_file, capsys):
    from wbsa.core import write_depth_png

    intr, alone, room = room_views
    png = tmp_path / "depth.png"
    write_depth_png(png, room.depth_m)
    rc = main(["estimate", str(png), "--model", str(model_file), "--camera", "kinect-v1", "--azimuth", "0",
               "--elevation", "0", "--json", "--out-mesh", str(tmp_path / "seen.ply")])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["wbsa_lo_m2"] < out["wbsa_m2"] < out["wbsa_hi_m2"]
    assert (tmp_path / "seen.ply").exists()
    for argv, words in ((["--stature-m", "180"], "stature"), (["--elevation", "33"], "elevation"),
                        (["--model", str(tmp_path / "none.json")], "does not exist")):
        base = ["estimate", str(png), "--model", str(model_file)]
        rc = main(base + argv)
        err = capsys.readouterr().err.strip()
        assert rc == 2 and err.startswith("error:") and "\n" not in err, err
        assert words in err, err
