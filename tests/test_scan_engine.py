"""The scan engine: chunking, parts, resume, settings check, dask vs in-process.

These tests drive the engine with a cheap stand-in chunk function defined here (no bodies,
no ray casting), so they check the engine alone; tests/test_scan.py runs the real worker.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import time
from dataclasses import dataclass
from pathlib import Path

import cloudpickle
import numpy as np
import pandas as pd
import pytest

from wbsa.errors import WbsaError
from wbsa import parallel
from wbsa.scan.engine import scan_population
from wbsa.scan.layout import PARTS_DIR, SETTINGS_FILE, TABLE_FILE, plan_chunks
from wbsa.scan.settings import ScanJob

# The dask workers are separate processes: ship this module's functions by value.
cloudpickle.register_pickle_by_value(sys.modules[__name__])


@dataclass(frozen=True)
class _Camera:
    name: str = "stand-in"
    width: int = 64
    height: int = 48


@dataclass(frozen=True)
class _View:
    azimuth_deg: float
    elevation_deg: float
    distance_m: float


VIEWS = tuple(_View(a, e, 4.3) for a in (0.0, 90.0, 180.0) for e in (-30.0, 0.0, 30.0))


def stand_in_chunk(subjects: pd.DataFrame, settings: ScanJob) -> pd.DataFrame:
    """A cheap, deterministic per-subject function with per-subject randomness, like the real worker."""
    rows = []
    for sid, height in zip(subjects["subject_id"].to_numpy(), subjects["p_height"].to_numpy()):
        rng = np.random.default_rng(np.random.SeedSequence([settings.seed, int(sid)]))
        noise = rng.normal(size=len(settings.views))
        for k, v in enumerate(settings.views):
            rows.append({"subject_id": int(sid), "azimuth_deg": v.azimuth_deg, "elevation_deg": v.elevation_deg,
                         "distance_m": v.distance_m, "camera": settings.camera_name,
                         "vbsa_hit_m2": 0.5 + height * np.cos(np.radians(v.azimuth_deg)) ** 2 + 0.01 * noise[k],
                         "n_pixels": int(1000 * height) + k})
    # Reverse the rows so the test sees the engine sort them.
    return pd.DataFrame(rows[::-1])


def pid_chunk(subjects: pd.DataFrame, settings: ScanJob) -> pd.DataFrame:
    """The stand-in rows plus the id of the process that made them."""
    rows = stand_in_chunk(subjects, settings)
    rows["pid"] = os.getpid()
    return rows


def failing_chunk(subjects: pd.DataFrame, settings: ScanJob) -> pd.DataFrame:
    if 7 in subjects["subject_id"].to_numpy():
        raise WbsaError("subject 7 cannot be scanned")
    return stand_in_chunk(subjects, settings)


def _population(n: int = 23, start: int = 0) -> pd.DataFrame:
    rng = np.random.default_rng(1)
    ids = np.arange(start, start + n, dtype=np.int64)
    # Shuffled rows: the engine orders subjects by id.
    return pd.DataFrame({"subject_id": ids, "p_height": rng.uniform(0, 1, n)}).sample(frac=1.0, random_state=3)


def _settings(**kw) -> ScanJob:
    return ScanJob(**{"camera": _Camera(), "views": VIEWS, "seed": 5, **kw})


def _scan(pop, out, **kw):
    kw.setdefault("workers", 1)
    kw.setdefault("chunk_size", 4)
    return scan_population(pop, kw.pop("settings", _settings()), out, chunk_fn=kw.pop("chunk_fn", stand_in_chunk),
                           show_progress=False, **kw)


def test_plan_chunks_covers_every_subject_once():
    chunks = plan_chunks(np.array([2, 3, 5, 8, 13, 21, 34]), 3)
    assert [(c.start, c.stop, c.first_id, c.last_id) for c in chunks] == [(0, 3, 2, 5), (3, 6, 8, 21), (6, 7, 34, 34)]
    assert chunks[1].part_name == "part-00000008-00000021.parquet"


def test_in_process_scan_writes_sorted_table_parts_and_settings(tmp_path):
    pop = _population()
    res = _scan(pop, tmp_path / "out")
    table = pd.read_parquet(tmp_path / "out" / TABLE_FILE)
    assert len(table) == len(pop) * len(VIEWS) == len(res.table)
    keys = table[["subject_id", "azimuth_deg", "elevation_deg", "distance_m"]]
    assert keys.equals(keys.sort_values(list(keys.columns), ignore_index=True))
    assert not keys.duplicated().any()
    parts = sorted(p.name for p in (tmp_path / "out" / PARTS_DIR).iterdir())
    assert parts[0] == "part-00000000-00000003.parquet" and parts[-1] == "part-00000020-00000022.parquet"
    assert len(parts) == res.n_chunks == 6 and res.n_resumed == 0
    doc = json.loads((tmp_path / "out" / SETTINGS_FILE).read_text())
    assert doc["settings"]["seed"] == 5 and len(doc["settings"]["views"]) == len(VIEWS)
    assert doc["population"]["n_subjects"] == len(pop)


def test_result_does_not_depend_on_chunk_size(tmp_path):
    a = _scan(_population(), tmp_path / "a").table
    b = _scan(_population(), tmp_path / "b", chunk_size=7).table
    pd.testing.assert_frame_equal(a, b)


def test_seed_changes_the_per_subject_noise(tmp_path):
    a = _scan(_population(), tmp_path / "a").table
    b = _scan(_population(), tmp_path / "b", settings=_settings(seed=6)).table
    assert not np.allclose(a["vbsa_hit_m2"], b["vbsa_hit_m2"])
    assert a["n_pixels"].equals(b["n_pixels"])


def test_resume_after_interruption_gives_the_uninterrupted_table(tmp_path):
    pop = _population()
    full = _scan(pop, tmp_path / "full").table

    out = tmp_path / "resumed"
    _scan(pop, out)
    parts_dir = out / PARTS_DIR
    parts = sorted(parts_dir.iterdir())
    # Simulate a run killed mid-way: some parts missing, a half-written temporary, no final table.
    for p in parts[1::2]:
        p.unlink()
    stale = parts_dir / ".part-00000004-00000007.parquet.abc123.part"
    stale.write_bytes(b"half a parquet file")
    (out / TABLE_FILE).unlink()
    # A finished part is not recomputed: the same file (inode, modification time) is still there.
    before = parts[0].stat()

    res = _scan(pop, out)
    assert res.n_resumed == 3 and res.n_chunks == 6
    assert not stale.exists()
    after = parts[0].stat()
    assert (after.st_ino, after.st_mtime_ns) == (before.st_ino, before.st_mtime_ns)
    pd.testing.assert_frame_equal(res.table, full)


def test_killed_run_resumes_to_the_uninterrupted_table(tmp_path):
    """SIGKILL a real scan process mid-way, run the same scan again: same table as an uninterrupted run.

    The process's third chunk says so (a file) and waits to be killed, so it dies with exactly two parts
    written, whatever the machine's speed."""
    full = _scan(_population(), tmp_path / "full").table
    out = tmp_path / "killed"
    waiting = tmp_path / "third-chunk-started"
    script = textwrap.dedent(f"""
        import pathlib, sys, time
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        import test_scan_engine as t

        calls = []

        def third_waits(subjects, settings):
            calls.append(1)
            if len(calls) == 3:
                pathlib.Path({str(waiting)!r}).touch()
                time.sleep(600)  # killed here
            return t.stand_in_chunk(subjects, settings)

        t._scan(t._population(), {str(out)!r}, chunk_fn=third_waits)
    """)
    proc = subprocess.Popen([sys.executable, "-c", script])
    try:
        deadline = time.monotonic() + 300  # a hung child fails the test instead of hanging the suite
        while not waiting.exists():
            assert proc.poll() is None, "the scan process ended before it could be killed"
            assert time.monotonic() < deadline, "the scan process never reached its third chunk"
            time.sleep(0.02)
    finally:
        proc.kill()
        proc.wait()
    done = len(list((out / PARTS_DIR).glob("part-*.parquet")))
    assert done == 2 and not (out / TABLE_FILE).exists()
    res = _scan(_population(), out)
    assert res.n_resumed == done
    pd.testing.assert_frame_equal(res.table, full)


