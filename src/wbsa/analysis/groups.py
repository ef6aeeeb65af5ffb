"""Subject groups of the paper (sex, age, stature) plus obesity, underweight and tall stature, as boolean columns."""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Literal, get_args

import numpy as np
import pandas as pd

from wbsa.errors import WbsaError

GroupName = Literal["all", "males", "females", "kids", "adults", "small", "normal", "big", "obese", "underweight",
                    "tall"]

#: Every group name, in report order.
GROUP_NAMES: tuple[str, ...] = get_args(GroupName)

#: The groups of the paper (section 2.5): all, males/females, kids/adults, small/normal/big stature.
PAPER_GROUPS: tuple[str, ...] = ("all", "males", "females", "kids", "adults", "small", "normal", "big")

#: Groups of the formulae comparison (issue: overall, kids, adults, BMI >= 30, big stature) plus the rest.
COMPARISON_GROUPS: tuple[str, ...] = GROUP_NAMES

#: Groups of the headline claim table (issue 10), in its order: who the height/weight formulae are said to fail.
CLAIM_GROUPS: tuple[str, ...] = ("all", "adults", "kids", "obese", "underweight", "small", "tall", "females", "males")

#: Thresholds used only by the claim groups; :meth:`GroupSpec.to_dict` records them only when changed, so fit
#: records written before these groups existed stay byte-identical.
_CLAIM_ONLY_FIELDS: tuple[str, ...] = ("underweight_max_bmi", "tall_min_stature_m")

#: Columns of the population table that :func:`assign_groups` reads.
GROUP_COLUMNS: tuple[str, ...] = ("sex", "age_years", "stature_m", "bmi")


@dataclass(frozen=True)
class GroupSpec:
    """Thresholds that define the groups.

    Attributes
    ----------
    kid_max_age_years : float
        Kids are ``age_years <= kid_max_age_years`` (paper: 15); adults are older.
    small_max_stature_m : float
        Small stature is ``stature_m <= small_max_stature_m`` (paper: 1.40 m).
    big_min_stature_m : float
        Big stature is ``stature_m > big_min_stature_m`` (paper: 2.00 m); normal lies between.
    obese_min_bmi : float
        Obese is ``bmi >= obese_min_bmi`` (WHO: 30 kg/m²).
    underweight_max_bmi : float
        Underweight is an adult with ``bmi < underweight_max_bmi`` (WHO: 18.5 kg/m²; children are left out
        because their BMI cut-offs depend on age and sex).
    tall_min_stature_m : float
        Tall is ``stature_m >= tall_min_stature_m`` (default 1.85 m: the 90th percentile of US adult men,
        NHANES 2017–2020 weighted, 184.6 cm; 4.4 % of US adults). The paper's ``big`` (> 2.00 m) is too rare
        in real populations to test a claim on.
    """

    kid_max_age_years: float = 15.0
    small_max_stature_m: float = 1.40
    big_min_stature_m: float = 2.00
    obese_min_bmi: float = 30.0
    underweight_max_bmi: float = 18.5
    tall_min_stature_m: float = 1.85

    def __post_init__(self) -> None:
        if not (0 < self.small_max_stature_m < self.big_min_stature_m):
            raise WbsaError(
                f"stature cuts {self.small_max_stature_m} m and {self.big_min_stature_m} m must satisfy "
                "0 < small < big; give --stature-cuts SMALL,BIG in metres, e.g. 1.40,2.00")
        if not self.kid_max_age_years > 0:
            raise WbsaError(f"kid age limit {self.kid_max_age_years} must be positive; e.g. --kid-max-age 15")
        if not self.obese_min_bmi > 0:
            raise WbsaError(f"obesity BMI limit {self.obese_min_bmi} must be positive; e.g. --obese-bmi 30")
        if not 0 < self.underweight_max_bmi < self.obese_min_bmi:
            raise WbsaError(f"underweight_max_bmi = {self.underweight_max_bmi} must lie in (0, obese_min_bmi = "
                            f"{self.obese_min_bmi}); WHO: 18.5")
        if not self.tall_min_stature_m > 0:
            raise WbsaError(f"tall_min_stature_m = {self.tall_min_stature_m} must be positive, in metres; e.g. 1.85")

    def to_dict(self) -> dict[str, float]:
        """The thresholds as plain JSON; the claim-only ones (underweight, tall) only when not at their defaults."""
        out = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name in _CLAIM_ONLY_FIELDS and value == f.default:
                continue
            out[f.name] = value
        return out

    def describe(self) -> dict[str, str]:
        """One human-readable definition per group name."""
        return {
            "all": "all subjects",
            "males": "sex == male",
            "females": "sex == female",
            "kids": f"age <= {self.kid_max_age_years:g} y",
            "adults": f"age > {self.kid_max_age_years:g} y",
            "small": f"stature <= {self.small_max_stature_m:g} m",
            "normal": f"{self.small_max_stature_m:g} m < stature <= {self.big_min_stature_m:g} m",
            "big": f"stature > {self.big_min_stature_m:g} m",
            "obese": f"BMI >= {self.obese_min_bmi:g} kg/m2",
            "underweight": f"adults with BMI < {self.underweight_max_bmi:g} kg/m2",
            "tall": f"stature >= {self.tall_min_stature_m:g} m",
        }


def check_names(names: tuple[str, ...] | list[str], valid: tuple[str, ...], what: str) -> tuple[str, ...]:
    """``names`` without repeats, in order, if all are in ``valid``; else a WbsaError naming the valid ones."""
    bad = [n for n in names if n not in valid]
    if bad:
        raise WbsaError(f"unknown {what}(s) {', '.join(bad)}; choose from {', '.join(valid)}")
    if not names:
        raise WbsaError(f"no {what} given; choose from {', '.join(valid)}")
    return tuple(dict.fromkeys(names))


def check_group_names(names: tuple[str, ...] | list[str]) -> tuple[str, ...]:
    """Validate group names; raise :class:`WbsaError` naming the valid ones."""
    return check_names(names, GROUP_NAMES, "group")


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
            "obese": bmi >= spec.obese_min_bmi,
            "underweight": (age > spec.kid_max_age_years) & (bmi < spec.underweight_max_bmi),
            "tall": stature >= spec.tall_min_stature_m,
        }
    return pd.DataFrame(members, index=population.index, columns=list(GROUP_NAMES))
