"""The report's figures and HTML, built from small synthetic tables with the documented columns.

The synthetic tables (``tests/helpers/synthetic.py``) follow the pinned population and scan schemas, so
these tests check that each figure draws exactly the numbers of the tables it is given; the end-to-end
test with real bodies is in ``test_study.py``.
"""

import base64
import contextlib
import io
import re
import struct

import numpy as np
import pandas as pd
import pytest

from wbsa.analysis.fit_views import FitSettings
from wbsa.analysis.outputs import run_fit
from helpers.synthetic import synthetic_population, synthetic_scan
from wbsa.cli import main
from wbsa.errors import WbsaError
from wbsa.report.build import build_report
from wbsa.report.data import load_report_data, nearest_view, select
from wbsa.report.figures.by_view import coefficients_by_view, group_errors
from wbsa.report.figures.distance import distance_effect
from wbsa.report.figures.formulae import formulae_comparison
from wbsa.report.figures.one_view import vbsa_wbsa_scatter, view_table
from wbsa.report.figures.population import wbsa_distribution
from wbsa.report.figures.reconstruction import reconstruction_by_view
from wbsa.report.figures.residuals import residual_diagnostics
from wbsa.report.figures.style import FigureUnavailable
from wbsa.report.sources import fit_dir_sources, resolve_sources

VIEWS = [(a, e) for e in (0.0, 60.0) for a in (0.0, 60.0, 90.0, 180.0)]
DISTANCES = (3.5, 4.3)
GROUPS = ("all", "males", "kids")


