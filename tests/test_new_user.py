"""What a new user trips on (issue 30): strict inputs, strict outputs, a happy path without warnings."""

from __future__ import annotations

import json

import numpy as np
import pytest

from wbsa.errors import WbsaError
from helpers.cli import assert_one_line_error, run_cli


def strict_json(text: str):
    """``json.loads`` that refuses NaN and Infinity (as Node, jq and FHIR tooling do)."""
    def refuse(name):
        raise AssertionError(f"{name} in JSON output")

    return json.loads(text, parse_constant=refuse)


def _box(size_m=(0.4, 0.2, 1.7)):
    """A closed box (vertices (8, 3) in metres, faces (12, 3)) standing on z = 0."""
    sx, sy, sz = size_m
    corners = np.array([[x, y, z] for x in (-sx / 2, sx / 2) for y in (-sy / 2, sy / 2) for z in (0.0, sz)])
    faces = np.array([[0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6], [0, 1, 3], [0, 3, 2],
                      [4, 6, 7], [4, 7, 5], [1, 5, 7], [1, 7, 3], [0, 2, 6], [0, 6, 4]])
    return corners, faces


# --- 1. mesh units -------------------------------------------------------------------------------------------

@pytest.mark.parametrize("scale,units,guess", [(1000.0, "m", "mm"), (100.0, "m", "cm"), (1 / 0.0254, "m", "in"),
                                               (1.0, "mm", "m"), (100.0, "mm", "cm")])
def test_a_mesh_in_other_units_is_refused_with_the_right_fix(tmp_path, scale, units, guess):
    from wbsa.core.mesh import TriangleMesh
    from wbsa.core.mesh_io import write_mesh

    v, f = _box()
    path = write_mesh(TriangleMesh(v * scale, f), tmp_path / "box.ply")
    code, out, err = run_cli("view", path, "--units", units, "--json")
    assert_one_line_error(code, err, f"give --units {guess}")
    assert out == ""
    if units == "m":  # the API: a mesh is in metres
        import wbsa

        with pytest.raises(WbsaError, match=f"scale its vertices by {1.0 / scale:g}"):
            wbsa.render(TriangleMesh(v * scale, f))


def test_a_mesh_of_no_person_size_in_any_units_is_refused(tmp_path):
    from wbsa.core.mesh import TriangleMesh
    from wbsa.core.mesh_io import write_mesh

    v, f = _box()
    path = write_mesh(TriangleMesh(v * 1e6, f), tmp_path / "huge.ply")
    code, _, err = run_cli("view", path, "--json")
    assert_one_line_error(code, err, "in any of metres, centimetres, millimetres, inches")


def test_a_mesh_in_the_stated_units_is_measured(tmp_path):
    from wbsa.core.mesh import TriangleMesh
    from wbsa.core.mesh_io import write_mesh

    v, f = _box()
    metres = json.loads(run_cli("view", write_mesh(TriangleMesh(v, f), tmp_path / "m.ply"), "--json")[1])
    code, out, err = run_cli("view", write_mesh(TriangleMesh(v / 0.0254, f), tmp_path / "in.ply"), "--units", "in",
                             "--json")
    assert code == 0 and err == "", err
    assert json.loads(out)["mesh_area_m2"] == pytest.approx(metres["mesh_area_m2"], rel=1e-9)


# --- 2. view angles ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("flag,value,fragment", [("--azimuth", "400", "-360 to 360 degrees"),
                                                 ("--elevation", "95", "-90 to 90 degrees"),
                                                 ("--elevation", "0:120:30", "got 120")])
def test_view_angles_out_of_range_are_refused_not_wrapped(tmp_path, flag, value, fragment):
    from wbsa.core.mesh import TriangleMesh
    from wbsa.core.mesh_io import write_mesh

    path = write_mesh(TriangleMesh(*_box()), tmp_path / "box.ply")
    code, out, err = run_cli("view", path, flag, value, "--json")
    assert_one_line_error(code, err, fragment)
    code, out, err = run_cli("view", path, "--azimuth", "-30", "--json")  # the subject's right: in range
    assert code == 0 and strict_json(out)["azimuth_deg"] == 330.0


