"""Triangle mesh files: read any mesh Open3D reads (metres), write PLY/OBJ atomically."""

from __future__ import annotations

import contextlib
import os
import sys
from pathlib import Path
from typing import Iterator

import numpy as np

from wbsa.core.mesh import TriangleMesh
from wbsa.core.ply import check_ply
from wbsa.errors import WbsaError
from wbsa.atomic import atomic_path

#: File types :func:`write_mesh` writes.
WRITE_SUFFIXES = (".ply", ".obj")
#: File types Open3D reads as triangle meshes.
READ_SUFFIXES = (".ply", ".obj", ".stl", ".off", ".gltf", ".glb")


@contextlib.contextmanager
def quiet_stderr() -> Iterator[None]:
    """Silence C-level messages on file descriptor 2 (Open3D's file readers print their own errors)."""
    fd = 2
    try:
        sys.stderr.flush()
        saved = os.dup(fd)
    except (OSError, ValueError):  # no file descriptor 2
        yield
        return
    try:
        with open(os.devnull, "wb") as devnull:
            os.dup2(devnull.fileno(), fd)
            yield
    finally:
        os.dup2(saved, fd)
        os.close(saved)


def read_mesh(path: str | os.PathLike) -> TriangleMesh:
    """Read a triangle mesh file with Open3D (vertices as stored, whatever their units; a person's mesh is
    checked for its size by :func:`wbsa.simulate.target.check_person_size`).

    Parameters
    ----------
    path : str or path
        A mesh file of :data:`READ_SUFFIXES`.

    Raises
    ------
    WbsaError
        If the file is missing, of an unknown type, unreadable, empty, or has no triangles.
    """
    path = Path(path)
    if not path.exists():
        raise WbsaError(f"mesh file {path} does not exist; check the path")
    if path.is_dir():
        raise WbsaError(f"mesh path {path} is a folder; give a {'/'.join(s[1:] for s in READ_SUFFIXES)} file")
    if path.suffix.lower() not in READ_SUFFIXES:
        raise WbsaError(f"cannot read {path.name}: use a mesh file ending in {', '.join(READ_SUFFIXES)}")
    import open3d as o3d

    with quiet_stderr(), o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
        mesh = o3d.io.read_triangle_mesh(str(path), enable_post_processing=False)
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.triangles, dtype=np.int64)
    if vertices.shape[0] == 0:
        raise WbsaError(f"{path} is empty or not a readable {path.suffix[1:].upper()} mesh; check the file")
    if faces.shape[0] == 0:
        raise WbsaError(f"{path} has {vertices.shape[0]} vertices but no triangles (a point cloud?); "
                        f"give a triangle mesh")
    return TriangleMesh(vertices, faces.astype(np.int32))


def write_mesh(mesh: TriangleMesh, path: str | os.PathLike) -> Path:
    """Write ``mesh`` atomically as PLY or OBJ (by suffix), in metres.

    The file is checked before it is renamed into place: a PLY must have exactly the size its header
    announces and the mesh's vertex and face counts, an OBJ the right number of ``v`` and ``f`` lines
    (Open3D reports success after a failed write, e.g. on a full disk).

    Parameters
    ----------
    mesh : TriangleMesh
    path : str or path
        A ``.ply`` or ``.obj`` name.

    Raises
    ------
    WbsaError
        Unknown suffix, or the file cannot be written completely (one line naming the path and the fix).
    """
    import open3d as o3d

    path = Path(path)
    if path.suffix.lower() not in WRITE_SUFFIXES:
        raise WbsaError(f"cannot write a mesh as {path.suffix or 'no suffix'}; use a .ply or .obj name")
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int32)
    m = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(vertices), o3d.utility.Vector3iVector(faces))
    n_v, n_f = len(vertices), len(faces)
    if path.suffix.lower() == ".ply":
        def verify(tmp: Path) -> None:
            check_ply(tmp, n_v, n_f)
    else:
        def verify(tmp: Path) -> None:
            _check_obj(tmp, n_v, n_f)
    with atomic_path(path, keep_suffix=True, verify=verify) as tmp:  # open3d picks the format from the suffix
        with quiet_stderr():
            ok = o3d.io.write_triangle_mesh(str(tmp), m, write_ascii=False, write_vertex_normals=False,
                                            write_vertex_colors=False)
        for extra in tmp.parent.glob(tmp.stem + "*.mtl"):
            extra.unlink()
        if not ok:
            raise WbsaError(f"open3d could not write {path}; check the disk and the folder")
    return path


def _check_obj(path: Path, n_vertices: int, n_faces: int) -> None:
    """Count the ``v`` and ``f`` lines of an OBJ file."""
    n_v = n_f = 0
    with open(path, "rb") as fh:
        for line in fh:
            if line.startswith(b"v "):
                n_v += 1
            elif line.startswith(b"f "):
                n_f += 1
    if (n_v, n_f) != (n_vertices, n_faces):
        raise WbsaError(f"it holds {n_v} vertices and {n_f} faces, not {n_vertices} and {n_faces}")
