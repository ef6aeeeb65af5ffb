"""The height/weight law refitted on the virtual bodies: log WBSA = a + b·log H + c·log W.

The fair opponent of the single view on virtual bodies (:mod:`wbsa.analysis.claim`): fitted by OLS on all
subjects, and cross-validated on the single-view model's folds. Pure functions of arrays.
"""

from __future__ import annotations

import numpy as np

from wbsa.analysis.cv import cv_predict, fit_statsmodels
from wbsa.analysis.design import design_matrix
from wbsa.errors import WbsaError


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

