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
UNIT_M = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}
#: Names of the units in messages.
UNIT_NAMES = {"m": "metres", "cm": "centimetres", "mm": "millimetres", "in": "inches"}
#: The longest extent (m) a mesh of a person can have: an infant's length to the tallest adult with arms raised.
PERSON_EXTENT_M = (0.4, 2.8)
#: The stature (m) units are guessed towards: the unit that makes the mesh nearest to it (in ratio) is named.
_TYPICAL_EXTENT_M = 1.7


def guess_units(extent: float) -> str | None:
    """The units in which a mesh whose longest extent is ``extent`` (file units) is a person's size.

    Parameters
    ----------
    extent : float
        The longest side of the mesh's bounding box, in the file's units.

    Returns
    -------
    str or None
        A key of :data:`UNIT_M` (of those that make the mesh 0.4–2.8 m long, the one nearest 1.7 m in ratio),
        or None if no unit does.

    Examples
    --------
    >>> guess_units(1725.0), guess_units(172.5), guess_units(67.0), guess_units(1.7), guess_units(1e6)
    ('mm', 'cm', 'in', 'm', None)
    """
    lo, hi = PERSON_EXTENT_M
    fits = [u for u, m in UNIT_M.items() if np.isfinite(extent) and lo <= extent * m <= hi]
    if not fits:
        return None
    return min(fits, key=lambda u: abs(np.log(extent * UNIT_M[u] / _TYPICAL_EXTENT_M)))


def check_person_size(mesh: TriangleMesh, units: str = "m", *, cli: bool = False) -> None:
    """Refuse a mesh (already in metres) whose size is implausible for a person: it is in other units.

    Parameters
    ----------
    mesh : TriangleMesh
        Vertices (n, 3) in metres, after :func:`to_body_frame` with the stated ``units``.
    units : {'m', 'cm', 'mm', 'in'}
        The units the file was read in (named in the message).
    cli : bool
        Name the fix as the ``--units`` flag of ``wbsa view`` (True) or as a scale factor (False).

    Raises
    ------
    WbsaError
        If the bounding box's longest side is outside :data:`PERSON_EXTENT_M`, or a vertex is not finite; the
        message names the units guessed from the extent (:func:`guess_units`) and how to give them.
    """
    v = np.asarray(mesh.vertices, dtype=np.float64)
    if not np.all(np.isfinite(v)):
        raise WbsaError("the mesh has vertices that are not finite numbers (NaN or infinite); repair the file")
    longest_m = float((v.max(axis=0) - v.min(axis=0)).max())
    lo, hi = PERSON_EXTENT_M
    if lo <= longest_m <= hi:
        return
    extent = longest_m / UNIT_M[units]
    guess = guess_units(extent)
    size = f"the mesh is {longest_m:.4g} m across read in {UNIT_NAMES[units]}, not a person's {lo:g}–{hi:g} m"
    if guess is None:
        raise WbsaError(f"{size}, in any of {', '.join(UNIT_NAMES.values())}; give a mesh of one person")
    if cli:
        fix = f"give --units {guess}"
    else:
        fix = f"scale its vertices by {UNIT_M[guess] / UNIT_M[units]:g}"
    raise WbsaError(f"{size}; it looks like {UNIT_NAMES[guess]} ({extent * UNIT_M[guess]:.2f} m): {fix}")


def to_body_frame(mesh: TriangleMesh, units: MeshUnits = "m", up: MeshUp = "z") -> TriangleMesh:
    """``mesh`` in metres with +Z up.

    Parameters
    ----------
    mesh : TriangleMesh
        Vertices (n, 3) in ``units``.
    units : {'m', 'cm', 'mm', 'in'}
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

    Raises
    ------
    WbsaError
        If the mesh is not a person's size in the stated units (:func:`check_person_size`).
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
    mesh = to_body_frame(read_mesh(args.mesh), units, up)
    check_person_size(mesh, units, cli=True)
    warning = lying_warning(mesh, up)
    if warning:
        sys.stderr.write(f"warning: {warning}\n")
    return mesh
