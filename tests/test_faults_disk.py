"""Fault injection: every command that writes, on a full disk.

As root (the build machine) the disk is a small tmpfs filled up to the free space each case asks for,
so the real writers (pyarrow, openpyxl, PIL, matplotlib, Open3D) meet a real ENOSPC part-way through
their files. Without root (CI) the disk is simulated: :func:`wbsa.atomic.atomic_path`'s sync step raises
ENOSPC once the bytes written exceed the budget, which checks the error path but not Open3D's silent
failures. Each case ends with exit 0 and complete files, or exit 2 and one line naming the path and
the fix; in both cases every file under a final name reads back whole and no temporary file is left.
"""

from __future__ import annotations

import contextlib
import errno
import io
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from wbsa.cli import main

pytestmark = pytest.mark.slow  # about a minute: every command, twice, on real bodies

LEVELS = (0, 40_000)  # bytes left free on the disk


class Disk:
    """A folder whose file system has ``free`` bytes left (tmpfs as root, else a simulated budget)."""

    def __init__(self, root: Path, monkeypatch) -> None:
        self.path = root / "disk"
        self.path.mkdir()
        self.monkeypatch = monkeypatch
        self.mounted = os.geteuid() == 0 and subprocess.run(
            ["mount", "-t", "tmpfs", "-o", "size=16m", "tmpfs", str(self.path)], capture_output=True).returncode == 0

    def fill(self, free: int) -> Path:
        """Leave ``free`` bytes free; returns the folder to write into."""
        if self.mounted:
            filler = self.path / "filler"
            with open(filler, "wb") as fh:
                fh.truncate(0)
            st = os.statvfs(self.path)
            room = st.f_bavail * st.f_frsize - free
            with open(filler, "wb") as fh:
                block = b"\0" * (1 << 20)
                while room > 0:
                    try:
                        room -= fh.write(block[:min(room, len(block))])
                    except OSError:
                        break
        else:
            import wbsa.atomic

            budget = {"left": free}
            real_sync = wbsa.atomic._sync

            def sync_within_budget(tmp: Path) -> None:
                budget["left"] -= tmp.stat().st_size
                if budget["left"] < 0:
                    raise OSError(errno.ENOSPC, "No space left on device", str(tmp))
                real_sync(tmp)

            self.monkeypatch.setattr(wbsa.atomic, "_sync", sync_within_budget)
        out = self.path / "out"
        out.mkdir(exist_ok=True)
        return out

    def close(self) -> None:
        if self.mounted:
            subprocess.run(["umount", "-l", str(self.path)], capture_output=True)


@pytest.fixture
def disk(tmp_path, monkeypatch):
    d = Disk(tmp_path, monkeypatch)
    yield d
    d.close()


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """Inputs on a normal disk: a real population, a synthetic fit folder, a depth image and a model."""
    from wbsa.analysis.fit_views import FitSettings
    from wbsa.analysis.outputs import run_fit
    from helpers.synthetic import synthetic_population, synthetic_scan

    root = tmp_path_factory.mktemp("inputs")
    assert main(["population", "--kind", "random", "--n", "3", "--seed", "2", "--out", str(root / "pop.parquet"),
                 "--workers", "1"]) == 0
    assert main(["view", "--population", str(root / "pop.parquet"), "--out", str(root / "view")]) == 0
    pop = synthetic_population(60, seed=3)
    scan = synthetic_scan(pop, [(0.0, 0.0), (90.0, 0.0)], seed=3)
    pop.to_parquet(root / "spop.parquet")
    scan.to_parquet(root / "sscan.parquet")
    run_fit(root / "spop.parquet", root / "sscan.parquet", root / "fit", FitSettings(groups=("all",), k=3))
    (root / "study.toml").write_text('[population]\nn = 4\n[scan]\nviews = "front"\n[fit]\nk = 2\ngroups = ["all"]\n'
                                     'models = ["linear"]\n[report]\ndpi = 30\n[run]\nworkers = 1\n')
    return root


def commands(i: Path, out: Path) -> dict[str, list[str]]:
    return {
        "population": ["population", "--kind", "random", "--n", "3", "--out", str(out / "p.parquet"), "--workers",
                       "1"],
        "body": ["body", "--out", str(out / "b.ply")],
        "body-obj": ["body", "--out", str(out / "b.obj")],
        "view": ["view", "--population", str(i / "pop.parquet"), "--out", str(out / "v")],
        "scan": ["scan", str(i / "pop.parquet"), "--out", str(out / "s"), "--views", "front", "--workers", "1",
                 "--no-progress"],
        "fit": ["fit", str(i / "spop.parquet"), str(i / "sscan.parquet"), "--out", str(out / "f"), "--k", "3",
                "--groups", "all"],
        "report": ["report", str(i / "fit"), "--population", str(i / "spop.parquet"), "--scan",
                   str(i / "sscan.parquet"), "--out", str(out / "r.html")],
        "estimate": ["estimate", str(i / "view" / "depth.png"), "--model", str(i / "fit" / "model.json"),
                     "--camera", "kinect-v1", "--azimuth", "0", "--elevation", "0", "--no-segment",
                     "--out-mesh", str(out / "m.ply")],
        "run": ["run", "--config", str(i / "study.toml"), "--out", str(out / "study")],
    }


