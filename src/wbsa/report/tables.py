"""The report's tables computed from the study's tables: groups, distances, stages and settings."""

from __future__ import annotations

import numpy as np
import pandas as pd

from wbsa.report.claim import group_spec_of
from wbsa.report.data import ReportData, select
from wbsa.report.sources import ReportSources


def population_table(population: pd.DataFrame, fit_info: dict) -> pd.DataFrame:
    """Counts, WBSA (m²) and stature (m) of every group (paper Table 1)."""
    from wbsa.analysis.groups import GROUP_NAMES, assign_groups

    spec = group_spec_of(fit_info)
    members = assign_groups(population.reset_index(drop=True), spec)
    desc = spec.describe()
    rows = []
    w = population["wbsa_m2"].to_numpy(float)
    s = population["stature_m"].to_numpy(float)
    a = population["age_years"].to_numpy(float)
    for g in GROUP_NAMES:
        m = members[g].to_numpy()
        n = int(m.sum())
        rows.append({"group": g, "definition": desc[g], "subjects": n,
                     "wbsa_mean_m2": w[m].mean() if n else np.nan, "wbsa_sd_m2": w[m].std(ddof=1) if n > 1 else np.nan,
                     "wbsa_min_m2": w[m].min() if n else np.nan, "wbsa_max_m2": w[m].max() if n else np.nan,
                     "stature_mean_m": s[m].mean() if n else np.nan,
                     "age_range_years": f"{a[m].min():.0f}–{a[m].max():.0f}" if n else ""})
    return pd.DataFrame(rows)


def group_table(d: ReportData) -> pd.DataFrame:
    """Per group and predictor set: median n and mean / min / max CV RMSE over the views."""
    sub = select(d.fits, model=d.model, vbsa_column=d.vbsa_column, distance_m=d.distance_m, camera=d.camera)
    g = sub.groupby(["group", "predictors"], sort=False).agg(
        views=("cv_rmse_m2", "size"), median_n=("n", "median"), mean_cv_rmse_m2=("cv_rmse_m2", "mean"),
        min_cv_rmse_m2=("cv_rmse_m2", "min"), max_cv_rmse_m2=("cv_rmse_m2", "max"),
        mean_cv_mape_pct=("cv_mape_pct", "mean"))
    return g.reset_index()


def distance_table(d: ReportData) -> pd.DataFrame:
    """Per distance: share of scan rows inside the frame, fitted subjects, CV RMSE over views."""
    rows = []
    fits = select(d.fits, group="all", model=d.model, predictors="vbsa", vbsa_column=d.vbsa_column, camera=d.camera)
    for dist in d.distances_m:
        sc = select(d.scan, distance_m=float(dist), camera=d.camera)
        f = select(fits, distance_m=float(dist))
        rows.append({"distance_m": dist,
                     "in_frame_pct": 100 * sc["fits_in_frame"].mean() if "fits_in_frame" in sc and len(sc) else np.nan,
                     "views": len(f), "median_n": f["n"].median() if len(f) else np.nan,
                     "mean_cv_rmse_m2": f["cv_rmse_m2"].mean() if len(f) else np.nan,
                     "max_cv_rmse_m2": f["cv_rmse_m2"].max() if len(f) else np.nan,
                     "mean_c1": f["c1"].mean() if len(f) else np.nan})
    return pd.DataFrame(rows)


def stage_table(sources: ReportSources) -> pd.DataFrame:
    """Stages with key, time to compute and reuse flag (from the manifest and the stage records)."""
    stages = sources.manifest.get("stages", [])
    if stages:
        rows = [{"stage": s.get("name"), "folder": s.get("path"), "computed_in_s": s.get("seconds_computed"),
                 "this_run_s": s.get("seconds_this_run"), "reused": bool(s.get("reused")),
                 "result": s.get("summary", "")} for s in stages]
        rows.append({"stage": "whole run (before the report)", "folder": "", "computed_in_s": np.nan,
                     "this_run_s": sources.manifest.get("seconds"), "reused": False, "result": ""})
        return pd.DataFrame(rows)
    rows = [{"stage": r.get("label", r.get("stage")), "folder": f"{r.get('stage')}-{r.get('key')}",
             "computed_in_s": r.get("seconds"),
             "result": r["info"].get("summary", "") if isinstance(r.get("info"), dict) else ""}
            for r in sources.stage_records]
    if not rows:
        rows = [{"stage": "fit", "folder": str(sources.fit_dir), "computed_in_s": np.nan, "result": ""}]
    return pd.DataFrame(rows)


def settings_table(sources: ReportSources, fit_info: dict) -> pd.DataFrame:
    """Every setting as (section, key, value)."""
    settings = sources.manifest.get("settings")
    if not settings:
        settings = {"fit": fit_info.get("settings", {})}
    rows = []
    for section, table in settings.items():
        for key, value in (table or {}).items():
            rows.append({"section": section, "key": key, "value": _show(value)})
    for i, p in enumerate(sources.scan_paths):
        rows.append({"section": "inputs", "key": f"scan[{i}]", "value": str(p)})
    rows.append({"section": "inputs", "key": "population", "value": str(sources.population_path)})
    rows.append({"section": "inputs", "key": "fit", "value": str(sources.fit_dir)})
    return pd.DataFrame(rows)


def _show(value) -> str:
    if isinstance(value, dict):
        return ", ".join(f"{k} = {_show(v)}" for k, v in value.items())
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_show(v) for v in value) + "]"
    return str(value)

