"""Population tables: build the anthropometric table for a set of phenotypes, read it back."""

from __future__ import annotations

import functools
import os

import numpy as np
import pandas as pd

from wbsa.io import read_table
from wbsa.parallel import keep_large_allocations, single_threaded_math
from wbsa.bodies.anthropometry import (DEFAULT_DENSITY_KG_M3, MEASURE_COLUMNS, NHANES_LIMB_COLUMNS,
                                      REQUIRED_MEASURE_COLUMNS, Anthropometer)
from wbsa.bodies.body_model import ALL_LOCAL_CHANGE_COLUMNS, PHENOTYPE_COLUMNS, BodyModel, body_parameter_array
from wbsa.bodies.composition import COMPOSITION_COLUMNS, CompositionSettings
from wbsa.progress import progress

#: Smallest local population worth starting worker processes for.
PARALLEL_MIN_BODIES = 2000

#: Columns every population table has (:func:`read_population` requires them).
POPULATION_COLUMNS = ("subject_id", "sex", "age_years", *PHENOTYPE_COLUMNS, *REQUIRED_MEASURE_COLUMNS)
#: Columns a population table is written with: :data:`POPULATION_COLUMNS`, the NHANES limb measures
#: (:data:`~wbsa.bodies.anthropometry.NHANES_LIMB_COLUMNS`), then the local changes (0 unless fitted,
#: see :data:`~wbsa.bodies.body_model.ALL_LOCAL_CHANGE_COLUMNS`). A density model other than
#: ``constant`` adds :data:`~wbsa.bodies.composition.COMPOSITION_COLUMNS` after them.
TABLE_COLUMNS = (*POPULATION_COLUMNS, *NHANES_LIMB_COLUMNS, *ALL_LOCAL_CHANGE_COLUMNS)


def measure_population(params: pd.DataFrame, *, density_kg_m3: float = DEFAULT_DENSITY_KG_M3,
                       composition: CompositionSettings | None = None,
                       model: BodyModel | None = None, batch_size: int = 64,
                       show_progress: bool | None = None, workers: int = 1,
                       scheduler: str | None = None) -> pd.DataFrame:
    """Build every body of ``params`` and append its anthropometric measures.

    Parameters
    ----------
    params
        ``subject_id``, ``sex``, ``age_years``, the ``p_*`` columns and optionally the ``l_*``
        local changes (extra columns are kept).
    density_kg_m3
        Body density for mass = volume × density (when ``composition`` is None or ``constant``).
    composition
        Density model (:mod:`~wbsa.bodies.composition`). Other than ``constant``, mass and BMI
        come from each body's own density, and the composition columns are added (see
        :func:`with_composition`).
    workers, scheduler
        Local worker processes (used from :data:`PARALLEL_MIN_BODIES` bodies up), or a dask
        scheduler address (see :mod:`wbsa.parallel`); the table is the same whatever the worker count.

    Returns
    -------
    pandas.DataFrame
        ``params`` (missing optional ``p_*`` columns filled with 0.5) followed by
        :data:`~wbsa.bodies.anthropometry.MEASURE_COLUMNS`, the ``l_*`` local changes
        (missing ones 0) and, with a composition model,
        :data:`~wbsa.bodies.composition.COMPOSITION_COLUMNS`.
    """
    from wbsa.parallel import dask_client, map_unordered, resolve_scheduler

    body_parameter_array(params)  # validate every row before any work
    if composition is not None and composition.constant:
        density_kg_m3, composition = composition.density_kg_m3, None
    starts = list(range(0, len(params), batch_size))
    chunks = [(params.iloc[s:s + batch_size], density_kg_m3) for s in starts]
    parts: list[pd.DataFrame | None] = [None] * len(chunks)
    scheduler = resolve_scheduler(scheduler)
    with progress(total=len(params), desc="bodies", unit="body", enabled=show_progress) as bar:
        # starting workers costs each a model load (~5 s): below PARALLEL_MIN_BODIES one process is faster
        if scheduler is None and (workers <= 1 or len(params) < PARALLEL_MIN_BODIES):
            meter = Anthropometer(model, density_kg_m3) if model is not None else _anthropometer(density_kg_m3)
            with single_threaded_math():
                for i, (chunk, _) in enumerate(chunks):
                    parts[i] = meter.measure(meter.model.rest_bodies(chunk))
                    bar.update(len(chunk))
        else:
            with dask_client(workers, scheduler) as client:
                for i, rows in map_unordered(client, _measure_chunk, chunks, tag="population"):
                    parts[i] = rows
                    bar.update(len(rows))
    measures = pd.concat(parts, ignore_index=True) if parts else pd.DataFrame(columns=list(MEASURE_COLUMNS))
    # a population table given as parameters: its measures are measured again, not duplicated
    out = params.reset_index(drop=True).drop(columns=[c for c in (*MEASURE_COLUMNS, "fat_fraction", "density_kg_m3")
                                                      if c in params.columns])
    for name in PHENOTYPE_COLUMNS:
        if name not in out.columns:
            out[name] = 0.5
    local = pd.DataFrame({name: out.pop(name) if name in out.columns else np.zeros(len(out))
                          for name in ALL_LOCAL_CHANGE_COLUMNS})
    table = pd.concat([out, measures, local], axis=1)
    return table if composition is None else with_composition(table, composition)


