"""Seeded k-fold cross-validation of the WBSA models and its error metrics."""

from __future__ import annotations

from typing import Mapping

import numpy as np

from wbsa.analysis.design import design_matrix, from_model_scale, to_model_scale, weights
from wbsa.errors import WbsaError


def fold_ids(subject_ids: np.ndarray, k: int, seed: int) -> np.ndarray:
    """Assign subjects to ``k`` folds, reproducibly.

    The distinct subject ids are sorted, shuffled by ``numpy.random.default_rng(seed)`` and
    dealt round-robin into folds, so fold sizes differ by at most one subject and the
    assignment depends only on the set of ids, ``k`` and ``seed`` (not on row order).
    Rows of the same subject (e.g. several views) share a fold.

    Parameters
    ----------
    subject_ids : (n,) int64
        Subject id of every row.
    k : int
        Number of folds, >= 2.
    seed : int
        Seed of the shuffle.

    Returns
    -------
    (n,) int64
        Fold index in ``[0, k)`` of every row.
    """
    if int(k) < 2:
        raise WbsaError(f"k = {k} folds is too few for cross-validation; use k = 2 or more (paper: 10)")
    ids = np.asarray(subject_ids)
    uniq = np.unique(ids)
    order = np.random.default_rng(seed).permutation(len(uniq))
    fold_of = np.empty(len(uniq), dtype=np.int64)
    fold_of[order] = np.arange(len(uniq)) % int(k)
    return fold_of[np.searchsorted(uniq, ids)]


def fit_statsmodels(y: np.ndarray, X: np.ndarray, w: np.ndarray | None):
    """Fit OLS (``w`` None) or WLS with statsmodels; returns its ``RegressionResults``."""
    import statsmodels.api as sm

    if w is None:
        return sm.OLS(y, X, hasconst=True).fit()
    return sm.WLS(y, X, weights=w, hasconst=True).fit()


def cv_predict(model: str, wbsa_m2: np.ndarray, vbsa_m2: np.ndarray, extras: Mapping[str, np.ndarray] | None,
               folds: np.ndarray) -> np.ndarray:
    """Out-of-fold predictions of WBSA.

    For every fold f the model is fitted (statsmodels) on the rows not in f and predicts the rows in f.

    Parameters
    ----------
    model : str
        A model kind of :mod:`wbsa.analysis.design`.
    wbsa_m2, vbsa_m2 : (n,) float64
        Response and view area, m².
    extras : mapping name -> (n,) float64
        Extra predictors.
    folds : (n,) int64
        Fold of every row (see :func:`fold_ids`).

    Returns
    -------
    (n,) float64
        Cross-validated prediction of every row, m².
    """
    X = design_matrix(model, vbsa_m2, extras)
    y = to_model_scale(model, wbsa_m2)
    w = weights(model, vbsa_m2)
    folds = np.asarray(folds)
    pred = np.full(len(y), np.nan)
    for f in np.unique(folds):
        test = folds == f
        train = ~test
        res = fit_statsmodels(y[train], take_rows(X, train), None if w is None else w[train])
        pred[test] = res.predict(X[test])
    return from_model_scale(model, pred)


def take_rows(X: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Rows of ``X`` (n, p) where ``mask`` (n,) bool, as a Fortran-ordered (m, p) copy."""
    out = np.empty((int(np.count_nonzero(mask)), X.shape[1]), order="F")
    for j in range(X.shape[1]):
        np.compress(mask, X[:, j], out=out[:, j])
    return out


def cv_metrics(wbsa_m2: np.ndarray, pred_m2: np.ndarray) -> dict[str, float]:
    """Prediction-error metrics of the paper (S1 tables) plus the bias.

    Parameters
    ----------
    wbsa_m2, pred_m2 : (n,) float64
        True and (cross-validated) predicted WBSA, m².

    Returns
    -------
    dict
        ``cv_mspe_m4`` mean squared prediction error, ``cv_rmse_m2`` its square root,
        ``cv_mape_pct`` mean absolute percentage error 100·mean(|pred − y|/y),
        ``cv_bias_m2`` mean(pred − y).
    """
    y = np.asarray(wbsa_m2, dtype=float)
    e = np.asarray(pred_m2, dtype=float) - y
    mspe = float(np.mean(e**2))
    return {
        "cv_rmse_m2": float(np.sqrt(mspe)),
        "cv_mspe_m4": mspe,
        "cv_mape_pct": float(100.0 * np.mean(np.abs(e) / y)),
        "cv_bias_m2": float(np.mean(e)),
    }
