"""The clothing layer: a known area over a sphere, bare parts left alone, and the right parts dressed."""

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
