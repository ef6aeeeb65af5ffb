"""Study settings: TOML loading over the embedded default, validation, shipped configs, stage keys."""

import tomllib

import pytest

from wbsa.cli import main
from wbsa.errors import WbsaError
from wbsa.study.settings import (
    SHIPPED_CONFIGS,
    fit_settings,
    load_settings,
    scan_settings,
    settings_from_dict,
    vbsa_columns,
)
from wbsa.study.stages import Stage, stage_key


def write(tmp_path, text, name="study.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_embedded_default_is_the_paper_grid_at_4_3_m():
    s = load_settings()
    assert s.source == "default"
    assert s.population.kind == "random" and 100 <= s.population.n <= 1000
    views = scan_settings(s, s.scan.distances_m[0]).views
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
    assert len(scan_settings(s, 4.3).views) == 65
    assert s.fit.k == 10


def test_a_study_file_overrides_only_its_keys(tmp_path):
    p = write(tmp_path, "[population]\nn = 12\n[scan]\nazimuths_deg = [0, 90]\ndistances_m = [3.5, 5]\n")
    s = load_settings(p)
    d = load_settings()
    assert s.population.n == 12 and s.population.seed == d.population.seed
    assert s.scan.distances_m == (3.5, 5.0)  # integers in TOML are accepted as floats
    assert [v.azimuth_deg for v in scan_settings(s, 3.5).views] == [0.0, 90.0]
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
    assert scan_settings(s, 4.3).reconstruct == ("grid",)
    assert scan_settings(s, 4.3).sensor is not None and scan_settings(s, 4.3).sensor.noise == "nguyen2012"
    assert scan_settings(load_settings(), 4.3).sensor is None  # ideal sensor: no sensor step at all


@pytest.mark.parametrize("text, match", [
    ("[population]\nnn = 3\n", r"unknown key 'nn' in \[population\]; valid keys: kind, n,"),
    ("[populaton]\nn = 3\n", r"unknown table \[populaton\]"),
    ("[population]\nn = -3\n", r"\[population\] n must be at least 1"),
    ("[population]\nn = 3.5\n", r"\[population\] n must be an integer, got 3.5"),
    ("[population]\nkind = 'martian'\n", r"\[population\] kind must be one of 'random', 'survey'"),
    ("[scan]\ndistances_m = [4.3, -1]\n", r"\[scan\] distances_m must be positive"),
    ("[scan]\ndistances_m = 4.3\n", r"\[scan\] distances_m must be a list of a number"),
    ("[scan]\ncamera = 'kinect-v9'\n", r"unknown camera preset 'kinect-v9'"),
    ("[scan]\nviews = 'everywhere'\n", r"unknown view set 'everywhere'"),
    ("[sensor]\nholes_fraction = 2.0\n", r"\[sensor\] holes_fraction must be a fraction"),
    ("[reconstruction]\nmethods = ['marching-cubes']\n", r"\[reconstruction\] methods must be one of 'grid', 'ball-pivoting', 'poisson', got 'marching-cubes'"),
    ("[fit]\nk = 1\n", r"\[fit\] k must be at least 2"),
    ("[fit]\ngroups = ['males']\n", r"\[fit\] groups must include 'all'"),
    ("[fit]\nvbsa = ['vbsa_magic_m2']\n", r"\[fit\] unknown VBSA column 'vbsa_magic_m2'"),
    ("[fit]\npredictor_sets = [['shoe_size']]\n", r"\[fit\] predictor 'shoe_size' is not a population column"),
    ("[fit]\nrequire_in_frame = 1\n", r"\[fit\] require_in_frame must be true or false"),
    ("[report]\nnonlinear_view_deg = [60]\n", r"\[report\] nonlinear_view_deg must be a list of 2 values"),
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


def test_scan_stage_key_ignores_workers():
    from wbsa.study.settings import merge_tables

    base = load_settings()
    other = settings_from_dict(merge_tables({}, {"run": {"workers": 1}}))
    key = lambda s: stage_key("scan", scan_settings(s, 4.3).to_dict())  # noqa: E731
    assert key(base) == key(other)
