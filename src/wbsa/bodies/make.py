"""The two calls a notebook starts with: :func:`population` (a table of virtual people) and :func:`body` (a mesh)."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

from wbsa.errors import WbsaError

if TYPE_CHECKING:  # pragma: no cover - for type hints only
    import pandas as pd

    from wbsa.bodies.build import PopulationKind
    from wbsa.core.mesh import TriangleMesh


def population(n: int, kind: PopulationKind = "random", seed: int = 0, *, show_progress: bool = False,
               **options: Any) -> pd.DataFrame:
    """A virtual population and its anthropometric table (what ``wbsa population`` writes).

    Parameters
    ----------
    n : int
        Subjects (``random``) or survey people (``survey``).
    kind : {'random', 'survey'}
        ``random``: the paper's Virtual Random; ``survey``: bodies matched to NHANES people.
    seed : int
        The same seed gives the same table.
    show_progress : bool
        A progress bar on stderr.
    **options
        Further options of :func:`wbsa.bodies.build.build_population` (``density_kg_m3``, ``variations``,
        ``workers``, ...).

    Returns
    -------
    pandas.DataFrame
        One row per subject: ``subject_id``, ``sex``, ``age_years``, ``stature_m``, ``mass_kg``, ``bmi``,
        ``wbsa_m2``, tape measures (``*_circ_m``) and the body parameters (``p_*``, ``l_*``).

    Examples
    --------
    >>> import wbsa
    >>> people = wbsa.population(n=2, seed=1)
    >>> list(people[["subject_id", "sex"]].itertuples(index=False, name=None))
    [(0, 'male'), (1, 'female')]
    >>> bool(((people["wbsa_m2"] > 0.5) & (people["wbsa_m2"] < 3.0)).all())
    True
    """
    from wbsa.bodies.build import build_population

    return build_population(kind, n=n, seed=seed, show_progress=show_progress, **options)


def body(people: pd.DataFrame | str | os.PathLike | None = None, subject_id: int = 0, **phenotypes: float
         ) -> TriangleMesh:
    """One virtual body's skin mesh (metres, standing on z = 0, facing −Y).

    Parameters
    ----------
    people : DataFrame or path, optional
        A population table (from :func:`population` or a file ``wbsa population`` wrote); the body of
        ``subject_id`` is rebuilt from its parameters.
    subject_id : int
        The subject of ``people``.
    **phenotypes : float
        Without ``people``: anny's phenotype parameters in [0, 1] (``gender`` 0 = male … 1 = female, ``age``,
        ``muscle``, ``weight``, ``height``, ``proportions``, ``african``, ``asian``, ``caucasian``, ...), the
        ``p_`` prefix optional; unset ones take 0.5 (the ethnic mix 1/3 each).

    Returns
    -------
    TriangleMesh

    Examples
    --------
    >>> import wbsa
    >>> wbsa.body(gender=0.0, height=0.7)
    TriangleMesh(13,718 vertices, 24,236 faces, area ... m², bbox ... m)
    """
    from wbsa.bodies.subject import subject_mesh

    if people is not None:
        if phenotypes:
            raise WbsaError("give either a population table or phenotype values, not both")
        if not hasattr(people, "columns"):
            if not (isinstance(people, str) or hasattr(people, "__fspath__")):
                raise WbsaError(f"people must be a population table (DataFrame) or its file path, "
                                f"got {type(people).__name__}")
            from wbsa.bodies.table import read_population

            people = read_population(people)
        return subject_mesh(people, subject_id)
    return subject_mesh(phenotype_table(**phenotypes), 0)


def phenotype_table(**phenotypes: float) -> pd.DataFrame:
    """A one-row population table of anny phenotype values (``p_`` prefix optional; others 0.5, ethnic mix 1/3)."""
    import pandas as pd

    from wbsa.bodies.body_model import BODY_PARAMETER_COLUMNS, LOCAL_CHANGE_COLUMNS, PHENOTYPE_COLUMNS

    row: dict[str, float] = {c: 0.5 for c in PHENOTYPE_COLUMNS}
    row.update({"p_african": 1 / 3, "p_asian": 1 / 3, "p_caucasian": 1 / 3})
    row.update({c: 0.0 for c in LOCAL_CHANGE_COLUMNS})
    for name, value in phenotypes.items():
        column = name if name in BODY_PARAMETER_COLUMNS else f"p_{name}"
        if column not in BODY_PARAMETER_COLUMNS:
            valid = ", ".join(c[2:] for c in PHENOTYPE_COLUMNS)
            raise WbsaError(f"unknown body parameter {name!r}; use one of {valid} (or an l_* local change)")
        row[column] = float(value)
    return pd.DataFrame([{"subject_id": 0, **row}])
