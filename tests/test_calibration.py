"""The calibration section (issue 10, point 4): published reference figures and the report section built from
the study's own population (``wbsa.analysis.calibration_refs``, ``wbsa.report.calibration``)."""

from __future__ import annotations

import dataclasses
import html as html_module
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from helpers.synthetic import synthetic_population, synthetic_scan
from wbsa.analysis.calibration_refs import (FIGURES, SOURCES, deurenberg_siri_density_kg_m3,
                                            schlich_female_effect_percent)
from wbsa.analysis.fit_views import FitSettings
from wbsa.analysis.outputs import run_fit
from wbsa.analysis.realism import (composition_table, dubois_bmi_slopes, hw_law, posed_area_change,
                                   realism_summary)
from wbsa.report.calibration import CITED_SOURCES
from wbsa.report.data import load_report_data
from wbsa.report.figures.calibration import calibration_figure
from wbsa.report.figures.style import FigureUnavailable
from wbsa.report.sections import SectionBuilder
from wbsa.report.settings import ReportSettings
from wbsa.report.sources import fit_dir_sources

DOC = Path(__file__).resolve().parents[1] / "docs" / "calibration.md"


# -- the reference module -----------------------------------------------------------------------------------------

def test_every_published_figure_names_a_source_and_the_missing_ones_say_why():
    for f in FIGURES.values():
        assert f.source in SOURCES, f.key
        if not f.found:
            assert f.text() == "not found" and f.note, f.key
    assert FIGURES["area_scatter_at_fixed_hw_percent"].value is None  # not quoted from memory
    assert FIGURES["fat_see_adult_percent"].text() == "4.1 %BF"
    assert FIGURES["deurenberg_bmi_range"].text() == "13.9–40.9 kg/m²"
    # Siri's two compartments: all fat 0.900 g/cm³, no fat 1.100 g/cm³
    assert FIGURES["density_range_kg_m3"].value == (900.0, 1100.0)


def test_the_doc_quotes_the_reference_module_and_names_it():
    doc = DOC.read_text()
    assert "wbsa.analysis.calibration_refs" in doc
    for f in FIGURES.values():
        if f.found and f.key != "density_range_kg_m3":
            assert f.text().split(" ")[0] in doc, f.key
    for key in CITED_SOURCES:  # the first author's name and the year
        name, year = SOURCES[key].label.split()[0].rstrip(","), SOURCES[key].label.split()[-1]
        assert re.search(f"{name}[^|\n]*{year}", doc), key


def test_schlich_sex_difference_and_deurenberg_density_at_known_points():
    # the doc's figures: Schlich's women have +3.7 % at 160 cm / 60 kg and +7.5 % at 165 cm / 100 kg
    assert schlich_female_effect_percent(np.array([1.60]), np.array([60.0])) == pytest.approx(3.7, abs=0.05)
    assert schlich_female_effect_percent(np.array([1.65]), np.array([100.0])) == pytest.approx(7.5, abs=0.05)
    assert np.isnan(schlich_female_effect_percent(np.array([]), np.array([])))
    # a 40-year-old woman of BMI 22: 1.2·22 + 0.23·40 − 5.4 = 30.2 % fat; Siri 495 / (30.2 + 450) g/cm³
    d = deurenberg_siri_density_kg_m3(np.array([22.0]), np.array([40.0]), np.array([False]))
    assert d[0] == pytest.approx(1000 * 495 / 480.2, rel=1e-12)


# -- the realism additions ----------------------------------------------------------------------------------------

def _population(n: int = 120, seed: int = 3) -> pd.DataFrame:
    return synthetic_population(n, seed=seed)


def test_bmi_slopes_and_expected_composition():
    t = _population()
    slopes = dubois_bmi_slopes(t)
    assert slopes["mesh"] == pytest.approx(hw_law(t).dubois_bmi_slope_percent, rel=1e-12)
    # Livingston & Lee's weight-only law rises above Du Bois with BMI, as in their obese patients
    assert slopes["livingston_lee"] > 0.5
    c = composition_table(t)
    np.testing.assert_allclose(c["density_kg_m3_mean"], 1010.0)  # the synthetic volume is mass / 1010
    # Deurenberg's fat rises with BMI in every sex, so its density falls across the adult classes
    for sex in ("female", "male"):
        adults = c[(c["sex"] == sex) & (c["bmi_class"] != "children")]
        assert adults["deurenberg_density_kg_m3_mean"].is_monotonic_decreasing


def test_posed_area_change_per_posture():
    t = _population(12).assign(posture=["a-pose", "arms-down", "feet-apart"] * 4)
    assert posed_area_change(t).empty
    t["wbsa_posed_m2"] = t["wbsa_m2"] * np.where(t["posture"] == "arms-down", 1.003, 0.999)
    p = posed_area_change(t).set_index("posture")
    assert list(p.index) == ["all", "a-pose", "arms-down", "feet-apart"]
    assert p.loc["arms-down", "mean_percent"] == pytest.approx(0.3)
    assert p.loc["all", "n"] == 12 and p.loc["all", "min_percent"] == pytest.approx(-0.1)


