"""Study settings: TOML loading over the embedded default, validation, shipped configs, stage keys.

The generic TOML layer and the stages' own settings classes are tested in tests/test_settings_io.py.
"""

import tomllib

import pytest

from wbsa.cli import main
from wbsa.errors import WbsaError
from wbsa.study.settings import (
    SHIPPED_CONFIGS,
    fit_settings,
    load_settings,
    scan_job,
    settings_from_dict,
    vbsa_columns,
)
from wbsa.analysis.settings import FitSettings
from wbsa.bodies.settings import PopulationSettings
from wbsa.parallel import RunSettings
from wbsa.report.settings import ReportSettings
from wbsa.scan.settings import ScanSettings
from wbsa.sensor.settings import SensorSettings
from wbsa.study.settings import shipped_config_path
from wbsa.study.stages import Stage, stage_key
from wbsa.surface.settings import ReconstructionSettings


def write(tmp_path, text, name="study.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_embedded_default_is_the_paper_grid_at_4_3_m():
    s = load_settings()
    assert s.source == "default"
    assert s.population.kind == "random" and 100 <= s.population.n <= 1000
    views = scan_job(s, s.scan.distances_m[0]).views
    assert len(views) == 65
    assert {v.distance_m for v in views} == {4.3}
    fs = fit_settings(s)
    assert fs.k == 10 and fs.predictor_sets == ((), ("stature_m",)) and fs.groups[0] == "all"


@pytest.mark.parametrize("name", SHIPPED_CONFIGS)
def test_every_shipped_config_loads(name):
    s = load_settings(name)
    assert s.scan.distances_m


def test_paper_config_is_paper_scale():
    s = load_settings("paper")
    assert s.population.n == 19995
    assert len(scan_job(s, 4.3).views) == 65
    assert s.fit.k == 10


def test_a_study_file_overrides_only_its_keys(tmp_path):
    p = write(tmp_path, "[population]\nn = 12\n[scan]\nazimuths_deg = [0, 90]\ndistances_m = [3.5, 5]\n")
    s = load_settings(p)
    d = load_settings()
    assert s.population.n == 12 and s.population.seed == d.population.seed
    assert s.scan.distances_m == (3.5, 5.0)  # integers in TOML are accepted as floats
    assert [v.azimuth_deg for v in scan_job(s, 3.5).views] == [0.0, 90.0]
    assert s.fit == d.fit


def test_resolved_settings_round_trip_through_toml(tmp_path):
    s = load_settings("distance-sweep")
    text = s.to_toml()
    tomllib.loads(text)  # valid TOML
    again = load_settings(write(tmp_path, text))
    assert again.to_dict() == s.to_dict()


def test_reconstruction_methods_add_their_vbsa_columns():
    s = load_settings("reconstruction")
    assert vbsa_columns(s) == ("vbsa_visible_m2", "vbsa_recon_m2:grid")
    assert scan_job(s, 4.3).reconstruct == ("grid",)
    assert scan_job(s, 4.3).sensor is not None and scan_job(s, 4.3).sensor.noise == "nguyen2012"
    assert scan_job(load_settings(), 4.3).sensor is None  # ideal sensor: no sensor step at all


@pytest.mark.parametrize("text, match", [
    ("[population]\nnn = 3\n", r"unknown key 'nn' in \[population\]; valid keys: kind, n,"),
    ("[populaton]\nn = 3\n", r"unknown table \[populaton\]"),
    ("[population]\nn = -3\n", r"\[population\] n must be at least 1"),
    ("[population]\nn = 3.5\n", r"\[population\] n must be an integer, got 3.5"),
    ("[population]\nkind = 'martian'\n", r"\[population\] kind must be one of 'random', 'survey', 'table'"),
    ("[population]\nkind = 'table'\nparams_path = 'p.csv'\n", r"\[population\] kind must be one of random, survey in a study"),
    ("[population]\ndensity_kg_m3 = 98\n", r"\[population\] density_kg_m3 must be a body density"),
    ("[scan]\ndistances_m = [4.3, -1]\n", r"\[scan\] distances_m must be positive"),
    ("[scan]\ndistances_m = 4.3\n", r"\[scan\] distances_m must be a list of a number"),
    ("[scan]\ncamera = 'kinect-v9'\n", r"unknown camera preset 'kinect-v9'"),
    ("[scan]\nviews = 'everywhere'\n", r"\[scan\] views must be one of paper, sphere:N, grid:STEP, front .*got 'everywhere'"),
    ("[scan]\nchunk_size = 10\n", r"\[scan\] chunk_size is now \[run\] chunk_size; move it there"),
    ("[sensor]\nholes_fraction = 2.0\n", r"\[sensor\] holes_fraction must be a fraction"),
    ("[reconstruction]\nmethods = ['marching-cubes']\n", r"\[reconstruction\] methods must be one of 'grid', 'ball-pivoting', 'poisson', got 'marching-cubes'"),
    ("[sensor]\ngrazing_dropout_deg = -1.0\n", r"\[sensor\] grazing_dropout_deg must be degrees in \[0, 90\) "
     r"\(or left out"),
    ("[sensor]\nrange_limits = true\n[scan]\ncamera = 'cam.json'\n", r"\[scan\] .*cam.json"),
    ("[reconstruction]\ndenoise = 'gauss'\n", r"\[reconstruction\] denoise must be one of 'quadratic'"),
    ("[fit]\nk = 1\n", r"\[fit\] k must be at least 2"),
    ("[fit]\ngroups = ['males']\n", r"\[fit\] groups must include 'all'"),
    ("[fit]\nvbsa_columns = ['vbsa_magic_m2']\n", r"\[fit\] vbsa_columns has unknown VBSA column 'vbsa_magic_m2'"),
    ("[fit]\nvbsa = ['vbsa_hit_m2']\n", r"\[fit\] vbsa is now \[fit\] vbsa_columns"),
    ("[fit.group_spec]\nsmall_max_stature_m = 2.5\n", r"\[fit.group_spec\] small_max_stature_m must be positive "
     r"and below big_min_stature_m"),
    ("[fit]\ngroup_spec = 3\n", r"fit.group_spec must be a table"),
    ("[fit]\npredictor_sets = [['shoe_size']]\n", r"\[fit\] predictor 'shoe_size' is not a population column"),
    ("[fit]\nrequire_in_frame = 1\n", r"\[fit\] require_in_frame must be true or false"),
    ("[report]\nnonlinear_view_deg = [60]\n", r"\[report\] nonlinear_view_deg must be a list of 2 values"),
    ("[report]\nsnapshot_subject = -1\n", r"\[report\] snapshot_subject must be a subject id .*leave it out"),
    ("[run]\nworkers = -2\n", r"\[run\] workers must be 0 \(all cores\) or more"),
    ("population = 3\n", r"population must be a table"),
    ("[population\nn = 3\n", r"is not valid TOML"),
])
def test_bad_study_files_are_one_line_errors(tmp_path, text, match):
    p = write(tmp_path, text)
    with pytest.raises(WbsaError, match=match) as info:
        load_settings(p)
    assert "\n" not in str(info.value)
    assert str(p) in str(info.value)


def test_missing_config_names_the_shipped_ones(tmp_path):
    with pytest.raises(WbsaError, match="does not exist.*default, paper"):
        load_settings(tmp_path / "nope.toml")


def test_bad_config_exits_2_with_one_line(tmp_path, capsys):
    p = write(tmp_path, "[fit]\nk = 0\n")
    assert main(["run", "--config", str(p), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1 and "[fit] k" in err
    assert not (tmp_path / "out").exists()  # nothing ran


def test_print_config_prints_the_resolved_toml(tmp_path, capsys):
    p = write(tmp_path, "[population]\nn = 7\n")
    assert main(["run", "--config", str(p), "--print-config"]) == 0
    doc = tomllib.loads(capsys.readouterr().out)
    assert doc["population"]["n"] == 7 and doc["fit"]["k"] == load_settings().fit.k


def test_settings_from_dict_without_files():
    s = settings_from_dict({"population": {"n": 5}})
    assert s.population.n == 5 and s.scan.views == "paper"
    with pytest.raises(WbsaError, match=r"<dict>: \[population\] n must be given for kind 'random'"):
        settings_from_dict({})  # a population has no default size


def test_stage_keys_follow_settings_and_inputs(tmp_path):
    a = stage_key("scan", {"d": 4.3, "views": [[0, 0]]}, {"population": "abc"})
    assert a == stage_key("scan", {"views": [[0, 0]], "d": 4.3}, {"population": "abc"})  # key order is irrelevant
    assert a != stage_key("scan", {"d": 4.4, "views": [[0, 0]]}, {"population": "abc"})
    assert a != stage_key("scan", {"d": 4.3, "views": [[0, 0]]}, {"population": "abd"})
    assert a != stage_key("fit", {"d": 4.3, "views": [[0, 0]]}, {"population": "abc"})
    st = Stage.create(tmp_path, "scan", {"d": 4.3}, {"population": "abc"})
    assert st.path.name == f"scan-{st.key}" and not st.done
    st.path.mkdir(parents=True)
    st.finish(1.5, {"scan": "scan.parquet"}, {"summary": "x"})
    assert not st.done  # its recorded output is missing
    (st.path / "scan.parquet").write_bytes(b"x")
    assert st.done and st.record()["seconds"] == 1.5 and st.record()["inputs"] == {"population": "abc"}


def test_scan_stage_key_ignores_execution_knobs(tmp_path):
    base = load_settings()
    other = load_settings(write(tmp_path, "[run]\nworkers = 3\nchunk_size = 7\nscheduler = 'tcp://1.2.3.4:8786'\n"
                                          "progress = true\n"))
    assert other.run.chunk_size == 7 and base.run.chunk_size != 7
    key = lambda s: stage_key("scan", scan_job(s, 4.3).to_dict())  # noqa: E731
    assert key(base) == key(other)
    assert "chunk_size" not in scan_job(other, 4.3).to_dict()
    changed = load_settings(write(tmp_path, "[scan]\nseed = 1\n", "seed.toml"))
    assert key(changed) != key(base)  # a setting that changes the rows does change the key


def test_default_toml_only_lists_what_differs_from_the_stage_defaults():
    """Defaults live once, in the stages' settings classes: the embedded default study sets only its size and name."""
    s = load_settings()
    assert s.population == PopulationSettings(n=300)
    assert (s.scan, s.sensor, s.reconstruction, s.fit, s.report, s.run) == (
        ScanSettings(), SensorSettings(), ReconstructionSettings(), FitSettings(), ReportSettings(), RunSettings())
    assert set(tomllib.loads(shipped_config_path("default").read_text())) == {"study", "population"}


def test_study_fit_settings_add_what_the_study_implies():
    s = load_settings("reconstruction")
    fs = fit_settings(s)
    assert fs.vbsa_columns == ("vbsa_visible_m2", "vbsa_recon_m2:grid") and fs.population_kind == "random"
    p = settings_from_dict({"population": {"n": 5, "kind": "survey"}, "fit": {"predictor_sets": [["mass"]]}})
    assert fit_settings(p).predictor_sets == ((), ("mass",)) and fit_settings(p).population_kind == "survey"
    assert p.fit.predictor_sets == (("mass",),)  # the [fit] table itself is kept as written