def test_view_angles_are_checked_where_they_enter_the_library():
    import wbsa
    from wbsa.scan.settings import ScanSettings

    with pytest.raises(WbsaError, match="view azimuth_deg must be -360 to 360 degrees"):
        wbsa.render(_box(), "kinect-v1", (400, 0, 3.0))
    with pytest.raises(WbsaError, match="view elevation_deg must be -90 to 90 degrees"):
        wbsa.render(_box(), "kinect-v1", (0, 95, 3.0))
    with pytest.raises(WbsaError, match="^azimuths_deg must be -360 to 360 degrees"):
        ScanSettings(azimuths_deg=(0.0, 400.0))
    with pytest.raises(WbsaError, match="^elevation_deg must be -90 to 90"):
        wbsa.estimate(np.ones((480, 640)), "kinect-v1", elevation_deg=95)
    with pytest.raises(WbsaError, match="^azimuth_deg must be -360 to 360"):
        wbsa.estimate(np.ones((480, 640)), "kinect-v1", azimuth_deg=float("nan"))


# --- 3. strict machine-readable output -----------------------------------------------------------------------

@pytest.fixture(scope="module")
def body_depth(tmp_path_factory, body_model):
    """A body mesh file, and the 16-bit depth PNG of its front view by a Kinect v2 at 2.5 m (the body alone)."""
    from wbsa.camera import MeshScene, View, preset
    from wbsa.core import write_depth_png
    from wbsa.core.mesh_io import read_mesh
    from wbsa.simulate import simulate_view

    root = tmp_path_factory.mktemp("body")
    assert run_cli("body", "--out", root / "body.ply")[0] == 0
    frame = simulate_view(MeshScene(read_mesh(root / "body.ply")), preset("kinect-v2"), View(0.0, 0.0, 2.5),
                          keep_frame=True).frame
    write_depth_png(root / "depth.png", frame.depth_m)
    return root / "body.ply", root / "depth.png"


@pytest.fixture(scope="module")
def fit_model(tmp_path_factory):
    """A ``wbsa fit`` model (Kinect v1 at 4.3 m, three views) from synthetic tables: it estimates no view."""
    from helpers.synthetic import synthetic_population, synthetic_scan
    from wbsa.analysis.fit_views import fit_all
    from wbsa.analysis.settings import FitSettings

    pop = synthetic_population(200, seed=1)
    out = fit_all(pop, synthetic_scan(pop, [(0.0, 0.0), (30.0, 0.0), (90.0, 0.0)], seed=1),
                  FitSettings(models=("linear",), groups=("all",), k=5))
    path = tmp_path_factory.mktemp("fit") / "model.json"
    out.model.save(path)
    return path


def test_every_json_and_fhir_output_parses_strictly(body_depth, fit_model, monkeypatch):
    """``--json``/``--fhir`` of every command that has them, through a parser that refuses NaN/Infinity; a
    number that was not estimated is null, and the flags say why."""
    monkeypatch.setenv("WBSA_CACHE_DIR", "/nonexistent/wbsa-cache")  # no default model to borrow a view from
    mesh, depth = body_depth
    outputs = {}
    for argv in (["bsa", "--height-cm", "170", "--weight-kg", "70", "--json"],
                 ["bsa", "--height-cm", "170", "--weight-kg", "70", "--sex", "female", "--formula", "schlich", "--json"],
                 ["view", mesh, "--json"], ["view", mesh, "--azimuth", "0,90", "--reconstruct", "grid", "--json"],
                 ["view", mesh, "--distance", "1e4", "--json"],  # sees nothing
                 ["estimate", depth, "--camera", "kinect-v2", "--model", fit_model, "--azimuth", "0", "--json"],
                 ["estimate", depth, "--camera", "kinect-v2", "--model", fit_model, "--azimuth", "0", "--fhir"]):
        code, out, err = run_cli(*argv)
        assert code == 0, (argv, err)
        outputs[" ".join(map(str, argv[:1] + argv[-1:]))] = strict_json(out)
    est = outputs["estimate --json"]
    # a wbsa fit model borrows the shipped model's view estimate: a number, not a NaN
    assert isinstance(est["view"]["azimuth_deg"], float) and "view_not_estimated" not in est["flags"]
    assert est["view_used"]["azimuth_deg"] == 0.0 and est["wbsa_m2"] > 1.0
    code, out, err = run_cli("estimate", depth, "--camera", "kinect-v2", "--model", fit_model, "--azimuth", "0")
    assert code == 0 and "nan" not in out.lower(), out


