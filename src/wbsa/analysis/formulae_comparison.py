"""Classical BSA formulae versus the mesh WBSA, side by side with the single-view models."""

from __future__ import annotations

from typing import Callable

import numpy as np
import pandas as pd

from wbsa.analysis.groups import COMPARISON_GROUPS, GroupSpec, assign_groups
from wbsa.errors import WbsaError

#: Columns of the comparison table, in order.
COMPARISON_COLUMNS: tuple[str, ...] = (
    "group", "kind", "method", "label", "view", "model", "predictors", "vbsa_column", "camera", "distance_m",
    "azimuth_deg", "elevation_deg", "n", "mape_pct", "bias_m2", "bias_pct", "rmse_m2",
)

#: Values of the ``kind`` column.
KIND_FORMULA = "formula"
KIND_ALL_MODEL = "single view, all-subjects model"
KIND_GROUP_MODEL = "single view, group model"

_SV_KEYS = ["model", "predictors", "vbsa_column", "camera", "distance_m"]


def formula_values(population: pd.DataFrame, bsa_table: Callable | None = None) -> pd.DataFrame:
    """BSA of every formula for every subject, m².

    Parameters
    ----------
    population : DataFrame
        ``stature_m``, ``mass_kg`` and ``sex``.
    bsa_table : callable, optional
        ``bsa_table(height_cm, weight_kg, sex=None, check=False) -> DataFrame`` with columns
        ``bsa_<key>_m2`` (default :func:`wbsa.formulae.bsa_table`).

    Returns
    -------
    DataFrame
        One row per subject (population order), one column per formula key.
    """
    if bsa_table is None:
        from wbsa.formulae import bsa_table
    sex = population["sex"] if "sex" in population and population["sex"].notna().all() else None
    table = bsa_table(population["stature_m"].to_numpy(float) * 100.0, population["mass_kg"].to_numpy(float),
                      None if sex is None else sex.to_numpy(), check=False)
    cols = [c for c in table.columns if c.startswith("bsa_") and c.endswith("_m2")]
    if not cols:
        raise WbsaError("the BSA formula table has no bsa_<key>_m2 columns")
    out = table[cols].reset_index(drop=True)
    out.columns = [c[len("bsa_"):-len("_m2")] for c in cols]
    return out


def formula_labels() -> dict[str, str]:
    """Display name of every formula key (``dubois`` -> "Du Bois & Du Bois")."""
    try:
        from wbsa.formulae import FORMULAE
    except ImportError:  # pragma: no cover - formulae is part of the package
        return {}
    labels = {k: f.name for k, f in FORMULAE.items()}
    labels.update(schlich_male="Schlich (male)", schlich_female="Schlich (female)")
    return labels


def formula_errors(population: pd.DataFrame, spec: GroupSpec = GroupSpec(),
                   groups: tuple[str, ...] = COMPARISON_GROUPS, bsa_table: Callable | None = None) -> pd.DataFrame:
    """Error of every formula against the mesh WBSA, per group.

    Returns
    -------
    DataFrame
        :data:`COMPARISON_COLUMNS`, ``kind`` = ``formula``, ``method`` the formula key:
        ``mape_pct`` = 100·mean(|F − WBSA|/WBSA), ``bias_m2`` = mean(F − WBSA),
        ``bias_pct`` = 100·mean((F − WBSA)/WBSA), ``rmse_m2``; groups without subjects are left out.
    """
    values = formula_values(population, bsa_table)
    wbsa = population["wbsa_m2"].to_numpy(float)
    members = assign_groups(population.reset_index(drop=True), spec)
    labels = formula_labels()
    rows = []
    for g in groups:
        for key in values.columns:
            f = values[key].to_numpy(float)
            ok = members[g].to_numpy() & np.isfinite(f) & np.isfinite(wbsa) & (wbsa > 0)
            if not ok.any():
                continue
            e = f[ok] - wbsa[ok]
            rel = e / wbsa[ok]
            rows.append({"group": g, "kind": KIND_FORMULA, "method": key, "label": labels.get(key, key), "view": "",
                         "n": int(ok.sum()), "mape_pct": float(100 * np.mean(np.abs(rel))),
                         "bias_m2": float(np.mean(e)), "bias_pct": float(100 * np.mean(rel)),
                         "rmse_m2": float(np.sqrt(np.mean(e**2)))})
    return pd.DataFrame(rows, columns=list(COMPARISON_COLUMNS))


