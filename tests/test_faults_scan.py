"""Fault injection on ``wbsa scan``: foreign, edited and corrupt parts, a second writer, kill -9, chunk sizes.

Each case ends with a one-line error (exit 2) naming the problem, or the correct result; and no file
that claims to be complete is not.
"""

from __future__ import annotations

import json
import os
import random
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pyarrow.parquet as pq
import pytest

from helpers.kill import kill_when
from test_scan_engine import VIEWS, _Camera, _population, stand_in_chunk
from wbsa.cli import main
from wbsa.errors import WbsaError
from wbsa.scan.engine import scan_population
from wbsa.scan.layout import PART_METADATA_KEY, PARTS_DIR, TABLE_FILE
from wbsa.scan.settings import ScanJob

SRC = str(Path(__file__).resolve().parents[1] / "src")


def _scan(pop, out, seed=0, chunk_size=4):
    return scan_population(pop, ScanJob(camera=_Camera(), views=VIEWS, seed=seed), out, chunk_size=chunk_size,
                           workers=1, chunk_fn=stand_in_chunk, show_progress=False)


def _python(code: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": SRC, "WBSA_PROGRESS": "0"}
    return subprocess.Popen([sys.executable, "-c", code], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)


def test_every_part_names_its_scan_and_chunk(tmp_path):
    res = _scan(_population(10), tmp_path / "s")
    settings_hash = json.loads((tmp_path / "s" / "settings.json").read_text())["settings_hash"]
    for path in sorted((tmp_path / "s" / PARTS_DIR).glob("part-*.parquet")):
        ident = json.loads(pq.read_schema(path).metadata[PART_METADATA_KEY])
        first, last = (int(x) for x in path.stem.split("-")[1:])
        assert (ident["settings_hash"], ident["first_id"], ident["last_id"]) == (settings_hash, first, last)
        assert ident["n_rows"] == pq.read_metadata(path).num_rows == ident["n_subjects"] * len(VIEWS)
    assert res.n_chunks == 3


def _damage_cases(out: Path, other: Path) -> dict:
    parts = sorted((out / PARTS_DIR).glob("part-*.parquet"))

    def foreign():  # a valid part of another scan (other seed) with the same name
        shutil.copyfile(other / PARTS_DIR / parts[1].name, parts[1])

    def plain_rewrite():  # values edited with pandas: wbsa's identity is gone
        df = pd.read_parquet(parts[1])
        df["vbsa_hit_m2"] *= 1.01
        df.to_parquet(parts[1], index=False)

    def edited_keeping_metadata():  # values edited, identity copied over: the row hash tells
        table = pq.read_table(parts[1])
        df = table.to_pandas()
        df.loc[0, "n_pixels"] += 1
        import pyarrow as pa

        edited = pa.Table.from_pandas(df, preserve_index=False).replace_schema_metadata(table.schema.metadata)
        pq.write_table(edited, parts[1])

    def truncated():  # cut short (a copy interrupted outside wbsa)
        data = parts[1].read_bytes()
        parts[1].write_bytes(data[: len(data) // 2])

    def other_chunking():  # a valid part of this scan under a name that is not a chunk of the plan
        parts[1].rename(parts[1].with_name("part-00000004-00000006.parquet"))

    return {"belongs to another scan": foreign, "was not written by wbsa scan": plain_rewrite,
            "changed after it was written": edited_keeping_metadata, "unreadable, corrupt or cut short": truncated,
            "not a chunk of this scan": other_chunking}


@pytest.mark.parametrize("case", ["belongs to another scan", "was not written by wbsa scan",
                                  "changed after it was written", "unreadable, corrupt or cut short",
                                  "not a chunk of this scan"])
def test_a_bad_part_is_refused_before_any_scanning(tmp_path, case):
    pop = _population(12)
    out, other = tmp_path / "s", tmp_path / "other"
    full = _scan(pop, out).table
    _scan(pop, other, seed=9)
    (out / TABLE_FILE).unlink()
    last = sorted((out / PARTS_DIR).glob("part-*.parquet"))[-1]
    last.unlink()  # a chunk still to scan: it must not be scanned before the check
    _damage_cases(out, other)[case]()
    calls = []

    def counting_chunk(subjects, settings):
        calls.append(len(subjects))
        return stand_in_chunk(subjects, settings)

    with pytest.raises(WbsaError, match=case) as info:
        scan_population(pop, ScanJob(camera=_Camera(), views=VIEWS), out, chunk_size=4, workers=1,
                        chunk_fn=counting_chunk, show_progress=False)
    assert "part-0000" in str(info.value) and "\n" not in str(info.value)
    assert calls == [] and not last.exists() and not (out / TABLE_FILE).exists()
    # the fix the message names works: delete the part, run again, get the uninterrupted table
    bad = str(info.value).split("scan part ", 1)[1].split(" ", 1)[0]
    Path(bad).unlink()
    pd.testing.assert_frame_equal(_scan(pop, out).table, full)


def test_a_second_writer_of_a_scan_folder_stops_with_one_line(tmp_path):
    pop = _population(6)
    out = tmp_path / "s"
    holder = _python(f"from wbsa.folder_lock import folder_lock\nimport time\n"
                     f"with folder_lock({str(out)!r}):\n    print('locked', flush=True)\n    time.sleep(60)\n")
    try:
        assert holder.stdout.readline().strip() == "locked"
        with pytest.raises(WbsaError, match="being written by another wbsa process") as info:
            _scan(pop, out)
        assert f"pid {holder.pid}" in str(info.value) and "\n" not in str(info.value)
        assert not (out / "settings.json").exists()  # it stopped before touching the folder
        os.killpg(holder.pid, signal.SIGKILL)  # a killed holder releases the lock at once
        holder.wait()
        assert len(_scan(pop, out).table) == 6 * len(VIEWS)
    finally:
        if holder.poll() is None:
            os.killpg(holder.pid, signal.SIGKILL)
            holder.wait()
        holder.stdout.close()
        holder.stderr.close()


@pytest.fixture(scope="module")
def real_population(tmp_path_factory):
    root = tmp_path_factory.mktemp("pop")
    assert main(["population", "--kind", "random", "--n", "5", "--seed", "4", "--out", str(root / "pop.parquet"),
                 "--workers", "1"]) == 0
    return root / "pop.parquet"


SCAN_ARGS = ("--azimuths", "0,90", "--elevations", "0,60", "--workers", "1", "--no-progress")


@pytest.mark.slow
def test_scan_bytes_do_not_depend_on_the_chunk_size(real_population, tmp_path):
    """Issue 12 item 7: chunk size changed results in the last bit (anny's batched pass); now the bytes are equal."""
    tables = []
    for chunk in (1, 2, 5):
        out = tmp_path / f"c{chunk}"
        assert main(["scan", str(real_population), "--out", str(out), "--chunk-size", str(chunk), *SCAN_ARGS]) == 0
        tables.append((out / TABLE_FILE).read_bytes())
    assert tables[0] == tables[1] == tables[2]


@pytest.mark.slow
def test_kill_9_at_random_points_of_a_scan_then_resume_gives_the_same_bytes(real_population, tmp_path):
    ref = tmp_path / "ref"
    assert main(["scan", str(real_population), "--out", str(ref), "--chunk-size", "1", *SCAN_ARGS]) == 0
    out = tmp_path / "killed"
    code = (f"import sys\nfrom wbsa.cli import main\nsys.exit(main(['scan', {str(real_population)!r}, '--out', "
            f"{str(out)!r}, '--chunk-size', '1', *{SCAN_ARGS!r}]))")
    rng = random.Random(5)
    total = len(list((ref / PARTS_DIR).glob("part-*.parquet")))

    def parts() -> int:
        return len(list((out / PARTS_DIR).glob("part-*.parquet")))

    for _ in range(2):  # two kills, each after a random number of parts; the run then resumes from what they left
        if parts() < total - 1:
            kill_when(_python(code), parts, rng.randint(parts() + 1, total - 1))
        for part in (out / PARTS_DIR).glob("part-*.parquet"):  # every part under its final name is whole
            pq.read_table(part)
    assert main(["scan", str(real_population), "--out", str(out), "--chunk-size", "1", *SCAN_ARGS]) == 0
    assert (out / TABLE_FILE).read_bytes() == (ref / TABLE_FILE).read_bytes()
    assert not [p for p in out.rglob("*.part*")]


@pytest.mark.slow
def test_views_with_the_camera_inside_the_body_are_marked_and_counted(real_population, tmp_path, capsys):
    """Behind and above the bounding-box centre at 0.1 m the camera is inside every body of this population
    (two of its subjects are scanned: a view from 0.1 m in front is seconds of grazing-triangle splits)."""
    two = tmp_path / "two.parquet"
    pq.write_table(pq.read_table(real_population).slice(0, 2), two)
    out = tmp_path / "inside"
    assert main(["scan", str(two), "--out", str(out), "--azimuths", "0,180", "--elevations", "60",
                 "--distance", "0.1", "--workers", "1", "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert "warning: 2 of 4 views put the camera inside the body" in err and err.count("\n") == 1
    table = pd.read_parquet(out / TABLE_FILE)
    assert len(table) == 4
    inside = table["camera_inside"].to_numpy()
    assert (table.loc[inside, "azimuth_deg"] == 180).all() and inside.sum() == 2
    assert (table.loc[inside, "n_pixels"] == 0).all() and table.loc[inside, "vbsa_visible_m2"].isna().all()
    assert table.loc[~inside, "vbsa_visible_m2"].gt(0).all()
    # wbsa view refuses the same view with one line
    rc = main(["view", "--population", str(real_population), "--subject", "1", "--azimuth", "180", "--elevation", "60",
               "--distance", "0.1"])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("error: ") and "inside the body" in err and err.count("\n") == 1
