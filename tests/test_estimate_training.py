"""The estimator's training and interval rank, without rendering: the conformal rank, the training parts."""

from __future__ import annotations

import pytest

from wbsa.errors import WbsaError


def test_conformal_rank_counts_in_subjects_and_is_exact_at_whole_products():
    """The split-conformal rank counted in subjects (⌈(m + 1) L⌉ of m subjects, as a level over the n
    captures): the default model's 1,347 captures of 337 subjects give k = 322 and the 1,285th score; the
    rank is taken exactly where (m + 1) L, or the rank through the level k / (m + 1), is a whole number that
    floating point lands just above."""
    from wbsa.estimation.methods.regression.model import conformal_rank

    assert conformal_rank(1347, 337, 0.95) == (1285, False)  # k = ⌈338 × 0.95⌉ = 322; ⌈1348 × 322 / 338⌉
    assert conformal_rank(300, 300, 0.95) == (286, False)  # one score per subject: the plain ⌈(n + 1) L⌉
    # k = ⌈(m + 1) L⌉ > m: no score promises L; the largest is taken, unsure
    assert conformal_rank(300, 75, 0.99) == (300, True)  # ⌈76 × 0.99⌉ = 76 > 75 subjects
    assert conformal_rank(19, 19, 0.96) == (19, True)  # ⌈20 × 0.96⌉ = 20 > 19
    assert conformal_rank(19, 19, 0.95) == (19, False)  # 20 × 0.95 = 19: k = 19 ≤ 19
    # 100 × 0.55 is 55.00000000000001 in floating point: k = 55 (a bare ceil gives 56), rank 55 and 220
    assert (100 * 0.55) > 55
    assert conformal_rank(99, 99, 0.55) == (55, False)
    assert conformal_rank(399, 99, 0.55) == (220, False)  # exact: 400 × 55 / 100 = 220, not 221
    assert conformal_rank(24, 24, 0.56) == (14, False)  # 25 × 0.56 = 14.000000000000002
    # the second step in integers: through the level k / (m + 1), 29 × (15 / 29) = 15.000000000000002
    assert conformal_rank(28, 28, 0.5) == (15, False)
    assert conformal_rank(115, 28, 0.5) == (60, False)  # 116 × 15 / 29 = 60
    # more subjects than scores (not met in training): a rank past the scores is unsure too
    assert conformal_rank(5, 50, 0.9) == (5, True)
    for bad in (0.0, 1.0, 1.5, -0.1):
        with pytest.raises(WbsaError, match="level"):
            conformal_rank(100, 25, bad)


def test_the_model_quantile_takes_the_conformal_rank():
    """:meth:`EstimatorModel.quantile` is the :func:`conformal_rank`-th score, and it is unsure with it."""
    import numpy as np

    from wbsa.estimation.methods.regression.model import EstimatorModel, conformal_rank

    scores = np.sort(np.random.default_rng(0).random(400))
    model = EstimatorModel(None, *(np.zeros(1),) * 3, 0.0, None, np.zeros(10), np.zeros(2), scores,
                           {"n_calibration_subjects": 99})
    for level in (0.5, 0.55, 0.9, 0.95, 0.99, 0.995):
        rank, unsure = conformal_rank(400, 99, level)
        assert model.quantile(level) == scores[rank - 1] and model.quantile_is_sure(level) is not unsure
    assert model.quantile(0.55) == scores[220]  # k = 55: ⌈401 × 55 / 100⌉ = 221 (a bare ceil's k = 56: 225)
    assert model.quantile(0.995) == scores[-1] and not model.quantile_is_sure(0.995)  # ⌈100 × 0.995⌉ > 99
    with pytest.raises(WbsaError, match="too few"):
        model.quantile(0.999)  # ⌈401 × 0.999⌉ = 401 > 400 renders


@pytest.mark.parametrize("parts, match", [(("fit", "held-out"), "'held-out' is unknown; use fit or calibration"),
                                          ((), "no training part"),
                                          ("calibration", r"a tuple .* use e\.g\. \('calibration',\)")])
def test_training_parts_are_checked_before_the_population_is_built(monkeypatch, parts, match):
    """A bad ``parts`` stops :func:`training_renders` at once, not after minutes of building and rendering."""
    from wbsa.training import pipeline as train

    def no_population(*args, **kwargs):
        raise AssertionError("the population was built before the parts were checked")

    monkeypatch.setattr(train, "training_population", no_population)
    with pytest.raises(WbsaError, match=match):
        train.training_renders(train.TrainSettings(), parts)
