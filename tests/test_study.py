"""``wbsa run`` end to end on a tiny study with real bodies: every stage, the report, reuse on re-run."""

import base64
import contextlib
import io
import json
import re
import time

import pandas as pd
import pytest

from wbsa.cli import main

pytestmark = pytest.mark.slow  # about 10 s (the study fixture 5.7 s): real bodies, ray casting, fits, a report

TINY = """
[study]
name = "tiny test study"

[population]
n = 12
seed = 3

[scan]
azimuths_deg = [0.0, 60.0, 90.0]
elevations_deg = [0.0, 60.0]
distances_m = [3.0, 4.3]

[fit]
k = 3
groups = ["all", "males", "females"]
models = ["linear", "loglog"]

[run]
workers = 1
"""

FIGURES = ("fig-wbsa-distribution", "fig-vbsa-wbsa", "fig-view-all", "fig-view-males", "fig-view-females",
           "fig-group-errors", "fig-models", "fig-nonlinear", "fig-residuals", "fig-snapshots", "fig-distance",
           "fig-formulae")
TABLES = ("tab-claim", "tab-summary", "tab-population", "tab-correlation", "tab-groups", "tab-models", "tab-distance",
          "tab-formulae", "tab-fits", "tab-stages", "tab-settings", "tab-versions")


def figures_in(html: str) -> dict[str, bytes]:
    found = re.findall(r'<figure id="([^"]+)"><img alt="[^"]*" src="data:image/png;base64,([A-Za-z0-9+/=]+)"', html)
    return {fid: base64.b64decode(b64) for fid, b64 in found}


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """Run the tiny study once through the CLI; returns (folder, stdout, stderr, seconds, config)."""
    root = tmp_path_factory.mktemp("study")
    cfg = root / "tiny.toml"
    cfg.write_text(TINY)
    out = root / "run"
    o, e = io.StringIO(), io.StringIO()
    t = time.perf_counter()
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(e):
        code = main(["run", "--config", str(cfg), "--out", str(out)])
    seconds = time.perf_counter() - t
    assert code == 0, e.getvalue()
    return out, o.getvalue(), e.getvalue(), seconds, cfg


def test_run_writes_every_stage_and_prints_the_report_path(study):
    out, stdout, stderr, _, _ = study
    assert stdout.strip() == str(out / "report.html")
    for line in ("population ", "scan 3 m", "scan 4.3 m", "fit ", "report "):
        assert re.search(rf"^{line}.*\(\d+\.\d s\)", stderr, re.M), (line, stderr)
    manifest = json.loads((out / "study.json").read_text())
    kinds = [s["stage"] for s in manifest["stages"]]
    assert kinds == ["population", "scan", "scan", "fit", "report"]
    for s in manifest["stages"]:
        assert (out / s["path"] / "stage.json").is_file()
        assert s["path"].endswith(s["key"])
    # the per-view fit table, as Parquet and CSV, at the top of the study folder
    fits = pd.read_parquet(out / "fits.parquet")
    assert len(fits) == len(pd.read_csv(out / "fits.csv"))
    assert set(fits["distance_m"]) == {3.0, 4.3}
    assert {"c0", "c1", "cv_rmse_m2", "cv_mape_pct"} <= set(fits.columns)
    # every scan row is a real measurement of a body: positive visible area below the WBSA
    scan = pd.read_parquet(out / manifest["stages"][2]["path"] / "scan.parquet")
    pop = pd.read_parquet(out / manifest["stages"][0]["path"] / "population.parquet")
    both = scan.merge(pop[["subject_id", "wbsa_m2"]], on="subject_id")
    assert len(scan) == 12 * 6
    assert ((both["vbsa_visible_m2"] > 0) & (both["vbsa_visible_m2"] < both["wbsa_m2"])).all()
    # the resolved settings reproduce the study
    assert "n = 12" in (out / "study.toml").read_text()


def test_report_embeds_every_figure_and_table(study):
    out = study[0]
    html = (out / "report.html").read_text()
    figs = figures_in(html)
    for fid in FIGURES:
        assert fid in figs, fid
        assert figs[fid][:8] == b"\x89PNG\r\n\x1a\n"
        assert len(figs[fid]) > 10_000, fid  # a drawn figure, not an empty canvas
    for tab in TABLES:
        assert f'id="{tab}"' in html, tab
    # no reconstruction in this study: the report says so instead of drawing a figure
    assert re.findall(r'class="na" id="([^"]+)"', html) == ["fig-reconstruction-na"]
    assert "tiny test study" in html


def test_rerun_reuses_every_stage_and_gives_the_same_fit_table(study, capsys, monkeypatch):
    """The rerun does no stage's work: the population builder, the scanner, the fit and the report builder
    are each called 0 times."""
    import importlib

    out, _, _, _, cfg = study
    before = (out / "fits.parquet").read_bytes()
    calls = []
    for module, name in (("wbsa.bodies.build", "build_population"), ("wbsa.scan.engine", "scan_population"),
                         ("wbsa.analysis.outputs", "run_fit"), ("wbsa.report.build", "build_report")):
        work = getattr(importlib.import_module(module), name)
        monkeypatch.setattr(f"{module}.{name}", lambda *a, _name=name, _work=work, **k: calls.append(_name)
                            or _work(*a, **k))
    assert main(["run", "--config", str(cfg), "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert captured.out.strip() == str(out / "report.html")
    assert captured.err.count(" reused ") == 5
    assert calls == []
    assert (out / "fits.parquet").read_bytes() == before
    manifest = json.loads((out / "study.json").read_text())
    assert all(s["reused"] for s in manifest["stages"])


def test_changing_only_execution_knobs_rescans_nothing(study, tmp_path, capsys):
    out, _, _, _, _ = study
    cfg = tmp_path / "knobs.toml"
    cfg.write_text(TINY.replace("[run]\nworkers = 1", "[run]\nworkers = 2\nchunk_size = 5\nprogress = false"))
    assert main(["run", "--config", str(cfg), "--out", str(out)]) == 0
    assert capsys.readouterr().err.count(" reused ") == 5  # population, both scans, fit, report
    assert "chunk_size = 5" in (out / "study.toml").read_text()


def test_report_command_finds_the_inputs_of_a_fit_stage(study, tmp_path, capsys):
    out = study[0]
    manifest = json.loads((out / "study.json").read_text())
    fit_dir = out / next(s["path"] for s in manifest["stages"] if s["stage"] == "fit")
    html_path = tmp_path / "again.html"
    assert main(["report", str(fit_dir), "--out", str(html_path)]) == 0
    assert capsys.readouterr().out.strip() == str(html_path)
    figs = figures_in(html_path.read_text())
    assert set(FIGURES) <= set(figs)
