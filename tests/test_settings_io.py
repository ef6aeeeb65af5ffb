"""The stages' settings classes and the one TOML layer that reads and writes all of them.

Round trips TOML -> settings -> TOML for every settings class, errors that name the field, optional
fields as left-out keys, and the command-line flags landing on the same fields as the study's keys.
"""

import argparse
import json
import tomllib

import pytest

from wbsa.analysis.settings import FitSettings, GroupSpec
from wbsa.bodies.settings import PopulationSettings
from wbsa.errors import SettingsError, WbsaError
from wbsa.parallel import RunSettings
from wbsa.report.settings import ReportSettings
from wbsa.scan.settings import ScanSettings
from wbsa.sensor.settings import SensorSettings
from wbsa.settings_io import dump_toml, field_defaults, from_table, to_table
from wbsa.study.settings import StudyInfo, scan_job, settings_from_dict
from wbsa.surface.settings import ReconstructionSettings

#: One non-default instance of every settings class (optional fields both set and unset across the list).
EXAMPLES = [
    PopulationSettings(kind="survey", n=40, seed=7, density_kg_m3=1010.0, variations=2, survey_weights=True),
    PopulationSettings(kind="table", params_path="phenotypes.csv"),
    ScanSettings(camera="tum", views="sphere:12", distances_m=(3.0, 4.3), seed=9),
    ScanSettings(azimuths_deg=(0.0, 45.0), elevations_deg=(-30.0,)),
    SensorSettings(noise="nguyen2012", lateral_noise=False, quantise=True, holes_fraction=0.1, pixel_dropout=0.02,
                   range_limits=True),
    SensorSettings(grazing_dropout_deg=12.5),
    SensorSettings(noise="camera", technology="lidar"),
    ReconstructionSettings(methods=("grid", "poisson"), denoise="median", boundary="footprint", smoothing="mls",
                           bpa_radii_px=(1.5, 3.0), poisson_depth=7),
    FitSettings(vbsa_columns=("vbsa_hit_m2", "vbsa_recon_m2:grid"), predictor_sets=((), ("stature_m", "mass_kg")),
                models=("quadratic",), groups=("all", "obese"), group_spec=GroupSpec(kid_max_age_years=12.0),
                k=5, seed=2, require_in_frame=False, qq_points=20, residual_groups=(), population_kind="survey",
                correlation_view_deg=(60.0, 30.0)),
    GroupSpec(small_max_stature_m=1.2, big_min_stature_m=1.9, obese_min_bmi=35.0),
    ReportSettings(scatter_view_deg=(90.0, 0.0), snapshot_subject=4, dpi=150),
    ReportSettings(),
    RunSettings(workers=3, scheduler="tcp://10.0.0.5:8786", chunk_size=7, progress=False),
    StudyInfo(name='a "quoted" name', description="two\nlines"),
]


@pytest.mark.parametrize("settings", EXAMPLES, ids=lambda s: type(s).__name__)
def test_toml_round_trip_of_every_settings_class(settings):
    text = dump_toml({"section": to_table(settings)})
    again = from_table(type(settings), tomllib.loads(text)["section"], "section")
    assert again == settings
    assert to_table(again) == to_table(settings)


def test_optional_fields_are_left_out_and_read_back_as_none():
    assert "grazing_dropout_deg" not in to_table(SensorSettings())
    assert from_table(SensorSettings, {}, "sensor").grazing_dropout_deg is None
    assert from_table(ReportSettings, {}, "report").snapshot_subject is None
    text = dump_toml({"report": to_table(ReportSettings(), keep_none=True)})
    assert "# snapshot_subject: not set" in text and tomllib.loads(text)["report"] == to_table(ReportSettings())


def test_nested_settings_are_sub_tables():
    text = dump_toml({"fit": to_table(FitSettings(group_spec=GroupSpec(obese_min_bmi=32.0)))})
    doc = tomllib.loads(text)
    assert "[fit.group_spec]" in text and doc["fit"]["group_spec"]["obese_min_bmi"] == 32.0
    assert from_table(FitSettings, doc["fit"], "fit").group_spec.obese_min_bmi == 32.0


