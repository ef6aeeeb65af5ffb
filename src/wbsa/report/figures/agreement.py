"""Agreement of the depth-image estimate with the true WBSA: a Bland–Altman plot and the error by body build.

Method comparisons in the BSA and clinical-measurement literature are read as Bland–Altman plots (Bland &
Altman, Lancet 1986): the difference of the two methods against their mean, with the mean difference
(bias) and the 95 % limits of agreement, bias ± 1.96 SD. Here the difference is in per cent of the mean,
since a BSA error matters in proportion to the body.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from wbsa.report.figures.style import LEGEND_FONTSIZE, FigureUnavailable, new_figure

#: Normal quantile of the 95 % limits of agreement.
LOA_Z = 1.96


def limits_of_agreement(difference: np.ndarray) -> tuple[float, float, float]:
    """Bias and 95 % limits of agreement of paired differences (Bland & Altman 1986).

    Parameters
    ----------
    difference : (n,) float64
        Method minus reference, per pair (NaN ignored); at least two finite values.

    Returns
    -------
    bias, lower, upper : float
        Mean difference and bias ∓ 1.96 × sample SD (ddof 1).
    """
    d = np.asarray(difference, dtype=np.float64)
    d = d[np.isfinite(d)]
    if len(d) < 2:
        raise FigureUnavailable(f"limits of agreement need at least two paired differences, got {len(d)}")
    bias, sd = float(d.mean()), float(d.std(ddof=1))
    return bias, bias - LOA_Z * sd, bias + LOA_Z * sd


def agreement_figure(truth_m2: np.ndarray, estimate_m2: np.ndarray, lower_m2: np.ndarray, upper_m2: np.ndarray,
                     groups: np.ndarray, *, order: list[str] | None = None, title: str = "",
                     dpi: int = 100) -> Figure:
    """Bland–Altman plot of the estimate against the truth, and the error by group with its interval coverage.

    Parameters
    ----------
    truth_m2, estimate_m2 : (n,) float64
        True and estimated WBSA (m²).
    lower_m2, upper_m2 : (n,) float64
        The estimate's interval; a point whose interval misses the truth is drawn hollow.
    groups : (n,) str
        Group of every subject (e.g. child, or the adult's BMI class).
    order : list of str, optional
        The groups' boxes from left to right (those present); default: in order of first appearance.
    title : str
    dpi : int

    Returns
    -------
    matplotlib.figure.Figure
        Left: 100 (estimate − truth) / mean against the mean (m²), bias and limits of agreement. Right: the
        per-cent error per group as boxes, n and coverage written under each.
    """
    truth, est = np.asarray(truth_m2, dtype=np.float64), np.asarray(estimate_m2, dtype=np.float64)
    lo, hi = np.asarray(lower_m2, dtype=np.float64), np.asarray(upper_m2, dtype=np.float64)
    groups = np.asarray(groups, dtype=object)
    ok = np.isfinite(truth) & np.isfinite(est)
    if ok.sum() < 2:
        raise FigureUnavailable("an agreement plot needs at least two estimated subjects")
    truth, est, lo, hi, groups = truth[ok], est[ok], lo[ok], hi[ok], groups[ok]
    mean_m2 = 0.5 * (truth + est)
    diff_pct = 100.0 * (est - truth) / mean_m2
    covered = (lo <= truth) & (truth <= hi)
    bias, lower, upper = limits_of_agreement(diff_pct)

    fig = new_figure(11.0, 4.4, dpi)
    ax, ax_g = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.1, 1.0]})
    ax.scatter(mean_m2[covered], diff_pct[covered], s=12, color="tab:blue", alpha=0.7,
               label=f"interval covers the truth ({covered.sum()})")
    ax.scatter(mean_m2[~covered], diff_pct[~covered], s=16, facecolors="none", edgecolors="tab:red",
               label=f"interval misses it ({(~covered).sum()})")
    for y, style, text in ((bias, "-", f"bias {bias:+.2f} %"), (lower, "--", f"−1.96 SD {lower:+.2f} %"),
                           (upper, "--", f"+1.96 SD {upper:+.2f} %")):
        ax.axhline(y, color="black", linestyle=style, linewidth=1.0)
        ax.annotate(text, (1.0, y), xycoords=("axes fraction", "data"), xytext=(-4, 3),
                    textcoords="offset points", ha="right", fontsize=8)
    ax.axhline(0.0, color="grey", linewidth=0.6)
    ax.set_xlabel("mean of estimate and truth (m²)")
    ax.set_ylabel("estimate − truth (% of the mean)")
    ax.set_title("Bland–Altman: agreement with the true WBSA", fontsize=10)
    ax.legend(loc="lower left", fontsize=LEGEND_FONTSIZE, frameon=False)

    present = list(dict.fromkeys(groups.tolist()))
    names = present if order is None else [g for g in order if g in present] + [g for g in present if g not in order]
    err_pct = 100.0 * (est / truth - 1.0)
    boxes = [err_pct[groups == g] for g in names]
    ax_g.boxplot(boxes, showfliers=True, flierprops={"markersize": 3})
    ax_g.axhline(0.0, color="grey", linewidth=0.6)
    ax_g.set_xticks(np.arange(1, len(names) + 1),
                    [f"{g}\nn={len(b)}, cov {covered[groups == g].mean():.2f}" for g, b in zip(names, boxes)],
                    fontsize=7, rotation=20, ha="right")
    ax_g.set_ylabel("estimate / truth − 1 (%)")
    ax_g.set_title("error by group (cov: share inside the interval)", fontsize=10)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig
