"""Paper Figs 15 and 17: reconstructed against ideal view area by azimuth."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from wbsa.report.data import select
from wbsa.report.figures.style import DM2, LEGEND_FONTSIZE, FigureUnavailable, angle_axis, new_figure


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
    fig = new_figure(12.0, 4.0, dpi)  # 1200 px: shown at its own size on the page
    a, b, c = fig.subplots(1, 3)
    for i, col in enumerate(cols):
        rel = 100.0 * (sc[col] - sc[reference_column]) / sc[reference_column]
        g = rel.groupby(sc["azimuth_deg"]).agg(["mean", "std"])
        a.errorbar(g.index, g["mean"], yerr=g["std"], marker="o", ms=3, capsize=2, color=f"C{i + 1}",
                   label=col.removeprefix("vbsa_recon_").removesuffix("_m2"))
    a.axhline(0, color="k", lw=0.8)
    a.set_ylabel(f"(reconstructed − {reference_column}) / ideal (%)")
    a.set_title(f"(a) reconstructed VBSA error, φ = {el:g}°", fontsize=10)
    a.legend(fontsize=LEGEND_FONTSIZE)
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
    b.legend(fontsize=LEGEND_FONTSIZE)
    for ax in (a, b, c):
        angle_axis(ax)
    return fig

