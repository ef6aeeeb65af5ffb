"""The per-chunk scan work: build each body of the chunk, then measure every view of it.

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
from wbsa.scan.settings import ScanJob

_BODY_MODEL = None


def body_model():
    """The process-wide :class:`wbsa.bodies.body_model.BodyModel`, built on first use.

    Building anny takes about 0.3 s from its cache (a minute on a fresh machine), so a worker builds it
    once and keeps it for every chunk it scans.
    """
    global _BODY_MODEL
    if _BODY_MODEL is None:
        from wbsa.bodies.body_model import BodyModel

        _BODY_MODEL = BodyModel()
    return _BODY_MODEL


def check_population(population: pd.DataFrame) -> None:
    """Check that a population table has the phenotype columns the body model needs.

    Raises
    ------
    WbsaError
        If a required ``p_*`` column is missing.
    """
    from wbsa.bodies.body_model import OPTIONAL_PHENOTYPES, PHENOTYPE_COLUMNS

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


def scan_chunk(subjects: pd.DataFrame, settings: ScanJob) -> pd.DataFrame:
    """Scan a chunk of subjects at every view of ``settings``.

    Parameters
    ----------
    subjects : DataFrame
        Rows of a population table: ``subject_id`` and the ``p_*`` phenotype columns.
    settings : ScanJob

    Returns
    -------
    DataFrame
        One row per subject x view, in subject then view order (see :func:`scan_subject`).

    Notes
    -----
    Each body is built on its own, not in one batch: anny's batched forward pass rounds differently
    for different batch sizes (up to 4.4e-16 m on a vertex), which would make the rows depend on the
    chunk size. Building one at a time costs a few milliseconds per body, against ~65 ray-cast views.
    """
    keep_large_allocations()
    with single_threaded_math():
        model = body_model()
        nthreads = cast_threads()
        rows: list[dict[str, Any]] = []
        for i in range(len(subjects)):
            one = subjects.iloc[i:i + 1]
            mesh = model.skin_meshes(one)[0]
            rows.extend(scan_subject(mesh, int(one["subject_id"].iloc[0]), settings, nthreads=nthreads))
    return pd.DataFrame(rows)


def scan_subject(mesh, subject_id: int, settings: ScanJob, *, nthreads: int = 0) -> list[dict[str, Any]]:
    """All views of one body.

    Parameters
    ----------
    mesh : TriangleMesh
        The subject's skin mesh (metres, standing on z = 0).
    subject_id : int
    settings : ScanJob
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
        a sensor, else from the ideal frame); and ``camera_inside``: True for a view whose camera stands
        inside the body, a view that is not measured (areas NaN, no pixels, ``fits_in_frame`` False) and
        that the fits leave out.
    """
    from wbsa.camera import MeshScene
    from wbsa.camera.extrinsics import pose_from_view
    from wbsa.simulate.view import simulate_views

    scene = MeshScene(mesh, nthreads=nthreads)
    rows = []
    inside = [scene.contains(pose_from_view(view, scene.center).camera_center) for view in settings.views]
    seen = iter(simulate_views(scene, settings.camera, [v for v, x in zip(settings.views, inside) if not x],
                               backend=settings.backend, sensor=settings.sensor, seed=settings.seed,
                               subject_id=subject_id, reconstruct=settings.reconstruct,
                               reconstruction=settings.reconstruction))
    for view, camera_inside in zip(settings.views, inside):
        if camera_inside:
            rows.append(invalid_view_row(subject_id, view, settings))
        else:
            rows.append({"subject_id": subject_id, **next(seen).row, "camera_inside": False})
    return rows


def invalid_view_row(subject_id: int, view, settings: ScanJob) -> dict[str, Any]:
    """The row of a view whose camera stands inside the body: the view's keys, no pixels, NaN areas."""
    from wbsa.surface.settings import recon_column

    nan = float("nan")
    row: dict[str, Any] = {"subject_id": subject_id, "azimuth_deg": view.azimuth_deg,
                           "elevation_deg": view.elevation_deg, "distance_m": view.distance_m,
                           "camera": settings.camera_name, "vbsa_hit_m2": nan, "vbsa_visible_m2": nan,
                           "n_pixels": 0, "n_triangles_hit": 0, "fits_in_frame": False}
    if settings.sensor is not None:
        row.update({"n_pixels_sensor": 0, "vbsa_hit_sensor_m2": nan, "vbsa_visible_sensor_m2": nan})
        row.update({f"sensor_{k}": v for k, v in settings.sensor.to_dict().items()})
    row.update({recon_column(m): nan for m in settings.reconstruct})
    row["camera_inside"] = True
    return row
