"""What the camera looks at: a mesh file (PLY, OBJ, STL, OFF, glTF) in metres, in the body model's frame."""

from __future__ import annotations

from wbsa.errors import WbsaError
from wbsa.core.mesh import TriangleMesh
from wbsa.core.mesh_io import read_mesh


def load_target(args) -> TriangleMesh:
    """The mesh a ``wbsa view`` command looks at (the hook for other sources, e.g. a population subject).

    Parameters
    ----------
    args : argparse.Namespace
        With ``mesh``: path of a mesh file in metres, +Z up, the subject facing −Y; or with
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
    return read_mesh(args.mesh)
