"""One view: recovery of a known law, CV against scikit-learn, diagnostics, and refusal to fit too little."""

import numpy as np
import pandas as pd
import pytest

from wbsa.analysis.cv import cv_metrics, fold_ids
from wbsa.analysis.regression import CannotFit, fit_arrays, fit_view


def linear_law(n, seed, c1=2.5, c0=0.1, sigma=0.02, stature_coef=None):
    """WBSA = c1*VBSA + c0 (+ b*stature) + N(0, sigma^2); VBSA and stature drawn independently."""
    rng = np.random.default_rng(seed)
    vbsa = rng.uniform(0.3, 1.0, n)
    stature = rng.uniform(1.0, 2.1, n)
    wbsa = c1 * vbsa + c0 + rng.normal(0, sigma, n)
    if stature_coef is not None:
        wbsa += stature_coef * stature
    return pd.DataFrame({"subject_id": rng.permutation(n) + 1000, "vbsa_visible_m2": vbsa, "stature_m": stature,
                         "wbsa_m2": wbsa})


def test_recovers_a_known_linear_law_within_its_standard_errors():
    df = linear_law(2000, seed=1)
    fit = fit_view(df, "vbsa_visible_m2", (), "linear", k=10, seed=0)
    c = fit.coefficient_columns()
    assert abs(c["c1"] - 2.5) < 3 * c["c1_se"]
    assert abs(c["c0"] - 0.1) < 3 * c["c0_se"]
    # the standard error itself is the textbook sigma / (sd(x) sqrt(n))
    expected_se = 0.02 / (df["vbsa_visible_m2"].std(ddof=0) * np.sqrt(len(df)))
    assert c["c1_se"] == pytest.approx(expected_se, rel=0.05)
    assert c["c1_t"] == pytest.approx(c["c1"] / c["c1_se"])
    assert fit.rse_m2 == pytest.approx(0.02, rel=0.05)
    assert fit.n == 2000 and fit.df_resid == 1998


def test_standard_errors_have_their_nominal_coverage():
    # Over many independent data sets, |c1_hat - c1| <= se about 68 % of the time (t, 98 dof).
    hits = []
    for seed in range(200):
        df = linear_law(100, seed=seed, sigma=0.05)
        folds = np.arange(100) % 2
        fit = fit_arrays("linear", df["wbsa_m2"].to_numpy(), df["vbsa_visible_m2"].to_numpy(), {}, folds)
        hits.append(abs(fit.params[1] - 2.5) <= fit.bse[1])
    assert 0.58 < np.mean(hits) < 0.78  # 0.68 +- 3 binomial sd


def test_recovers_the_stature_coefficient_of_eq_8():
    df = linear_law(3000, seed=2, c1=1.8, c0=-0.2, stature_coef=0.5)
    fit = fit_view(df, "vbsa_visible_m2", ("stature_m",), "linear", k=10, seed=0)
    c = fit.coefficient_columns()
    assert fit.terms == ("const", "vbsa", "stature_m")
    for name, true in (("c0", -0.2), ("c1", 1.8), ("c_stature_m", 0.5)):
        assert abs(c[name] - true) < 3 * c[f"{name}_se"], name


def test_r2_and_rse_equal_statsmodels_for_ols():
    import statsmodels.api as sm

    df = linear_law(500, seed=4, stature_coef=0.3)
    fit = fit_view(df, "vbsa_visible_m2", ("stature_m",), "linear", k=5, seed=1)
    res = sm.OLS(df["wbsa_m2"], sm.add_constant(df[["vbsa_visible_m2", "stature_m"]])).fit()
    assert fit.r2 == pytest.approx(res.rsquared, rel=1e-12)
    assert fit.rse_m2 == pytest.approx(np.sqrt(res.scale), rel=1e-12)
    np.testing.assert_allclose(fit.params, res.params.to_numpy(), rtol=1e-10)
    np.testing.assert_allclose(fit.bse, res.bse.to_numpy(), rtol=1e-10)
    studentized = res.get_influence().resid_studentized_internal
    np.testing.assert_allclose(fit.standardized, studentized, rtol=1e-9)


def test_cv_predictions_and_metrics_agree_with_sklearn():
    from sklearn.linear_model import LinearRegression
    from sklearn.model_selection import PredefinedSplit, cross_val_predict

    df = linear_law(700, seed=5, stature_coef=0.4)
    fit = fit_view(df, "vbsa_visible_m2", ("stature_m",), "linear", k=10, seed=7)
    folds = fold_ids(df["subject_id"].to_numpy(), 10, 7)
    X = df[["vbsa_visible_m2", "stature_m"]].to_numpy()
    y = df["wbsa_m2"].to_numpy()
    pred = cross_val_predict(LinearRegression(), X, y, cv=PredefinedSplit(folds))
    np.testing.assert_allclose(fit.cv_pred_m2, pred, rtol=1e-10, atol=1e-12)
    e = pred - y
    assert fit.cv["cv_mspe_m4"] == pytest.approx(np.mean(e**2), rel=1e-9)
    assert fit.cv["cv_rmse_m2"] == pytest.approx(np.sqrt(np.mean(e**2)), rel=1e-9)
    assert fit.cv["cv_mape_pct"] == pytest.approx(100 * np.mean(np.abs(e) / y), rel=1e-9)
    assert fit.cv["cv_bias_m2"] == pytest.approx(np.mean(e), abs=1e-12)
    # cross-validated error exceeds the in-sample one, but only slightly with 2 parameters and 700 rows
    assert fit.rse_m2 < fit.cv["cv_rmse_m2"] < 1.05 * fit.rse_m2


