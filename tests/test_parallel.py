"""wbsa.parallel.map_chunks: results in argument order, in process or on a local dask cluster."""

from __future__ import annotations

import time

import pytest

from wbsa.parallel import map_chunks


def _slow_square(x: int) -> int:
    time.sleep(0.05 * (3 - x))  # later chunks finish first on a cluster
    return x * x


def test_map_chunks_in_process_keeps_order_and_reports_each_result():
    seen = []
    assert map_chunks(_slow_square, [(0,), (1,), (2,)], workers=1, tag="t", on_result=seen.append) == [0, 1, 4]
    assert seen == [0, 1, 4]


@pytest.mark.slow  # starts a two-worker dask cluster (a few seconds)
def test_map_chunks_on_a_cluster_gives_the_same_list():
    seen = []
    assert map_chunks(_slow_square, [(0,), (1,), (2,)], workers=2, tag="t", on_result=seen.append) == [0, 1, 4]
    assert sorted(seen) == [0, 1, 4]
