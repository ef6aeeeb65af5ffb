"""Paper Fig 10 / S1 Fig and Fig 16: VBSA against WBSA at one view, with the fitted lines and residuals."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from wbsa.report.data import nearest_view, select
from wbsa.report.figures.style import DM2, LEGEND_FONTSIZE, FigureUnavailable, new_figure


def view_table(population: pd.DataFrame, scan: pd.DataFrame, vbsa_column: str, azimuth_deg: float,
               elevation_deg: float, distance_m: float, camera: str) -> pd.DataFrame:
    """Subjects at one view: ``subject_id``, ``vbsa_m2``, ``wbsa_m2``, ``fits_in_frame``, ``stature_m``."""
    if vbsa_column not in scan.columns:
        raise FigureUnavailable(f"the scan has no column {vbsa_column}")
    rows = select(scan, azimuth_deg=float(azimuth_deg), elevation_deg=float(elevation_deg),
                  distance_m=float(distance_m), camera=camera)
    if rows.empty:
        raise FigureUnavailable(f"the scan has no view at azimuth {azimuth_deg:g}°, elevation {elevation_deg:g}°")
    cols = ["subject_id", vbsa_column] + (["fits_in_frame"] if "fits_in_frame" in rows else [])
    t = rows[cols].rename(columns={vbsa_column: "vbsa_m2"})
    if "fits_in_frame" not in t:
        t["fits_in_frame"] = True
    t = t.merge(population[["subject_id", "wbsa_m2", "stature_m"]], on="subject_id", how="inner")
    return t[np.isfinite(t["vbsa_m2"].to_numpy(float))]


def _fit_row(fits: pd.DataFrame, **keys) -> pd.Series:
    rows = select(fits, **keys)
    if rows.empty:
        raise FigureUnavailable("no fit for " + ", ".join(f"{k} = {v}" for k, v in keys.items()))
    return rows.iloc[0]


def vbsa_wbsa_scatter(population: pd.DataFrame, scan: pd.DataFrame, fits: pd.DataFrame, *, view: tuple[float, float],
                      distance_m: float, camera: str, vbsa_column: str, model: str = "linear", dpi: int = 100) -> Figure:
    """VBSA against WBSA at one view with the fitted line (paper Fig 10 and S1 Fig).

    The line is the all-subjects VBSA-only fit of ``fits`` (``model``, usually linear): WBSA = c1·VBSA + c0.
    Bodies cut by the image border are drawn as crosses (they are left out of the fit when the fit
    requires the body in the frame).
    """
    az, el = nearest_view(select(fits, distance_m=float(distance_m), camera=camera), *view)
    t = view_table(population, scan, vbsa_column, az, el, distance_m, camera)
    row = _fit_row(fits, group="all", model=model, predictors="vbsa", vbsa_column=vbsa_column, camera=camera,
                   distance_m=float(distance_m), azimuth_deg=az, elevation_deg=el)
    fig = new_figure(6.4, 4.8, dpi)
    ax = fig.subplots()
    inside = t["fits_in_frame"].fillna(False).to_numpy(bool)
    ax.scatter(t.loc[inside, "vbsa_m2"] * DM2, t.loc[inside, "wbsa_m2"] * DM2, s=10, alpha=0.7, label="subjects")
    if (~inside).any():
        ax.scatter(t.loc[~inside, "vbsa_m2"] * DM2, t.loc[~inside, "wbsa_m2"] * DM2, s=14, marker="x", color="grey",
                   label=f"cut by the frame ({int((~inside).sum())})")
    x = np.linspace(t["vbsa_m2"].min(), t["vbsa_m2"].max(), 50)
    if model == "linear":
        y = row["c0"] + row["c1"] * x
        text = f"WBSA = {row['c1']:.3f}·VBSA {'+' if row['c0'] >= 0 else '−'} {abs(row['c0']) * DM2:.2f} dm²"
    elif model == "loglog":
        y = np.exp(row["c0"]) * x ** row["c1"]
        text = f"log WBSA = {row['c1']:.3f}·log VBSA + {row['c0']:.3f}"
    else:
        y = row["c0"] + row["c1"] * x + (row.get("c_vbsa_sq", 0.0) if pd.notna(row.get("c_vbsa_sq", np.nan)) else 0.0) * x**2
        text = f"{model}: c1 = {row['c1']:.3f}, c0 = {row['c0'] * DM2:.2f} dm²"
    ax.plot(x * DM2, y * DM2, color="C3", lw=1.5, label=f"{model} fit")
    ax.set_xlabel(f"VBSA (dm²), {vbsa_column}")
    ax.set_ylabel("WBSA (dm²)")
    ax.set_title(f"θ = {az:g}°, φ = {el:g}°, D = {distance_m:g} m, {camera}", fontsize=10)
    ax.text(0.02, 0.98, f"{text}\nR² = {row['r2']:.4f}, n = {int(row['n'])}\n"
            f"CV RMSE = {row['cv_rmse_m2'] * DM2:.2f} dm², CV MAPE = {row['cv_mape_pct']:.2f} %",
            transform=ax.transAxes, va="top", fontsize=8.5, bbox=dict(boxstyle="round", fc="white", alpha=0.85))
    ax.legend(loc="lower right", fontsize=LEGEND_FONTSIZE)
    ax.grid(True, alpha=0.3)
    return fig


def nonlinear_view(population: pd.DataFrame, scan: pd.DataFrame, fits: pd.DataFrame, *, view: tuple[float, float],
                   distance_m: float, camera: str, vbsa_column: str, dpi: int = 100) -> Figure:
    """The VBSA–WBSA relation at an occluded view (paper Fig 16, θ = 60°, φ = 60°) and its residuals.

    Left: the scatter with the linear fit and, where fitted, the log-log power law. Right: residuals
    WBSA − (c1·VBSA + c0) against WBSA, with the Breusch–Pagan p-value of the fit (small p: the
    variance grows with the body, i.e. heteroscedasticity).
    """
    az, el = nearest_view(select(fits, distance_m=float(distance_m), camera=camera), *view)
    t = view_table(population, scan, vbsa_column, az, el, distance_m, camera)
    lin = _fit_row(fits, group="all", model="linear", predictors="vbsa", vbsa_column=vbsa_column, camera=camera,
                   distance_m=float(distance_m), azimuth_deg=az, elevation_deg=el)
    fig = new_figure(10.0, 4.2, dpi)
    ax, ax2 = fig.subplots(1, 2)
    inside = t["fits_in_frame"].fillna(False).to_numpy(bool)
    t = t[inside]
    v, w = t["vbsa_m2"].to_numpy(float), t["wbsa_m2"].to_numpy(float)
    ax.scatter(v * DM2, w * DM2, s=10, alpha=0.7, label="subjects")
    x = np.linspace(v.min(), v.max(), 60)
    ax.plot(x * DM2, (lin["c0"] + lin["c1"] * x) * DM2, color="C3", label=f"linear (c1 = {lin['c1']:.3f})")
    ll = select(fits, group="all", model="loglog", predictors="vbsa", vbsa_column=vbsa_column, camera=camera,
                distance_m=float(distance_m), azimuth_deg=az, elevation_deg=el)
    if len(ll):
        r = ll.iloc[0]
        ax.plot(x * DM2, np.exp(r["c0"]) * x ** r["c1"] * DM2, color="C2", ls="--",
                label=f"log-log power law (exponent {r['c1']:.3f})")
    ax.set_xlabel(f"VBSA (dm²), {vbsa_column}")
    ax.set_ylabel("WBSA (dm²)")
    ax.set_title(f"θ = {az:g}°, φ = {el:g}°, D = {distance_m:g} m", fontsize=10)
    ax.legend(fontsize=LEGEND_FONTSIZE)
    ax.grid(True, alpha=0.3)
    resid = w - (lin["c0"] + lin["c1"] * v)
    ax2.scatter(w * DM2, resid * DM2, s=10, alpha=0.7)
    ax2.axhline(0.0, color="k", lw=0.8)
    ax2.set_xlabel("WBSA (dm²)")
    ax2.set_ylabel("residual WBSA − fit (dm²)")
    bp = lin.get("bp_pvalue", np.nan)
    ax2.set_title(f"linear-fit residuals: RSE {lin['rse_m2'] * DM2:.2f} dm², Breusch–Pagan p = {bp:.2g}", fontsize=10)
    ax2.grid(True, alpha=0.3)
    return fig

