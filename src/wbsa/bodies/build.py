"""One entry point for every population kind (the API behind ``wbsa population``)."""

from __future__ import annotations

import pandas as pd

from wbsa.errors import WbsaError
from wbsa.bodies.anthropometry import DEFAULT_DENSITY_KG_M3
from wbsa.bodies.settings import PopulationSettings
from wbsa.typing import PopulationKind


def build_population(kind: PopulationKind, n: int | None = None, seed: int = 0, *,
                     density_kg_m3: float = DEFAULT_DENSITY_KG_M3, params_path: str | None = None,
                     variations: int = 0, survey_weights: bool = False, posture: str = "a-pose",
                     show_progress: bool | None = None, workers: int = 1,
                     scheduler: str | None = None) -> pd.DataFrame:
    """Build a population table.

    The settings are checked as a :class:`~wbsa.bodies.settings.PopulationSettings` (same names), so
    ``build_population(**dataclasses.asdict(settings))`` builds the population of ``settings``.

    Parameters
    ----------
    kind
        ``random`` (uniform macro parameters, paper's Virtual Random), ``survey`` (bodies matched to
        NHANES people, paper's Virtual NHANES) or ``table`` (phenotypes read from ``params_path``).
    n
        Subjects (random) or survey people (survey).
    posture
        ``a-pose`` (every body at rest, no posture columns: the paper), ``mixed`` (a random named
        posture per subject) or one name of :data:`wbsa.bodies.posture.POSTURES`; drawn with ``seed``
        (see :func:`wbsa.bodies.posture_table.add_postures`).
    workers, scheduler
        Parallel body building (see :mod:`wbsa.parallel`); the table does not depend on them.
    """
    from wbsa.bodies.posture import PostureSettings
    from wbsa.bodies.posture_table import add_postures

    postures = PostureSettings(posture, seed)  # checked before any body is built
    table = _build_table(kind, n, seed, density_kg_m3=density_kg_m3, params_path=params_path,
                         variations=variations, survey_weights=survey_weights, show_progress=show_progress,
                         workers=workers, scheduler=scheduler)
    return add_postures(table, postures, show_progress=show_progress, workers=workers, scheduler=scheduler)


def _build_table(kind: PopulationKind, n: int | None, seed: int, *, density_kg_m3: float,
                 params_path: str | None, variations: int, survey_weights: bool,
                 show_progress: bool | None, workers: int, scheduler: str | None) -> pd.DataFrame:
    """The population table of ``kind`` in the rest pose (see :func:`build_population`)."""
    from wbsa.bodies.table import measure_population

    PopulationSettings(kind=kind, n=n, seed=seed, density_kg_m3=density_kg_m3, variations=variations,
                       survey_weights=survey_weights, params_path=params_path)  # checks every argument
    if kind == "random":
        from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters

        params = sample_random_parameters(RandomPopulationSettings(n=n, seed=seed))
        return measure_population(params, density_kg_m3=density_kg_m3, show_progress=show_progress,
                                  workers=workers, scheduler=scheduler)
    if kind == "table":
        return measure_population(_read_params(params_path), density_kg_m3=density_kg_m3,
                                  show_progress=show_progress, workers=workers, scheduler=scheduler)
    if kind == "survey":
        try:
            from wbsa.bodies.survey import build_survey_population
        except ModuleNotFoundError:
            raise WbsaError("the survey population is not available in this build") from None
        return build_survey_population(n=n, variations=variations, seed=seed, density_kg_m3=density_kg_m3,
                                       survey_weights=survey_weights, show_progress=show_progress)
    raise AssertionError(kind)  # pragma: no cover - PopulationSettings accepts only the kinds above


def _read_params(path: str | None) -> pd.DataFrame:
    """Read a user phenotype table and give it subject ids, sex and age in years."""
    import numpy as np

    from wbsa.io import read_table
    from wbsa.bodies.age import param_to_years

    required = ("p_gender", "p_age", "p_muscle", "p_weight", "p_height", "p_proportions",
                "p_african", "p_asian", "p_caucasian")
    df = read_table(path, required=required, what="phenotype table").copy()
    if df.empty:
        raise WbsaError(f"{path} has no rows; give at least one subject")
    if "subject_id" not in df.columns:
        df.insert(0, "subject_id", np.arange(len(df), dtype=np.int64))
    if "sex" not in df.columns:
        df.insert(1, "sex", np.where(df["p_gender"] >= 0.5, "female", "male"))
    if "age_years" not in df.columns:
        df.insert(2, "age_years", param_to_years(df["p_age"].clip(0, 1)))
    return df
