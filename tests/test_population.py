"""Virtual bodies, skin mask, anthropometry and the random population."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from wbsa.cli import main
from wbsa.bodies.anthropometry import closed_volume_m3, reference_adult
from wbsa.bodies.body_model import PHENOTYPE_COLUMNS
from wbsa.core.mesh import TriangleMesh, triangle_areas_m2
from wbsa.bodies.sections import plane_section_points, tape_perimeter_m


def _neutral() -> pd.DataFrame:
    row = {c: 0.5 for c in PHENOTYPE_COLUMNS}
    return pd.DataFrame([row])


# -- skin surface ----------------------------------------------------------------------------
def test_default_body_skin_area_matches_independent_computation(body_model):
    """Skin = shell − eyeballs − tongue − cavities, recomputed here with Open3D from anny's own data."""
    import anny
    import open3d as o3d
    import torch
    from anny.face_segmentation import get_face_segmentation_mask

    mesh = body_model.skin_meshes(_neutral())[0]
    m = body_model.anny
    faces = m.faces.numpy()
    verts = body_model.rest_bodies(_neutral()).vertices[0]
    drop = np.zeros(len(faces), bool)
    for label in ("eye_front.L", "eye_front.R", "eye_back.L", "eye_back.R", "tongue"):
        drop |= np.asarray(get_face_segmentation_mask(m, [label]), bool)
    cav = torch.load(f"{anny.__path__[0]}/data/template_mesh_internal_cavities.pth", weights_only=False)
    cav_v = set(int(i) for i in cav["vertex_indices"])
    base = m.base_mesh_vertex_indices.numpy()
    is_cav = np.array([int(b) in cav_v for b in base])
    drop |= is_cav[faces].all(axis=1)
    o3 = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(verts), o3d.utility.Vector3iVector(faces[~drop]))
    assert mesh.area_m2 == pytest.approx(o3.get_surface_area(), rel=1e-9)
    # measured with anny 0.6.2: the default body's skin is 1.5224 m² (shell 1.5663 m²; docs/population.md)
    assert mesh.area_m2 == pytest.approx(1.5224, abs=5e-4)
    assert triangle_areas_m2(verts, faces).sum() == pytest.approx(1.5663, abs=5e-4)


def test_closed_shell_is_watertight_and_volume_matches_anny(body_model):
    """Skin + cavities close the body: every edge is shared by exactly two triangles."""
    import torch
    from anny import Anthropometry

    f = body_model.closed_faces
    edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert (counts == 2).all()
    v = body_model.rest_bodies(reference_adult(0.0)).vertices
    ours = closed_volume_m3(v[0], f)
    theirs = float(Anthropometry(body_model.anny).volume(torch.as_tensor(v))[0])  # includes eyeballs, tongue
    assert ours == pytest.approx(theirs, rel=0.01)


def test_bodies_stand_on_floor_and_face_minus_y(body_model):
    bodies = body_model.rest_bodies(pd.concat([reference_adult(0.0), reference_adult(1.0)]))
    for v, joints in zip(bodies.vertices, bodies.bone_heads):
        assert v[:, 2].min() == pytest.approx(0.0, abs=1e-12)
        head = joints[body_model.bone_index("head")]
        face = v[(v[:, 2] > head[2]) & (np.abs(v[:, 0]) < 0.02)]
        assert face[:, 1].min() < head[1] - 0.05  # the nose points to −Y
        left_arm = joints[body_model.bone_index("lowerarm01.L")]
        assert left_arm[0] > 0.1  # the subject's left at +X


def test_phenotypes_outside_unit_interval_are_rejected(body_model):
    from wbsa.errors import WbsaError

    bad = _neutral()
    bad["p_weight"] = 1.3
    with pytest.raises(WbsaError, match="p_weight"):
        body_model.rest_bodies(bad)


