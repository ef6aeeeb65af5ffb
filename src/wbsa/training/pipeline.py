"""Train an estimator model on virtual captures: fit on some subjects, calibrate the interval on others.

1. A population: random bodies (ages uniform in years) and survey-matched bodies (NHANES people).
2. Subjects are split: ``1 − calibration_fraction`` fit the models, the rest only calibrate the interval.
3. Every subject is rendered from ``views_per_subject`` random captures in random postures
   (:func:`~wbsa.training.renders.render_samples`) and measured by the estimator's own code.
4. The view model is fitted; the WBSA model is fitted on *out-of-fold* view estimates, so it learns with
   the view errors it will meet; its spread model on its own out-of-fold residuals.
5. The calibration subjects go through the finished models; their scores set the interval.
"""

from __future__ import annotations

from dataclasses import asdict, replace

import numpy as np
import pandas as pd

from wbsa.errors import WbsaError
from wbsa.estimation.methods.regression.design import range_values
from wbsa.estimation.methods.regression.model import EstimatorModel
from wbsa.estimation.methods.view import fold_azimuth
from wbsa.training.fit import (VIEW_DIMS, calibration_scores, fit_spread, fit_view_model, fit_wbsa, oof_view, rms,
                               sample_columns)
from wbsa.training.renders import Samples, render_samples
from wbsa.training.settings import TrainSettings
from wbsa.training.store import RenderStore


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

        from wbsa.bodies.survey import SurveyPopulationSettings, build_survey_population
        from wbsa.bodies.survey_match import MatchSettings

        survey = SurveyPopulationSettings(match=MatchSettings(measures=settings.survey_measures))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # unmatched people are still people; their truth is their body
            parts.append(build_survey_population(settings.n_survey, seed=settings.seed + 1, settings=survey,
                                                 show_progress=show_progress).assign(population="survey"))
    pop = pd.concat(parts, ignore_index=True)
    pop["subject_id"] = np.arange(len(pop))
    return pop


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
                     workers: int = 1, folder=None, show_progress: bool | None = None,
                     log_lines: bool = False) -> dict[str, Samples]:
    """Render the training captures: the fit subjects' and the calibration subjects' (steps 1–3).

    Parameters
    ----------
    settings : TrainSettings
    parts : tuple of {'fit', 'calibration'}
        Which to render, at least one (the calibration captures alone re-create a model's calibration
        scores). Checked before anything is built.
    workers : int
        Local worker processes (the renders do not depend on it).
    folder : path-like, optional
        Where finished chunks are kept (:class:`~wbsa.training.store.RenderStore`, one subfolder per part): a
        run killed half-way resumes from them.
    show_progress : bool, optional
        Progress bars (None: when stderr is a terminal, :func:`wbsa.progress.progress`).
    log_lines : bool
        Where no bar is shown, log lines of the renders' progress instead.

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
    from pathlib import Path

    from wbsa.training.recipe import MODEL_REVISION, settings_hash

    _check_parts(parts)
    pop = training_population(settings, show_progress)
    rng = np.random.default_rng(settings.seed)
    calib = rng.random(len(pop)) < settings.calibration_fraction
    chosen = {"fit": (~calib, settings.seed), "calibration": (calib, settings.seed + 7919)}
    out = {}
    for part in parts:
        rows, seed = chosen[part]
        key = f"r{MODEL_REVISION}-{settings_hash(settings)}"  # renders of another wbsa revision are not reused
        store = None if folder is None else RenderStore(Path(folder) / part, key)
        out[part] = render_samples(pop[rows].reset_index(drop=True), settings.render, seed, workers=workers,
                                   store=store, show_progress=show_progress, log_lines=log_lines)
    return out


def train_model(settings: TrainSettings = TrainSettings(), *, workers: int = 1, show_progress: bool | None = None,
                samples: tuple[Samples, Samples] | None = None, folder=None, log_lines: bool = False) -> EstimatorModel:
    """Train an estimator model (see the module doc).

    Parameters
    ----------
    settings : TrainSettings
    workers : int
        Local worker processes for the renders (the model does not depend on it).
    samples : (Samples, Samples), optional
        Already rendered (fit, calibration) samples; skips steps 1–3.
    folder : path-like, optional
        Keep the renders there as they finish, and resume from them (:func:`training_renders`).
    log_lines : bool
        Where no progress bar is shown, log lines of the renders' progress instead.

    Returns
    -------
    EstimatorModel
        ``meta`` holds the settings, the training ranges and held-out calibration metrics.
    """
    if samples is None:
        parts = training_renders(settings, workers=workers, folder=folder, show_progress=show_progress,
                                 log_lines=log_lines)
        fit_s, cal_s = parts["fit"], parts["calibration"]
    else:
        fit_s, cal_s = samples
    fit_s, cal_s = (usable(s) for s in (fit_s, cal_s))
    if len(fit_s) < 20 or len(cal_s) < 20:
        raise WbsaError(f"too few usable renders to train ({len(fit_s)} fit, {len(cal_s)} calibration); "
                        "use more subjects")
    fit_t = fit_s.table
    psi_oof, sd_oof, axis_sd = oof_view(fit_s, settings.folds, settings.seed)
    on_floor = fit_t["m_floor_seen"].to_numpy() > 0.5
    on_floor = on_floor if on_floor.any() else np.ones(len(fit_t), dtype=bool)
    el_sd = {"floor": rms((fit_t["m_elevation_deg"] - fit_t["elevation_deg"])[on_floor]),
             "axis": rms(fit_t["m_elevation_axis_deg"] - fit_t["elevation_deg"])}
    view = fit_view_model(fit_s.descriptors[:, :VIEW_DIMS], fit_t["azimuth_deg"].to_numpy(), seed=settings.seed,
                          axis_sd_deg=axis_sd, elevation_sd_deg=el_sd)
    shape = fit_s.descriptors[:, VIEW_DIMS:]
    mean, scale, coef, intercept, trees = fit_wbsa(fit_t, shape, psi_oof, sd_oof, settings)
    spread, spread_range = fit_spread(fit_s, psi_oof, sd_oof, settings)
    model = EstimatorModel(view, mean, scale, coef, intercept, trees, spread, spread_range, np.zeros(1), {})
    # calibration: held-out subjects through the finished models
    cal_t = cal_s.table
    resid, scores, psi_c, sd_c = calibration_scores(model, cal_s)
    model.scores = np.sort(scores)
    err = 100 * (np.exp(-resid) - 1)
    az_err = np.abs(psi_c - fold_azimuth(cal_t["azimuth_deg"].to_numpy()))
    feats_f = sample_columns(fit_t)
    render = settings.render
    model.meta = {
        "name": "estimator", "settings": asdict(settings),
        "ranges": {**{k: [float(np.min(v)), float(np.max(v))] for k, v in range_values(feats_f).items()},
                   # the layers drawn are uniform in the settings' range, whose top no draw reaches exactly
                   "clothing_m": [0.0, float(render.clothing_m[1]) if render.clothed_share > 0 else 0.0]},
        "n_fit": len(fit_s), "n_calibration": len(cal_s),
        "n_calibration_subjects": int(cal_t["subject_id"].nunique()),
        "calibration": {"wbsa_mape_pct": float(np.mean(np.abs(err))), "wbsa_bias_pct": float(np.mean(err)),
                        "azimuth_error_median_deg": float(np.median(az_err)),
                        "azimuth_error_p95_deg": float(np.percentile(az_err, 95))},
        # the view spread the WBSA model learnt on and the one it meets at run time
        "azimuth_sd_median_deg": {"fit": float(np.median(sd_oof)), "calibration": float(np.median(sd_c))},
    }
    return model


def usable(s: Samples) -> Samples:
    """The renders whose measures succeeded (``m_ok``)."""
    ok = s.table["m_ok"].to_numpy(dtype=bool)
    return Samples(s.table[ok].reset_index(drop=True), s.descriptors[ok])
