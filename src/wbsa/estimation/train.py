"""Train an estimator model on virtual captures: fit on some subjects, calibrate the interval on others.

1. A population: random bodies (ages uniform in years) and survey-matched bodies (NHANES people).
2. Subjects are split: ``1 − calibration_fraction`` fit the models, the rest only calibrate the interval.
3. Every subject is rendered from ``views_per_subject`` random captures in random postures
   (:func:`~wbsa.estimation.renders.render_samples`) and measured by the estimator's own code.
4. The view model is fitted; the WBSA model is fitted on *out-of-fold* view estimates, so it learns with
   the view errors it will meet; its spread model on its own out-of-fold residuals.
5. The calibration subjects go through the finished models; their scores set the interval.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, replace

import numpy as np
import pandas as pd

from wbsa.errors import WbsaError
from wbsa.estimation.capture import CaptureSettings
from wbsa.estimation.measure import SCALAR_MEASURES
from wbsa.estimation.model import (SPREAD_TERMS, EstimatorModel, design, range_values, spread_design,
                                   tree_features, with_clothing)
from wbsa.estimation.renders import RenderSettings, Samples, check_clothing_settings, render_samples
from wbsa.estimation.view import ViewModel, azimuth_sd_deg, fold_azimuth

#: Columns of :meth:`SubjectMeasures.features` the model reads (``m_`` prefixed in sample tables).
FEATURES = SCALAR_MEASURES
_VIEW_DIMS = 160  # view descriptor length; the shape bands follow it in Samples.descriptors
#: Share of the subjects each bagged tree model is fitted on (:attr:`TrainSettings.tree_bags`).
BAG_SUBJECT_SHARE = 0.9


@dataclass(frozen=True)
class TrainSettings:
    """What the default model is trained on (see the module doc).

    Attributes
    ----------
    n_random, n_survey : int
        Random and survey-matched subjects.
    views_per_subject : int
    calibration_fraction : float
        Share of subjects kept for the interval's calibration (never fitted on).
    age_years : (float, float)
        Ages of the random subjects, uniform in years.
    capture : CaptureSettings
    postures : tuple of str or None
    room : bool
        Capture the bodies in a room and find them by segmentation, as real images are
        (:class:`~wbsa.estimation.renders.RenderSettings`).
    alone_share : float
        With ``room``: share of captures of the body alone, with no floor or wall (a frame whose room was
        removed, or a rendered body scan).
    scan_share : float
        Share of those read as a rendered 3-D body scan is: no sensor effects, the render's own edges
        (:func:`~wbsa.estimation.capture.as_scan_render`).
    clothed_share : float
        Share of captures of a dressed body, a layer of clothes drawn uniform in ``clothing_m`` over the trunk,
        upper arms, legs and feet; the model reads the layer as the user states it, the truth is the skin's.
    clothing_m : (float, float)
        Range of that layer (m).
    folds : int
        Folds of the out-of-fold view estimates and residuals.
    tree_iterations, tree_leaves : int
        Boosting rounds and leaves per tree of the residual trees (learning rate 0.05).
    tree_l2 : float
        L2 penalty on the trees' leaf values.
    tree_bags : int
        Boosted models averaged, each fitted on a random :data:`BAG_SUBJECT_SHARE` of the subjects (1: one
        model on all). A refit on slightly different captures moved single-model benchmark estimates by
        1.7 % (standard deviation); the average of five cut revision 10's calibration MAPE from 2.46 % to
        2.42 %.
    seed : int
    """

    n_random: int = 900
    n_survey: int = 480
    views_per_subject: int = 4
    calibration_fraction: float = 0.25
    age_years: tuple[float, float] = (3.0, 80.0)
    capture: CaptureSettings = field(default_factory=CaptureSettings)
    postures: tuple[str, ...] | None = None
    room: bool = True
    alone_share: float = 0.15
    scan_share: float = 0.5
    clothed_share: float = 0.2
    clothing_m: tuple[float, float] = (0.0, 0.015)
    folds: int = 3
    tree_iterations: int = 800
    tree_leaves: int = 31
    tree_l2: float = 0.1
    tree_bags: int = 5
    seed: int = 0

    def __post_init__(self) -> None:
        if self.n_random < 0 or self.n_survey < 0 or self.n_random + self.n_survey < 8:
            raise WbsaError("n_random + n_survey must be at least 8 subjects")
        if not 0.05 <= self.calibration_fraction <= 0.5:
            raise WbsaError(f"calibration_fraction {self.calibration_fraction} must lie in [0.05, 0.5]")
        if not 0.0 <= self.alone_share <= 1.0:
            raise WbsaError(f"alone_share {self.alone_share} must be a share of the captures in [0, 1]")
        if not 0.0 <= self.scan_share <= 1.0:
            raise WbsaError(f"scan_share {self.scan_share} must be a share of the captures of a body alone in [0, 1]")
        check_clothing_settings(self.clothed_share, self.clothing_m)
        if self.views_per_subject < 1 or self.folds < 2:
            raise WbsaError("views_per_subject must be >= 1 and folds >= 2")
        counts_ok = all(isinstance(v, int) for v in (self.tree_iterations, self.tree_leaves, self.tree_bags))
        if not (counts_ok and self.tree_iterations >= 1 and self.tree_leaves >= 2 and self.tree_l2 >= 0
                and self.tree_bags >= 1):
            raise WbsaError(f"tree_iterations ({self.tree_iterations!r}) must be an integer >= 1, tree_leaves "
                            f"({self.tree_leaves!r}) an integer >= 2, tree_bags ({self.tree_bags!r}) an integer "
                            f">= 1 and tree_l2 ({self.tree_l2!r}) a number >= 0")


def training_population(settings: TrainSettings, show_progress: bool | None = None) -> pd.DataFrame:
    """Random and survey-matched subjects with their true WBSA (``population`` column: random or survey)."""
    from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters
    from wbsa.bodies.table import measure_population

    parts = []
    if settings.n_random:
        params = sample_random_parameters(RandomPopulationSettings(n=settings.n_random, seed=settings.seed,
                                                                   age_years=settings.age_years, age_sampling="years"))
        parts.append(measure_population(params, show_progress=show_progress).assign(population="random"))
    if settings.n_survey:
        import warnings

        from wbsa.bodies.survey import build_survey_population

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # unmatched people are still people; their truth is their body
            parts.append(build_survey_population(settings.n_survey, seed=settings.seed + 1,
                                                 show_progress=show_progress).assign(population="survey"))
    pop = pd.concat(parts, ignore_index=True)
    pop["subject_id"] = np.arange(len(pop))
    return pop


def _columns(table: pd.DataFrame) -> dict[str, np.ndarray]:
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


def _oof_view(samples: Samples, folds: int, seed: int) -> tuple[np.ndarray, np.ndarray, float]:
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
        model = ViewModel.fit(samples.descriptors[k != f, :_VIEW_DIMS], az[k != f], seed=seed)
        psi[k == f], _, p_front[k == f] = model.predict(samples.descriptors[k == f, :_VIEW_DIMS])
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

    from wbsa.estimation.trees import TreeEnsemble

    feats = _columns(table)
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


#: The parts :func:`training_renders` renders.
_PARTS = ("fit", "calibration")


def _check_parts(parts) -> None:
    """Raise :class:`WbsaError` unless ``parts`` is a non-empty collection of :data:`_PARTS`."""
    if isinstance(parts, str):
        raise WbsaError(f"training parts must be a tuple of part names, got the string {parts!r}; "
                        f"use e.g. ({parts!r},)")
    unknown = [p for p in parts if p not in _PARTS]
    if unknown:
        raise WbsaError(f"training part {unknown[0]!r} is unknown; use fit or calibration")
    if not parts:
        raise WbsaError("no training part to render; use fit, calibration or both")


def training_renders(settings: TrainSettings = TrainSettings(), parts: tuple[str, ...] = ("fit", "calibration"), *,
                     workers: int = 1, show_progress: bool | None = None) -> dict[str, Samples]:
    """Render the training captures: the fit subjects' and the calibration subjects' (steps 1–3).

    Parameters
    ----------
    settings : TrainSettings
    parts : tuple of {'fit', 'calibration'}
        Which to render, at least one (the calibration captures alone re-create a model's calibration
        scores). Checked before anything is built.
    workers : int
        Local worker processes (the renders do not depend on it).
    show_progress : bool, optional
        Progress bars (None: when stderr is a terminal, :func:`wbsa.progress.progress`).

    Returns
    -------
    dict of str to Samples
        One entry per part, keyed by its name: a table of one row per capture of the part's subjects
        (unusable ones included, ``m_ok`` False; :func:`usable`) and its (n, d) float32 descriptors.

    Raises
    ------
    WbsaError
        ``parts`` empty, a string rather than a tuple of them, or naming an unknown part.
    """
    _check_parts(parts)
    pop = training_population(settings, show_progress)
    rng = np.random.default_rng(settings.seed)
    calib = rng.random(len(pop)) < settings.calibration_fraction
    render = RenderSettings(views_per_subject=settings.views_per_subject, capture=settings.capture,
                            postures=settings.postures, room=settings.room, alone_share=settings.alone_share,
                            scan_share=settings.scan_share, clothed_share=settings.clothed_share,
                            clothing_m=settings.clothing_m, seed=settings.seed)
    chosen = {"fit": (~calib, render), "calibration": (calib, replace(render, seed=settings.seed + 7919))}
    out = {}
    for part in parts:
        rows, part_render = chosen[part]
        out[part] = render_samples(pop[rows].reset_index(drop=True), part_render, workers=workers,
                                   show_progress=show_progress)
    return out


def train_model(settings: TrainSettings = TrainSettings(), *, workers: int = 1, show_progress: bool | None = None,
                samples: tuple[Samples, Samples] | None = None) -> EstimatorModel:
    """Train an estimator model (see the module doc).

    Parameters
    ----------
    settings : TrainSettings
    workers : int
        Local worker processes for the renders (the model does not depend on it).
    samples : (Samples, Samples), optional
        Already rendered (fit, calibration) samples; skips steps 1–3.

    Returns
    -------
    EstimatorModel
        ``meta`` holds the settings, the training ranges and held-out calibration metrics.
    """
    if samples is None:
        parts = training_renders(settings, workers=workers, show_progress=show_progress)
        fit_s, cal_s = parts["fit"], parts["calibration"]
    else:
        fit_s, cal_s = samples
    fit_s, cal_s = (usable(s) for s in (fit_s, cal_s))
    if len(fit_s) < 20 or len(cal_s) < 20:
        raise WbsaError(f"too few usable renders to train ({len(fit_s)} fit, {len(cal_s)} calibration); "
                        "use more subjects")
    fit_t = fit_s.table
    psi_oof, sd_oof, axis_sd = _oof_view(fit_s, settings.folds, settings.seed)
    on_floor = fit_t["m_floor_seen"].to_numpy() > 0.5
    on_floor = on_floor if on_floor.any() else np.ones(len(fit_t), dtype=bool)
    el_sd = {"floor": _rms((fit_t["m_elevation_deg"] - fit_t["elevation_deg"])[on_floor]),
             "axis": _rms(fit_t["m_elevation_axis_deg"] - fit_t["elevation_deg"])}
    view = ViewModel.fit(fit_s.descriptors[:, :_VIEW_DIMS], fit_t["azimuth_deg"].to_numpy(), seed=settings.seed,
                         axis_sd_deg=axis_sd, elevation_sd_deg=el_sd)
    shape = fit_s.descriptors[:, _VIEW_DIMS:]
    mean, scale, coef, intercept, trees = fit_wbsa(fit_t, shape, psi_oof, sd_oof, settings)
    spread, spread_range = _fit_spread(fit_s, psi_oof, sd_oof, settings)
    model = EstimatorModel(view, mean, scale, coef, intercept, trees, spread, spread_range, np.zeros(1), {})
    # calibration: held-out subjects through the finished models
    cal_t = cal_s.table
    resid, scores, psi_c, sd_c = calibration_scores(model, cal_s)
    model.scores = np.sort(scores)
    err = 100 * (np.exp(-resid) - 1)
    az_err = np.abs(psi_c - fold_azimuth(cal_t["azimuth_deg"].to_numpy()))
    feats_f = _columns(fit_t)
    model.meta = {
        "name": "estimator", "settings": asdict(settings),
        "ranges": {**{k: [float(np.min(v)), float(np.max(v))] for k, v in range_values(feats_f).items()},
                   # the layers drawn are uniform in the settings' range, whose top no draw reaches exactly
                   "clothing_m": [0.0, float(settings.clothing_m[1]) if settings.clothed_share > 0 else 0.0]},
        "n_fit": len(fit_s), "n_calibration": len(cal_s),
        "n_calibration_subjects": int(cal_t["subject_id"].nunique()),
        "calibration": {"wbsa_mape_pct": float(np.mean(np.abs(err))), "wbsa_bias_pct": float(np.mean(err)),
                        "azimuth_error_median_deg": float(np.median(az_err)),
                        "azimuth_error_p95_deg": float(np.percentile(az_err, 95))},
        # the view spread the WBSA model learnt on and the one it meets at run time
        "azimuth_sd_median_deg": {"fit": float(np.median(sd_oof)), "calibration": float(np.median(sd_c))},
    }
    return model


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
    psi, psi_sd, _ = model.view.predict(samples.descriptors[:, :_VIEW_DIMS])
    feats = _columns(samples.table)
    mu = model.log_wbsa(feats, samples.descriptors[:, _VIEW_DIMS:], psi, psi_sd, feats["elevation_deg"])
    resid = np.log(samples.table["wbsa_m2"].to_numpy()) - mu
    return resid, np.abs(resid) / model.spread(feats, psi, psi_sd, mu), psi, psi_sd


def usable(s: Samples) -> Samples:
    """The renders whose measures succeeded (``m_ok``)."""
    ok = s.table["m_ok"].to_numpy(dtype=bool)
    return Samples(s.table[ok].reset_index(drop=True), s.descriptors[ok])


def _rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(np.asarray(x, dtype=np.float64)))))


def _fit_spread(samples: Samples, psi: np.ndarray, psi_sd: np.ndarray,
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
    shape = samples.descriptors[:, _VIEW_DIMS:]
    mu = np.zeros(len(t))
    for f in range(settings.folds):
        tr, te = k != f, k == f
        mean, scale, coef, icpt, trees = fit_wbsa(t[tr], shape[tr], psi[tr], psi_sd[tr], settings)
        m = EstimatorModel(None, mean, scale, coef, icpt, trees, np.zeros(SPREAD_TERMS), np.zeros(2),
                           np.zeros(1))  # type: ignore[arg-type]
        feats = _columns(t[te])
        mu[te] = m.log_wbsa(feats, shape[te], psi[te], psi_sd[te], feats["elevation_deg"])
    resid = np.log(t["wbsa_m2"].to_numpy()) - mu
    Z = spread_design(psi, psi_sd, _columns(t), mu)
    target = np.log(np.maximum(np.abs(resid), 1e-4))
    coef, *_ = np.linalg.lstsq(Z, target, rcond=None)
    z = Z @ coef
    return coef, np.array([z.min(), z.max()])
