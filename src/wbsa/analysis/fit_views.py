"""Fit every view × group × model × predictor set: the fit table, diagnostics and the model file."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field

import numpy as np
import pandas as pd

from wbsa.analysis.cv import cv_metrics, fold_ids
from wbsa.analysis.data import VIEW_KEYS, join_tables, resolve_predictor, resolve_vbsa_column
from wbsa.analysis.design import MODEL_DESCRIPTIONS, check_model_kinds
from wbsa.analysis.groups import GROUP_NAMES, PAPER_GROUPS, GroupSpec, assign_groups, check_group_names
from wbsa.analysis.model_file import WbsaModel
from wbsa.analysis.regression import CannotFit, fit_arrays
from wbsa.analysis.residuals import qq_quantiles, residual_frame
from wbsa.core.limits import check_seed
from wbsa.errors import WbsaError
from wbsa.progress import progress

#: Key columns of every per-fit table, in order.
FIT_KEYS: tuple[str, ...] = ("group", "model", "predictors", "vbsa_column", *VIEW_KEYS)

#: Columns of the subgroup CV table.
SUBGROUP_COLUMNS: list[str] = [*FIT_KEYS, "fit_group", "n", "cv_rmse_m2", "cv_mspe_m4", "cv_mape_pct", "cv_bias_m2"]


@dataclass(frozen=True)
class FitSettings:
    """What :func:`fit_all` fits.

    Attributes
    ----------
    vbsa_columns : tuple of str
        VBSA selectors (``vbsa_hit_m2``, ``vbsa_visible_m2``, ``vbsa_recon_m2:<method>``), one fit each.
    predictor_sets : tuple of tuple of str
        Extra predictors besides VBSA, one fit per set; ``()`` is the VBSA-only model of eq. 5–7,
        ``('stature_m',)`` eq. 8 with stature. Aliases (``stature``, ``mass``, ``age``, ``sex``) are resolved.
    models : tuple of str
        Model kinds (:data:`wbsa.analysis.design.MODEL_KINDS`).
    groups : tuple of str
        Groups fitted, each on its own (:data:`wbsa.analysis.groups.GROUP_NAMES`).
    group_spec : GroupSpec
        Group thresholds.
    k : int
        Cross-validation folds (paper: 10).
    seed : int
        Seed of the fold assignment (folds are per group, by subject, the same at every view).
    require_in_frame : bool
        Drop scan rows whose body is cut by the image border (``fits_in_frame`` False).
    qq_points : int
        Quantiles per fit in the QQ table.
    residual_groups, residual_models : tuple of str
        Fits whose per-subject residuals are kept (the table grows as subjects × views).
    population_kind : str
        Label of the population (e.g. ``random``, ``survey``), recorded in the model file.
    """

    vbsa_columns: tuple[str, ...] = ("vbsa_visible_m2",)
    predictor_sets: tuple[tuple[str, ...], ...] = ((), ("stature_m",))
    models: tuple[str, ...] = ("linear", "loglog", "wls")
    groups: tuple[str, ...] = PAPER_GROUPS
    group_spec: GroupSpec = field(default_factory=GroupSpec)
    k: int = 10
    seed: int = 0
    require_in_frame: bool = True
    qq_points: int = 99
    residual_groups: tuple[str, ...] = ("all",)
    residual_models: tuple[str, ...] = ("linear",)
    population_kind: str = "unknown"

    def __post_init__(self) -> None:
        if int(self.k) < 2:
            raise WbsaError(f"k = {self.k} folds is too few; use --k 2 or more (paper: 10)")
        check_seed(self.seed, "the fold seed")
        if int(self.qq_points) < 2:
            raise WbsaError(f"qq_points = {self.qq_points} is too few; use 2 or more")
        check_model_kinds(self.models)
        check_group_names(self.groups)
        if not self.vbsa_columns:
            raise WbsaError("no VBSA column given; use --vbsa vbsa_visible_m2")
        if not self.predictor_sets:
            raise WbsaError("no predictor set given; use () for VBSA only")
        if self.residual_groups:
            check_group_names(self.residual_groups)
        if self.residual_models:
            check_model_kinds(self.residual_models)

    def to_dict(self) -> dict:
        """Plain-JSON form of the settings."""
        d = asdict(self)
        d["predictor_sets"] = [list(s) for s in self.predictor_sets]
        return d


@dataclass
class FitOutput:
    """Everything :func:`fit_all` produces.

    Attributes
    ----------
    fits : DataFrame
        One row per group × model × predictor set × VBSA column × view (:data:`FIT_KEYS`), with
        ``n``, ``n_excluded``, coefficients ``c0, c0_se, c0_t, c1, c1_se, c1_t, c_<term>...``, ``r2``,
        ``rse_m2``, ``cv_rmse_m2``, ``cv_mspe_m4``, ``cv_mape_pct``, ``cv_bias_m2``, ``bp_stat``,
        ``bp_pvalue``, ``df_resid``, ``scale``, ``wbsa_mean_m2``, ``vbsa_mean_m2``.
    skipped : DataFrame
        :data:`FIT_KEYS`, ``n`` and ``reason`` of every combination not fitted.
    residuals : DataFrame
        :data:`FIT_KEYS` plus :func:`wbsa.analysis.residuals.residual_frame` columns, for the
        residual groups and models.
    qq : DataFrame
        :data:`FIT_KEYS` plus ``p``, ``theoretical``, ``sample`` for every fit.
    subgroup_cv : DataFrame
        Cross-validated errors of the all-subjects model evaluated within each group
        (``group`` = evaluated group, every name of :data:`GROUP_NAMES`): :data:`FIT_KEYS`, ``n``,
        ``cv_rmse_m2``, ``cv_mspe_m4``, ``cv_mape_pct``, ``cv_bias_m2``. Empty if ``all`` is not fitted.
    model : WbsaModel
        The fitted models, ready to save and predict.
    info : dict
        Counts (subjects, views, rows out of frame) and the run time in seconds.
    """

    fits: pd.DataFrame
    skipped: pd.DataFrame
    residuals: pd.DataFrame
    qq: pd.DataFrame
    subgroup_cv: pd.DataFrame
    model: WbsaModel
    info: dict


def predictors_label(predictors: tuple[str, ...]) -> str:
    """Fit-table label of a predictor set: ``vbsa`` or ``vbsa+stature_m+...``."""
    return "+".join(("vbsa", *predictors))


def _resolve_sets(settings: FitSettings, columns: pd.Index) -> tuple[tuple[str, ...], ...]:
    sets = []
    for s in settings.predictor_sets:
        cols = tuple(dict.fromkeys(resolve_predictor(p, columns) for p in s))
        if cols not in sets:
            sets.append(cols)
    return tuple(sets)


def fit_all(population: pd.DataFrame, scan: pd.DataFrame, settings: FitSettings = FitSettings(),
            show_progress: bool | None = None) -> FitOutput:
    """Fit and cross-validate every view of the scan for every group, model and predictor set.

    Parameters
    ----------
    population : DataFrame
        Population table (one row per subject; see the pinned interface).
    scan : DataFrame
        Scan table (one row per subject × view).
    settings : FitSettings
        What to fit.
    show_progress : bool, optional
        Progress bar on stderr (default: when stderr is a terminal).

    Returns
    -------
    FitOutput
    """
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):  # many small solves: threads only add overhead
        return _fit_all(population, scan, settings, show_progress)


def _fit_all(population: pd.DataFrame, scan: pd.DataFrame, settings: FitSettings,
             show_progress: bool | None) -> FitOutput:
    t0 = time.perf_counter()
    vbsa_columns = tuple(dict.fromkeys(resolve_vbsa_column(c) for c in settings.vbsa_columns))
    sets = _resolve_sets(settings, population.columns)
    all_predictors = tuple(dict.fromkeys(p for s in sets for p in s))
    joined = join_tables(population, scan, vbsa_columns, all_predictors, settings.require_in_frame)
    table = joined.table

    pop = population.reset_index(drop=True)
    members = assign_groups(pop, settings.group_spec)
    pop_ids = pop["subject_id"].to_numpy()
    pop_pos = pd.Index(pop_ids).get_indexer(table["subject_id"].to_numpy())
    member_rows = members.to_numpy()[pop_pos]  # (rows, groups) bool
    gcol = {g: i for i, g in enumerate(members.columns)}
    folds_by_group = {}
    for g in settings.groups:
        f = np.full(len(pop), -1, dtype=np.int64)
        m = members[g].to_numpy()
        f[m] = fold_ids(pop_ids[m], settings.k, settings.seed)
        folds_by_group[g] = f[pop_pos]

    wbsa = table["wbsa_m2"].to_numpy(float)
    sid_all = table["subject_id"].to_numpy()
    extra_all = {p: table[p].to_numpy(float) for p in all_predictors}
    view_groups = table.groupby(list(VIEW_KEYS), sort=True).indices

    fit_rows, skipped, resid_frames, qq_frames, sub_rows, entries = [], [], [], [], [], []
    bar = progress(total=len(view_groups) * len(vbsa_columns), desc="fit", unit="view", enabled=show_progress)
    for vcol in vbsa_columns:
        vbsa_all = table[vcol].to_numpy(float)
        for view, idx in view_groups.items():
            view_key = dict(zip(VIEW_KEYS, view))
            y, v, sid, mem = wbsa[idx], vbsa_all[idx], sid_all[idx], member_rows[idx]
            base_ok = np.isfinite(y) & np.isfinite(v)
            for g in settings.groups:
                in_group = mem[:, gcol[g]]
                folds = folds_by_group[g][idx]
                for pset in sets:
                    ok = in_group & base_ok
                    for p in pset:
                        ok &= np.isfinite(extra_all[p][idx])
                    extras = {p: extra_all[p][idx][ok] for p in pset}
                    for model in settings.models:
                        key = {"group": g, "model": model, "predictors": predictors_label(pset),
                               "vbsa_column": vcol, **view_key}
                        try:
                            fit = fit_arrays(model, y[ok], v[ok], extras, folds[ok], k=settings.k)
                        except CannotFit as exc:
                            skipped.append({**key, "n": int(ok.sum()), "reason": str(exc)})
                            continue
                        fit_id = len(fit_rows)
                        fit_rows.append({**key, "n": fit.n, "n_excluded": int(in_group.sum() - ok.sum()),
                                         **fit.statistics(), "wbsa_mean_m2": float(y[ok].mean()),
                                         "vbsa_mean_m2": float(v[ok].mean())})
                        entries.append({"group": g, "vbsa_column": vcol, **view_key, **fit.model_entry()})
                        qq_frames.append((fit_id, qq_quantiles(fit.standardized, settings.qq_points)))
                        if g in settings.residual_groups and model in settings.residual_models:
                            resid_frames.append((fit_id, residual_frame(sid[ok], y[ok], fit)))
                        if g == "all":
                            sub_mem = mem[ok]
                            for c in GROUP_NAMES:
                                cm = sub_mem[:, gcol[c]]
                                if cm.any():
                                    sub_rows.append({**key, "group": c, "fit_group": "all", "n": int(cm.sum()),
                                                     **cv_metrics(y[ok][cm], fit.cv_pred_m2[cm])})
            bar.update(1)
    bar.close()

    fits = _order_columns(pd.DataFrame(fit_rows, columns=None if fit_rows else [*FIT_KEYS, "n"]))
    order = _sort_order(fits, settings.groups, settings.models)
    rank = np.empty(len(order), dtype=np.int64)
    rank[order] = np.arange(len(order))
    fits = fits.iloc[order].reset_index(drop=True)
    meta = {
        "population_kind": settings.population_kind,
        "cameras": sorted(table["camera"].unique().tolist()),
        "distances_m": sorted(float(d) for d in table["distance_m"].unique()),
        "vbsa_columns": list(vbsa_columns),
        "predictor_sets": [list(s) for s in sets],
        "groups": {g: settings.group_spec.describe()[g] for g in settings.groups},
        "models": {m: MODEL_DESCRIPTIONS[m] for m in settings.models},
        "settings": settings.to_dict(),
    }
    info = {
        "n_subjects": int(table["subject_id"].nunique()),
        "n_views": len(view_groups),
        "n_rows": len(table),
        "n_out_of_frame": joined.n_out_of_frame,
        "n_subjects_not_scanned": joined.n_subjects_not_scanned,
        "n_fits": len(fits),
        "n_skipped": len(skipped),
        "seconds": time.perf_counter() - t0,
    }
    return FitOutput(
        fits=fits,
        skipped=_sorted(pd.DataFrame(skipped, columns=[*FIT_KEYS, "n", "reason"]), settings.groups, settings.models),
        residuals=_stack(resid_frames, fits, rank),
        qq=_stack(qq_frames, fits, rank),
        subgroup_cv=_sorted(pd.DataFrame(sub_rows, columns=SUBGROUP_COLUMNS), GROUP_NAMES, settings.models),
        model=WbsaModel(entries=[entries[i] for i in order], meta=meta),
        info=info,
    )


def fit_views(population: pd.DataFrame, scan: pd.DataFrame, settings: FitSettings = FitSettings()) -> pd.DataFrame:
    """The fit table of :func:`fit_all` (one row per group × model × predictors × VBSA column × view)."""
    return fit_all(population, scan, settings).fits


def _stack(blocks: list[tuple[int, pd.DataFrame]], fits: pd.DataFrame, rank: np.ndarray) -> pd.DataFrame:
    """Concatenate per-fit frames in fit-table order, each row prefixed by its fit's keys (strings as categories).

    ``blocks`` holds (fit id in creation order, frame); ``rank[fit_id]`` is the fit's row in ``fits``.
    """
    keys = fits[list(FIT_KEYS)].copy()
    for c in ("group", "model", "predictors", "vbsa_column", "camera"):
        keys[c] = keys[c].astype("category")
    if not blocks:
        return keys.iloc[:0].reset_index(drop=True)
    blocks = sorted(((int(rank[i]), df) for i, df in blocks), key=lambda b: b[0])
    ids = np.concatenate([np.full(len(df), r, dtype=np.int64) for r, df in blocks])
    body = pd.concat([df for _, df in blocks], ignore_index=True)
    head = keys.iloc[ids].reset_index(drop=True)
    return pd.concat([head, body], axis=1)


def _order_columns(fits: pd.DataFrame) -> pd.DataFrame:
    """Keys, counts, c0 and c1 statistics, the other coefficients (``c_*``), then the fit statistics."""
    head = [*FIT_KEYS, "n", "n_excluded", "c0", "c0_se", "c0_t", "c1", "c1_se", "c1_t"]
    head = [c for c in head if c in fits.columns]
    coefs = [c for c in fits.columns if c.startswith("c_") and c not in head]
    rest = [c for c in fits.columns if c not in head and c not in coefs]
    return fits[head + coefs + rest]


def _sort_order(df: pd.DataFrame, groups: tuple[str, ...], models: tuple[str, ...]) -> np.ndarray:
    """Row order of a per-fit table: group and model in the given order, then predictors, VBSA column, view."""
    if df.empty:
        return np.arange(0)
    g_rank = df["group"].map({g: i for i, g in enumerate(groups)}).to_numpy()
    m_rank = df["model"].map({m: i for i, m in enumerate(models)}).to_numpy()
    cols = [df[c].to_numpy() for c in ("azimuth_deg", "elevation_deg", "distance_m", "camera", "vbsa_column",
                                       "predictors")]
    return np.lexsort([*cols, m_rank, g_rank])


def _sorted(df: pd.DataFrame, groups: tuple[str, ...], models: tuple[str, ...]) -> pd.DataFrame:
    return df.iloc[_sort_order(df, groups, models)].reset_index(drop=True)
