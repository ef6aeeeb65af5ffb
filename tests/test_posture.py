"""Standing postures: drawn per subject, posed by skinning on anny's skeleton, kept out of the body."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from wbsa.bodies.posture import (ANGLE_COLUMNS, JOINT_MOTIONS, POSTURE_COLUMNS, POSTURES, SETTLE_TOLERANCE_M,
                                 PostureSettings, draw_postures, posture_angles, settle_posture)
from wbsa.errors import WbsaError


def nominal(name: str) -> np.ndarray:
    """The (10,) nominal angles of a named posture, both sides."""
    return np.array([POSTURES[name].nominal(m) for _ in ("l", "r") for m in JOINT_MOTIONS])


@pytest.fixture(scope="module")
def adults(body_model):
    """Rest bodies of a neutral adult man and a woman with a heavy trunk (BMI ~30)."""
    from wbsa.bodies.anthropometry import reference_adult

    heavy = reference_adult(1.0).assign(p_weight=0.95, p_muscle=0.1, p_height=0.3)
    return body_model.rest_bodies(pd.concat([reference_adult(0.0), heavy], ignore_index=True))


@pytest.fixture(scope="module")
def mixed_table(body_model):
    """A 6-subject random population in mixed postures (table, as ``wbsa population --posture mixed``)."""
    from wbsa.bodies.build import build_population

    return build_population("random", n=6, seed=4, posture="mixed")


def test_postures_and_their_names_agree():
    from wbsa.typing import POSTURE_NAMES

    assert tuple(POSTURES) == POSTURE_NAMES
    assert len(ANGLE_COLUMNS) == 10 and len(set(ANGLE_COLUMNS)) == 10
    assert all(c.endswith("_deg") for c in ANGLE_COLUMNS) and POSTURE_COLUMNS[0] == "posture"


def test_zero_angles_give_the_rest_vertices_bit_for_bit(body_model, adults):
    from wbsa.bodies.posing import pose_vertices

    v, heads = adults.vertices[0], adults.bone_heads[0]
    assert np.array_equal(pose_vertices(v, heads, np.zeros(10), body_model.rig), v)
    # a table whose rows stand in the rest pose gives exactly the meshes of a table without posture columns
    from wbsa.bodies.anthropometry import reference_adult

    row = reference_adult(0.0).assign(subject_id=0)
    posed = row.join(draw_postures([0], PostureSettings("a-pose")).drop(columns="posture").assign(posture="a-pose"))
    assert np.array_equal(body_model.skin_meshes(posed)[0].vertices, body_model.skin_meshes(row)[0].vertices)
    assert np.array_equal(body_model.skin_meshes(row)[0].vertices, v)


def test_posture_draw_is_seeded_per_subject():
    s = PostureSettings("mixed", seed=7)
    a = draw_postures(np.arange(10), s)
    pd.testing.assert_frame_equal(a, draw_postures(np.arange(10), s))
    # subject i's posture does not depend on which other subjects are drawn
    b = draw_postures(np.arange(5, 15), s)
    pd.testing.assert_frame_equal(a.iloc[5:].reset_index(drop=True), b.iloc[:5].reset_index(drop=True))
    assert not a.equals(draw_postures(np.arange(10), PostureSettings("mixed", seed=8)))
    # jitter stays within each posture's documented range
    for name, rows in draw_postures(np.arange(200), s).groupby("posture"):
        spec = POSTURES[name]
        for col in ANGLE_COLUMNS:
            motion = col.replace("_l_", "_").replace("_r_", "_")[:-4]
            dev = (rows[col] - spec.nominal(motion)).abs()
            assert dev.max() <= spec.jitter(motion) + 1e-12
    assert set(draw_postures(np.arange(200), s)["posture"]) == set(POSTURES)
    assert (draw_postures(np.arange(3), PostureSettings("arms-down"))["posture"] == "arms-down").all()


def test_arms_down_lowers_the_hands_to_the_thighs(body_model, adults):
    """Fingertips of hanging arms are near 0.38 of stature (Drillis & Contini 1966 segment lengths);
    anny's A-pose holds them above half the stature."""
    from wbsa.bodies.posing import pose_vertices

    hand = body_model.vertices_of_bones(("wrist", "finger", "metacarpal"))
    for v, heads in zip(adults.vertices, adults.bone_heads):
        stature = v[:, 2].max()
        posed = pose_vertices(v, heads, nominal("arms-down"), body_model.rig)
        rest_tip, posed_tip = v[hand, 2].min() / stature, posed[hand, 2].min() / stature
        assert rest_tip > 0.5 and 0.36 < posed_tip < 0.44
        assert np.abs(posed[hand, 0]).mean() < 0.6 * np.abs(v[hand, 0]).mean()  # hands come in towards the body
        assert posed[:, 2].min() == 0.0  # still standing on the floor


