"""``wbsa train-start``'s work: the crops, the network, its held-out figures, and the files (:func:`train_start`)."""

from __future__ import annotations

import time
from dataclasses import asdict
from pathlib import Path

import numpy as np

from wbsa.training.start.settings import StartSettings

#: The weights and the card :func:`train_start` writes into its folder.
MODEL_NAME, CARD_NAME = "start.npz", "start_card.json"


def start_folder(settings: StartSettings) -> Path:
    """The cache folder of a run with these settings without ``--out`` (``start-<data key>``)."""
    from wbsa.training.cache import cache_dir
    from wbsa.training.start.data import data_key

    return cache_dir() / f"start-{data_key(settings)}"


def train_start(settings: StartSettings, out=None, *, workers: int = 1, show_progress: bool | None = None,
                log=None) -> tuple[Path, Path]:
    """Make the crops (resuming from ``out``/crops), train the network, judge it on the validation bodies.

    Parameters
    ----------
    settings : StartSettings
    out : path-like, optional
        The run's folder (default :func:`start_folder`): ``crops/`` (the chunks), :data:`MODEL_NAME`,
        :data:`CARD_NAME`, and the run's timings in ``start.npz.log.json``.
    workers : int
        Local worker processes for the captures (the crops do not depend on it).
    show_progress : bool, optional
    log : callable, optional
        ``log(line)`` of the training's progress.

    Returns
    -------
    (Path, Path)
        The model and its card.
    """
    from wbsa.core.versions import WBSA_VERSION
    from wbsa.io import write_json, write_run_log
    from wbsa.training.start.data import data_key, start_crops
    from wbsa.training.start.fit import (ADULT_YEARS, fit_start, predict_crops, start_figures, stature_sex_rule,
                                         validation_subjects)

    folder = Path(out) if out is not None else start_folder(settings)
    t0, c0 = time.perf_counter(), time.process_time()
    data = start_crops(settings, folder / "crops", workers=workers, show_progress=show_progress)
    t1, c1 = time.perf_counter(), time.process_time()
    held = validation_subjects(data["subject_id"], settings)
    ok = data["ok"].astype(bool)
    model = fit_start(data, ~held, settings, log)
    t2, c2 = time.perf_counter(), time.process_time()
    val = held & ok
    figures = start_figures(predict_crops(model, data, val), {k: data[k][val] for k in data}) if val.any() \
        else {"n": 0}
    trained = ~held & ok
    if (data["age_years"][trained] >= ADULT_YEARS).any():
        cut = stature_sex_rule(data["height_m"][trained], data["male"][trained], data["age_years"][trained])
    else:  # a trial run without an adult: no rule to compare with
        cut = float("nan")
    adult = val & (data["age_years"] >= ADULT_YEARS)
    rule_right = (data["height_m"][adult] > cut) == data["male"][adult].astype(bool)
    import torch

    model.card.update({
        "what": "the body fit's learned start: anny's parameters, age, mass, stature, sex and view from one "
                "segmented depth view, each with a spread (wbsa.estimation.methods.body_fit.start_net)",
        "command": "wbsa train-start " + " ".join(settings_options(settings)),
        "data": {"key": data_key(settings), "bodies": int(settings.n_random + settings.n_survey),
                 "random": settings.n_random, "survey": settings.n_survey,
                 "views_per_body": settings.render.views_per_subject, "crops": int(len(ok)), "usable": int(ok.sum()),
                 "validation_bodies": int(len(np.unique(data["subject_id"][held]))), "seed": settings.seed},
        "settings": asdict(settings),
        "validation": figures,
        "stature_sex_rule": {"threshold_m": cut, "sex_right_adults_pct": float(100.0 * rule_right.mean())
                             if adult.any() else float("nan")},
        "versions": {"wbsa": WBSA_VERSION, "torch": torch.__version__},
    })
    model_path = model.save(folder / MODEL_NAME)
    card_path = write_json(model.card, folder / CARD_NAME)
    # timings are run information, not data: beside the model, not in it (same settings, same bytes)
    write_run_log({"crops_seconds": round(t1 - t0, 1), "train_seconds": round(t2 - t1, 1),
                   "train_cpu_seconds": round(c2 - c1, 1), "crops_main_process_cpu_seconds": round(c1 - c0, 1),
                   "workers": workers}, model_path)
    return model_path, card_path


def settings_options(settings: StartSettings) -> list[str]:
    """The ``wbsa train-start`` options that give ``settings`` (those that differ from the defaults)."""
    d = StartSettings()
    opts = []
    for name, value, default in (("--subjects", settings.n_random, d.n_random),
                                 ("--survey-subjects", settings.n_survey, d.n_survey),
                                 ("--views", settings.render.views_per_subject, d.render.views_per_subject),
                                 ("--epochs", settings.epochs, d.epochs), ("--batch", settings.batch, d.batch),
                                 ("--seed", settings.seed, d.seed),
                                 ("--chunk-subjects", settings.chunk_subjects, d.chunk_subjects)):
        if value != default:
            opts += [name, str(value)]
    return opts
