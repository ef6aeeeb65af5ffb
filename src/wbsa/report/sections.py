"""The report's sections in page order: each one draws its figures and lays out its tables on a :class:`Page`.

A figure whose data are absent from the study (:class:`~wbsa.report.figures.style.FigureUnavailable`) is
replaced by a note saying why, and the section goes on.
"""

from __future__ import annotations

import time
from typing import Callable

import pandas as pd

from wbsa.core.versions import WBSA_VERSION as __version__
from wbsa.errors import WbsaError
from wbsa.report.claim import comparisons_display, compute_claim, group_spec_of, headline_display, method_text
from wbsa.report.data import ReportData, select
from wbsa.report.figures.by_view import coefficients_by_view, group_errors, model_comparison
from wbsa.report.figures.distance import distance_effect
from wbsa.report.figures.formulae import formulae_comparison
from wbsa.report.figures.one_view import nonlinear_view, vbsa_wbsa_scatter
from wbsa.report.figures.point_cloud import point_cloud_snapshots
from wbsa.report.figures.population import wbsa_distribution
from wbsa.report.figures.reconstruction import reconstruction_by_view
from wbsa.report.figures.residuals import residual_diagnostics
from wbsa.report.figures.style import GROUP_LABELS, FigureUnavailable, predictors_title
from wbsa.report.html import Page, png_bytes
from wbsa.report.settings import ReportSettings
from wbsa.report.tables import distance_table, group_table, population_table, settings_table, stage_table