def with_composition(table: pd.DataFrame, settings: CompositionSettings) -> pd.DataFrame:
    """``table`` with mass and BMI from each body's own density, and the composition columns.

    Uses ``volume_m3``, ``stature_m``, ``age_years``, ``sex`` and each subject's residual deviate:
    the table's ``fat_residual_z`` where it has one (the survey matcher's fitted deviates), else
    drawn from the subject's stream (keys: :func:`residual_keys`); see
    :func:`~wbsa.bodies.composition.solve_composition`. The constant model gives the table back
    unchanged.
    """
    from wbsa.bodies.composition import residual_z, solve_composition

    if settings.constant:
        return table
    if "fat_residual_z" in table.columns:
        z = table["fat_residual_z"].to_numpy(dtype=np.float64)
    else:
        z = residual_z(settings.seed, residual_keys(table))
    comp = solve_composition(settings, table["volume_m3"].to_numpy(), table["stature_m"].to_numpy(),
                             table["age_years"].to_numpy(), (table["sex"] == "male").to_numpy(), z)
    out = table.drop(columns=[c for c in COMPOSITION_COLUMNS if c in table.columns])
    out["mass_kg"] = comp.mass_kg
    out["bmi"] = comp.bmi
    last = next((c for c in reversed(ALL_LOCAL_CHANGE_COLUMNS) if c in out.columns), None)
    at = out.columns.get_loc(last) + 1 if last is not None else len(out.columns)
    out.insert(at, "fat_fraction", comp.fat_fraction)
    out.insert(at + 1, "density_kg_m3", comp.density_kg_m3)
    out.insert(at + 2, "fat_residual_z", z)
    return out


def residual_keys(table: pd.DataFrame) -> np.ndarray:
    """``(n, k) int64`` keys of each subject's composition residual stream.

    ``(survey_id, variation)`` in survey populations (a person's draw then does not depend on
    the number of variations or on who else was drawn), else ``subject_id``.
    """
    if {"survey_id", "variation"} <= set(table.columns):
        return table[["survey_id", "variation"]].to_numpy(dtype=np.int64)
    return table[["subject_id"]].to_numpy(dtype=np.int64)


@functools.lru_cache(maxsize=4)
def _anthropometer(density_kg_m3: float) -> Anthropometer:
    """One anthropometer per process and density (the body model inside is built once)."""
    return Anthropometer(BodyModel(), density_kg_m3)


def _measure_chunk(params: pd.DataFrame, density_kg_m3: float) -> pd.DataFrame:
    """Measures of one chunk of bodies in a worker process (its body model is built once)."""
    keep_large_allocations()
    meter = _anthropometer(density_kg_m3)
    with single_threaded_math():
        return meter.measure(meter.model.rest_bodies(params))


def read_population(path: str | os.PathLike) -> pd.DataFrame:
    """Read and validate a population table written by ``wbsa population``.

    Tables without the local-change columns (written before they existed) get them as 0,
    which rebuilds the same bodies; tables without the NHANES limb measures are read without them.

    Raises
    ------
    WbsaError
        If the file is missing, corrupt, or not a population table.
    """
    df = read_table(path, required=POPULATION_COLUMNS, what="population table")
    if df["subject_id"].duplicated().any():
        from wbsa.errors import WbsaError

        raise WbsaError(f"{path} has duplicate subject_id values; regenerate it with wbsa population")
    df["subject_id"] = df["subject_id"].astype(np.int64)
    for name in ALL_LOCAL_CHANGE_COLUMNS:
        if name not in df.columns:
            df[name] = 0.0
    return df
