"""Groups of subjects: thresholds, boundaries, and that the paper's groupings partition the population."""

import numpy as np
import pandas as pd
import pytest

from wbsa.analysis.groups import GROUP_NAMES, GroupSpec, assign_groups, check_group_names
from wbsa.analysis.synthetic import synthetic_population
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
    assert m["obese"].tolist() == [True, False, False, True]  # BMI >= 30


def test_custom_thresholds_move_subjects():
    pop = pd.DataFrame({"sex": ["male"] * 3, "age_years": [12.0, 17.0, 30.0], "stature_m": [1.5, 1.7, 1.9],
                        "bmi": [20.0, 26.0, 28.0]})
    m = assign_groups(pop, GroupSpec(kid_max_age_years=18, small_max_stature_m=1.6, big_min_stature_m=1.8,
                                     obese_min_bmi=25))
    assert m["kids"].tolist() == [True, True, False]
    assert m["small"].tolist() == [True, False, False]
    assert m["big"].tolist() == [False, False, True]
    assert m["obese"].tolist() == [False, True, True]


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
