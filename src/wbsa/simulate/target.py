"""What the camera looks at: a mesh file (PLY, OBJ, STL, OFF, glTF), brought to the body model's frame.

The body model's frame is metres, +Z up, the subject facing −Y. 3-D body scans often come in millimetres
and with +Y up (glTF's convention, and many scanners', the subject facing +Z): ``--units`` and ``--up``
bring them over.
"""

from __future__ import annotations

import sys

import numpy as np

from wbsa.errors import WbsaError
from wbsa.core.mesh import TriangleMesh
from wbsa.core.mesh_io import read_mesh
from wbsa.typing import MESH_UNITS, MESH_UPS, MeshUnits, MeshUp

#: Metres per unit of a mesh file.
UNIT_M = {"m": 1.0, "cm": 0.01, "mm": 0.001}


def to_body_frame(mesh: TriangleMesh, units: MeshUnits = "m", up: MeshUp = "z") -> TriangleMesh:
    """``mesh`` in metres with +Z up.

    Parameters
    ----------
    mesh : TriangleMesh
        Vertices (n, 3) in ``units``.
    units : {'m', 'cm', 'mm'}
    up : {'z', 'y'}
        The mesh's up axis. ``y``: (x, y, z) becomes (x, −z, y), so a subject facing +Z (glTF) faces −Y.

    Returns
    -------
    TriangleMesh
    """
    if units not in MESH_UNITS or up not in MESH_UPS:
        raise WbsaError(f"units {units!r} / up {up!r}: use units {', '.join(MESH_UNITS)} and up {' or '.join(MESH_UPS)}")
    v = np.asarray(mesh.vertices, dtype=np.float64) * UNIT_M[units]
    if up == "y":
        v = np.column_stack([v[:, 0], -v[:, 2], v[:, 1]])  # a proper rotation (+90° about x): faces keep their side
    return TriangleMesh(v, mesh.faces)


def lying_warning(mesh: TriangleMesh, up: MeshUp = "z") -> str | None:
    """A warning when a body-sized mesh is much longer across than it is tall (read with the wrong ``up``)."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    extent = v.max(axis=0) - v.min(axis=0)
    longest = float(extent.max())
    if 0.5 <= longest <= 2.6 and extent[2] < 0.5 * longest:
        axis = "xy"[int(np.argmax(extent[:2]))]
        hint = ("if the file is y-up (glTF, many scanners), give --up y" if up == "z"
                else "the file may be z-up after all: leave out --up y")
        return (f"the mesh is {extent[2]:.2f} m tall and {longest:.2f} m long along {axis}: a standing body is "
                f"tallest along z; {hint}")
    return None


def load_target(args) -> TriangleMesh:
    """The mesh a ``wbsa view`` command looks at (the hook for other sources, e.g. a population subject).

    Parameters
    ----------
    args : argparse.Namespace
        With ``mesh``: path of a mesh file (``units``, ``up``: :func:`to_body_frame`); or with
        ``population`` and ``subject``: that subject's skin mesh rebuilt from its phenotypes.
    """
    population = getattr(args, "population", None)
    if population:
        if getattr(args, "mesh", None):
            raise WbsaError("give either a MESH file or --population, not both")
        from wbsa.bodies.subject import subject_mesh
        from wbsa.bodies.table import read_population

        return subject_mesh(read_population(population), int(args.subject))
    if getattr(args, "mesh", None) is None:
        raise WbsaError("give a mesh file to look at (wbsa view MESH) or --population FILE --subject ID")
    units, up = getattr(args, "units", "m"), getattr(args, "up", "z")
    mesh = to_body_frame(read_mesh(args.mesh, UNIT_M.get(units, 1.0)), units, up)
    warning = lying_warning(mesh, up)
    if warning:
        sys.stderr.write(f"warning: {warning}\n")
    return mesh
