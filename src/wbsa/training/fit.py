"""The fit of an estimator model on rendered samples: view model, WBSA regression and trees, spread, scores.

Every function here is pure: samples (tables and descriptors) and settings in, arrays or models out.
:func:`wbsa.training.pipeline.train_model` calls them in order.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from wbsa.estimation.subject.measure import SCALAR_MEASURES
from wbsa.estimation.methods.regression.design import SPREAD_TERMS, design, spread_design, tree_features, with_clothing
from wbsa.estimation.methods.regression.model import EstimatorModel
from wbsa.estimation.methods.regression.trees import TreeEnsemble
from wbsa.estimation.methods.regression.view_model import ViewModel, azimuth_sd_deg
from wbsa.estimation.methods.view import fold_azimuth
from wbsa.training.renders import Samples
from wbsa.training.settings import TrainSettings

#: Columns of :meth:`SubjectMeasures.features` the model reads (``m_`` prefixed in sample tables).
FEATURES = SCALAR_MEASURES
#: View descriptor length; the shape bands follow it in :attr:`Samples.descriptors`.
VIEW_DIMS = 160
#: Share of the subjects each bagged tree model is fitted on (:attr:`TrainSettings.tree_bags`).
BAG_SUBJECT_SHARE = 0.9


def fit_view_model(descriptors: np.ndarray, azimuth_deg: np.ndarray, *, seed: int = 0, max_iter: int = 150,
                   axis_sd_deg: float | None = None, elevation_sd_deg: dict | None = None) -> ViewModel:
    """A :class:`~wbsa.estimation.methods.regression.view_model.ViewModel` fitted on renders' view descriptors (n, d) and true azimuths (n,).

    ``axis_sd_deg`` should come from held-out renders; None takes the (optimistic) training spread.
    """
    from sklearn.ensemble import HistGradientBoostingClassifier, HistGradientBoostingRegressor

    from wbsa.estimation.methods.regression.view_model import ELEVATION_SD_DEG

    psi = fold_azimuth(azimuth_deg)
    axis_deg = np.minimum(psi, 180.0 - psi)
    common = dict(max_iter=max_iter, learning_rate=0.1, max_leaf_nodes=31, random_state=seed,
                  early_stopping=False)
    axis = HistGradientBoostingRegressor(**common).fit(descriptors, axis_deg)
    front = HistGradientBoostingClassifier(**common).fit(descriptors, psi < 90.0)
    if axis_sd_deg is None:
        axis_sd_deg = float(np.sqrt(np.mean((axis.predict(descriptors) - axis_deg) ** 2)))
    return ViewModel(TreeEnsemble.from_sklearn(axis), TreeEnsemble.from_sklearn(front), float(axis_sd_deg),
                     dict(elevation_sd_deg or ELEVATION_SD_DEG))


def sample_columns(table: pd.DataFrame) -> dict[str, np.ndarray]:
    """The measures (``m_`` columns) and the stated clothes (``clothing_m``; 0 where a table has none)."""
    feats = {k: table[f"m_{k}"].to_numpy(dtype=np.float64) for k in FEATURES}
    clothing_m = table["clothing_m"].to_numpy(dtype=np.float64) if "clothing_m" in table else 0.0
    return with_clothing(feats, clothing_m)


def _folds(table: pd.DataFrame, folds: int, seed: int) -> np.ndarray:
    """(n,) fold of every sample, whole subjects per fold."""
    subjects = table["subject_id"].to_numpy()
    perm = np.random.default_rng(seed).permutation(np.unique(subjects))
    fold_of = dict(zip(perm.tolist(), (np.arange(len(perm)) % folds).tolist()))
    return np.array([fold_of[s] for s in subjects.tolist()])


def oof_view(samples: Samples, folds: int, seed: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Out-of-fold view estimates of every sample (folds by subject).

    Parameters
    ----------
    samples : Samples
        The fit renders (n): ``subject_id`` and ``azimuth_deg`` columns, view descriptors first.
    folds : int
    seed : int
        Seed of the fold split and of the fold view models.

    Returns
    -------
    psi_deg, psi_sd_deg : (n,) float64
        ψ̂ and its spread. The spread is the one the finished view model reports at run time (its
        ``axis_sd_deg`` is the held-out spread below): the WBSA trees and the interval's spread read it, so
        they must learn it on that scale. The fold models' own, in-sample spread is about a fifth of it.
    axis_sd_deg : float
        Root-mean-square out-of-fold error of ψ' = min(ψ, 180 − ψ).
    """
    k = _folds(samples.table, folds, seed)
    psi, p_front = np.zeros(len(k)), np.zeros(len(k))
    az = samples.table["azimuth_deg"].to_numpy()
    for f in range(folds):
        model = fit_view_model(samples.descriptors[k != f, :VIEW_DIMS], az[k != f], seed=seed)
        psi[k == f], _, p_front[k == f] = model.predict(samples.descriptors[k == f, :VIEW_DIMS])
    true_psi = fold_azimuth(az)
    axis_sd = float(np.sqrt(np.mean((np.minimum(psi, 180 - psi) - np.minimum(true_psi, 180 - true_psi)) ** 2)))
    return psi, azimuth_sd_deg(psi, p_front, axis_sd), axis_sd


