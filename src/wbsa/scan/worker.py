"""The per-chunk scan work: build the chunk's bodies in one batch, then measure every view of each.

Runs in a dask worker process (or in the main process with ``--workers 1``). The anny body model
is built once per process (:func:`body_model`) and reused by every chunk that process scans.
One :class:`~wbsa.camera.MeshScene` (Open3D BVH) is built per body and reused for all its views.
The optional steps, sensor simulation and surface reconstruction, run only when the settings ask
for them; without them no full-image depth frame is built at all.
"""

from __future__ import annotations

from contextlib import contextmanager
from typing import Any, Iterator

import numpy as np
import pandas as pd

from wbsa.errors import WbsaError
from wbsa.parallel import keep_large_allocations, single_threaded_math
from wbsa.scan.settings import ScanSettings

_BODY_MODEL = None


def body_model():
    """The process-wide :class:`wbsa.population.body_model.BodyModel`, built on first use.

    Building anny takes about 0.3 s from its cache (a minute on a fresh machine), so a worker builds it
    once and keeps it for every chunk it scans.
    """
    global _BODY_MODEL
    if _BODY_MODEL is None:
        from wbsa.population.body_model import BodyModel

        _BODY_MODEL = BodyModel()
    return _BODY_MODEL


def check_population(population: pd.DataFrame) -> None:
    """Check that a population table has the phenotype columns the body model needs.

    Raises
    ------
    WbsaError
        If a required ``p_*`` column is missing.
    """
    from wbsa.population.body_model import OPTIONAL_PHENOTYPES, PHENOTYPE_COLUMNS

    missing = [c for c in PHENOTYPE_COLUMNS if c not in OPTIONAL_PHENOTYPES and c not in population.columns]
    if missing:
        raise WbsaError(f"population table lacks phenotype column(s) {', '.join(missing)}; "
                        "make it with wbsa population")


def cast_threads() -> int:
    """Open3D threads per ray cast: 1 inside a dask worker (one worker per core), else all cores (0)."""
    return 1 if _in_dask_worker() else 0


def _in_dask_worker() -> bool:
    try:
        from distributed import get_worker

        get_worker()
        return True
    except (ImportError, ValueError):
        return False


def scan_chunk(subjects: pd.DataFrame, settings: ScanSettings) -> pd.DataFrame:
    """Scan a chunk of subjects at every view of ``settings``.

    Parameters
    ----------
    subjects : DataFrame
        Rows of a population table: ``subject_id`` and the ``p_*`` phenotype columns.
    settings : ScanSettings

    Returns
    -------
    DataFrame
        One row per subject x view, in subject then view order (see :func:`scan_subject`).
    """
    keep_large_allocations()
    with single_threaded_math():
        meshes = body_model().skin_meshes(subjects)
        nthreads = cast_threads()
        rows: list[dict[str, Any]] = []
        for subject_id, mesh in zip(subjects["subject_id"].to_numpy(), meshes):
            rows.extend(scan_subject(mesh, int(subject_id), settings, nthreads=nthreads))
    return pd.DataFrame(rows)


def scan_subject(mesh, subject_id: int, settings: ScanSettings, *, nthreads: int = 0) -> list[dict[str, Any]]:
    """All views of one body.

    Parameters
    ----------
    mesh : TriangleMesh
        The subject's skin mesh (metres, standing on z = 0).
    subject_id : int
    settings : ScanSettings
    nthreads : int
        Open3D threads per ray cast (0 = all cores).

    Returns
    -------
    list of dict
        Per view: ``subject_id`` and :func:`wbsa.camera.measure_view`'s row (``azimuth_deg, elevation_deg,
        distance_m, camera, vbsa_hit_m2, vbsa_visible_m2, n_pixels, n_triangles_hit, fits_in_frame``);
        with a sensor also ``n_pixels_sensor, vbsa_hit_sensor_m2, vbsa_visible_sensor_m2`` (the same
        measures on the sensor's frame) and ``sensor_<setting>`` for each sensor setting; and
        ``vbsa_recon_<method>_m2`` for each reconstruction method (from the sensor's frame when there is
        a sensor, else from the ideal frame).
    """
    from wbsa.camera import MeshScene
    from wbsa.camera.measure import iter_measure_views

    scene = MeshScene(mesh, nthreads=nthreads)
    sensor, methods = settings.sensor, settings.reconstruct
    need_frame = sensor is not None or bool(methods)
    if sensor is not None:
        from wbsa.sensor.measure import sense_view, view_rng
    if methods:
        from wbsa.surface import recon_column, vbsa_recon_m2

    rows = []
    measured = iter_measure_views(scene, settings.camera, settings.views, scene.center, backend=settings.backend,
                                  return_frames=need_frame)
    for view, (row, frame) in zip(settings.views, measured):
        row = {"subject_id": subject_id, **row}
        if sensor is not None:
            frame, sensed = sense_view(frame, scene, sensor, view_rng(settings.seed, subject_id, view))
            row.update(sensed)
        for method in methods:
            row[recon_column(method)] = vbsa_recon_m2(frame, method, settings.reconstruction)
        rows.append(row)
    return rows
