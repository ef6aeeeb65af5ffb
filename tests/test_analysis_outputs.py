"""Correlation matrix, formulae comparison, model-kind summary and the ``wbsa fit`` command end to end."""

import json

import numpy as np
import pandas as pd
import pytest

from wbsa.analysis.correlation import spearman_matrix
from wbsa.analysis.formulae_comparison import (
    KIND_ALL_MODEL,
    KIND_FORMULA,
    KIND_GROUP_MODEL,
    best_worst_views,
    formula_errors,
)
from wbsa.analysis.model_file import WbsaModel
from wbsa.analysis.summary import model_summary
from helpers.synthetic import synthetic_population, synthetic_scan
from wbsa.cli import main
from wbsa.errors import WbsaError

VIEWS = [(0.0, 0.0), (90.0, 0.0), (45.0, 45.0)]


@pytest.fixture(scope="module")
def tables():
    pop = synthetic_population(300, seed=31)
    return pop, synthetic_scan(pop, VIEWS, seed=31)


def test_spearman_matrix_equals_scipy(tables):
    from scipy.stats import spearmanr

    pop, scan = tables
    m = spearman_matrix(pop, scan, "vbsa_visible_m2", 90, 0)
    assert list(m.columns[:3]) == ["stature_m", "wbsa_m2", "vbsa_visible_m2"]
    np.testing.assert_allclose(np.diag(m), 1.0)
    np.testing.assert_allclose(m.to_numpy(), m.to_numpy().T)
    rows = scan[(scan["azimuth_deg"] == 90) & (scan["elevation_deg"] == 0) & scan["fits_in_frame"]]
    df = rows.merge(pop, on="subject_id")
    rho = spearmanr(df["wbsa_m2"], df["vbsa_visible_m2"]).statistic
    assert m.loc["wbsa_m2", "vbsa_visible_m2"] == pytest.approx(rho, rel=1e-12)
    rho_sex = spearmanr(df["wbsa_m2"], (df["sex"] == "male").astype(float)).statistic
    assert m.loc["wbsa_m2", "sex_male"] == pytest.approx(rho_sex, rel=1e-12)
    with pytest.raises(WbsaError, match="no view at azimuth 30"):
        spearman_matrix(pop, scan, "vbsa_visible_m2", 30, 0)


def test_a_formula_that_is_the_truth_has_no_error():
    from wbsa.formulae import bsa

    pop = synthetic_population(500, seed=32)
    pop["wbsa_m2"] = bsa("mosteller", pop["stature_m"] * 100, pop["mass_kg"], check=False)
    errors = formula_errors(pop)
    mosteller = errors[errors["method"] == "mosteller"].set_index("group")
    np.testing.assert_allclose(mosteller["mape_pct"], 0.0, atol=1e-9)
    np.testing.assert_allclose(mosteller["bias_m2"], 0.0, atol=1e-12)
    # another formula: the table equals the direct computation
    dubois = bsa("dubois", pop["stature_m"] * 100, pop["mass_kg"], check=False)
    kids = pop["age_years"] <= 15
    rel = (dubois[kids] - pop["wbsa_m2"][kids]) / pop["wbsa_m2"][kids]
    row = errors.query("group == 'kids' and method == 'dubois'").iloc[0]
    assert row["mape_pct"] == pytest.approx(100 * np.mean(np.abs(rel)), rel=1e-12)
    assert row["bias_pct"] == pytest.approx(100 * np.mean(rel), rel=1e-12)
    assert row["n"] == kids.sum()
    assert "schlich" in set(errors["method"])  # sex given: one Schlich column
    assert {"all", "kids", "adults", "obese", "big"} <= set(errors["group"])


def test_best_and_worst_views_are_the_extremes():
    t = pd.DataFrame({"group": "all", "model": "linear", "predictors": "vbsa", "vbsa_column": "v", "camera": "c",
                      "distance_m": 4.3, "azimuth_deg": [0.0, 60.0, 90.0], "elevation_deg": 0.0, "n": 10,
                      "cv_mape_pct": [1.5, 4.0, 0.7], "cv_bias_m2": 0.0, "cv_rmse_m2": [0.02, 0.05, 0.01]})
    bw = best_worst_views(t, KIND_GROUP_MODEL).set_index("view")
    assert bw.loc["best", "azimuth_deg"] == 90.0 and bw.loc["best", "mape_pct"] == 0.7
    assert bw.loc["worst", "azimuth_deg"] == 60.0 and bw.loc["worst", "mape_pct"] == 4.0


