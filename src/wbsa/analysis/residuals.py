"""Residual tables for residual and QQ plots."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pandas as pd

from wbsa.analysis.regression import ViewFit


def qq_probabilities(points: int) -> np.ndarray:
    """(points,) float64 plotting positions (i + 0.5) / points, i = 0..points-1."""
    return (np.arange(int(points)) + 0.5) / int(points)


def qq_quantiles(standardized: np.ndarray, points: int = 99) -> pd.DataFrame:
    """Normal QQ points of standardized residuals.

    Parameters
    ----------
    standardized : (n,) float64
        Standardized residuals (NaN ignored).
    points : int
        Number of quantiles.

    Returns
    -------
    DataFrame
        ``p`` (probability), ``theoretical`` (standard normal quantile), ``sample``
        (empirical quantile of the residuals); ``points`` rows.
    """
    p, theoretical = _normal_quantiles(int(points))
    r = np.asarray(standardized, dtype=float)
    r = r[np.isfinite(r)]
    sample = np.quantile(r, p) if r.size else np.full(p.shape, np.nan)
    return pd.DataFrame({"p": p, "theoretical": theoretical, "sample": sample})


@lru_cache(maxsize=8)
def _normal_quantiles(points: int) -> tuple[np.ndarray, np.ndarray]:
    from scipy import stats

    p = qq_probabilities(points)
    return p, stats.norm.ppf(p)


def residual_frame(subject_id: np.ndarray, wbsa_m2: np.ndarray, fit: ViewFit) -> pd.DataFrame:
    """Per-subject residuals of one fit.

    Parameters
    ----------
    subject_id : (n,) int64
        Subjects of the fitted rows, in fit order.
    wbsa_m2 : (n,) float64
        Their WBSA, m².
    fit : ViewFit
        The fit.

    Returns
    -------
    DataFrame
        ``subject_id``, ``wbsa_m2``, ``fitted_m2`` (in-sample), ``residual_m2`` (WBSA − fitted),
        ``standardized`` (studentized, model scale), ``cv_pred_m2`` (out-of-fold prediction).
    """
    return pd.DataFrame({
        "subject_id": np.asarray(subject_id),
        "wbsa_m2": np.asarray(wbsa_m2, dtype=float),
        "fitted_m2": fit.fitted_m2,
        "residual_m2": fit.residual_m2,
        "standardized": fit.standardized,
        "cv_pred_m2": fit.cv_pred_m2,
    })
