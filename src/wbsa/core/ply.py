"""PLY files checked without Open3D: a header parser and an exact size check of binary PLY files.

Open3D's PLY writer reports success after a failed write (a full disk), and its reader returns the
element counts of the header even when the body is cut short, so neither can tell a complete file
from a truncated one. :func:`check_ply` reads the header and checks that the file holds exactly the
bytes the header announces, and the counts the writer meant to write.
"""

from __future__ import annotations

import os
from pathlib import Path

from wbsa.errors import WbsaError

_SIZES = {"char": 1, "uchar": 1, "int8": 1, "uint8": 1, "short": 2, "ushort": 2, "int16": 2, "uint16": 2,
          "int": 4, "uint": 4, "int32": 4, "uint32": 4, "float": 4, "float32": 4, "double": 8, "float64": 8}
_MAX_HEADER = 1 << 16


def read_ply_header(path: str | os.PathLike) -> tuple[str, list[tuple[str, int, list[tuple]]], int]:
    """The format, the elements and the header length of a PLY file.

    Parameters
    ----------
    path : str or path

    Returns
    -------
    format : str
        ``ascii``, ``binary_little_endian`` or ``binary_big_endian``.
    elements : list of (name, count, properties)
        Each property is ``('scalar', type)`` or ``('list', count_type, item_type)``.
    header_bytes : int
        Length of the header including ``end_header\\n``.

    Raises
    ------
    WbsaError
        Not a PLY file, or a malformed header.
    """
    with open(path, "rb") as fh:
        head = fh.read(_MAX_HEADER)
    end = head.find(b"end_header\n")
    if not head.startswith(b"ply\n") or end < 0:
        raise WbsaError("it has no complete PLY header")
    fmt = ""
    elements: list[tuple[str, int, list[tuple]]] = []
    for line in head[:end].decode("ascii", "replace").splitlines()[1:]:
        words = line.split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "format":
            fmt = words[1]
        elif words[0] == "element":
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property" and elements:
            if words[1] == "list":
                elements[-1][2].append(("list", words[2], words[3]))
            else:
                elements[-1][2].append(("scalar", words[1]))
    return fmt, elements, end + len(b"end_header\n")


def check_ply(path: str | os.PathLike, n_vertices: int, n_faces: int = 0, face_size: int = 3) -> None:
    """Check that a binary PLY file is complete and holds ``n_vertices`` vertices and ``n_faces`` faces.

    Parameters
    ----------
    path : path-like
    n_vertices, n_faces : int
        What the writer was given.
    face_size : int
        Vertices per face (list length) for the size check.

    Raises
    ------
    WbsaError
        If the counts differ or the file is shorter or longer than its header announces.
    """
    path = Path(path)
    fmt, elements, header = read_ply_header(path)
    counts = {name: count for name, count, _ in elements}
    if counts.get("vertex", 0) != n_vertices or counts.get("face", 0) != n_faces:
        raise WbsaError(f"it holds {counts.get('vertex', 0)} vertices and {counts.get('face', 0)} faces, "
                        f"not {n_vertices} and {n_faces}")
    if fmt == "ascii":
        return
    size = header
    for _name, count, props in elements:
        per = 0
        for p in props:
            per += _SIZES[p[1]] if p[0] == "scalar" else _SIZES[p[1]] + face_size * _SIZES[p[2]]
        size += count * per
    actual = path.stat().st_size
    if actual != size:
        raise WbsaError(f"it has {actual} bytes where its header announces {size}")


def empty_point_cloud_ply() -> bytes:
    """A valid binary PLY with no points (Open3D refuses to write one)."""
    return (b"ply\nformat binary_little_endian 1.0\ncomment no point of the body is visible\n"
            b"element vertex 0\nproperty double x\nproperty double y\nproperty double z\n"
            b"property double nx\nproperty double ny\nproperty double nz\nend_header\n")
