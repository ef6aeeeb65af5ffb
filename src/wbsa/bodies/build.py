"""One entry point for every population kind (the API behind ``wbsa population``)."""

from __future__ import annotations

from typing import Literal

import pandas as pd

from wbsa.errors import WbsaError
from wbsa.bodies.anthropometry import DEFAULT_DENSITY_KG_M3

PopulationKind = Literal["random", "survey", "table"]


def build_population(kind: PopulationKind, n: int | None = None, seed: int = 0, *,
                     density_kg_m3: float = DEFAULT_DENSITY_KG_M3, params_path: str | None = None,
                     variations: int = 0, survey_weights: bool = False,
                     show_progress: bool | None = None, workers: int = 1,
                     scheduler: str | None = None) -> pd.DataFrame:
    """Build a population table.

    Parameters
    ----------
    kind
        ``random`` (uniform macro parameters, paper's Virtual Random), ``survey`` (bodies matched to
        NHANES people, paper's Virtual NHANES) or ``table`` (phenotypes read from ``params_path``).
    n
        Subjects (random) or survey people (survey).
    workers, scheduler
        Parallel body building (see :mod:`wbsa.parallel`); the table does not depend on them.
        ``workers`` 0 (or None) means all cores.

    Raises
    ------
    WbsaError
        A negative seed, a density that is not a finite body density (500–2000 kg/m³), a negative
        worker count, or the kind's own errors.
    """
    import math

    from wbsa.bodies.table import measure_population
    from wbsa.core.limits import check_seed
    from wbsa.parallel import resolve_workers

    check_seed(seed, "the population seed")
    if not (isinstance(density_kg_m3, (int, float)) and math.isfinite(density_kg_m3)
            and 500.0 <= density_kg_m3 <= 2000.0):
        raise WbsaError(f"body density must be a finite number in 500–2000 kg/m³, got {density_kg_m3!r}; "
                        "use e.g. 980 (anny's)")
    workers = resolve_workers(workers)

    if kind == "random":
        from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters

        if n is None:
            raise WbsaError("--kind random needs --n, the number of subjects")
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
        if n is None:
            raise WbsaError("--kind survey needs --n, the number of survey people")
        return build_survey_population(n=n, variations=variations, seed=seed, density_kg_m3=density_kg_m3,
                                       survey_weights=survey_weights, show_progress=show_progress)
    raise WbsaError(f"unknown population kind {kind!r}; use random, survey or table")


def _read_params(path: str | None) -> pd.DataFrame:
    """Read a user phenotype table and give it subject ids, sex and age in years."""
    import numpy as np

    from wbsa.io import read_table
    from wbsa.bodies.age import param_to_years

    if not path:
        raise WbsaError("--kind table needs --params FILE with p_gender, p_age, ... columns")
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
