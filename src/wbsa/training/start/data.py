"""The learned start's training data: crops of ``wbsa train``'s captures, with their truth, kept in chunks.

Each body of the population (:func:`start_population`) is captured ``render.views_per_subject`` times by
:func:`wbsa.training.renders.draw_captures` (the rooms, cameras, sensors, postures and clothes of ``wbsa train``),
segmented as a real frame is, and cropped by :func:`~wbsa.estimation.methods.body_fit.start_crop.start_crop`.
A chunk of bodies is one ``chunk-<first sample>.npz`` (:class:`CropStore`); a run killed half-way reads the
chunks it finished and crops only the rest. Sample ``i`` draws from ``SeedSequence([seed, i])``: the same
seed gives the same crops whatever the chunking or workers.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pandas as pd

from wbsa.errors import WbsaError
from wbsa.training.start.settings import StartSettings
from wbsa.training.store import RenderStore

#: Revision of the crops; a store of crops made otherwise is refused rather than mixed.
DATA_REVISION = 1
#: Per-crop arrays of a chunk besides the image (their truth and conditions).
CHUNK_FIELDS = ("sample", "subject_id", "ok", "height_m", "cell_m", "floor_seen", "male", "age_years", "mass_kg",
                "stature_m", "azimuth_deg", "elevation_deg", "distance_m", "clothing_m", "params", "posture",
                "camera", "population")


def start_population(settings: StartSettings, show_progress: bool | None = None) -> pd.DataFrame:
    """The bodies: random and survey-matched, drawn as ``wbsa train`` draws its own
    (:func:`wbsa.training.pipeline.training_population`), one row per body with its truth."""
    from wbsa.training.pipeline import training_population
    from wbsa.training.settings import TrainSettings

    return training_population(TrainSettings(n_random=settings.n_random, n_survey=settings.n_survey,
                                             survey_measures=settings.survey_measures,
                                             age_years=settings.age_years, seed=settings.seed), show_progress)


def data_key(settings: StartSettings) -> str:
    """Hash of what the crops depend on: the population, the captures, the seed and the crop's layout."""
    from wbsa.estimation.methods.body_fit import start_crop as sc

    record = {"revision": DATA_REVISION, "n_random": settings.n_random, "n_survey": settings.n_survey,
              "survey_measures": settings.survey_measures, "age_years": list(settings.age_years),
              "render": asdict(settings.render), "seed": settings.seed, "chunk_subjects": settings.chunk_subjects,
              "crop": [list(sc.CROP_SHAPE), sc.SPAN_OF_HEIGHT, sc.DEPTH_SCALE_M, sc.DEPTH_CLIP, sc.TOP_QUANTILE]}
    text = json.dumps(record, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def crop_chunk(population: pd.DataFrame, first_sample: int, settings: StartSettings) -> dict[str, np.ndarray]:
    """Capture and crop every body of ``population`` (samples from ``first_sample`` on).

    Returns
    -------
    dict of str to ndarray
        ``image`` (n, 2, rows, cols) float32 (zeros where ``ok`` is False: no subject found, or too few
        returns) and the :data:`CHUNK_FIELDS`, one entry per capture: ``params`` (n, 18) float64 (anny's
        :data:`~wbsa.bodies.body_model.BODY_PARAMETER_COLUMNS`), ``male`` bool, ``posture``, ``camera`` and
        ``population`` str, the others numbers.
    """
    from wbsa.bodies.body_model import body_parameter_array
    from wbsa.estimation.methods.body_fit.start_crop import CROP_SHAPE, start_crop
    from wbsa.parallel import keep_large_allocations, single_threaded_math
    from wbsa.training.renders import draw_captures

    keep_large_allocations()
    params = body_parameter_array(population)
    by_id = {int(s): i for i, s in enumerate(population["subject_id"])}
    images, rows = [], []
    with single_threaded_math():
        for drawn in draw_captures(population, first_sample, settings.render, settings.seed):
            r = drawn.row
            crop = None
            if drawn.mask is not None:
                try:
                    crop = start_crop(drawn.depth_m, drawn.mask, drawn.camera, drawn.floor)
                except WbsaError:
                    crop = None
            b = by_id[int(r["subject_id"])]
            images.append(crop.image if crop is not None else np.zeros((2, *CROP_SHAPE), np.float32))
            rows.append({"sample": r["sample"], "subject_id": r["subject_id"], "ok": crop is not None,
                         "height_m": crop.height_m if crop is not None else np.nan,
                         "cell_m": crop.cell_m if crop is not None else np.nan,
                         "floor_seen": bool(crop is not None and crop.floor_seen), "male": r["sex"] == "male",
                         "age_years": r["age_years"], "mass_kg": r["mass_kg"], "stature_m": r["stature_m"],
                         "azimuth_deg": r["azimuth_deg"], "elevation_deg": r["elevation_deg"],
                         "distance_m": r["distance_m"], "clothing_m": r["clothing_m"], "params": params[b],
                         "posture": str(r["posture"]), "camera": str(r["camera"]),
                         "population": str(population["population"].iloc[b]) if "population" in population else ""})
    out = {"image": np.stack(images) if images else np.zeros((0, 2, *CROP_SHAPE), np.float32)}
    for k in CHUNK_FIELDS:
        values = [row[k] for row in rows]
        out[k] = np.asarray(values, dtype=str) if k in ("posture", "camera", "population") else np.asarray(values)
    out["sample"] = out["sample"].astype(np.int64)
    out["subject_id"] = out["subject_id"].astype(np.int64)
    out["ok"] = out["ok"].astype(bool)
    out["floor_seen"] = out["floor_seen"].astype(bool)
    out["male"] = out["male"].astype(bool)
    return out


class CropStore(RenderStore):
    """Finished crop chunks of one data set (``chunk-<first sample>.npz``, written atomically, the
    same bytes for the same crops), refusing a
    folder of other settings as :class:`~wbsa.training.store.RenderStore` does."""

    def _path(self, first_sample: int) -> Path:
        return self.folder / f"chunk-{first_sample:07d}.npz"

    def read(self, first_sample: int):
        """The chunk starting at ``first_sample`` (a dict of arrays) if it is done, else None."""
        path = self._path(first_sample)
        if not path.is_file():
            return None
        try:
            with np.load(path, allow_pickle=False) as z:
                return {k: z[k] for k in z.files}
        except (OSError, ValueError) as exc:
            raise WbsaError(f"crop chunk {path} is unreadable ({type(exc).__name__}); delete it and run again to "
                            "make it anew") from None

    def write(self, part: dict) -> None:
        """Keep a finished chunk (:func:`crop_chunk`'s arrays; named by its first sample)."""
        from wbsa.io import write_npz

        write_npz(part, self._path(int(part["sample"][0])))


def start_crops(settings: StartSettings, folder=None, *, population: pd.DataFrame | None = None, workers: int = 1,
                show_progress: bool | None = None) -> dict[str, np.ndarray]:
    """Every crop of the data set, in sample order (see the module doc).

    Parameters
    ----------
    settings : StartSettings
    folder : path-like, optional
        Where finished chunks are kept (:class:`CropStore`); chunks found there are read, not made again.
    population : pandas.DataFrame, optional
        The bodies (default :func:`start_population`; given, e.g. by a test, it must be what the settings draw).
    workers : int
        Local worker processes (the crops do not depend on it).
    show_progress : bool, optional
        Progress bar (None: when stderr is a terminal).

    Returns
    -------
    dict of str to ndarray
        :func:`crop_chunk`'s arrays of all chunks, concatenated.
    """
    from wbsa.parallel import map_chunks
    from wbsa.progress import progress

    pop = start_population(settings, show_progress) if population is None else population
    v, n = settings.render.views_per_subject, settings.chunk_subjects
    starts = list(range(0, len(pop), n))
    store = None if folder is None else CropStore(Path(folder), data_key(settings))
    done = {s: store.read(s * v) for s in starts} if store is not None else {}
    done = {s: part for s, part in done.items() if part is not None}
    todo = [s for s in starts if s not in done]
    args = [(pop.iloc[s:s + n].reset_index(drop=True), s * v, settings) for s in todo]
    bar = progress(total=len(pop) * v, desc="start crops", unit="view", enabled=show_progress)
    bar.update(sum(len(p["sample"]) for p in done.values()))

    def finished(part: dict) -> None:
        if store is not None:
            store.write(part)
        bar.update(len(part["sample"]))

    try:
        parts = map_chunks(crop_chunk, args, workers=workers, tag="start-crops", on_result=finished)
    finally:
        bar.close()
    by_start = {**done, **dict(zip(todo, parts))}
    ordered = [by_start[s] for s in starts]
    return {k: np.concatenate([p[k] for p in ordered]) for k in ordered[0]}
