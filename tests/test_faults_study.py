"""Fault injection on ``wbsa run``: another run overwriting shared files, concurrent runs, kill -9 and resume.

Each case ends with a one-line error (exit 2) or the correct result, and no file that claims to be
complete is not.
"""

from __future__ import annotations

import json
import os
import random
import subprocess
import sys
from pathlib import Path

import pytest

from helpers.cli import run_cli
from helpers.kill import kill_when

pytestmark = pytest.mark.slow  # real bodies, a scan, a fit and a report per study (10-30 s each)

SMALL = """
[study]
name = "{name}"

[population]
n = 8
seed = {seed}

[scan]
camera = "cam.json"
azimuths_deg = [0.0, 90.0]
elevations_deg = [0.0]

[fit]
k = 2
groups = ["all"]
models = ["linear"]

[report]
dpi = 30

[run]
workers = 1
chunk_size = {chunk}
"""

#: Files of a study folder whose bytes depend only on the settings.
DATA_FILES = ("fits.parquet", "fits.csv", "model.json")


def config(root: Path, name: str, seed: int = 1, chunk: int = 3) -> Path:
    """A small study file with a camera JSON beside it, named relative to the file (as users write it)."""
    from wbsa.camera.presets import preset

    (root / "cam.json").write_text(json.dumps(preset("kinect-v1").to_open3d_json()))
    path = root / f"{name.replace(' ', '_')}.toml"
    path.write_text(SMALL.format(name=name, seed=seed, chunk=chunk))
    return path


def wbsa_process(*args: str) -> subprocess.Popen:
    """``python -m wbsa ARGS`` in a new process (its own process group, so kill -9 takes the workers too)."""
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1] / "src"), "WBSA_PROGRESS": "0"}
    return subprocess.Popen([sys.executable, "-m", "wbsa", *args], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)


def assert_nothing_incomplete(folder: Path) -> None:
    """Every file under a final name reads back whole; every finished stage has its recorded outputs."""
    import pyarrow.parquet as pq

    from wbsa.study.stages import Stage

    for path in folder.rglob("*"):
        if not path.is_file() or ".part" in path.name or path.name.startswith("."):
            continue
        if path.suffix == ".parquet":
            pq.read_table(path)
        elif path.suffix == ".json":
            json.loads(path.read_text())
    for marker in folder.glob("stages/*/stage.json"):
        rec = json.loads(marker.read_text())
        stage = Stage(rec["stage"], rec["key"], marker.parent, rec["settings"], rec["inputs"])
        assert stage.done, marker


def report_title(html_path: Path) -> str:
    html = html_path.read_text()
    return html.split("<title>", 1)[1].split("</title>", 1)[0]


def stage_files(out: Path, kind: str) -> list[Path]:
    return sorted((out / "stages").glob(f"{kind}-*"))


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """Study A run once, uninterrupted: the bytes every resumed run must reproduce."""
    root = tmp_path_factory.mktemp("ref")
    cfg = config(root, "study A")
    code, _, err = run_cli("run", "--config", str(cfg), "--out", str(root / "A"))
    assert code == 0, err
    return root, cfg


def test_report_stage_is_built_from_its_own_inputs_not_the_shared_manifest(reference, tmp_path, monkeypatch):
    """Failure 1 of issue 12: another run rewrites study.json while this run builds its report."""
    import shutil

    import wbsa.io

    root, cfg_a = reference
    out = tmp_path / "X"
    shutil.copytree(root / "A", out)
    manifest_a = (out / "study.json").read_bytes()
    cfg_b = config(tmp_path, "study B")
    real_write_text = wbsa.io.write_text

    def other_run_wins(text, path):  # every study.json this run writes is replaced by study A's at once
        written = real_write_text(text, path)
        if Path(path).name == "study.json":
            Path(path).write_bytes(manifest_a)
        return written

    monkeypatch.setattr(wbsa.io, "write_text", other_run_wins)
    code, _, err = run_cli("run", "--config", str(cfg_b), "--out", str(out))
    assert code == 0, err
    monkeypatch.undo()
    [rep_b] = [p for p in stage_files(out, "report") if p.name not in {q.name for q in stage_files(root / "A", "report")}]
    assert report_title(rep_b / "report.html") == "study B"
    record = json.loads((rep_b / "stage.json").read_text())
    assert record["settings"]["study"]["name"] == "study B"
    # re-running B alone reuses its own report stage, which is B's
    code, _, err = run_cli("run", "--config", str(cfg_b), "--out", str(out))
    assert code == 0 and "4 of 4 stages reused" in err, err
    assert report_title(out / "report.html") == "study B"
    assert json.loads((out / "study.json").read_text())["study"]["name"] == "study B"


