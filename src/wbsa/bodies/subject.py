"""One subject's skin mesh rebuilt from its row of a population table."""

from __future__ import annotations

from wbsa.errors import WbsaError
from wbsa.core.mesh import TriangleMesh


def subject_mesh(population, subject_id: int, model=None) -> TriangleMesh:
    """The skin mesh of one subject of a population table.

    Parameters
    ----------
    population : pandas.DataFrame
        A table with ``subject_id`` and the ``p_*`` columns.
    subject_id
        The subject to rebuild.
    """
    from wbsa.bodies.body_model import BodyModel

    rows = population[population["subject_id"] == subject_id]
    if rows.empty:
        ids = population["subject_id"]
        raise WbsaError(f"subject {subject_id} is not in the population (ids {ids.min()}–{ids.max()})")
    return (model or BodyModel()).skin_meshes(rows.iloc[:1])[0]
