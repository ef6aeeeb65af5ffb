"""Read every table a report shows into one record (population, scan, and the fit outputs)."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from wbsa.analysis.data import nearest_view, reference_distance, resolve_vbsa_column  # noqa: F401 (re-export)
from wbsa.camera.views import PAPER_DISTANCE_M
from wbsa.errors import WbsaError
from wbsa.io import read_table
from wbsa.report.sources import FIT_INFO, ReportSources

#: The paper's camera distance: the per-view figures use the fitted distance nearest to it.

_FIT_KEYS = ("group", "model", "predictors", "vbsa_column", "camera", "distance_m", "azimuth_deg", "elevation_deg")


@dataclass
class ReportData:
    """The tables of one report.

    Attributes
    ----------
    population : DataFrame
        One row per subject.
    scan : DataFrame
        One row per subject × view (every distance).
    fits : DataFrame
        The per-view fit table (``fits.parquet``).
    residuals, qq, subgroup_cv, formulae, correlation, model_summary, skipped : DataFrame
        The other fit outputs (empty when a file is absent).
    fit_info : dict
        ``fit_info.json`` (settings, counts, run time).
    sources : ReportSources
    model : str
        Model kind of the figures (the first one fitted).
    vbsa_column : str
        VBSA column of the figures (the first one fitted).
    camera : str
        Camera of the figures (the first one).
    distance_m : float
        Camera distance of the per-view figures (nearest to 4.3 m).
    """

    population: pd.DataFrame
    scan: pd.DataFrame
    fits: pd.DataFrame
    residuals: pd.DataFrame
    qq: pd.DataFrame
    subgroup_cv: pd.DataFrame
    formulae: pd.DataFrame
    correlation: pd.DataFrame
    model_summary: pd.DataFrame
    skipped: pd.DataFrame
    fit_info: dict
    sources: ReportSources
    model: str = "linear"
    vbsa_column: str = "vbsa_visible_m2"
    camera: str = ""
    distance_m: float = PAPER_DISTANCE_M
    distances_m: tuple[float, ...] = field(default_factory=tuple)

    @property
    def groups(self) -> list[str]:
        """Groups with fits, in fit-table order."""
        return list(dict.fromkeys(self.fits["group"].astype(str)))

    @property
    def predictor_labels(self) -> list[str]:
        """Predictor-set labels with fits (``vbsa``, ``vbsa+stature_m``, ...), VBSA only first."""
        labels = list(dict.fromkeys(self.fits["predictors"].astype(str)))
        return sorted(labels, key=lambda s: (s != "vbsa", s))

    @property
    def vbsa_columns(self) -> list[str]:
        """VBSA columns with fits."""
        return list(dict.fromkeys(self.fits["vbsa_column"].astype(str)))


def _optional(path: Path) -> pd.DataFrame:
    if not path.is_file():
        return pd.DataFrame()
    try:
        return pd.read_csv(path) if path.suffix == ".csv" else pd.read_parquet(path)
    except Exception as exc:  # pyarrow / pandas raise many types for corrupt files
        raise WbsaError(f"{path} is unreadable ({type(exc).__name__}); run wbsa fit again") from None


def _strings(df: pd.DataFrame) -> pd.DataFrame:
    """Key columns as plain strings (the fit outputs store some as categories)."""
    for c in ("group", "model", "predictors", "vbsa_column", "camera", "fit_group", "kind", "method", "label", "view"):
        if c in df.columns:
            df[c] = df[c].astype(object).where(df[c].notna(), None)
            df[c] = df[c].map(lambda v: v if v is None else str(v))
    return df


def _checked_fit_info(info: object, path: Path) -> dict:
    """``fit_info.json`` with the parts a report reads checked (it may have been edited by hand)."""
    fix = "run wbsa fit again to rewrite it"
    if not isinstance(info, dict):
        raise WbsaError(f"{path} is not a JSON object; {fix}")
    settings = info.get("settings", {})
    if not isinstance(settings, dict):
        raise WbsaError(f"{path}: 'settings' is not an object; {fix}")
    if not isinstance(settings.get("models", []), list):
        raise WbsaError(f"{path}: settings 'models' is not a list; {fix}")
    spec = settings.get("group_spec") or {}
    if spec:
        from wbsa.analysis.groups import GroupSpec

        try:
            GroupSpec(**spec)
        except (TypeError, ValueError, WbsaError) as exc:
            raise WbsaError(f"{path}: settings 'group_spec' is not valid ({str(exc).splitlines()[0]}); {fix}") from None
    return info


def load_report_data(sources: ReportSources) -> ReportData:
    """Read the population, the scans and the fit outputs named by ``sources``.

    Raises
    ------
    WbsaError
        A missing or unreadable table, or a fit table without rows.
    """
    fit_dir = sources.fit_dir
    try:
        info = json.loads((fit_dir / FIT_INFO).read_text())
    except (OSError, ValueError):
        info = {}
    info = _checked_fit_info(info, fit_dir / FIT_INFO)
    population = read_table(sources.population_path, ("subject_id", "sex", "age_years", "stature_m", "mass_kg",
                                                      "wbsa_m2"), what="population")
    scans = [read_table(p, ("subject_id", "azimuth_deg", "elevation_deg", "distance_m", "camera"), what="scan")
             for p in sources.scan_paths]
    scan = pd.concat(scans, ignore_index=True) if len(scans) > 1 else scans[0]
    scan = _strings(scan)
    fits = _strings(read_table(fit_dir / "fits.parquet", _FIT_KEYS + ("c0", "c1", "cv_rmse_m2"), what="fit"))
    if fits.empty:
        raise WbsaError(f"{fit_dir / 'fits.parquet'} has no fitted views (too few subjects?); "
                        "fit more subjects or fewer folds (--k)")
    settings = info.get("settings", {})
    models = [m for m in settings.get("models", []) if m in set(fits["model"])] or list(dict.fromkeys(fits["model"]))
    fitted = list(dict.fromkeys(fits["vbsa_column"]))  # the fit table sorts them by name: use the asked order
    asked = [resolve_vbsa_column(c) for c in settings.get("vbsa_columns", [])]
    vcols = [c for c in asked if c in fitted] or fitted
    cameras = sorted(fits["camera"].unique())
    distances = tuple(sorted(float(d) for d in fits["distance_m"].unique()))
    ref = reference_distance(distances)
    return ReportData(
        population=population,
        scan=scan,
        fits=fits,
        residuals=_strings(_optional(fit_dir / "residuals.parquet")),
        qq=_strings(_optional(fit_dir / "qq.parquet")),
        subgroup_cv=_strings(_optional(fit_dir / "subgroup_cv.parquet")),
        formulae=_strings(_optional(fit_dir / "formulae_comparison.parquet")),
        correlation=_optional(fit_dir / "correlation.csv"),
        model_summary=_strings(_optional(fit_dir / "model_summary.csv")),
        skipped=_strings(_optional(fit_dir / "skipped.csv")),
        fit_info=info,
        sources=sources,
        model=models[0],
        vbsa_column=vcols[0],
        camera=cameras[0],
        distance_m=float(ref),
        distances_m=distances,
    )


def select(df: pd.DataFrame, **keys) -> pd.DataFrame:
    """Rows of ``df`` whose columns equal the given values (floats compared to 1e-6)."""
    mask = np.ones(len(df), dtype=bool)
    for col, value in keys.items():
        if value is None:
            continue
        if isinstance(value, float):
            mask &= np.abs(df[col].to_numpy(float) - value) < 1e-6
        else:
            mask &= (df[col] == value).to_numpy()
    return df[mask]


