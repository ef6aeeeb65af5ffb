"""The regression models WBSA = f(VBSA, extra predictors): design matrices, response scale, weights.

Fitting (:mod:`wbsa.analysis.regression`) and prediction from a saved model file
(:mod:`wbsa.analysis.model_file`) build their design matrices here, so both always agree.

Models
------
linear
    WBSA = c0 + c1·VBSA + Σ c_j·x_j, ordinary least squares (paper eq. 5–8).
quadratic
    WBSA = c0 + c1·VBSA + c_vbsa_sq·VBSA² + Σ c_j·x_j, ordinary least squares.
loglog
    log WBSA = c0 + c1·log VBSA + Σ c_j·log x_j, ordinary least squares on the log scale
    (a power law with multiplicative, i.e. WBSA-proportional, error). Predictions are
    exp(·) of the log-scale prediction: the conditional median.
wls
    The linear law fitted by weighted least squares with weights 1/VBSA², i.e. an error
    standard deviation proportional to VBSA (the heteroscedasticity of paper section 4.2).
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from wbsa.errors import WbsaError
from wbsa.analysis.settings import check_model_kinds  # noqa: F401 - re-exported for the analysis modules
from wbsa.typing import MODEL_KINDS, ModelKind  # noqa: F401 - re-exported for the analysis modules

#: Short description of every model kind, for tables and the report.
MODEL_DESCRIPTIONS: dict[str, str] = {
    "linear": "OLS: WBSA = c0 + c1*VBSA (+ c_j*x_j)",
    "quadratic": "OLS: WBSA = c0 + c1*VBSA + c_vbsa_sq*VBSA^2 (+ c_j*x_j)",
    "loglog": "OLS on logs: log WBSA = c0 + c1*log VBSA (+ c_j*log x_j)",
    "wls": "WLS, weights 1/VBSA^2: WBSA = c0 + c1*VBSA (+ c_j*x_j)",
}


def term_names(model: str, predictors: tuple[str, ...] | list[str]) -> tuple[str, ...]:
    """Names of the design-matrix columns: ``const``, ``vbsa``, [``vbsa_sq``], predictors..."""
    terms = ["const", "vbsa"]
    if model == "quadratic":
        terms.append("vbsa_sq")
    return tuple(terms + list(predictors))


def n_params(model: str, n_predictors: int) -> int:
    """Number of coefficients of ``model`` with ``n_predictors`` extra predictors."""
    return len(term_names(model, ("x",) * n_predictors))


def needs_positive(model: str) -> bool:
    """Whether the model takes logs, so VBSA, WBSA and predictors must be > 0."""
    return model == "loglog"


def design_matrix(model: str, vbsa_m2: np.ndarray, extras: Mapping[str, np.ndarray] | None = None) -> np.ndarray:
    """The design matrix of ``model``.

    Parameters
    ----------
    model : str
        One of :data:`MODEL_KINDS`.
    vbsa_m2 : (n,) float64
        View body surface area, m².
    extras : mapping name -> (n,) float64
        Extra predictors in the order of :func:`term_names` (e.g. ``{'stature_m': ...}``).

    Returns
    -------
    (n, p) float64, Fortran order
        Columns as :func:`term_names`; the first is the constant 1.
    """
    vbsa = np.asarray(vbsa_m2, dtype=float)
    cols = [np.ones_like(vbsa)]
    if model == "loglog":
        with np.errstate(divide="ignore", invalid="ignore"):
            cols.append(np.log(vbsa))
            cols += [np.log(np.asarray(x, dtype=float)) for x in (extras or {}).values()]
    elif model in ("linear", "wls", "quadratic"):
        cols.append(vbsa)
        if model == "quadratic":
            cols.append(vbsa**2)
        cols += [np.asarray(x, dtype=float) for x in (extras or {}).values()]
    else:
        check_model_kinds([model])
    X = np.empty((vbsa.shape[0], len(cols)), order="F")  # column-major: fast column reductions and LAPACK
    for j, c in enumerate(cols):
        X[:, j] = c
    return X


def to_model_scale(model: str, wbsa_m2: np.ndarray) -> np.ndarray:
    """The response on the scale the model is fitted on: (n,) float64 (log for ``loglog``)."""
    y = np.asarray(wbsa_m2, dtype=float)
    if model == "loglog":
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.log(y)
    return y


def from_model_scale(model: str, y: np.ndarray) -> np.ndarray:
    """Back to m²: (n,) float64 (exp for ``loglog``, the conditional median)."""
    return np.exp(y) if model == "loglog" else np.asarray(y, dtype=float)


def weights(model: str, vbsa_m2: np.ndarray) -> np.ndarray | None:
    """Regression weights (n,) float64 for ``wls`` (1/VBSA²), else None (equal weights)."""
    if model == "wls":
        v = np.asarray(vbsa_m2, dtype=float)
        with np.errstate(divide="ignore"):
            return 1.0 / v**2
    return None
