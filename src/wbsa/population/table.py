"""Population tables: build the anthropometric table for a set of phenotypes, read it back."""

from __future__ import annotations

import os

import numpy as np
import pandas as pd

from wbsa.io import read_table
from wbsa.population.anthropometry import DEFAULT_DENSITY_KG_M3, MEASURE_COLUMNS, Anthropometer
from wbsa.population.body_model import PHENOTYPE_COLUMNS, BodyModel
from wbsa.progress import progress

#: Columns every population table has.
POPULATION_COLUMNS = ("subject_id", "sex", "age_years", *PHENOTYPE_COLUMNS, *MEASURE_COLUMNS)


def measure_population(params: pd.DataFrame, *, density_kg_m3: float = DEFAULT_DENSITY_KG_M3,
                       model: BodyModel | None = None, batch_size: int = 64,
                       show_progress: bool | None = None) -> pd.DataFrame:
    """Build every body of ``params`` and append its anthropometric measures.

    Parameters
    ----------
    params
        ``subject_id``, ``sex``, ``age_years`` and the ``p_*`` columns (extra columns are kept).
    density_kg_m3
        Body density for mass = volume × density.

    Returns
    -------
    pandas.DataFrame
        ``params`` followed by :data:`~wbsa.population.anthropometry.MEASURE_COLUMNS`.
    """
    model = model or BodyModel(batch_size=batch_size)
    meter = Anthropometer(model, density_kg_m3)
    model.phenotype_array(params)  # validate every row before any work
    parts = []
    with progress(total=len(params), desc="bodies", unit="body", enabled=show_progress) as bar:
        for start in range(0, len(params), batch_size):
            chunk = params.iloc[start:start + batch_size]
            parts.append(meter.measure(model.rest_bodies(chunk)))
            bar.update(len(chunk))
    measures = pd.concat(parts, ignore_index=True) if parts else pd.DataFrame(columns=list(MEASURE_COLUMNS))
    out = params.reset_index(drop=True).copy()
    for name in PHENOTYPE_COLUMNS:
        if name not in out.columns:
            out[name] = 0.5
    return pd.concat([out, measures], axis=1)


def read_population(path: str | os.PathLike) -> pd.DataFrame:
    """Read and validate a population table written by ``wbsa population``.

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
    return df
