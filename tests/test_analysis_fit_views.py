"""All views × groups × models: table shape, group partitions, skips, reproducibility, input errors."""

import numpy as np
import pandas as pd
import pytest

from wbsa.analysis.fit_views import FIT_KEYS, FitSettings, fit_all, fit_views
from wbsa.analysis.regression import fit_view
from helpers.synthetic import synthetic_population, synthetic_scan
from wbsa.errors import WbsaError

VIEWS = [(0.0, 0.0), (60.0, 30.0), (0.0, 90.0)]


@pytest.fixture(scope="module")
def tables():
    pop = synthetic_population(400, seed=11)
    return pop, synthetic_scan(pop, VIEWS, seed=11)


@pytest.fixture(scope="module")
def result(tables):
    pop, scan = tables
    return fit_all(pop, scan, FitSettings(models=("linear", "wls"), k=5, seed=3))


def test_one_row_per_group_model_predictors_and_view(result):
    fits = result.fits
    assert len(fits) + len(result.skipped) == 8 * 2 * 2 * len(VIEWS)
    assert not fits.duplicated(list(FIT_KEYS)).any()
    assert set(fits["predictors"]) == {"vbsa", "vbsa+stature_m"}
    for col in ("n", "c0", "c0_se", "c0_t", "c1", "c1_se", "c1_t", "r2", "rse_m2", "cv_rmse_m2", "cv_mspe_m4",
                "cv_mape_pct", "bp_stat", "bp_pvalue", "c_stature_m", "c_stature_m_se", "c_stature_m_t"):
        assert col in fits.columns, col
    with_stature = fits["predictors"] == "vbsa+stature_m"
    assert fits.loc[with_stature, "c_stature_m"].notna().all()
    assert fits.loc[~with_stature, "c_stature_m"].isna().all()
    np.testing.assert_allclose(fits["cv_rmse_m2"] ** 2, fits["cv_mspe_m4"], rtol=1e-12)
    # rows come grouped as the paper's S1 tables: group, then model
    assert list(dict.fromkeys(fits["group"])) == [g for g in FitSettings().groups if g in set(fits["group"])]


def test_groups_partition_the_fitted_subjects(result, tables):
    pop, scan = tables
    fits = result.fits.set_index(["model", "predictors", "azimuth_deg", "elevation_deg", "group"])["n"]
    n_all = fits.xs("all", level="group")
    for parts in (("males", "females"), ("kids", "adults"), ("small", "normal", "big")):
        total = sum(fits.xs(p, level="group") for p in parts)
        pd.testing.assert_series_equal(total.sort_index(), n_all.sort_index(), check_names=False)
    # subjects taller than the synthetic frame limit are left out, and counted
    tall = int((pop["stature_m"] > 2.25).sum())
    assert tall > 0
    assert (result.fits.loc[result.fits["group"] == "all", "n"] == len(pop) - tall).all()
    assert (result.fits.loc[result.fits["group"] == "all", "n_excluded"] == tall).all()


def test_matches_a_direct_single_view_fit(result, tables):
    pop, scan = tables
    rows = scan[(scan["azimuth_deg"] == 60) & (scan["elevation_deg"] == 30) & scan["fits_in_frame"]]
    df = rows.merge(pop[["subject_id", "wbsa_m2", "stature_m", "age_years"]], on="subject_id")
    kids = df[df["age_years"] <= 15]
    direct = fit_view(kids, "vbsa_visible_m2", ("stature_m",), "linear", k=5, seed=3)
    row = result.fits.query("group == 'kids' and model == 'linear' and predictors == 'vbsa+stature_m' "
                            "and azimuth_deg == 60 and elevation_deg == 30").iloc[0]
    assert row["n"] == direct.n
    assert row["c1"] == pytest.approx(direct.params[1], rel=1e-12)
    assert row["cv_rmse_m2"] == pytest.approx(direct.cv["cv_rmse_m2"], rel=1e-12)


def test_subgroup_cv_of_the_all_model(result):
    sub = result.subgroup_cv
    allrows = sub[sub["group"] == "all"].merge(result.fits[result.fits["group"] == "all"],
                                               on=[k for k in FIT_KEYS], suffixes=("", "_fit"))
    np.testing.assert_allclose(allrows["cv_rmse_m2"], allrows["cv_rmse_m2_fit"], rtol=1e-12)
    assert {"obese", "big", "kids"} <= set(sub["group"])
    # MSPE over a partition is the n-weighted mean of the parts' MSPE
    key = ["model", "predictors", "azimuth_deg", "elevation_deg"]
    parts = sub[sub["group"].isin(["kids", "adults"])]
    pooled = (parts["cv_mspe_m4"] * parts["n"]).groupby([parts[k] for k in key]).sum() / parts.groupby(key)["n"].sum()
    whole = sub[sub["group"] == "all"].set_index(key)["cv_mspe_m4"]
    np.testing.assert_allclose(pooled.sort_index().to_numpy(), whole.sort_index().to_numpy(), rtol=1e-10)