def test_written_json_files_are_strict(tmp_path):
    from wbsa.io import write_json

    path = write_json({"a": float("nan"), "b": [np.inf, 1.0]}, tmp_path / "x.json")
    assert strict_json(path.read_text()) == {"a": None, "b": [None, 1.0]}


# --- 4. wbsa run overrides -----------------------------------------------------------------------------------

def test_run_overrides_are_written_into_the_resolved_settings(tmp_path):
    import tomllib

    code, out, err = run_cli("run", "--print-config", "--n", "20", "--views", "front", "--k", "3", "--camera",
                             "kinect-v2", "--distance", "2.5,3", "--title", "my small study")
    assert code == 0, err
    t = tomllib.loads(out)
    assert t["population"]["n"] == 20 and t["scan"]["views"] == "front" and t["fit"]["k"] == 3
    assert t["scan"]["camera"] == "kinect-v2" and t["scan"]["distances_m"] == [2.5, 3.0]
    assert t["study"] == {"name": "my small study", "description": ""}  # not the demo's description
    code, _, err = run_cli("run", "--print-config", "--n", "0")
    assert_one_line_error(code, err, "[population] n")
    code, _, err = run_cli("run", "--print-config", "--distance", "far")
    assert_one_line_error(code, err, "--distance must be metres")


def test_a_study_file_without_a_study_table_does_not_inherit_the_demo_title(tmp_path):
    import tomllib

    path = tmp_path / "mine.toml"
    path.write_text("[population]\nn = 10\n")
    code, out, err = run_cli("run", "--config", path, "--print-config")
    assert code == 0, err
    assert tomllib.loads(out)["study"] == {"name": "mine", "description": ""}
    assert "demo" not in tomllib.loads(run_cli("run", "--print-config", "--n", "10")[1])["study"]["name"]
    assert "demo" in tomllib.loads(run_cli("run", "--print-config")[1])["study"]["name"]  # the demo itself


def test_a_view_set_with_angle_lists_is_refused_and_views_replace_inherited_lists(tmp_path):
    import wbsa

    path = tmp_path / "both.toml"
    path.write_text('[population]\nn = 10\n[scan]\nviews = "front"\nazimuths_deg = [0, 30]\n')
    code, _, err = run_cli("run", "--config", path, "--print-config")
    assert_one_line_error(code, err, "views = 'front' and azimuths_deg contradict")
    code, out, err = run_cli("run", "--config", path, "--views", "paper", "--print-config")  # the flag wins
    assert code == 0 and 'views = "paper"' in out and "azimuths_deg = []" in out, err
    angles = wbsa.Study.from_toml("default").replace(scan={"azimuths_deg": [0, 30]})
    front = angles.replace(scan={"views": "front"})
    assert len(front.settings.scan.view_list(4.3)) == 1


def test_the_worker_count_recorded_is_the_one_used(tmp_path, monkeypatch):
    """``--workers 1`` was recorded as 0; the pipeline's recorded settings are now those it ran with."""

    import wbsa.study.pipeline as pipeline

    seen = {}

    def stop(settings, out, run, *args):
        seen["settings"], seen["run"] = settings, run
        raise WbsaError("stopped before any work")

    monkeypatch.setattr(pipeline, "_run_locked", stop)
    from wbsa.study.settings import load_settings

    settings = load_settings(None, {"population": {"n": 5}})
    with pytest.raises(WbsaError, match="stopped"):
        pipeline.run_study(settings, tmp_path / "s", workers=1, stream=None)
    assert seen["run"].workers == 1 and seen["settings"].run.workers == 1
    assert "workers = 1" in seen["settings"].to_toml()
    with pytest.raises(WbsaError, match="stopped"):
        pipeline.run_study(settings, tmp_path / "t", workers=0, stream=None)
    assert seen["settings"].run.workers >= 1  # 0 = all cores, resolved


