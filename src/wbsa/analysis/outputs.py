"""Run the whole analysis on two table files and write every output table (``wbsa fit`` without argparse)."""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pandas as pd

from wbsa.analysis.correlation import correlation_table, spearman_matrix
from wbsa.analysis.data import (REQUIRED_POPULATION_COLUMNS, SCAN_COLUMNS, nearest_view, reference_distance,
                                resolve_vbsa_column)
from wbsa.analysis.fit_views import FitOutput, FitSettings, fit_all
from wbsa.analysis.formulae_comparison import compare_formulae
from wbsa.analysis.groups import COMPARISON_GROUPS
from wbsa.analysis.summary import model_comparison, model_summary
from wbsa.errors import WbsaError
from wbsa.io import read_table, relative_path, staged_files, write_json, write_sheets, write_table

#: Output files of :func:`run_fit`, by key (relative to the output folder).
OUTPUT_FILES: dict[str, str] = {
    "fits_parquet": "fits.parquet",
    "fits_csv": "fits.csv",
    "fits_xlsx": "fits.xlsx",
    "skipped": "skipped.csv",
    "residuals": "residuals.parquet",
    "qq": "qq.parquet",
    "subgroup_cv": "subgroup_cv.parquet",
    "model_comparison": "model_comparison.csv",
    "model_summary": "model_summary.csv",
    "model": "model.json",
    "correlation_csv": "correlation.csv",
    "correlation_xlsx": "correlation.xlsx",
    "formulae_parquet": "formulae_comparison.parquet",
    "formulae_csv": "formulae_comparison.csv",
    "formulae_xlsx": "formulae_comparison.xlsx",
    "run_log": "run_log.json",
    "info": "fit_info.json",
}
#: The marker of a complete fit folder: written last; readers require it (:func:`wbsa.atomic.staged_files`).
MARKER = OUTPUT_FILES["info"]


