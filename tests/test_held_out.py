"""The held-out captures drawn by both renderers, and a benchmark that resumes after a stop."""

from __future__ import annotations

import pytest

from wbsa.errors import WbsaError

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def two_subjects():
    from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters
    from wbsa.bodies.table import measure_population

    params = sample_random_parameters(RandomPopulationSettings(n=2, seed=5, age_years=(20, 60), age_sampling="years"))
    pop = measure_population(params, show_progress=False)
    pop["subject_id"] = range(len(pop))
    return pop


def test_both_renderers_side_by_side_and_resume(two_subjects, tmp_path):
    """Two rows per capture (project, plain) on the same subject and camera; a run given the same rows folder
    reads the chunks it finds and captures only the missing one, to the same table; other settings are refused."""
    from wbsa.testing.testset import RoomTestSettings, run_room_tests

    settings = RoomTestSettings(renderer="both", second_person=0.0)
    rows = tmp_path / "rows"
    first = run_room_tests(two_subjects, settings, None, chunk=1, rows_dir=str(rows))
    assert list(first["renderer"]) == ["plain", "project", "plain", "project"]
    assert (first.groupby("image")["camera"].nunique() == 1).all()
    assert (first.groupby("image")["wbsa_m2"].nunique() == 1).all()
    kept = rows / "chunk-000000.parquet"
    stamp = kept.stat().st_mtime_ns
    (rows / "chunk-000001.parquet").unlink()  # as if stopped before the second chunk
    again = run_room_tests(two_subjects, settings, None, chunk=1, rows_dir=str(rows))
    assert kept.stat().st_mtime_ns == stamp
    cols = ["image", "renderer", "camera", "est_wbsa_m2", "est_stature_m", "flags"]
    assert again[cols].equals(first[cols])
    with pytest.raises(WbsaError, match="another run"):
        run_room_tests(two_subjects, RoomTestSettings(renderer="plain"), None, chunk=1, rows_dir=str(rows))