def test_limbs_move_rigidly_and_the_trunk_stays(body_model, adults):
    """Vertices moved by the left forearm alone keep their distances to each other; the trunk does not move."""
    from wbsa.bodies.posing import SEGMENTS, pose_vertices

    v, heads = adults.vertices[0], adults.bone_heads[0]
    rig = body_model.rig
    posed = pose_vertices(v, heads, nominal("hands-on-hips"), rig, floor=False)
    seg = SEGMENTS.index("forearm")  # left side
    fore = rig.skin.vertices[rig.skin.rows[seg][rig.skin.weights[seg] >= 1.0 - 1e-9]]
    assert len(fore) > 500
    d_rest = np.linalg.norm(v[fore] - v[fore[0]], axis=1)
    d_posed = np.linalg.norm(posed[fore] - posed[fore[0]], axis=1)
    assert np.allclose(d_rest, d_posed, atol=1e-9)
    assert np.linalg.norm(posed[fore] - v[fore], axis=1).max() > 0.1
    still = np.setdiff1d(np.arange(len(v)), rig.skin.vertices)
    assert np.array_equal(posed[still], v[still])


def test_settling_keeps_heavy_arms_out_of_the_trunk(body_model, adults):
    from wbsa.bodies.posing import limb_sink_depths_m, pose_vertices

    v, heads = adults.vertices[1], adults.bone_heads[1]
    rig = body_model.rig
    drawn = nominal("arms-down")
    before = limb_sink_depths_m(pose_vertices(v, heads, drawn, rig), rig)
    assert before["arm_l"] > 0.01  # the nominal arms-down posture passes through this trunk
    angles, posed = settle_posture(v, heads, drawn, rig)
    after = limb_sink_depths_m(posed, rig)
    assert max(after["arm_l"], after["arm_r"]) <= SETTLE_TOLERANCE_M
    raised = angles - drawn
    assert raised[ANGLE_COLUMNS.index("shoulder_l_abduction_deg")] > 0
    assert np.count_nonzero(raised) <= 2  # only the shoulder abductions changed
    assert np.array_equal(posed, pose_vertices(v, heads, angles, rig))
    # a body at rest has no limb inside another part
    assert max(limb_sink_depths_m(v, rig).values()) == 0.0


def test_population_table_records_postures_and_posed_area(body_model, mixed_table):
    table = mixed_table
    assert all(c in table.columns for c in (*POSTURE_COLUMNS, "wbsa_posed_m2"))
    assert table["posture"].isin(list(POSTURES)).all()
    # the recorded posed area is the area of the mesh every later stage builds from the row
    meshes = body_model.skin_meshes(table)
    assert [m.area_m2 for m in meshes] == table["wbsa_posed_m2"].tolist()
    # skinning changes the skin area by well under 2 %; WBSA stays the rest area
    change = table["wbsa_posed_m2"] / table["wbsa_m2"] - 1
    assert (change.abs() < 0.02).all() and (change != 0).any()
    rest = body_model.rest_bodies(table)
    assert not any(np.array_equal(m.vertices, r) for m, r in zip(meshes, rest.vertices))


def test_a_pose_population_has_no_posture_columns():
    from wbsa.bodies.build import build_population
    from wbsa.bodies.table import TABLE_COLUMNS

    table = build_population("random", n=2, seed=1)
    assert list(table.columns) == list(TABLE_COLUMNS)


@pytest.mark.parametrize("change, message", [
    ({"elbow_l_flexion_deg": np.nan}, "elbow_l_flexion_deg = nan in row 0 is not a finite angle"),
    ({"hip_r_abduction_deg": 400.0}, "hip_r_abduction_deg = 400.0 in row 0"),
])
def test_bad_posture_angles_are_one_line_errors(change, message):
    table = draw_postures([0, 1], PostureSettings("mixed")).assign(**change)
    with pytest.raises(WbsaError, match=message):
        posture_angles(table)
    with pytest.raises(WbsaError, match="lacks shoulder_l_flexion_deg"):
        posture_angles(table.drop(columns="shoulder_l_flexion_deg"))
    assert posture_angles(table.drop(columns=list(ANGLE_COLUMNS))) is None