def test_residual_and_qq_tables(result):
    res = result.residuals
    assert set(res["group"].astype(str)) == {"all"} and set(res["model"].astype(str)) == {"linear"}
    np.testing.assert_allclose(res["residual_m2"], res["wbsa_m2"] - res["fitted_m2"], atol=1e-12)
    n = result.fits.query("group == 'all' and model == 'linear'")["n"].sum()
    assert len(res) == n
    qq = result.qq
    assert len(qq) == len(result.fits) * 99
    for _, part in qq.groupby(list(FIT_KEYS), observed=True):
        assert np.all(np.diff(part["sample"].to_numpy()) >= 0)
        assert np.all(np.diff(part["theoretical"].to_numpy()) > 0)


def test_small_groups_are_skipped_with_a_reason(tables):
    pop, scan = tables
    pop = pop.copy()
    pop["stature_m"] = np.minimum(pop["stature_m"], 1.99)
    pop.loc[:4, "stature_m"] = 2.05  # 5 big subjects < k + p
    out = fit_all(pop, scan, FitSettings(models=("linear",), predictor_sets=((),), k=5,
                                         groups=("all", "big")))
    assert set(out.fits["group"]) == {"all"}
    assert len(out.skipped) == len(VIEWS)
    assert out.skipped["reason"].str.contains("rows < k \\+ p = 5 \\+ 2").all()


def test_same_seed_same_table_whatever_the_row_order(tables):
    pop, scan = tables
    settings = FitSettings(models=("linear", "loglog"), k=4, seed=9, groups=("all", "adults"))
    a = fit_views(pop, scan, settings)
    b = fit_views(pop.sample(frac=1, random_state=1), scan.sample(frac=1, random_state=2), settings)
    pd.testing.assert_frame_equal(a, b)
    c = fit_views(pop, scan, FitSettings(models=("linear", "loglog"), k=4, seed=10, groups=("all", "adults")))
    assert not np.allclose(a["cv_rmse_m2"], c["cv_rmse_m2"])
    np.testing.assert_allclose(a["c1"], c["c1"])  # the full fit does not depend on the folds


def test_several_vbsa_columns_and_aliases(tables):
    pop, scan = tables
    out = fit_all(pop, scan, FitSettings(vbsa_columns=("vbsa_hit_m2", "vbsa_visible_m2"), models=("linear",),
                                         predictor_sets=(("stature", "mass"),), k=3, groups=("all",)))
    assert set(out.fits["vbsa_column"]) == {"vbsa_hit_m2", "vbsa_visible_m2"}
    assert set(out.fits["predictors"]) == {"vbsa+stature_m+mass_kg"}
    hit = out.fits[out.fits["vbsa_column"] == "vbsa_hit_m2"].reset_index(drop=True)
    vis = out.fits[out.fits["vbsa_column"] == "vbsa_visible_m2"].reset_index(drop=True)
    np.testing.assert_allclose(hit["c1"] * 1.02, vis["c1"], rtol=1e-9)  # hit = 1.02 * visible


def test_bad_inputs_are_user_errors(tables):
    pop, scan = tables
    with pytest.raises(WbsaError, match="missing from the population"):
        fit_views(pop[pop["subject_id"] > 5], scan, FitSettings(k=3))
    with pytest.raises(WbsaError, match="vbsa_recon_grid_m2"):
        fit_views(pop, scan, FitSettings(vbsa_columns=("vbsa_recon_m2:grid",), k=3))
    with pytest.raises(WbsaError, match="several rows for one subject"):
        fit_views(pop, pd.concat([scan, scan.iloc[:1]]), FitSettings(k=3))
    with pytest.raises(WbsaError, match="not a population column"):
        fit_views(pop, scan, FitSettings(predictor_sets=(("shoe_size",),), k=3))
    with pytest.raises(WbsaError, match="models must be one of"):
        FitSettings(models=("spline",))
    with pytest.raises(WbsaError, match="k must be at least 2 folds"):
        FitSettings(k=1)