def test_local_changes_default_to_none_and_move_their_own_girth(anthropometer, body_model):
    """l_* absent = l_* 0 (the phenotype-only body); the waist change moves the waist, the hip change the hip."""
    from wbsa.bodies.body_model import LOCAL_CHANGE_COLUMNS

    adult = reference_adult(1.0)
    plain = body_model.rest_bodies(adult).vertices
    zeros = adult.assign(**{c: 0.0 for c in LOCAL_CHANGE_COLUMNS})
    np.testing.assert_array_equal(body_model.rest_bodies(zeros).vertices, plain)
    adult = adult.assign(l_waist_circ=0.0, l_hips_circ=0.0)
    rows = pd.concat([adult, adult.assign(l_waist_circ=1.0), adult.assign(l_waist_circ=-1.0),
                      adult.assign(l_hips_circ=1.0), adult.assign(l_hips_circ=-1.0)], ignore_index=True)
    m = anthropometer.measure(body_model.rest_bodies(rows))
    waist, hip = m["waist_circ_m"].to_numpy(), m["hip_circ_m"].to_numpy()
    assert waist[1] > waist[0] + 0.02 and waist[2] < waist[0] - 0.02
    assert hip[3] > hip[0] + 0.02 and hip[4] < hip[0] - 0.01
    assert abs(hip[1] - hip[0]) < abs(waist[1] - waist[0])  # the waist change is local
    assert abs(waist[3] - waist[0]) < abs(hip[3] - hip[0])


def test_local_changes_outside_their_range_are_rejected(body_model):
    from wbsa.errors import WbsaError

    with pytest.raises(WbsaError, match="l_buttocks_volume"):
        body_model.rest_bodies(_neutral().assign(l_buttocks_volume=-1.5))


def test_old_tables_without_local_changes_are_read_as_zero(tmp_path, body_model):
    from wbsa.bodies.body_model import LOCAL_CHANGE_COLUMNS
    from wbsa.bodies.table import TABLE_COLUMNS, measure_population, read_population

    params = reference_adult(0.0).assign(subject_id=0, sex="male", age_years=35.0)
    table = measure_population(params, model=body_model)
    assert set(TABLE_COLUMNS) <= set(table.columns) and (table[list(LOCAL_CHANGE_COLUMNS)] == 0).all(axis=None)
    table.drop(columns=list(LOCAL_CHANGE_COLUMNS)).to_parquet(tmp_path / "old.parquet")
    back = read_population(tmp_path / "old.parquet")
    assert (back[list(LOCAL_CHANGE_COLUMNS)] == 0).all(axis=None)
    assert body_model.skin_meshes(back)[0].area_m2 == pytest.approx(table["wbsa_m2"].iloc[0], rel=1e-12)


# -- tape measures ---------------------------------------------------------------------------
def _cylinder(radius: float, height: float, n: int = 256) -> TriangleMesh:
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    ring = np.stack([radius * np.cos(t), radius * np.sin(t)], axis=1)
    v = np.concatenate([np.c_[ring, np.zeros(n)], np.c_[ring, np.full(n, height)]])
    i = np.arange(n)
    j = (i + 1) % n
    f = np.concatenate([np.c_[i, j, i + n], np.c_[j, j + n, i + n]])
    return TriangleMesh(v, f.astype(np.int32))


def test_tape_around_a_cylinder_is_its_circumference():
    cyl = _cylinder(0.15, 1.0)
    pts = plane_section_points(cyl.vertices, cyl.faces, np.array([0, 0, 0.4]), np.array([0, 0, 1.0]))
    assert tape_perimeter_m(pts, np.array([0, 0, 1.0])) == pytest.approx(2 * np.pi * 0.15, rel=1e-3)


def test_tape_bridges_concavities_like_a_real_tape():
    """Two touching cylinders: the tape spans the gap, it does not follow the waist between them."""
    a, b = _cylinder(0.1, 1.0), _cylinder(0.1, 1.0)
    v = np.concatenate([a.vertices - [0.1, 0, 0], b.vertices + [0.1, 0, 0]])
    f = np.concatenate([a.faces, b.faces + len(a.vertices)])
    pts = plane_section_points(v, f, np.array([0, 0, 0.5]), np.array([0, 0, 1.0]))
    assert tape_perimeter_m(pts, np.array([0, 0, 1.0])) == pytest.approx(2 * np.pi * 0.1 + 4 * 0.1, rel=1e-3)


