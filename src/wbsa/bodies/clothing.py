"""A layer of everyday clothes over the skin: what a depth camera sees of a dressed person.

The bodies are bare skin, as the paper's subjects were ("nude, or wearing tight-fitting clothes"). A
dressed person shows the camera the outside of the clothes, which encloses more area than the skin:
a layer of thickness t over a limb of radius r adds about t / r of its area (1 cm over a 6 cm thigh,
17 %). :func:`clothed_vertices` moves the skin outwards along its normals by a layer where a T-shirt,
trousers and shoes cover it (:data:`COVERED_BONES`: trunk, upper arms, legs, feet), and leaves the head,
neck, forearms and hands bare. The layer is uniform and follows the skin: loose folds, a skirt or a coat
bridging the legs are not modelled. :func:`dressed_vertices` also flattens the shoe soles onto the floor.
The estimator's training dresses a share of its captures so (the user states the layer, ``--clothing-cm``),
and ``benchmarks/bench_estimate.py --clothing-m`` measures it on dressed held-out bodies.
"""

from __future__ import annotations

import numpy as np

#: anny bones (name prefixes) whose vertices a T-shirt, trousers and shoes cover.
COVERED_BONES = ("root", "pelvis", "spine", "clavicle", "shoulder", "upperarm", "upperleg", "lowerleg", "foot",
                 "toe")


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit vertex normals of an outward-wound mesh (Open3D's, area-weighted); zero where no triangle uses a vertex.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (m, 3) int
        Counter-clockwise seen from outside.

    Returns
    -------
    (n, 3) float64
    """
    import open3d as o3d

    mesh = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(np.asarray(vertices, dtype=np.float64)),
                                     o3d.utility.Vector3iVector(np.asarray(faces, dtype=np.int32)))
    mesh.compute_vertex_normals(normalized=True)
    return np.asarray(mesh.vertex_normals, dtype=np.float64)


def clothed_vertices(vertices: np.ndarray, faces: np.ndarray, covered: np.ndarray, layer_m: float) -> np.ndarray:
    """The skin moved outwards by a layer of clothes where ``covered``.

    Parameters
    ----------
    vertices : (n, 3) float64
        One posed body's skin (metres).
    faces : (m, 3) int
        Its triangles, counter-clockwise seen from outside.
    covered : (n,) bool
        Vertices under the clothes (e.g. ``BodyModel.vertices_of_bones(COVERED_BONES)``).
    layer_m : float
        Thickness of the layer (m), 0 or more.

    Returns
    -------
    (n, 3) float64
        The outside of the clothes; bare vertices unchanged.

    Raises
    ------
    ValueError
        A negative or non-finite ``layer_m``, or ``covered`` of the wrong length.
    """
    v = np.asarray(vertices, dtype=np.float64)
    covered = np.asarray(covered, dtype=bool)
    if not (np.isfinite(layer_m) and layer_m >= 0.0):
        raise ValueError(f"the clothing layer must be 0 or more metres, got {layer_m}")
    if covered.shape != (len(v),):
        raise ValueError(f"covered must be one flag per vertex ({len(v)}), got shape {covered.shape}")
    if layer_m == 0.0 or not covered.any():
        return v.copy()
    return v + (layer_m * covered)[:, None] * vertex_normals(v, faces)


def dressed_vertices(vertices: np.ndarray, faces: np.ndarray, covered: np.ndarray, layer_m: float) -> np.ndarray:
    """:func:`clothed_vertices` standing on the floor z = 0: the shoe soles flattened onto it, not through it.

    Parameters
    ----------
    vertices : (n, 3) float64
        One posed body's skin (metres), standing on z = 0.
    faces : (m, 3) int
    covered : (n,) bool
    layer_m : float
        0 gives the skin itself (a copy).

    Returns
    -------
    (n, 3) float64
    """
    dressed = clothed_vertices(vertices, faces, covered, layer_m)
    if layer_m > 0.0:
        dressed[:, 2] = np.maximum(dressed[:, 2], 0.0)
    return dressed