def test_loglog_and_wls_cv_agree_with_a_manual_sklearn_loop():
    from sklearn.linear_model import LinearRegression

    rng = np.random.default_rng(6)
    vbsa = rng.uniform(0.3, 1.2, 600)
    wbsa = 3.0 * vbsa**0.95 * np.exp(rng.normal(0, 0.03, 600))
    folds = fold_ids(np.arange(600), 8, 3)
    loglog = fit_arrays("loglog", wbsa, vbsa, {}, folds)
    wls = fit_arrays("wls", wbsa, vbsa, {}, folds)
    want_log, want_wls = np.empty(600), np.empty(600)
    for f in range(8):
        tr, te = folds != f, folds == f
        m = LinearRegression().fit(np.log(vbsa[tr, None]), np.log(wbsa[tr]))
        want_log[te] = np.exp(m.predict(np.log(vbsa[te, None])))
        m = LinearRegression().fit(vbsa[tr, None], wbsa[tr], sample_weight=1 / vbsa[tr] ** 2)
        want_wls[te] = m.predict(vbsa[te, None])
    np.testing.assert_allclose(loglog.cv_pred_m2, want_log, rtol=1e-10)
    np.testing.assert_allclose(wls.cv_pred_m2, want_wls, rtol=1e-10)
    assert loglog.params[1] == pytest.approx(0.95, abs=3 * loglog.bse[1])
    want = cv_metrics(wbsa, want_log)
    assert loglog.cv == pytest.approx(want, rel=1e-8, abs=1e-12)


def test_fold_ids_are_balanced_seeded_and_follow_the_subjects():
    ids = np.random.default_rng(0).permutation(np.arange(1003) * 7)
    f = fold_ids(ids, 10, 42)
    assert sorted(np.bincount(f)) == [100] * 7 + [101] * 3
    np.testing.assert_array_equal(f, fold_ids(ids, 10, 42))
    assert not np.array_equal(f, fold_ids(ids, 10, 43))
    # same subjects in another row order (and repeated, e.g. several views) -> same folds per subject
    order = np.argsort(ids)
    g = fold_ids(np.concatenate([ids[order], ids[order]]), 10, 42)
    np.testing.assert_array_equal(g[:1003], f[order])
    np.testing.assert_array_equal(g[1003:], f[order])


def test_breusch_pagan_separates_constant_from_growing_variance():
    rng = np.random.default_rng(8)
    vbsa = rng.uniform(0.3, 1.2, 1500)
    folds = np.arange(1500) % 10
    homo = fit_arrays("linear", 2.5 * vbsa + 0.1 + rng.normal(0, 0.03, 1500), vbsa, {}, folds)
    hetero = fit_arrays("linear", 2.5 * vbsa + 0.1 + rng.normal(0, 0.06, 1500) * vbsa**2, vbsa, {}, folds)
    assert homo.bp_pvalue > 0.01
    assert hetero.bp_pvalue < 1e-6
    # weighting by 1/VBSA^2 removes heteroscedasticity whose sd grows like VBSA
    wls = fit_arrays("wls", 2.5 * vbsa + 0.1 + rng.normal(0, 0.03, 1500) * vbsa, vbsa, {}, folds)
    assert wls.bp_pvalue > 0.01


def test_too_little_data_or_a_bad_domain_cannot_be_fitted():
    df = linear_law(11, seed=9)
    with pytest.raises(CannotFit, match="11 rows < k \\+ p = 10 \\+ 2"):
        fit_view(df, "vbsa_visible_m2", (), "linear", k=10)
    fit_view(linear_law(12, seed=9), "vbsa_visible_m2", (), "linear", k=10)  # 12 = k + p is enough
    bad = linear_law(50, seed=10)
    bad.loc[0, "vbsa_visible_m2"] = 0.0
    with pytest.raises(CannotFit, match="positive"):
        fit_view(bad, "vbsa_visible_m2", (), "loglog", k=5)
    const = linear_law(50, seed=11).assign(stature_m=1.7)
    with pytest.raises(CannotFit, match="rank deficient"):
        fit_view(const, "vbsa_visible_m2", ("stature_m",), "linear", k=5)
