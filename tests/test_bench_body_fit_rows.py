"""``benchmarks/bench_body_fit.py --rows`` and ``--noise-sweep``: a stopped run resumes to the uninterrupted table,
a folder of other settings is refused, the sweep's scales are checked and its paired differences are right.

The fits are replaced by a cheap stand-in whose rows depend on the image, renderer and noise scale only (the
resume and sweep machinery is what is judged here; one slow test draws two real captures).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from wbsa.errors import WbsaError

BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"


@pytest.fixture(scope="module")
def bench():
    sys.path.insert(0, str(BENCHMARKS))
    import bench_body_fit

    return bench_body_fit


def tiny_population(n: int, *_args) -> pd.DataFrame:
    """``n`` made-up subjects with the columns the benchmark reads (no body model)."""
    i = np.arange(n)
    return pd.DataFrame({"subject_id": i, "population": "random", "sex": np.where(i % 2, "male", "female"),
                         "age_years": 20.0 + 3 * i, "stature_m": 1.5 + 0.02 * i, "mass_kg": 50.0 + 4 * i,
                         "volume_m3": 0.05 + 0.004 * i, "wbsa_m2": 1.5 + 0.05 * i})


class StandIn:
    """A cheap ``fit_chunk``: per image and renderer, an error that depends on the image, renderer and noise scale;
    image 3 is refused. Records the images it fits; raises KeyboardInterrupt at its ``stop_at``-th call."""

    def __init__(self, stop_at: int | None = None):
        self.fitted: list[int] = []
        self.stop_at = stop_at

    def __call__(self, population, others, first, settings, displace, model_path, fit_settings) -> pd.DataFrame:
        if self.stop_at is not None and len(self.fitted) == self.stop_at:
            raise KeyboardInterrupt
        f = settings.capture.noise_scale[0]
        renderers = ("project", "plain") if settings.renderer == "both" else (settings.renderer,)
        rows = []
        for b, (_, s) in enumerate(population.iterrows()):
            index = first + b
            self.fitted.append(index)
            for r in renderers:
                row = {**s.to_dict(), "image": index, "renderer": r, "noise_scale": f, "error": ""}
                if index == 3:
                    rows.append({**row, "error": "no subject found; aim the camera at the subject"})
                    continue
                err = 0.01 * np.sin(index + 1) + 0.004 * f * (1.0 if r == "plain" else -1.0)
                rows.append({**row, "fit_wbsa_m2": s["wbsa_m2"] * (1 + err),
                             "fit_stature_m": s["stature_m"] + 0.005 * f, "seconds": 1.0})
        return pd.DataFrame(rows)


def fit(bench, pop, rows_dir, renderer="both", noise_scale=1.0, displace=False, stop=None):
    from wbsa.estimation.methods.body_fit import BodyFitSettings

    return bench.fit_rows(pop, bench.held_out_settings(1000, renderer, noise_scale), BodyFitSettings(), first=0,
                          stop=len(pop) if stop is None else stop, displace=displace, model_path=None,
                          rows_dir=None if rows_dir is None else str(rows_dir))


def test_scale_one_is_todays_captures(bench):
    """At noise scale 1 the captures are those the benchmark drew before the sweep existed; at another scale only
    the capture's noise scale differs."""
    from dataclasses import replace

    from wbsa.testing.testset import RoomTestSettings

    assert bench.held_out_settings(1000, "both", 1.0) == RoomTestSettings(seed=1000, renderer="both")
    other = bench.held_out_settings(1000, "both", 0.3)
    assert other.capture.noise_scale == (0.3, 0.3)
    assert replace(other, capture=RoomTestSettings().capture) == RoomTestSettings(seed=1000, renderer="both")


