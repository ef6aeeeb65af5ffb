"""The body fit's learned start (phase 1): its crop, its network, its training's determinism and its data's resume."""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from helpers.shapes import body_like  # noqa: E402
from wbsa.errors import WbsaError  # noqa: E402


@pytest.fixture(scope="module")
def figure_scene():
    """A body-like figure (1.75 m, no anny) as a mesh."""
    return body_like(1.75)


def _render(mesh, camera, azimuth_deg: float, distance_m: float, elevation_deg: float = 5.0,
            pan_deg: float = 0.0, tilt_deg: float = 0.0) -> np.ndarray:
    """The depth image (metres, whole millimetres, 0: no return) of ``mesh`` from this view, the camera then
    turned about its own centre by ``pan_deg`` (right) and ``tilt_deg`` (down): the body moves in the image."""
    from wbsa.camera.extrinsics import pose_from_view
    from wbsa.camera.views import View
    from wbsa.testing.plain_render import plain_depth

    pose = pose_from_view(View(azimuth_deg, elevation_deg, distance_m), mesh.bbox_center)
    a, b = np.radians(pan_deg), np.radians(tilt_deg)
    pan = np.array([[np.cos(a), 0.0, -np.sin(a)], [0.0, 1.0, 0.0], [np.sin(a), 0.0, np.cos(a)]])
    tilt = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(b), np.sin(b)], [0.0, -np.sin(b), np.cos(b)]])
    depth, _ = plain_depth(mesh.vertices, mesh.faces, width=camera.width, height=camera.height, fx=camera.fx,
                           fy=camera.fy, cx=camera.cx, cy=camera.cy, rotation=tilt @ pan @ pose.R,
                           center_m=pose.camera_center, rng=None)
    return depth


def _crop(depth: np.ndarray, camera):
    from wbsa.estimation.methods.body_fit.start_crop import start_crop

    return start_crop(depth, depth > 0, camera, None)


def _agreement(a, b) -> tuple[float, float]:
    """(IoU of the two crops' body cells, mean |depth difference| over the shared cells in channel units)."""
    ma, mb = a.image[1] > 0, b.image[1] > 0
    iou = float((ma & mb).sum() / (ma | mb).sum())
    both = ma & mb
    return iou, float(np.abs(a.image[0][both] - b.image[0][both]).mean())


def test_crop_shape_and_channels(figure_scene):
    from wbsa.camera.presets import preset
    from wbsa.estimation.methods.body_fit.start_crop import CROP_SHAPE

    cam = preset("kinect-v2")
    crop = _crop(_render(figure_scene, cam, 20.0, 2.5), cam)
    assert crop.image.shape == (2, *CROP_SHAPE) and crop.image.dtype == np.float32
    assert set(np.unique(crop.image[1])) == {0.0, 1.0}
    assert np.all(crop.image[0][crop.image[1] == 0] == 0.0)
    assert abs(crop.height_m - 1.75) < 0.05  # no floor: the base is the lowest return
    assert 0.08 < crop.image[1].mean() < 0.5


def test_crop_of_a_shifted_or_magnified_image_agrees(figure_scene):
    """The same body placed elsewhere in the image, or seen by a longer lens, gives the same crop; a turned body
    does not (the comparison can fail)."""
    from wbsa.camera.presets import preset

    cam = preset("kinect-v2")
    base = _crop(_render(figure_scene, cam, 20.0, 2.5), cam)
    panned = _render(figure_scene, cam, 20.0, 2.5, pan_deg=9.0, tilt_deg=-4.0)
    moved = np.argwhere(panned > 0).mean(0) - np.argwhere(_render(figure_scene, cam, 20.0, 2.5) > 0).mean(0)
    assert abs(moved[1]) > 40 and abs(moved[0]) > 15  # the body did move in the image
    iou, dz = _agreement(base, _crop(panned, cam))
    assert iou > 0.9 and dz < 0.05
    long_lens = replace(cam, fx=cam.fx * 1.4, fy=cam.fy * 1.4, name="long")
    iou, dz = _agreement(base, _crop(_render(figure_scene, long_lens, 20.0, 2.5), long_lens))
    assert iou > 0.85 and dz < 0.05
    iou_side, _ = _agreement(base, _crop(_render(figure_scene, cam, 90.0, 2.5), cam))
    assert iou_side < 0.75


