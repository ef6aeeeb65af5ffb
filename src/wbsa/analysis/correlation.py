"""Spearman correlation of WBSA, VBSA and the anthropometric measures at one view (paper Table 2)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from wbsa.analysis.data import predictor_values, resolve_vbsa_column
from wbsa.errors import WbsaError

#: Population columns of paper Table 2 (in its order, VBSA inserted after WBSA), plus mass and BMI.
TABLE2_COLUMNS: tuple[str, ...] = ("stature_m", "wbsa_m2", "sex_male", "age_years", "hip_circ_m", "waist_circ_m",
                                   "bust_circ_m", "underbust_circ_m", "neck_circ_m", "front_chest_width_m",
                                   "mass_kg", "bmi")


def view_rows(scan: pd.DataFrame, azimuth_deg: float, elevation_deg: float, distance_m: float | None = None,
              camera: str | None = None) -> pd.DataFrame:
    """The scan rows of one view (azimuth compared modulo 360, to 1e-6 degrees).

    Raises
    ------
    WbsaError
        No such view, or several distances/cameras and none chosen.
    """
    az = np.mod(scan["azimuth_deg"].to_numpy(float), 360.0)
    d_az = np.abs((az - float(azimuth_deg) % 360.0 + 180.0) % 360.0 - 180.0)
    mask = (d_az < 1e-6) & (np.abs(scan["elevation_deg"].to_numpy(float) - float(elevation_deg)) < 1e-6)
    rows = scan[mask]
    if rows.empty:
        views = scan[["azimuth_deg", "elevation_deg"]].drop_duplicates().to_numpy()
        near = views[np.argmin(np.abs(views[:, 0] - azimuth_deg) + np.abs(views[:, 1] - elevation_deg))]
        raise WbsaError(f"the scan has no view at azimuth {azimuth_deg:g}, elevation {elevation_deg:g}; "
                        f"nearest is {near[0]:g},{near[1]:g}")
    for col, want in (("distance_m", distance_m), ("camera", camera)):
        have = sorted(rows[col].unique().tolist())
        if want is None:
            if len(have) > 1:
                raise WbsaError(f"the scan holds several {col} values at this view "
                                f"({', '.join(map(str, have))}); choose one")
        else:
            if col == "distance_m":
                rows = rows[np.isclose(rows[col], want)]
            else:
                rows = rows[rows[col].astype(str) == str(want)]
            if rows.empty:
                raise WbsaError(f"no scan rows with {col} = {want} at this view; "
                                f"available: {', '.join(map(str, have))}")
    return rows


def spearman_matrix(population: pd.DataFrame, scan: pd.DataFrame, vbsa_column: str = "vbsa_visible_m2",
                    azimuth_deg: float = 0.0, elevation_deg: float = 0.0, distance_m: float | None = None,
                    camera: str | None = None, columns: tuple[str, ...] | None = None,
                    require_in_frame: bool = True) -> pd.DataFrame:
    """Spearman's rho between WBSA, VBSA at one view and the anthropometric columns.

    Parameters
    ----------
    population, scan : DataFrame
        Population and scan tables.
    vbsa_column : str
        VBSA selector (see :func:`wbsa.analysis.data.resolve_vbsa_column`).
    azimuth_deg, elevation_deg : float
        The view (paper Table 2: 0, 0).
    distance_m, camera : optional
        Needed if the scan holds several.
    columns : tuple of str, optional
        Population columns (default: those of :data:`TABLE2_COLUMNS` present; ``sex_male`` is 1 for males).
    require_in_frame : bool
        Leave out subjects whose body does not fit in the frame.

    Returns
    -------
    DataFrame
        Square (m, m) matrix, index and columns the variable names (the VBSA column under its own name),
        pairwise complete observations.
    """
    vcol = resolve_vbsa_column(vbsa_column)
    if vcol not in scan.columns:
        raise WbsaError(f"scan table has no column {vcol}; choose another VBSA column")
    rows = view_rows(scan, azimuth_deg, elevation_deg, distance_m, camera)
    if require_in_frame and "fits_in_frame" in rows.columns:
        rows = rows[rows["fits_in_frame"].fillna(False).astype(bool)]
    if columns is None:
        columns = tuple(c for c in TABLE2_COLUMNS
                        if c in population.columns or (c == "sex_male" and "sex" in population.columns))
    pop = pd.DataFrame({"subject_id": population["subject_id"].to_numpy()})
    for c in columns:
        if c != "sex_male" and c not in population.columns:
            raise WbsaError(f"population table has no column {c!r} for the correlation matrix")
        pop[c] = predictor_values(population, c)
    data = rows[["subject_id", vcol]].merge(pop, on="subject_id", how="inner").drop(columns="subject_id")
    if len(data) < 3:
        raise WbsaError(f"only {len(data)} subjects at this view; need at least 3 for a correlation")
    order = list(columns)
    order.insert(order.index("wbsa_m2") + 1 if "wbsa_m2" in order else 0, vcol)
    return data[order].corr(method="spearman")


def correlation_table(matrix: pd.DataFrame, view: tuple[float, float], vbsa_column: str,
                      distance_m: float | None = None, camera: str | None = None) -> pd.DataFrame:
    """The matrix as a flat table for files: ``variable``, the view (``azimuth_deg``, ``elevation_deg``,
    ``distance_m``, ``camera``), ``vbsa_column``, then one column per variable."""
    out = matrix.reset_index(names="variable")
    for i, (name, value) in enumerate((("azimuth_deg", float(view[0])), ("elevation_deg", float(view[1])),
                                       ("distance_m", distance_m), ("camera", camera), ("vbsa_column", vbsa_column))):
        out.insert(1 + i, name, value)
    return out