def test_stopped_run_resumes_to_the_uninterrupted_table(bench, monkeypatch, tmp_path):
    """Stopped after two captures, the same call again fits only the other three and gives the table of a run
    never stopped (and of a run keeping no rows); a chunk already kept is not rewritten."""
    pop = tiny_population(5)
    whole = StandIn()
    monkeypatch.setattr(bench, "fit_chunk", whole)
    reference = fit(bench, pop, None)
    uninterrupted = fit(bench, pop, tmp_path / "whole")

    stopped = StandIn(stop_at=2)
    monkeypatch.setattr(bench, "fit_chunk", stopped)
    with pytest.raises(KeyboardInterrupt):
        fit(bench, pop, tmp_path / "rows")
    assert sorted(p.name for p in (tmp_path / "rows").iterdir()) == ["chunk-000000.parquet", "chunk-000001.parquet",
                                                                    "run.json"]
    stamp = (tmp_path / "rows" / "chunk-000000.parquet").stat().st_mtime_ns
    rest = StandIn()
    monkeypatch.setattr(bench, "fit_chunk", rest)
    resumed = fit(bench, pop, tmp_path / "rows")
    assert rest.fitted == [2, 3, 4]
    assert (tmp_path / "rows" / "chunk-000000.parquet").stat().st_mtime_ns == stamp
    assert list(resumed["image"]) == [0, 0, 1, 1, 2, 2, 3, 3, 4, 4]
    assert list(resumed["renderer"][:2]) == ["project", "plain"]
    pd.testing.assert_frame_equal(resumed, uninterrupted, check_dtype=False)
    pd.testing.assert_frame_equal(resumed, reference, check_dtype=False)

    again = StandIn()
    monkeypatch.setattr(bench, "fit_chunk", again)
    pd.testing.assert_frame_equal(fit(bench, pop, tmp_path / "rows"), uninterrupted, check_dtype=False)
    assert again.fitted == []


def test_a_folder_of_other_settings_is_refused(bench, monkeypatch, tmp_path):
    """Other displacement, renderer, noise scale or subjects: refused with the fix, nothing fitted."""
    pop = tiny_population(3)
    monkeypatch.setattr(bench, "fit_chunk", StandIn())
    fit(bench, pop, tmp_path, stop=2)
    fit(bench, pop, tmp_path)  # another range of the same run's images shares the folder
    for subjects, change in ((pop, {"displace": True}), (pop, {"renderer": "plain"}), (pop, {"noise_scale": 0.3}),
                             (tiny_population(4), {})):
        probe = StandIn()
        monkeypatch.setattr(bench, "fit_chunk", probe)
        with pytest.raises(WbsaError, match="holds rows of another run .*give a new folder or remove it"):
            fit(bench, subjects, tmp_path, **change)
        assert probe.fitted == []


def run_main(bench, argv, capsys) -> str:
    bench.main(argv)
    return capsys.readouterr().out


def test_the_sweep_resumes_per_scale_and_pairs_the_scales(bench, monkeypatch, tmp_path, capsys):
    """``--noise-sweep 0,1,3 --rows DIR``: a subfolder per scale; stopped part-way, the same command again fits only
    the rest and prints the table of an uninterrupted run; the paired differences are those of the stand-in."""
    import bench_estimate

    monkeypatch.setattr(bench_estimate, "population", tiny_population)
    argv = ["--subjects", "4", "--renderer", "both", "--noise-sweep", "0,1,3"]
    monkeypatch.setattr(bench, "fit_chunk", StandIn())
    whole = run_main(bench, [*argv, "--rows", str(tmp_path / "whole")], capsys)
    assert sorted(p.name for p in (tmp_path / "whole").iterdir()) == ["scale-0", "scale-1", "scale-3"]

    monkeypatch.setattr(bench, "fit_chunk", StandIn(stop_at=6))  # all of scale 0, two captures of scale 1
    with pytest.raises(KeyboardInterrupt):
        run_main(bench, [*argv, "--rows", str(tmp_path / "rows")], capsys)
    rest = StandIn()
    monkeypatch.setattr(bench, "fit_chunk", rest)
    resumed = run_main(bench, [*argv, "--rows", str(tmp_path / "rows")], capsys)
    assert rest.fitted == [2, 3, 0, 1, 2, 3]
    table = whole[whole.index("noise sweep of the body fit"):]
    assert resumed[resumed.index("noise sweep of the body fit"):] == table

    # the stand-in's error moves by ±0.4 % per unit of scale (plain +, project −); image 3 refused everywhere
    lines = table.splitlines()
    paired = lines[lines.index(next(x for x in lines if x.startswith("mean signed WBSA error minus at 1x"))) + 1:]
    rows = {x.split()[0]: [float(v) for v in x.split()[1:]] for x in paired if x.split()[:1] in (["plain"], ["project"])}
    assert rows["plain"] == pytest.approx([-0.4, 0.0, 0.8], abs=1e-3)
    assert rows["project"] == pytest.approx([0.4, 0.0, -0.8], abs=1e-3)
    assert "worst: 0.80 %: met" in table
    by_scale = lines[lines.index(next(x for x in lines if x.startswith("renderer noise_factor"))) + 1:]
    by_scale = [x.split() for x in by_scale[:by_scale.index("")]]
    assert len(by_scale) == 6 and all(x[-5] == "3" and x[-1] == "1" for x in by_scale)  # n, refused
    assert [float(x[-2]) for x in by_scale] == [0.0, 0.5, 1.5] * 2  # fitted stature median, cm


