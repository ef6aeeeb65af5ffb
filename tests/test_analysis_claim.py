"""The claim test: paired bootstrap with a known answer, the refitted H/W law, the per-group verdicts."""

import numpy as np
import pandas as pd
import pytest

from wbsa.analysis.bootstrap import TOO_FEW, ape_pct, paired_bootstrap, verdict
from wbsa.analysis.claim import HW_KEY, ClaimSettings, evaluate_claim, view_roles
from wbsa.analysis.hw_law import hw_law_fit, hw_law_oof
from wbsa.analysis.cv import cv_predict, fold_ids
from wbsa.analysis.fit_views import FitSettings, fit_all
from helpers.synthetic import synthetic_population, synthetic_scan
from wbsa.errors import WbsaError


def test_paired_bootstrap_covers_a_known_difference():
    """A's errors are B's plus 0.30 points plus noise: the interval covers 0.30 and excludes 0 (A loses)."""
    rng = np.random.default_rng(1)
    n = 400
    b = rng.gamma(2.0, 0.5, n)  # skewed, like absolute errors
    a = b + 0.30 + rng.normal(0.0, 0.5, n)
    true_diff = 0.30 + 0.0  # the noise has mean 0; the sample difference is near it
    bs = paired_bootstrap(a, b, resamples=2000, level=0.95, seed=0)
    assert bs.lo[0] < true_diff < bs.hi[0]
    assert bs.diff[0] == pytest.approx(a.mean() - b.mean())
    assert bs.verdicts == ["loses"]
    # the other way round it wins, by the same amount
    bs2 = paired_bootstrap(b, a, resamples=2000, level=0.95, seed=0)
    assert bs2.verdicts == ["wins"] and bs2.diff[0] == pytest.approx(-bs.diff[0])


def test_paired_bootstrap_interval_has_its_nominal_coverage():
    """Over 200 fresh samples with a known mean difference, the 90 % interval covers it about 90 % of the time."""
    rng = np.random.default_rng(7)
    true_diff, hits, trials = -0.2, 0, 200
    for t in range(trials):
        b = rng.gamma(2.0, 0.5, 150)
        a = b + true_diff + rng.normal(0.0, 0.4, 150)
        bs = paired_bootstrap(a, b, resamples=400, level=0.90, seed=t)
        hits += bool(bs.lo[0] <= true_diff <= bs.hi[0])
    assert 0.82 <= hits / trials <= 0.96


def test_equal_predictors_tie_and_pairing_matters():
    rng = np.random.default_rng(2)
    common = rng.gamma(2.0, 1.0, 300)  # a body that is hard for both predictors
    a = common + rng.normal(0.0, 0.05, 300)
    b = common + rng.normal(0.0, 0.05, 300)
    bs = paired_bootstrap(a, np.column_stack([b, a]), resamples=2000, seed=3)
    assert bs.verdicts == ["ties", "ties"]
    assert bs.diff[1] == 0.0 and bs.lo[1] == 0.0 and bs.hi[1] == 0.0  # identical predictors: no spread at all
    # pairing removes the shared part: the interval is much narrower than the spread of either error
    assert bs.hi[0] - bs.lo[0] < 0.1 * common.std()


def test_paired_bootstrap_is_seeded_and_checks_its_input():
    rng = np.random.default_rng(4)
    a, b = rng.random(50), rng.random(50)
    one = paired_bootstrap(a, b, resamples=300, seed=9)
    two = paired_bootstrap(a, b, resamples=300, seed=9)
    assert one.lo[0] == two.lo[0] and one.hi[0] == two.hi[0]
    with pytest.raises(WbsaError, match="same subjects"):
        paired_bootstrap(a, b[:40])
    with pytest.raises(WbsaError, match="non-finite"):
        paired_bootstrap(np.r_[a[:-1], np.nan], b)


def test_verdict_reads_the_interval():
    assert verdict(-0.5, -0.1) == "wins"
    assert verdict(-0.1, 0.2) == "ties"
    assert verdict(0.1, 0.4) == "loses"


def _hw_bodies(n=500, seed=0, a=-2.1, b=0.725, c=0.425, sd=0.01):
    rng = np.random.default_rng(seed)
    H = rng.uniform(1.0, 2.0, n)
    W = rng.uniform(15.0, 120.0, n)
    wbsa = np.exp(a + b * np.log(H) + c * np.log(W) + rng.normal(0.0, sd, n))
    return H, W, wbsa


def test_hw_law_refit_recovers_known_coefficients():
    """Bodies made with a Du Bois-like law, log WBSA = a + b log H + c log W + N(0, 1 %)."""
    H, W, wbsa = _hw_bodies()
    law = hw_law_fit(H, W, wbsa)
    for name, true in (("a", -2.1), ("b", 0.725), ("c", 0.425)):
        assert abs(law[name] - true) < 4 * law[f"{name}_se"], name
        assert law[f"{name}_se"] < 0.05
    assert law["resid_sd_pct"] == pytest.approx(1.0, rel=0.1)
    assert law["r2"] > 0.99


def test_hw_law_out_of_fold_error_is_the_scatter_at_fixed_h_and_w():
    H, W, wbsa = _hw_bodies(n=600, sd=0.02)
    folds = fold_ids(np.arange(600), 10, 0)
    pred = hw_law_oof(H, W, wbsa, folds)
    # for log-normal error with sd s, mean |e| ≈ s·sqrt(2/π)
    assert ape_pct(pred, wbsa).mean() == pytest.approx(100 * 0.02 * np.sqrt(2 / np.pi), rel=0.12)
    # out of fold: a fold's predictions do not change when that fold's own WBSA changes
    wbsa2 = wbsa.copy()
    wbsa2[folds == 3] *= 1.5
    pred2 = hw_law_oof(H, W, wbsa2, folds)
    assert np.array_equal(pred[folds == 3], pred2[folds == 3])
    with pytest.raises(WbsaError, match="positive"):
        hw_law_oof(H, -W, wbsa, folds)