# -- the report section ------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def data(tmp_path_factory):
    root = tmp_path_factory.mktemp("calibration-fit")
    pop = synthetic_population(80, seed=11)
    scan = synthetic_scan(pop, [(0.0, 0.0), (30.0, 0.0), (90.0, 0.0)], seed=11)
    pop.to_parquet(root / "population.parquet")
    scan.to_parquet(root / "scan.parquet")
    run_fit(root / "population.parquet", root / "scan.parquet", root / "fit",
            FitSettings(groups=("all", "males"), models=("linear",), k=3))
    return load_report_data(fit_dir_sources(root / "fit", root / "population.parquet", [root / "scan.parquet"]))


def _section(data) -> tuple[SectionBuilder, str]:
    """The calibration section alone, as HTML (unescaped text)."""
    b = SectionBuilder(data, ReportSettings())
    b.calibration()
    return b, html_module.unescape(b.page.render())


def _table(page: str, tab_id: str) -> pd.DataFrame:
    """A table of the page as strings (header row, then the body rows)."""
    body = re.search(f'<table[^>]*id="{tab_id}".*?</table>', page, re.S).group(0)
    rows = [re.findall(r"<t[hd][^>]*>(.*?)</t[hd]>", r, re.S) for r in re.findall(r"<tr[^>]*>(.*?)</tr>", body, re.S)]
    return pd.DataFrame(rows[1:], columns=rows[0])


def test_the_section_shows_the_study_numbers_beside_the_cited_figures(data):
    b, page = _section(data)
    s = realism_summary(data.population)
    assert b.page.tables == ["tab-calibration", "tab-calibration-dubois", "tab-calibration-composition",
                             "tab-calibration-groups"]
    assert b.page.figures == ["fig-calibration"]
    law = s["hw_law"]
    assert f"residual SD of {law['residual_sd_percent']:.2f} %" in page
    overview = _table(page, "tab-calibration").set_index("quantity")
    assert int(overview.loc["bodies", "this population"]) == law["n"]
    assert overview.loc["scatter of area at fixed H and W (residual SD)", "real bodies (published)"] == "not found"
    # Livingston & Lee's "as much as 20 %" and the full citation of every source used
    assert "as much as 20 %" in page
    for key in CITED_SOURCES:
        assert SOURCES[key].citation in page, key
    groups = _table(page, "tab-calibration-groups").set_index("group")["subjects"]
    assert {k: int(v) for k, v in groups.items()} == s["groups"]
    dub = _table(page, "tab-calibration-dubois")
    assert dub["n"].astype(int).sum() == len(data.population)
    # no composition columns: the constant density is compared with Deurenberg + Siri, no virtual fat column
    comp = _table(page, "tab-calibration-composition")
    assert "fat %" not in comp.columns and "Deurenberg fat %" in comp.columns
    assert "every body has 1,010 kg/m³" in page
    # no posture column: said, no posture table
    assert "A-pose" in page and "tab-calibration-posture" not in b.page.tables


def test_the_section_reads_composition_and_posture_columns(data):
    pop = data.population.copy()
    rng = np.random.default_rng(0)
    pop["fat_fraction"] = rng.uniform(0.15, 0.4, len(pop))
    pop["posture"] = np.array(["a-pose", "arms-down", "hands-on-hips"])[np.arange(len(pop)) % 3]
    pop["wbsa_posed_m2"] = pop["wbsa_m2"] * (1 + 0.002 * rng.standard_normal(len(pop)))
    b, page = _section(dataclasses.replace(data, population=pop))
    assert "tab-calibration-posture" in b.page.tables
    comp = _table(page, "tab-calibration-composition")
    assert "fat %" in comp.columns
    assert "by construction" in page
    groups = _table(page, "tab-calibration-groups").set_index("group")["subjects"]
    assert int(groups["posture: arms-down"]) == (pop["posture"] == "arms-down").sum()
    posed = _table(page, "tab-calibration-posture").set_index("posture")
    assert int(posed.loc["all", "n"]) == len(pop)


def test_the_section_says_why_when_the_population_lacks_columns(data):
    b, page = _section(dataclasses.replace(data, population=data.population.drop(columns=["volume_m3"])))
    assert b.page.tables == [] and "tab-calibration" in b.unavailable
    assert "volume_m3" in page and "not drawn" in page


def test_the_section_follows_the_claim(data):
    names = [getattr(step, "__name__", "") for step in SectionBuilder(data, ReportSettings()).steps()]
    assert names[:3] == ["claim", "calibration", "summary"]


def test_calibration_figure_draws_every_subject_at_its_ratio(data):
    from wbsa.analysis.realism import dubois_m2

    pop = data.population
    fig = calibration_figure(pop)
    ax = fig.axes[0]
    points = np.vstack([c.get_offsets() for c in ax.collections if hasattr(c, "get_offsets")
                        and len(c.get_offsets()) and c.get_label() and "(n = " in c.get_label()])
    expected = np.column_stack([pop["bmi"], pop["wbsa_m2"] / dubois_m2(pop)])
    assert len(points) == len(pop)
    np.testing.assert_allclose(np.sort(points[:, 1]), np.sort(expected[:, 1]))
    with pytest.raises(FigureUnavailable, match="volume_m3"):
        calibration_figure(pop.drop(columns=["volume_m3"]))
