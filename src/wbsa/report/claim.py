"""The report's opening section: the paper's central claim tested per group (tables from :mod:`wbsa.analysis.claim`)."""

from __future__ import annotations

import re

import numpy as np
import pandas as pd

from wbsa.analysis.bootstrap import TOO_FEW
from wbsa.analysis.claim import ClaimResult, ClaimSettings, evaluate_claim
from wbsa.analysis.claim_sentences import GROUP_PLAIN, vbsa_plain
from wbsa.analysis.groups import GroupSpec
from wbsa.report.data import ReportData


def group_spec_of(fit_info: dict) -> GroupSpec:
    """The fit's group thresholds (``fit_info.json`` settings), or the defaults."""
    spec = fit_info.get("settings", {}).get("group_spec") or {}
    return GroupSpec(**spec) if spec else GroupSpec()


def claim_model(data: ReportData) -> str:
    """Model kind of the single view: the report's model if the fit kept its out-of-fold predictions, else the
    first one kept for the all-subjects fits."""
    r = data.residuals
    if r.empty or "model" not in r:
        return data.model
    kept = list(dict.fromkeys(r.loc[r["group"] == "all", "model"]))
    return data.model if data.model in kept or not kept else kept[0]


def compute_claim(data: ReportData, settings: ClaimSettings = ClaimSettings()) -> ClaimResult:
    """:func:`wbsa.analysis.claim.evaluate_claim` on a report's tables (the fit's folds, groups, camera and the
    reference distance). Raises :class:`wbsa.analysis.claim.ClaimUnavailable` when the fit kept no
    out-of-fold predictions."""
    fs = data.fit_info.get("settings", {})
    return evaluate_claim(data.population, data.residuals, k=int(fs.get("k", 10)), fold_seed=int(fs.get("seed", 0)),
                          group_spec=group_spec_of(data.fit_info), camera=data.camera, distance_m=data.distance_m,
                          model=claim_model(data), settings=settings)


def _pp(x: float) -> str:
    return "" if not np.isfinite(x) else f"{x:+.2f}".replace("-", "−")


def _interval(diff: float, lo: float, hi: float) -> str:
    if not np.isfinite(lo):
        return _pp(diff)
    return f"{_pp(diff)} [{_pp(lo)}, {_pp(hi)}]"


def _area_short(column: str) -> str:
    """``ideal`` for the ideal visible area, else the plain name without 'reconstruction'."""
    return "ideal" if column == "vbsa_visible_m2" else vbsa_plain(column).removesuffix(" reconstruction")


def _short_verdict(v: str) -> str:
    return "too few" if v == TOO_FEW else v


def _view(role: str, az: float, el: float) -> str:
    role = re.sub(r"^[-+\d.]+° oblique", "oblique", role.replace(" = best", ", best"))
    return f"{role} ({az:g}°, {el:g}°)"


def _view_columns(t: pd.DataFrame) -> dict[str, list]:
    """The columns every claim table starts with: group, view area, view, n and the view's MAPE."""
    return {
        "group": [GROUP_PLAIN.get(g, g) for g in t["group"]],
        "view area": [_area_short(v) for v in t["vbsa_column"]],
        "view (θ, φ)": [_view(r, a, e) for r, a, e in zip(t["role"], t["azimuth_deg"], t["elevation_deg"])],
        "n": list(t["n"].astype(int)),
        "view MAPE %": [f"{x:.2f}" for x in t["view_mape_pct"]],
    }


def headline_display(result: ClaimResult) -> pd.DataFrame:
    """The headline table as printed: one row per group × VBSA × view, MAPE in %, differences in points."""
    h = result.headline
    pct = int(round(100 * result.settings.level))
    return pd.DataFrame({
        **_view_columns(h),
        "refitted H/W MAPE %": [f"{x:.2f}" for x in h["hw_refit_mape_pct"]],
        f"view − H/W [{pct} % CI]": [_interval(*t) for t in zip(h["diff_vs_hw"], h["lo_vs_hw"], h["hi_vs_hw"])],
        "vs H/W": [_short_verdict(v) for v in h["verdict_vs_hw"]],
        "best formula": h["best_formula"],
        "its MAPE %": [f"{x:.2f}" for x in h["best_formula_mape_pct"]],
        f"view − formula [{pct} % CI]": [_interval(*t) for t in zip(h["diff_vs_formula"], h["lo_vs_formula"],
                                                                    h["hi_vs_formula"])],
        "vs formula": [_short_verdict(v) for v in h["verdict_vs_formula"]],
        "all formulae W/T/L": h["formulae_w_t_l"],
    })


def comparisons_display(result: ClaimResult) -> pd.DataFrame:
    """Every paired comparison as printed (group, view area, view, comparator, MAPEs, difference and verdict)."""
    c = result.comparisons
    pct = int(round(100 * result.settings.level))
    return pd.DataFrame({
        **_view_columns(c),
        "compared with": c["comparator_label"],
        "its MAPE %": [f"{x:.2f}" for x in c["comparator_mape_pct"]],
        f"view − it [{pct} % CI]": [_interval(*t) for t in zip(c["diff_pct_points"], c["diff_lo"],
                                                                        c["diff_hi"])],
        "verdict": [_short_verdict(v) for v in c["verdict"]],
    })


def method_text(result: ClaimResult, k: int) -> str:
    """The paragraph that says what the headline table compares and how."""
    s = result.settings
    law = result.hw_law
    return (
        "Does one camera view beat height and weight? For every subject the single view's prediction is the "
        f"out-of-fold prediction of the all-subjects {result.model} model with the view area alone ({k}-fold "
        "cross-validation of the fit stage), so no subject is predicted by a model that saw it. It is compared "
        "with every published height/weight formula and with a height/weight law refitted on the same bodies "
        "with the same folds, log WBSA = a + b·log H + c·log W (out of fold too): the fair opponent on virtual "
        f"bodies. On all {law['n']} subjects that law is WBSA = e^{law['a']:.3f} · H^{law['b']:.3f} · "
        f"W^{law['c']:.3f} (H in m, W in kg), R² = {law['r2']:.4f} on the log scale, residual SD "
        f"{law['resid_sd_pct']:.2f} %: the scatter of the mesh area at fixed height and weight, which is all a view "
        "can add. Errors are absolute percentage errors (APE); a difference is the view's MAPE minus the other "
        f"method's, in percentage points, with a {100 * s.level:g} % paired-bootstrap interval ({s.resamples} "
        f"resamples of subjects, seed {s.seed}). The view wins when the whole interval is below 0, loses when it is "
        f"above 0, and ties otherwise; groups with fewer than {s.min_subjects} subjects are not tested. The views are "
        "the front view, the 30° oblique view (both fixed in advance) and the view with the lowest CV MAPE over all "
        "subjects (chosen on the same errors, so its row is optimistic). The models were fitted on all subjects and "
        "are evaluated within each group, as a formula would be.")
