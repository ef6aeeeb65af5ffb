"""The calibration figure: the study's bodies beside what real bodies are published to do."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from wbsa.analysis.groups import GroupSpec
from wbsa.report.figures.style import LEGEND_FONTSIZE, FigureUnavailable, new_figure

#: Colours of the sexes, as in the WBSA distribution (Fig 5).
SEX_COLORS = {"male": "#4C72B0", "female": "#DD8452"}
_SEX_PLAIN = {"female": "women", "male": "men"}
#: Adults per BMI bin of the published formulae's lines and band (bins of equal count, at most :data:`MAX_BINS`).
PER_BIN = 8
MAX_BINS = 6


def _bins(bmi: np.ndarray) -> list[np.ndarray]:
    """Masks of BMI bins holding about :data:`PER_BIN` subjects each (none for fewer than ``PER_BIN``)."""
    count = min(MAX_BINS, bmi.size // PER_BIN)
    if count < 1:
        return []
    edges = np.quantile(bmi, np.linspace(0, 1, count + 1))
    idx = np.clip(np.searchsorted(edges, bmi, side="right") - 1, 0, count - 1)
    return [idx == i for i in range(count) if (idx == i).any()]


def _legend_below(fig: Figure, axes) -> None:
    """One legend under the panels, each label once (the sexes' markers are shared by both panels)."""
    seen: dict[str, object] = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            seen.setdefault(label, handle)
    if seen:
        fig.legend(list(seen.values()), list(seen), loc="outside lower center", ncol=2, fontsize=LEGEND_FONTSIZE,
                   frameon=False)


def calibration_figure(population: pd.DataFrame, spec: GroupSpec = GroupSpec(), dpi: int = 100) -> Figure:
    """Mesh / Du Bois and body density against BMI, beside the published real-body relations.

    (a) Every subject's mesh area / Du Bois against BMI (women and men coloured, children hollow), with
    Livingston & Lee's law (normal-weight and obese patients) / Du Bois at the same adults (band: 10–90 %
    per BMI bin of equal count) and Yu's and Schlich's scan-fitted formulae / Du Bois (bin means); (b)
    adults' density (mass / volume) against BMI with Deurenberg's body-fat equation and Siri's density at
    the adults' median age per sex (line: the equation's mean; band: ± its standard error of estimate).
    A formula's line needs two bins (2 × :data:`PER_BIN` adults, per sex for Schlich's); fewer, and it is
    left out.

    Parameters
    ----------
    population : DataFrame
        ``sex``, ``age_years``, ``stature_m``, ``mass_kg``, ``bmi``, ``wbsa_m2``, ``volume_m3``; survey
        tables count their matched bodies (variation 0) only.
    """
    from wbsa.analysis.calibration_refs import FIGURES
    from wbsa.analysis.realism import one_row_per_body, dubois_m2
    from wbsa.bodies.composition import density_from_fat, fat_fraction_limits, predicted_fat_percent
    from wbsa.formulae import bsa

    needed = ("sex", "age_years", "stature_m", "mass_kg", "bmi", "wbsa_m2", "volume_m3")
    missing = [c for c in needed if c not in population.columns]
    if missing:
        raise FigureUnavailable(f"the population lacks {', '.join(missing)}")
    t = one_row_per_body(population)
    t = t[np.isfinite(t[list(needed[1:])].to_numpy(float)).all(axis=1)]
    if len(t) < 3:
        raise FigureUnavailable("the population has fewer than 3 complete subjects")
    sex = t["sex"].astype(str).to_numpy()
    bmi, age = t["bmi"].to_numpy(float), t["age_years"].to_numpy(float)
    h, w = 100 * t["stature_m"].to_numpy(float), t["mass_kg"].to_numpy(float)
    dubois = dubois_m2(t)
    ratio = t["wbsa_m2"].to_numpy(float) / dubois
    adult = age > spec.kid_max_age_years

    fig = new_figure(11.0, 5.0, dpi)
    ax, ax2 = fig.subplots(1, 2, width_ratios=[1.25, 1])
    ax.axhline(1.0, color="0.3", lw=0.8)
    # the published formulae at the same adults, by BMI bin
    ab, ah, aw, asex = bmi[adult], h[adult], w[adult], sex[adult]
    bins = _bins(ab)
    if len(bins) >= 2:  # a line needs two bins
        centre = np.array([ab[m].mean() for m in bins])
        ll = np.asarray(bsa("livingston_lee", ah, aw, check=False)) / dubois[adult]
        ax.fill_between(centre, [np.percentile(ll[m], 10) for m in bins], [np.percentile(ll[m], 90) for m in bins],
                        color="0.55", alpha=0.25, lw=0,
                        label="Livingston & Lee 2001 (normal-weight and obese patients): 10–90 %")
        ax.plot(centre, [ll[m].mean() for m in bins], color="0.45", lw=1.6, label="Livingston & Lee 2001: mean")
        yu = np.asarray(bsa("yu", ah, aw, check=False)) / dubois[adult]
        ax.plot(centre, [yu[m].mean() for m in bins], color="0.2", ls="--", lw=1.2, label="Yu 2010, 3-D scans")
        sch = np.asarray(bsa("schlich", ah, aw, asex, check=False)) / dubois[adult]
        for s in ("female", "male"):
            sb = _bins(ab[asex == s])
            if len(sb) >= 2:
                ax.plot([ab[asex == s][m].mean() for m in sb], [sch[asex == s][m].mean() for m in sb],
                        color=SEX_COLORS[s], ls=":", lw=1.6, label=f"Schlich 2010, 3-D scans, {_SEX_PLAIN[s]}")
    for s in ("female", "male"):
        for who, filled in ((adult, True), (~adult, False)):
            m = (sex == s) & who
            if m.any():
                ax.scatter(bmi[m], ratio[m], s=14, linewidths=0.8, alpha=0.85,
                           facecolors=SEX_COLORS[s] if filled else "none", edgecolors=SEX_COLORS[s],
                           label=f"{_SEX_PLAIN[s] if filled else 'girls' if s == 'female' else 'boys'} "
                                 f"(n = {int(m.sum())})")
    ax.axvline(spec.obese_min_bmi, color="0.6", lw=0.8, ls="-.")
    ax.text(spec.obese_min_bmi, ax.get_ylim()[0], f" obese ≥ {spec.obese_min_bmi:g}", va="bottom", ha="left",
            fontsize=8, color="0.4")
    ax.set_xlabel("BMI (kg/m²)")
    ax.set_ylabel("area / Du Bois")
    ax.set_title("(a) skin area / Du Bois against BMI", fontsize=10)
    ax.grid(True, alpha=0.3)

    # (b) density of the adults beside Deurenberg + Siri at their median age
    density = t["mass_kg"].to_numpy(float) / t["volume_m3"].to_numpy(float)
    if not adult.any():
        ax2.text(0.5, 0.5, "no adults", ha="center", va="center", transform=ax2.transAxes)
    see = FIGURES["fat_see_adult_percent"].value
    grid = np.linspace(bmi[adult].min(), bmi[adult].max(), 60) if adult.any() else np.array([])
    for s in ("female", "male"):
        m = adult & (sex == s)
        if not m.any():
            continue
        ax2.scatter(bmi[m], density[m], s=12, color=SEX_COLORS[s], alpha=0.8,
                    label=f"{_SEX_PLAIN[s]} (n = {int(m.sum())})")
        a = np.full(grid.shape, float(np.median(age[m])))
        male = np.full(grid.shape, s == "male")
        lo, hi = fat_fraction_limits(a, male)
        pct = predicted_fat_percent(grid, a, male)
        band = [density_from_fat(np.clip((pct + d) / 100, lo, hi)) for d in (-see, 0.0, see)]
        ax2.fill_between(grid, band[2], band[0], color=SEX_COLORS[s], alpha=0.15, lw=0)
        ax2.plot(grid, band[1], color=SEX_COLORS[s], lw=1.4,
                 label=f"Deurenberg 1991 + Siri 1961, {_SEX_PLAIN[s]} {a[0]:.0f} y (± SEE {see:g} %BF)")
    ax2.set_xlabel("BMI (kg/m²)")
    ax2.set_ylabel("density (kg/m³)")
    ax2.set_title("(b) adults' density (mass / volume) against BMI", fontsize=10)
    ax2.grid(True, alpha=0.3)
    _legend_below(fig, (ax, ax2))
    return fig