def best_worst_views(table: pd.DataFrame, kind: str) -> pd.DataFrame:
    """Rows of a per-view CV table at the view with the lowest and the highest ``cv_mape_pct``.

    Parameters
    ----------
    table : DataFrame
        A fit table or a subgroup CV table (``group``, ``model``, ``predictors``, ``vbsa_column``,
        ``camera``, ``distance_m``, ``azimuth_deg``, ``elevation_deg``, ``n``, ``cv_mape_pct``,
        ``cv_bias_m2``, ``cv_rmse_m2``).
    kind : str
        Value of the ``kind`` column.

    Returns
    -------
    DataFrame
        :data:`COMPARISON_COLUMNS`, two rows (``view`` = best, worst) per group × model × predictors ×
        VBSA column × camera × distance.
    """
    if table.empty:
        return pd.DataFrame(columns=list(COMPARISON_COLUMNS))
    t = table.copy()
    for c in ("group", *_SV_KEYS):
        t[c] = t[c].astype(object) if c != "distance_m" else t[c]
    t = t[np.isfinite(t["cv_mape_pct"].to_numpy(float))]
    by = t.groupby(["group", *_SV_KEYS], sort=False)["cv_mape_pct"]
    parts = []
    for which, idx in (("best", by.idxmin()), ("worst", by.idxmax())):
        part = t.loc[idx.to_numpy()].copy()
        part["view"] = which
        parts.append(part)
    rows = pd.concat(parts, ignore_index=True)
    out = pd.DataFrame({
        "group": rows["group"], "kind": kind,
        "method": rows["model"].astype(str) + " " + rows["predictors"].astype(str),
        "label": rows["model"].astype(str) + " (" + rows["predictors"].astype(str) + "), " + rows["view"] + " view",
        "view": rows["view"], **{c: rows[c] for c in _SV_KEYS},
        "azimuth_deg": rows["azimuth_deg"], "elevation_deg": rows["elevation_deg"], "n": rows["n"],
        "mape_pct": rows["cv_mape_pct"], "bias_m2": rows["cv_bias_m2"], "bias_pct": np.nan,
        "rmse_m2": rows["cv_rmse_m2"],
    })
    return out[list(COMPARISON_COLUMNS)]


def compare_formulae(population: pd.DataFrame, fits: pd.DataFrame, subgroup_cv: pd.DataFrame,
                     spec: GroupSpec = GroupSpec(), groups: tuple[str, ...] = COMPARISON_GROUPS,
                     bsa_table: Callable | None = None) -> pd.DataFrame:
    """Formulae versus single-view models, per group.

    For every group: each formula's MAPE and bias against the mesh WBSA; the single-view
    all-subjects model's CV MAPE within the group at its best and worst view (from
    ``subgroup_cv``); and, where the group was fitted on its own, the group model's CV MAPE at its
    best and worst view (from ``fits``).

    Returns
    -------
    DataFrame
        :data:`COMPARISON_COLUMNS`, grouped by group (in ``groups`` order), then formulae,
        all-subjects model, group model.
    """
    parts = [formula_errors(population, spec, groups, bsa_table),
             best_worst_views(subgroup_cv[subgroup_cv["group"].isin(groups)] if len(subgroup_cv) else subgroup_cv,
                              KIND_ALL_MODEL),
             best_worst_views(fits[fits["group"].isin(groups)] if len(fits) else fits, KIND_GROUP_MODEL)]
    out = pd.concat([p for p in parts if len(p)], ignore_index=True) if any(len(p) for p in parts) else parts[0]
    if out.empty:
        return out
    g_rank = out["group"].map({g: i for i, g in enumerate(groups)})
    k_rank = out["kind"].map({KIND_FORMULA: 0, KIND_ALL_MODEL: 1, KIND_GROUP_MODEL: 2})
    v_rank = out["view"].map({"": 0, "best": 0, "worst": 1})
    m_rank, _ = pd.factorize(out["method"])  # first appearance: formulae in catalogue order
    order = np.lexsort([v_rank.to_numpy(), m_rank, k_rank.to_numpy(), g_rank.to_numpy()])
    return out.iloc[order].reset_index(drop=True)
