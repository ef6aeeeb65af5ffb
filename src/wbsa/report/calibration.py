"""The report's calibration section: the study's own bodies beside what real bodies are published to do.

Tables and plain sentences from :func:`wbsa.analysis.realism.realism_summary` of the study's population
and the published figures of :mod:`wbsa.analysis.calibration_refs`. Every sentence
names the virtual number, the published one and the difference; a published figure that the stored
sources do not give is said to be missing, not guessed.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from wbsa.analysis.calibration_refs import FIGURES, SOURCES, cite
from wbsa.analysis.groups import GroupSpec
from wbsa.analysis.realism import BMI_CLASSES, CHILDREN

#: Du Bois' weight exponent: a mass p % too low lowers Du Bois by about 0.425·p %.
_DUBOIS_WEIGHT_EXPONENT = 0.425
#: Sources cited in the section, in the order of the list under it.
CITED_SOURCES = ("deurenberg_1991", "siri_1961", "livingston_lee_2001", "schlich_2010", "yu_2010",
                 "kuehnapfel_2017", "verbraecken_2006")
_SEX_PLAIN = {"female": "women", "male": "men"}


def _signed(x: float, digits: int = 1, unit: str = " %") -> str:
    """``+1.2 %`` / ``−1.2 %`` (a true minus), ``0.0 %`` when it rounds to zero, ``—`` when not finite."""
    if not np.isfinite(x):
        return "—"
    if round(x, digits) == 0:
        return f"{0:.{digits}f}{unit}"
    return f"{x:+.{digits}f}{unit}".replace("-", "−")


def _mean_sd(mean: float, sd: float, fmt: str) -> str:
    if not np.isfinite(mean):
        return ""
    return format(mean, fmt) + ("" if not np.isfinite(sd) else " ± " + format(sd, fmt))


def _weighted(rows: pd.DataFrame, column: str) -> float:
    """n-weighted mean of a per-class mean column (NaN for no rows)."""
    n = rows["n"].to_numpy(dtype=float)
    return float(np.average(rows[column].to_numpy(dtype=float), weights=n)) if n.sum() else float("nan")


def obese_classes(spec: GroupSpec) -> list[str]:
    """Labels of the adult BMI classes at or above the obese cut-off (``spec.obese_min_bmi``)."""
    return [label for label, low, _ in BMI_CLASSES if low >= spec.obese_min_bmi]


def _adults(rows: pd.DataFrame, sex: str | None = None) -> pd.DataFrame:
    a = rows[rows["bmi_class"].astype(str) != CHILDREN]
    return a if sex is None else a[a["sex"] == sex]


def _obese(rows: pd.DataFrame, spec: GroupSpec) -> pd.DataFrame:
    a = _adults(rows)
    return a[a["bmi_class"].astype(str).isin(obese_classes(spec))]


def calibration_sentences(summary: dict, spec: GroupSpec = GroupSpec()) -> list[str]:
    """One plain sentence per comparison: the virtual number, the published one, the difference."""
    law, slopes = summary["hw_law"], summary["dubois_bmi_slopes"]
    dub, comp = pd.DataFrame(summary["dubois"]), pd.DataFrame(summary["composition"])
    out = [
        f"Area at fixed height and weight: on these {law['n']} bodies the law log WBSA = a + b·log H + c·log W "
        f"leaves a residual SD of {law['residual_sd_percent']:.2f} % (R² = {law['r2']:.5f}), the most a view can "
        "add. The real-body figure was not found (" + FIGURES["area_scatter_at_fixed_hw_percent"].note
        + "), so this comparison stays open."]
    fe, se = law["female_effect_percent"], summary["schlich_female_effect_percent"]
    if np.isfinite(fe) and np.isfinite(se):
        out.append(f"Women against men of the same height and weight: {_signed(fe)} area here; Schlich's formulae "
                   f"fitted on 3-D scans give {_signed(se)} at these adults' heights and weights, so the virtual "
                   f"difference is {abs(se - fe):.1f} points {'smaller' if fe < se else 'larger'} than the "
                   "scanned one.")
    obese = _obese(dub, spec)
    if len(obese):
        mesh, ll = _weighted(obese, "mesh_over_dubois_mean"), _weighted(obese, "livingston_lee_over_dubois_mean")
        out.append(
            f"Obese adults (BMI ≥ {spec.obese_min_bmi:g}, n = {int(obese['n'].sum())}): mesh / Du Bois is "
            f"{mesh:.3f} here, Livingston & Lee's law, fitted on normal-weight and obese patients, gives {ll:.3f} at "
            f"the same heights and weights: these bodies lie {abs(100 * (ll - mesh)):.1f} points of Du Bois "
            f"{'below' if ll > mesh else 'above'} that law (those patients had Du Bois under by as much as "
            f"{FIGURES['dubois_obese_underestimate_max_percent'].text()}). With BMI, mesh / Du Bois moves by "
            f"{_signed(slopes['mesh'], 3, '')} % per kg/m² here, against {_signed(slopes['livingston_lee'], 3, '')} "
            f"(Livingston & Lee), {_signed(slopes['yu'], 3, '')} (Yu) and {_signed(slopes['schlich'], 3, '')} "
            "(Schlich) at the same bodies; a measured per-class Du Bois bias "
            f"({SOURCES['kuehnapfel_2017'].label}) was not found.")
    else:
        out.append(f"No adult here has a BMI of {spec.obese_min_bmi:g} or more: the Du Bois bias of obese bodies "
                   f"({cite('dubois_obese_underestimate_max_percent')}) cannot be compared.")
    adults = _adults(comp)
    if len(adults):
        rho, ref = _weighted(adults, "density_kg_m3_mean"), _weighted(adults, "deurenberg_density_kg_m3_mean")
        diff = 100 * (rho / ref - 1)
        by_sex = "; ".join(
            f"{_SEX_PLAIN.get(s, s)} {_weighted(_adults(comp, s), 'density_kg_m3_mean'):,.0f} against "
            f"{_weighted(_adults(comp, s), 'deurenberg_density_kg_m3_mean'):,.0f}"
            for s in ("female", "male") if len(_adults(comp, s)))
        if summary["composition_columns"]:
            out.append(
                f"Density: each body's fat fraction is drawn from Deurenberg's equation with its scatter "
                f"(SEE {FIGURES['fat_see_adult_percent'].text()} in adults), so the adults' mean density, "
                f"{rho:,.0f} kg/m³, agrees with the equation's {ref:,.0f} kg/m³ at the same BMI, age and sex "
                f"by construction ({_signed(diff)}; {by_sex}).")
        else:
            out.append(
                f"Density: every body has {rho:,.0f} kg/m³ (a constant, "
                f"{100 * _weighted(adults, 'fat_fraction_mean'):.0f} % fat by Siri's equation); Deurenberg's "
                f"equation with Siri's density gives adults of these BMI, ages and sexes {ref:,.0f} kg/m³ "
                f"({by_sex}): these bodies are {abs(diff):.1f} % {'lighter' if diff < 0 else 'heavier'} per litre, "
                f"which moves Du Bois by about {_signed(_DUBOIS_WEIGHT_EXPONENT * diff)}.")
    mix, posed = summary["posture"], pd.DataFrame(summary["posed_area"])
    if mix:
        text = "Postures: " + ", ".join(f"{k} {v}" for k, v in mix.items())
        if len(posed):
            a = posed.iloc[0]
            text += (f"; the posed skin area differs from the rest-pose WBSA by {_signed(a['mean_percent'], 2)} on "
                     f"average (from {_signed(a['min_percent'], 2)} to {_signed(a['max_percent'], 2)})")
        out.append(text + ".")
    else:
        out.append("Posture: every body stands in the paper's A-pose (the population has no posture column); "
                   "real people do not.")
    return out


def reference_table(summary: dict, spec: GroupSpec = GroupSpec()) -> pd.DataFrame:
    """The overview table: quantity, this population, real bodies (published), source."""
    law, slopes = summary["hw_law"], summary["dubois_bmi_slopes"]
    dub, comp = pd.DataFrame(summary["dubois"]), pd.DataFrame(summary["composition"])
    obese = _obese(dub, spec)
    lo_hi = summary["bmi_range_adults"]
    rows = [
        ("bodies", f"{law['n']}", "", ""),
        ("log H/W law: R² of log WBSA", f"{law['r2']:.5f}", "not found", SOURCES["kuehnapfel_2017"].label),
        ("scatter of area at fixed H and W (residual SD)", f"{law['residual_sd_percent']:.2f} %",
         FIGURES["area_scatter_at_fixed_hw_percent"].text(), SOURCES["kuehnapfel_2017"].label),
        ("women − men at the same H and W", _signed(law["female_effect_percent"]),
         f"{_signed(summary['schlich_female_effect_percent'])} (formulae at these adults' H and W)",
         SOURCES["schlich_2010"].label),
        ("mesh / Du Bois against BMI, adults (% per kg/m²)", _signed(slopes["mesh"], 3, ""),
         f"Livingston & Lee {_signed(slopes['livingston_lee'], 3, '')}, Yu {_signed(slopes['yu'], 3, '')}, "
         f"Schlich {_signed(slopes['schlich'], 3, '')} (at these bodies)",
         ", ".join(SOURCES[k].label for k in ("livingston_lee_2001", "yu_2010", "schlich_2010"))),
        (f"mesh − Du Bois, obese adults (BMI ≥ {spec.obese_min_bmi:g}; mean, % of Du Bois)",
         _signed(100 * (_weighted(obese, "mesh_over_dubois_mean") - 1)) if len(obese) else "no obese adult",
         f"Du Bois under by up to {FIGURES['dubois_obese_underestimate_max_percent'].text()}",
         SOURCES["livingston_lee_2001"].label),
        ("Du Bois bias by sex and BMI class", "table below", FIGURES["dubois_bias_by_class"].text(),
         SOURCES["kuehnapfel_2017"].label),
        ("adult BMI range (kg/m²)", f"{lo_hi[0]:.1f}–{lo_hi[1]:.1f}" if lo_hi else "no adult",
         f"{FIGURES['deurenberg_bmi_range'].text()} (body-fat sample)", SOURCES["deurenberg_1991"].label),
    ]
    for sex in ("female", "male"):
        a = _adults(comp, sex)
        if len(a):
            rows.append((f"density, adult {_SEX_PLAIN[sex]} (kg/m³)", f"{_weighted(a, 'density_kg_m3_mean'):,.0f}",
                         f"{_weighted(a, 'deurenberg_density_kg_m3_mean'):,.0f} (equations at these BMI, ages)",
                         f"{SOURCES['deurenberg_1991'].label}, {SOURCES['siri_1961'].label}"))
    rows.append(("body density, all fat to no fat (kg/m³)", "", FIGURES["density_range_kg_m3"].text(),
                 SOURCES["siri_1961"].label))
    return pd.DataFrame(rows, columns=["quantity", "this population", "real bodies (published)", "source"])


def dubois_display(summary: dict) -> pd.DataFrame:
    """Mesh / Du Bois by sex and BMI class beside the measured-area formulae at the same bodies."""
    d = pd.DataFrame(summary["dubois"])
    return pd.DataFrame({
        "sex": d["sex"].astype(str), "BMI class": d["bmi_class"].astype(str), "n": d["n"].astype(int),
        "mesh / Du Bois": [_mean_sd(m, s, ".3f") for m, s in zip(d["mesh_over_dubois_mean"], d["mesh_over_dubois_sd"])],
        "Schlich / Du Bois": [f"{x:.3f}" for x in d["schlich_over_dubois_mean"]],
        "Yu / Du Bois": [f"{x:.3f}" for x in d["yu_over_dubois_mean"]],
        "Livingston & Lee / Du Bois": [f"{x:.3f}" for x in d["livingston_lee_over_dubois_mean"]],
    })


def composition_display(summary: dict) -> pd.DataFrame:
    """Density and fat by sex and BMI class beside Deurenberg + Siri at the same BMI, age and sex.

    Without the population's own fat fractions (a constant density) the virtual fat column is left out:
    it would be the constant density's Siri fat for everyone."""
    c = pd.DataFrame(summary["composition"])
    out = pd.DataFrame({
        "sex": c["sex"].astype(str), "BMI class": c["bmi_class"].astype(str), "n": c["n"].astype(int),
        "density kg/m³": [_mean_sd(m, s, ",.0f") for m, s in zip(c["density_kg_m3_mean"], c["density_kg_m3_sd"])],
        "Deurenberg + Siri density kg/m³": [f"{x:,.0f}" for x in c["deurenberg_density_kg_m3_mean"]],
    })
    if summary["composition_columns"]:
        out["fat %"] = [_mean_sd(100 * m, 100 * s, ".1f") for m, s in zip(c["fat_fraction_mean"],
                                                                         c["fat_fraction_sd"])]
    out["Deurenberg fat %"] = [f"{100 * x:.1f}" for x in c["deurenberg_fat_fraction_mean"]]
    return out


