"""The top-level Python API: its docstring examples and the notebook session of docs/python.md."""

from __future__ import annotations

import doctest
import importlib
import re
from pathlib import Path

import numpy as np
import pytest

import wbsa

DOCS = Path(__file__).resolve().parents[1] / "docs" / "python.md"

#: Modules whose examples are part of the public API's documentation.
API_MODULES = ("wbsa", "wbsa.core.mesh", "wbsa.simulate.view", "wbsa.bodies.make", "wbsa.study.study")


@pytest.mark.parametrize("name", API_MODULES)
def test_docstring_examples_run(name, monkeypatch):
    monkeypatch.chdir(Path(__file__).resolve().parents[1])
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.failed == 0


def test_every_public_name_imports():
    for name in wbsa.__all__:
        assert getattr(wbsa, name) is not None, name
    assert set(dir(wbsa)) >= set(wbsa.__all__)


def test_meshes_from_other_libraries_give_the_same_area():
    import open3d as o3d

    box = o3d.geometry.TriangleMesh.create_box(0.4, 0.2, 1.7)
    ours = wbsa.TriangleMesh.from_any(box)
    assert ours.area_m2 == pytest.approx(2 * (0.4 * 0.2 + 0.4 * 1.7 + 0.2 * 1.7), rel=1e-12)
    assert wbsa.TriangleMesh.from_any(o3d.t.geometry.TriangleMesh.from_legacy(box)).area_m2 == pytest.approx(
        ours.area_m2, rel=1e-6)
    assert wbsa.TriangleMesh.from_any((np.asarray(box.vertices), np.asarray(box.triangles))).area_m2 == ours.area_m2
    with pytest.raises(wbsa.WbsaError, match="cannot use a builtins.dict as a mesh"):
        wbsa.TriangleMesh.from_any({})


def test_render_takes_open3d_meshes_and_intrinsics():
    import open3d as o3d

    box = o3d.geometry.TriangleMesh.create_box(0.4, 0.2, 1.7)
    box.translate((-0.2, -0.1, 0.0))
    k = o3d.camera.PinholeCameraIntrinsic(o3d.camera.PinholeCameraIntrinsicParameters.PrimeSenseDefault)
    seen = wbsa.render(box, camera=k, view=(0, 0, 3.0))
    assert seen.depth_m.shape == (480, 640)
    assert seen.row["vbsa_hit_m2"] == pytest.approx(0.4 * 1.7, rel=1e-9)  # the front face only
    assert "pixels" in repr(seen) and len(repr(seen)) < 200


def _notebook_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", DOCS.read_text(), flags=re.S)


@pytest.mark.slow
def test_notebook_session_in_the_docs_runs(tmp_path, monkeypatch):
    blocks = _notebook_blocks()
    assert len(blocks) >= 4
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    for block in blocks:
        exec(compile(block, str(DOCS), "exec"), namespace)
    assert (tmp_path / "notebook-study" / "model.json").is_file()


@pytest.mark.slow
def test_the_readme_python_example_runs_as_a_script(readme_example):
    """The README's "From Python" block, saved as a file and run with ``python script.py`` (dask's worker
    processes import the script again: the example must work as written; tests/conftest.py runs it once, and
    the browser test of the report reads the report it writes)."""
    code, done, folder = readme_example
    assert "Study" in code and "workers=2" in code  # the block that starts worker processes
    assert done.returncode == 0, done.stderr[-2000:]
    assert "Traceback" not in done.stderr and "Nanny failed" not in done.stderr
    assert (folder / "runs" / "demo" / "report.html").is_file()
    assert "StudyResult(" in done.stdout