def test_adult_tape_measures_are_human(anthropometer, body_model):
    """Reference adults: every measure in a plausible adult range; waist agrees with anny's."""
    import torch
    from anny import Anthropometry

    params = pd.concat([reference_adult(0.0), reference_adult(1.0)])
    bodies = body_model.rest_bodies(params)
    m = anthropometer.measure(bodies)
    ranges = {
        "stature_m": (1.5, 2.0), "mass_kg": (45, 110), "bmi": (17, 30), "wbsa_m2": (1.4, 2.4),
        "waist_circ_m": (0.6, 1.1), "hip_circ_m": (0.8, 1.2), "bust_circ_m": (0.75, 1.2),
        "underbust_circ_m": (0.65, 1.05), "neck_circ_m": (0.28, 0.45), "upper_arm_circ_m": (0.22, 0.4),
        "thigh_circ_m": (0.4, 0.7), "front_chest_width_m": (0.25, 0.45),
    }
    for col, (lo, hi) in ranges.items():
        assert m[col].between(lo, hi).all(), (col, m[col].tolist())
    anny_waist = Anthropometry(body_model.anny).waist_circumference(torch.as_tensor(bodies.vertices)).numpy()
    assert np.allclose(m["waist_circ_m"], anny_waist, rtol=0.05)
    # the bust sits above the underbust: a woman's bust tape is longer than her underbust tape
    assert m["bust_circ_m"].iloc[1] > m["underbust_circ_m"].iloc[1] + 0.05
    assert m["stature_m"].iloc[0] > m["stature_m"].iloc[1]


def test_heavier_body_has_larger_girths_and_area(anthropometer, body_model):
    light, heavy = reference_adult(0.0), reference_adult(0.0)
    light["p_weight"], heavy["p_weight"] = 0.2, 0.8
    m = anthropometer.measure(body_model.rest_bodies(pd.concat([light, heavy])))
    for col in ("mass_kg", "wbsa_m2", "waist_circ_m", "hip_circ_m", "thigh_circ_m", "upper_arm_circ_m"):
        assert m[col].iloc[1] > m[col].iloc[0], col


def test_age_mapping_follows_anny_anchors():
    from wbsa.bodies.age import param_to_years, years_to_param

    assert param_to_years(0.5) == pytest.approx(12.67, abs=0.01)  # anny's age anchors: 0.5 ≈ 12.7 y
    assert param_to_years(0.77) == pytest.approx(18.0)
    years = np.array([1.0, 12.0, 30.0, 70.0])
    assert np.allclose(param_to_years(years_to_param(years)), years)


# -- random population -------------------------------------------------------------------------
def test_random_population_is_deterministic_and_prefix_stable():
    from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters

    a = sample_random_parameters(RandomPopulationSettings(n=20, seed=3))
    b = sample_random_parameters(RandomPopulationSettings(n=20, seed=3))
    c = sample_random_parameters(RandomPopulationSettings(n=5, seed=3))
    d = sample_random_parameters(RandomPopulationSettings(n=20, seed=4))
    pd.testing.assert_frame_equal(a, b)
    pd.testing.assert_frame_equal(a.iloc[:5], c)
    assert not a.equals(d)
    assert a["age_years"].between(12, 70).all()
    assert set(a["sex"]) <= {"male", "female"}
    assert np.allclose(a[["p_african", "p_asian", "p_caucasian"]].sum(axis=1), 1.0)
    assert ((a["p_gender"] == 1.0) == (a["sex"] == "female")).all()


def test_varied_sampling_draws_local_changes_in_two_correlated_pairs():
    from wbsa.bodies.body_model import LOCAL_CHANGE_COLUMNS
    from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters

    v = sample_random_parameters(RandomPopulationSettings.varied(n=3000, seed=1))
    paper = sample_random_parameters(RandomPopulationSettings(n=3000, seed=1))
    pd.testing.assert_frame_equal(v.iloc[:40], sample_random_parameters(RandomPopulationSettings.varied(n=40, seed=1)))
    assert (v["sex"] == paper["sex"]).all()  # the same streams: the paper's draws come first
    assert "l_waist_circ" not in paper.columns
    assert v["age_years"].between(7, 80).all()
    child = v["age_years"] <= 15
    assert 0.4 < child.mean() < 0.65  # uniform in anny's age parameter: about half are children
    local = v[list(LOCAL_CHANGE_COLUMNS)]
    assert local[~child].abs().max().max() <= 1.0 and local[child].abs().max().max() <= 0.5
    assert local[~child].abs().max().min() > 0.9  # adults reach the ends of the range
    r = local[~child].corr()
    assert r.loc["l_waist_circ", "l_stomach_pregnant"] > 0.7 and r.loc["l_hips_circ", "l_buttocks_volume"] > 0.7
    assert abs(r.loc["l_waist_circ", "l_hips_circ"]) < 0.1
    assert abs(r.loc["l_stomach_pregnant", "l_buttocks_volume"]) < 0.1
    # half the adults sit in the heavy corner on purpose, a sixteenth more by chance; children by chance only
    corner = (v["p_weight"] >= 0.75) & (v["p_muscle"] <= 0.25)
    assert abs(corner[~child].mean() - (0.5 + 0.5 / 16)) < 0.04
    assert abs(corner[child].mean() - 1 / 16) < 0.03
    assert v["p_height"].min() < 0.01 and v["p_height"].max() > 0.99