def test_resume_with_the_same_command_is_idempotent(tmp_path):
    pop = _population()
    first = _scan(pop, tmp_path / "out").table
    again = _scan(pop, tmp_path / "out")
    assert again.n_resumed == again.n_chunks
    pd.testing.assert_frame_equal(first, again.table)


@pytest.mark.parametrize("change", [{"seed": 6}, {"views": VIEWS[:3]}])
def test_refuses_to_resume_with_other_settings(tmp_path, change):
    _scan(_population(), tmp_path / "out")
    with pytest.raises(WbsaError, match="other settings.*use another output folder") as exc:
        _scan(_population(), tmp_path / "out", settings=_settings(**change))
    assert "\n" not in str(exc.value)


def counting_chunk(subjects: pd.DataFrame, settings: ScanJob) -> pd.DataFrame:
    """The stand-in rows; appends the chunk's subject ids to the file named by $WBSA_TEST_CHUNK_LOG."""
    with open(os.environ["WBSA_TEST_CHUNK_LOG"], "a") as fh:
        fh.write(" ".join(map(str, subjects["subject_id"])) + "\n")
    return stand_in_chunk(subjects, settings)


def test_chunk_size_is_not_part_of_the_folder_key_and_never_rescans(tmp_path, monkeypatch):
    log = tmp_path / "chunks.log"
    monkeypatch.setenv("WBSA_TEST_CHUNK_LOG", str(log))
    pop, out = _population(), tmp_path / "out"
    first = _scan(pop, out, chunk_fn=counting_chunk)
    assert len(log.read_text().splitlines()) == first.n_chunks == 6
    # A finished folder with another chunk size: reused as it is, nothing scanned again.
    again = _scan(pop, out, chunk_fn=counting_chunk, chunk_size=9)
    assert again.n_views_scanned == 0 and again.n_resumed == again.n_chunks == 6
    assert len(log.read_text().splitlines()) == 6
    pd.testing.assert_frame_equal(first.table, again.table)
    # An interrupted folder resumed with another chunk size keeps its own plan: only the missing chunk runs.
    (out / PARTS_DIR / "part-00000004-00000007.parquet").unlink()
    resumed = _scan(pop, out, chunk_fn=counting_chunk, chunk_size=2)
    assert log.read_text().splitlines()[6:] == ["4 5 6 7"] and resumed.n_resumed == 5
    pd.testing.assert_frame_equal(first.table, resumed.table)
    assert "chunk_size" not in json.loads((out / SETTINGS_FILE).read_text())["settings"]