def test_crop_of_a_farther_body_matches_the_nearer(figure_scene):
    from wbsa.camera.presets import preset

    cam = preset("kinect-v2")
    near = _crop(_render(figure_scene, cam, 20.0, 2.0), cam)
    far = _crop(_render(figure_scene, cam, 20.0, 4.0), cam)
    iou, dz = _agreement(near, far)
    assert iou > 0.85 and dz < 0.06
    assert abs(near.height_m - far.height_m) < 0.03
    assert far.cell_m == pytest.approx(near.cell_m, rel=0.03)


def test_crop_refuses_too_few_returns():
    from wbsa.camera.presets import preset

    cam = preset("kinect-v2")
    depth = np.zeros((cam.height, cam.width))
    depth[200:205, 250:260] = 2.0
    with pytest.raises(WbsaError, match="too few"):
        _crop(depth, cam)


def _tiny_data(n: int = 48, seed: int = 0) -> dict:
    """Random crops and truth in :func:`wbsa.training.start.data.crop_chunk`'s layout."""
    from wbsa.bodies.body_model import BODY_PARAMETER_COLUMNS
    from wbsa.estimation.methods.body_fit.start_crop import CROP_SHAPE

    rng = np.random.default_rng(seed)
    image = np.zeros((n, 2, *CROP_SHAPE), np.float32)
    image[:, 1, 10:80, 20:44] = 1.0
    image[:, 0] = image[:, 1] * rng.normal(0, 0.3, (n, *CROP_SHAPE)).astype(np.float32)
    return {"image": image, "ok": np.ones(n, bool), "subject_id": np.arange(n) // 2,
            "sample": np.arange(n), "height_m": rng.uniform(1.0, 1.9, n), "floor_seen": rng.random(n) < 0.8,
            "male": rng.random(n) < 0.5, "age_years": rng.uniform(5, 80, n), "mass_kg": rng.uniform(20, 110, n),
            "stature_m": rng.uniform(1.0, 1.9, n), "azimuth_deg": rng.uniform(0, 360, n),
            "params": rng.uniform(0, 1, (n, len(BODY_PARAMETER_COLUMNS)))}


def test_network_outputs_and_training_are_deterministic(tmp_path):
    import torch

    from wbsa.estimation.methods.body_fit.start_crop import CROP_SHAPE
    from wbsa.estimation.methods.body_fit.start_net import GAUSSIAN_TARGETS, StartModel, build_net
    from wbsa.training.start.fit import fit_start
    from wbsa.training.start.settings import StartSettings

    net = build_net(CROP_SHAPE, 3)
    mean, log_var, logit = net(torch.zeros(5, 2, *CROP_SHAPE), torch.zeros(5, 2))
    assert mean.shape == log_var.shape == (5, len(GAUSSIAN_TARGETS)) and logit.shape == (5,)
    same = build_net(CROP_SHAPE, 3).state_dict()
    other = build_net(CROP_SHAPE, 4).state_dict()
    assert all(torch.equal(v, same[k]) for k, v in net.state_dict().items())
    assert not all(torch.equal(v, other[k]) for k, v in net.state_dict().items())

    data = _tiny_data()
    settings = StartSettings(n_random=8, n_survey=0, epochs=1, batch=8, seed=5)
    a = fit_start(data, np.ones(48, bool), settings)
    b = fit_start(data, np.ones(48, bool), settings)
    c = fit_start(data, np.ones(48, bool), replace(settings, seed=6))
    assert all(np.array_equal(v, b.state[k]) for k, v in a.state.items())
    assert not all(np.array_equal(v, c.state[k]) for k, v in a.state.items())

    path = a.save(tmp_path / "start.npz")
    assert path.read_bytes() == b.save(tmp_path / "again.npz").read_bytes()  # same seed and data, same bytes
    back = StartModel.load(path)
    from wbsa.estimation.methods.body_fit.start_net import scalar_inputs

    s = scalar_inputs(data["height_m"][:4], data["floor_seen"][:4])
    p, q = a.predict(data["image"][:4], s), back.predict(data["image"][:4], s)
    assert np.array_equal(p["mean"], q["mean"]) and np.array_equal(p["p_male"], q["p_male"])
    assert p["mean"].shape == p["sd"].shape == (4, len(GAUSSIAN_TARGETS)) and np.all(p["sd"] > 0)
    assert np.all((p["azimuth_deg"] >= 0) & (p["azimuth_deg"] < 360))


