"""The random population: the paper's "Virtual Random" (uniform macro parameters) and a varied variant.

``shape="paper"`` (the default) draws the phenotypes uniformly in restricted intervals, as the paper's
sliders, with no local change. ``shape="varied"`` (:meth:`RandomPopulationSettings.varied`) also draws
the body model's local changes, and half of its subjects in the high-weight, low-muscle corner where
real people sit in anny's parameter space, so that bodies of the same stature and mass differ in where
their volume sits and the obese are numerous enough to be studied (see ``docs/population.md``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import pandas as pd

from wbsa.errors import WbsaError
from wbsa.bodies.age import param_to_years, years_to_param
from wbsa.bodies.body_model import LOCAL_CHANGE_COLUMNS
from wbsa.settings_io import check_types

Shape = Literal["paper", "varied"]
#: The fat depot each local change follows in the varied shape (abdominal or gluteal).
_LOCAL_CHANGE_FACTOR = {"l_waist_circ": "abdominal", "l_stomach_pregnant": "abdominal",
                        "l_hips_circ": "gluteal", "l_buttocks_volume": "gluteal"}


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

    ``shape="varied"`` changes two things (every other draw stays as above, from the same streams):

    * a fraction ``heavy_fraction`` of the adults (age > 15 y; chosen per subject) draws weight and
      muscle in ``heavy_weight`` × ``heavy_muscle`` instead of ``weight`` × ``muscle``;
    * every subject draws its four local changes (``l_*`` columns) from two shared factors, an
      abdominal one (waist, belly) and a gluteal one (hips, buttocks), each uniform in [−1, 1]:
      ``l = amplitude · (shared · factor + (1 − shared) · own)`` with the change's own uniform
      deviate; ``amplitude`` is ``local_change_amplitude`` for adults and
      ``child_local_change_amplitude`` for children (age ≤ 15 y).

    :meth:`varied` gives the documented values.
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
    shape: Shape = "paper"
    heavy_fraction: float = 0.5
    heavy_weight: tuple[float, float] = (0.75, 1.0)
    heavy_muscle: tuple[float, float] = (0.0, 0.25)
    local_change_amplitude: float = 1.0
    child_local_change_amplitude: float = 0.5
    local_change_shared: float = 2.0 / 3.0

    @classmethod
    def varied(cls, n: int, seed: int = 0) -> "RandomPopulationSettings":
        """The varied population (``docs/population.md``, "Varied shapes").

        * ages 7–80 y, uniform in anny's age parameter: 7 y is the youngest age of Deurenberg's
          body-fat sample (the composition models' calibration), 80 the survey's top code; about
          half are children (≤ 15 y), as with the paper's rule;
        * weight, muscle, height, proportions and cup size over anny's whole range [0, 1]: very
          short and very tall bodies, and the proportions and cup sizes the survey matcher gives real
          adults (their 5th–95th percentiles span 0–1);
        * half of the adults in the corner weight 0.75–1, muscle 0–0.25: where the survey matcher
          puts real adults with BMI ≥ 30 (5th–95th percentiles of the matched NHANES adults at
          their own density: weight 0.75–1 for men, 0.90–1 for women; muscle 0–0.21 and 0–0.08),
          so that obese bodies are common, as among real adults (38 % of the matched NHANES adults;
          the paper's uniform draw: 8 of the default study's 186 adults). Children are not: the matched NHANES children
          spread over the whole weight range;
        * local changes over [−1, 1] for adults, from two shared factors with weight 2/3: the local
          changes the matcher needs to reach real adults' waist and hip span almost the whole range
          (5th–95th percentiles about −0.7…0.8 waist, −1…1 hips, −1…0.7 belly, −1…0.5 buttocks), and
          correlate in two pairs, waist with belly (r = 0.70) and hips with buttocks (r = 0.77):
          abdominal and gluteal fat. Two equal uniform parts in the ratio 2 : 1 correlate at 0.8.
          The correlation across the pairs (0.2–0.5 in the matches) is left at 0, so apple and pear
          shapes are spread more evenly than among real adults. Children get ±0.5: matched children
          need −0.9…+0.5 (5th–95th percentiles), mostly negative.
        """
        return cls(n=n, seed=seed, age_years=(7.0, 80.0), weight=(0.0, 1.0), muscle=(0.0, 1.0),
                   height=(0.0, 1.0), proportions=(0.0, 1.0), cupsize=(0.0, 1.0), shape="varied")

    def __post_init__(self) -> None:
        check_types(self)
        if self.n <= 0:
            raise WbsaError(f"population size n = {self.n} must be a positive integer; e.g. 100")
        lo, hi = self.age_years
        if not 0 <= lo <= hi <= 110:
            raise WbsaError(f"age range {lo}–{hi} years is invalid; anny covers 0–110 years")
        for name in ("weight", "muscle", "height", "proportions", "cupsize", "firmness", "heavy_weight",
                     "heavy_muscle"):
            lo, hi = getattr(self, name)
            if not 0.0 <= lo <= hi <= 1.0:
                raise WbsaError(f"{name} range ({lo}, {hi}) must lie within [0, 1] with low ≤ high")
        if not 0.0 <= self.heavy_fraction <= 1.0:
            raise WbsaError(f"heavy_fraction = {self.heavy_fraction} must be a fraction in [0, 1]")
        for name in ("local_change_amplitude", "child_local_change_amplitude", "local_change_shared"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise WbsaError(f"{name} = {getattr(self, name)} must lie in [0, 1]")


def sample_random_parameters(settings: RandomPopulationSettings) -> pd.DataFrame:
    """Draw the phenotype parameters of every subject.

    Subject ``i`` is drawn from its own stream ``SeedSequence([seed, i])``, so the same seed
    gives the same subject ``i`` whatever the population size or the worker count.

    The varied shape draws its extra numbers after the paper's, from the same stream, so a
    subject has the same sex, proportions and ethnic mix in both.

    Returns
    -------
    pandas.DataFrame
        ``subject_id``, ``sex``, ``age_years`` and the ``p_*`` phenotype columns, ``n`` rows;
        with ``shape="varied"`` also the ``l_*`` local changes.
    """
    s = settings
    varied = s.shape == "varied"
    rows = np.empty((s.n, 11 + 7 * varied))
    for i in range(s.n):
        rng = np.random.default_rng(np.random.SeedSequence([s.seed, i]))
        u = rng.random(8)
        mix = rng.dirichlet((1.0, 1.0, 1.0))
        rows[i, :8] = u
        rows[i, 8:11] = mix
        if varied:
            rows[i, 11:] = rng.random(7)  # heavy or not, two shared factors, four own deviates

    def scale(u: np.ndarray, interval: tuple[float, float]) -> np.ndarray:
        return interval[0] + u * (interval[1] - interval[0])

    female = rows[:, 0] < 0.5
    if s.age_sampling == "years":
        age_years = scale(rows[:, 1], s.age_years)
        p_age = years_to_param(age_years)
    else:
        p_age = scale(rows[:, 1], tuple(years_to_param(np.array(s.age_years))))
        age_years = param_to_years(p_age)
    weight, muscle = scale(rows[:, 3], s.weight), scale(rows[:, 2], s.muscle)
    child = age_years <= 15.0
    if varied:
        heavy = (rows[:, 11] < s.heavy_fraction) & ~child
        weight = np.where(heavy, scale(rows[:, 3], s.heavy_weight), weight)
        muscle = np.where(heavy, scale(rows[:, 2], s.heavy_muscle), muscle)
    out = pd.DataFrame({
        "subject_id": np.arange(s.n, dtype=np.int64),
        "sex": np.where(female, "female", "male"),
        "age_years": age_years,
        "p_gender": female.astype(np.float64),
        "p_age": p_age,
        "p_muscle": muscle,
        "p_weight": weight,
        "p_height": scale(rows[:, 4], s.height),
        "p_proportions": scale(rows[:, 5], s.proportions),
        "p_cupsize": scale(rows[:, 6], s.cupsize),
        "p_firmness": scale(rows[:, 7], s.firmness),
        "p_african": rows[:, 8],
        "p_asian": rows[:, 9],
        "p_caucasian": rows[:, 10],
    })
    if varied:
        amplitude = np.where(child, s.child_local_change_amplitude, s.local_change_amplitude)
        factor = {"abdominal": 2 * rows[:, 12] - 1, "gluteal": 2 * rows[:, 13] - 1}
        for j, name in enumerate(LOCAL_CHANGE_COLUMNS):
            own = 2 * rows[:, 14 + j] - 1
            shared = factor[_LOCAL_CHANGE_FACTOR[name]]
            out[name] = amplitude * (s.local_change_shared * shared + (1 - s.local_change_shared) * own)
    return out