@pytest.mark.parametrize("cls, kwargs, field", [
    (PopulationSettings, {"n": 0}, "n"),
    (PopulationSettings, {}, "n"),
    (PopulationSettings, {"n": 5, "seed": -1}, "seed"),
    (PopulationSettings, {"n": 5, "density_kg_m3": 50.0}, "density_kg_m3"),
    (PopulationSettings, {"kind": "table"}, "params_path"),
    (ScanSettings, {"distances_m": ()}, "distances_m"),
    (ScanSettings, {"distances_m": (4.3, 4.3)}, "distances_m"),
    (ScanSettings, {"views": "everywhere"}, "views"),
    (ScanSettings, {"azimuths_deg": (float("nan"),)}, "azimuths_deg"),
    (SensorSettings, {"pixel_dropout": -0.1}, "pixel_dropout"),
    (SensorSettings, {"baseline_m": 0.0}, "baseline_m"),
    (ReconstructionSettings, {"methods": ("grid", "grid")}, "methods"),
    (ReconstructionSettings, {"methods": ("marching-cubes",)}, "methods"),
    (ReconstructionSettings, {"max_angle_deg": 90.0}, "max_angle_deg"),
    (ReconstructionSettings, {"poisson_depth": 20}, "poisson_depth"),
    (FitSettings, {"k": 1}, "k"),
    (FitSettings, {"models": ("spline",)}, "models"),
    (FitSettings, {"groups": ()}, "groups"),
    (FitSettings, {"residual_models": ("cubic",)}, "residual_models"),
    (FitSettings, {"vbsa_columns": ("vbsa_magic_m2",)}, "vbsa_columns"),
    (FitSettings, {"qq_points": 1}, "qq_points"),
    (GroupSpec, {"small_max_stature_m": 2.1}, "small_max_stature_m"),
    (GroupSpec, {"obese_min_bmi": 0.0}, "obese_min_bmi"),
    (ReportSettings, {"dpi": 10}, "dpi"),
    (ReportSettings, {"snapshot_subject": -1}, "snapshot_subject"),
    (RunSettings, {"workers": -1}, "workers"),
    (RunSettings, {"chunk_size": 0}, "chunk_size"),
])
def test_bad_values_raise_errors_that_name_the_field_not_a_flag(cls, kwargs, field):
    with pytest.raises(SettingsError) as info:
        cls(**kwargs)
    assert info.value.field == field
    assert str(info.value).startswith(f"{field} ") and "--" not in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize("table, match", [
    ({"k": 2.5}, r"^f.toml: \[fit\] k must be an integer, got 2.5$"),
    ({"models": "linear"}, r"\[fit\] models must be a list of one of 'linear', 'quadratic', 'loglog', 'wls'"),
    ({"correlation_view_deg": [1.0]}, r"\[fit\] correlation_view_deg must be a list of 2 values"),
    ({"group_spec": {"kids": 3}}, r"unknown key 'kids' in \[fit.group_spec\]"),
    ({"population_kind": 3}, r"\[fit\] population_kind must be a string, got 3"),
])
def test_wrong_types_name_file_table_and_key(table, match):
    with pytest.raises(WbsaError, match=match):
        from_table(FitSettings, table, "fit", "f.toml")


def test_the_scan_flags_set_the_same_fields_as_the_study_keys():
    from wbsa.scan.command import register, run_settings_from_args, settings_from_args

    parser = argparse.ArgumentParser()
    register(parser.add_subparsers())
    args = parser.parse_args(["scan", "pop.parquet", "--out", "o", "--azimuths", "0:90:45", "--elevations", "30",
                              "--distance", "3.5", "--seed", "3", "--noise", "nguyen2012", "--holes", "0.1",
                              "--reconstruct", "grid", "--chunk-size", "9"])
    study = settings_from_dict({"population": {"n": 5},
                                "scan": {"azimuths_deg": [0, 45, 90], "elevations_deg": [30], "distances_m": [3.5],
                                         "seed": 3},
                                "sensor": {"noise": "nguyen2012", "holes_fraction": 0.1},
                                "reconstruction": {"methods": ["grid"]}})
    assert settings_from_args(args).to_dict() == scan_job(study, 3.5).to_dict()
    assert run_settings_from_args(args) == RunSettings(chunk_size=9)
    defaults = parser.parse_args(["scan", "pop.parquet", "--out", "o"])
    assert run_settings_from_args(defaults) == RunSettings()  # one default chunk size, in RunSettings
    assert settings_from_args(defaults).to_dict() == ScanSettings().job(ScanSettings().distances_m[0]).to_dict()


