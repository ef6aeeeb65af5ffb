"""Projected wall time of the paper's study (19,995 subjects x 65 views, all four stages) on this machine.

Usage::

    python benchmarks/bench_paper_scale.py [--subjects 60,240] [--workers N] [--backends open3d,warp]
                                           [--repeat 1] [--skip-paper-fit]

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
    parser.add_argument("--backends", default="open3d,warp", help="ray-casting back ends of the scan stage")
    parser.add_argument("--repeat", type=int, default=1, help="runs per size (median reported)")
    parser.add_argument("--skip-paper-fit", action="store_true",
                        help="project the fit and report stages from the small runs instead of timing them at 19,995")
    args = parser.parse_args()

    from wbsa.camera.backends import resolve_backend
    from wbsa.parallel import default_workers

    sizes = sorted(int(x) for x in args.subjects.split(","))
    if len(sizes) < 2:
        parser.error("--subjects needs two sizes or more, e.g. 60,240")
    workers = args.workers or default_workers()
    backends = [resolve_backend(b.strip()) for b in args.backends.split(",") if b.strip()]
    runs: dict[str, dict[int, list]] = {b: {n: [] for n in sizes} for b in backends}
    with tempfile.TemporaryDirectory() as tmp:
        for backend in backends:
            run_once(sizes[0], workers, backend, Path(tmp))  # warm-up: imports, caches, compiled kernels
        for _ in range(args.repeat):
            for n in sizes:
                for backend in backends:
                    runs[backend][n].append(run_once(n, workers, backend, Path(tmp)))
        direct = {} if args.skip_paper_fit else paper_fit_and_report(Path(tmp))
    for s in direct:
        print(f"{s} stage timed at 19,995 x 65 (synthetic tables): {direct[s][0]:.0f} s wall, {direct[s][1]:.0f} s CPU")
    for backend in backends:
        report(runs[backend], sizes, direct, workers, backend)


def report(runs: dict[int, list], sizes: list[int], direct: dict, workers: int, backend: str) -> None:
    """Print one back end's stage table and projection."""
    import numpy as np

    names = ["population", "scan", "fit", "report"]
    med = {n: {s: tuple(statistics.median(r[s][i] for r in runs[n]) for i in (0, 1)) for s in names + ["all"]}
           for n in sizes}
    x = np.array(sizes, dtype=float)

    def project(values: list[float]) -> tuple[float, float, float]:
        """(intercept s, slope s/subject, value at the paper's size) of a least-squares line through the sizes."""
        slope, intercept = np.polyfit(x, values, 1)
        return intercept, slope, intercept + slope * PAPER_SUBJECTS

    print(f"\npaper-scale projection, back end {backend}: paper config, sizes {sizes} subjects x 65 views, "
          f"{workers} workers, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}, "
          f"{len(runs[sizes[0]])} run(s) per size (medians)")
    print(f"{'stage':12s} " + " ".join(f"{f'{n} s':>9s}" for n in sizes)
          + f" {'start s':>8s} {'rate':>17s} {'19,995 min':>11s} {'CPU min':>8s}")
    total = total_cpu = 0.0
    cores = min(workers, os.cpu_count() or workers)
    for s in names:
        a, b, proj = project([med[n][s][0] for n in sizes])
        cpu_b, cpu_proj = project([med[n][s][1] for n in sizes])[1:]
        if s in direct:
            proj, cpu_proj = direct[s]
            rate = "timed at 19,995"
        elif s == "population":
            rate = f"{1 / b:,.1f} subjects/s" if b > 0 else "n/a"
        elif s == "scan":
            rate = f"{65 / b:,.0f} views/s" if b > 0 else "n/a"
            if b > 0 and 65 / b > 65 * cores / cpu_b:  # faster than its own CPU time allows: load changed
                rate += "!"
        else:
            rate = f"{b * 1e3:,.1f} ms/subject"
        total += proj
        total_cpu += cpu_proj
        print(f"{s:12s} " + " ".join(f"{med[n][s][0]:9.1f}" for n in sizes)
              + f" {a:8.1f} {rate:>17s} {proj / 60:11.1f} {cpu_proj / 60:8.1f}")
    print(f"{'all':12s} " + " ".join(f"{med[n]['all'][0]:9.1f}" for n in sizes)
          + f" {'':8s} {'':17s} {total / 60:11.1f} {total_cpu / 60:8.1f}")
    scan_cpu_view = project([med[n]["scan"][1] for n in sizes])[1] / 65
    print(f"scan CPU per view (all processes, slope): {scan_cpu_view * 1e3:.2f} ms -> at most "
          f"{cores / scan_cpu_view:,.0f} views/s on {cores} idle cores ('!' above: a wall slope faster than that, "
          f"i.e. other jobs slowed the smaller run)")
    print(f"paper study ({backend}) projected on {cores} cores: {total_cpu / cores / 60:.1f} min from the CPU time / "
          f"{cores} cores (target <= {TARGET_MIN:.0f} min: {'met' if total_cpu / cores / 60 <= TARGET_MIN else 'NOT met'}); "
          f"{total / 60:.1f} min from the wall times as measured here")


if __name__ == "__main__":
    main()
