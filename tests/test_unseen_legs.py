"""Legs the frame does not show: the area profile, the completion of the measures, the wider interval, feet told by
their shape, and a stated stature that is always used."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from wbsa.bodies.area_profile import AREA_BELOW, HEIGHT_SHARES, area_below_share, measure_area_profile, skin_share_below
from wbsa.estimation.subject.people import FEET_SPREAD, feet_shape_unseen
from wbsa.estimation.subject.unseen import CUT_LOG_ERROR_PER_SHARE, completed, corrected, unseen_legs, widened


def _tube(n_rings: int = 41, n_around: int = 32, height_m: float = 2.0):
    """An open vertical tube standing on z = 0: its side area is uniform in height."""
    z = np.linspace(0.0, height_m, n_rings)
    a = np.linspace(0.0, 2 * np.pi, n_around, endpoint=False)
    v = np.array([[0.1 * np.cos(t), 0.1 * np.sin(t), h] for h in z for t in a])
    faces = []
    for r in range(n_rings - 1):
        for k in range(n_around):
            p, q = r * n_around + k, r * n_around + (k + 1) % n_around
            faces += [[p, q, p + n_around], [q, q + n_around, p + n_around]]
    return v, np.array(faces)


def test_the_share_of_area_below_a_height_of_a_uniform_tube_is_that_height():
    v, f = _tube()
    shares = skin_share_below(v, f, np.array([0.0, 0.25, 0.5, 1.0]))
    np.testing.assert_allclose(shares, [0.0, 0.25, 0.5, 1.0], atol=0.02)


def test_the_shipped_area_profile_is_what_anny_bodies_measure(body_model):
    """Eight bodies of the benchmark's mix measured again: within 0.03 of the shipped table at every height
    (the table's spread over people is about 0.01), rising from 0 to about a third below mid-thigh."""
    from wbsa.testing.testset import held_out_population

    pop = held_out_population(8, 0.0, 2000)
    again = measure_area_profile(pop, 2000)
    assert np.abs(again[:, 0] - AREA_BELOW[:, 0]).max() < 0.03
    assert np.all(np.diff(AREA_BELOW[:, 0]) > 0)
    assert 0.17 < area_below_share(0.28)[0] < 0.25  # below the knees: lower legs and feet, about 21 % (Lund-Browder)
    assert HEIGHT_SHARES[-1] == 0.6 and area_below_share(0.9)[0] == AREA_BELOW[-1, 0]


def test_the_area_measures_are_completed_by_the_unseen_share_and_nothing_else():
    unseen = unseen_legs(1.80, 0.50)
    share = area_below_share(0.50 / 1.80)[0]
    assert unseen.area_share == pytest.approx(share) and unseen.seen_from_m == 0.5
    features = {"seen_area_m2": np.array([0.6]), "silhouette_m2": np.array([0.5]), "stature_m": np.array([1.8])}
    out = completed(features, unseen)
    assert out["seen_area_m2"][0] == pytest.approx(0.6 / (1 - share))
    assert out["silhouette_m2"][0] == pytest.approx(0.5 / (1 - share))
    assert out["stature_m"][0] == 1.8 and completed(features, None) is features
    assert unseen_legs(1.80, 0.0) is None  # seen down to the floor: nothing is missing


def test_the_interval_widens_by_the_unseen_legs_spread_in_quadrature_and_the_mean_error_is_taken_off():
    unseen = unseen_legs(1.70, 0.60)
    lo, hi = widened(1.8, 2.2, 2.0, unseen, 0.95)
    extra = 1.959964 * math.hypot(unseen.area_share_sd / (1 - unseen.area_share),
                                  CUT_LOG_ERROR_PER_SHARE[1] * unseen.area_share)
    assert math.log(2.0 / lo) == pytest.approx(math.hypot(math.log(2.0 / 1.8), extra), rel=1e-5)
    assert math.log(hi / 2.0) == pytest.approx(math.hypot(math.log(2.2 / 2.0), extra), rel=1e-5)
    assert widened(1.8, 2.2, 2.0, None, 0.95) == (1.8, 2.2)
    nothing_unseen = dataclasses.replace(unseen, area_share=0.0, area_share_sd=0.0)
    assert widened(1.8, 2.2, 2.0, nothing_unseen, 0.95) == pytest.approx((1.8, 2.2))
    assert corrected(2.0, None) == 2.0
    assert corrected(2.0, unseen) == pytest.approx(2.0 * math.exp(-CUT_LOG_ERROR_PER_SHARE[0] * unseen.area_share))


def test_feet_are_told_from_legs_that_end_over_nothing_by_their_spread():
    legs = np.r_[np.full(20, 0.3), np.full(20, 0.12)]  # the lowest band as wide and deep as the legs above
    assert "no feet" in feet_shape_unseen(legs)
    feet = legs.copy()
    feet[20] = 0.12 * FEET_SPREAD * 1.1  # toes forward: the lowest band deeper
    assert feet_shape_unseen(feet) is None
    side = legs.copy()
    side[0] = 0.3 * FEET_SPREAD * 1.1  # seen from the side: the feet longer than the legs are wide
    assert feet_shape_unseen(side) is None


@dataclasses.dataclass(frozen=True)
class _Measures:
    """The one measure :func:`stated_stature` reads and replaces."""

    stature_m: float


def test_a_stated_stature_is_always_used_and_what_differs_is_said():
    """Feet on a seen floor: the stated stature replaces the measured one, flagged beyond 5 cm; no floor and a
    body seen shorter than stated: the legs below are taken as unseen; feet not seen: unseen from the
    lowest returns over the floor."""
    from wbsa.estimation.single_view import stated_stature

    m, unseen, flags = stated_stature(_Measures(1.70), 1.72, None, 0.0)
    assert m.stature_m == 1.72 and unseen is None and flags == {}
    m, unseen, flags = stated_stature(_Measures(1.60), 1.72, None, 0.0)
    assert m.stature_m == 1.72 and unseen is None and "+12 cm" in flags["stature_disagrees"]
    m, unseen, flags = stated_stature(_Measures(1.22), 1.71, None, None)
    assert unseen.seen_from_m == pytest.approx(0.49) and "legs may end over nothing" in flags["feet_not_seen"]
    m, unseen, flags = stated_stature(_Measures(1.30), 1.80, "the feet touch the bottom edge", 0.45)
    assert unseen.seen_from_m == 0.45 and flags["feet_not_seen"].startswith("the feet touch the bottom edge")
    assert m.stature_m == 1.80