# --- 5. short reprs ------------------------------------------------------------------------------------------

def test_objects_the_api_returns_print_short(tmp_path):
    """Every object the public API returns prints a line (or a small table), its detail one attribute away."""

    import wbsa
    from wbsa.camera import preset
    from wbsa.study.pipeline import StageRun, StudyResult
    from wbsa.study.stages import Stage

    study = wbsa.Study.from_toml("default")
    stage = Stage.create(tmp_path, "population", {"n": 300, "x": list(range(500))})
    result = StudyResult(tmp_path, tmp_path / "report.html", tmp_path / "fits.parquet",
                         [StageRun("population", stage, False, 3.2, 3.2, "300 subjects"),
                          StageRun("fit", stage, True, 0.0, 9.0, "65 fits")], 12.5)
    for obj in (study, study.settings, preset("kinect-v1"), wbsa.View(30, 0, 4.3), wbsa.SensorSettings(),
                wbsa.TriangleMesh(*_box()), result, result.stages[0]):
        assert "\n" not in repr(obj) and len(repr(obj)) < 260, repr(obj)
    text = str(result)
    assert len(text.splitlines()) == 4 and "reused" in text and "report.html" in text
    assert "300 subjects" in repr(result.stages[0]) and "range" not in repr(result.stages[0])
    assert "[population]" in study.settings.to_toml()  # the detail, one call away


@pytest.fixture(scope="module")
def tiny_model(small_estimator_model):
    """The run's small trained estimator model file (tests/conftest.py)."""
    return small_estimator_model


@pytest.mark.slow
def test_the_estimator_model_prints_short(tiny_model):
    from wbsa.estimation.methods.regression.model import EstimatorModel

    model = EstimatorModel.load(tiny_model)
    for obj in (model, model.view, model.view.axis, model.residual):
        assert "\n" not in repr(obj) and len(repr(obj)) < 260 and "array" not in repr(obj), repr(obj)
    assert "calibration renders" in repr(model) and "ranges" in model.meta


# --- 6. the estimator's bad inputs ---------------------------------------------------------------------------

def _npy_header(path, shape):
    """A ``.npy`` file whose header announces ``shape`` float32 values (the data is absent)."""
    with open(path, "wb") as fh:
        np.lib.format.write_array_header_1_0(fh, {"descr": "<f4", "fortran_order": False, "shape": shape})
    return path


def _tiff_header(path, width, height):
    """A little-endian TIFF whose header announces width x height 32-bit float pixels (the data is absent)."""
    import struct

    entries = [(256, 4, 1, width), (257, 4, 1, height), (258, 3, 1, 32), (259, 3, 1, 1), (262, 3, 1, 1),
               (273, 4, 1, 8), (277, 3, 1, 1), (278, 4, 1, height), (279, 4, 1, min(4 * width * height, 2**32 - 1)),
               (339, 3, 1, 3)]
    ifd = struct.pack("<H", len(entries)) + b"".join(struct.pack("<HHII", *e) for e in entries) + b"\0\0\0\0"
    path.write_bytes(b"II*\0" + struct.pack("<I", 8) + ifd)
    return path