@pytest.mark.slow
def test_varied_population_has_the_obese_adults_the_issue_asks_for(body_model):
    """A default-size (300) varied population at real densities: at least 30 obese adults, BMI 14 to 40+."""
    from wbsa.analysis.realism import group_counts, hw_law
    from wbsa.bodies.build import build_population

    t = build_population("random", n=300, seed=0, sampling="varied", density_model="deurenberg-siri",
                         show_progress=False)
    counts = group_counts(t)
    assert counts["obese"] >= 30 and counts["underweight"] >= 5
    adults = t[t["age_years"] > 15]
    assert adults["bmi"].min() < 16 and adults["bmi"].max() > 40
    assert t["stature_m"].min() < 1.1 and t["stature_m"].max() > 2.3
    paper = build_population("random", n=300, seed=0, show_progress=False)
    # local changes and composition spread the area at fixed stature and mass
    assert hw_law(t).residual_sd_percent > hw_law(paper).residual_sd_percent + 0.15


@pytest.mark.slow
def test_population_is_identical_with_worker_processes(monkeypatch, body_model, dask_cluster):
    from wbsa.bodies import table as table_module
    from wbsa.bodies.composition import CompositionSettings
    from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters

    params = sample_random_parameters(RandomPopulationSettings.varied(n=70, seed=4))
    composition = CompositionSettings(model="deurenberg-siri", seed=4)
    one = table_module.measure_population(params, model=body_model, composition=composition, batch_size=16)
    monkeypatch.setattr(table_module, "PARALLEL_MIN_BODIES", 0)
    two = table_module.measure_population(params, composition=composition, workers=2, batch_size=16,
                                          scheduler=dask_cluster)
    pd.testing.assert_frame_equal(one, two, check_exact=True)


def test_population_cli_writes_identical_tables_for_same_seed(tmp_path, body_model):
    out1, out2 = tmp_path / "a.parquet", tmp_path / "b.parquet"
    assert main(["population", "--kind", "random", "--n", "6", "--seed", "7", "--out", str(out1)]) == 0
    assert main(["population", "--kind", "random", "--n", "6", "--seed", "7", "--out", str(out2)]) == 0
    a, b = pd.read_parquet(out1), pd.read_parquet(out2)
    pd.testing.assert_frame_equal(a, b)
    from wbsa.bodies.table import POPULATION_COLUMNS, read_population

    assert list(read_population(out1).columns[: len(POPULATION_COLUMNS)]) == list(POPULATION_COLUMNS)
    assert (a["bmi"] - a["mass_kg"] / a["stature_m"] ** 2).abs().max() < 1e-9
    # csv and xlsx exports carry the same table
    assert main(["population", "--kind", "random", "--n", "6", "--seed", "7", "--out", str(tmp_path / "a.csv")]) == 0
    assert main(["population", "--kind", "random", "--n", "6", "--seed", "7", "--out", str(tmp_path / "a.xlsx")]) == 0
    csv = pd.read_csv(tmp_path / "a.csv")
    assert np.allclose(csv["wbsa_m2"], a["wbsa_m2"])
    assert np.allclose(pd.read_excel(tmp_path / "a.xlsx")["stature_m"], a["stature_m"])


def test_table_kind_builds_given_phenotypes(tmp_path, body_model):
    params = pd.concat([reference_adult(0.0), reference_adult(1.0)])
    params.to_csv(tmp_path / "p.csv", index=False)
    out = tmp_path / "t.parquet"
    assert main(["population", "--kind", "table", "--params", str(tmp_path / "p.csv"), "--out", str(out)]) == 0
    t = pd.read_parquet(out)
    assert list(t["sex"]) == ["male", "female"]
    expected = body_model.skin_meshes(params)[1].area_m2
    assert t["wbsa_m2"].iloc[1] == pytest.approx(expected)