class SectionBuilder:
    """Fills a :class:`Page` section by section from a :class:`ReportData`."""

    def __init__(self, data: ReportData, settings: ReportSettings) -> None:
        self.d = data
        self.s = settings
        self.dpi = int(settings.dpi)
        self.unavailable: dict[str, str] = {}
        self.claim_result = None
        manifest = data.sources.manifest
        title = str(manifest.get("study", {}).get("name") or f"wbsa report: {data.sources.fit_dir}")
        self.page = Page(title=title, subtitle=(
            f"Generated {time.strftime('%Y-%m-%d %H:%M')} by wbsa {__version__} from "
            f"{data.sources.study_dir or data.sources.fit_dir}. Tables give areas in m² and errors in %; figures "
            "draw areas in dm² (1 m² = 100 dm², the paper's unit)."))

    # -- helpers -------------------------------------------------------------------------------------------------

    def _figure(self, fig_id: str, what: str, draw: Callable, caption: str) -> None:
        try:
            fig = draw()
        except FigureUnavailable as exc:
            self.unavailable[fig_id] = str(exc)
            self.page.unavailable(fig_id, what, str(exc))
            return
        self.page.figure(fig_id, png_bytes(fig, self.dpi), caption)

    @property
    def common(self) -> dict:
        d = self.d
        return dict(distance_m=d.distance_m, camera=d.camera, dpi=self.dpi)

    def steps(self) -> list[Callable[[], None]]:
        steps = [self.claim, self.calibration, self.summary, self.population, self.scatter]
        steps += [lambda g=g: self.view_figure(g) for g in self.d.groups]
        steps += [self.groups, self.nonlinear, self.residuals, self.snapshots, self.reconstruction, self.distance,
                  self.formulae, self.claim_details, self.fit_table, self.run_info]
        return steps

    # -- sections ------------------------------------------------------------------------------------------------

    def claim(self) -> None:
        """The opening section: one view against height and weight, per group."""
        from wbsa.analysis.claim import ClaimUnavailable

        p = self.page
        p.section("claim", "The central claim: one view against height and weight")
        try:
            self.claim_result = compute_claim(self.d)
        except ClaimUnavailable as exc:
            self.claim_result = None
            self.unavailable["tab-claim"] = str(exc)
            p.unavailable("tab-claim", "claim table", str(exc))
            return
        r = self.claim_result
        k = int(self.d.fit_info.get("settings", {}).get("k", 10))
        p.bullets(list(r.sentences.values()))
        p.table("tab-claim", headline_display(r), "The single view against the height/weight (H/W) law refitted on "
                "the same bodies and against the best published formula of each group: MAPE in %, differences "
                "view − other in percentage points (negative: the view is better) with their paired-bootstrap "
                "interval; W/T/L counts the published formulae the view beats, ties with and loses to (each "
                "comparison is listed in 'The central claim: every comparison').", nowrap=True)
        p.paragraph(method_text(r, k))

    def calibration(self) -> None:
        """The study's own bodies beside the published real-body figures."""
        from wbsa.analysis.realism import realism_summary
        from wbsa.report import calibration as cal
        from wbsa.report.figures.calibration import calibration_figure

        d, p = self.d, self.page
        spec = group_spec_of(d.fit_info)
        p.section("calibration", "How real are these bodies?",
                  "The claim above can only be as good as the bodies it is tested on: a view beats height and weight "
                  "only where bodies of the same stature and mass differ in area. This section puts this study's "
                  "population beside what real bodies are published to do (docs/calibration.md).")
        try:
            summary = realism_summary(d.population, spec)
        except WbsaError as exc:
            self.unavailable["tab-calibration"] = str(exc)
            p.unavailable("tab-calibration", "calibration tables", str(exc))
            return
        p.bullets(cal.calibration_sentences(summary, spec))
        p.table("tab-calibration", cal.reference_table(summary, spec), "This population beside the published "
                "real-body figures (the published formulae evaluated at these subjects' height and weight where a "
                "source gives an equation, not a table); 'not found': the stored sources do not give it.")
        self._figure("fig-calibration", "calibration figure", lambda: calibration_figure(d.population, spec, self.dpi),
                     "(a) Mesh area / Du Bois against BMI for every subject (children hollow), with Livingston & "
                     "Lee's law fitted on normal-weight and obese patients (band: 10–90 % of the adults in each BMI "
                     "bin) and the 3-D-scan formulae of Yu and Schlich, all divided by Du Bois at the same adults; "
                     "(b) adults' density against BMI with Deurenberg's body-fat equation and Siri's density at the "
                     "median age (band: ± the equation's standard error).")
        p.table("tab-calibration-dubois", cal.dubois_display(summary), "Mesh area / Du Bois by sex and BMI class "
                "(mean ± SD; adults in WHO classes, children one class), beside the formulae fitted on measured "
                "areas, divided by Du Bois at the same subjects.")
        p.table("tab-calibration-composition", cal.composition_display(summary), "Density (mass / volume) and fat "
                "by sex and BMI class (mean ± SD), beside Deurenberg's body-fat equation (its mean) and Siri's "
                "density at the same BMI, age and sex.")
        p.table("tab-calibration-groups", cal.groups_display(summary, spec), "Subjects per group, and per posture.")
        posed = cal.posture_display(summary)
        if not posed.empty:
            p.table("tab-calibration-posture", posed, "Posed skin area − rest-pose WBSA, % of WBSA, per posture "
                    "(WBSA is the rest-pose area; the scans see the posed bodies).")
        p.paragraph("Sources: " + " · ".join(cal.sources_text()))

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
            for which, row in (("best", best), ("worst", worst)):
                rows.append((f"all subjects, {predictors_title(lab)}: CV RMSE (m²) and CV MAPE (%), {which} view",
                             f"{row['cv_rmse_m2']:.4f} m² ({row['cv_mape_pct']:.2f} %) at θ = {row['azimuth_deg']:g}°, "
                             f"φ = {row['elevation_deg']:g}°"))
        rows.append(("paper (Virtual Random, 19,995 subjects)",
                     "CV RMSE 0.0071–0.055 m² over the views; mean WBSA 1.67 m²"))
        p.table("tab-summary", pd.DataFrame(rows, columns=["quantity", "value"]),
                "Key numbers of this study (all-subjects fits at the reference distance).")

    def population(self) -> None:
        d, p = self.d, self.page
        p.section("population", "Population",
                  "The virtual population the study scanned; WBSA is the area of each body's skin mesh.")
        self._figure("fig-wbsa-distribution", "WBSA distribution", lambda: wbsa_distribution(d.population, self.dpi),
                     "Distribution of WBSA, stacked by sex (left), and WBSA against stature coloured by BMI (right) "
                     "(paper Fig 5).")
        p.table("tab-population", population_table(d.population, d.fit_info),
                "Composition of the population by group (paper Table 1): counts, WBSA and stature.")

    def scatter(self) -> None:
        d, p = self.d, self.page
        p.section("vbsa-wbsa", "VBSA and WBSA")
        self._figure("fig-vbsa-wbsa", "VBSA–WBSA scatter",
                     lambda: vbsa_wbsa_scatter(d.population, d.scan, d.fits, view=tuple(self.s.scatter_view_deg),
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
                     lambda: coefficients_by_view(d.fits, group=group, model=d.model, vbsa_column=d.vbsa_column,
                                                  predictor_labels=d.predictor_labels, **self.common),
                     f"{GROUP_LABELS.get(group, group).capitalize()}: CV RMSE (left) and VBSA coefficient c1 "
                     "(right) against azimuth, without and with stature (paper Figs 11, 13, 14).")

    def groups(self) -> None:
        d, p = self.d, self.page
        p.section("groups", "Groups")
        self._figure("fig-group-errors", "errors by group",
                     lambda: group_errors(d.fits, model=d.model, vbsa_column=d.vbsa_column,
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
                     lambda: nonlinear_view(d.population, d.scan, d.fits, view=tuple(self.s.nonlinear_view_deg),
                                            vbsa_column=d.vbsa_column, **self.common),
                     "The VBSA–WBSA relation at an occluded view with the linear and power-law fits, and the linear "
                     "fit's residuals against WBSA (paper Fig 16).")
        self._figure("fig-models", "model comparison",
                     lambda: model_comparison(d.fits, vbsa_column=d.vbsa_column, **self.common),
                     "Cross-validated RMSE of every model kind at elevation 0 (left) and its ratio to the first "
                     "model at every view (right).")
        if not d.model_summary.empty:
            ms = d.model_summary
            if "fit_group" in ms:
                ms = ms[ms["fit_group"] == ms["group"]]
            ms = ms[(ms["group"] == "all") & (ms["vbsa_column"] == d.vbsa_column)]
            ms = select(ms, distance_m=d.distance_m, camera=d.camera if "camera" in ms else None)
            # older fit folders may hold the all-subjects rows twice (once from the group fits, once
            # from the subgroup evaluation of the same model): keep the first, which has the Breusch–Pagan counts
            ms = ms.drop_duplicates(subset=[c for c in ("group", "predictors", "vbsa_column", "camera", "distance_m",
                                                        "model") if c in ms.columns])
            cols = [c for c in ("predictors", "model", "n_views", "mean_cv_rmse_m2", "max_cv_rmse_m2",
                                "mean_cv_mape_pct", "rmse_ratio", "views_better", "heteroscedastic_views")
                    if c in ms.columns]
            p.table("tab-models", ms[cols], "Model kinds over all views, all subjects: mean and worst CV RMSE, "
                    "ratio to the linear model, views where it is better, views with Breusch–Pagan p < 0.05.")

    def residuals(self) -> None:
        d, p = self.d, self.page
        p.section("residuals", "Residual analysis")
        self._figure("fig-residuals", "residual analysis",
                     lambda: residual_diagnostics(d.residuals, d.qq, view=tuple(self.s.scatter_view_deg),
                                                  model=d.model, vbsa_column=d.vbsa_column, **self.common),
                     "Residuals of the all-subjects VBSA-only fit: (a) normal QQ plot, (b) residuals against fitted "
                     "values, (c) histogram, (d) scale–location (paper S2 Fig).")

    def snapshots(self) -> None:
        d, p = self.d, self.page
        p.section("point-clouds", "Point clouds")
        self._figure("fig-snapshots", "point-cloud snapshots", self._draw_snapshots,
                     "What one camera sees of one subject at the scanned view nearest to [report] snapshot_view_deg: "
                     "its depth image and its point cloud looked at from four sides; grey is the skin the camera "
                     "misses (paper Fig 8).")

    def _draw_snapshots(self):
        from wbsa.report.snapshots import pick_subject, render_snapshot, scanned_view, snapshot_intrinsics

        d = self.d
        missing = [c for c in ("p_gender", "p_age", "p_weight", "p_height") if c not in d.population.columns]
        if missing:
            raise FigureUnavailable(f"the population lacks the body parameters ({', '.join(missing)})")
        try:
            az, el = scanned_view(d.scan, self.s.snapshot_view_deg, distance_m=d.distance_m, camera=d.camera)
            intr = snapshot_intrinsics(d.sources.scan_paths, d.camera)
            sid = pick_subject(d.population, self.s.snapshot_subject)
            snap = render_snapshot(d.population, sid, intr, az, el, d.distance_m)
        except WbsaError as exc:
            raise FigureUnavailable(str(exc)) from None
        return point_cloud_snapshots(snap.points_world, snap.depth_m, snap.body_vertices, view=(az, el),
                                     distance_m=d.distance_m, subject_id=sid, camera=d.camera, dpi=self.dpi)

    def reconstruction(self) -> None:
        d, p = self.d, self.page
        p.section("reconstruction", "Surface reconstruction")
        ref = d.vbsa_column if not d.vbsa_column.startswith("vbsa_recon_") else "vbsa_visible_m2"
        self._figure("fig-reconstruction", "reconstruction by view",
                     lambda: reconstruction_by_view(d.scan, d.fits, model=d.model, reference_column=ref,
                                                    **self.common),
                     "Reconstructed against ideal view area by azimuth at elevation 0: relative VBSA error, CV RMSE "
                     "and c1 with each VBSA (paper Figs 15 and 17).")

    def distance(self) -> None:
        d, p = self.d, self.page
        p.section("distance", "Camera distance")
        common = {k: v for k, v in self.common.items() if k != "distance_m"}
        self._figure("fig-distance", "camera distance",
                     lambda: distance_effect(d.fits, d.scan, model=d.model, vbsa_column=d.vbsa_column, **common),
                     "CV RMSE and c1 against the camera distance at a few views, and the share of bodies inside the "
                     "frame (paper section 3.4).")
        if len(d.distances_m) > 1:
            p.table("tab-distance", distance_table(d), "Per camera distance: bodies inside the frame, subjects "
                    "fitted and CV RMSE (m²) of the all-subjects VBSA-only fit over the views.")

    def formulae(self) -> None:
        d, p = self.d, self.page
        p.section("formulae", "Classical formulae")
        self._figure("fig-formulae", "formulae comparison",
                     lambda: formulae_comparison(d.formulae, model=d.model, vbsa_column=d.vbsa_column, **self.common),
                     "MAPE (%) of the classical BSA formulae (height and weight) against the mesh WBSA, and below "
                     "them the all-subjects single-view model's cross-validated MAPE at its best and worst view in "
                     "each group; one column per group.")
        if not d.formulae.empty:
            cols = [c for c in ("group", "kind", "label", "azimuth_deg", "elevation_deg", "n", "mape_pct", "bias_pct",
                                "bias_m2", "rmse_m2") if c in d.formulae.columns]
            p.table("tab-formulae", d.formulae[cols], "Formulae and single-view models against the mesh WBSA, per "
                    "group (MAPE in %, bias and RMSE in m²).", scroll=True)

    def claim_details(self) -> None:
        r = getattr(self, "claim_result", None)
        if r is None:
            return
        p = self.page
        p.section("claim-details", "The central claim: every comparison")
        p.table("tab-claim-all", comparisons_display(r), "Every paired comparison of the headline table: the single "
                "view against the refitted height/weight law and against each published formula, per group, view "
                "area and view (MAPE in %, difference in percentage points with its paired-bootstrap interval).",
                scroll=True, nowrap=True)

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