@pytest.mark.parametrize("make,fragment", [
    (lambda p: _tiff_header(p / "bomb.tiff", 100_000, 100_000),  # above Pillow's own limit: its size said too
     "100000 x 100000 pixels (10000.0 megapixels) is above wbsa's limit of 16.8 megapixels (4096 x 4096"),
    (lambda p: _tiff_header(p / "big.tiff", 9_000, 9_000), "9000 x 9000 pixels"),
    (lambda p: _npy_header(p / "big.npy", (9_000, 9_000)), "9000 x 9000 pixels"),
    (lambda p: (p / "t.npy").write_bytes(b"\x93NUMPY\x01\x00") and p / "t.npy", "not a readable .npy"),
    (lambda p: (p / "bomb.exr").write_bytes(b"\x76\x2f\x31\x01\x02\0\0\0" + b"dataWindow\0box2i\0"
                                            + np.array([16], "<i4").tobytes()
                                            + np.array([0, 0, 99_999, 99_999], "<i4").tobytes() + b"\0")
     and p / "bomb.exr", "100000 x 100000 pixels"),
])
def test_depth_images_are_refused_from_their_header_whatever_the_format(tmp_path, make, fragment, monkeypatch):
    """Refused from the header: no decoder runs (NumPy's array reader, Pillow's pixel loader and the EXR
    reader are made to fail, and the refusal is still the header's)."""
    import PIL.Image

    from wbsa.core import depth_image

    path = make(tmp_path)
    decoded = []

    def decoder(name):
        def refuse(*args, **kwargs):
            decoded.append(name)
            raise AssertionError(f"{name} decoded the pixels")
        return refuse

    monkeypatch.setattr(np, "load", decoder("numpy.load"))
    monkeypatch.setattr(PIL.Image.Image, "load", decoder("PIL load"))
    monkeypatch.setattr(depth_image, "_read_exr", decoder("EXR reader"))
    code, _, err = run_cli("estimate", path, "--camera", "kinect-v2", "--model", tmp_path / "none.npz")
    assert_one_line_error(code, err, fragment)
    assert decoded == []
    with pytest.raises(WbsaError, match=fragment.split(" x ")[0]):
        import wbsa

        wbsa.estimate(path, "kinect-v2")


def test_what_is_not_a_file_is_named_truthfully(tmp_path):
    import os

    os.mkfifo(tmp_path / "pipe.png")
    (tmp_path / "dir.png").mkdir()
    os.symlink(tmp_path / "loop.png", tmp_path / "loop.png")
    for path, fragment in ((tmp_path / "pipe.png", "is a FIFO"), (tmp_path / "dir.png", "is a folder"),
                           (tmp_path / "loop.png", "loop of symbolic links"), ("/dev/zero", "is a device"),
                           (tmp_path / "missing.png", "does not exist")):
        code, _, err = run_cli("estimate", path, "--camera", "kinect-v2")
        assert_one_line_error(code, err, fragment)


@pytest.mark.parametrize("argv,fragment", [
    (["--json", "--fhir"], "give one of them"),
    (["--fhir", "--patient", ""], "--patient needs a FHIR reference"),
    (["--mask-out", ""], "--mask-out needs a file name"),
    (["--mask-out", "m.jpg"], "must end in .png"),
    (["--out-mesh", "x.stl"], "must end in .ply or .obj"),
    (["--mask-out", "same.png", "--out-mesh", "same.png"], "must end in .ply or .obj"),
    (["--mask-out", "FILE/m.png"], "is a file, not a folder"),
])
def test_outputs_are_checked_before_any_work(tmp_path, monkeypatch, argv, fragment):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "FILE").write_text("x")
    code, _, err = run_cli("estimate", "missing.png", "--camera", "kinect-v2", *argv)  # refused before reading
    assert_one_line_error(code, err, fragment)


def test_outputs_are_written_as_a_set(body_depth, fit_model, tmp_path, monkeypatch):
    import wbsa.core.mesh_io as mesh_io

    monkeypatch.setenv("WBSA_CACHE_DIR", "/nonexistent/wbsa-cache")
    _, depth = body_depth
    base = ["estimate", depth, "--camera", "kinect-v2", "--model", fit_model, "--azimuth", "0", "--no-segment",
            "--mask-out", tmp_path / "m.png", "--out-mesh", tmp_path / "s.ply"]

    def full_disk(*args, **kwargs):
        raise WbsaError("no space left on the disk writing s.ply; free some space")

    monkeypatch.setattr(mesh_io, "write_mesh", full_disk)
    code, out, err = run_cli(*base, "--json")
    assert_one_line_error(code, err.splitlines()[-1] + "\n", "no space left")
    assert out == "" and sorted(p.name for p in tmp_path.iterdir()) == []  # no mask, no temporaries
    monkeypatch.undo()
    monkeypatch.setenv("WBSA_CACHE_DIR", "/nonexistent/wbsa-cache")
    code, out, err = run_cli(*base, "--json")
    assert code == 0 and (tmp_path / "m.png").is_file() and (tmp_path / "s.ply").is_file(), err
    code, _, err = run_cli("estimate", depth, "--camera", "kinect-v2", "--model", fit_model, "--azimuth", "0",
                           "--pick", "99999,99999")
    assert_one_line_error(code, err, "lies outside the 512 x 424 depth image")