def test_start_model_refuses_another_file(tmp_path):
    from wbsa.estimation.methods.body_fit.start_net import StartModel

    np.savez(tmp_path / "other.npz", a=np.zeros(3))
    with pytest.raises(WbsaError, match="not a version-1 start model"):
        StartModel.load(tmp_path / "other.npz")


def test_stature_rule_reads_the_best_threshold():
    from wbsa.training.start.fit import stature_sex_rule

    h = np.array([1.55, 1.60, 1.62, 1.70, 1.72, 1.80, 1.85])
    male = np.array([False, False, False, True, False, True, True])
    cut = stature_sex_rule(h, male, np.full(7, 40.0))
    assert 1.62 < cut < 1.70  # five of seven right at 1.66 (or 1.76); the lowest such
    assert stature_sex_rule(h, male, np.where(h < 1.65, 10.0, 40.0)) < 1.70  # children are left out


def test_crop_chunks_resume_after_an_interruption(tmp_path, monkeypatch):
    import pandas as pd

    import wbsa.training.start.data as data_mod
    from wbsa.training.start.settings import StartSettings

    pop = pd.DataFrame({"subject_id": np.arange(10)})
    settings = StartSettings(n_random=10, n_survey=0, chunk_subjects=3, seed=7)
    made = []

    def fake_chunk(population, first_sample, s):  # a chunk's arrays, made from what it was given
        made.append(first_sample)
        if len(made) == 3 and fail[0]:
            raise KeyboardInterrupt
        n = len(population) * s.render.views_per_subject
        return {"sample": first_sample + np.arange(n), "image": np.full((n, 1), float(first_sample), np.float32),
                "subject_id": np.repeat(population["subject_id"].to_numpy(), s.render.views_per_subject)}

    monkeypatch.setattr(data_mod, "crop_chunk", fake_chunk)
    fail = [True]
    with pytest.raises(KeyboardInterrupt):
        data_mod.start_crops(settings, tmp_path / "crops", population=pop, show_progress=False)
    assert len(list((tmp_path / "crops").glob("chunk-*.npz"))) == 2
    made.clear()
    fail[0] = False
    resumed = data_mod.start_crops(settings, tmp_path / "crops", population=pop, show_progress=False)
    v = settings.render.views_per_subject
    assert made == [6 * v, 9 * v]  # only the chunks not finished before
    made.clear()
    whole = data_mod.start_crops(settings, None, population=pop, show_progress=False)
    assert all(np.array_equal(resumed[k], whole[k]) for k in whole)
    assert np.array_equal(whole["sample"], np.arange(10 * v))
    with pytest.raises(WbsaError, match="other training settings"):
        data_mod.start_crops(replace(settings, seed=8), tmp_path / "crops", population=pop, show_progress=False)


def test_train_start_command_refuses_bad_options():
    from wbsa.cli import main

    assert main(["train-start", "--views", "0"]) == 2
    assert main(["train-start", "--seed", "1000"]) == 2
    assert main(["train-start", "--subjects", "2", "--survey-subjects", "0"]) == 2
