"""Fit one WBSA model at one view: coefficients, fit statistics, cross-validation, diagnostics."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np
import pandas as pd

from wbsa.analysis.cv import cv_metrics, cv_predict, fit_statsmodels, fold_ids
from wbsa.analysis.design import (
    design_matrix,
    from_model_scale,
    n_params,
    needs_positive,
    term_names,
    to_model_scale,
    weights,
)
from wbsa.errors import WbsaError


class CannotFit(WbsaError):
    """This group/view/model cannot be fitted (too few rows, a constant predictor...); the reason is the message."""


@dataclass(frozen=True)
class ViewFit:
    """One fitted model at one view for one group.

    Attributes
    ----------
    model : str
        Model kind (:data:`wbsa.analysis.design.MODEL_KINDS`).
    predictors : tuple of str
        Extra predictors besides VBSA, in design order.
    terms : tuple of str
        Names of the coefficients (``const``, ``vbsa``, ...).
    params, bse, tvalues : (p,) float64
        Coefficients, their standard errors and t-values (model scale: log for ``loglog``).
    cov_unscaled : (p, p) float64
        (X'WX)^-1 of the full fit; the coefficient covariance is ``scale * cov_unscaled``.
    scale : float
        Residual variance on the model scale (weighted for ``wls``).
    df_resid : int
        Residual degrees of freedom, n − p.
    n : int
        Rows fitted.
    r2 : float
        1 − RSS/TSS of the in-sample fit on the m² scale (equals statsmodels' R² for OLS).
    rse_m2 : float
        Residual standard error on the m² scale, sqrt(RSS / df_resid).
    fitted_m2, residual_m2 : (n,) float64
        In-sample prediction and WBSA − prediction, m².
    standardized : (n,) float64
        Internally studentized residuals on the model scale (whitened for ``wls``): e / sqrt(s²(1 − h)).
    cv_pred_m2 : (n,) float64
        Out-of-fold predictions, m².
    cv : dict
        :func:`wbsa.analysis.cv.cv_metrics` of ``cv_pred_m2``.
    bp_stat, bp_pvalue : float
        Breusch–Pagan LM statistic (Koenker's studentised form) and p-value of the model-scale
        (whitened) residuals against the design; a small p-value rejects homoscedasticity.
    """

    model: str
    predictors: tuple[str, ...]
    terms: tuple[str, ...]
    params: np.ndarray
    bse: np.ndarray
    tvalues: np.ndarray
    cov_unscaled: np.ndarray
    scale: float
    df_resid: int
    n: int
    r2: float
    rse_m2: float
    fitted_m2: np.ndarray = field(repr=False)
    residual_m2: np.ndarray = field(repr=False)
    standardized: np.ndarray = field(repr=False)
    cv_pred_m2: np.ndarray = field(repr=False)
    cv: dict = field(default_factory=dict)
    bp_stat: float = float("nan")
    bp_pvalue: float = float("nan")

    def coefficient_columns(self) -> dict[str, float]:
        """Flat coefficient statistics: c0, c0_se, c0_t, c1, c1_se, c1_t, c_<term>, c_<term>_se, c_<term>_t."""
        out: dict[str, float] = {}
        for term, b, se, t in zip(self.terms, self.params, self.bse, self.tvalues):
            name = coefficient_name(term)
            out[name] = float(b)
            out[f"{name}_se"] = float(se)
            out[f"{name}_t"] = float(t)
        return out

    def statistics(self) -> dict[str, float]:
        """The per-view row of the fit table (without the view and group keys)."""
        return {
            "n": self.n,
            **self.coefficient_columns(),
            "r2": self.r2,
            "rse_m2": self.rse_m2,
            **self.cv,
            "bp_stat": self.bp_stat,
            "bp_pvalue": self.bp_pvalue,
            "df_resid": self.df_resid,
            "scale": self.scale,
        }

    def model_entry(self) -> dict:
        """What :class:`wbsa.analysis.model_file.WbsaModel` needs to predict with an interval."""
        return {
            "model": self.model,
            "predictors": list(self.predictors),
            "terms": list(self.terms),
            "coef": self.params.tolist(),
            "cov_unscaled": self.cov_unscaled.tolist(),
            "scale": self.scale,
            "df_resid": self.df_resid,
            "n": self.n,
        }


def coefficient_name(term: str) -> str:
    """Fit-table name of a design term: ``const`` -> ``c0``, ``vbsa`` -> ``c1``, others ``c_<term>``."""
    return {"const": "c0", "vbsa": "c1"}.get(term, f"c_{term}")


def fit_arrays(model: str, wbsa_m2: np.ndarray, vbsa_m2: np.ndarray, extras: Mapping[str, np.ndarray] | None,
               folds: np.ndarray, k: int | None = None) -> ViewFit:
    """Fit ``model`` on complete rows and cross-validate it on the given folds.

    Parameters
    ----------
    model : str
        Model kind.
    wbsa_m2, vbsa_m2 : (n,) float64
        Whole and view body surface area, m²; all finite (and > 0 for ``loglog``).
    extras : mapping name -> (n,) float64
        Extra predictors (e.g. ``{'stature_m': ...}``), finite.
    folds : (n,) int64
        Cross-validation fold of every row.
    k : int, optional
        Number of folds asked for (default: the number of distinct ``folds``); a group needs
        at least k + p rows, p the number of coefficients.

    Raises
    ------
    CannotFit
        Too few rows (fewer than k + number of coefficients), values out of the model's domain,
        or a rank-deficient design (e.g. a predictor that is constant in the group).
    """
    extras = dict(extras or {})
    predictors = tuple(extras)
    y_m2 = np.asarray(wbsa_m2, dtype=float)
    vbsa = np.asarray(vbsa_m2, dtype=float)
    folds = np.asarray(folds)
    n = len(y_m2)
    p = n_params(model, len(predictors))
    k = max(int(k or 0), len(np.unique(folds)), 2)
    if n < k + p:
        raise CannotFit(f"{n} rows < k + p = {k} + {p}")
    if needs_positive(model):
        bad = [name for name, arr in (("wbsa", y_m2), ("vbsa", vbsa), *extras.items()) if np.any(np.asarray(arr) <= 0)]
        if bad:
            raise CannotFit(f"{model} needs positive values; {', '.join(bad)} has values <= 0")
    if model == "wls" and np.any(vbsa <= 0):
        raise CannotFit("wls weights 1/VBSA^2 need VBSA > 0")

    X = design_matrix(model, vbsa, extras)
    y = to_model_scale(model, y_m2)
    w = weights(model, vbsa)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # statsmodels warns on rank deficiency; it is checked just below
        res = fit_statsmodels(y, X, w)
    if res.model.rank < p:
        raise CannotFit(f"design is rank deficient (rank {res.model.rank} < {p}); "
                        "a predictor is constant or collinear here")

    fitted = from_model_scale(model, res.fittedvalues)
    resid = y_m2 - fitted
    rss = float(resid @ resid)
    tss = float(np.sum((y_m2 - y_m2.mean()) ** 2))
    df_resid = int(round(res.df_resid))
    cov_unscaled = np.asarray(res.normalized_cov_params, dtype=float)
    scale = float(res.scale)
    wX = res.model.wexog
    wresid = np.asarray(res.wresid, dtype=float)
    leverage = np.einsum("ij,jk,ik->i", wX, cov_unscaled, wX)
    with np.errstate(divide="ignore", invalid="ignore"):
        standardized = wresid / np.sqrt(scale * (1.0 - leverage))
    bp_stat, bp_p = breusch_pagan(wresid, X)
    pred = cv_predict(model, y_m2, vbsa, extras, folds)
    return ViewFit(
        model=model,
        predictors=predictors,
        terms=term_names(model, predictors),
        params=np.asarray(res.params, dtype=float),
        bse=np.asarray(res.bse, dtype=float),
        tvalues=np.asarray(res.tvalues, dtype=float),
        cov_unscaled=cov_unscaled,
        scale=scale,
        df_resid=df_resid,
        n=n,
        r2=1.0 - rss / tss if tss > 0 else float("nan"),
        rse_m2=float(np.sqrt(rss / df_resid)),
        fitted_m2=fitted,
        residual_m2=resid,
        standardized=standardized,
        cv_pred_m2=pred,
        cv=cv_metrics(y_m2, pred),
        bp_stat=bp_stat,
        bp_pvalue=bp_p,
    )


def breusch_pagan(resid: np.ndarray, X: np.ndarray) -> tuple[float, float]:
    """Breusch–Pagan test (statsmodels ``het_breuschpagan``, Koenker's robust form) -> (LM, p-value)."""
    from statsmodels.stats.diagnostic import het_breuschpagan

    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        try:
            lm, lm_p, _, _ = het_breuschpagan(resid, X)
        except (ValueError, np.linalg.LinAlgError):
            return float("nan"), float("nan")
    return float(lm), float(lm_p)


def fit_view(df: pd.DataFrame, vbsa_col: str, predictors: tuple[str, ...] | list[str] = (), model: str = "linear",
             k: int = 10, seed: int = 0, wbsa_col: str = "wbsa_m2") -> ViewFit:
    """Fit and cross-validate one model on the rows of one view.

    Parameters
    ----------
    df : DataFrame
        One row per subject: ``subject_id``, ``wbsa_col``, ``vbsa_col`` and the ``predictors`` columns.
        Rows with a missing value in any of them are dropped.
    vbsa_col : str
        Column with the view body surface area, m².
    predictors : sequence of str
        Extra predictor columns (e.g. ``('stature_m',)``).
    model : str
        Model kind.
    k, seed : int
        Folds of the cross-validation and the seed of their assignment (:func:`fold_ids`).

    Returns
    -------
    ViewFit
    """
    cols = ["subject_id", wbsa_col, vbsa_col, *predictors]
    missing = [c for c in cols if c not in df.columns]
    if missing:
        raise WbsaError(f"table lacks column(s) {', '.join(missing)}; check the VBSA column and the predictors")
    sub = df[cols].dropna()
    if sub["subject_id"].duplicated().any():
        raise WbsaError("several rows per subject; pass the rows of one view only")
    folds = fold_ids(sub["subject_id"].to_numpy(), k, seed)
    return fit_arrays(model, sub[wbsa_col].to_numpy(float), sub[vbsa_col].to_numpy(float),
                      {p: sub[p].to_numpy(float) for p in predictors}, folds, k=k)
