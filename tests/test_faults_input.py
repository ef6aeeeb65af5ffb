"""Nonsense input at the library boundary: one-line errors (exit 2) before any work, or a correct result.

The cases of issue 12: non-finite numbers, negative seeds, images above the memory budget, views that
see nothing, model files with NaN coefficients, hand-edited study manifests, worker counts; and the
deterministic bytes of data files (no timings in a survey population's Parquet metadata).
"""

from __future__ import annotations

import json
import struct
import zlib
from pathlib import Path

import pandas as pd
import pytest

from wbsa.analysis.fit_views import FitSettings
from wbsa.analysis.outputs import run_fit
from helpers.synthetic import synthetic_population, synthetic_scan
from wbsa.errors import WbsaError
from helpers.cli import assert_one_line_error, run_cli


@pytest.fixture(scope="module")
def tables(tmp_path_factory):
    """Synthetic population and scan tables, and a fit folder made from them."""
    root = tmp_path_factory.mktemp("tables")
    pop = synthetic_population(60, seed=3)
    scan = synthetic_scan(pop, [(0.0, 0.0), (90.0, 0.0)], seed=3)
    pop.to_parquet(root / "pop.parquet")
    scan.to_parquet(root / "scan.parquet")
    run_fit(root / "pop.parquet", root / "scan.parquet", root / "fit", FitSettings(groups=("all",), k=3))
    return root


@pytest.mark.parametrize("args,fragment", [
    (["--seed", "-1"], "seed must be 0 or more"),
    (["--density", "inf"], "density_kg_m3 must be a body density in 500–2000 kg/m³"),
    (["--density", "nan"], "density_kg_m3 must be a body density in 500–2000 kg/m³"),
    (["--density", "5"], "500–2000 kg/m³"),
    (["--workers", "-1"], "workers must be 0 (all cores) or more"),
])
def test_population_refuses_nonsense_before_building(tmp_path, args, fragment):
    code, _, err = run_cli("population", "--kind", "random", "--n", "2", "--out", tmp_path / "p.parquet", *args)
    assert_one_line_error(code, err, fragment)
    assert not (tmp_path / "p.parquet").exists()


def test_fit_refuses_a_negative_seed(tables, tmp_path):
    code, _, err = run_cli("fit", tables / "pop.parquet", tables / "scan.parquet", "--out", tmp_path / "f", "--seed",
                           "-1")
    assert_one_line_error(code, err, "seed must be a whole number 0 or more")
    assert not (tmp_path / "f").exists()


def test_view_refuses_a_negative_sensor_seed_and_huge_images(tmp_path):
    mesh = tmp_path / "ball.ply"
    code, _, err = run_cli("body", "--out", mesh)
    assert code == 0, err
    code, _, err = run_cli("view", mesh, "--noise", "nguyen2012", "--sensor-seed", "-1")
    assert_one_line_error(code, err, "sensor seed must be a whole number 0 or more")
    code, _, err = run_cli("view", mesh, "--width", "100000", "--height", "100000")
    assert_one_line_error(code, err, "100000 x 100000 pixels", "limit of 16.8 megapixels")
    code, _, err = run_cli("view", mesh, "--scale", "100")
    assert_one_line_error(code, err, "limit of 16.8 megapixels")


def test_usage_errors_point_to_the_help_of_the_command_given():
    code, _, err = run_cli("estimate", "a.png", "extra", "words")
    assert_one_line_error(code, err, "unrecognized arguments: extra words", "(see wbsa estimate --help)")
    code, _, err = run_cli("--bogus")
    assert_one_line_error(code, err, "(see wbsa --help)")
    code, _, err = run_cli("view", "--noise", "nguyen2012", "--noise-scale", "-1")
    assert_one_line_error(code, err, "--noise-scale", "(see wbsa view --help)")