def png_size(data: bytes) -> tuple[int, int]:
    """(width, height) from a PNG's IHDR chunk; fails if ``data`` is not a PNG."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24])


def embedded_figures(html: str) -> dict[str, bytes]:
    found = re.findall(r'<figure id="([^"]+)"><img alt="[^"]*" src="data:image/png;base64,([A-Za-z0-9+/=]+)"', html)
    return {fid: base64.b64decode(b64) for fid, b64 in found}


@pytest.fixture(scope="module")
def fit_dir(tmp_path_factory):
    """A fit folder from synthetic tables: two distances (taller bodies cut at the near one) and a
    reconstruction column."""
    root = tmp_path_factory.mktemp("synthetic-fit")
    pop = synthetic_population(90, seed=5)
    scans = [synthetic_scan(pop, VIEWS, seed=5, distance_m=d, frame_limit_m=2.25 * d / 4.3) for d in DISTANCES]
    scan = pd.concat(scans, ignore_index=True)
    rng = np.random.default_rng(7)
    scan["vbsa_recon_grid_m2"] = scan["vbsa_visible_m2"] * (1.03 + 0.02 * rng.standard_normal(len(scan)))
    pop_path, scan_path = root / "population.parquet", root / "scan.parquet"
    pop.to_parquet(pop_path)
    scan.to_parquet(scan_path)
    settings = FitSettings(vbsa_columns=("vbsa_visible_m2", "vbsa_recon_m2:grid"), models=("linear", "loglog"),
                           groups=GROUPS, k=4)
    run_fit(pop_path, scan_path, root / "fit", settings)
    return root


@pytest.fixture(scope="module")
def data(fit_dir):
    return load_report_data(fit_dir_sources(fit_dir / "fit", fit_dir / "population.parquet",
                                            [fit_dir / "scan.parquet"]))


@pytest.fixture(scope="module")
def cli_report(fit_dir, tmp_path_factory):
    """``wbsa report`` run once on the synthetic fit: (exit code, stdout, the report's path)."""
    out = tmp_path_factory.mktemp("report") / "r.html"
    stdout = io.StringIO()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(io.StringIO()):
        code = main(["report", str(fit_dir / "fit"), "--population", str(fit_dir / "population.parquet"),
                     "--scan", str(fit_dir / "scan.parquet"), "--out", str(out)])
    return code, stdout.getvalue(), out


@pytest.fixture(scope="module")
def report_html(cli_report):
    return cli_report[2].read_text()


def test_report_command_embeds_every_figure_as_png_and_every_table(cli_report):
    code, stdout, out = cli_report
    assert code == 0
    assert stdout.strip() == str(out)  # stdout: just the report's path
    html = out.read_text()
    figs = embedded_figures(html)
    expected = {"fig-calibration", "fig-wbsa-distribution", "fig-vbsa-wbsa", "fig-group-errors", "fig-models", "fig-nonlinear",
                "fig-residuals", "fig-reconstruction", "fig-distance", "fig-formulae",
                *(f"fig-view-{g}" for g in GROUPS)}
    assert set(figs) == expected
    for fid, png in figs.items():
        w, h = png_size(png)
        assert w >= 300 and h >= 200, fid
    # synthetic subjects have no body parameters, so there is no point cloud to draw: said, not faked
    assert re.findall(r'class="na" id="([^"]+)"', html) == ["fig-snapshots-na"]
    assert "body parameters" in html
    for tab in ("tab-claim", "tab-calibration", "tab-summary", "tab-population", "tab-correlation", "tab-groups", "tab-models", "tab-distance",
                "tab-formulae", "tab-fits", "tab-stages", "tab-settings", "tab-versions"):
        assert f'id="{tab}"' in html, tab
    assert html.startswith("<!DOCTYPE html>") and html.rstrip().endswith("</html>")
    assert "<script" not in html and "http://" not in html and "https://" not in html  # self-contained


def test_scatter_draws_the_measured_points_and_the_fitted_line(data):
    fig = vbsa_wbsa_scatter(data.population, data.scan, data.fits, view=(0, 0), distance_m=4.3,
                            camera=data.camera, vbsa_column="vbsa_visible_m2")
    ax = fig.axes[0]
    t = view_table(data.population, data.scan, "vbsa_visible_m2", 0.0, 0.0, 4.3, data.camera)
    inside = t[t["fits_in_frame"]]
    pts = ax.collections[0].get_offsets()
    np.testing.assert_allclose(np.sort(pts[:, 0]), np.sort(inside["vbsa_m2"] * 100))
    np.testing.assert_allclose(np.sort(pts[:, 1]), np.sort(inside["wbsa_m2"] * 100))
    row = select(data.fits, group="all", model="linear", predictors="vbsa", vbsa_column="vbsa_visible_m2",
                 distance_m=4.3, azimuth_deg=0.0, elevation_deg=0.0).iloc[0]
    line = ax.lines[0]
    x, y = line.get_xdata(), line.get_ydata()
    np.testing.assert_allclose(y, (row["c0"] + row["c1"] * x / 100) * 100)
    cut = t[~t["fits_in_frame"]]
    assert len(cut) == (len(ax.collections[1].get_offsets()) if len(ax.collections) > 1 else 0)


def test_coefficient_figure_lines_are_the_fit_table(data):
    fig = coefficients_by_view(data.fits, group="all", model="linear", vbsa_column="vbsa_visible_m2",
                               distance_m=4.3, camera=data.camera, predictor_labels=data.predictor_labels)
    axes = fig.axes
    assert len(axes) == 4  # (VBSA only, VBSA + stature) x (CV RMSE, c1)
    for row, label in enumerate(["vbsa", "vbsa+stature_m"]):
        sub = select(data.fits, group="all", model="linear", predictors=label, vbsa_column="vbsa_visible_m2",
                     distance_m=4.3)
        rmse_ax, c1_ax = axes[2 * row], axes[2 * row + 1]
        assert len(c1_ax.lines) == sub["elevation_deg"].nunique()
        for line_rmse, line_c1, el in zip(rmse_ax.lines, c1_ax.lines, sorted(sub["elevation_deg"].unique())):
            part = sub[sub["elevation_deg"] == el].sort_values("azimuth_deg")
            np.testing.assert_allclose(line_c1.get_xdata(), part["azimuth_deg"])
            np.testing.assert_allclose(line_c1.get_ydata(), part["c1"])
            np.testing.assert_allclose(line_rmse.get_ydata(), part["cv_rmse_m2"] * 100)


def test_wbsa_histogram_counts_every_subject(data):
    fig = wbsa_distribution(data.population)
    ax = fig.axes[0]
    top = {}
    for patch in ax.patches:  # stacked: the top of each bin's last bar is the bin's total
        x = round(patch.get_x(), 9)
        top[x] = max(top.get(x, 0.0), patch.get_y() + patch.get_height())
    assert sum(top.values()) == pytest.approx(len(data.population))


def test_group_errors_show_each_group_at_elevation_zero(data):
    fig = group_errors(data.fits, model="linear", vbsa_column="vbsa_visible_m2", distance_m=4.3,
                       camera=data.camera, predictor_labels=data.predictor_labels)
    ax = fig.axes[0]
    sub = select(data.fits, model="linear", predictors="vbsa", vbsa_column="vbsa_visible_m2", distance_m=4.3,
                 elevation_deg=0.0)
    groups = list(dict.fromkeys(sub["group"]))
    assert len(ax.lines) == len(groups)
    for line, g in zip(ax.lines, groups):
        np.testing.assert_allclose(line.get_ydata(), sub[sub["group"] == g].sort_values("azimuth_deg")["cv_rmse_m2"] * 100)


def test_distance_figure_shows_the_share_of_bodies_in_frame(data):
    fig = distance_effect(data.fits, data.scan, model="linear", vbsa_column="vbsa_visible_m2", camera=data.camera,
                          views=[(0.0, 0.0)])
    share_ax = fig.axes[2]
    rows = select(data.scan, azimuth_deg=0.0, elevation_deg=0.0)
    expected = rows.groupby("distance_m")["fits_in_frame"].mean() * 100
    np.testing.assert_allclose(share_ax.lines[0].get_ydata(), expected.to_numpy())
    assert expected.loc[3.5] < expected.loc[4.3]  # the nearer camera cuts the tallest bodies
    c1_ax = fig.axes[1]
    c1 = select(data.fits, group="all", model="linear", predictors="vbsa", vbsa_column="vbsa_visible_m2",
                azimuth_deg=0.0, elevation_deg=0.0).sort_values("distance_m")["c1"]
    np.testing.assert_allclose(c1_ax.lines[0].get_ydata(), c1)


def test_reconstruction_figure_shows_the_relative_area_error(data):
    fig = reconstruction_by_view(data.scan, data.fits, model="linear", distance_m=4.3, camera=data.camera)
    err_ax = fig.axes[0]
    sc = select(data.scan, distance_m=4.3, elevation_deg=0.0)
    sc = sc[sc["fits_in_frame"]]
    rel = 100 * (sc["vbsa_recon_grid_m2"] - sc["vbsa_visible_m2"]) / sc["vbsa_visible_m2"]
    expected = rel.groupby(sc["azimuth_deg"]).mean()
    np.testing.assert_allclose(np.asarray(err_ax.lines[0].get_ydata(), dtype=float), expected.to_numpy())
    assert 2.0 < expected.mean() < 4.0  # the synthetic reconstruction over-estimates by 3 %


def test_figures_without_their_data_say_why(data):
    one_distance = select(data.fits, distance_m=4.3)
    with pytest.raises(FigureUnavailable, match="single camera distance"):
        distance_effect(one_distance, data.scan, model="linear", vbsa_column="vbsa_visible_m2", camera=data.camera)
    with pytest.raises(FigureUnavailable, match="no reconstruction columns"):
        reconstruction_by_view(data.scan.drop(columns="vbsa_recon_grid_m2"), data.fits, model="linear",
                               distance_m=4.3, camera=data.camera)
    with pytest.raises(FigureUnavailable, match="no per-subject residuals"):
        residual_diagnostics(pd.DataFrame(), data.qq, view=(0, 0), model="linear", vbsa_column="vbsa_visible_m2",
                             distance_m=4.3, camera=data.camera)


def test_nearest_view_is_on_the_sphere():
    views = pd.DataFrame({"azimuth_deg": [0.0, 60.0, 90.0, 0.0], "elevation_deg": [0.0, 60.0, 0.0, 90.0]})
    assert nearest_view(views, 60, 60) == (60.0, 60.0)
    assert nearest_view(views, 170, 88) == (0.0, 90.0)  # near the pole the azimuth hardly matters
    assert nearest_view(views, 80, 5) == (90.0, 0.0)


def test_report_inputs_that_cannot_be_found_are_one_line_errors(fit_dir, tmp_path, capsys):
    with pytest.raises(WbsaError, match="does not exist"):
        resolve_sources(tmp_path / "nowhere")
    with pytest.raises(WbsaError, match="neither a study folder"):
        resolve_sources(tmp_path)
    found = resolve_sources(fit_dir / "fit")  # wbsa fit recorded its input tables in fit_info.json
    assert found.population_path.resolve() == (fit_dir / "population.parquet").resolve()
    import json
    import shutil

    bare = tmp_path / "bare_fit"
    shutil.copytree(fit_dir / "fit", bare)
    info = json.loads((bare / "fit_info.json").read_text())
    info.pop("inputs")
    (bare / "fit_info.json").write_text(json.dumps(info))
    with pytest.raises(WbsaError, match="give --population FILE and --scan FILE"):
        resolve_sources(bare)
    assert main(["report", str(bare)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1
    with pytest.raises(WbsaError, match="must end in .html"):
        build_report(fit_dir_sources(fit_dir / "fit", fit_dir / "population.parquet", [fit_dir / "scan.parquet"]),
                     tmp_path / "r.pdf")


def _table_rows(html: str, tab_id: str) -> list[tuple[str, ...]]:
    i = html.index(f'id="{tab_id}"')
    body = html[i:html.index("</table>", i)]
    rows = re.findall(r"<tr[^>]*>(.*?)</tr>", body, re.S)
    cells = [tuple(c.strip() for c in re.findall(r"<td[^>]*>(.*?)</td>", r, re.S)) for r in rows]
    return [c for c in cells if c]


def test_report_opens_with_the_claim_table_and_its_sentences(report_html, data):
    html = report_html
    first_h2 = re.search(r'<h2 id="([^"]+)"', html).group(1)
    assert first_h2 == "claim"
    claim_at = html.index('id="tab-claim"')
    assert claim_at < html.index("<figure") and claim_at < html.index('id="tab-summary"')
    sentences = re.search(r'<ul class="claims">(.*?)</ul>', html, re.S).group(1)
    assert html.index('<ul class="claims">') < html.index("<figure")
    assert "All subjects (n = " in sentences
    assert re.search(r"(beats|ties with|loses to)", sentences)
    rows = _table_rows(html, "tab-claim")
    assert rows and rows[0][0] == "All subjects"
    # both VBSA columns of the fit: the ideal area and the sensor reconstruction
    assert {r[1] for r in rows} >= {"ideal", "sensor + grid"}
    # every verdict is one of the three words (or a group too small to test)
    verdicts = {r[7] for r in rows} | {r[11] for r in rows}
    assert verdicts <= {"wins", "ties", "loses", "too few"}
    assert 'id="tab-claim-all"' in html


def test_model_table_has_no_duplicate_rows(report_html, fit_dir):
    rows = _table_rows(report_html, "tab-models")
    assert rows and len(rows) == len(set(rows))
    assert len({r[:2] for r in rows}) == len(rows)  # one row per predictor set × model kind
    ms = pd.read_csv(fit_dir / "fit" / "model_summary.csv")
    keys = ["group", "predictors", "vbsa_column", "camera", "distance_m", "model", "fit_group"]
    assert not ms.duplicated(keys).any()
    assert not ms[ms["group"] == ms["fit_group"]].duplicated(keys[:-1]).any()


def test_summary_uses_one_area_unit_and_printing_shows_every_row(report_html):
    i = report_html.index('id="tab-summary"')
    summary = report_html[i:report_html.index("</table>", i)]
    assert "dm²" not in summary and "m²" in summary and "%" in summary
    css = re.search(r"@media print \{(.*?)\n\}", report_html, re.S).group(1)
    assert re.search(r"\.scroll \{[^}]*max-height: none[^}]*overflow: visible", css)


def test_formulae_grid_is_one_readable_panel_with_the_table_numbers(data):
    fig = formulae_comparison(data.formulae, model="linear", vbsa_column="vbsa_visible_m2", distance_m=4.3,
                              camera=data.camera, dpi=100)
    ax = fig.axes[0]
    assert len(fig.axes) == 2  # the grid and its colour bar
    assert min(t.get_fontsize() for t in ax.get_yticklabels()) >= 9
    assert min(t.get_fontsize() for t in ax.texts) >= 9
    assert fig.get_size_inches()[0] * 100 <= 1400  # shown at about its own size in a 1200 px page
    # the cells are the table's MAPE values: Du Bois in the "all" column
    f = data.formulae
    want = f[(f["group"] == "all") & (f["method"] == "dubois")]["mape_pct"].iloc[0]
    labels = [t.get_text() for t in ax.get_yticklabels()]
    groups = [t.get_text().split("\n")[0] for t in ax.get_xticklabels()]
    row, col = labels.index("Du Bois & Du Bois"), groups.index("all subjects")
    cell = [t for t in ax.texts if t.get_position() == (col, row)]
    assert cell and cell[0].get_text() == f"{want:.2f}"


# ---------------------------------------------------------------- counting axes, scanned views, legends at 1280 px
def _ticks_shown(axis) -> list[float]:
    lo, hi = sorted(axis.get_view_interval())
    return [float(t) for t in axis.get_majorticklocs() if lo - 1e-9 <= t <= hi + 1e-9]


def test_axes_that_count_tick_whole_numbers_only(data):
    from wbsa.report.figures.by_view import model_comparison

    # two views: a plain axis would tick the view numbers at 1.25, 1.5, 1.75
    fits = data.fits[(data.fits["elevation_deg"] == 0.0) & data.fits["azimuth_deg"].isin([0.0, 90.0])]
    ax = model_comparison(fits, vbsa_column="vbsa_visible_m2", distance_m=4.3, camera=data.camera).axes[1]
    assert sorted({float(x) for c in ax.collections for x in c.get_offsets()[:, 0]}) == [1.0, 2.0]
    ticks = _ticks_shown(ax.xaxis)
    assert len(ticks) >= 2 and all(t.is_integer() for t in ticks), ticks
    # six subjects: at most a few per histogram bin, counted in whole subjects
    ax = wbsa_distribution(data.population.iloc[:6]).axes[0]
    assert max(p.get_height() for p in ax.patches) <= 3
    ticks = _ticks_shown(ax.yaxis)
    assert len(ticks) >= 2 and all(t.is_integer() for t in ticks), ticks
    few = data.residuals[data.residuals["subject_id"].isin(data.population["subject_id"].iloc[:6])]
    fig = residual_diagnostics(few, pd.DataFrame(), view=(0, 0), model="linear", vbsa_column="vbsa_visible_m2",
                               distance_m=4.3, camera=data.camera)
    ticks = _ticks_shown(fig.axes[2].yaxis)
    assert fig.axes[2].get_ylabel() == "subjects"
    assert len(ticks) >= 2 and all(t.is_integer() for t in ticks), ticks


def test_the_snapshot_view_is_the_scanned_view_nearest_the_asked_one(data):
    from wbsa.report.snapshots import scanned_view

    scan, cam = data.scan, data.camera
    assert scanned_view(scan, (60.0, 60.0), distance_m=4.3, camera=cam) == (60.0, 60.0)  # scanned: kept
    level = scan[scan["elevation_deg"] == 0.0]
    assert scanned_view(level, (60.0, 60.0), distance_m=4.3, camera=cam) == (60.0, 0.0)
    front = scan[(scan["azimuth_deg"] == 0.0) & (scan["elevation_deg"] == 0.0)]
    assert scanned_view(front, (60.0, 60.0), distance_m=3.5, camera=cam) == (0.0, 0.0)
    with pytest.raises(WbsaError, match="no view at D = 2 m"):
        scanned_view(scan, (60.0, 60.0), distance_m=2.0, camera=cam)
    with pytest.raises(WbsaError, match="no view"):
        scanned_view(scan, (60.0, 60.0), distance_m=4.3, camera="another-camera")


def test_the_snapshot_figure_renders_and_names_a_view_the_study_scanned(data, monkeypatch):
    """The study scanned only the front at elevation 0; the settings ask for the paper's (60°, 60°)."""
    import dataclasses

    import wbsa.report.snapshots as snapshots
    from wbsa.report.sections import SectionBuilder
    from wbsa.report.settings import ReportSettings

    rendered = []

    def fake_render(population, subject_id, intrinsics, azimuth_deg, elevation_deg, distance_m):
        rendered.append((azimuth_deg, elevation_deg, distance_m))
        rng = np.random.default_rng(0)
        return snapshots.Snapshot(subject_id, rng.normal(size=(50, 3)), np.ones((8, 4), np.float32),
                                  rng.normal(size=(200, 3)))

    monkeypatch.setattr(snapshots, "render_snapshot", fake_render)
    pop = data.population.assign(p_gender=0.5, p_age=0.5, p_weight=0.5, p_height=0.5)
    scan = data.scan[data.scan["elevation_deg"] == 0.0]
    d = dataclasses.replace(data, population=pop, scan=scan)
    builder = SectionBuilder(d, ReportSettings(snapshot_view_deg=(60.0, 60.0)))
    fig = builder._draw_snapshots()
    assert rendered == [(60.0, 0.0, d.distance_m)]
    assert "θ = 60°, φ = 0°" in fig.axes[0].get_title()
    assert "(60, 60)" not in fig.get_suptitle() and "φ = 60°" not in fig.get_suptitle()


#: The report's content is 1200 px wide in a 1280 px window (measured in tests/test_report_browser.py); a wider
#: figure is scaled down to it.
PAGE_PX = 1200
#: Smallest legible legend text on that page, px (the page's table text is 12.8 px).
MIN_LEGEND_PX = 12.0


def test_every_legend_is_legible_and_inside_its_figure_at_1280_px(data):
    from wbsa.analysis.groups import GroupSpec
    from wbsa.report.figures.by_view import model_comparison
    from wbsa.report.figures.calibration import calibration_figure
    from wbsa.report.figures.one_view import nonlinear_view
    from wbsa.report.html import png_bytes

    common = dict(vbsa_column="vbsa_visible_m2", distance_m=4.3, camera=data.camera)
    figures = {
        "calibration": calibration_figure(data.population, GroupSpec()),
        "wbsa-distribution": wbsa_distribution(data.population),
        "vbsa-wbsa": vbsa_wbsa_scatter(data.population, data.scan, data.fits, view=(0, 0), **common),
        "view-all": coefficients_by_view(data.fits, group="all", model="linear", predictor_labels=data.predictor_labels,
                                         **common),
        "group-errors": group_errors(data.fits, model="linear", predictor_labels=data.predictor_labels, **common),
        "models": model_comparison(data.fits, **common),
        "nonlinear": nonlinear_view(data.population, data.scan, data.fits, view=(60, 60), **common),
        "distance": distance_effect(data.fits, data.scan, model="linear", vbsa_column="vbsa_visible_m2",
                                    camera=data.camera),
        "reconstruction": reconstruction_by_view(data.scan, data.fits, model="linear",
                                                 reference_column="vbsa_visible_m2", distance_m=4.3,
                                                 camera=data.camera),
    }
    for name, fig in figures.items():
        png_bytes(fig)  # lays the figure out as the report does
        width_px, height_px = fig.get_size_inches() * fig.dpi
        shown = min(1.0, PAGE_PX / width_px)
        legends = list(fig.legends) + [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
        assert legends, name
        for legend in legends:
            texts = legend.get_texts() + ([legend.get_title()] if legend.get_title().get_text() else [])
            for text in texts:
                px = text.get_fontsize() * fig.dpi / 72 * shown
                assert px >= MIN_LEGEND_PX, (name, text.get_text(), round(px, 1))
            box = legend.get_window_extent()
            assert box.x0 >= -1 and box.y0 >= -1 and box.x1 <= width_px + 1 and box.y1 <= height_px + 1, (name, box)
