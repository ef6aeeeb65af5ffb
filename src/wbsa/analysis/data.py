"""Select and join the analysis inputs: population (one row per subject) and scan (subject × view)."""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import pandas as pd

from wbsa.camera.views import PAPER_DISTANCE_M
from wbsa.errors import WbsaError

#: Columns of the scan table that identify a view, in table order.
VIEW_KEYS: tuple[str, ...] = ("camera", "distance_m", "azimuth_deg", "elevation_deg")

#: The columns of a population table (:data:`wbsa.bodies.table.POPULATION_COLUMNS`) that the fit always reads.
REQUIRED_POPULATION_COLUMNS: tuple[str, ...] = ("subject_id", "sex", "age_years", "stature_m", "mass_kg", "bmi", "wbsa_m2")

#: Scan columns the analysis always needs (besides the VBSA columns).
SCAN_COLUMNS: tuple[str, ...] = ("subject_id", "azimuth_deg", "elevation_deg", "distance_m", "camera", "fits_in_frame")

#: Short predictor names accepted on the command line.
PREDICTOR_ALIASES: dict[str, str] = {
    "stature": "stature_m",
    "height": "stature_m",
    "mass": "mass_kg",
    "weight": "mass_kg",
    "age": "age_years",
    "sex": "sex_male",
}

_BASE_VBSA = ("vbsa_hit_m2", "vbsa_visible_m2")
_RECON_RE = re.compile(r"vbsa_recon_[a-z0-9_]+_m2")


def resolve_vbsa_column(spec: str) -> str:
    """Column name of a VBSA selector.

    ``vbsa_hit_m2`` and ``vbsa_visible_m2`` name themselves; ``vbsa_recon_m2:<method>`` names
    ``vbsa_recon_<method>_m2`` with '-' turned into '_' (e.g. ``vbsa_recon_m2:ball-pivoting`` ->
    ``vbsa_recon_ball_pivoting_m2``); a full ``vbsa_recon_<method>_m2`` name is accepted as is.
    """
    spec = spec.strip()
    if spec.startswith("vbsa_recon_m2:"):
        method = spec.split(":", 1)[1].strip().lower().replace("-", "_")
        if not re.fullmatch(r"[a-z0-9_]+", method):
            raise WbsaError(f"bad VBSA selector {spec!r}; write vbsa_recon_m2:<method>, e.g. vbsa_recon_m2:grid")
        return f"vbsa_recon_{method}_m2"
    if spec in _BASE_VBSA or _RECON_RE.fullmatch(spec):
        return spec
    raise WbsaError(f"unknown VBSA column {spec!r}; use vbsa_hit_m2, vbsa_visible_m2 or vbsa_recon_m2:<method>")


def resolve_predictor(name: str, population_columns: list[str] | tuple[str, ...] | pd.Index) -> str:
    """Population column of a predictor name (aliases: stature, mass, age, sex -> ``sex_male``)."""
    name = name.strip()
    col = PREDICTOR_ALIASES.get(name, name)
    if col == "sex_male" and "sex" in population_columns:
        return col
    if col in ("subject_id", "wbsa_m2") or col.startswith("vbsa"):
        raise WbsaError(f"{name!r} cannot be an extra predictor; give anthropometric columns such as stature_m")
    if col not in population_columns:
        raise WbsaError(f"predictor {name!r} is not a population column; choose e.g. stature, mass_kg, "
                        "waist_circ_m, hip_circ_m (any numeric column of the population table)")
    return col


def predictor_values(population: pd.DataFrame, col: str) -> np.ndarray:
    """(n,) float64 values of predictor ``col`` (``sex_male`` is 1.0 for males, 0.0 for females)."""
    if col == "sex_male":
        sex = population["sex"].astype("string").str.lower()
        return np.where(sex.isna(), np.nan, (sex == "male").astype(float))
    values = population[col]
    if not pd.api.types.is_numeric_dtype(values):
        raise WbsaError(f"predictor {col!r} is not numeric; choose a numeric population column")
    return values.to_numpy(dtype=float)


