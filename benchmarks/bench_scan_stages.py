"""Where a scan's CPU time per view goes, by stage, for both ray-casting back ends (one process, one thread).

Usage::

    python benchmarks/bench_scan_stages.py [--subjects 12] [--views paper] [--camera kinect-v1]

Real anny bodies, one at a time as the scan worker builds them, each measured at every view by both back
ends the way a dask worker runs them (one Open3D thread, single-threaded math); CPU time of this
process. Printed per view: the body (anny), the ``MeshScene``, Embree's BVH build, each back end's
``measure_views`` with its parts (Open3D: the pixel rays' ``cast_rays``, the grazing points' any-hit
rays, the rest = numpy; Warp: every kernel by its launches, the any-hit rays, the rest = host work), the
whole in-process ``scan_population`` per back end (adds the rows, the Parquet parts and the final
table), and the floor: bare ``cast_rays`` of exactly the pixel rays the Open3D back end casts. The
ratios to the floor are the CPU side of issue 13's target (end to end within 1.25x of the floor);
``bench_scan.py`` measures the same end to end on a warm dask cluster.
"""

from __future__ import annotations

import argparse
import collections
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("WBSA_PROGRESS", "0")
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", type=int, default=12)
    parser.add_argument("--views", default="paper")
    parser.add_argument("--camera", default="kinect-v1")
    args = parser.parse_args()

    import numpy as np

    import wbsa.scan.worker as worker
    from wbsa.bodies.random_population import RandomPopulationSettings, sample_random_parameters
    from wbsa.camera import MeshScene
    from wbsa.camera.backends import measure_views
    from wbsa.camera.backends.warp_backend import warp_module
    from wbsa.camera.presets import resolve_camera
    from wbsa.camera.views import parse_views
    from wbsa.scan.engine import scan_population
    from wbsa.scan.settings import ScanJob

    worker.cast_threads = lambda: 1  # as in a dask worker (one worker per core)
    params = sample_random_parameters(RandomPopulationSettings(n=args.subjects, seed=0))
    cam = resolve_camera(args.camera)
    views = tuple(parse_views(args.views))
    n_views = args.subjects * len(views)
    model = worker.body_model()
    worker.keep_large_allocations()
    wp = warp_module()
    clock = time.process_time
    t = collections.defaultdict(float)
    bare_launch = wp.launch

    def timed_launch(kernel, *a, **k):
        t0 = clock()
        out = bare_launch(kernel, *a, **k)
        t[f"warp: kernel {kernel.key}"] += clock() - t0
        return out

    warm = MeshScene(model.skin_meshes(params.iloc[:1])[0], nthreads=1)
    for b in ("open3d", "warp"):  # imports, kernel compilation or cache load
        measure_views(warm, cam, views[:3], backend=b, return_frames=False)
    with worker.single_threaded_math():
        for i in range(args.subjects):
            t0 = clock()
            mesh = model.skin_meshes(params.iloc[i:i + 1])[0]
            t["body (anny, one at a time)"] += clock() - t0
            t0 = clock()
            scene = MeshScene(mesh, nthreads=1)
            t["MeshScene"] += clock() - t0
            cast_rays, occluded = scene.cast_rays, scene.occluded
            t0 = clock()
            cast_rays(np.zeros((1, 6), np.float32))
            t["Embree BVH build (first cast)"] += clock() - t0
            rays: list = []
            who = ["open3d"]

            def recording_cast(r):
                rays.append(r.copy())
                t0 = clock()
                out = cast_rays(r)
                t["open3d: pixel rays (cast_rays)"] += clock() - t0
                return out

            def timed_occluded(r, t_far):
                t0 = clock()
                out = occluded(r, t_far)
                t[f"{who[0]}: any-hit rays (test_occlusions)"] += clock() - t0
                return out

            scene.cast_rays, scene.occluded = recording_cast, timed_occluded
            t0 = clock()
            measure_views(scene, cam, views, backend="open3d", return_frames=False)
            t["open3d: measure_views"] += clock() - t0
            who[0] = "warp"
            wp.launch = timed_launch
            t0 = clock()
            measure_views(scene, cam, views, backend="warp", return_frames=False)
            t["warp: measure_views"] += clock() - t0
            wp.launch = bare_launch
            t0 = clock()
            for r in rays:
                cast_rays(r)
            t["floor: bare cast_rays of the same rays"] += clock() - t0
        with tempfile.TemporaryDirectory() as tmp:
            for b in ("open3d", "warp"):
                job = ScanJob(camera=cam, views=views, backend=b)
                scan_population(params.iloc[:1], job, Path(tmp) / f"warm-{b}", workers=1)
                t0 = clock()
                scan_population(params, job, Path(tmp) / b, workers=1, chunk_size=6)
                t[f"{b}: scan_population, in-process"] += clock() - t0
    for b in ("open3d", "warp"):
        parts = sum(v for k, v in t.items() if k.startswith(f"{b}: ") and ("kernel" in k or "rays" in k))
        t[f"{b}: rest of measure_views (numpy / host)"] = t[f"{b}: measure_views"] - parts

    floor = t["floor: bare cast_rays of the same rays"]
    print(f"scan stages: {args.subjects} bodies x {len(views)} views, camera {cam.name}, one thread, "
          f"load average {os.getloadavg()[0]:.1f}; CPU ms per view (x floor)")
    for key in sorted(t, key=lambda k: (k.split(":")[0], -t[k])):
        print(f"  {key:48s} {t[key] / n_views * 1e3:7.3f}  ({t[key] / floor:5.2f}x)")


if __name__ == "__main__":
    main()
