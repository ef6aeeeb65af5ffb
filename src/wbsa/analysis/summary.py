"""Model kinds side by side: does a non-linear or weighted model beat the linear one (paper section 4.2)?"""

from __future__ import annotations

import numpy as np
import pandas as pd

_SETTING = ["group", "predictors", "vbsa_column", "camera", "distance_m"]
_VIEW = ["azimuth_deg", "elevation_deg"]


def model_comparison(table: pd.DataFrame) -> pd.DataFrame:
    """Per view, the CV errors of every model kind in one row.

    Parameters
    ----------
    table : DataFrame
        Fit table or subgroup CV table (``group``, ``model``, ``predictors``, ``vbsa_column``, ``camera``,
        ``distance_m``, ``azimuth_deg``, ``elevation_deg``, ``cv_rmse_m2``, ``cv_mape_pct``).

    Returns
    -------
    DataFrame
        One row per group × predictors × VBSA column × camera × distance × view with
        ``cv_rmse_m2_<model>``, ``cv_mape_pct_<model>`` for every model and ``best_model`` (lowest CV RMSE).
    """
    if table.empty:
        return pd.DataFrame(columns=[*_SETTING, *_VIEW, "best_model"])
    t = table.copy()
    for c in ("group", "model", "predictors", "vbsa_column", "camera"):
        t[c] = t[c].astype(str)
    wide = t.pivot_table(index=[*_SETTING, *_VIEW], columns="model", values=["cv_rmse_m2", "cv_mape_pct"],
                         aggfunc="first", sort=False)
    rmse = wide["cv_rmse_m2"]
    out = pd.DataFrame(index=wide.index)
    for metric in ("cv_rmse_m2", "cv_mape_pct"):
        for model in wide[metric].columns:
            out[f"{metric}_{model}"] = wide[(metric, model)]
    out["best_model"] = rmse.idxmin(axis=1, skipna=True) if rmse.notna().any().any() else np.nan
    return out.reset_index()


def model_summary(table: pd.DataFrame, reference: str = "linear", alpha: float = 0.05) -> pd.DataFrame:
    """Per group and model kind, the CV errors over all views, relative to the ``reference`` model.

    Returns
    -------
    DataFrame
        One row per group × predictors × VBSA column × camera × distance × model: ``n_views``,
        ``mean_cv_rmse_m2``, ``max_cv_rmse_m2``, ``mean_cv_mape_pct``, ``rmse_ratio`` (mean over views of
        CV RMSE / reference CV RMSE), ``views_better`` (views where it beats the reference),
        ``heteroscedastic_views`` (views with Breusch–Pagan p < ``alpha``; fit tables only).
    """
    if table.empty:
        return pd.DataFrame(columns=[*_SETTING, "model"])
    t = table.copy()
    for c in ("group", "model", "predictors", "vbsa_column", "camera"):
        t[c] = t[c].astype(str)
    ref = t[t["model"] == reference][[*_SETTING, *_VIEW, "cv_rmse_m2"]].rename(columns={"cv_rmse_m2": "_ref"})
    t = t.merge(ref, on=[*_SETTING, *_VIEW], how="left")
    t["_ratio"] = t["cv_rmse_m2"] / t["_ref"]
    t["_better"] = t["cv_rmse_m2"] < t["_ref"]
    agg = {"n_views": ("cv_rmse_m2", "size"), "mean_cv_rmse_m2": ("cv_rmse_m2", "mean"),
           "max_cv_rmse_m2": ("cv_rmse_m2", "max"), "mean_cv_mape_pct": ("cv_mape_pct", "mean"),
           "rmse_ratio": ("_ratio", "mean"), "views_better": ("_better", "sum")}
    if "bp_pvalue" in t.columns:
        t["_het"] = t["bp_pvalue"] < alpha
        agg["heteroscedastic_views"] = ("_het", "sum")
    return t.groupby([*_SETTING, "model"], sort=False).agg(**agg).reset_index()
