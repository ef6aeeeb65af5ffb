"""The clothing layer: a known area over a sphere, bare parts left alone, the right parts dressed, the soles on
the floor, and dressed training renders that differ from the bare ones only by the clothes."""

import numpy as np
import pytest


def _sphere(radius_m: float):
    import open3d as o3d

    s = o3d.geometry.TriangleMesh.create_sphere(radius=radius_m, resolution=60)
    return np.asarray(s.vertices, dtype=np.float64), np.asarray(s.triangles, dtype=np.int64)


def _area_m2(vertices, faces):
    from wbsa.core.mesh import triangle_areas_m2

    return float(triangle_areas_m2(vertices, faces).sum())


def test_a_layer_over_a_sphere_gives_the_larger_sphere():
    from wbsa.bodies.clothing import clothed_vertices

    v, f = _sphere(0.10)
    out = clothed_vertices(v, f, np.ones(len(v), dtype=bool), 0.01)
    np.testing.assert_allclose(np.linalg.norm(out, axis=1), 0.11, rtol=1e-4)
    # a sphere's area grows as (r + t)² / r²: 21 % for 1 cm over 10 cm (a limb, a cylinder, by t / r: 10 %)
    assert _area_m2(out, f) / _area_m2(v, f) == pytest.approx(1.21, rel=1e-3)


def test_bare_vertices_stay_put_and_bad_layers_are_refused():
    from wbsa.bodies.clothing import clothed_vertices

    v, f = _sphere(0.10)
    upper = v[:, 2] > 0.0
    out = clothed_vertices(v, f, upper, 0.02)
    np.testing.assert_array_equal(out[~upper], v[~upper])
    assert np.all(np.linalg.norm(out[upper], axis=1) > 0.119)
    np.testing.assert_array_equal(clothed_vertices(v, f, upper, 0.0), v)
    with pytest.raises(ValueError, match="0 or more metres"):
        clothed_vertices(v, f, upper, -0.01)
    with pytest.raises(ValueError, match="one flag per vertex"):
        clothed_vertices(v, f, upper[:-1], 0.01)


def test_clothes_cover_trunk_and_legs_but_not_head_or_hands(body_model):
    from wbsa.bodies.anthropometry import reference_adult
    from wbsa.bodies.clothing import COVERED_BONES

    covered = body_model.vertices_of_bones(COVERED_BONES)
    head = body_model.vertices_of_bones(("head", "neck", "eye"))
    hands = body_model.vertices_of_bones(("wrist", "finger", "metacarpal"))
    legs = body_model.vertices_of_bones(("upperleg", "lowerleg"))
    assert head.any() and hands.any() and legs.any()
    assert not (covered & head).any() and not (covered & hands).any()
    assert covered[legs].all()
    # most of the skin's area is under the clothes (the head and hands hold many small triangles)
    v = body_model.rest_bodies(reference_adult(0.0)).vertices[0]
    f = body_model.skin_faces
    share = _area_m2(v, f[covered[f].all(axis=1)]) / _area_m2(v, f)
    assert 0.6 < share < 0.9


def test_dressed_bodies_stand_on_the_floor_and_no_layer_is_the_skin(body_model):
    from wbsa.bodies.anthropometry import reference_adult
    from wbsa.bodies.clothing import COVERED_BONES, clothed_vertices, dressed_vertices

    v = body_model.rest_bodies(reference_adult(0.0)).vertices[0].astype(np.float64)
    f = body_model.skin_faces
    covered = body_model.vertices_of_bones(COVERED_BONES)
    assert v[:, 2].min() == pytest.approx(0.0, abs=0.005)  # anny's bodies stand on z = 0
    np.testing.assert_array_equal(dressed_vertices(v, f, covered, 0.0), v)
    layer = clothed_vertices(v, f, covered, 0.01)
    assert layer[:, 2].min() < -0.005  # the layer alone pushes the soles through the floor ...
    dressed = dressed_vertices(v, f, covered, 0.01)
    assert dressed[:, 2].min() == 0.0  # ... the shoes stand on it
    np.testing.assert_array_equal(dressed[layer[:, 2] >= 0], layer[layer[:, 2] >= 0])


@pytest.mark.slow
def test_dressed_training_renders_differ_from_bare_ones_only_by_the_clothes():
    """The clothes draw from their own (seventh) stream: with every body dressed, the captures (posture,
    camera, view) are those of the bare renders, the row records the layer, and the measured VBSA grows by
    about the layer over the limbs' radius (1 cm: some 8 % on an adult, more on a child)."""
    from wbsa.training.renders import render_chunk
    from wbsa.training.settings import RenderSettings
    from wbsa.training.pipeline import TrainSettings, training_population

    pop = training_population(TrainSettings(n_random=8, n_survey=0, seed=5), show_progress=False).iloc[:2]
    bare = render_chunk(pop, 0, RenderSettings(views_per_subject=2, clothed_share=0.0))
    dressed = render_chunk(pop, 0, RenderSettings(views_per_subject=2, clothed_share=1.0, clothing_m=(0.01, 0.01)))
    same = ["posture", "camera", "azimuth_deg", "elevation_deg", "distance_m", "camera_height_m", "wbsa_m2"]
    pd_equal = (bare.table[same] == dressed.table[same]).all().all()
    assert pd_equal and (bare.table["clothing_m"] == 0).all() and (dressed.table["clothing_m"] == 0.01).all()
    gain = dressed.table["m_vbsa_m2"] / bare.table["m_vbsa_m2"]
    assert gain.between(1.04, 1.25).all(), gain.tolist()
