"""Paper section 3.4: how the camera distance changes c1, the CV RMSE and the bodies inside the frame."""

from __future__ import annotations

import pandas as pd
from matplotlib.figure import Figure

from wbsa.report.data import nearest_view, select
from wbsa.report.figures.style import DM2, LEGEND_FONTSIZE, FigureUnavailable, new_figure


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
    fig = new_figure(12.0, 4.0, dpi)  # 1200 px: shown at its own size on the page
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
    a.legend(fontsize=LEGEND_FONTSIZE)
    fig.suptitle(f"camera distance, all subjects, {model}, VBSA only ({vbsa_column}, {camera})", fontsize=10)
    return fig