def test_a_scan_in_millimetres_or_y_up_is_brought_to_the_body_frame(tmp_path):
    """A body scan in millimetres, +Y up (glTF, many scanners), renders as the same body in metres, +Z up;
    read as it is, it is refused with the flag that fixes it, or warned about (lying down)."""
    import numpy as np

    from wbsa.core.mesh_io import read_mesh, write_mesh
    from wbsa.core.mesh import TriangleMesh

    body = tmp_path / "body.ply"
    assert run_cli("body", "--out", body)[0] == 0
    mesh = read_mesh(body)
    v = np.asarray(mesh.vertices)
    scan = tmp_path / "scan.ply"
    write_mesh(TriangleMesh(1000.0 * np.column_stack([v[:, 0], v[:, 2], -v[:, 1]]), mesh.faces), scan)
    reference = json.loads(run_cli("view", body, "--json", "--azimuth", "30")[1])
    code, out, err = run_cli("view", scan, "--units", "mm", "--up", "y", "--json", "--azimuth", "30")
    assert code == 0 and err == "", err
    again = json.loads(out)
    assert again["n_pixels"] == reference["n_pixels"]
    assert again["vbsa_visible_m2"] == pytest.approx(reference["vbsa_visible_m2"], rel=1e-6)
    from wbsa.simulate.target import to_body_frame

    back = to_body_frame(read_mesh(scan), "mm", "y")
    np.testing.assert_allclose(back.vertices, v, atol=1e-6)  # a rotation back, not a mirror

    def signed_volume(m):
        p = np.asarray(m.vertices)[np.asarray(m.faces)]
        return float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0)

    assert signed_volume(back) == pytest.approx(signed_volume(mesh), rel=1e-6)  # same winding, same sign
    code, _, err = run_cli("view", scan, "--up", "y", "--json")
    assert_one_line_error(code, err, "--units mm")  # refused, not measured (issue 30)
    code, _, err = run_cli("view", scan, "--units", "mm", "--json")
    assert code == 0 and "--up y" in err and err.count("\n") == 1


def test_a_view_that_sees_nothing_has_no_visible_area(tmp_path):
    """Issue 12 item 5: view --distance 1e6 reported 0.288 m² from 0 pixels, then blamed the output folder."""
    from wbsa.core.ply import check_ply

    mesh = tmp_path / "body.ply"
    assert run_cli("body", "--out", mesh)[0] == 0
    code, out, err = run_cli("view", mesh, "--distance", "1e6", "--out", tmp_path / "v", "--json")
    assert code == 0, err
    row = json.loads(out)
    assert row["n_pixels"] == 0 and row["vbsa_visible_m2"] == 0.0 and row["vbsa_hit_m2"] == 0.0
    assert err.startswith("warning: no pixel sees the body") and err.count("\n") == 1
    check_ply(tmp_path / "v" / "points.ply", 0)  # a valid, empty point cloud


