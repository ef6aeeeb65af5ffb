"""Projected wall time of the paper's study (19,995 subjects x 65 views, all four stages) on this machine.

Usage::

    python benchmarks/bench_paper_scale.py [--subjects 60,240] [--workers N] [--backend open3d] [--repeat 1]
                                           [--skip-paper-fit]

The paper's study config (``wbsa run --config paper``: Virtual Random population, Kinect v1 at 4.3 m,
the 65 views, per-view fits with 10-fold CV, the report) is run end to end with ``run_study`` at two
small population sizes (after one untimed warm-up run). Each stage's wall time is fitted as
``a + b · subjects`` (start-up plus a per-subject cost) and projected to 19,995 subjects; the printed
rates are the per-subject slopes (population: subjects/s; scan: views/s). The fit and report stages do
not grow in proportion to the subjects (thousands of small fits, a fixed set of figures), so they are
timed directly at the paper's size instead: ``run_fit`` and ``build_report`` on synthetic tables of
19,995 subjects x 65 views (``tests/helpers/synthetic.py``; the report then lacks only the body
snapshot figure, whose cost does not depend on the size). ``--backend`` picks the ray-casting back end
of the scan stage (the study itself has no such key yet). The CPU time of all processes of the small
runs is reported as well: on a shared machine it is the better measure of what two idle cores would
take (CPU / cores, assuming perfect scaling).

Target (issue 13): the paper's study projected on 2 cores <= 45 min; on a GPU (when lent) the scan
<= 2 min. The repeat medians guard against other jobs on the machine.
"""

from __future__ import annotations

import argparse
import functools
import os
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("WBSA_PROGRESS", "0")
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # helpers: test meshes and tables

PAPER_SUBJECTS = 19_995
TARGET_MIN = 45.0


def scan_chunk_with_backend(subjects, settings, backend: str):
    """The scan stage's chunk function with another ray-casting back end."""
    import dataclasses

    from wbsa.scan.worker import scan_chunk

    return scan_chunk(subjects, dataclasses.replace(settings, backend=backend))