def test_bad_posture_settings_name_the_field():
    with pytest.raises(WbsaError, match="posture must be one of 'a-pose', 'mixed', 'arms-down'.*got 'dancing'"):
        PostureSettings("dancing")
    with pytest.raises(WbsaError, match="posture mix"):
        PostureSettings("mixed", mix=("twirl",))
    from wbsa.bodies.settings import PopulationSettings
    from wbsa.study.settings import settings_from_dict

    assert PopulationSettings(n=1).posture == "a-pose"
    with pytest.raises(WbsaError, match="posture must be one of 'a-pose', 'mixed', 'arms-down'"):
        PopulationSettings(n=1, posture="sit")
    assert settings_from_dict({"population": {"n": 3, "posture": "mixed"}}).population.posture == "mixed"
    with pytest.raises(WbsaError, match=r"\[population\] posture must be one of 'a-pose', 'mixed', .* got 'sit'"):
        settings_from_dict({"population": {"n": 3, "posture": "sit"}})


def test_population_cli_posture(tmp_path, capsys):
    from wbsa.cli import main

    assert main(["population", "--kind", "random", "--n", "2", "--posture", "sitting",
                 "--out", str(tmp_path / "p.parquet")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: posture must be one of 'a-pose', 'mixed'") and err.count("\n") == 1
    assert not (tmp_path / "p.parquet").exists()
    assert main(["population", "--kind", "random", "--n", "2", "--posture", "elbows-bent", "--workers", "1",
                 "--out", str(tmp_path / "p.parquet")]) == 0
    table = pd.read_parquet(tmp_path / "p.parquet")
    assert (table["posture"] == "elbows-bent").all() and (table["elbow_l_flexion_deg"] > 30).all()


def _scan(pop_path, out, *extra):
    from wbsa.cli import main

    return main(["scan", str(pop_path), "--azimuths", "0,90", "--elevations", "0", "--out", str(out),
                 "--chunk-size", "2", "--no-progress", *extra])


def test_scan_sees_the_posed_bodies(body_model, mixed_table, tmp_path, monkeypatch):
    from wbsa.scan import worker
    from wbsa.scan.layout import TABLE_FILE

    monkeypatch.setattr(worker, "_BODY_MODEL", body_model)
    table = mixed_table.iloc[:3]
    table.to_parquet(tmp_path / "posed.parquet", index=False)
    table.drop(columns=[*POSTURE_COLUMNS, "wbsa_posed_m2"]).to_parquet(tmp_path / "rest.parquet", index=False)
    assert _scan(tmp_path / "posed.parquet", tmp_path / "a", "--workers", "1") == 0
    assert _scan(tmp_path / "rest.parquet", tmp_path / "b", "--workers", "1") == 0
    posed = pd.read_parquet(tmp_path / "a" / TABLE_FILE)
    rest = pd.read_parquet(tmp_path / "b" / TABLE_FILE)
    assert (posed["vbsa_visible_m2"] != rest["vbsa_visible_m2"]).all()
    # the visible area of the posed mesh is what a view of the same mesh measures directly
    from wbsa.camera import MeshScene, preset
    from wbsa.camera.views import parse_views
    from wbsa.simulate import simulate_view

    mesh = body_model.skin_meshes(table.iloc[:1])[0]
    view = parse_views(None, azimuths="0", elevations="0", distance_m=4.3)[0]
    row = simulate_view(MeshScene(mesh), preset("kinect-v1"), view).row
    first = posed[(posed["subject_id"] == table["subject_id"].iloc[0]) & (posed["azimuth_deg"] == 0)]
    assert first["vbsa_visible_m2"].item() == row["vbsa_visible_m2"]


@pytest.mark.slow
def test_scan_of_postured_bodies_is_the_same_on_two_workers(body_model, mixed_table, tmp_path, monkeypatch,
                                                            dask_cluster):
    from wbsa.scan import worker
    from wbsa.scan.layout import TABLE_FILE

    monkeypatch.setattr(worker, "_BODY_MODEL", body_model)
    mixed_table.iloc[:4].to_parquet(tmp_path / "posed.parquet", index=False)
    assert _scan(tmp_path / "posed.parquet", tmp_path / "one", "--workers", "1") == 0
    assert _scan(tmp_path / "posed.parquet", tmp_path / "two", "--scheduler", dask_cluster) == 0  # two workers
    one = pd.read_parquet(tmp_path / "one" / TABLE_FILE)
    pd.testing.assert_frame_equal(one, pd.read_parquet(tmp_path / "two" / TABLE_FILE))
    assert len(one) == 8
