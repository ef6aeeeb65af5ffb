"""Write bodies (or any :class:`TriangleMesh`) as PLY/OBJ, and rebuild a subject's mesh."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from wbsa.errors import WbsaError
from wbsa.io import atomic_path
from wbsa.population.mesh import TriangleMesh

MESH_SUFFIXES = (".ply", ".obj")


def write_mesh(mesh: TriangleMesh, path: str | os.PathLike) -> Path:
    """Write ``mesh`` atomically as PLY or OBJ (by suffix), in metres."""
    import open3d as o3d

    path = Path(path)
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise WbsaError(f"cannot write a mesh as {path.suffix or 'no suffix'}; use a .ply or .obj name")
    m = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(np.asarray(mesh.vertices, dtype=np.float64)),
                                  o3d.utility.Vector3iVector(np.asarray(mesh.faces, dtype=np.int32)))
    with atomic_path(path, keep_suffix=True) as tmp:  # open3d picks the format from the suffix
        ok = o3d.io.write_triangle_mesh(str(tmp), m, write_ascii=False, write_vertex_normals=False,
                                        write_vertex_colors=False)
        if not ok:
            raise WbsaError(f"open3d could not write {path}")
        for extra in tmp.parent.glob(tmp.stem + "*.mtl"):
            extra.unlink()
    return path


def subject_mesh(population, subject_id: int, model=None) -> TriangleMesh:
    """The skin mesh of one subject of a population table.

    Parameters
    ----------
    population : pandas.DataFrame
        A table with ``subject_id`` and the ``p_*`` columns.
    subject_id
        The subject to rebuild.
    """
    from wbsa.population.body_model import BodyModel

    rows = population[population["subject_id"] == subject_id]
    if rows.empty:
        ids = population["subject_id"]
        raise WbsaError(f"subject {subject_id} is not in the population (ids {ids.min()}–{ids.max()})")
    return (model or BodyModel()).skin_meshes(rows.iloc[:1])[0]