def test_the_api_refuses_arguments_of_the_wrong_kind():
    import wbsa

    depth = np.full((424, 512), 2.0)
    for kwargs, fragment in (({"depth": depth.astype(complex)}, "complex"), ({"model": object()}, "model must be"),
                             ({"level": "0.95"}, "interval level"), ({"clothing_m": "0.01"}, "clothes' layer"),
                             ({"depth_scale": "1000"}, "depth_scale")):
        args = {"depth": depth, "camera": "kinect-v2", **kwargs}
        with pytest.raises(WbsaError, match=fragment):
            wbsa.estimate(args.pop("depth"), args.pop("camera"), **args)


def test_an_absurd_depth_scale_gives_no_raw_numpy_warning(body_depth, capfd):
    import warnings

    _, depth = body_depth
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        code, _, err = run_cli("estimate", depth, "--camera", "kinect-v2", "--depth-scale", "1e-300")
    assert_one_line_error(code, err)
    assert "RuntimeWarning" not in capfd.readouterr().err


@pytest.mark.parametrize("change,fragment", [
    ({"intrinsic_matrix": [1e-300, 0, 0, 0, 1e-300, 0, 256, 212, 1]}, "field of view"),
    ({"intrinsic_matrix": [0, 0, 0, 0, 365, 0, 256, 212, 1]}, "check the camera's intrinsics"),
    ({"max_range_m": "4.5"}, "max_range_m must be a finite number of metres"),
    ({"min_range_m": [0.5]}, "min_range_m must be a finite number of metres"),
    ({"width": "512"}, "width must be a whole number"),
])
def test_intrinsics_json_is_checked(tmp_path, change, fragment):
    cam = {"width": 512, "height": 424, "intrinsic_matrix": [365.0, 0, 0, 0, 365.0, 0, 255.5, 211.5, 1],
           "min_range_m": 0.5, "max_range_m": 4.5, **change}
    (tmp_path / "cam.json").write_text(json.dumps(cam))
    code, _, err = run_cli("estimate", tmp_path / "missing.png", "--camera", tmp_path / "cam.json")
    assert_one_line_error(code, err, fragment)
    assert "--fx" not in err


