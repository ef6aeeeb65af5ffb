"""Paper S2 Fig: residual diagnostics of the all-subjects VBSA-only fit at one view."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from wbsa.report.data import nearest_view, select
from wbsa.report.figures.style import DM2, FigureUnavailable, count_axis, new_figure


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
    fig = new_figure(9.0, 7.0, dpi)
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
    count_axis(c.yaxis)
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

