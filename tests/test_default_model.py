"""The shipped default model: its recipe, its card, its size, and a small rebuild through the same code path."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys

import numpy as np
import pytest

from wbsa.errors import WbsaError


def test_the_shipped_model_matches_its_recipe():
    """Changing the training settings or the revision without ``wbsa train --default`` fails here."""
    from wbsa.estimation.methods.regression.default_model import default_model, default_model_path, model_card
    from wbsa.estimation.methods.regression.model import VERSION
    from wbsa.training.recipe import MODEL_REVISION, settings_hash
    from wbsa.training.settings import TrainSettings

    card, model = model_card(), default_model()
    expected = settings_hash(TrainSettings())
    assert card["settings_hash"] == expected and model.meta["settings_hash"] == expected, \
        "TrainSettings() changed: rebuild the shipped model with `wbsa train --default`"
    assert card["revision"] == MODEL_REVISION == model.meta["revision"], \
        "MODEL_REVISION changed: rebuild the shipped model with `wbsa train --default`"
    assert card["file_format"]["version"] == VERSION == model.meta["version"]
    assert card["calibration"] == model.meta["calibration"]
    assert card["trained_ranges"] == model.meta["ranges"]
    size_mb = default_model_path().stat().st_size / 1e6
    assert size_mb < 8.0, f"the shipped model is {size_mb:.1f} MB"


def test_the_card_says_what_the_model_was_trained_on():
    from wbsa.camera.presets import TRAINED_CAMERAS
    from wbsa.estimation.methods.regression.default_model import model_card

    world = model_card()["trained_on"]
    assert [c["name"] for c in world["cameras"]] == list(TRAINED_CAMERAS)
    assert world["distance_m"] == [1.5, 4.5] and world["clothes"]["layer_m"] == [0.0, 0.015]
    assert world["subjects"]["random"] + world["subjects"]["survey_matched_nhanes"] == 1380


def test_the_run_time_estimator_imports_no_training_code():
    """``wbsa.estimate`` with the shipped model answers without importing wbsa.training or scikit-learn."""
    code = ("import sys, numpy as np, wbsa\n"
            "from wbsa.estimation.methods.regression.default_model import default_model\n"
            "from wbsa.estimation.methods import predictors_for\n"
            "predictors_for('regression', None)\n"
            "bad = [m for m in sys.modules if m.startswith(('wbsa.training', 'wbsa.testing', 'sklearn'))]\n"
            "print(bad)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", out.stdout + out.stderr


@pytest.mark.slow
def test_a_small_rebuild_through_the_same_code_path_is_a_loadable_model_and_resumes(small_training_run, tmp_path,
                                                                                     monkeypatch):
    """``wbsa.train`` on a few subjects (the run's small model, tests/conftest.py) writes a model of the shipped
    format; a second run in a folder holding its renders (as a run killed after its renders would leave it)
    renders nothing and fits the same model; renders of other settings are refused."""
    import shutil

    from helpers.training import small_training_settings
    from wbsa.estimation.methods.regression.default_model import default_model_path
    from wbsa.estimation.methods.regression.model import EstimatorModel
    from wbsa.training import renders
    from wbsa.training.run import train

    first = small_training_run / "model.npz"
    loaded = EstimatorModel.load(first)
    with np.load(first, allow_pickle=False) as small, np.load(default_model_path(), allow_pickle=False) as shipped:
        assert set(small.files) == set(shipped.files)
        assert json.loads(str(small["meta_json"]))["version"] == json.loads(str(shipped["meta_json"]))["version"]
    assert sorted(p.name for p in (small_training_run / "renders").iterdir()) == ["calibration", "fit"]
    shutil.copytree(small_training_run / "renders", tmp_path / "run" / "renders")
    chunks = []
    render_chunk = renders.render_chunk
    monkeypatch.setattr(renders, "render_chunk", lambda *a, **k: chunks.append(1) or render_chunk(*a, **k))
    again = train(small_training_settings(), tmp_path / "run", workers=1, show_progress=False)
    assert chunks == []  # every render read back, none rendered again
    for key in ("coef", "scores", "spread_coef", "mean", "scale"):
        assert np.array_equal(getattr(EstimatorModel.load(again.path), key), getattr(loaded, key))
    assert "calibration: WBSA MAPE" in again.summary()
    with pytest.raises(WbsaError, match="renders of other training settings"):
        train(dataclasses.replace(small_training_settings(), seed=4), tmp_path / "run", workers=1, show_progress=False)
    assert chunks == []


def test_train_refuses_bad_settings_in_one_line(tmp_path, capsys):
    from wbsa.cli import main

    (tmp_path / "not-intrinsics.json").write_text('{"hello": 1}')
    cases = [(["--camera", str(tmp_path / "not-intrinsics.json")], "it needs width, height and intrinsic_matrix"),
             (["--distance", "0.2,3"], "0.5 <= LOW <= HIGH <= 8 m"),
             (["--distance", "2,9"], "0.5 <= LOW <= HIGH <= 8 m"),
             (["--camera", "kinect-v9"], "unknown camera preset 'kinect-v9'"),
             (["--disparity", "0.05,0.1"], "--disparity goes with --camera"),
             (["--default", "--subjects", "10"], "--default rebuilds the shipped model")]
    for extra, words in cases:
        assert main(["train", "--out", str(tmp_path / "run"), *extra]) == 2
        err = capsys.readouterr().err
        assert words in err and err.count("\n") == 1, err
    assert not (tmp_path / "run").exists()  # nothing written


def test_a_folder_another_run_holds_is_refused(tmp_path):
    from wbsa.training.settings import RenderSettings
    from wbsa.training.run import train
    from wbsa.training.settings import TrainSettings

    settings = TrainSettings(n_random=24, n_survey=0, render=RenderSettings(views_per_subject=2))
    code = ("import sys, time\nfrom wbsa.folder_lock import folder_lock\n"
            f"with folder_lock({str(tmp_path / 'run')!r}):\n    print('held', flush=True); time.sleep(30)\n")
    holder = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(WbsaError, match="training folder"):
            train(settings, tmp_path / "run", workers=1, show_progress=False)
    finally:
        holder.kill()


def test_training_without_scikit_learn_names_the_install_command(monkeypatch):
    import builtins

    from wbsa.training.run import check_training_dependencies

    real_import = builtins.__import__

    def no_sklearn(name, *args, **kwargs):
        if name == "sklearn" or name.startswith("sklearn."):
            raise ImportError("No module named 'sklearn'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_sklearn)
    with pytest.raises(WbsaError, match=r"pip install 'wbsa\[train\]'"):
        check_training_dependencies()
