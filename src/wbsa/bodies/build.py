"""One entry point for every population kind (the API behind ``wbsa population``)."""

from __future__ import annotations

from typing import Literal

import pandas as pd

from wbsa.errors import WbsaError
from wbsa.bodies.anthropometry import DEFAULT_DENSITY_KG_M3
from wbsa.bodies.composition import CompositionSettings, DensityModel

PopulationKind = Literal["random", "survey", "table"]
Sampling = Literal["paper", "varied"]


def build_population(kind: PopulationKind, n: int | None = None, seed: int = 0, *,
                     density_kg_m3: float = DEFAULT_DENSITY_KG_M3, density_model: DensityModel = "constant",
                     sampling: Sampling = "paper", params_path: str | None = None,
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
    density_kg_m3, density_model
        Body density: ``constant`` (every body ``density_kg_m3``, anny's 980 kg/m³ by default: the
        paper's tables) or a composition model (``deurenberg-siri``, ``deurenberg-brozek``: each
        body's density from its fat fraction, see :mod:`wbsa.bodies.composition`; residuals seeded
        with ``seed``).
    sampling
        (random) ``paper``: the paper's uniform macro parameters, no local change; ``varied``:
        local changes, anny's whole range and a high-adiposity half
        (:meth:`~wbsa.bodies.random_population.RandomPopulationSettings.varied`).
    workers, scheduler
        Parallel body building (see :mod:`wbsa.parallel`); the table does not depend on them.
    """
    from wbsa.bodies.table import measure_population

    composition = CompositionSettings(model=density_model, density_kg_m3=density_kg_m3, seed=seed)

    if kind == "random":
        from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters

        if n is None:
            raise WbsaError("--kind random needs --n, the number of subjects")
        if sampling not in ("paper", "varied"):
            raise WbsaError(f"sampling {sampling!r} is unknown; use paper or varied")
        settings = (RandomPopulationSettings.varied(n=n, seed=seed) if sampling == "varied"
                    else RandomPopulationSettings(n=n, seed=seed))
        params = sample_random_parameters(settings)
        return measure_population(params, composition=composition, show_progress=show_progress,
                                  workers=workers, scheduler=scheduler)
    if kind == "table":
        return measure_population(_read_params(params_path), composition=composition,
                                  show_progress=show_progress, workers=workers, scheduler=scheduler)
    if kind == "survey":
        try:
            from wbsa.bodies.survey import build_survey_population
        except ModuleNotFoundError:
            raise WbsaError("the survey population is not available in this build") from None
        if n is None:
            raise WbsaError("--kind survey needs --n, the number of survey people")
        return build_survey_population(n=n, variations=variations, seed=seed, composition=composition,
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
