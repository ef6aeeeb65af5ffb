"""Settings of a virtual population (``[population]`` of a study, the flags of ``wbsa population``)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from wbsa.errors import check_field
from wbsa.typing import DensityModel, PopulationKind, PostureChoice, Sampling, SurveyMeasures
from wbsa.settings_io import check_types

#: Default body density (kg/m³), as anny's own ``Anthropometry``.
DEFAULT_DENSITY_KG_M3 = 980.0


@dataclass(frozen=True)
class PopulationSettings:
    """Which population :func:`wbsa.bodies.build.build_population` builds.

    The fields are the keyword arguments of :func:`~wbsa.bodies.build.build_population`, so
    ``build_population(**dataclasses.asdict(settings))`` builds it.

    Attributes
    ----------
    kind : {'random', 'survey', 'table'}
        ``random`` is the paper's Virtual Random, ``survey`` its Virtual NHANES (bodies matched to
        survey people); ``table`` reads the phenotypes from ``params_path``.
    n : int or None
        Subjects (random) or survey people (survey), >= 1; needed by those kinds, unused by ``table``.
    seed : int
        Seed of the parameter draw, >= 0.
    density_kg_m3 : float
        Body density for mass = volume × density with ``density_model = "constant"`` (500–2000 kg/m³;
        anny's default 980).
    density_model : {'constant', 'deurenberg-siri', 'deurenberg-brozek'}
        ``constant`` (the paper's tables) or each body's density from its fat fraction
        (:mod:`wbsa.bodies.composition`).
    sampling : {'paper', 'varied'}
        (random) ``paper``: the paper's uniform macro parameters; ``varied``: local changes, anny's whole
        range, an obese half of the adults, ages 7–80 (``docs/population.md``).
    variations : int
        (survey) weight/muscle variations per person, >= 0.
    survey_weights : bool
        (survey) select people by their exam weights.
    survey_measures : {'seven', 'four'}
        (survey) match all seven NHANES measures (stature, mass, waist, hip, arm circumference, upper
        arm and upper leg length) or the first four.
    params_path : str or None
        (table) Parquet/CSV file with ``p_gender, p_age, ...`` columns in [0, 1].
    posture : {'a-pose', 'mixed', 'arms-down', 'arms-wide', 'hands-on-hips', 'elbows-bent', 'feet-together', 'feet-apart'}
        ``a-pose`` (the paper: every body at rest, no posture columns), ``mixed`` (a random posture per
        subject) or one posture name; drawn with random joint jitter (:mod:`wbsa.bodies.posture`).
    """

    kind: PopulationKind = "random"
    n: int | None = None
    seed: int = 0
    density_kg_m3: float = DEFAULT_DENSITY_KG_M3
    density_model: DensityModel = "constant"
    sampling: Sampling = "paper"
    variations: int = 0
    survey_weights: bool = False
    survey_measures: SurveyMeasures = "seven"
    params_path: str | None = None
    posture: PostureChoice = "a-pose"

    def __post_init__(self) -> None:
        check_types(self)
        if self.kind in ("random", "survey"):
            what = "subjects" if self.kind == "random" else "survey people"
            check_field(self.n is not None, "n", f"must be given for kind {self.kind!r}: the number of {what}, e.g. 300")
        if self.n is not None:
            check_field(self.n >= 1, "n", f"must be at least 1, got {self.n}")
        check_field(self.seed >= 0, "seed", f"must be 0 or more, got {self.seed}")
        check_field(math.isfinite(self.density_kg_m3) and 500 <= self.density_kg_m3 <= 2000, "density_kg_m3",
                    f"must be a body density in 500–2000 kg/m³, got {self.density_kg_m3:g}")
        check_field(self.variations >= 0, "variations", f"must be 0 or more, got {self.variations}")
        if self.kind == "table":
            check_field(bool(self.params_path), "params_path",
                        "must name a phenotype table (p_gender, p_age, ... columns) for kind 'table'")