def test_view_roles_name_the_best_view_once():
    table = pd.DataFrame({"azimuth_deg": [0.0, 30.0, 60.0, 90.0], "elevation_deg": [0.0] * 4,
                          "mape_pct": [0.9, 0.4, 0.6, 1.2]})
    assert view_roles(table, ClaimSettings()) == [("front", 0.0, 0.0), ("30° oblique = best", 30.0, 0.0)]
    table["mape_pct"] = [0.9, 0.7, 0.3, 1.2]
    assert view_roles(table, ClaimSettings()) == [("front", 0.0, 0.0), ("30° oblique", 30.0, 0.0),
                                                  ("best", 60.0, 0.0)]
    no_oblique = table[table["azimuth_deg"] != 30.0]
    assert [r[0] for r in view_roles(no_oblique, ClaimSettings())] == ["front", "best"]


@pytest.fixture(scope="module")
def fitted():
    pop = synthetic_population(240, seed=5)
    scan = synthetic_scan(pop, [(0.0, 0.0), (30.0, 0.0), (90.0, 0.0)], seed=5)
    settings = FitSettings(models=("linear",), predictor_sets=((),), groups=("all",), k=5, seed=3)
    return pop, scan, settings, fit_all(pop, scan, settings, show_progress=False)


def test_claim_uses_the_fits_folds(fitted):
    """The folds the claim rebuilds from (k, seed) reproduce the fit stage's out-of-fold predictions exactly."""
    pop, scan, settings, out = fitted
    r = out.residuals
    r = r[(r["azimuth_deg"] == 30.0)]
    pos = pd.Index(pop["subject_id"]).get_indexer(r["subject_id"])
    folds = fold_ids(pop["subject_id"].to_numpy(), settings.k, settings.seed)[pos]
    v = scan[scan["azimuth_deg"] == 30.0].set_index("subject_id").loc[r["subject_id"], "vbsa_visible_m2"]
    again = cv_predict("linear", r["wbsa_m2"].to_numpy(), v.to_numpy(), None, folds)
    np.testing.assert_allclose(again, r["cv_pred_m2"].to_numpy(), rtol=1e-12)


def test_claim_table_per_group(fitted):
    pop, scan, settings, out = fitted
    cs = ClaimSettings(resamples=300)
    res = evaluate_claim(pop, out.residuals, k=settings.k, fold_seed=settings.seed, settings=cs)
    c, h = res.comparisons, res.headline
    assert list(dict.fromkeys(c["group"])) == [g for g in cs.groups if g in set(c["group"])]
    # every group × role has the refitted law then all 12 published formulae, no duplicate row
    assert not c.duplicated(["group", "vbsa_column", "role", "comparator"]).any()
    per = c.groupby(["group", "role"]).size()
    assert (per == 13).all()
    assert (c.groupby(["group", "role"])["comparator"].first() == HW_KEY).all()
    # the headline repeats the comparisons' numbers
    row = h[(h["group"] == "all") & (h["role"] == "front = best")].iloc[0]
    hw = c[(c["group"] == "all") & (c["role"] == "front = best") & (c["comparator"] == HW_KEY)].iloc[0]
    assert row["diff_vs_hw"] == hw["diff_pct_points"] == pytest.approx(hw["view_mape_pct"] - hw["comparator_mape_pct"])
    assert row["view_mape_pct"] == pytest.approx(ape_pct(out.residuals.loc[out.residuals["azimuth_deg"] == 0.0,
                                                                           "cv_pred_m2"],
                                                         out.residuals.loc[out.residuals["azimuth_deg"] == 0.0,
                                                                           "wbsa_m2"]).mean())
    # known answers: synthetic WBSA is Mosteller's H/W law × (1 + 1 % noise), so the refitted law errs by
    # ~0.8 %; the view errs by its VBSA noise, 0.5 % at the front (better) and 1.5 % at 30° (worse)
    all_ = h[h["group"] == "all"].set_index("role")
    assert list(all_.index) == ["front = best", "30° oblique"]
    assert all_.loc["front = best", "verdict_vs_hw"] == "wins"
    assert all_.loc["30° oblique", "verdict_vs_hw"] == "loses"
    assert all_["hw_refit_mape_pct"].between(0.6, 1.0).all()
    n_all = int(all_["n"].iloc[0])
    assert set(res.sentences) == set(h["group"])
    assert res.sentences["all"].startswith(f"All subjects (n = {n_all}): with the ideal visible area the front view "
                                           "(the best) beats both the refitted H/W law and ")
    assert res.sentences["all"].endswith("the 30° oblique view loses to the law and ties with the formula.") or \
        res.sentences["all"].endswith("the 30° oblique view loses to both.")
    # a group smaller than min_subjects gets no interval
    small = c[c["n"] < cs.min_subjects]
    assert small["diff_lo"].isna().all() and (small["verdict"] == TOO_FEW).all()


def test_claim_without_out_of_fold_predictions_says_why(fitted):
    pop, _, settings, out = fitted
    from wbsa.analysis.claim import ClaimUnavailable

    with pytest.raises(ClaimUnavailable, match="residual"):
        evaluate_claim(pop, out.residuals.iloc[:0], k=settings.k, fold_seed=settings.seed)
    with pytest.raises(ClaimUnavailable, match="wls"):
        evaluate_claim(pop, out.residuals, k=settings.k, fold_seed=settings.seed, model="wls")