def test_study_toml_with_a_relative_camera_json_can_be_run_again(reference):
    """Issue 12 item 7: the written study.toml names the camera copy beside it, so it re-runs as is."""
    root, _ = reference
    out = root / "A"
    assert (out / "camera.json").is_file()
    code, _, err = run_cli("run", "--config", str(out / "study.toml"), "--out", str(out))
    assert code == 0 and "4 of 4 stages reused" in err, err
    assert_nothing_incomplete(out)


def test_two_concurrent_runs_with_different_configs_on_one_folder(tmp_path):
    """One run writes the folder; the other stops at once with one line; the folder is the winner's, whole."""
    out = tmp_path / "shared"
    cfg_a, cfg_b = config(tmp_path, "study A", seed=1), config(tmp_path, "study B", seed=2)
    procs = {"study A": wbsa_process("run", "--config", str(cfg_a), "--out", str(out)),
             "study B": wbsa_process("run", "--config", str(cfg_b), "--out", str(out))}
    results = {name: (p.wait(timeout=300), *p.communicate()) for name, p in procs.items()}
    winners = [name for name, (code, _, _) in results.items() if code == 0]
    losers = [name for name, (code, _, _) in results.items() if code != 0]
    assert winners, results
    for name in losers:
        code, _, err = results[name]
        assert code == 2 and err.count("\n") == 1 and "being written by another wbsa process" in err, err
    manifest = json.loads((out / "study.json").read_text())
    assert manifest["study"]["name"] in winners
    assert report_title(out / "report.html") == manifest["study"]["name"]
    fit = next(s for s in manifest["stages"] if s["stage"] == "fit")
    assert (out / "fits.parquet").read_bytes() == (out / fit["path"] / "fits.parquet").read_bytes()
    assert (out / "model.json").read_bytes() == (out / fit["path"] / "model.json").read_bytes()
    assert_nothing_incomplete(out)


def files_in(folder: Path) -> int:
    """How many files a study folder holds (0 before it exists): the work a run has done so far."""
    return sum(1 for p in folder.rglob("*") if p.is_file()) if folder.exists() else 0


def test_kill_9_at_random_points_then_resume_gives_the_same_bytes(reference, tmp_path):
    """kill -9 twice at random points of a run (after a random number of its files are written, not after a
    time), then finish it: the data files equal an uninterrupted run's."""
    root, _ = reference
    cfg = config(tmp_path, "study A")
    out = tmp_path / "killed"
    rng = random.Random(12)
    total = files_in(root / "A")
    for attempt in range(2):
        if files_in(out) >= total - 1:
            break
        written = rng.randint(files_in(out) + 1, total - 1)
        kill_when(wbsa_process("run", "--config", str(cfg), "--out", str(out)), lambda: files_in(out), written)
        if out.exists():
            assert_nothing_incomplete(out)
    code, _, err = run_cli("run", "--config", str(cfg), "--out", str(out))
    assert code == 0, err
    for name in DATA_FILES:
        assert (out / name).read_bytes() == (root / "A" / name).read_bytes(), name
    for kind, table in (("population", "population.parquet"), ("scan", "scan.parquet")):
        [a], [b] = stage_files(out, kind), stage_files(root / "A", kind)
        assert a.name == b.name and (a / table).read_bytes() == (b / table).read_bytes(), kind
    assert not [p for p in out.rglob("*.part*")], "temporary files left behind"
    assert_nothing_incomplete(out)