def test_model_summary_ratio_to_linear():
    t = pd.DataFrame({"group": "big", "model": ["linear", "wls"] * 2, "predictors": "vbsa", "vbsa_column": "v",
                      "camera": "c", "distance_m": 4.3, "azimuth_deg": [0.0, 0.0, 60.0, 60.0], "elevation_deg": 0.0,
                      "cv_rmse_m2": [0.04, 0.02, 0.05, 0.06], "cv_mape_pct": 1.0, "bp_pvalue": [0.001, 0.5, 0.2, 0.3]})
    s = model_summary(t).set_index("model")
    assert s.loc["wls", "rmse_ratio"] == pytest.approx((0.5 + 1.2) / 2)
    assert s.loc["wls", "views_better"] == 1 and s.loc["linear", "views_better"] == 0
    assert s.loc["linear", "heteroscedastic_views"] == 1


def test_wbsa_fit_writes_every_table(tables, tmp_path):
    pop, scan = tables
    pop.to_parquet(tmp_path / "pop.parquet")
    scan.to_parquet(tmp_path / "scan.parquet")
    out = tmp_path / "fit"
    rc = main(["fit", str(tmp_path / "pop.parquet"), str(tmp_path / "scan.parquet"), "--out", str(out),
               "--k", "5", "--models", "linear,loglog", "--groups", "all,kids,adults,big",
               "--predictors", "stature", "--predictors", "stature,waist_circ_m", "--correlation-view", "90,0"])
    assert rc == 0
    fits = pd.read_parquet(out / "fits.parquet")
    assert set(fits["predictors"]) == {"vbsa", "vbsa+stature_m", "vbsa+stature_m+waist_circ_m"}
    pd.testing.assert_frame_equal(pd.read_csv(out / "fits.csv"), fits, check_dtype=False)
    sheets = pd.read_excel(out / "fits.xlsx", sheet_name=None)
    assert list(sheets) == ["all", "kids", "adults", "big"]
    assert sum(len(s) for s in sheets.values()) == len(fits)
    model = WbsaModel.load(out / "model.json")
    assert model.meta["population_kind"] == "pop"
    wbsa, lo, hi = model.predict(90, 0, 0.4, stature_m=1.7, extras={"waist_circ_m": 0.8}, group="adults")
    assert lo < wbsa < hi
    corr = pd.read_csv(out / "correlation.csv")
    assert corr.loc[0, "azimuth_deg"] == 90 and corr.loc[0, "variable"] == "stature_m"
    comp = pd.read_parquet(out / "formulae_comparison.parquet")
    assert {KIND_FORMULA, KIND_ALL_MODEL, KIND_GROUP_MODEL} == set(comp["kind"])
    assert set(comp.loc[comp["kind"] == KIND_ALL_MODEL, "group"]) >= {"all", "kids", "adults", "obese", "big"}
    assert set(pd.read_excel(out / "formulae_comparison.xlsx", sheet_name=None)) >= {"all", "kids", "obese"}
    for name in ("residuals.parquet", "qq.parquet", "subgroup_cv.parquet", "model_summary.csv",
                 "model_comparison.csv", "skipped.csv", "correlation.xlsx"):
        assert (out / name).is_file(), name
    info = json.loads((out / "fit_info.json").read_text())
    assert info["settings"]["k"] == 5 and info["info"]["n_views"] == len(VIEWS)


@pytest.mark.parametrize("extra,message", [
    (["--models", "spline"], "models must be one of 'linear'"),
    (["--groups", "giants"], "groups must be one of 'all'"),
    (["--correlation-view", "30,0"], "no view at azimuth 30"),
    (["--stature-cuts", "2.1,1.4"], "stature cuts 0 < small < big"),
    (["--vbsa", "vbsa_recon_m2:poisson"], "vbsa_recon_poisson_m2"),
    (["--predictors", "shoe_size"], "not a population column"),
    (["--k", "1000"], "no model could be fitted"),
])
def test_bad_arguments_exit_2_with_one_line(tables, tmp_path, capsys, extra, message):
    pop, scan = tables
    pop.to_parquet(tmp_path / "pop.parquet")
    scan.to_parquet(tmp_path / "scan.parquet")
    rc = main(["fit", str(tmp_path / "pop.parquet"), str(tmp_path / "scan.parquet"), "--out", str(tmp_path / "o"),
               "--k", "3", *extra])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.startswith("error: ") and message in err and err.count("\n") == 1