def test_refuses_to_resume_with_another_population(tmp_path):
    _scan(_population(), tmp_path / "out")
    other = _population()
    other.loc[other["subject_id"] == 3, "p_height"] += 0.1
    with pytest.raises(WbsaError, match="another population"):
        _scan(other, tmp_path / "out")


def test_refuses_parts_without_settings(tmp_path):
    _scan(_population(), tmp_path / "out")
    (tmp_path / "out" / SETTINGS_FILE).unlink()
    with pytest.raises(WbsaError, match="no settings.json"):
        _scan(_population(), tmp_path / "out")


@pytest.mark.parametrize("pop, match", [
    (pd.DataFrame({"id": [1, 2]}), "no subject_id"),
    (pd.DataFrame({"subject_id": [1, 1], "p_height": [0.5, 0.5]}), "duplicate subject id 1"),
    (pd.DataFrame({"subject_id": [-1, 2], "p_height": [0.5, 0.5]}), "negative"),
    (pd.DataFrame({"subject_id": [0.5, 2.0], "p_height": [0.5, 0.5]}), "not integer"),
    (pd.DataFrame({"subject_id": pd.Series([], dtype="int64")}), "no subjects"),
])
def test_bad_population_is_a_one_line_error(tmp_path, pop, match):
    with pytest.raises(WbsaError, match=match):
        _scan(pop, tmp_path / "out")


def test_error_in_a_chunk_keeps_the_finished_parts(tmp_path):
    with pytest.raises(WbsaError, match="subject 7"):
        _scan(_population(), tmp_path / "out", chunk_fn=failing_chunk)
    parts = sorted(p.name for p in (tmp_path / "out" / PARTS_DIR).iterdir())
    assert parts == ["part-00000000-00000003.parquet"]
    assert not (tmp_path / "out" / TABLE_FILE).exists()


def test_two_worker_local_cluster_equals_in_process(tmp_path, dask_cluster):
    """A real two-process dask cluster on loopback gives the same table as the in-process path."""
    from distributed import Client

    pop = _population(n=30, start=100)
    local = _scan(pop, tmp_path / "local").table
    with Client(dask_cluster) as client:
        res = _scan(pop, tmp_path / "dask", scheduler=dask_cluster)
        # The chunks really ran in the worker processes, not in this one.
        worker_pids = set(client.run(os.getpid).values())
        pids = _scan(pop, tmp_path / "pids", scheduler=dask_cluster, chunk_fn=pid_chunk).table["pid"]
        assert set(pids) <= worker_pids and os.getpid() not in worker_pids and len(worker_pids) == 2
    # Resume into a half-finished folder on the cluster, too.
    parts = sorted((tmp_path / "dask" / PARTS_DIR).iterdir())
    for p in parts[::3]:
        p.unlink()
    again = _scan(pop, tmp_path / "dask", scheduler=dask_cluster)
    pd.testing.assert_frame_equal(local, res.table)
    pd.testing.assert_frame_equal(local, again.table)
    assert again.n_resumed == len(parts) - len(parts[::3])


def test_scheduler_address_from_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", "tcp://127.0.0.1:1")
    monkeypatch.setattr(parallel, "CONNECT_TIMEOUT_S", 1)
    with pytest.raises(WbsaError, match="cannot reach the dask scheduler at tcp://127.0.0.1:1"):
        _scan(_population(), tmp_path / "out")


def test_worker_reuses_large_allocations_under_dask_malloc_settings():
    """dask's MALLOC_TRIM_THRESHOLD_ makes every large array fresh zeroed pages; the worker undoes that."""
    script = textwrap.dedent("""
        import resource
        import numpy as np
        from wbsa.scan.worker import keep_large_allocations

        def faults():
            before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
            for _ in range(50):
                a = np.ones(1 << 18)  # 2 MB
                del a
            return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before

        untuned = faults()
        keep_large_allocations()
        faults()
        print(untuned, faults())
    """)
    env = {**os.environ, "MALLOC_TRIM_THRESHOLD_": "65536"}
    out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True).stdout
    untuned, tuned = map(int, out.split())
    assert untuned > 50 * 400 and tuned < 50
