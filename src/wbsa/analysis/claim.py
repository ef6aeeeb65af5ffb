"""The paper's central claim, tested: one view against the height/weight formulae, per group.

The paper argues that the height/weight (H/W) formulae fail for obese people, children and other groups
while one depth view sees the body's actual shape. On virtual bodies the fair opponent is not only the
published formulae but an H/W law refitted on the same bodies (log WBSA = a + b·log H + c·log W), with
the same cross-validation folds as the single-view model. This module compares, per group, the
single view's out-of-fold absolute percentage errors (APE) with every published formula's and with the
refitted law's, subject by subject, and puts a paired-bootstrap interval on each difference of mean APE
(MAPE, in percentage points). The single view *wins* when the whole interval lies below 0, *loses*
when it lies above 0, and *ties* otherwise.

Everything here is a pure function of the tables; the report draws the result.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import pandas as pd

from wbsa.analysis.cv import cv_predict, fit_statsmodels, fold_ids
from wbsa.analysis.data import VIEW_KEYS
from wbsa.analysis.design import design_matrix
from wbsa.analysis.formulae_comparison import formula_labels, formula_values
from wbsa.analysis.groups import CLAIM_GROUPS, GROUP_NAMES, GroupSpec, assign_groups, check_group_names
from wbsa.errors import WbsaError

Verdict = Literal["wins", "ties", "loses"]

#: Verdict of a group with fewer subjects than :attr:`ClaimSettings.min_subjects`.
TOO_FEW = "too few subjects"

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
        Groups with fewer subjects at a view get no interval and the verdict :data:`TOO_FEW`.
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
        if int(self.resamples) < 200:
            raise WbsaError(f"resamples = {self.resamples} is too few for a 95 % interval; use 200 or more (e.g. 2000)")
        if not 0.5 < float(self.level) < 1.0:
            raise WbsaError(f"level = {self.level} must lie in (0.5, 1), e.g. 0.95")
        if int(self.min_subjects) < 3:
            raise WbsaError(f"min_subjects = {self.min_subjects} must be at least 3")
        if not self.view_tolerance_deg >= 0:
            raise WbsaError(f"view_tolerance_deg = {self.view_tolerance_deg} must be >= 0")
        check_group_names(self.groups)


@dataclass(frozen=True)
class BootstrapDiff:
    """Paired-bootstrap differences of mean APE, A − B, one entry per comparator B.

    Attributes
    ----------
    diff, lo, hi : (m,) float64
        Observed difference of MAPE (percentage points) and its percentile interval.
    """

    diff: np.ndarray
    lo: np.ndarray
    hi: np.ndarray

    @property
    def verdicts(self) -> list[str]:
        """:func:`verdict` of every interval."""
        return [verdict(lo, hi) for lo, hi in zip(self.lo, self.hi)]


def verdict(lo: float, hi: float) -> Verdict:
    """``wins`` if the interval of (A − B) lies below 0, ``loses`` if above 0, else ``ties``."""
    if hi < 0:
        return "wins"
    if lo > 0:
        return "loses"
    return "ties"


def paired_bootstrap(ape_a: np.ndarray, ape_b: np.ndarray, resamples: int = 2000, level: float = 0.95,
                     seed: int | list[int] | np.random.SeedSequence = 0) -> BootstrapDiff:
    """Percentile interval of mean(ape_a) − mean(ape_b), resampling subjects with replacement.

    Both predictors are evaluated on the same resampled subjects (paired), so what they share (a body
    that is hard for both) cancels. Every comparator uses the same resamples.

    Parameters
    ----------
    ape_a : (n,) float64
        Absolute percentage errors of predictor A (e.g. the single view), one per subject.
    ape_b : (n,) or (n, m) float64
        Those of one or ``m`` comparators, on the same subjects in the same order.
    resamples : int
        Bootstrap resamples.
    level : float
        Interval level.
    seed : int, list of int or SeedSequence
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    BootstrapDiff
        ``(m,)`` arrays (``m = 1`` for a 1-D ``ape_b``).
    """
    a = np.asarray(ape_a, dtype=float)
    b = np.asarray(ape_b, dtype=float)
    if b.ndim == 1:
        b = b[:, None]
    if a.ndim != 1 or b.shape[0] != a.shape[0]:
        raise WbsaError(f"paired bootstrap needs errors of the same subjects: got {a.shape} and {b.shape}")
    n = a.shape[0]
    if n < 2:
        raise WbsaError(f"paired bootstrap needs at least 2 subjects, got {n}")
    if not (np.isfinite(a).all() and np.isfinite(b).all()):
        raise WbsaError("paired bootstrap got non-finite errors; drop the subjects without a prediction first")
    d = a[:, None] - b  # (n, m)
    rng = np.random.default_rng(seed)
    means = np.empty((int(resamples), d.shape[1]))
    chunk = max(1, min(int(resamples), 4_000_000 // n))  # bounded memory: a (chunk, n) count matrix at a time
    p = np.full(n, 1.0 / n)
    for start in range(0, int(resamples), chunk):
        stop = min(int(resamples), start + chunk)
        counts = rng.multinomial(n, p, size=stop - start)  # same law as drawing n subjects with replacement
        means[start:stop] = counts @ d / n
    q = np.quantile(means, [(1 - level) / 2, (1 + level) / 2], axis=0)
    return BootstrapDiff(diff=d.mean(axis=0), lo=q[0], hi=q[1])


def ape_pct(pred_m2: np.ndarray, wbsa_m2: np.ndarray) -> np.ndarray:
    """Absolute percentage error 100·|pred − WBSA|/WBSA, shape of the inputs (broadcast)."""
    y = np.asarray(wbsa_m2, dtype=float)
    return 100.0 * np.abs(np.asarray(pred_m2, dtype=float) - y) / y


# -------------------------------------------------------------------------------------------------------------------
# the height/weight law refitted on the virtual bodies


def hw_law_fit(stature_m: np.ndarray, mass_kg: np.ndarray, wbsa_m2: np.ndarray) -> dict[str, float]:
    """Fit log WBSA = a + b·log H + c·log W by OLS (statsmodels).

    Parameters
    ----------
    stature_m, mass_kg, wbsa_m2 : (n,) float64

    Returns
    -------
    dict
        ``a``, ``b``, ``c`` and their standard errors ``a_se``, ``b_se``, ``c_se``; ``r2`` (log scale);
        ``resid_sd_pct`` = 100·(residual SD on the log scale), about the relative scatter at fixed H and W;
        ``n``. WBSA = e^a · H^b · W^c, H in m and W in kg.
    """
    y = np.log(np.asarray(wbsa_m2, dtype=float))
    X = _hw_design(stature_m, mass_kg)
    res = fit_statsmodels(y, X, None)
    a, b, c = (float(v) for v in res.params)
    a_se, b_se, c_se = (float(v) for v in res.bse)
    return {"a": a, "b": b, "c": c, "a_se": a_se, "b_se": b_se, "c_se": c_se, "r2": float(res.rsquared),
            "resid_sd_pct": 100.0 * float(np.sqrt(res.scale)), "n": int(len(y))}


def hw_law_oof(stature_m: np.ndarray, mass_kg: np.ndarray, wbsa_m2: np.ndarray, folds: np.ndarray) -> np.ndarray:
    """Out-of-fold predictions (m²) of the refitted H/W law: each fold predicted by the law fitted on the others.

    Parameters
    ----------
    stature_m, mass_kg, wbsa_m2 : (n,) float64
    folds : (n,) int64
        Fold of every subject (:func:`wbsa.analysis.cv.fold_ids`), the same as the single-view model's.

    Returns
    -------
    (n,) float64
        exp of the log-scale prediction (the conditional median, as the ``loglog`` view model).
    """
    # the log-log model design with stature in the VBSA slot and mass as the extra predictor is exactly
    # [1, log H, log W]: reuse the fitted models' cross-validation rather than a second loop
    _check_hw_inputs(stature_m, mass_kg, wbsa_m2)
    return cv_predict("loglog", np.asarray(wbsa_m2, float), np.asarray(stature_m, float),
                      {"mass_kg": np.asarray(mass_kg, float)}, np.asarray(folds))


def _hw_design(stature_m: np.ndarray, mass_kg: np.ndarray) -> np.ndarray:
    _check_hw_inputs(stature_m, mass_kg)
    return design_matrix("loglog", np.asarray(stature_m, float), {"mass_kg": np.asarray(mass_kg, float)})


def _check_hw_inputs(*arrays: np.ndarray) -> None:
    for x in arrays:
        x = np.asarray(x, dtype=float)
        if not (np.isfinite(x).all() and (x > 0).all()):
            raise WbsaError("the H/W law needs positive, finite stature, mass and WBSA for every subject")


# -------------------------------------------------------------------------------------------------------------------
# the claim table


@dataclass
class ClaimResult:
    """What :func:`evaluate_claim` found.

    Attributes
    ----------
    comparisons : DataFrame
        :data:`COMPARISON_COLUMNS`: one row per group × VBSA column × view role × comparator (the refitted
        H/W law first, then every published formula). ``diff_pct_points`` = view MAPE − comparator MAPE
        (negative: the view is better), ``diff_lo``/``diff_hi`` its paired-bootstrap interval,
        ``verdict`` wins / ties / loses (or :data:`TOO_FEW`).
    headline : DataFrame
        One row per group × VBSA column × view role: ``n``, the view's MAPE, the refitted law's MAPE and
        the difference with its interval and verdict, the best published formula in the group (label,
        MAPE, difference, interval, verdict) and ``formulae_w_t_l`` (wins / ties / losses over all formulae).
    sentences : dict
        Group -> one plain sentence.
    hw_law : dict
        :func:`hw_law_fit` on all subjects of the population (coefficients, R², residual SD in %).
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