def read_inputs(population_path: str | os.PathLike, scan_path: str | os.PathLike,
                vbsa_columns: tuple[str, ...]) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Read and check the population and scan tables (Parquet or CSV)."""
    population = read_table(population_path, REQUIRED_POPULATION_COLUMNS, what="population")
    cols = tuple(resolve_vbsa_column(c) for c in vbsa_columns)
    scan = read_table(scan_path, SCAN_COLUMNS + cols, what="scan")
    return population, scan


def _sheets(df: pd.DataFrame, order: tuple[str, ...]) -> dict[str, pd.DataFrame]:
    groups = [g for g in order if g in set(df["group"].astype(str))] if len(df) else []
    if not groups:
        return {"empty": df}
    return {g: df[df["group"].astype(str) == g] for g in groups}


def write_outputs(out: FitOutput, population: pd.DataFrame, scan: pd.DataFrame, out_dir: str | os.PathLike,
                  settings: FitSettings, correlation: pd.DataFrame, inputs: dict | None = None) -> dict[str, Path]:
    """Write the fit results, the formulae comparison and the correlation table into ``out_dir``.

    ``inputs`` (e.g. ``{"population": path, "scan": path}``) is recorded in ``fit_info.json`` (relative
    to ``out_dir``) so a report can find the tables the fit came from. The files are written into a
    staging folder and moved into ``out_dir`` together, ``fit_info.json`` last
    (:func:`wbsa.atomic.staged_files`): a refit that fails part-way leaves the previous outputs as they
    were, and a folder without ``fit_info.json`` is not a finished fit. The run time goes to
    ``run_log.json``, so the other files depend only on the inputs and the settings.

    Returns
    -------
    dict
        Output key (:data:`OUTPUT_FILES`) -> path written.
    """
    out_dir = Path(out_dir)
    with staged_files(out_dir, MARKER) as stage:
        _write_all(out, population, stage, settings, correlation, inputs or {}, out_dir)
    return {k: out_dir / v for k, v in OUTPUT_FILES.items()}


def _write_all(out: FitOutput, population: pd.DataFrame, stage: Path, settings: FitSettings,
               correlation: pd.DataFrame, inputs: dict, out_dir: Path) -> None:
    p = {k: stage / v for k, v in OUTPUT_FILES.items()}
    fits = out.fits
    write_table(fits, p["fits_parquet"])
    write_table(fits, p["fits_csv"])
    write_sheets(_sheets(fits, settings.groups), p["fits_xlsx"])
    write_table(out.skipped, p["skipped"])
    write_table(out.residuals, p["residuals"])
    write_table(out.qq, p["qq"])
    write_table(out.subgroup_cv, p["subgroup_cv"])
    # the all-subjects model evaluated within the other groups; within "all" it is the group fit itself, whose
    # rows (with the Breusch-Pagan counts) come first, so "all" is not repeated
    sub = out.subgroup_cv[out.subgroup_cv["group"].astype(str) != "all"] if len(out.subgroup_cv) else out.subgroup_cv
    write_table(pd.concat([model_comparison(fits).assign(fit_group=lambda d: d["group"]),
                           model_comparison(sub).assign(fit_group="all")], ignore_index=True),
                p["model_comparison"])
    write_table(pd.concat([model_summary(fits).assign(fit_group=lambda d: d["group"]),
                           model_summary(sub).assign(fit_group="all")], ignore_index=True),
                p["model_summary"])
    out.model.save(p["model"])
    write_table(correlation, p["correlation_csv"])
    write_sheets({"spearman": correlation}, p["correlation_xlsx"])
    comparison = compare_formulae(population, fits, out.subgroup_cv, settings.group_spec, COMPARISON_GROUPS)
    write_table(comparison, p["formulae_parquet"])
    write_table(comparison, p["formulae_csv"])
    write_sheets(_sheets(comparison, COMPARISON_GROUPS), p["formulae_xlsx"])
    write_json({"seconds": out.info.get("seconds"), "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z")},
               p["run_log"])
    write_json({"settings": settings.to_dict(), "info": {k: v for k, v in out.info.items() if k != "seconds"},
                "files": {k: v.name for k, v in p.items()},
                "inputs": {k: relative_path(v, out_dir) for k, v in inputs.items()}}, p["info"])



def run_fit(population_path: str | os.PathLike, scan_path: str | os.PathLike, out_dir: str | os.PathLike,
            settings: FitSettings = FitSettings(), show_progress: bool | None = None,
            nearest_correlation_view: bool = False
            ) -> tuple[FitOutput, dict[str, Path]]:
    """Read the tables, fit every view, write every output; the API behind ``wbsa fit``.

    The correlation matrix (paper Table 2, Spearman) is computed first with the first VBSA column,
    at the scanned distance nearest the paper's 4.3 m and at ``settings.correlation_view_deg`` (an unscanned view
    is an error, found before the long fit, unless ``nearest_correlation_view`` picks the nearest scanned one).
    """
    correlation_view = tuple(float(a) for a in settings.correlation_view_deg)
    population, scan = read_inputs(population_path, scan_path, settings.vbsa_columns)
    vcol = resolve_vbsa_column(settings.vbsa_columns[0])
    distance = reference_distance(scan["distance_m"].unique().tolist())
    camera = _single(scan, "camera")
    if nearest_correlation_view:
        correlation_view = nearest_view(scan[np.isclose(scan["distance_m"], distance)], *correlation_view)
    matrix = spearman_matrix(population, scan, vcol, *correlation_view, require_in_frame=settings.require_in_frame,
                             distance_m=distance, camera=camera)
    correlation = correlation_table(matrix, correlation_view, vcol, distance, camera)
    out = fit_all(population, scan, settings, show_progress=show_progress)
    if out.fits.empty:
        reason = out.skipped["reason"].iloc[0] if len(out.skipped) else "no scan rows"
        raise WbsaError(f"no model could be fitted ({len(out.skipped)} combinations skipped, e.g. {reason}); "
                        "lower k, include more subjects or check the VBSA column")
    paths = write_outputs(out, population, scan, out_dir, settings, correlation,
                          inputs={"population": population_path, "scan": scan_path})
    return out, paths


def _single(scan: pd.DataFrame, col: str):
    """The first value of ``col`` in sorted order (the correlation uses one camera and distance)."""
    return sorted(scan[col].unique().tolist())[0]
