"""Build the report: every figure and table of a study (or a fit folder) in one self-contained HTML file."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from wbsa import __version__
from wbsa.errors import WbsaError
from wbsa.io import write_text
from wbsa.progress import progress
from wbsa.report import figures as F
from wbsa.report.data import ReportData, load_report_data, select
from wbsa.report.html import Page, png_bytes
from wbsa.report.sources import ReportSources, resolve_sources
from wbsa.study.settings import ReportConfig, section_from_table

#: Figures of the report in order: id -> what it reproduces.
FIGURES: dict[str, str] = {
    "fig-wbsa-distribution": "paper Fig 5",
    "fig-vbsa-wbsa": "paper Fig 10 and S1 Fig",
    "fig-view-<group>": "paper Figs 11, 13, 14",
    "fig-group-errors": "paper Fig 12",
    "fig-models": "paper section 4.2",
    "fig-nonlinear": "paper Fig 16",
    "fig-residuals": "paper S2 Fig",
    "fig-snapshots": "paper Fig 8",
    "fig-reconstruction": "paper Figs 15 and 17",
    "fig-distance": "paper section 3.4",
    "fig-formulae": "formulae comparison",
}


@dataclass
class ReportResult:
    """What :func:`build_report` wrote.

    Attributes
    ----------
    path : Path
        The HTML file.
    figures : list of str
        Ids of the figures drawn (``fig-...``), in page order.
    tables : list of str
        Ids of the tables (``tab-...``).
    unavailable : dict
        Figure id -> why it was not drawn (data absent from the study).
    seconds : float
    """

    path: Path
    figures: list[str] = field(default_factory=list)
    tables: list[str] = field(default_factory=list)
    unavailable: dict[str, str] = field(default_factory=dict)
    seconds: float = 0.0


def report_settings_of(sources: ReportSources) -> ReportConfig:
    """The ``[report]`` settings recorded in the study's manifest, or the defaults."""
    table = sources.manifest.get("settings", {}).get("report")
    if not table:
        return ReportConfig()
    return section_from_table(ReportConfig, table, "report", str(sources.study_dir or sources.fit_dir))


def build_report(sources: ReportSources | str | os.PathLike, out: str | os.PathLike,
                 settings: ReportConfig | None = None, *, show_progress: bool | None = None) -> ReportResult:
    """Draw every figure, lay out every table and write one HTML file.

    Parameters
    ----------
    sources : ReportSources or path
        The inputs, or a study / fit folder (see :func:`wbsa.report.sources.resolve_sources`).
    out : path
        The HTML file to write (atomically).
    settings : ReportConfig, optional
        Views of the single-view figures; default: the study's ``[report]`` settings.
    show_progress : bool, optional
        Progress bar over the figures.

    Returns
    -------
    ReportResult
    """
    t0 = time.perf_counter()
    if not isinstance(sources, ReportSources):
        sources = resolve_sources(sources)
    settings = settings or report_settings_of(sources)
    data = load_report_data(sources)
    out = Path(out)
    if out.suffix.lower() not in (".html", ".htm"):
        raise WbsaError(f"report file {out} must end in .html")

    builder = _Builder(data, settings)
    steps = builder.steps()
    bar = progress(total=len(steps), desc="report", unit="part", enabled=show_progress)
    for step in steps:
        step()
        bar.update(1)
    bar.close()
    seconds = time.perf_counter() - t0
    page = builder.page
    page.paragraph(f"Report built in {seconds:.1f} s.")
    write_text(page.render(), out)
    return ReportResult(path=out, figures=list(page.figures), tables=list(page.tables),
                        unavailable=dict(builder.unavailable), seconds=seconds)