def groups_display(summary: dict, spec: GroupSpec = GroupSpec()) -> pd.DataFrame:
    """Subjects per group with each group's definition, then the posture mix."""
    defined = spec.describe()  # the analysis groups' own definitions, under the plain names
    what = {name: ("" if name in ("all", "women", "men") else defined[{"children": "kids"}.get(name, name)])
            for name in summary["groups"]}
    rows = [(g, what.get(g, ""), n) for g, n in summary["groups"].items()]
    rows += [(f"posture: {k}", "", v) for k, v in summary["posture"].items()]
    return pd.DataFrame(rows, columns=["group", "definition", "subjects"])


def posture_display(summary: dict) -> pd.DataFrame:
    """Posed − rest skin area per posture, % (empty without postures)."""
    p = pd.DataFrame(summary["posed_area"])
    if p.empty:
        return p
    return pd.DataFrame({"posture": p["posture"], "n": p["n"].astype(int),
                         "mean %": [_signed(x, 2, "") for x in p["mean_percent"]],
                         "SD %": [f"{x:.2f}" if np.isfinite(x) else "" for x in p["sd_percent"]],
                         "min %": [_signed(x, 2, "") for x in p["min_percent"]],
                         "max %": [_signed(x, 2, "") for x in p["max_percent"]]})


def sources_text() -> list[str]:
    """Full citations of :data:`CITED_SOURCES`, with what each measured."""
    return [f"{SOURCES[k].label}: {SOURCES[k].citation} ({SOURCES[k].bodies}; {SOURCES[k].measured})"
            if SOURCES[k].bodies != "—" else f"{SOURCES[k].label}: {SOURCES[k].citation} ({SOURCES[k].measured})"
            for k in CITED_SOURCES]