def _rewrite(src, dst, change):
    with np.load(src, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    change(arrays)
    np.savez(dst, **arrays)
    return dst


def _meta(change):
    def edit(arrays):
        meta = json.loads(str(arrays["meta_json"]))
        change(meta)
        arrays["meta_json"] = np.array(json.dumps(meta))
    return edit


@pytest.mark.slow
@pytest.mark.parametrize("edit,fragment", [
    (lambda a: a.pop("coef"), "the member coef is missing"),
    (lambda a: a.pop("view_axis_left"), "view_axis_left is missing"),
    (lambda a: a.update(scores=np.array(["a", "b"])), "scores is a <U1 array"),
    (_meta(lambda m: m.update(ranges=[1, 2])), "meta ranges is a list"),
    (lambda a: a.update(view_axis_roots=a["view_axis_roots"] + 10**6), "view_axis_roots points outside"),
    (lambda a: a.update(scale=np.zeros_like(a["scale"])), "scale holds"),
    (lambda a: a.update(scores=-a["scores"]), "calibration scores must be positive"),
    (lambda a: a.update(scores=np.zeros_like(a["scores"])), "calibration scores must be positive"),
    (lambda a: a.update(view_axis_sd_deg=np.array([-3.0])), "view_axis_sd_deg must be 1 positive"),
    (_meta(lambda m: m["ranges"].update(vbsa_m2=[float("nan"), 1.0])), "trained range of vbsa_m2"),
])
def test_a_broken_model_file_is_refused_in_one_line(tiny_model, body_depth, tmp_path, edit, fragment):
    path = _rewrite(tiny_model, tmp_path / "broken.npz", edit)
    code, _, err = run_cli("estimate", body_depth[1], "--camera", "kinect-v2", "--model", path)
    assert_one_line_error(code, err, fragment, "broken.npz")


@pytest.mark.parametrize("content", [b"", b"PK\x03\x04 truncated", b"not a zip at all"])
def test_an_empty_truncated_or_corrupt_model_file_is_refused_in_one_line(tmp_path, body_depth, content):
    (tmp_path / "m.npz").write_bytes(content)
    code, _, err = run_cli("estimate", body_depth[1], "--camera", "kinect-v2", "--model", tmp_path / "m.npz")
    assert_one_line_error(code, err, "is not a wbsa estimator model")


# --- 7. not a person -----------------------------------------------------------------------------------------

def _in_room(mesh, azimuth_deg, distance_m=3.0):
    """A depth image (Kinect v2, noisy, 12° above) of ``mesh`` standing in a room, a wall 0.8 m behind."""
    from wbsa.camera import MeshScene, View, preset
    from wbsa.training.room import compose_room
    from wbsa.sensor.settings import SensorSettings
    from wbsa.simulate import simulate_view

    room = compose_room(mesh, float(azimuth_deg), wall_behind_m=0.8)
    return simulate_view(MeshScene(room.mesh, surroundings=True), preset("kinect-v2"),
                         View(float(azimuth_deg), 12.0, distance_m), sensor=SensorSettings(noise="nguyen2012"), seed=4,
                         keep_frame=True, target=room.subject_center).frame.depth_m


def _post():
    import open3d as o3d

    from wbsa.core.mesh import TriangleMesh

    cyl = o3d.geometry.TriangleMesh.create_cylinder(0.06, 1.7, 24, 4)
    cyl.translate((0.0, 0.0, 0.85))
    return TriangleMesh.from_any(cyl)


@pytest.mark.slow
def test_objects_that_are_not_a_standing_person_are_refused_or_flagged_and_people_are_not(fit_model, body_model,
                                                                                          monkeypatch):
    """A board, a post and a wall piece edge-on are no person: refused in one line (flat, no head) or, when the
    segmentation takes them, flagged ``not_a_person``; people of every build and a young child are neither."""
    import wbsa
    from wbsa.core.mesh import TriangleMesh
    from wbsa.errors import WbsaError
    from wbsa.estimation import SegmentSettings

    monkeypatch.setenv("WBSA_CACHE_DIR", "/nonexistent/wbsa-cache")

    def flags(mesh, az):
        return wbsa.estimate(_in_room(mesh, az), "kinect-v2", fit_model, azimuth_deg=az,
                             segment=SegmentSettings(pick="center")).flags

    board = TriangleMesh(*_box((0.45, 0.02, 1.69)))
    for mesh, az in ((board, 0), (board, 45), (board, 90), (_post(), 0), (TriangleMesh(*_box((1.2, 0.1, 2.0))), 90)):
        try:
            assert "not_a_person" in flags(mesh, az), (az, mesh)
        except WbsaError as exc:
            assert "no person in the depth image" in str(exc) and "is not one" in str(exc), (az, mesh, exc)
    people = wbsa.population(n=3, seed=1, posture="arms-down")  # the narrowest, fullest silhouettes
    child = wbsa.body(gender=1.0, age=0.15, height=0.3)  # a young child in anny's A-pose
    assert 0.8 < float(np.ptp(np.asarray(child.vertices)[:, 2])) < 1.4
    for mesh in (*(wbsa.body(people, i) for i in range(3)), child):
        for az in (0, 90, 135):
            assert "not_a_person" not in flags(mesh, az), az