def test_body_export_round_trips_through_ply_and_obj(tmp_path, body_model):
    import open3d as o3d

    for name in ("b.ply", "b.obj"):
        path = tmp_path / name
        assert main(["body", "--gender", "1", "--age", "0.8", "--out", str(path)]) == 0
        m = o3d.io.read_triangle_mesh(str(path))
        row = _neutral()
        row["p_gender"], row["p_age"] = 1.0, 0.8
        row["p_cupsize"] = row["p_firmness"] = 0.5
        assert m.get_surface_area() == pytest.approx(body_model.skin_meshes(row)[0].area_m2, rel=1e-6)


# -- bad input ----------------------------------------------------------------------------------
def _fails_cleanly(capsys, argv: list[str], words: str) -> None:
    with pytest.raises(SystemExit) as exc:
        raise SystemExit(main(argv))
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and "\n" not in err and "Traceback" not in err
    assert words in err, err


def test_bad_inputs_give_one_line_errors(tmp_path, capsys, body_model):
    out = tmp_path / "p.parquet"
    _fails_cleanly(capsys, ["population", "--kind", "martian", "--n", "3", "--out", str(out)], "invalid choice")
    _fails_cleanly(capsys, ["population", "--kind", "random", "--n", "0", "--out", str(out)], "n must be at least 1")
    _fails_cleanly(capsys, ["population", "--kind", "random", "--n", "-4", "--out", str(out)], "n must be at least 1")
    _fails_cleanly(capsys, ["population", "--kind", "random", "--out", str(out)], "n must be given for kind 'random'")
    _fails_cleanly(capsys, ["population", "--kind", "table", "--out", str(out)], "params_path must name")
    blocker = tmp_path / "file"
    blocker.write_text("x")
    _fails_cleanly(capsys, ["population", "--kind", "random", "--n", "2", "--out", str(blocker / "p.parquet")],
                   "cannot")
    bad = pd.concat([reference_adult(0.0)])
    bad["p_height"] = -0.2
    bad.to_parquet(tmp_path / "bad.parquet")
    _fails_cleanly(capsys, ["population", "--kind", "table", "--params", str(tmp_path / "bad.parquet"),
                            "--out", str(out)], "outside [0, 1]")
    (tmp_path / "corrupt.parquet").write_bytes(b"PAR1 this is not parquet")
    _fails_cleanly(capsys, ["population", "--kind", "table", "--params", str(tmp_path / "corrupt.parquet"),
                            "--out", str(out)], "not a readable Parquet")
    pd.DataFrame({"x": [1, 2]}).to_parquet(tmp_path / "foreign.parquet")
    _fails_cleanly(capsys, ["population", "--kind", "table", "--params", str(tmp_path / "foreign.parquet"),
                            "--out", str(out)], "missing column")
    _fails_cleanly(capsys, ["body", "--population", str(tmp_path / "foreign.parquet"), "--out",
                            str(tmp_path / "b.ply")], "missing column")
    assert not out.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temp files left


def test_failed_run_keeps_an_existing_table_intact(tmp_path, capsys, body_model):
    out = tmp_path / "keep.parquet"
    assert main(["population", "--kind", "random", "--n", "3", "--out", str(out)]) == 0
    before = out.read_bytes()
    bad = reference_adult(0.0)
    bad["p_weight"] = 2.0
    bad.to_csv(tmp_path / "bad.csv", index=False)
    _fails_cleanly(capsys, ["population", "--kind", "table", "--params", str(tmp_path / "bad.csv"),
                            "--out", str(out)], "p_weight")
    assert out.read_bytes() == before


def test_body_model_and_bodies_print_their_sizes(body_model, anthropometer):
    n_vertices = body_model.anny.template_vertices.shape[-2]
    text = repr(body_model)
    assert text.startswith(f"BodyModel(anny: {n_vertices:,} vertices, {len(body_model.faces):,} faces "
                           f"({len(body_model.skin_faces):,} skin), 11 phenotypes, 7 local changes")
    assert repr(anthropometer) == f"Anthropometer(density 980 kg/m³, {text})"
    bodies = body_model.rest_bodies(pd.concat([reference_adult(0.0), reference_adult(1.0)]))
    assert repr(bodies) == (f"RestBodies(2 bodies × {n_vertices:,} vertices, "
                            f"{len(body_model.bone_labels)} bone heads, metres)")