def _png_16bit(path: Path, width: int, height: int, value: int) -> None:
    """A valid 16-bit grayscale PNG of one value, written row by row (no full image in memory)."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    comp = zlib.compressobj(9)
    row = b"\0" + struct.pack(">H", value) * width
    body = b"".join(comp.compress(row) for _ in range(height)) + comp.flush()
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 16, 0, 0, 0, 0))
                     + chunk(b"IDAT", body) + chunk(b"IEND", b""))


def test_estimate_refuses_an_image_above_the_memory_budget_before_decoding(tables, tmp_path):
    png = tmp_path / "huge.png"
    _png_16bit(png, 8000, 8000, 2500)
    code, _, err = run_cli("estimate", png, "--model", tables / "fit" / "model.json")
    assert_one_line_error(code, err, "8000 x 8000 pixels", "limit of 16.8 megapixels")


@pytest.mark.parametrize("edit,fragment", [
    (lambda e: e.update(coef=[float("nan")] * len(e["coef"])), "non-finite (NaN or infinite) coefficients"),
    (lambda e: e.update(scale=float("inf")), "non-finite or non-numeric scale"),
    (lambda e: e.update(scale=-1.0), "negative residual variance"),
    (lambda e: e.update(df_resid=0), "df_resid = 0"),
    (lambda e: e.update(cov_unscaled=[[1.0]]), "covariance for"),
    (lambda e: e.pop("terms"), "lacks terms"),
])
def test_model_files_with_nonsense_numbers_are_refused_on_load(tables, tmp_path, edit, fragment):
    """Issue 12 item 5: NaN coefficients gave 'WBSA estimate: nan m²' with exit 0."""
    from wbsa.analysis.model_file import WbsaModel

    doc = json.loads((tables / "fit" / "model.json").read_text())
    edit(doc["entries"][0])
    path = tmp_path / "model.json"
    path.write_text(json.dumps(doc))  # json writes NaN and Infinity, as a hand edit would
    with pytest.raises(WbsaError, match="entry 0 ") as info:
        WbsaModel.load(path)
    assert fragment in str(info.value) and "\n" not in str(info.value)
    png = tmp_path / "depth.png"
    _png_16bit(png, 640, 480, 2500)
    code, _, err = run_cli("estimate", png, "--model", path, "--camera", "kinect-v1", "--azimuth", "0", "--no-segment")
    assert_one_line_error(code, err, fragment)


@pytest.fixture(scope="module")
def study(tables, tmp_path_factory):
    """A study folder with finished population, scan and fit stages (synthetic tables) and its study.json."""
    from wbsa.study.stages import Stage

    root = tmp_path_factory.mktemp("study")
    pop = Stage.create(root, "population", {"synthetic": 60})
    scan = Stage.create(root, "scan", {"views": 2}, {"population": pop.key})
    fit = Stage.create(root, "fit", {"k": 3}, {"population": pop.key, "scans": [scan.key]})
    for stage, src, name in ((pop, "pop.parquet", "population.parquet"), (scan, "scan.parquet", "scan.parquet")):
        stage.path.mkdir(parents=True)
        (stage.path / name).write_bytes((tables / src).read_bytes())
        stage.finish(0.0, {name.split(".")[0]: name})
    run_fit(pop.path / "population.parquet", scan.path / "scan.parquet", fit.path, FitSettings(groups=("all",), k=3))
    fit.finish(0.0, {"fit_info": "fit_info.json"})
    manifest = {"study": {"name": "synthetic study"}, "settings": {"report": {"dpi": 30}}, "seconds": 1.0,
                "stages": [{"name": s.name, "stage": s.name, "key": s.key, "path": f"stages/{s.path.name}",
                            "reused": False, "seconds_computed": 0.0} for s in (pop, scan, fit)],
                "versions": {"wbsa": "test"}}
    (root / "study.json").write_text(json.dumps(manifest))
    return root, manifest


@pytest.mark.parametrize("edit,fragment", [
    (lambda m: m.update(stages="all of them"), "'stages' has the wrong type"),
    (lambda m: m.update(stages=[1, 2, 3]), "stage 0 is not a record"),
    (lambda m: m["stages"][0].pop("path"), "stage 0 is not a record"),
    (lambda m: m.update(stages=m["stages"][:1]), "lacks the population, scan or fit stage"),
    (lambda m: m.update(study="a name"), "'study' has the wrong type"),
    (lambda m: m.update(versions=["wbsa"]), "'versions' has the wrong type"),
    (lambda m: m.update(seconds="long"), "'seconds' has the wrong type"),
    (lambda m: m.update(settings={"report": 5}), "settings table 'report' is not an object"),
    (lambda m: m.update(settings={"report": {"dpi": "high"}}), "[report] dpi must be an integer"),
    (lambda m: m.update(settings={"report": {"colour": "red"}}), "unknown key 'colour' in [report]"),
    (lambda m: m["stages"][2].update(path="stages/fit-0000000000000000"), "is missing from the study"),
])
def test_report_on_a_hand_edited_study_json_is_one_line(study, tmp_path, edit, fragment):
    """Issue 12 item 6: AttributeError / KeyError tracebacks on an edited manifest."""
    import copy
    import shutil

    root, manifest = study
    folder = tmp_path / "study"
    shutil.copytree(root, folder)
    m = copy.deepcopy(manifest)
    edit(m)
    (folder / "study.json").write_text(json.dumps(m))
    code, _, err = run_cli("report", folder)
    assert_one_line_error(code, err, fragment)
    assert not (folder / "report.html").exists()


@pytest.mark.parametrize("edit,fragment", [
    (lambda i: [i], "is not a JSON object"),
    (lambda i: {**i, "settings": 5}, "'settings' is not an object"),
    (lambda i: {**i, "settings": {**i["settings"], "models": "linear"}}, "'models' is not a list"),
    (lambda i: {**i, "settings": {**i["settings"], "group_spec": {"tallest": 2.5}}}, "'group_spec' is not valid"),
])
def test_report_on_a_hand_edited_fit_info_is_one_line(tables, tmp_path, edit, fragment):
    import shutil

    fit = tmp_path / "fit"
    shutil.copytree(tables / "fit", fit)
    (fit / "fit_info.json").write_text(json.dumps(edit(json.loads((fit / "fit_info.json").read_text()))))
    code, _, err = run_cli("report", fit, "--population", tables / "pop.parquet", "--scan", tables / "scan.parquet")
    assert_one_line_error(code, err, fragment)


def test_report_refuses_a_stage_that_did_not_finish(study, tmp_path):
    import shutil

    root, manifest = study
    folder = tmp_path / "study"
    shutil.copytree(root, folder)
    (folder / manifest["stages"][2]["path"] / "stage.json").unlink()
    code, _, err = run_cli("report", folder)
    assert_one_line_error(code, err, "did not finish")


@pytest.mark.slow
def test_report_on_odd_but_readable_values_builds(study, tmp_path):
    import shutil

    root, manifest = study
    folder = tmp_path / "study"
    shutil.copytree(root, folder)
    m = json.loads(json.dumps(manifest))
    m["study"]["name"] = 42
    m["stages"][0]["seconds_computed"] = "a while"
    (folder / "study.json").write_text(json.dumps(m))
    code, out, err = run_cli("report", folder)
    assert code == 0, err
    assert "<title>42</title>" in (folder / "report.html").read_text()


def test_workers_zero_means_all_cores_everywhere():
    from wbsa.parallel import default_workers, resolve_workers

    assert resolve_workers(0) == resolve_workers(None) == default_workers()
    assert resolve_workers(3) == 3
    for bad in (-1, 1.5, "two"):
        with pytest.raises(WbsaError, match="workers must be"):
            resolve_workers(bad)


def test_a_run_log_never_goes_into_a_data_file(tmp_path):
    from wbsa.io import RUN_LOG_ATTR, write_table

    df = pd.DataFrame({"x": [1.0, 2.0]})
    df.attrs = {"survey": {"rows": 2}, RUN_LOG_ATTR: {"seconds": 1.25}}
    write_table(df, tmp_path / "a.parquet")
    df.attrs[RUN_LOG_ATTR] = {"seconds": 9.5}
    write_table(df, tmp_path / "b.parquet")
    assert (tmp_path / "a.parquet").read_bytes() == (tmp_path / "b.parquet").read_bytes()
    assert pd.read_parquet(tmp_path / "a.parquet").attrs == {"survey": {"rows": 2}}
    assert df.attrs[RUN_LOG_ATTR] == {"seconds": 9.5}  # the caller's frame is untouched


def test_a_fit_folder_has_the_same_bytes_on_every_run(tables, tmp_path):
    """No timings or absolute paths in the fit's files (XLSX dates included); the run time is in run_log.json."""
    import time

    runs = []
    for name in ("a", "b"):
        out = tmp_path / name / "fit"
        assert run_cli("fit", tables / "pop.parquet", tables / "scan.parquet", "--out", out, "--k", "3",
                       "--groups", "all")[0] == 0
        runs.append({p.name: p.read_bytes() for p in out.iterdir()})
        time.sleep(2.1)  # ZIP entry times have a 2-second resolution
    a, b = runs
    assert set(a) == set(b) and "run_log.json" in a
    assert [name for name in a if a[name] != b[name]] == ["run_log.json"]
    assert str(tmp_path) not in a["fit_info.json"].decode()


