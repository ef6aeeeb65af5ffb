"""The server's bookkeeping without a browser: one estimate's place (Runner.slot) and torch's thread count."""

from __future__ import annotations

import pytest

from wbsa.server.jobs import Runner
from wbsa.server.uploads import UploadError


def test_a_slot_is_given_back_when_its_block_ends_however_it_ends():
    runner = Runner(workers=1, max_pending=1)
    try:
        with runner.slot():
            assert runner.pending == 1
            with pytest.raises(UploadError, match="busy"), runner.slot():
                pass  # refused: the one place is taken, and nothing is counted for it
            assert runner.pending == 1
        assert runner.pending == 0
        with pytest.raises(RuntimeError), runner.slot():
            raise RuntimeError("a failure inside the block")
        assert runner.pending == 0
    finally:
        runner.close()


def test_a_slot_handed_on_is_given_back_once_by_the_work():
    runner = Runner(workers=1, max_pending=2)
    try:
        with runner.slot() as slot:
            release = slot.hand_on()
        assert runner.pending == 1  # the work it started holds it
        release()
        release("a future", "called it again")
        assert runner.pending == 0
    finally:
        runner.close()


def test_the_server_sets_the_fit_threads_once_and_its_fits_keep_them():
    from wbsa.estimation.methods.body_fit.settings import BodyFitSettings
    from wbsa.server.app import create_app

    app = create_app(body_fit=BodyFitSettings(steps=3, threads=1))
    try:
        assert app.state.body_fit.threads is None and app.state.body_fit.steps == 3
    finally:
        import shutil

        shutil.rmtree(app.state.root, ignore_errors=True)
        app.state.runner.close()


def test_torch_threads_is_the_one_place_the_count_is_set():
    """Saving, setting and restoring torch's process-wide thread count is written once (wbsa.parallel)."""
    from pathlib import Path

    import torch

    from wbsa.parallel import torch_threads

    src = Path(__file__).resolve().parents[1] / "src" / "wbsa"
    setters = sorted(str(p.relative_to(src)) for p in src.rglob("*.py") if "set_num_threads(" in p.read_text())
    assert setters == ["parallel.py"], setters
    before = torch.get_num_threads()
    with torch_threads(None):
        assert torch.get_num_threads() == before
    with torch_threads(1):
        assert torch.get_num_threads() == 1
    assert torch.get_num_threads() == before
