"""The paper's central claim, tested: one view against the height/weight formulae, per group.

The paper argues that the height/weight (H/W) formulae fail for obese people, children and other groups
while one depth view sees the body's actual shape. On virtual bodies the fair opponent is not only the
published formulae but an H/W law refitted on the same bodies (log WBSA = a + b·log H + c·log W), with
the same cross-validation folds as the single-view model. This module compares, per group, the
single view's out-of-fold absolute percentage errors (APE) with every published formula's and with the
refitted law's, subject by subject, and puts a paired-bootstrap interval on each difference of mean APE
(MAPE, in percentage points). The single view *wins* when the whole interval lies below 0, *loses*
when it lies above 0, and *ties* otherwise.

Everything here is a pure function of the tables; the report draws the result. This module assembles
the comparison and headline tables; the paired bootstrap and the verdicts are in
:mod:`wbsa.analysis.bootstrap`, the refitted law in :mod:`wbsa.analysis.hw_law` and the sentences in
:mod:`wbsa.analysis.claim_sentences`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from wbsa.analysis.bootstrap import TOO_FEW, ape_pct, paired_bootstrap
from wbsa.analysis.claim_sentences import group_sentences
from wbsa.analysis.cv import fold_ids
from wbsa.analysis.data import VIEW_KEYS
from wbsa.analysis.formulae_comparison import formula_labels, formula_values
from wbsa.analysis.groups import CLAIM_GROUPS, GROUP_NAMES, GroupSpec, assign_groups, check_group_names
from wbsa.analysis.hw_law import hw_law_fit, hw_law_oof
from wbsa.errors import WbsaError
from wbsa.settings_io import check_types

#: Comparator key and label of the refitted height/weight law.
HW_KEY = "hw_refit"
HW_LABEL = "H/W law refitted on these bodies"

#: Kinds of comparator.
KIND_REFIT = "refitted H/W law"
KIND_FORMULA = "published formula"

#: Columns of :attr:`ClaimResult.comparisons`, in order.
COMPARISON_COLUMNS: tuple[str, ...] = (
    "group", "vbsa_column", "role", "camera", "distance_m", "azimuth_deg", "elevation_deg", "n", "view_mape_pct",
    "comparator", "comparator_label", "comparator_kind", "comparator_mape_pct", "diff_pct_points", "diff_lo",
    "diff_hi", "verdict",
)


class ClaimUnavailable(WbsaError):
    """The tables lack what the claim test needs; the message says what."""


@dataclass(frozen=True)
class ClaimSettings:
    """How the claim is tested.

    Attributes
    ----------
    resamples : int
        Paired-bootstrap resamples of subjects (>= 200).
    level : float
        Confidence level of the percentile intervals, in (0.5, 1).
    seed : int
        Root seed of the bootstrap; each group draws from ``SeedSequence([seed, group index])``.
    front_view_deg, oblique_view_deg : (float, float)
        (azimuth, elevation) of the front and the oblique view tested; the scanned view nearest to each
        is used if it lies within ``view_tolerance_deg``, else that role is left out.
    view_tolerance_deg : float
        Largest angular distance between an asked and a scanned view.
    predictors : str
        Predictor-set label of the single-view model (``vbsa``: the view alone, paper eq. 5–7).
    groups : tuple of str
        Groups tested, in table order (:data:`wbsa.analysis.groups.CLAIM_GROUPS`).
    min_subjects : int
        Groups with fewer subjects at a view get no interval and the verdict
        :data:`~wbsa.analysis.bootstrap.TOO_FEW`.
    """

    resamples: int = 2000
    level: float = 0.95
    seed: int = 0
    front_view_deg: tuple[float, float] = (0.0, 0.0)
    oblique_view_deg: tuple[float, float] = (30.0, 0.0)
    view_tolerance_deg: float = 1.0
    predictors: str = "vbsa"
    groups: tuple[str, ...] = CLAIM_GROUPS
    min_subjects: int = 10

    def __post_init__(self) -> None:
        check_types(self)
        if int(self.resamples) < 200:
            raise WbsaError(f"resamples = {self.resamples} is too few for a 95 % interval; use 200 or more (e.g. 2000)")
        if not 0.5 < float(self.level) < 1.0:
            raise WbsaError(f"level = {self.level} must lie in (0.5, 1), e.g. 0.95")
        if int(self.min_subjects) < 3:
            raise WbsaError(f"min_subjects = {self.min_subjects} must be at least 3")
        if not self.view_tolerance_deg >= 0:
            raise WbsaError(f"view_tolerance_deg = {self.view_tolerance_deg} must be >= 0")
        check_group_names(self.groups)



@dataclass
class ClaimResult:
    """What :func:`evaluate_claim` found.

    Attributes
    ----------
    comparisons : DataFrame
        :data:`COMPARISON_COLUMNS`: one row per group × VBSA column × view role × comparator (the refitted
        H/W law first, then every published formula). ``diff_pct_points`` = view MAPE − comparator MAPE
        (negative: the view is better), ``diff_lo``/``diff_hi`` its paired-bootstrap interval,
        ``verdict`` wins / ties / loses (or :data:`~wbsa.analysis.bootstrap.TOO_FEW`).
    headline : DataFrame
        One row per group × VBSA column × view role: ``n``, the view's MAPE, the refitted law's MAPE and
        the difference with its interval and verdict, the best published formula in the group (label,
        MAPE, difference, interval, verdict) and ``formulae_w_t_l`` (wins / ties / losses over all formulae).
    sentences : dict
        Group -> one plain sentence.
    hw_law : dict
        :func:`~wbsa.analysis.hw_law.hw_law_fit` on all subjects of the population (coefficients, R², residual
        SD in %).
    settings : ClaimSettings
    model : str
        Model kind of the single view.
    """

    comparisons: pd.DataFrame
    headline: pd.DataFrame
    sentences: dict[str, str]
    hw_law: dict
    settings: ClaimSettings
    model: str = "linear"


def view_roles(view_mape: pd.DataFrame, settings: ClaimSettings) -> list[tuple[str, float, float]]:
    """The views tested: (role, azimuth, elevation) for front, oblique and the best view by CV MAPE.

    Parameters
    ----------
    view_mape : DataFrame
        ``azimuth_deg``, ``elevation_deg``, ``mape_pct`` of every scanned view (one VBSA column).

    Returns
    -------
    list
        Roles in order front, oblique, best; a role whose asked view is not scanned (farther than
        ``view_tolerance_deg``) is left out; the best view, when it is the front or the oblique view,
        is named in that role (``30° oblique = best``) rather than repeated.
    """
    views = view_mape[["azimuth_deg", "elevation_deg"]].to_numpy(float)
    roles: list[tuple[str, float, float]] = []
    for name, (az0, el0) in (("front", settings.front_view_deg),
                             (f"{settings.oblique_view_deg[0]:g}° oblique", settings.oblique_view_deg)):
        ang = _angular_distance_deg(views, az0, el0)
        i = int(np.argmin(ang))
        if ang[i] <= settings.view_tolerance_deg + 1e-9:
            roles.append((name, float(views[i, 0]), float(views[i, 1])))
    j = int(np.argmin(view_mape["mape_pct"].to_numpy(float)))
    best = (float(views[j, 0]), float(views[j, 1]))
    for i, (name, az, el) in enumerate(roles):
        if (az, el) == best:
            roles[i] = (f"{name} = best", az, el)
            return roles
    roles.append(("best", *best))
    return roles


def _angular_distance_deg(views: np.ndarray, azimuth_deg: float, elevation_deg: float) -> np.ndarray:
    a, e = np.radians(views[:, 0]), np.radians(views[:, 1])
    a0, e0 = np.radians(azimuth_deg), np.radians(elevation_deg)
    cos = np.sin(e) * np.sin(e0) + np.cos(e) * np.cos(e0) * np.cos(a - a0)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def evaluate_claim(population: pd.DataFrame, residuals: pd.DataFrame, *, k: int, fold_seed: int,
               group_spec: GroupSpec = GroupSpec(), camera: str | None = None, distance_m: float | None = None,
               model: str = "linear", settings: ClaimSettings = ClaimSettings()) -> ClaimResult:
    """Single view against the refitted H/W law and every published formula, per group.

    Parameters
    ----------
    population : DataFrame
        ``subject_id``, ``sex``, ``age_years``, ``stature_m``, ``mass_kg``, ``bmi``, ``wbsa_m2``.
    residuals : DataFrame
        The fit stage's ``residuals.parquet``: per subject and view, ``cv_pred_m2``, the out-of-fold
        prediction of the all-subjects model (``group`` = all) of kind ``model`` and predictor set
        ``settings.predictors``, for each VBSA column fitted.
    k, fold_seed : int
        The fit's folds (``FitSettings.k`` and ``seed``): the H/W law is cross-validated on the same folds.
    group_spec : GroupSpec
        Group thresholds (the fit's).
    camera, distance_m : optional
        The camera and distance tested (default: the only one in ``residuals``, else the first).
    model : str
        Model kind of the single view.
    settings : ClaimSettings

    Returns
    -------
    ClaimResult

    Raises
    ------
    ClaimUnavailable
        No out-of-fold predictions of that model in ``residuals``.
    """
    r = _view_predictions(residuals, model, settings.predictors, camera, distance_m)
    pop = population.reset_index(drop=True)
    need = [c for c in ("subject_id", "stature_m", "mass_kg", "wbsa_m2", "sex", "age_years", "bmi") if c not in pop]
    if need:
        raise ClaimUnavailable(f"the population lacks column(s) {', '.join(need)}")
    ids = pop["subject_id"].to_numpy()
    folds_all = fold_ids(ids, k, fold_seed)  # the fit's folds of group "all": they depend only on the ids
    members = assign_groups(pop, group_spec)
    formulas = formula_values(pop)
    f_keys = list(formulas.columns)
    f_labels = formula_labels()
    H, W, Y = (pop[c].to_numpy(float) for c in ("stature_m", "mass_kg", "wbsa_m2"))
    hw_law = hw_law_fit(H, W, Y)

    rows = []
    for vcol in sorted(dict.fromkeys(r["vbsa_column"]), key=_vbsa_rank):
        rv = r[r["vbsa_column"] == vcol]
        per_view = (rv.assign(_ape=ape_pct(rv["cv_pred_m2"], rv["wbsa_m2"]))
                    .groupby(["azimuth_deg", "elevation_deg"], sort=True)["_ape"].mean()
                    .rename("mape_pct").reset_index())
        for role, az, el in view_roles(per_view, settings):
            at = rv[(rv["azimuth_deg"] == az) & (rv["elevation_deg"] == el)]
            pos = pd.Index(ids).get_indexer(at["subject_id"].to_numpy())
            if (pos < 0).any():
                raise ClaimUnavailable("the residuals name subjects missing from the population; "
                                       "give the population the fit was made from")
            y = Y[pos]
            ape_view = ape_pct(at["cv_pred_m2"].to_numpy(float), y)
            hw = hw_law_oof(H[pos], W[pos], y, folds_all[pos])
            others = np.column_stack([ape_pct(hw, y)] + [ape_pct(formulas[c].to_numpy(float)[pos], y) for c in f_keys])
            keys = [HW_KEY, *f_keys]
            labels = [HW_LABEL, *(f_labels.get(c, c) for c in f_keys)]
            kinds = [KIND_REFIT] + [KIND_FORMULA] * len(f_keys)
            view_key = {"camera": at["camera"].iloc[0], "distance_m": float(at["distance_m"].iloc[0]),
                        "azimuth_deg": az, "elevation_deg": el}
            for g in settings.groups:
                m = members[g].to_numpy()[pos] & np.isfinite(others).all(axis=1)
                n = int(m.sum())
                if n == 0:
                    continue
                if n >= settings.min_subjects:
                    seed = np.random.SeedSequence([int(settings.seed), GROUP_NAMES.index(g)])
                    bs = paired_bootstrap(ape_view[m], others[m], settings.resamples, settings.level, seed)
                    diff, lo, hi, verdicts = bs.diff, bs.lo, bs.hi, bs.verdicts
                else:
                    diff = ape_view[m].mean() - others[m].mean(axis=0)
                    lo = hi = np.full(len(keys), np.nan)
                    verdicts = [TOO_FEW] * len(keys)
                view_mape = float(ape_view[m].mean())
                for j, key in enumerate(keys):
                    rows.append({"group": g, "vbsa_column": vcol, "role": role, **view_key, "n": n,
                                 "view_mape_pct": view_mape, "comparator": key, "comparator_label": labels[j],
                                 "comparator_kind": kinds[j], "comparator_mape_pct": float(others[m, j].mean()),
                                 "diff_pct_points": float(diff[j]), "diff_lo": float(lo[j]), "diff_hi": float(hi[j]),
                                 "verdict": verdicts[j]})
    comparisons = pd.DataFrame(rows, columns=list(COMPARISON_COLUMNS))
    comparisons = _in_group_order(comparisons, settings.groups)
    headline = headline_table(comparisons)
    return ClaimResult(comparisons=comparisons, headline=headline,
                       sentences=group_sentences(headline), hw_law=hw_law, settings=settings,
                       model=model)


def _view_predictions(residuals: pd.DataFrame, model: str, predictors: str, camera: str | None,
                      distance_m: float | None) -> pd.DataFrame:
    need = {"group", "model", "predictors", "vbsa_column", "subject_id", "wbsa_m2", "cv_pred_m2", *VIEW_KEYS}
    if residuals.empty or not need <= set(residuals.columns):
        raise ClaimUnavailable("the fit kept no out-of-fold predictions (residuals.parquet); fit with "
                               "residual_groups = [\"all\"] and the model in residual_models")
    r = residuals[(residuals["group"].astype(str) == "all") & (residuals["model"].astype(str) == model)
                  & (residuals["predictors"].astype(str) == predictors)]
    if r.empty:
        raise ClaimUnavailable(f"the fit kept no out-of-fold predictions of the all-subjects {model} model with "
                               f"predictors {predictors}; add \"all\" to residual_groups and {model} to residual_models")
    r = r.assign(camera=r["camera"].astype(str), vbsa_column=r["vbsa_column"].astype(str))
    cam = camera if camera is not None else sorted(r["camera"].unique())[0]
    r = r[r["camera"] == cam]
    if distance_m is None:
        distance_m = float(sorted(r["distance_m"].unique())[0])
    r = r[np.abs(r["distance_m"].to_numpy(float) - float(distance_m)) < 1e-6]
    r = r[np.isfinite(r["cv_pred_m2"].to_numpy(float))]
    if r.empty:
        raise ClaimUnavailable(f"no out-of-fold predictions for camera {cam} at {distance_m:g} m")
    return r


def _vbsa_rank(column: str) -> int:
    """Ideal visible area first, then the ideal hit triangles, then the sensor reconstructions."""
    return {"vbsa_visible_m2": 0, "vbsa_hit_m2": 1}.get(column, 2)


def _in_group_order(df: pd.DataFrame, groups: tuple[str, ...]) -> pd.DataFrame:
    """Rows by group (in ``groups`` order), then VBSA column and role as first met, comparators as added."""
    if df.empty:
        return df
    g = df["group"].map({x: i for i, x in enumerate(groups)}).to_numpy()
    v, _ = pd.factorize(df["vbsa_column"])
    return df.iloc[np.lexsort([np.arange(len(df)), v, g])].reset_index(drop=True)


def headline_table(comparisons: pd.DataFrame) -> pd.DataFrame:
    """One row per group × VBSA column × view role (see :attr:`ClaimResult.headline`)."""
    cols = ["group", "vbsa_column", "role", "azimuth_deg", "elevation_deg", "n", "view_mape_pct",
            "hw_refit_mape_pct", "diff_vs_hw", "lo_vs_hw", "hi_vs_hw", "verdict_vs_hw", "best_formula",
            "best_formula_mape_pct", "diff_vs_formula", "lo_vs_formula", "hi_vs_formula", "verdict_vs_formula",
            "formulae_w_t_l"]
    out = []
    for _, part in comparisons.groupby(["group", "vbsa_column", "role"], sort=False):
        hw = part[part["comparator_kind"] == KIND_REFIT].iloc[0]
        f = part[part["comparator_kind"] == KIND_FORMULA]
        best = f.loc[f["comparator_mape_pct"].idxmin()]
        counts = f["verdict"].value_counts()
        out.append({
            "group": hw["group"], "vbsa_column": hw["vbsa_column"], "role": hw["role"],
            "azimuth_deg": hw["azimuth_deg"], "elevation_deg": hw["elevation_deg"], "n": int(hw["n"]),
            "view_mape_pct": hw["view_mape_pct"], "hw_refit_mape_pct": hw["comparator_mape_pct"],
            "diff_vs_hw": hw["diff_pct_points"], "lo_vs_hw": hw["diff_lo"], "hi_vs_hw": hw["diff_hi"],
            "verdict_vs_hw": hw["verdict"], "best_formula": best["comparator_label"],
            "best_formula_mape_pct": best["comparator_mape_pct"], "diff_vs_formula": best["diff_pct_points"],
            "lo_vs_formula": best["diff_lo"], "hi_vs_formula": best["diff_hi"], "verdict_vs_formula": best["verdict"],
            "formulae_w_t_l": ("/".join(str(int(counts.get(v, 0))) for v in ("wins", "ties", "loses"))
                               if counts.reindex(["wins", "ties", "loses"]).fillna(0).sum() else ""),
        })
    return pd.DataFrame(out, columns=cols)

