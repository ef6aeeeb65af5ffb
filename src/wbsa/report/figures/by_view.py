"""Errors and coefficients against the camera azimuth: per group and predictor set (paper Figs 11, 13, 14),
every group at elevation 0 (paper Fig 12) and every model kind (paper section 4.2)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from wbsa.report.data import select
from wbsa.report.figures.style import (
    DM2,
    GROUP_LABELS,
    FigureUnavailable,
    LEGEND_FONTSIZE,
    angle_axis,
    count_axis,
    elevation_colors,
    new_figure,
    predictors_title,
)


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
    colors = elevation_colors(sorted(sub["elevation_deg"].unique()))
    fig = new_figure(10.0, 3.3 * len(labels) + 1.0, dpi)  # + the legend under the panels
    axes = np.atleast_2d(fig.subplots(len(labels), 2, squeeze=False))
    for i, lab in enumerate(labels):
        part = sub[sub["predictors"] == lab]
        _by_view_panel(axes[i, 0], axes[i, 1], part, colors)
        axes[i, 0].set_ylabel("CV RMSE (dm²)")
        axes[i, 1].set_ylabel("c1, VBSA coefficient (–)")
        axes[i, 0].set_title(f"{GROUP_LABELS.get(group, group)}, {predictors_title(lab)}: CV RMSE", fontsize=10)
        axes[i, 1].set_title(f"{GROUP_LABELS.get(group, group)}, {predictors_title(lab)}: c1", fontsize=10)
        for ax in axes[i]:
            angle_axis(ax)
    handles, names = axes[0, 1].get_legend_handles_labels()
    fig.legend(handles, names, loc="outside lower center", ncol=min(len(names), 5), fontsize=LEGEND_FONTSIZE,
               title="elevation", title_fontsize=LEGEND_FONTSIZE, frameon=False)
    n = int(sub["n"].median())
    fig.suptitle(f"{model} model, {vbsa_column}, D = {distance_m:g} m, {camera}, median n = {n}", fontsize=10)
    return fig


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
    fig = new_figure(min(5.0 * len(labels), 12.0), 4.7, dpi)  # + the legend under the panels; at most the page
    axes = np.atleast_1d(fig.subplots(1, len(labels), squeeze=False)[0])
    # one colour per group in every panel, so one legend under the panels names them all
    groups = list(dict.fromkeys(sub["group"]))
    legend: dict[str, object] = {}
    for ax, lab in zip(axes, labels):
        part = sub[sub["predictors"] == lab]
        for g in dict.fromkeys(part["group"]):
            pg = part[part["group"] == g].sort_values("azimuth_deg")
            name = f"{GROUP_LABELS.get(g, g)} (n ≈ {int(sub.loc[sub['group'] == g, 'n'].median())})"
            (line,) = ax.plot(pg["azimuth_deg"], pg["cv_rmse_m2"] * DM2, marker="o", ms=3,
                              color=f"C{groups.index(g) % 10}")
            legend.setdefault(name, line)
        ax.set_ylabel("CV RMSE (dm²)")
        ax.set_title(f"{predictors_title(lab)}, φ = {el:g}°", fontsize=10)
        angle_axis(ax)
    if legend:
        fig.legend(list(legend.values()), list(legend), loc="outside lower center",
                   ncol=min(len(legend), 2 * len(labels)), fontsize=LEGEND_FONTSIZE, frameon=False)
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
    fig = new_figure(10.0, 4.0, dpi)
    ax, ax2 = fig.subplots(1, 2)
    els = np.array(sorted(sub["elevation_deg"].unique()), dtype=float)
    el = float(els[np.argmin(np.abs(els - elevation_deg))])
    for i, m in enumerate(models):
        pm = sub[(sub["model"] == m) & (np.abs(sub["elevation_deg"] - el) < 1e-6)].sort_values("azimuth_deg")
        ax.plot(pm["azimuth_deg"], pm["cv_rmse_m2"] * DM2, marker="o", ms=3, color=f"C{i}", label=m)
    ax.set_ylabel("CV RMSE (dm²)")
    ax.set_title(f"all subjects, VBSA only, φ = {el:g}°", fontsize=10)
    angle_axis(ax)
    ax.legend(fontsize=LEGEND_FONTSIZE)
    ref = sub[sub["model"] == models[0]].set_index(["azimuth_deg", "elevation_deg"])["cv_rmse_m2"]
    for i, m in enumerate(models[1:], start=1):
        other = sub[sub["model"] == m].set_index(["azimuth_deg", "elevation_deg"])["cv_rmse_m2"]
        ratio = (other / ref).dropna()
        ax2.scatter(np.arange(1, len(ratio) + 1), ratio.to_numpy(), s=12, color=f"C{i}", label=f"{m} / {models[0]}")
    ax2.axhline(1.0, color="k", lw=0.8)
    ax2.set_xlabel("view number (sorted by azimuth, then elevation)")
    count_axis(ax2.xaxis)
    ax2.set_ylabel(f"CV RMSE ratio to {models[0]} (–)")
    ax2.set_title("every view: below 1 = better than the first model", fontsize=10)
    ax2.legend(fontsize=LEGEND_FONTSIZE)
    ax2.grid(True, alpha=0.3)
    return fig

