"""The paper's "Virtual Random" population: macro parameters drawn uniformly in restricted intervals."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import pandas as pd

from wbsa.errors import WbsaError
from wbsa.bodies.age import param_to_years, years_to_param


@dataclass(frozen=True)
class RandomPopulationSettings:
    """Uniform sampling intervals of the random population (paper section 2.2.2).

    Every interval is ``(low, high)`` in anny's normalised [0, 1] units, except ages in years.
    Sex is discrete (male/female with equal probability) and the ethnic mix
    (african, asian, caucasian) is uniform on the simplex (Dirichlet(1, 1, 1)).

    Ages are drawn like every other macro parameter, uniformly in anny's normalised ``age``
    parameter between the values of ``age_years`` (``age_sampling="parameter"``, as the paper drew
    MakeHuman's sliders); this gives about 40 % children (≤ 15 y) for 12–70 y, so the paper's kid
    groups can be fitted. ``age_sampling="years"`` draws uniformly in years instead (5 % children).

    The defaults follow the paper: ages 12–70, and weight, muscle and height over most
    of their range but without the last 5 % at either end, where anny produces non-human
    extremes (adult BMI beyond ~45 or below ~13). Proportions, cup size and firmness vary
    over the middle half of their range.
    """

    n: int
    seed: int = 0
    age_years: tuple[float, float] = (12.0, 70.0)
    age_sampling: Literal["parameter", "years"] = "parameter"
    weight: tuple[float, float] = (0.05, 0.95)
    muscle: tuple[float, float] = (0.05, 0.95)
    height: tuple[float, float] = (0.05, 0.95)
    proportions: tuple[float, float] = (0.25, 0.75)
    cupsize: tuple[float, float] = (0.25, 0.75)
    firmness: tuple[float, float] = (0.25, 0.75)

    def __post_init__(self) -> None:
        if not isinstance(self.n, (int, np.integer)) or self.n <= 0:
            raise WbsaError(f"population size n = {self.n} must be a positive integer; use --n 100, say")
        if self.age_sampling not in ("parameter", "years"):
            raise WbsaError(f"age_sampling {self.age_sampling!r} is unknown; use parameter or years")
        lo, hi = self.age_years
        if not 0 <= lo <= hi <= 110:
            raise WbsaError(f"age range {lo}–{hi} years is invalid; anny covers 0–110 years")
        for name in ("weight", "muscle", "height", "proportions", "cupsize", "firmness"):
            lo, hi = getattr(self, name)
            if not 0.0 <= lo <= hi <= 1.0:
                raise WbsaError(f"{name} range ({lo}, {hi}) must lie within [0, 1] with low ≤ high")


def sample_random_parameters(settings: RandomPopulationSettings) -> pd.DataFrame:
    """Draw the phenotype parameters of every subject.

    Subject ``i`` is drawn from its own stream ``SeedSequence([seed, i])``, so the same seed
    gives the same subject ``i`` whatever the population size or the worker count.

    Returns
    -------
    pandas.DataFrame
        ``subject_id``, ``sex``, ``age_years`` and the ``p_*`` phenotype columns, ``n`` rows.
    """
    s = settings
    rows = np.empty((s.n, 11))
    for i in range(s.n):
        rng = np.random.default_rng(np.random.SeedSequence([s.seed, i]))
        u = rng.random(8)
        mix = rng.dirichlet((1.0, 1.0, 1.0))
        rows[i, :8] = u
        rows[i, 8:] = mix

    def scale(u: np.ndarray, interval: tuple[float, float]) -> np.ndarray:
        return interval[0] + u * (interval[1] - interval[0])

    female = rows[:, 0] < 0.5
    if s.age_sampling == "years":
        age_years = scale(rows[:, 1], s.age_years)
        p_age = years_to_param(age_years)
    else:
        p_age = scale(rows[:, 1], tuple(years_to_param(np.array(s.age_years))))
        age_years = param_to_years(p_age)
    return pd.DataFrame({
        "subject_id": np.arange(s.n, dtype=np.int64),
        "sex": np.where(female, "female", "male"),
        "age_years": age_years,
        "p_gender": female.astype(np.float64),
        "p_age": p_age,
        "p_muscle": scale(rows[:, 2], s.muscle),
        "p_weight": scale(rows[:, 3], s.weight),
        "p_height": scale(rows[:, 4], s.height),
        "p_proportions": scale(rows[:, 5], s.proportions),
        "p_cupsize": scale(rows[:, 6], s.cupsize),
        "p_firmness": scale(rows[:, 7], s.firmness),
        "p_african": rows[:, 8],
        "p_asian": rows[:, 9],
        "p_caucasian": rows[:, 10],
    })
