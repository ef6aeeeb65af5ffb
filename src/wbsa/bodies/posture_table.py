"""Posture columns of a population table: draw each subject's posture, settle it on its body, measure it."""

from __future__ import annotations

import functools

import numpy as np
import pandas as pd

from wbsa.bodies.posture import ANGLE_COLUMNS, POSTURE_COLUMNS, PostureSettings, draw_postures, settle_posture
from wbsa.parallel import single_threaded_math
from wbsa.progress import progress

#: Column of the posed body's skin area (WBSA itself, ``wbsa_m2``, is the rest pose's).
POSED_AREA_COLUMN = "wbsa_posed_m2"


def add_postures(table: pd.DataFrame, settings: PostureSettings, *, model=None, batch_size: int = 64,
                 show_progress: bool | None = None, workers: int = 1, scheduler: str | None = None) -> pd.DataFrame:
    """``table`` with every subject's posture and the skin area of its posed body.

    Each subject's angles are drawn (:func:`~wbsa.bodies.posture.draw_postures`, from its own random
    stream), then settled on its own body (:func:`~wbsa.bodies.posture.settle_posture`: limbs that would
    sink into the body are raised), and the table records the settled angles: these are the angles
    every later stage applies (:meth:`~wbsa.bodies.body_model.BodyModel.skin_meshes`).

    Parameters
    ----------
    table : pandas.DataFrame
        A population table (``subject_id``, the ``p_*`` and optionally ``l_*`` columns); any posture
        columns it has are replaced.
    settings : PostureSettings
        ``posture="a-pose"`` returns ``table`` unchanged (no posture columns: the paper's rest pose).
    model : BodyModel, optional
        Used in this process (built when not given).
    batch_size : int
        Bodies per anny forward pass and per chunk of work.
    workers, scheduler
        Worker processes (used from :data:`~wbsa.bodies.table.PARALLEL_MIN_BODIES` bodies up) or a dask
        scheduler address (see :mod:`wbsa.parallel`); the table does not depend on them.

    Returns
    -------
    pandas.DataFrame
        ``table`` without old posture columns, followed by :data:`~wbsa.bodies.posture.POSTURE_COLUMNS`
        and :data:`POSED_AREA_COLUMN` (m²).
    """
    if not settings.varies:
        return table
    from wbsa.bodies.table import PARALLEL_MIN_BODIES
    from wbsa.parallel import dask_client, map_unordered, resolve_scheduler

    base = table.drop(columns=[c for c in (*POSTURE_COLUMNS, POSED_AREA_COLUMN) if c in table.columns])
    base = base.reset_index(drop=True)
    drawn = draw_postures(base["subject_id"].to_numpy(), settings)
    angles = drawn[list(ANGLE_COLUMNS)].to_numpy(dtype=np.float64, copy=True)
    areas = np.empty(len(base))
    starts = list(range(0, len(base), batch_size))
    chunks = [(base.iloc[s:s + batch_size], angles[s:s + batch_size]) for s in starts]
    scheduler = resolve_scheduler(scheduler)
    with progress(total=len(base), desc="postures", unit="body", enabled=show_progress) as bar:
        if scheduler is None and (workers <= 1 or len(base) < PARALLEL_MIN_BODIES):
            for start, (rows, drawn_angles) in zip(starts, chunks):
                done = slice(start, start + len(rows))
                angles[done], areas[done] = settle_chunk(rows, drawn_angles, model)
                bar.update(len(rows))
        else:
            with dask_client(workers, scheduler) as client:
                for i, (chunk_angles, chunk_areas) in map_unordered(client, settle_chunk, chunks, tag="postures"):
                    done = slice(starts[i], starts[i] + len(chunk_areas))
                    angles[done], areas[done] = chunk_angles, chunk_areas
                    bar.update(len(chunk_areas))
    drawn[list(ANGLE_COLUMNS)] = angles
    drawn[POSED_AREA_COLUMN] = areas
    return pd.concat([base, drawn], axis=1)


def settle_chunk(rows: pd.DataFrame, angles: np.ndarray, model=None) -> tuple[np.ndarray, np.ndarray]:
    """Settle the drawn postures of a chunk of bodies and measure their posed skin areas.

    Parameters
    ----------
    rows : pandas.DataFrame
        Population rows (``p_*`` and optionally ``l_*`` columns).
    angles : (b, 10) float64
        Their drawn joint angles (:data:`~wbsa.bodies.posture.ANGLE_COLUMNS` order).
    model : BodyModel, optional
        Default: this process's model, built once.

    Returns
    -------
    angles : (b, 10) float64
        The settled angles.
    areas : (b,) float64
        Posed skin areas, m² (the area of :meth:`~wbsa.bodies.body_model.BodyModel.skin_meshes`).
    """
    from wbsa.core.mesh import TriangleMesh
    from wbsa.parallel import keep_large_allocations

    keep_large_allocations()
    model = model or _process_model()
    out = np.array(angles, dtype=np.float64, copy=True)
    areas = np.empty(len(rows))
    with single_threaded_math():
        bodies = model.rest_bodies(rows)
        for k, (v, heads) in enumerate(zip(bodies.vertices, bodies.bone_heads)):
            out[k], posed = settle_posture(v, heads, out[k], model.rig)
            areas[k] = TriangleMesh(posed, model.skin_faces).area_m2
    return out, areas


@functools.lru_cache(maxsize=1)
def _process_model():
    """This process's body model (built once per worker)."""
    from wbsa.bodies.body_model import BodyModel

    return BodyModel()