@dataclass(frozen=True)
class Joined:
    """The population joined onto the scan rows.

    Attributes
    ----------
    table : DataFrame
        One row per (subject, view): ``subject_id``, :data:`VIEW_KEYS`, ``wbsa_m2``, the VBSA columns
        (NaN where the body does not fit in the frame and ``require_in_frame``), the predictor columns.
    n_out_of_frame : int
        Scan rows whose body is cut by the image border.
    n_subjects_not_scanned : int
        Population subjects without any scan row.
    """

    table: pd.DataFrame
    n_out_of_frame: int
    n_subjects_not_scanned: int


def join_tables(population: pd.DataFrame, scan: pd.DataFrame, vbsa_columns: tuple[str, ...],
                predictors: tuple[str, ...] = (), require_in_frame: bool = True) -> Joined:
    """Join the population's WBSA and predictors onto the scan rows.

    Raises
    ------
    WbsaError
        Missing columns, duplicate subjects or (subject, view) rows, or scan subjects absent from the population.
    """
    for what, df, need in (("population", population, REQUIRED_POPULATION_COLUMNS),
                           ("scan", scan, SCAN_COLUMNS + vbsa_columns)):
        missing = [c for c in need if c not in df.columns]
        if missing:
            hint = ""
            if what == "scan" and any(c.startswith("vbsa") for c in missing):
                have = [c for c in df.columns if c.startswith("vbsa")]
                hint = f" (it has {', '.join(have) or 'no VBSA column'})"
            raise WbsaError(f"{what} table lacks column(s) {', '.join(missing)}{hint}; check the file and the VBSA column")
    if population["subject_id"].duplicated().any():
        raise WbsaError("population table has duplicate subject_id values; regenerate it with wbsa population")
    if scan.duplicated(["subject_id", *VIEW_KEYS]).any():
        raise WbsaError("scan table has several rows for one subject and view; "
                        "fit scans of different settings separately")
    unknown = ~scan["subject_id"].isin(population["subject_id"])
    if unknown.any():
        raise WbsaError(f"{int(unknown.sum())} scan rows name subjects missing from the population table; "
                        "pass the population the scan was made from")

    pop = pd.DataFrame({"subject_id": population["subject_id"].to_numpy(),
                        "wbsa_m2": population["wbsa_m2"].to_numpy(dtype=float)})
    for col in predictors:
        pop[col] = predictor_values(population, col)
    table = scan[["subject_id", *VIEW_KEYS, *vbsa_columns]].copy()
    table["camera"] = table["camera"].astype(str)
    in_frame = scan["fits_in_frame"].fillna(False).to_numpy(dtype=bool)
    if require_in_frame:
        for col in vbsa_columns:
            table.loc[~in_frame, col] = np.nan
    table = table.merge(pop, on="subject_id", how="left", validate="many_to_one")
    n_not_scanned = int((~population["subject_id"].isin(scan["subject_id"])).sum())
    return Joined(table=table, n_out_of_frame=int((~in_frame).sum()), n_subjects_not_scanned=n_not_scanned)


def reference_distance(distances_m) -> float:
    """The listed camera distance nearest to the paper's 4.3 m (ties: the nearer camera)."""
    return float(min(distances_m, key=lambda d: (abs(d - PAPER_DISTANCE_M), d)))


def nearest_view(df: pd.DataFrame, azimuth_deg: float, elevation_deg: float) -> tuple[float, float]:
    """The (azimuth, elevation) of ``df`` nearest to the asked one (angular distance on the sphere)."""
    views = df[["azimuth_deg", "elevation_deg"]].drop_duplicates().to_numpy(float)
    if len(views) == 0:
        raise WbsaError("no views in the table")
    a, e = np.radians(views[:, 0]), np.radians(views[:, 1])
    a0, e0 = np.radians(azimuth_deg), np.radians(elevation_deg)
    cos = np.sin(e) * np.sin(e0) + np.cos(e) * np.cos(e0) * np.cos(a - a0)
    best = views[int(np.argmax(cos))]
    return float(best[0]), float(best[1])
