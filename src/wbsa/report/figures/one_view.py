"""The report's figures, one function each, drawn from the measured tables (matplotlib, no pyplot state).

Every function takes tables with the documented columns (population, scan, fit outputs; areas in m²)
and returns a :class:`matplotlib.figure.Figure`; areas are shown in dm² (the paper's unit,
1 m² = 100 dm²). A function raises :class:`FigureUnavailable` when its data are not in the tables
(e.g. no reconstruction columns), and the report then says why instead of showing the figure.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from wbsa.errors import WbsaError
from wbsa.report.data import nearest_view, select

#: m² -> dm².
DM2 = 100.0

#: Groups drawn in the group figures, in order, with their labels.
GROUP_LABELS = {"all": "all subjects", "males": "males", "females": "females", "kids": "kids", "adults": "adults",
                "small": "small stature", "normal": "normal stature", "big": "big stature", "obese": "obese (BMI ≥ 30)",
                "underweight": "underweight adults (BMI < 18.5)", "tall": "tall (≥ 1.85 m)"}


class FigureUnavailable(WbsaError):
    """The tables lack what a figure needs; the message says what."""


def predictors_title(label: str) -> str:
    """``vbsa`` -> 'VBSA only'; ``vbsa+stature_m`` -> 'VBSA + stature'."""
    extra = [p for p in label.split("+") if p != "vbsa"]
    if not extra:
        return "VBSA only"
    names = {"stature_m": "stature", "mass_kg": "mass", "age_years": "age", "sex_male": "sex"}
    return "VBSA + " + " + ".join(names.get(p, p) for p in extra)


def _fig(width: float, height: float, dpi: int) -> Figure:
    return Figure(figsize=(width, height), dpi=dpi, layout="constrained")


def _elevation_colors(elevations: list[float]):
    """Colour per elevation: black at 0, blues below (darker further down), reds above (darker further up)."""
    from matplotlib import colormaps

    out = {}
    for e in elevations:
        if abs(e) < 1e-9:
            out[e] = (0.0, 0.0, 0.0, 1.0)
        else:
            cmap = colormaps["Reds" if e > 0 else "Blues"]
            out[e] = cmap(0.4 + 0.6 * min(abs(e), 90.0) / 90.0)
    return out


def _angle_axis(ax, label: str = "Azimuth θ (deg)") -> None:
    ax.set_xlabel(label)
    ax.set_xticks([0, 30, 45, 60, 90, 120, 135, 150, 180])
    ax.grid(True, alpha=0.3)


# ---------------------------------------------------------------------------------------------------------------
# Fig 5: distribution of WBSA


def wbsa_distribution(population: pd.DataFrame, dpi: int = 100) -> Figure:
    """Histogram of WBSA (paper Fig 5), stacked by sex, with n, mean and SD.

    Parameters
    ----------
    population : DataFrame
        ``wbsa_m2`` and ``sex``; optionally ``stature_m``.
    """
    w = population["wbsa_m2"].to_numpy(float) * DM2
    w = w[np.isfinite(w)]
    if w.size == 0:
        raise FigureUnavailable("the population has no WBSA values")
    fig = _fig(9.0, 3.6, dpi)
    ax, ax2 = fig.subplots(1, 2, width_ratios=[1.3, 1])
    bins = np.histogram_bin_edges(w, bins=min(40, max(8, int(np.sqrt(w.size)))))
    sex = population["sex"].astype(str).to_numpy()
    parts = [(w_s, lab) for lab in ("male", "female") if (w_s := population.loc[sex == lab, "wbsa_m2"]
                                                           .to_numpy(float) * DM2).size]
    ax.hist([p[0] for p in parts], bins=bins, stacked=True, label=[f"{p[1]}s (n = {p[0].size})" for p in parts],
            color=["#4C72B0", "#DD8452"][:len(parts)], edgecolor="white", linewidth=0.4)
    ax.set_xlabel("WBSA (dm²)")
    ax.set_ylabel("subjects")
    ax.set_title(f"WBSA of {w.size} subjects: mean {w.mean():.0f} dm², SD {w.std(ddof=1) if w.size > 1 else 0:.0f} dm²",
                 fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    if "stature_m" in population:
        sc = ax2.scatter(population["stature_m"] * 100, population["wbsa_m2"] * DM2, s=6,
                         c=population["bmi"] if "bmi" in population else None, cmap="viridis", alpha=0.8)
        if "bmi" in population:
            fig.colorbar(sc, ax=ax2, label="BMI (kg/m²)")
        ax2.set_xlabel("stature (cm)")
        ax2.set_ylabel("WBSA (dm²)")
        ax2.set_title("WBSA against stature", fontsize=10)
        ax2.grid(True, alpha=0.3)
    else:
        ax2.set_visible(False)
    return fig


# ---------------------------------------------------------------------------------------------------------------
# Fig 10 / S1 and Fig 16: one view


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
    fig = _fig(6.4, 4.8, dpi)
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
    ax.legend(loc="lower right", fontsize=8)
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
    fig = _fig(10.0, 4.2, dpi)
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
    ax.legend(fontsize=8)
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


# ---------------------------------------------------------------------------------------------------------------
# Fig 11 / 13 / 14: coefficient and CV RMSE against azimuth, one line per elevation


def _by_view_panel(ax_rmse, ax_c1, sub: pd.DataFrame, colors: dict) -> None:
    """Draw CV RMSE and c1 against azimuth, one line per elevation; the poles as single markers."""
    for el in sorted(sub["elevation_deg"].unique()):
        part = sub[sub["elevation_deg"] == el].sort_values("azimuth_deg")
        style = dict(color=colors[el], label=f"φ = {el:g}°", ls="--" if el < 0 else "-")
        if abs(abs(el) - 90.0) < 1e-9 or len(part) == 1:
            marker = "^" if el > 0 else "v" if el < 0 else "o"
            style["ls"] = "none"
            ax_rmse.plot(part["azimuth_deg"], part["cv_rmse_m2"] * DM2, marker=marker, ms=7, **style)
            ax_c1.plot(part["azimuth_deg"], part["c1"], marker=marker, ms=7, **style)
        else:
            ax_rmse.plot(part["azimuth_deg"], part["cv_rmse_m2"] * DM2, marker="o", ms=3, **style)
            ax_c1.plot(part["azimuth_deg"], part["c1"], marker="o", ms=3, **style)


def coefficients_by_view(fits: pd.DataFrame, *, group: str, model: str, vbsa_column: str, distance_m: float,
                         camera: str, predictor_labels: list[str], dpi: int = 100) -> Figure:
    """CV RMSE (left) and the VBSA coefficient c1 (right) against azimuth, one line per elevation
    (paper Figs 11, 13, 14); one row per predictor set (VBSA only, VBSA + stature, ...).
    """
    sub = select(fits, group=group, model=model, vbsa_column=vbsa_column, distance_m=float(distance_m), camera=camera)
    labels = [p for p in predictor_labels if (sub["predictors"] == p).any()]
    if not labels:
        raise FigureUnavailable(f"no {model} fits for group {group}")
    colors = _elevation_colors(sorted(sub["elevation_deg"].unique()))
    fig = _fig(10.0, 3.3 * len(labels) + 0.4, dpi)
    axes = np.atleast_2d(fig.subplots(len(labels), 2, squeeze=False))
    for i, lab in enumerate(labels):
        part = sub[sub["predictors"] == lab]
        _by_view_panel(axes[i, 0], axes[i, 1], part, colors)
        axes[i, 0].set_ylabel("CV RMSE (dm²)")
        axes[i, 1].set_ylabel("c1, VBSA coefficient (–)")
        axes[i, 0].set_title(f"{GROUP_LABELS.get(group, group)}, {predictors_title(lab)}: CV RMSE", fontsize=10)
        axes[i, 1].set_title(f"{GROUP_LABELS.get(group, group)}, {predictors_title(lab)}: c1", fontsize=10)
        for ax in axes[i]:
            _angle_axis(ax)
    axes[0, 1].legend(fontsize=7, ncol=2, title="elevation", title_fontsize=7)
    n = int(sub["n"].median())
    fig.suptitle(f"{model} model, {vbsa_column}, D = {distance_m:g} m, {camera}, median n = {n}", fontsize=10)
    return fig


# ---------------------------------------------------------------------------------------------------------------
# Fig 12: errors by group at elevation 0


def group_errors(fits: pd.DataFrame, *, model: str, vbsa_column: str, distance_m: float, camera: str,
                 predictor_labels: list[str], elevation_deg: float = 0.0, dpi: int = 100) -> Figure:
    """CV RMSE against azimuth for every group at one elevation (paper Fig 12), without and with stature.

    Each group is fitted on its own (its own c0, c1); groups too small to fit are absent.
    """
    sub = select(fits, model=model, vbsa_column=vbsa_column, distance_m=float(distance_m), camera=camera)
    els = np.array(sorted(sub["elevation_deg"].unique()), dtype=float)
    if els.size == 0:
        raise FigureUnavailable(f"no {model} fits")
    el = float(els[np.argmin(np.abs(els - elevation_deg))])
    sub = sub[np.abs(sub["elevation_deg"] - el) < 1e-6]
    labels = [p for p in predictor_labels if (sub["predictors"] == p).any()]
    fig = _fig(5.0 * len(labels), 4.0, dpi)
    axes = np.atleast_1d(fig.subplots(1, len(labels), squeeze=False)[0])
    for ax, lab in zip(axes, labels):
        part = sub[sub["predictors"] == lab]
        for i, g in enumerate(dict.fromkeys(part["group"])):
            pg = part[part["group"] == g].sort_values("azimuth_deg")
            ax.plot(pg["azimuth_deg"], pg["cv_rmse_m2"] * DM2, marker="o", ms=3, color=f"C{i % 10}",
                    label=f"{GROUP_LABELS.get(g, g)} (n ≈ {int(pg['n'].median())})")
        ax.set_ylabel("CV RMSE (dm²)")
        ax.set_title(f"{predictors_title(lab)}, φ = {el:g}°", fontsize=10)
        _angle_axis(ax)
    axes[-1].legend(fontsize=7)
    fig.suptitle(f"CV RMSE by group ({model} model fitted per group, D = {distance_m:g} m)", fontsize=10)
    return fig


def model_comparison(fits: pd.DataFrame, *, vbsa_column: str, distance_m: float, camera: str,
                     elevation_deg: float = 0.0, dpi: int = 100) -> Figure:
    """CV RMSE against azimuth of every model kind, all subjects, VBSA only (paper section 4.2)."""
    sub = select(fits, group="all", predictors="vbsa", vbsa_column=vbsa_column, distance_m=float(distance_m),
                 camera=camera)
    models = list(dict.fromkeys(sub["model"]))
    if len(models) < 2:
        raise FigureUnavailable("only one model kind was fitted")
    fig = _fig(10.0, 4.0, dpi)
    ax, ax2 = fig.subplots(1, 2)
    els = np.array(sorted(sub["elevation_deg"].unique()), dtype=float)
    el = float(els[np.argmin(np.abs(els - elevation_deg))])
    for i, m in enumerate(models):
        pm = sub[(sub["model"] == m) & (np.abs(sub["elevation_deg"] - el) < 1e-6)].sort_values("azimuth_deg")
        ax.plot(pm["azimuth_deg"], pm["cv_rmse_m2"] * DM2, marker="o", ms=3, color=f"C{i}", label=m)
    ax.set_ylabel("CV RMSE (dm²)")
    ax.set_title(f"all subjects, VBSA only, φ = {el:g}°", fontsize=10)
    _angle_axis(ax)
    ax.legend(fontsize=8)
    ref = sub[sub["model"] == models[0]].set_index(["azimuth_deg", "elevation_deg"])["cv_rmse_m2"]
    for i, m in enumerate(models[1:], start=1):
        other = sub[sub["model"] == m].set_index(["azimuth_deg", "elevation_deg"])["cv_rmse_m2"]
        ratio = (other / ref).dropna()
        ax2.scatter(np.arange(len(ratio)), ratio.to_numpy(), s=12, color=f"C{i}", label=f"{m} / {models[0]}")
    ax2.axhline(1.0, color="k", lw=0.8)
    ax2.set_xlabel("view (sorted by azimuth, then elevation)")
    ax2.set_ylabel(f"CV RMSE ratio to {models[0]} (–)")
    ax2.set_title("every view: below 1 = better than the first model", fontsize=10)
    ax2.legend(fontsize=8)
    ax2.grid(True, alpha=0.3)
    return fig


# ---------------------------------------------------------------------------------------------------------------
# S2: residual diagnostics


def residual_diagnostics(residuals: pd.DataFrame, qq: pd.DataFrame, *, view: tuple[float, float], model: str,
                         vbsa_column: str, distance_m: float, camera: str, dpi: int = 100) -> Figure:
    """Residual analysis of the all-subjects VBSA-only fit at one view (paper S2 Fig):
    (a) normal QQ plot, (b) residuals against fitted values, (c) histogram, (d) scale–location.
    """
    if residuals.empty:
        raise FigureUnavailable("the fit kept no per-subject residuals (residual_groups/residual_models)")
    keys = dict(group="all", model=model, predictors="vbsa", vbsa_column=vbsa_column, distance_m=float(distance_m),
                camera=camera)
    r_all = select(residuals, **keys)
    if r_all.empty:
        raise FigureUnavailable(f"no residuals kept for the all-subjects {model} VBSA-only fit")
    az, el = nearest_view(r_all, *view)
    r = select(r_all, azimuth_deg=az, elevation_deg=el)
    q = select(qq, **keys, azimuth_deg=az, elevation_deg=el) if not qq.empty else qq
    fig = _fig(9.0, 7.0, dpi)
    (a, b), (c, d) = fig.subplots(2, 2)
    std = r["standardized"].to_numpy(float)
    if len(q):
        a.scatter(q["theoretical"], q["sample"], s=10)
        lim = [float(np.nanmin(q["theoretical"])), float(np.nanmax(q["theoretical"]))]
    else:
        from scipy import stats

        s = np.sort(std[np.isfinite(std)])
        th = stats.norm.ppf((np.arange(s.size) + 0.5) / s.size)
        a.scatter(th, s, s=10)
        lim = [float(th.min()), float(th.max())]
    a.plot(lim, lim, color="C3", lw=1)
    a.set_xlabel("standard normal quantile")
    a.set_ylabel("standardized residual quantile")
    a.set_title("(a) normal QQ plot", fontsize=10)
    fitted = r["fitted_m2"].to_numpy(float) * DM2
    res = r["residual_m2"].to_numpy(float) * DM2
    b.scatter(fitted, res, s=8, alpha=0.7)
    b.axhline(0, color="k", lw=0.8)
    b.set_xlabel("fitted WBSA (dm²)")
    b.set_ylabel("residual (dm²)")
    b.set_title("(b) residuals against fitted", fontsize=10)
    c.hist(res, bins=min(30, max(5, int(np.sqrt(res.size)))), color="C0", edgecolor="white")
    c.set_xlabel("residual (dm²)")
    c.set_ylabel("subjects")
    c.set_title("(c) residual histogram", fontsize=10)
    d.scatter(fitted, np.sqrt(np.abs(std)), s=8, alpha=0.7)
    d.set_xlabel("fitted WBSA (dm²)")
    d.set_ylabel("√|standardized residual| (–)")
    d.set_title("(d) scale–location", fontsize=10)
    for ax in (a, b, c, d):
        ax.grid(True, alpha=0.3)
    fig.suptitle(f"all subjects, {model}, VBSA only, θ = {az:g}°, φ = {el:g}°, D = {distance_m:g} m, n = {len(r)}",
                 fontsize=10)
    return fig


# ---------------------------------------------------------------------------------------------------------------
# Formulae comparison


def formulae_comparison(formulae: pd.DataFrame, groups: tuple[str, ...] | None = None, *, model: str | None = None,
                        vbsa_column: str | None = None, distance_m: float | None = None, camera: str | None = None,
                        dpi: int = 100) -> Figure:
    """MAPE of every BSA formula against the mesh WBSA beside the single-view all-subjects model's CV MAPE
    (best and worst view in the group), as one grid: a row per method, a column per group, the MAPE
    written in every cell.

    Parameters
    ----------
    formulae : DataFrame
        :func:`wbsa.analysis.formulae_comparison.compare_formulae` table.
    groups : tuple of str, optional
        Columns, those present (default: the claim groups, :data:`wbsa.analysis.groups.CLAIM_GROUPS`).
    model, vbsa_column, distance_m, camera : optional
        Keep only the single-view rows of this model, VBSA column, distance and camera.
    """
    from wbsa.analysis.formulae_comparison import KIND_ALL_MODEL, KIND_FORMULA
    from wbsa.analysis.groups import CLAIM_GROUPS

    if formulae.empty:
        raise FigureUnavailable("no formulae comparison table")
    groups = CLAIM_GROUPS if groups is None else groups
    sv = formulae["kind"] == KIND_ALL_MODEL
    for col, value in (("model", model), ("vbsa_column", vbsa_column), ("camera", camera)):
        if value is not None:
            sv &= formulae[col] == value
    if distance_m is not None:
        sv &= np.abs(formulae["distance_m"].astype(float) - float(distance_m)) < 1e-6
    table = formulae[(formulae["kind"] == KIND_FORMULA) | sv]
    present = [g for g in groups if (table["group"] == g).any()]
    if not present:
        raise FigureUnavailable("the formulae comparison has none of the groups " + ", ".join(groups))
    table = table.assign(_row=[_short_label(r) for _, r in table.iterrows()])
    rows = list(dict.fromkeys(table["_row"]))
    grid = table.pivot_table(index="_row", columns="group", values="mape_pct", aggfunc="first").reindex(
        index=rows, columns=present)
    n = table.groupby("group")["n"].max()
    values = grid.to_numpy(float)
    fig = _fig(1.0 * len(present) + 4.2, 0.34 * len(rows) + 1.4, dpi)
    ax = fig.subplots()
    finite = values[np.isfinite(values)]
    vmax = float(np.quantile(finite, 0.95)) if finite.size else 1.0
    im = ax.imshow(values, cmap="YlOrRd", vmin=0.0, vmax=max(vmax, 1e-6), aspect="auto")
    for i in range(values.shape[0]):
        for j in range(values.shape[1]):
            v = values[i, j]
            if np.isfinite(v):
                ax.text(j, i, f"{v:.2f}", ha="center", va="center", fontsize=9,
                        color="white" if v > 0.7 * vmax else "black")
    ax.set_xticks(range(len(present)))
    ax.set_xticklabels([f"{GROUP_LABELS.get(g, g)}\n(n = {int(n.get(g, 0))})" for g in present], fontsize=9,
                       rotation=30, ha="right", rotation_mode="anchor")
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels(rows, fontsize=9)
    for i, r in enumerate(rows):
        if not r.startswith("one view"):
            continue
        ax.get_yticklabels()[i].set_fontweight("bold")
    n_formulae = int((table.drop_duplicates("_row")["kind"] == KIND_FORMULA).sum())
    if 0 < n_formulae < len(rows):
        ax.axhline(n_formulae - 0.5, color="k", lw=1.5)
    ax.tick_params(top=False, bottom=True, length=0)
    fig.colorbar(im, ax=ax, shrink=0.6, label="MAPE against the mesh WBSA (%)")
    ax.set_title("Height/weight formulae (top) and one camera view (bottom, cross-validated), MAPE in %",
                 fontsize=10)
    return fig


def _short_label(row: pd.Series) -> str:
    if row["kind"] == "formula":
        return str(row["label"])
    return f"one view, {predictors_title(str(row['predictors']))}, {row['view']} view in group"


# ---------------------------------------------------------------------------------------------------------------
# Fig 15 / 17: reconstruction


def recon_columns(scan: pd.DataFrame) -> list[str]:
    """Reconstruction VBSA columns of the scan (``vbsa_recon_<method>_m2``)."""
    return [c for c in scan.columns if c.startswith("vbsa_recon_") and c.endswith("_m2")]


def reconstruction_by_view(scan: pd.DataFrame, fits: pd.DataFrame, *, model: str, distance_m: float, camera: str,
                           reference_column: str = "vbsa_visible_m2", elevation_deg: float = 0.0,
                           dpi: int = 100) -> Figure:
    """Reconstruction against the ideal view area by azimuth (paper Figs 15 and 17):
    (a) relative error of the reconstructed VBSA (mean ± SD over subjects), (b) CV RMSE and (c) c1 of the
    all-subjects VBSA-only fit with the ideal and with each reconstructed VBSA.
    """
    cols = recon_columns(scan)
    if not cols:
        raise FigureUnavailable("the scan has no reconstruction columns (set [reconstruction] methods)")
    sc = select(scan, distance_m=float(distance_m), camera=camera)
    els = np.array(sorted(sc["elevation_deg"].unique()), dtype=float)
    el = float(els[np.argmin(np.abs(els - elevation_deg))])
    sc = sc[np.abs(sc["elevation_deg"] - el) < 1e-6]
    if "fits_in_frame" in sc:
        sc = sc[sc["fits_in_frame"].fillna(False).astype(bool)]
    fig = _fig(13.0, 4.0, dpi)
    a, b, c = fig.subplots(1, 3)
    for i, col in enumerate(cols):
        rel = 100.0 * (sc[col] - sc[reference_column]) / sc[reference_column]
        g = rel.groupby(sc["azimuth_deg"]).agg(["mean", "std"])
        a.errorbar(g.index, g["mean"], yerr=g["std"], marker="o", ms=3, capsize=2, color=f"C{i + 1}",
                   label=col.removeprefix("vbsa_recon_").removesuffix("_m2"))
    a.axhline(0, color="k", lw=0.8)
    a.set_ylabel(f"(reconstructed − {reference_column}) / ideal (%)")
    a.set_title(f"(a) reconstructed VBSA error, φ = {el:g}°", fontsize=10)
    a.legend(fontsize=8)
    sub = select(fits, group="all", model=model, predictors="vbsa", distance_m=float(distance_m), camera=camera)
    sub = sub[np.abs(sub["elevation_deg"] - el) < 1e-6]
    for i, col in enumerate([reference_column, *cols]):
        part = sub[sub["vbsa_column"] == col].sort_values("azimuth_deg")
        if part.empty:
            continue
        label = "ideal (" + col + ")" if col == reference_column else col.removeprefix("vbsa_recon_").removesuffix("_m2")
        b.plot(part["azimuth_deg"], part["cv_rmse_m2"] * DM2, marker="o", ms=3, color=f"C{i}", label=label)
        c.plot(part["azimuth_deg"], part["c1"], marker="o", ms=3, color=f"C{i}", label=label)
    b.set_ylabel("CV RMSE (dm²)")
    b.set_title(f"(b) WBSA prediction error ({model}, all subjects)", fontsize=10)
    c.set_ylabel("c1, VBSA coefficient (–)")
    c.set_title("(c) VBSA coefficient", fontsize=10)
    b.legend(fontsize=8)
    for ax in (a, b, c):
        _angle_axis(ax)
    return fig


# ---------------------------------------------------------------------------------------------------------------
# Camera distance sweep


def distance_effect(fits: pd.DataFrame, scan: pd.DataFrame, *, model: str, vbsa_column: str, camera: str,
                    views: list[tuple[float, float]] | None = None, dpi: int = 100) -> Figure:
    """How the camera distance changes c1 and CV RMSE (paper section 3.4), and the share of bodies that
    fit in the frame at each distance (all subjects, VBSA only).
    """
    sub = select(fits, group="all", model=model, predictors="vbsa", vbsa_column=vbsa_column, camera=camera)
    distances = sorted(sub["distance_m"].unique())
    if len(distances) < 2:
        raise FigureUnavailable("the study has a single camera distance")
    if views is None:
        have = sub[["azimuth_deg", "elevation_deg"]].drop_duplicates()
        wanted = [(0.0, 0.0), (90.0, 0.0), (60.0, 60.0), (180.0, 0.0), (0.0, 90.0)]
        views = list(dict.fromkeys(nearest_view(have, *v) for v in wanted))[:4]
    fig = _fig(13.0, 4.0, dpi)
    a, b, c = fig.subplots(1, 3)
    for i, (az, el) in enumerate(views):
        part = select(sub, azimuth_deg=az, elevation_deg=el).sort_values("distance_m")
        label = f"θ = {az:g}°, φ = {el:g}°"
        a.plot(part["distance_m"], part["cv_rmse_m2"] * DM2, marker="o", color=f"C{i}", label=label)
        b.plot(part["distance_m"], part["c1"], marker="o", color=f"C{i}", label=label)
        rows = select(scan, azimuth_deg=az, elevation_deg=el, camera=camera)
        if "fits_in_frame" in rows:
            share = rows.groupby("distance_m")["fits_in_frame"].mean() * 100
            c.plot(share.index, share.to_numpy(), marker="o", color=f"C{i}", label=label)
    if "fits_in_frame" in scan:
        overall = select(scan, camera=camera).groupby("distance_m")["fits_in_frame"].mean() * 100
        c.plot(overall.index, overall.to_numpy(), color="k", ls="--", label="all views")
    a.set_ylabel("CV RMSE (dm²)")
    a.set_title("(a) WBSA prediction error", fontsize=10)
    b.set_ylabel("c1, VBSA coefficient (–)")
    b.set_title("(b) VBSA coefficient", fontsize=10)
    c.set_ylabel("bodies inside the frame (%)")
    c.set_ylim(-3, 103)
    c.set_title("(c) bodies not cut by the image border", fontsize=10)
    for ax in (a, b, c):
        ax.set_xlabel("camera distance D (m)")
        ax.grid(True, alpha=0.3)
    a.legend(fontsize=8)
    fig.suptitle(f"camera distance, all subjects, {model}, VBSA only ({vbsa_column}, {camera})", fontsize=10)
    return fig


# ---------------------------------------------------------------------------------------------------------------
# Fig 8: point-cloud snapshots


def point_cloud_snapshots(points_world: np.ndarray, depth_m: np.ndarray, body_vertices: np.ndarray, *,
                          view: tuple[float, float], distance_m: float, subject_id: int, camera: str,
                          dpi: int = 100) -> Figure:
    """The point cloud one camera sees, looked at from other directions (paper Fig 8).

    Parameters
    ----------
    points_world : (k, 3) float
        The camera's returns in world coordinates (metres).
    depth_m : (h, w) float
        The depth image (0 = no return), cropped or whole.
    body_vertices : (n, 3) float
        The whole body (drawn light grey behind the points, so the unseen skin shows).
    view, distance_m, subject_id, camera
        For the titles.
    """
    from wbsa.camera.extrinsics import look_at_rotation

    if len(points_world) == 0:
        raise FigureUnavailable("the camera saw no point of the subject")
    fig = _fig(14.0, 4.4, dpi)
    axes = fig.subplots(1, 5)
    rows, cols = np.nonzero(depth_m > 0)
    crop = depth_m[rows.min():rows.max() + 1, cols.min():cols.max() + 1].astype(float)
    crop[crop <= 0] = np.nan
    im = axes[0].imshow(crop, cmap="viridis")
    fig.colorbar(im, ax=axes[0], shrink=0.8, label="depth (m)")
    axes[0].set_title(f"depth image, θ = {view[0]:g}°, φ = {view[1]:g}°", fontsize=9)
    axes[0].set_xticks([])
    axes[0].set_yticks([])
    center = 0.5 * (body_vertices.min(axis=0) + body_vertices.max(axis=0))
    rng = np.random.default_rng(0)
    body = body_vertices[rng.permutation(len(body_vertices))[:6000]] - center
    pts = points_world - center
    for ax, (az, name) in zip(axes[1:], ((0.0, "front"), (90.0, "left side"), (180.0, "back"), (270.0, "right side"))):
        R = look_at_rotation(az, 0.0)
        ax.scatter(body @ R[0], -(body @ R[1]), s=0.3, color="0.85", rasterized=True)
        depth_along = pts @ R[2]
        ax.scatter(pts @ R[0], -(pts @ R[1]), s=0.3, c=depth_along, cmap="plasma", rasterized=True)
        ax.set_aspect("equal")
        ax.set_title(f"points seen from the {name}", fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(f"subject {subject_id}: {len(points_world)} points from θ = {view[0]:g}°, φ = {view[1]:g}°, "
                 f"D = {distance_m:g} m ({camera}); grey = skin the camera does not see", fontsize=10)
    return fig