def cpu_seconds() -> float:
    """CPU seconds of this process and of its finished children (the dask workers, once their cluster closed)."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def run_once(n: int, workers: int, backend: str, tmp: Path) -> dict[str, tuple[float, float]]:
    """Run the paper config with ``n`` subjects: stage -> (wall, CPU) seconds, and ``all``."""
    from wbsa.study import pipeline
    from wbsa.study.settings import load_settings

    config = tmp / f"paper-{n}.toml"
    config.write_text(f'[population]\nkind = "random"\nn = {n}\n\n[run]\nchunk_size = 50\n')
    settings = load_settings(config)
    chunk_fn = None if backend == "open3d" else functools.partial(scan_chunk_with_backend, backend=backend)
    times: dict[str, tuple[float, float]] = {}
    saved = {}
    for stage in ("population", "scan", "fit", "report"):
        name = f"_{stage}_stage"
        saved[name] = getattr(pipeline, name)

        def timed(*a, _stage=stage, _fn=saved[name], **kw):
            c0, w0 = cpu_seconds(), time.perf_counter()
            try:
                return _fn(*a, **kw)
            finally:
                wall, cpu = times.get(_stage, (0.0, 0.0))
                times[_stage] = (wall + time.perf_counter() - w0, cpu + cpu_seconds() - c0)

        setattr(pipeline, name, timed)
    try:
        c0, w0 = cpu_seconds(), time.perf_counter()
        pipeline.run_study(settings, tmp / f"study-{n}-{time.monotonic_ns()}", workers=workers, stream=None,
                           show_progress=False, scan_chunk_fn=chunk_fn)
        times["all"] = (time.perf_counter() - w0, cpu_seconds() - c0)
    finally:
        for name, fn in saved.items():
            setattr(pipeline, name, fn)
    return times


def paper_fit_and_report(tmp: Path) -> dict[str, tuple[float, float]]:
    """(wall, CPU) seconds of the fit stage (``run_fit``) and the report stage (``build_report``) on synthetic
    paper-size tables (19,995 subjects x 65 views), with the paper config's fit and report settings."""
    from wbsa.analysis.outputs import run_fit
    from helpers.synthetic import paper_view_angles, synthetic_population, synthetic_scan
    from wbsa.report.build import build_report
    from wbsa.report.sources import fit_dir_sources
    from wbsa.study.settings import fit_settings, load_settings

    settings = load_settings("paper")
    pop = synthetic_population(PAPER_SUBJECTS, seed=0)
    pop.to_parquet(tmp / "population.parquet", index=False)
    synthetic_scan(pop, paper_view_angles(), seed=0).to_parquet(tmp / "scan.parquet", index=False)
    out = {}
    c0, w0 = time.process_time(), time.perf_counter()
    run_fit(tmp / "population.parquet", tmp / "scan.parquet", tmp / "fit", fit_settings(settings),
            tuple(settings.fit.correlation_view_deg), nearest_correlation_view=True)
    out["fit"] = (time.perf_counter() - w0, time.process_time() - c0)
    c0, w0 = time.process_time(), time.perf_counter()
    build_report(fit_dir_sources(tmp / "fit"), tmp / "report.html", settings.report)
    out["report"] = (time.perf_counter() - w0, time.process_time() - c0)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", default="60,240", help="two (or more) population sizes to run")
    parser.add_argument("--workers", type=int, default=None, help="worker processes (default: all cores)")
    parser.add_argument("--backend", default="open3d", help="ray-casting back end of the scan stage")
    parser.add_argument("--repeat", type=int, default=1, help="runs per size (median reported)")
    parser.add_argument("--skip-paper-fit", action="store_true",
                        help="project the fit and report stages from the small runs instead of timing them at 19,995")
    args = parser.parse_args()

    import numpy as np

    from wbsa.camera.backends import resolve_backend
    from wbsa.parallel import default_workers

    sizes = sorted(int(x) for x in args.subjects.split(","))
    if len(sizes) < 2:
        parser.error("--subjects needs two sizes or more, e.g. 60,240")
    workers = args.workers or default_workers()
    backend = resolve_backend(args.backend)
    runs: dict[int, list] = {n: [] for n in sizes}
    with tempfile.TemporaryDirectory() as tmp:
        run_once(sizes[0], workers, backend, Path(tmp))  # warm-up: imports, caches, compiled kernels
        for _ in range(args.repeat):
            for n in sizes:
                runs[n].append(run_once(n, workers, backend, Path(tmp)))
        direct = {} if args.skip_paper_fit else paper_fit_and_report(Path(tmp))

    names = ["population", "scan", "fit", "report"]
    med = {n: {s: tuple(statistics.median(r[s][i] for r in runs[n]) for i in (0, 1)) for s in names + ["all"]}
           for n in sizes}
    x = np.array(sizes, dtype=float)

    def project(values: list[float]) -> tuple[float, float, float]:
        """(intercept s, slope s/subject, value at the paper's size) of a least-squares line through the sizes."""
        slope, intercept = np.polyfit(x, values, 1)
        return intercept, slope, intercept + slope * PAPER_SUBJECTS

    print(f"paper-scale projection: paper config, sizes {sizes} subjects x 65 views, {workers} workers, back end "
          f"{backend}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}, {args.repeat} run(s) per size "
          f"(medians)")
    print(f"{'stage':12s} " + " ".join(f"{f'{n} s':>9s}" for n in sizes)
          + f" {'start s':>8s} {'rate':>17s} {'19,995 min':>11s} {'CPU min':>8s}")
    total = total_cpu = 0.0
    for s in names:
        a, b, proj = project([med[n][s][0] for n in sizes])
        cpu_proj = project([med[n][s][1] for n in sizes])[2]
        if s in direct:
            proj, cpu_proj = direct[s]
            rate = "timed at 19,995"
        elif s == "population":
            rate = f"{1 / b:,.1f} subjects/s" if b > 0 else "n/a"
        elif s == "scan":
            rate = f"{65 / b:,.0f} views/s" if b > 0 else "n/a"
        else:
            rate = f"{b * 1e3:,.1f} ms/subject"
        total += proj
        total_cpu += cpu_proj
        print(f"{s:12s} " + " ".join(f"{med[n][s][0]:9.1f}" for n in sizes)
              + f" {a:8.1f} {rate:>17s} {proj / 60:11.1f} {cpu_proj / 60:8.1f}")
    print(f"{'all':12s} " + " ".join(f"{med[n]['all'][0]:9.1f}" for n in sizes)
          + f" {'':8s} {'':17s} {total / 60:11.1f} {total_cpu / 60:8.1f}")
    cores = min(workers, os.cpu_count() or workers)
    print(f"paper study projected on {cores} cores: {total / 60:.1f} min wall as measured here; "
          f"{total_cpu / cores / 60:.1f} min from the CPU time / {cores} cores (target <= {TARGET_MIN:.0f} min: "
          f"{'met' if total / 60 <= TARGET_MIN else 'NOT met'} / "
          f"{'met' if total_cpu / cores / 60 <= TARGET_MIN else 'NOT met'})")


if __name__ == "__main__":
    main()