@pytest.mark.parametrize("sweep", ["0,0.3,3", "0,1,x", "1", "0,1,1", "-1,1"])
def test_the_sweep_refuses_a_bad_list_before_anything_runs(bench, monkeypatch, capsys, sweep):
    """A list without 1, with a word, 1 alone, a scale twice or a negative one: one line naming the fix."""
    import bench_estimate

    monkeypatch.setattr(bench_estimate, "population", lambda *a: pytest.fail("the population was built"))
    with pytest.raises(SystemExit) as exc:
        bench.main([f"--noise-sweep={sweep}"])
    message = str(exc.value)
    assert message.startswith("error: --noise-sweep") and "\n" not in message
    assert ("must include 1" in message) if sweep == "0,0.3,3" else ("e.g. 0,0.3,1,3" in message)


def test_the_cli_refuses_another_runs_folder_in_one_line(bench, monkeypatch, tmp_path, capsys):
    import bench_estimate

    monkeypatch.setattr(bench_estimate, "population", tiny_population)
    monkeypatch.setattr(bench, "fit_chunk", StandIn())
    run_main(bench, ["--subjects", "3", "--renderer", "both", "--noise-sweep", "0,1", "--rows", str(tmp_path)],
             capsys)
    with pytest.raises(SystemExit) as exc:
        bench.main(["--subjects", "3", "--renderer", "both", "--noise-sweep", "0,1", "--displace",
                    "--rows", str(tmp_path)])
    message = str(exc.value)
    assert message.startswith("error: ") and "\n" not in message
    assert "other displace" in message and "give a new folder or remove it" in message


@pytest.mark.slow
def test_real_captures_reach_the_fit_at_each_scale(bench, monkeypatch, tmp_path):
    """Two real captures (the fit replaced by a digest of the depth it is given): scale 1 of the sweep draws the
    benchmark's captures, scale 0 the same views with no noise; kept rows read back as they were made."""
    from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters
    from wbsa.bodies.table import measure_population
    from wbsa.estimation.methods.body_fit import BodyFitSettings

    params = sample_random_parameters(RandomPopulationSettings(n=2, seed=5, age_years=(20, 60), age_sampling="years"))
    pop = measure_population(params, show_progress=False)
    pop["subject_id"] = range(len(pop))

    def digest(tc, drawn, subject, settings, displace, model_path, fit_settings, body_model) -> dict:
        depth = drawn[2]
        return {"image": tc.index, "renderer": drawn[0], "camera": drawn[1].name,
                "azimuth_deg": tc.capture.view.azimuth_deg, "noise_scale": tc.capture.sensor.effective_noise_scale,
                "depth_sum_m": float(depth.sum()), "error": ""}

    monkeypatch.setattr(bench, "fit_row", digest)
    plain = fit(bench, pop, None, renderer="project")
    sweep = bench.noise_sweep(pop, [0.0, 1.0], BodyFitSettings(), seed=1000, renderer="project",
                              rows_dir=str(tmp_path), first=0, stop=2, displace=False, model_path=None)
    at = {f: g.drop(columns="noise_factor").reset_index(drop=True) for f, g in sweep.groupby("noise_factor")}
    pd.testing.assert_frame_equal(at[1.0], plain, check_dtype=False)
    assert (at[0.0][["camera", "azimuth_deg"]].values == plain[["camera", "azimuth_deg"]].values).all()
    assert (at[0.0]["noise_scale"] == 0.0).all() and not np.allclose(at[0.0]["depth_sum_m"], plain["depth_sum_m"])
    kept = pd.concat([pd.read_parquet(p) for p in sorted((tmp_path / "scale-1").glob("chunk-*.parquet"))])
    pd.testing.assert_frame_equal(kept.reset_index(drop=True), plain, check_dtype=False)