class _Builder:
    """Fills a :class:`Page` section by section from a :class:`ReportData`."""

    def __init__(self, data: ReportData, settings: ReportConfig) -> None:
        self.d = data
        self.s = settings
        self.dpi = int(settings.dpi)
        self.unavailable: dict[str, str] = {}
        manifest = data.sources.manifest
        title = str(manifest.get("study", {}).get("name") or f"wbsa report: {data.sources.fit_dir}")
        self.page = Page(title=title, subtitle=(
            f"Generated {time.strftime('%Y-%m-%d %H:%M')} by wbsa {__version__} from "
            f"{data.sources.study_dir or data.sources.fit_dir}. Areas in figures are in dm² (1 m² = 100 dm², the "
            "paper's unit); tables are in SI units (m²)."))

    # -- helpers -------------------------------------------------------------------------------------------------

    def _figure(self, fig_id: str, what: str, draw: Callable, caption: str) -> None:
        try:
            fig = draw()
        except F.FigureUnavailable as exc:
            self.unavailable[fig_id] = str(exc)
            self.page.unavailable(fig_id, what, str(exc))
            return
        self.page.figure(fig_id, png_bytes(fig, self.dpi), caption)

    @property
    def common(self) -> dict:
        d = self.d
        return dict(distance_m=d.distance_m, camera=d.camera, dpi=self.dpi)

    def steps(self) -> list[Callable[[], None]]:
        steps = [self.summary, self.population, self.scatter]
        steps += [lambda g=g: self.view_figure(g) for g in self.d.groups]
        steps += [self.groups, self.nonlinear, self.residuals, self.snapshots, self.reconstruction, self.distance,
                  self.formulae, self.fit_table, self.run_info]
        return steps

    # -- sections ------------------------------------------------------------------------------------------------

    def summary(self) -> None:
        d, p = self.d, self.page
        p.section("summary", "Summary")
        fits = select(d.fits, group="all", model=d.model, vbsa_column=d.vbsa_column, distance_m=d.distance_m,
                      camera=d.camera)
        rows = [
            ("subjects", f"{len(d.population)}"),
            ("scan rows (subject × view)", f"{len(d.scan)}"),
            ("views per distance", f"{len(select(d.scan, distance_m=d.distance_m)[['azimuth_deg', 'elevation_deg']].drop_duplicates())}"),
            ("camera distances (m)", ", ".join(f"{x:g}" for x in d.distances_m)),
            ("camera", d.camera),
            ("VBSA column of the figures", d.vbsa_column),
            ("model of the figures", d.model),
            ("cross-validation folds k", str(d.fit_info.get("settings", {}).get("k", ""))),
            ("groups fitted", ", ".join(d.groups)),
            ("mean WBSA (m²)", f"{d.population['wbsa_m2'].mean():.4f}"),
        ]
        for lab in d.predictor_labels:
            part = fits[fits["predictors"] == lab]
            if part.empty:
                continue
            best, worst = part.loc[part["cv_rmse_m2"].idxmin()], part.loc[part["cv_rmse_m2"].idxmax()]
            rows.append((f"all subjects, {F.predictors_title(lab)}: CV RMSE (m²), best view",
                         f"{best['cv_rmse_m2']:.4f} at θ = {best['azimuth_deg']:g}°, φ = {best['elevation_deg']:g}°"))
            rows.append((f"all subjects, {F.predictors_title(lab)}: CV RMSE (m²), worst view",
                         f"{worst['cv_rmse_m2']:.4f} at θ = {worst['azimuth_deg']:g}°, φ = {worst['elevation_deg']:g}°"))
        rows.append(("paper (Virtual Random, 19,995 subjects)",
                     "CV RMSE 0.0071–0.055 m² (0.71–5.5 dm²) over the views; mean WBSA 1.67 m²"))
        p.table("tab-summary", pd.DataFrame(rows, columns=["quantity", "value"]),
                "Key numbers of this study (all-subjects fits at the reference distance).")

    def population(self) -> None:
        d, p = self.d, self.page
        p.section("population", "Population",
                  "The virtual population the study scanned; WBSA is the area of each body's skin mesh.")
        self._figure("fig-wbsa-distribution", "WBSA distribution", lambda: F.wbsa_distribution(d.population, self.dpi),
                     "Distribution of WBSA, stacked by sex (left), and WBSA against stature coloured by BMI (right) "
                     "(paper Fig 5).")
        p.table("tab-population", population_table(d.population, d.fit_info),
                "Composition of the population by group (paper Table 1): counts, WBSA and stature.")

    def scatter(self) -> None:
        d, p = self.d, self.page
        p.section("vbsa-wbsa", "VBSA and WBSA")
        self._figure("fig-vbsa-wbsa", "VBSA–WBSA scatter",
                     lambda: F.vbsa_wbsa_scatter(d.population, d.scan, d.fits, view=tuple(self.s.scatter_view_deg),
                                                 vbsa_column=d.vbsa_column, model=d.model, **self.common),
                     "View body surface area against whole body surface area at one view with the all-subjects fit "
                     "(paper Fig 10 and S1 Fig).")
        if not d.correlation.empty:
            corr = d.correlation.drop(columns=[c for c in ("azimuth_deg", "elevation_deg", "distance_m", "camera",
                                                           "vbsa_column") if c in d.correlation.columns])
            c0 = d.correlation.iloc[0]
            p.table("tab-correlation", corr, f"Spearman correlation of WBSA, VBSA ({c0.get('vbsa_column', '')}) and "
                    f"the body measures at θ = {c0.get('azimuth_deg', 0):g}°, φ = {c0.get('elevation_deg', 0):g}° "
                    "(paper Table 2).", digits=3)
        p.section("orientation", "Camera orientation",
                  "The VBSA coefficient c1 and the cross-validated RMSE of the WBSA prediction against the camera "
                  "azimuth, one line per elevation; the poles (φ = ±90°) are single markers at θ = 0.")

    def view_figure(self, group: str) -> None:
        d = self.d
        self._figure(f"fig-view-{group}", f"coefficients by view, {group}",
                     lambda: F.coefficients_by_view(d.fits, group=group, model=d.model, vbsa_column=d.vbsa_column,
                                                    predictor_labels=d.predictor_labels, **self.common),
                     f"{F.GROUP_LABELS.get(group, group).capitalize()}: CV RMSE (left) and VBSA coefficient c1 "
                     "(right) against azimuth, without and with stature (paper Figs 11, 13, 14).")

    def groups(self) -> None:
        d, p = self.d, self.page
        p.section("groups", "Groups")
        self._figure("fig-group-errors", "errors by group",
                     lambda: F.group_errors(d.fits, model=d.model, vbsa_column=d.vbsa_column,
                                            predictor_labels=d.predictor_labels, **self.common),
                     "CV RMSE of the WBSA prediction at elevation 0 for every group fitted on its own, without and "
                     "with stature (paper Fig 12).")
        p.table("tab-groups", group_table(d), "CV RMSE (m²) over all views per group and predictor set.")
        sk = d.skipped
        if not sk.empty and {"group", "reason"} <= set(sk.columns):
            fitted = set(d.groups)
            notes = [f"{g}: {part['reason'].iloc[0]}" for g, part in sk.groupby("group", sort=False)
                     if g not in fitted]
            if notes:
                p.paragraph("Groups too small to fit at any view (rows < k + number of coefficients): "
                            + "; ".join(notes) + ".")

    def nonlinear(self) -> None:
        d, p = self.d, self.page
        p.section("nonlinear", "Non-linearity and alternative models")
        self._figure("fig-nonlinear", "non-linear view",
                     lambda: F.nonlinear_view(d.population, d.scan, d.fits, view=tuple(self.s.nonlinear_view_deg),
                                              vbsa_column=d.vbsa_column, **self.common),
                     "The VBSA–WBSA relation at an occluded view with the linear and power-law fits, and the linear "
                     "fit's residuals against WBSA (paper Fig 16).")
        self._figure("fig-models", "model comparison",
                     lambda: F.model_comparison(d.fits, vbsa_column=d.vbsa_column, **self.common),
                     "Cross-validated RMSE of every model kind at elevation 0 (left) and its ratio to the first "
                     "model at every view (right).")
        if not d.model_summary.empty:
            ms = d.model_summary
            if "fit_group" in ms:
                ms = ms[ms["fit_group"] == ms["group"]]
            ms = ms[(ms["group"] == "all") & (ms["vbsa_column"] == d.vbsa_column)]
            ms = select(ms, distance_m=d.distance_m) if "distance_m" in ms else ms
            cols = [c for c in ("predictors", "model", "n_views", "mean_cv_rmse_m2", "max_cv_rmse_m2",
                                "mean_cv_mape_pct", "rmse_ratio", "views_better", "heteroscedastic_views")
                    if c in ms.columns]
            p.table("tab-models", ms[cols], "Model kinds over all views, all subjects: mean and worst CV RMSE, "
                    "ratio to the linear model, views where it is better, views with Breusch–Pagan p < 0.05.")

    def residuals(self) -> None:
        d, p = self.d, self.page
        p.section("residuals", "Residual analysis")
        self._figure("fig-residuals", "residual analysis",
                     lambda: F.residual_diagnostics(d.residuals, d.qq, view=tuple(self.s.scatter_view_deg),
                                                    model=d.model, vbsa_column=d.vbsa_column, **self.common),
                     "Residuals of the all-subjects VBSA-only fit: (a) normal QQ plot, (b) residuals against fitted "
                     "values, (c) histogram, (d) scale–location (paper S2 Fig).")

    def snapshots(self) -> None:
        d, p = self.d, self.page
        p.section("point-clouds", "Point clouds")
        self._figure("fig-snapshots", "point-cloud snapshots", self._draw_snapshots,
                     "What one camera sees of one subject: its depth image and its point cloud looked at from four "
                     "sides; grey is the skin the camera misses (paper Fig 8).")

    def _draw_snapshots(self):
        from wbsa.report.snapshots import pick_subject, render_snapshot, snapshot_intrinsics

        d = self.d
        az, el = (float(x) for x in self.s.snapshot_view_deg)
        missing = [c for c in ("p_gender", "p_age", "p_weight", "p_height") if c not in d.population.columns]
        if missing:
            raise F.FigureUnavailable(f"the population lacks the body parameters ({', '.join(missing)})")
        try:
            intr = snapshot_intrinsics(d.sources.scan_paths, d.camera)
            sid = pick_subject(d.population, int(self.s.snapshot_subject))
            snap = render_snapshot(d.population, sid, intr, az, el, d.distance_m)
        except WbsaError as exc:
            raise F.FigureUnavailable(str(exc)) from None
        return F.point_cloud_snapshots(snap.points_world, snap.depth_m, snap.body_vertices, view=(az, el),
                                       distance_m=d.distance_m, subject_id=sid, camera=d.camera, dpi=self.dpi)

    def reconstruction(self) -> None:
        d, p = self.d, self.page
        p.section("reconstruction", "Surface reconstruction")
        ref = d.vbsa_column if not d.vbsa_column.startswith("vbsa_recon_") else "vbsa_visible_m2"
        self._figure("fig-reconstruction", "reconstruction by view",
                     lambda: F.reconstruction_by_view(d.scan, d.fits, model=d.model, reference_column=ref,
                                                      **self.common),
                     "Reconstructed against ideal view area by azimuth at elevation 0: relative VBSA error, CV RMSE "
                     "and c1 with each VBSA (paper Figs 15 and 17).")

    def distance(self) -> None:
        d, p = self.d, self.page
        p.section("distance", "Camera distance")
        common = {k: v for k, v in self.common.items() if k != "distance_m"}
        self._figure("fig-distance", "camera distance",
                     lambda: F.distance_effect(d.fits, d.scan, model=d.model, vbsa_column=d.vbsa_column, **common),
                     "CV RMSE and c1 against the camera distance at a few views, and the share of bodies inside the "
                     "frame (paper section 3.4).")
        if len(d.distances_m) > 1:
            p.table("tab-distance", distance_table(d), "Per camera distance: bodies inside the frame, subjects "
                    "fitted and CV RMSE (m²) of the all-subjects VBSA-only fit over the views.")

    def formulae(self) -> None:
        d, p = self.d, self.page
        p.section("formulae", "Classical formulae")
        self._figure("fig-formulae", "formulae comparison",
                     lambda: F.formulae_comparison(d.formulae, model=d.model, vbsa_column=d.vbsa_column, **self.common),
                     "MAPE of the classical BSA formulae (height and weight) against the mesh WBSA, beside the "
                     "single-view models' cross-validated MAPE at their best and worst view.")
        if not d.formulae.empty:
            cols = [c for c in ("group", "kind", "label", "azimuth_deg", "elevation_deg", "n", "mape_pct", "bias_pct",
                                "bias_m2", "rmse_m2") if c in d.formulae.columns]
            p.table("tab-formulae", d.formulae[cols], "Formulae and single-view models against the mesh WBSA, per "
                    "group (MAPE in %, bias and RMSE in m²).", scroll=True)

    def fit_table(self) -> None:
        d, p = self.d, self.page
        p.section("fits", "Per-view fits")
        sub = select(d.fits, group="all", model=d.model, vbsa_column=d.vbsa_column, distance_m=d.distance_m,
                     camera=d.camera)
        cols = [c for c in ("predictors", "azimuth_deg", "elevation_deg", "n", "c0", "c1", "c_stature_m", "r2",
                            "rse_m2", "cv_rmse_m2", "cv_mape_pct", "bp_pvalue") if c in sub.columns]
        p.table("tab-fits", sub[cols], f"All subjects, {d.model} model, {d.vbsa_column}, D = {d.distance_m:g} m: "
                "coefficients, R², residual SE and cross-validated errors per view (areas in m²). The full table of "
                "every group, model and distance is fits.parquet / fits.csv.", scroll=True)

    def run_info(self) -> None:
        d, p = self.d, self.page
        p.section("run", "Settings, versions and run time")
        p.table("tab-stages", stage_table(d.sources), "Stages of the study: content address, time to compute, "
                "and whether this run reused them.")
        p.table("tab-settings", settings_table(d.sources, d.fit_info), "Settings.")
        from wbsa.core.versions import package_versions

        versions = d.sources.manifest.get("versions") or package_versions()
        p.table("tab-versions", pd.DataFrame(sorted(versions.items()), columns=["package", "version"]),
                "Software versions.")


