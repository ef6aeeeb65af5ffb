"""The height/weight formulae and the single-view model, MAPE per group, as one grid."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from wbsa.report.figures.style import GROUP_LABELS, FigureUnavailable, new_figure, predictors_title


def formulae_comparison(formulae: pd.DataFrame, groups: tuple[str, ...] | None = None, *, model: str | None = None,
                        vbsa_column: str | None = None, distance_m: float | None = None, camera: str | None = None,
                        dpi: int = 100) -> Figure:
    """MAPE of every BSA formula against the mesh WBSA beside the single-view all-subjects model's CV MAPE
    (best and worst view in the group), as one grid: a row per method, a column per group, the MAPE
    written in every cell.

    Parameters
    ----------
    formulae : DataFrame
        :func:`wbsa.analysis.formulae_comparison.compare_formulae` table.
    groups : tuple of str, optional
        Columns, those present (default: the claim groups, :data:`wbsa.analysis.groups.CLAIM_GROUPS`).
    model, vbsa_column, distance_m, camera : optional
        Keep only the single-view rows of this model, VBSA column, distance and camera.
    """
    from wbsa.analysis.formulae_comparison import KIND_ALL_MODEL, KIND_FORMULA
    from wbsa.analysis.groups import CLAIM_GROUPS

    if formulae.empty:
        raise FigureUnavailable("no formulae comparison table")
    groups = CLAIM_GROUPS if groups is None else groups
    sv = formulae["kind"] == KIND_ALL_MODEL
    for col, value in (("model", model), ("vbsa_column", vbsa_column), ("camera", camera)):
        if value is not None:
            sv &= formulae[col] == value
    if distance_m is not None:
        sv &= np.abs(formulae["distance_m"].astype(float) - float(distance_m)) < 1e-6
    table = formulae[(formulae["kind"] == KIND_FORMULA) | sv]
    present = [g for g in groups if (table["group"] == g).any()]
    if not present:
        raise FigureUnavailable("the formulae comparison has none of the groups " + ", ".join(groups))
    table = table.assign(_row=[_short_label(r) for _, r in table.iterrows()])
    rows = list(dict.fromkeys(table["_row"]))
    grid = table.pivot_table(index="_row", columns="group", values="mape_pct", aggfunc="first").reindex(
        index=rows, columns=present)
    n = table.groupby("group")["n"].max()
    values = grid.to_numpy(float)
    fig = new_figure(1.0 * len(present) + 4.2, 0.34 * len(rows) + 1.4, dpi)
    ax = fig.subplots()
    finite = values[np.isfinite(values)]
    vmax = float(np.quantile(finite, 0.95)) if finite.size else 1.0
    im = ax.imshow(values, cmap="YlOrRd", vmin=0.0, vmax=max(vmax, 1e-6), aspect="auto")
    for i in range(values.shape[0]):
        for j in range(values.shape[1]):
            v = values[i, j]
            if np.isfinite(v):
                ax.text(j, i, f"{v:.2f}", ha="center", va="center", fontsize=9,
                        color="white" if v > 0.7 * vmax else "black")
    ax.set_xticks(range(len(present)))
    ax.set_xticklabels([f"{GROUP_LABELS.get(g, g)}\n(n = {int(n.get(g, 0))})" for g in present], fontsize=9,
                       rotation=30, ha="right", rotation_mode="anchor")
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels(rows, fontsize=9)
    for i, r in enumerate(rows):
        if not r.startswith("one view"):
            continue
        ax.get_yticklabels()[i].set_fontweight("bold")
    n_formulae = int((table.drop_duplicates("_row")["kind"] == KIND_FORMULA).sum())
    if 0 < n_formulae < len(rows):
        ax.axhline(n_formulae - 0.5, color="k", lw=1.5)
    ax.tick_params(top=False, bottom=True, length=0)
    fig.colorbar(im, ax=ax, shrink=0.6, label="MAPE against the mesh WBSA (%)")
    ax.set_title("Height/weight formulae (top) and one camera view (bottom, cross-validated), MAPE in %",
                 fontsize=10)
    return fig


def _short_label(row: pd.Series) -> str:
    if row["kind"] == "formula":
        return str(row["label"])
    return f"one view, {predictors_title(str(row['predictors']))}, {row['view']} view in group"