def assert_all_complete(folder: Path) -> None:
    """Every file under a final name reads back whole; no temporary file or staging folder is left."""
    import pyarrow.parquet as pq
    from PIL import Image

    from wbsa.core.ply import check_ply, read_ply_header

    left = [p for p in folder.rglob("*") if ".part" in p.name or p.name.startswith(".staging")]
    assert not left, left
    for p in folder.rglob("*"):
        if not p.is_file() or p.name == ".wbsa.lock":
            continue
        if p.suffix == ".parquet":
            pq.read_table(p)
        elif p.suffix == ".ply":
            counts = {name: n for name, n, _ in read_ply_header(p)[1]}
            check_ply(p, counts.get("vertex", 0), counts.get("face", 0))
        elif p.suffix == ".png":
            with Image.open(p) as img:
                img.load()
        elif p.suffix == ".json":
            json.loads(p.read_text())
        elif p.suffix == ".html":
            assert p.read_text().rstrip().endswith("</html>"), p
        elif p.suffix == ".csv":
            pd.read_csv(p)
        elif p.suffix == ".xlsx":
            pd.read_excel(p, sheet_name=None)
        elif p.suffix == ".npy":
            np.load(p)
        elif p.suffix == ".obj":
            assert p.read_bytes().endswith(b"\n"), p


@pytest.mark.parametrize("free", LEVELS)
@pytest.mark.parametrize("command", ["population", "body", "body-obj", "view", "scan", "fit", "report", "estimate",
                                     "run"])
def test_full_disk_gives_one_line_or_a_complete_result(inputs, disk, command, free):
    out = disk.fill(free)
    o, e = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(e):
        code = main(commands(inputs, out)[command])
    lines = e.getvalue().splitlines()
    assert "Traceback" not in e.getvalue()
    if code != 0:  # the error is one line, the last (wbsa run logs its stages before it)
        err = lines[-1]
        assert code == 2 and [x for x in lines if x.startswith("error")] == [err], lines
        assert err.startswith("error: cannot ") and "no space left on the device" in err and str(out) in err, err
    assert_all_complete(out)


def test_open3d_reports_success_after_a_failed_write(tmp_path, disk):
    """Why PLY files are checked by size: on a full disk Open3D's writer returns True for a cut-short file."""
    if not disk.mounted:
        pytest.skip("needs a real full file system (root)")
    import open3d as o3d

    from wbsa.core.ply import check_ply

    out = disk.fill(0)
    mesh = o3d.geometry.TriangleMesh.create_sphere(0.1, resolution=60)
    ok = o3d.io.write_triangle_mesh(str(out / "raw.ply"), mesh)
    assert ok  # the library's claim
    with pytest.raises(Exception):
        check_ply(out / "raw.ply", len(mesh.vertices), len(mesh.triangles))


def test_full_disk_stderr_is_one_line_even_from_open3d(inputs, disk):
    """Open3D's PLY writer prints a line per failed block on file descriptor 2; the user sees one line."""
    if not disk.mounted:
        pytest.skip("needs a real full file system (root)")
    import sys

    out = disk.fill(40_000)
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1] / "src"), "WBSA_PROGRESS": "0"}
    proc = subprocess.run([sys.executable, "-m", "wbsa", *commands(inputs, out)["view"]], env=env,
                          capture_output=True, text=True)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    assert proc.stderr.startswith(f"error: cannot write {out}") and "no space left" in proc.stderr
    assert_all_complete(out)


def test_a_failed_refit_leaves_the_previous_outputs_as_they_were(inputs, tmp_path, monkeypatch, capsys):
    """Issue 12 item 3: a refit that fails part-way (here: the disk fills while writing model.json)."""
    import wbsa.io

    out = tmp_path / "f"
    base = ["fit", str(inputs / "spop.parquet"), str(inputs / "sscan.parquet"), "--out", str(out), "--groups", "all"]
    assert main([*base, "--k", "5"]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.name != "run_log.json"}
    dead = subprocess.Popen(["true"])
    dead.wait()
    (out / f".fits.xlsx.{dead.pid}-0badcafe.part").write_bytes(b"left by a killed writer")  # a dead writer's temp
    real_write_text = wbsa.io.write_text

    def full_at_model(text, path):
        if Path(path).name == "model.json":
            raise wbsa.io.WbsaError(wbsa.io.os_error_message(OSError(errno.ENOSPC, "full"), path))
        return real_write_text(text, path)

    monkeypatch.setattr("wbsa.analysis.model_file.write_text", full_at_model)
    assert main([*base, "--k", "3"]) == 2
    assert "no space left" in capsys.readouterr().err
    after = {p.name: p.read_bytes() for p in out.iterdir() if p.name != "run_log.json"}
    assert after == before  # old fits.parquet, model.json and fit_info.json (k = 5) untouched and together
    assert json.loads((out / "fit_info.json").read_text())["settings"]["k"] == 5
    monkeypatch.undo()
    assert main([*base, "--k", "3"]) == 0
    assert json.loads((out / "fit_info.json").read_text())["settings"]["k"] == 3
    assert not [p for p in out.iterdir() if ".part" in p.name]  # the stale temporary is gone