# -------------------------------------------------------------------------------------------------------------------
# tables


def population_table(population: pd.DataFrame, fit_info: dict) -> pd.DataFrame:
    """Counts, WBSA (m²) and stature (m) of every group (paper Table 1)."""
    from wbsa.analysis.groups import GROUP_NAMES, GroupSpec, assign_groups

    spec_d = fit_info.get("settings", {}).get("group_spec") or {}
    spec = GroupSpec(**spec_d) if spec_d else GroupSpec()
    members = assign_groups(population.reset_index(drop=True), spec)
    desc = spec.describe()
    rows = []
    w = population["wbsa_m2"].to_numpy(float)
    s = population["stature_m"].to_numpy(float)
    a = population["age_years"].to_numpy(float)
    for g in GROUP_NAMES:
        m = members[g].to_numpy()
        n = int(m.sum())
        rows.append({"group": g, "definition": desc[g], "subjects": n,
                     "wbsa_mean_m2": w[m].mean() if n else np.nan, "wbsa_sd_m2": w[m].std(ddof=1) if n > 1 else np.nan,
                     "wbsa_min_m2": w[m].min() if n else np.nan, "wbsa_max_m2": w[m].max() if n else np.nan,
                     "stature_mean_m": s[m].mean() if n else np.nan,
                     "age_range_years": f"{a[m].min():.0f}–{a[m].max():.0f}" if n else ""})
    return pd.DataFrame(rows)


