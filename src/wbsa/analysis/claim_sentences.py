"""The claim test in words: one plain sentence per group from the headline table of :mod:`wbsa.analysis.claim`."""

from __future__ import annotations

import pandas as pd

from wbsa.analysis.bootstrap import TOO_FEW


#: Plain names of the claim groups in sentences.
GROUP_PLAIN: dict[str, str] = {
    "all": "All subjects", "adults": "Adults", "kids": "Children", "obese": "Obese subjects",
    "underweight": "Underweight adults", "small": "Small subjects", "tall": "Tall subjects", "females": "Women",
    "males": "Men", "normal": "Subjects of normal stature", "big": "Very tall subjects (paper's big)",
}


def vbsa_plain(column: str) -> str:
    """``vbsa_visible_m2`` -> 'ideal visible area'; ``vbsa_recon_grid_m2`` -> 'sensor + grid reconstruction'."""
    if column == "vbsa_visible_m2":
        return "ideal visible area"
    if column == "vbsa_hit_m2":
        return "ideal hit triangles"
    if column.startswith("vbsa_recon_"):
        return f"sensor + {column.removeprefix('vbsa_recon_').removesuffix('_m2').replace('_', '-')} reconstruction"
    return column


#: Verb of each verdict in the sentences.
_VERB = {"wins": "beats", "ties": "ties with", "loses": "loses to"}


def group_sentences(headline: pd.DataFrame) -> dict[str, str]:
    """One plain sentence per group: does each view beat, tie with or lose to the H/W law refitted on the
    same bodies and the group's best published formula (the numbers are in the headline table)."""
    out = {}
    for g, part in headline.groupby("group", sort=False):
        n = int(part["n"].max())
        if (part["verdict_vs_hw"] == TOO_FEW).all():
            out[g] = f"{GROUP_PLAIN.get(g, g)} (n = {n}): too few subjects to test."
            continue
        clauses = []
        for vcol, pv in part.groupby("vbsa_column", sort=False):
            views = []
            for i, (_, row) in enumerate(pv.iterrows()):
                name = _role_plain(row)
                v_hw, v_f = row["verdict_vs_hw"], row["verdict_vs_formula"]
                if v_hw == TOO_FEW:
                    views.append(f"the {name} has too few subjects")
                elif v_hw == v_f:
                    both = f"both the refitted H/W law and {row['best_formula']}" if i == 0 else "both"
                    views.append(f"the {name} {_VERB[v_hw]} {both}")
                else:
                    law, formula = (("the refitted H/W law", row["best_formula"]) if i == 0
                                    else ("the law", "the formula"))
                    views.append(f"the {name} {_VERB[v_hw]} {law} and {_VERB[v_f]} {formula}")
            clauses.append(f"with the {vbsa_plain(vcol)} " + ", ".join(views))
        out[g] = f"{GROUP_PLAIN.get(g, g)} (n = {n}): " + "; ".join(clauses) + "."
    return out


def _role_plain(row: pd.Series) -> str:
    role = str(row["role"])
    if role == "best":
        return f"best view (θ = {row['azimuth_deg']:g}°, φ = {row['elevation_deg']:g}°)"
    if role.endswith("= best"):
        return f"{role.removesuffix(' = best')} view (the best)"
    return f"{role} view"

