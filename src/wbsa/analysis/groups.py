"""Subject groups of the paper (sex, age, stature) plus obesity, underweight and tall stature, as boolean columns."""

from __future__ import annotations

import numpy as np
import pandas as pd

from wbsa.analysis.settings import PAPER_GROUPS, GroupSpec, check_group_names  # noqa: F401 - re-exported
from wbsa.errors import WbsaError
from wbsa.typing import GROUP_NAMES, GroupName  # noqa: F401 - GroupName re-exported for the analysis modules

#: Groups of the formulae comparison (overall, kids, adults, BMI >= 30, big stature) plus the rest.
COMPARISON_GROUPS: tuple[str, ...] = GROUP_NAMES

#: Groups of the headline claim table, in its order: who the height/weight formulae are said to fail.
CLAIM_GROUPS: tuple[str, ...] = ("all", "adults", "kids", "obese", "underweight", "small", "tall", "females", "males")

#: Columns of the population table that :func:`assign_groups` reads.
GROUP_COLUMNS: tuple[str, ...] = ("sex", "age_years", "stature_m", "bmi")




def assign_groups(population: pd.DataFrame, spec: GroupSpec = GroupSpec()) -> pd.DataFrame:
    """Membership of every subject in every group.

    Parameters
    ----------
    population : DataFrame
        At least ``sex`` ('male'|'female'), ``age_years``, ``stature_m`` and ``bmi``; one row per subject.
    spec : GroupSpec
        The thresholds.

    Returns
    -------
    DataFrame
        Same index as ``population``; one bool column per name in :data:`GROUP_NAMES`.
        males/females, kids/adults and small/normal/big each partition the subjects
        (a subject with a missing value is in ``all`` only).
    """
    missing = [c for c in GROUP_COLUMNS if c not in population.columns]
    if missing:
        raise WbsaError(f"population table lacks column(s) {', '.join(missing)} needed for the groups; "
                        "regenerate it with wbsa population")
    sex = population["sex"].astype("string").str.lower()
    age = population["age_years"].to_numpy(dtype=float)
    stature = population["stature_m"].to_numpy(dtype=float)
    bmi = population["bmi"].to_numpy(dtype=float)
    with np.errstate(invalid="ignore"):
        members = {
            "all": np.ones(len(population), dtype=bool),
            "males": (sex == "male").fillna(False).to_numpy(dtype=bool),
            "females": (sex == "female").fillna(False).to_numpy(dtype=bool),
            "kids": age <= spec.kid_max_age_years,
            "adults": age > spec.kid_max_age_years,
            "small": stature <= spec.small_max_stature_m,
            "normal": (stature > spec.small_max_stature_m) & (stature <= spec.big_min_stature_m),
            "big": stature > spec.big_min_stature_m,
            "obese": (age > spec.kid_max_age_years) & (bmi >= spec.obese_min_bmi),
            "underweight": (age > spec.kid_max_age_years) & (bmi < spec.underweight_max_bmi),
            "tall": stature >= spec.tall_min_stature_m,
        }
    return pd.DataFrame(members, index=population.index, columns=list(GROUP_NAMES))