def group_table(d: ReportData) -> pd.DataFrame:
    """Per group and predictor set: median n and mean / min / max CV RMSE over the views."""
    sub = select(d.fits, model=d.model, vbsa_column=d.vbsa_column, distance_m=d.distance_m, camera=d.camera)
    g = sub.groupby(["group", "predictors"], sort=False).agg(
        views=("cv_rmse_m2", "size"), median_n=("n", "median"), mean_cv_rmse_m2=("cv_rmse_m2", "mean"),
        min_cv_rmse_m2=("cv_rmse_m2", "min"), max_cv_rmse_m2=("cv_rmse_m2", "max"),
        mean_cv_mape_pct=("cv_mape_pct", "mean"))
    return g.reset_index()


def distance_table(d: ReportData) -> pd.DataFrame:
    """Per distance: share of scan rows inside the frame, fitted subjects, CV RMSE over views."""
    rows = []
    fits = select(d.fits, group="all", model=d.model, predictors="vbsa", vbsa_column=d.vbsa_column, camera=d.camera)
    for dist in d.distances_m:
        sc = select(d.scan, distance_m=float(dist), camera=d.camera)
        f = select(fits, distance_m=float(dist))
        rows.append({"distance_m": dist,
                     "in_frame_pct": 100 * sc["fits_in_frame"].mean() if "fits_in_frame" in sc and len(sc) else np.nan,
                     "views": len(f), "median_n": f["n"].median() if len(f) else np.nan,
                     "mean_cv_rmse_m2": f["cv_rmse_m2"].mean() if len(f) else np.nan,
                     "max_cv_rmse_m2": f["cv_rmse_m2"].max() if len(f) else np.nan,
                     "mean_c1": f["c1"].mean() if len(f) else np.nan})
    return pd.DataFrame(rows)


