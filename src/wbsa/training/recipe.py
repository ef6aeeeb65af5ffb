"""The recipe of the shipped default model: its revision, its training settings' hash, its rebuild and its card.

The model that ships in ``wbsa/data`` (:mod:`wbsa.estimation.methods.regression.default_model`) is what ``TrainSettings()``
trains at :data:`MODEL_REVISION`. ``wbsa train --default`` rebuilds it (:func:`wbsa.training.run.rebuild_default_model`) (about 70 minutes on 2 cores) and writes
its model card; a test fails when the settings or the revision change without that rebuild
(``tests/test_default_model.py``).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict
from pathlib import Path

from wbsa.estimation.methods.regression.model import EstimatorModel
from wbsa.training.settings import TrainSettings

#: Bumped whenever the measures, the renders or the model change what a trained model means.
MODEL_REVISION = 21
#: The command that rebuilds the shipped model (also written into its card).
REBUILD_COMMAND = "wbsa train --default"


def settings_hash(settings: TrainSettings) -> str:
    """12 hex digits of the SHA-256 of the settings (sorted JSON): the same settings, the same hash."""
    text = json.dumps(asdict(settings), sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def training_world(settings: TrainSettings) -> dict:
    """What a model trained with ``settings`` has seen: subjects, postures, cameras, distances, clothes."""
    from wbsa.bodies.posture import POSTURES
    from wbsa.camera.presets import camera_record

    r, c = settings.render, settings.render.capture
    cameras = [{"name": name, "technology": camera_record(name).technology,
                "working_range_m": list(camera_record(name).working_range_m)}
               for name in c.cameras if isinstance(name, str)]
    return {
        "subjects": {"random": settings.n_random, "survey_matched_nhanes": settings.n_survey,
                     "survey_measures": settings.survey_measures,
                     "random_age_years": list(settings.age_years),
                     "calibration_share": settings.calibration_fraction},
        "captures_per_subject": r.views_per_subject,
        "postures": list(r.postures) if r.postures else sorted(POSTURES),
        "cameras": cameras,
        "distance_m": list(c.distance_m), "camera_height_m": list(c.camera_height_m),
        "azimuth_deg": [0.0, 360.0],
        "sensor": {"noise_scale": list(c.noise_scale), "grazing_dropout_scale": list(c.grazing_dropout_scale),
                   "ideal_share": c.ideal_share, "edge_pixels": list(c.edge_pixels)},
        "scene": {"room": r.room, "body_alone_share": r.alone_share, "scan_render_share_of_alone": r.scan_share},
        "clothes": {"dressed_share": r.clothed_share, "layer_m": list(r.clothing_m)},
    }


def model_card(model: EstimatorModel, settings: TrainSettings, benchmark: dict | None = None) -> dict:
    """The card of a model trained with ``settings``: revision, hash, training world, figures, ranges."""
    return {
        "model": "wbsa estimator (regression)", "revision": MODEL_REVISION, "settings_hash": settings_hash(settings),
        "file_format": {"name": "wbsa-estimator", "version": _format_version()},
        "rebuild": REBUILD_COMMAND,
        "trained_on": training_world(settings),
        "n_fit_captures": model.meta.get("n_fit"), "n_calibration_captures": model.meta.get("n_calibration"),
        "n_calibration_subjects": model.meta.get("n_calibration_subjects"),
        "calibration": model.meta.get("calibration"),
        "trained_ranges": model.meta.get("ranges"),
        "benchmark": benchmark,
        "settings": asdict(settings),
    }


def _format_version() -> int:
    from wbsa.estimation.methods.regression.model import VERSION

    return VERSION


def write_default_model(model: EstimatorModel, settings: TrainSettings, folder: Path,
                        benchmark: dict | None = None) -> tuple[Path, Path]:
    """Write ``model`` and its card as the shipped default (``folder``: ``src/wbsa/data`` of a checkout)."""
    from wbsa.estimation.methods.regression.default_model import DEFAULT_CARD_FILE, DEFAULT_MODEL_FILE
    from wbsa.io import write_text

    model.meta["name"] = "default"
    model.meta["revision"] = MODEL_REVISION
    model.meta["settings_hash"] = settings_hash(settings)
    path = model.save(Path(folder) / DEFAULT_MODEL_FILE)
    card = write_text(json.dumps(model_card(model, settings, benchmark), indent=1, default=str) + "\n",
                      Path(folder) / DEFAULT_CARD_FILE)
    return path, card