def fit_wbsa(table: pd.DataFrame, shape: np.ndarray, psi: np.ndarray, psi_sd: np.ndarray, settings: TrainSettings,
             *, alpha: float = 1e-3) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, object]:
    """Ridge on :func:`design` and residual trees (a bag of ``settings.tree_bags`` boosted models); returns
    (mean, scale, coef, intercept, trees).

    Parameters
    ----------
    table : pandas.DataFrame
        Samples (n rows) with the ``m_`` measures of :data:`FEATURES`, the true ``wbsa_m2`` and (for a bag)
        the ``subject_id``.
    shape : (n, 40) float
        Band widths and thicknesses of every sample.
    psi, psi_sd : (n,) float64
        Estimated azimuth, folded left–right (0–180°), and its spread (degrees).
    settings : TrainSettings
        Its ``tree_iterations``, ``tree_leaves``, ``tree_l2``, ``tree_bags`` and ``seed`` shape the trees.
    alpha : float
        Ridge penalty on the standardised design.
    """
    from sklearn.ensemble import HistGradientBoostingRegressor
    from sklearn.linear_model import Ridge

    feats = sample_columns(table)
    el = feats["elevation_deg"]
    y = np.log(table["wbsa_m2"].to_numpy(dtype=np.float64))
    X = design(feats, psi, el)
    mean, scale = X.mean(axis=0), X.std(axis=0)
    scale[scale == 0] = 1.0
    ridge = Ridge(alpha=alpha).fit((X - mean) / scale, y)
    resid = y - ridge.predict((X - mean) / scale)
    tree_x = tree_features(feats, shape, psi, psi_sd, el)
    bags = []
    for k in range(settings.tree_bags):
        rows = (_bag_rows(table["subject_id"].to_numpy(), settings.seed, k) if settings.tree_bags > 1
                else np.ones(len(y), dtype=bool))
        trees = HistGradientBoostingRegressor(max_iter=settings.tree_iterations, learning_rate=0.05,
                                              max_leaf_nodes=settings.tree_leaves, min_samples_leaf=20,
                                              l2_regularization=settings.tree_l2, random_state=settings.seed,
                                              early_stopping=False)
        bags.append(TreeEnsemble.from_sklearn(trees.fit(tree_x[rows], resid[rows])))
    return mean, scale, ridge.coef_.astype(np.float64), float(ridge.intercept_), TreeEnsemble.average(bags)


def _bag_rows(subjects: np.ndarray, seed: int, bag: int) -> np.ndarray:
    """(n,) bool: the samples of a random :data:`BAG_SUBJECT_SHARE` of the subjects, for bag number ``bag``."""
    unique = np.unique(subjects)
    rng = np.random.default_rng([seed, 7, bag])
    chosen = rng.choice(unique, max(1, int(round(BAG_SUBJECT_SHARE * len(unique)))), replace=False)
    return np.isin(subjects, chosen)


def calibration_scores(model: EstimatorModel, samples: Samples) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A model's residuals and conformal scores on held-out renders.

    Parameters
    ----------
    model : EstimatorModel
    samples : Samples
        Usable renders of subjects the model was not fitted on (n rows).

    Returns
    -------
    residual : (n,) float64
        log true WBSA − log predicted WBSA.
    score : (n,) float64
        |residual| / s(x), the scores whose quantile sizes the interval (:meth:`EstimatorModel.quantile`).
    psi_deg, psi_sd_deg : (n,) float64
        The folded azimuth the view model estimated and its s.d.
    """
    psi, psi_sd, _ = model.view.predict(samples.descriptors[:, :VIEW_DIMS])
    feats = sample_columns(samples.table)
    mu = model.log_wbsa(feats, samples.descriptors[:, VIEW_DIMS:], psi, psi_sd, feats["elevation_deg"])
    resid = np.log(samples.table["wbsa_m2"].to_numpy()) - mu
    return resid, np.abs(resid) / model.spread(feats, psi, psi_sd, mu), psi, psi_sd


def rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(np.asarray(x, dtype=np.float64)))))


def fit_spread(samples: Samples, psi: np.ndarray, psi_sd: np.ndarray,
                settings: TrainSettings) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients of log s(x), fitted on out-of-fold absolute log residuals of the WBSA model, and its range.

    The apparent build in :func:`spread_design` comes here from the fold models' predictions and at run
    time from the full model's; the calibration scores are taken with the latter, as run time is.

    Parameters
    ----------
    samples : Samples
        The fit renders (n).
    psi, psi_sd : (n,) float64
        Out-of-fold folded azimuth and its spread (degrees).
    settings : TrainSettings

    Returns
    -------
    coef : (SPREAD_TERMS,) float64
    spread_range : (2,) float64
        Lowest and highest log s(x) over these renders.
    """
    t = samples.table
    k = _folds(t, settings.folds, settings.seed + 1)
    shape = samples.descriptors[:, VIEW_DIMS:]
    mu = np.zeros(len(t))
    for f in range(settings.folds):
        tr, te = k != f, k == f
        mean, scale, coef, icpt, trees = fit_wbsa(t[tr], shape[tr], psi[tr], psi_sd[tr], settings)
        m = EstimatorModel(None, mean, scale, coef, icpt, trees, np.zeros(SPREAD_TERMS), np.zeros(2),
                           np.zeros(1))  # type: ignore[arg-type]
        feats = sample_columns(t[te])
        mu[te] = m.log_wbsa(feats, shape[te], psi[te], psi_sd[te], feats["elevation_deg"])
    resid = np.log(t["wbsa_m2"].to_numpy()) - mu
    Z = spread_design(psi, psi_sd, sample_columns(t), mu)
    target = np.log(np.maximum(np.abs(resid), 1e-4))
    coef, *_ = np.linalg.lstsq(Z, target, rcond=None)
    z = Z @ coef
    return coef, np.array([z.min(), z.max()])
