"""What every report figure shares: the dm² unit, group labels, the figure factory, axis styling and the
legend font size.

A figure function raises :class:`FigureUnavailable` when its data are not in the tables (e.g. no
reconstruction columns), and the report then says why instead of showing the figure.
"""

from __future__ import annotations

from matplotlib.figure import Figure

from wbsa.errors import WbsaError

#: m² -> dm².
DM2 = 100.0

#: Groups drawn in the group figures, in order, with their labels.
GROUP_LABELS = {"all": "all subjects", "males": "males", "females": "females", "kids": "kids", "adults": "adults",
                "small": "small stature", "normal": "normal stature", "big": "big stature", "obese": "obese (BMI ≥ 30)",
                "underweight": "underweight adults (BMI < 18.5)", "tall": "tall (≥ 1.85 m)"}


#: Font size of legend text, points. The figures are drawn at 100 dpi and shown at their own size on a page up to
#: 1200 px wide (a 1280 px window), so 9 pt is 12.5 px on screen: as large as the page's table text (12.8 px).
LEGEND_FONTSIZE = 9.0


class FigureUnavailable(WbsaError):
    """The tables lack what a figure needs; the message says what."""


def predictors_title(label: str) -> str:
    """``vbsa`` -> 'VBSA only'; ``vbsa+stature_m`` -> 'VBSA + stature'."""
    extra = [p for p in label.split("+") if p != "vbsa"]
    if not extra:
        return "VBSA only"
    names = {"stature_m": "stature", "mass_kg": "mass", "age_years": "age", "sex_male": "sex"}
    return "VBSA + " + " + ".join(names.get(p, p) for p in extra)


def new_figure(width: float, height: float, dpi: int) -> Figure:
    """A ``width`` × ``height`` inch figure with constrained layout, not registered with pyplot."""
    return Figure(figsize=(width, height), dpi=dpi, layout="constrained")


def elevation_colors(elevations: list[float]):
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


def angle_axis(ax, label: str = "Azimuth θ (deg)") -> None:
    """Label an azimuth x axis, tick it at the paper's angles and draw a light grid."""
    ax.set_xlabel(label)
    ax.set_xticks([0, 30, 45, 60, 90, 120, 135, 150, 180])
    ax.grid(True, alpha=0.3)



def count_axis(axis) -> None:
    """Tick an axis that counts (subjects, views) at whole numbers only.

    Parameters
    ----------
    axis : matplotlib.axis.Axis
        ``ax.xaxis`` or ``ax.yaxis``.
    """
    from matplotlib.ticker import MaxNLocator

    axis.set_major_locator(MaxNLocator(integer=True))