def test_the_fit_and_population_flags_default_to_the_settings_defaults():
    from wbsa.analysis.command import register as register_fit
    from wbsa.analysis.command import settings_from_args as fit_from_args
    from wbsa.bodies.command import register as register_population
    from wbsa.bodies.command import settings_from_args as population_from_args

    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers()
    register_fit(sub)
    register_population(sub)
    args = parser.parse_args(["fit", "people.parquet", "scan.parquet", "--out", "o"])
    assert fit_from_args(args) == FitSettings(population_kind="people")
    args = parser.parse_args(["fit", "p.parquet", "s.parquet", "--out", "o", "--stature-cuts", "1.3,1.9",
                              "--predictors", "stature", "--correlation-view", "60,30", "--models", "wls"])
    fs = fit_from_args(args)
    assert (fs.group_spec.small_max_stature_m, fs.group_spec.big_min_stature_m) == (1.3, 1.9)
    assert fs.predictor_sets == ((), ("stature",)) and fs.correlation_view_deg == (60.0, 30.0)
    assert fs.models == ("wls",)
    args = parser.parse_args(["population", "--kind", "random", "--n", "4", "--out", "p.parquet"])
    assert population_from_args(args) == PopulationSettings(n=4)
    assert field_defaults(PopulationSettings)["density_kg_m3"] == PopulationSettings(n=1).density_kg_m3


def test_fit_settings_to_dict_keeps_the_model_file_layout():
    """model.json records FitSettings.to_dict(): the same keys, in the same order, as before the settings moved."""
    d = FitSettings().to_dict()
    assert list(d) == ["vbsa_columns", "predictor_sets", "models", "groups", "group_spec", "k", "seed",
                       "require_in_frame", "qq_points", "residual_groups", "residual_models", "population_kind"]
    assert d["population_kind"] == "unknown" and d["predictor_sets"] == [[], ["stature_m"]]
    assert list(d["group_spec"]) == ["kid_max_age_years", "small_max_stature_m", "big_min_stature_m", "obese_min_bmi"]
    json.dumps(d)


def test_range_limits_need_a_camera_with_a_range(tmp_path):
    from wbsa.camera.intrinsics import Intrinsics

    cam = tmp_path / "cam.json"
    cam.write_text(json.dumps(Intrinsics(64, 48, 50.0, 50.0, 31.5, 23.5).to_open3d_json()))
    with pytest.raises(WbsaError, match=r"s.toml: \[sensor\] range_limits needs a camera with a working range"):
        settings_from_dict({"population": {"n": 5}, "scan": {"camera": "cam.json"}, "sensor": {"range_limits": True}},
                           source="s.toml", base_dir=str(tmp_path))
    ok = settings_from_dict({"population": {"n": 5}, "scan": {"camera": "cam.json"}}, base_dir=str(tmp_path))
    assert scan_job(ok, 4.3).camera.width == 64  # the relative JSON path is read from the study file's folder


def test_the_parsers_read_the_settings_defaults_without_importing_pandas():
    import subprocess
    import sys

    code = ("import sys, wbsa.cli\n"
            "try:\n    wbsa.cli.main(['--help'])\nexcept SystemExit:\n    pass\n"
            "print(sorted({m.split('.')[0] for m in sys.modules} & {'pandas', 'torch', 'open3d', 'matplotlib'}))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip().splitlines()[-1] == "[]"


def test_the_report_reads_its_settings_from_study_manifests_old_and_new(tmp_path):
    from wbsa.report.build import report_settings_of
    from wbsa.report.sources import ReportSources

    def sources(report_table):
        return ReportSources(tmp_path, tmp_path / "p.parquet", (), tmp_path, {"settings": {"report": report_table}})

    new = ReportSettings(snapshot_subject=3, dpi=120)
    assert report_settings_of(sources(to_table(new))) == new
    old = {"scatter_view_deg": [0.0, 0.0], "nonlinear_view_deg": [60.0, 60.0], "snapshot_view_deg": [60.0, 60.0],
           "snapshot_subject": -1, "dpi": 100}  # study.json of a study run before optional keys
    assert report_settings_of(sources(old)) == ReportSettings()
