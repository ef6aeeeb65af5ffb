"""Paper Fig 5: the distribution of WBSA in the population."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from wbsa.report.figures.style import DM2, LEGEND_FONTSIZE, FigureUnavailable, count_axis, new_figure


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
    fig = new_figure(9.0, 3.6, dpi)
    ax, ax2 = fig.subplots(1, 2, width_ratios=[1.3, 1])
    bins = np.histogram_bin_edges(w, bins=min(40, max(8, int(np.sqrt(w.size)))))
    sex = population["sex"].astype(str).to_numpy()
    parts = [(w_s, lab) for lab in ("male", "female") if (w_s := population.loc[sex == lab, "wbsa_m2"]
                                                           .to_numpy(float) * DM2).size]
    ax.hist([p[0] for p in parts], bins=bins, stacked=True, label=[f"{p[1]}s (n = {p[0].size})" for p in parts],
            color=["#4C72B0", "#DD8452"][:len(parts)], edgecolor="white", linewidth=0.4)
    ax.set_xlabel("WBSA (dm²)")
    ax.set_ylabel("subjects")
    count_axis(ax.yaxis)
    ax.set_title(f"WBSA of {w.size} subjects: mean {w.mean():.0f} dm², SD {w.std(ddof=1) if w.size > 1 else 0:.0f} dm²",
                 fontsize=10)
    ax.legend(fontsize=LEGEND_FONTSIZE)
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

