"""One entry point for every population kind (the API behind ``wbsa population``)."""

from __future__ import annotations

import pandas as pd

from wbsa.errors import WbsaError
from wbsa.bodies.anthropometry import DEFAULT_DENSITY_KG_M3
from wbsa.bodies.composition import CompositionSettings
from wbsa.bodies.settings import PopulationSettings
from wbsa.typing import DensityModel, PopulationKind, PostureChoice, Sampling, SurveyMeasures


def build_population(kind: PopulationKind, n: int | None = None, seed: int = 0, *,
                     density_kg_m3: float = DEFAULT_DENSITY_KG_M3, density_model: DensityModel = "constant",
                     sampling: Sampling = "paper", params_path: str | None = None,
                     variations: int = 0, survey_weights: bool = False, survey_measures: SurveyMeasures = "seven",
                     posture: PostureChoice = "a-pose",
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
    density_kg_m3, density_model
        Body density: ``constant`` (every body ``density_kg_m3``, anny's 980 kg/m³ by default: the
        paper's tables) or a composition model (``deurenberg-siri``, ``deurenberg-brozek``: each
        body's density from its fat fraction, see :mod:`wbsa.bodies.composition`; residuals seeded
        with ``seed``).
    sampling
        (random) ``paper``: the paper's uniform macro parameters, no local change; ``varied``:
        local changes, anny's whole range and a high-adiposity half
        (:meth:`~wbsa.bodies.random_population.RandomPopulationSettings.varied`).
    survey_measures
        (survey) ``seven`` NHANES measures matched (default) or the first ``four``.
    posture
        ``a-pose`` (every body at rest, no posture columns: the paper), ``mixed`` (a random named
        posture per subject) or one name of :data:`wbsa.bodies.posture.POSTURES`; drawn with ``seed``
        (see :func:`wbsa.bodies.posture_table.add_postures`).
    workers, scheduler
        Parallel body building (see :mod:`wbsa.parallel`); the table does not depend on them.
        ``workers`` 0 (or None) means all cores.

    Raises
    ------
    WbsaError
        A negative seed, a density that is not a finite body density (500–2000 kg/m³), a negative
        worker count, or the kind's own errors.
    """
    from wbsa.bodies.posture import PostureSettings
    from wbsa.bodies.posture_table import add_postures

    from wbsa.parallel import resolve_workers

    PopulationSettings(kind=kind, n=n, seed=seed, density_kg_m3=density_kg_m3, density_model=density_model,
                       sampling=sampling, variations=variations, survey_weights=survey_weights,
                       survey_measures=survey_measures, params_path=params_path,
                       posture=posture)  # checks every argument first
    workers = resolve_workers(workers)
    postures = PostureSettings(posture, seed)
    table = _build_table(kind, n, seed, density_kg_m3=density_kg_m3, density_model=density_model,
                         sampling=sampling, params_path=params_path, variations=variations,
                         survey_weights=survey_weights, survey_measures=survey_measures, posture=posture,
                         show_progress=show_progress, workers=workers, scheduler=scheduler)
    return add_postures(table, postures, show_progress=show_progress, workers=workers, scheduler=scheduler)


def _build_table(kind: PopulationKind, n: int | None, seed: int, *, density_kg_m3: float,
                 density_model: DensityModel, sampling: Sampling, params_path: str | None, variations: int,
                 survey_weights: bool, survey_measures: SurveyMeasures, posture: PostureChoice,
                 show_progress: bool | None, workers: int,
                 scheduler: str | None) -> pd.DataFrame:
    """The population table of ``kind`` in the rest pose (see :func:`build_population`)."""
    from wbsa.bodies.table import measure_population
    composition = CompositionSettings(model=density_model, density_kg_m3=density_kg_m3, seed=seed)
    if kind == "random":
        from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters

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
            from wbsa.bodies.survey import SurveyPopulationSettings, build_survey_population
            from wbsa.bodies.survey_match import MatchSettings
        except ModuleNotFoundError:
            raise WbsaError("the survey population is not available in this build") from None
        settings = SurveyPopulationSettings(match=MatchSettings(measures=survey_measures))
        return build_survey_population(n=n, variations=variations, seed=seed, composition=composition,
                                       survey_weights=survey_weights, show_progress=show_progress, settings=settings)
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
