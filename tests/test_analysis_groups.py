"""Groups of subjects: thresholds, boundaries, and that the paper's groupings partition the population."""

import numpy as np
import pandas as pd
import pytest

from wbsa.analysis.groups import GROUP_NAMES, GroupSpec, assign_groups, check_group_names
from helpers.synthetic import synthetic_population
from wbsa.errors import WbsaError


def test_paper_groupings_partition_the_subjects():
    pop = synthetic_population(3000, seed=3)
    m = assign_groups(pop)
    assert list(m.columns) == list(GROUP_NAMES)
    assert m["all"].all()
    for parts in (("males", "females"), ("kids", "adults"), ("small", "normal", "big")):
        counts = m[list(parts)].sum(axis=1)
        assert (counts == 1).all(), parts  # every subject in exactly one part
        assert all(m[p].any() for p in parts), parts  # the synthetic population fills every part


def test_boundaries_follow_the_paper():
    pop = pd.DataFrame({
        "sex": ["male", "female", "Male", "female"],
        "age_years": [15.0, 15.01, 40.0, 8.0],
        "stature_m": [1.40, 1.4001, 2.00, 2.0001],
        "bmi": [30.0, 29.99, 18.0, 35.0],
    })
    m = assign_groups(pop)
    assert m["males"].tolist() == [True, False, True, False]
    assert m["kids"].tolist() == [True, False, False, True]  # <= 15 y is a kid
    assert m["small"].tolist() == [True, False, False, False]  # <= 140 cm is small
    assert m["normal"].tolist() == [False, True, True, False]  # 140 < S <= 200
    assert m["big"].tolist() == [False, False, False, True]  # > 200 cm
    assert m["obese"].tolist() == [False, False, False, False]  # adults with BMI >= 30: none here (ages 15, 8)
    adults = pop.assign(age_years=40.0)
    assert assign_groups(adults)["obese"].tolist() == [True, False, False, True]  # BMI >= 30 (WHO, adults)


def test_custom_thresholds_move_subjects():
    pop = pd.DataFrame({"sex": ["male"] * 3, "age_years": [12.0, 17.0, 30.0], "stature_m": [1.5, 1.7, 1.9],
                        "bmi": [20.0, 26.0, 28.0]})
    m = assign_groups(pop, GroupSpec(kid_max_age_years=18, small_max_stature_m=1.6, big_min_stature_m=1.8,
                                     obese_min_bmi=25))
    assert m["kids"].tolist() == [True, True, False]
    assert m["small"].tolist() == [True, False, False]
    assert m["big"].tolist() == [False, False, True]
    assert m["obese"].tolist() == [False, False, True]  # adults (> 18 y) with BMI >= 25


def test_missing_values_leave_a_subject_only_in_all():
    pop = pd.DataFrame({"sex": [None], "age_years": [np.nan], "stature_m": [np.nan], "bmi": [np.nan]})
    m = assign_groups(pop)
    assert m.iloc[0].sum() == 1 and m.loc[0, "all"]


def test_bad_settings_are_user_errors():
    with pytest.raises(WbsaError, match="small_max_stature_m must be positive and below big_min_stature_m"):
        GroupSpec(small_max_stature_m=2.1, big_min_stature_m=2.0)
    with pytest.raises(WbsaError, match="unknown group"):
        check_group_names(["all", "giants"])
    with pytest.raises(WbsaError, match="lacks column"):
        assign_groups(pd.DataFrame({"sex": ["male"]}))


def test_underweight_is_adults_below_18_5_and_tall_is_from_1_85_m():
    pop = pd.DataFrame({
        "sex": ["male", "female", "male", "female"],
        "age_years": [30.0, 10.0, 40.0, 25.0],
        "stature_m": [1.85, 1.30, 1.8499, 1.90],
        "bmi": [18.49, 14.0, 18.5, 22.0],
    })
    m = assign_groups(pop)
    assert m["underweight"].tolist() == [True, False, False, False]  # the child's low BMI is not adult underweight
    assert m["tall"].tolist() == [True, False, False, True]  # >= 1.85 m
    m2 = assign_groups(pop, GroupSpec(underweight_max_bmi=20.0, tall_min_stature_m=1.95))
    assert m2["underweight"].tolist() == [True, False, True, False]
    assert not m2["tall"].any()


def test_claim_thresholds_are_recorded_only_when_changed():
    """Fit records (model.json, fit_info.json) written before the claim groups existed stay the same."""
    assert set(GroupSpec().to_dict()) == {"kid_max_age_years", "small_max_stature_m", "big_min_stature_m",
                                          "obese_min_bmi"}
    d = GroupSpec(tall_min_stature_m=1.9).to_dict()
    assert d["tall_min_stature_m"] == 1.9 and "underweight_max_bmi" not in d
    assert GroupSpec(**d) == GroupSpec(tall_min_stature_m=1.9)  # round trip
    with pytest.raises(WbsaError, match="underweight_max_bmi"):
        GroupSpec(underweight_max_bmi=35.0)