@pytest.mark.slow
def test_survey_population_bytes_are_the_same_on_every_run(tmp_path):
    """Issue 12 item 7: the survey table's Parquet metadata held the run's timings."""
    import warnings

    from test_survey import _small_settings
    from wbsa.bodies.survey import SurveyMatchWarning, SurveyPopulationSettings, build_survey_population
    from wbsa.io import RUN_LOG_ATTR, write_table

    settings = SurveyPopulationSettings(match=_small_settings(max_iterations=10))
    for name in ("a", "b"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SurveyMatchWarning)
            table = build_survey_population(2, seed=1, settings=settings, show_progress=False)
        assert set(table.attrs[RUN_LOG_ATTR]) == {"seconds", "cpu_seconds"}
        write_table(table, tmp_path / f"{name}.parquet")
    assert (tmp_path / "a.parquet").read_bytes() == (tmp_path / "b.parquet").read_bytes()


def test_depth_and_camera_files_are_refused_in_plain_words_with_the_fix(tmp_path):
    """Issue 42's small words: what a picture is (never Pillow's mode letter), an empty file as empty, a float
    file in millimetres named as such with its option, a camera matrix written row by row named as Open3D's
    column order; each on the command line (exit 2, one line) and, where the words differ, in Python."""
    import numpy as np
    from PIL import Image

    import wbsa
    from wbsa.camera import Intrinsics, preset

    Image.fromarray(np.full((424, 512), 128, np.uint8)).save(tmp_path / "photo.png")
    Image.fromarray(np.full((424, 512, 3), 128, np.uint8)).save(tmp_path / "colour.tiff")
    (tmp_path / "empty.png").write_bytes(b"")
    for name, words in (("photo.png", "photo.png is an 8-bit grey-scale picture, not a 16-bit depth image; export the "
                                      "depth frame from the camera's software as a 16-bit PNG in millimetres"),
                        ("colour.tiff", "colour.tiff is a colour picture (TIFF), not a single-channel depth image; "
                                        "save the depth as 32-bit float metres or 16-bit millimetres"),
                        ("empty.png", "empty.png is empty (0 bytes); export the depth frame again")):
        assert_one_line_error(*run_cli("estimate", tmp_path / name, "--camera", "kinect-v2")[::2], words)
    depth_mm = np.zeros((424, 512))
    depth_mm[100:380, 220:290] = 2500.0  # a person 2.5 m away, in millimetres, as float
    np.save(tmp_path / "mm.npy", depth_mm)
    assert_one_line_error(*run_cli("estimate", tmp_path / "mm.npy", "--camera", "kinect-v2")[::2],
                          "has 0 returns between 0.3 and 8 m; its returns lie 2500 m away (median): millimetres "
                          "read as metres? A float file (.npy, .tiff, .exr) or array is read as metres: for "
                          "millimetres add --depth-scale 1000 (depth_scale=1000 in Python)")
    with pytest.raises(WbsaError, match="depth_scale=1000 in Python") as err:
        wbsa.estimate(tmp_path / "mm.npy", "kinect-v2")
    assert err.value.code == "depth_scale" and "save the depth in metres" in err.value.page_words()
    k = preset("kinect-v2")
    row_major = {"width": k.width, "height": k.height, "intrinsic_matrix": [float(x) for x in k.K.ravel()]}
    (tmp_path / "cam.json").write_text(json.dumps(row_major))
    assert_one_line_error(*run_cli("estimate", tmp_path / "mm.npy", "--camera", tmp_path / "cam.json")[::2],
                          "intrinsic_matrix is not a pinhole camera matrix ([[fx, s, cx], [0, fy, cy], [0, 0, 1]]); "
                          "Open3D lists it column by column, [fx, 0, 0, s, fy, 0, cx, cy, 1], and this one is "
                          "written row by row: write it column by column")
    assert Intrinsics.from_open3d_json(k.to_open3d_json()) == k  # the column order Open3D writes is read
    with pytest.raises(WbsaError, match=r"\[0, 0, 1\]\]\); Open3D lists it column by column, \[fx, 0, 0, s, fy, "
                                        r"0, cx, cy, 1\]$"):
        Intrinsics.from_open3d_json({**row_major, "intrinsic_matrix": [1.0] * 9})  # neither order