def stage_table(sources: ReportSources) -> pd.DataFrame:
    """Stages with key, time to compute and reuse flag (from the manifest and the stage records)."""
    stages = sources.manifest.get("stages", [])
    if stages:
        rows = [{"stage": s.get("name"), "folder": s.get("path"), "computed_in_s": s.get("seconds_computed"),
                 "this_run_s": s.get("seconds_this_run"), "reused": bool(s.get("reused")),
                 "result": s.get("summary", "")} for s in stages]
        rows.append({"stage": "whole run (before the report)", "folder": "", "computed_in_s": np.nan,
                     "this_run_s": sources.manifest.get("seconds"), "reused": False, "result": ""})
        return pd.DataFrame(rows)
    rows = [{"stage": r.get("label", r.get("stage")), "folder": f"{r.get('stage')}-{r.get('key')}",
             "computed_in_s": r.get("seconds"),
             "result": r["info"].get("summary", "") if isinstance(r.get("info"), dict) else ""}
            for r in sources.stage_records]
    if not rows:
        rows = [{"stage": "fit", "folder": str(sources.fit_dir), "computed_in_s": np.nan, "result": ""}]
    return pd.DataFrame(rows)


def settings_table(sources: ReportSources, fit_info: dict) -> pd.DataFrame:
    """Every setting as (section, key, value)."""
    settings = sources.manifest.get("settings")
    if not settings:
        settings = {"fit": fit_info.get("settings", {})}
    rows = []
    for section, table in settings.items():
        for key, value in (table or {}).items():
            rows.append({"section": section, "key": key, "value": _show(value)})
    for i, p in enumerate(sources.scan_paths):
        rows.append({"section": "inputs", "key": f"scan[{i}]", "value": str(p)})
    rows.append({"section": "inputs", "key": "population", "value": str(sources.population_path)})
    rows.append({"section": "inputs", "key": "fit", "value": str(sources.fit_dir)})
    return pd.DataFrame(rows)


def _show(value) -> str:
    if isinstance(value, dict):
        return ", ".join(f"{k} = {_show(v)}" for k, v in value.items())
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_show(v) for v in value) + "]"
    return str(value)
