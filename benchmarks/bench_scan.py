"""Scan throughput end to end (views/s) against the bare Open3D ray casting of the same rays.

Usage::

    python benchmarks/bench_scan.py [--subjects 24] [--workers N] [--chunk-size 6] [--views paper]

Real anny bodies (``wbsa.population.body_model``), the camera stage's ``measure_view`` and the scan
engine, as ``wbsa scan`` runs them. In the same run:

* **floor**: every ray that the scan casts (ROI rays and any extra rays the visible-area estimate
  casts) is recorded, then cast again with bare ``RaycastingScene.cast_rays`` on one thread; the
  floor of a W-worker scan is that time / W (perfect scaling over W cores);
* **in-process** (``--workers 1``): ``scan_population`` end to end, body model already built;
* **dask, warm**: ``scan_population`` on a running W-worker local cluster whose workers have built
  the body model (the steady state of a long scan);
* **dask, cold**: ``scan_population(workers=W)`` including cluster start-up and the model build in
  every worker (what a short ``wbsa scan`` costs).

The issue's targets (2-core machine): >= 500 views/s end to end and the scan within 1.25x of the
bare ray-casting time. Timings are wall-clock on a shared machine: run it when the machine is quiet.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("WBSA_PROGRESS", "0")
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

TARGET_VIEWS_PER_S = 500.0
TARGET_RATIO = 1.25


def record_rays(scene, store: list, occlusions: list) -> None:
    """Make ``scene.cast_rays`` (and ``scene.occluded``, if the camera stage has it) keep a copy of every
    ray batch they get (instance-attribute wrappers around the bound methods)."""
    bare_cast = scene.cast_rays

    def cast_rays(rays):
        store.append(rays.copy())
        return bare_cast(rays)

    scene.cast_rays = cast_rays
    if hasattr(scene, "occluded"):
        bare_occluded = scene.occluded

        def occluded(rays, t_far):
            occlusions.append((rays.copy(), t_far))
            return bare_occluded(rays, t_far)

        scene.occluded = occluded


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", type=int, default=24)
    parser.add_argument("--workers", type=int, default=None, help="worker processes (default: all cores)")
    parser.add_argument("--chunk-size", type=int, default=6)
    parser.add_argument("--views", default="paper")
    parser.add_argument("--camera", default="kinect-v1")
    parser.add_argument("--skip-cold", action="store_true", help="skip the cold-start dask run")
    args = parser.parse_args()

    import numpy as np

    from wbsa.camera.intrinsics import resolve_camera
    from wbsa.camera.measure import measure_view
    from wbsa.camera.raycast import MeshScene
    from wbsa.camera.views import parse_views
    from wbsa.parallel import dask_client, default_workers
    from wbsa.population.random_population import RandomPopulationSettings, sample_random_parameters
    from wbsa.scan.engine import scan_population
    from wbsa.scan.settings import ScanSettings
    from wbsa.scan.worker import body_model

    workers = args.workers or default_workers()
    camera = resolve_camera(args.camera)
    views = tuple(parse_views(args.views))
    settings = ScanSettings(camera=camera, views=views, chunk_size=args.chunk_size)
    params = sample_random_parameters(RandomPopulationSettings(n=args.subjects, seed=0))
    n_views = args.subjects * len(views)

    t0 = time.perf_counter()
    model = body_model()
    model_s = time.perf_counter() - t0
    warm_scene = MeshScene(model.skin_meshes(params.iloc[:1])[0])  # imports Open3D: not part of any timing
    measure_view(warm_scene, camera, views[0], warm_scene.center, return_frame=False)

    # -- stage breakdown in this process (wall and CPU), recording every ray batch --------------
    clock = Clock()
    with clock:
        meshes = model.skin_meshes(params)
    bodies = clock.result()
    scene_t = Clock()
    measure_t = Clock()
    rays: list[tuple[object, list]] = []
    for mesh in meshes:
        with scene_t:
            scene = MeshScene(mesh, nthreads=1)
        store: list = []
        occ: list = []
        record_rays(scene, store, occ)
        with measure_t:
            for view in views:
                measure_view(scene, camera, view, scene.center, return_frame=False)
        rays.append((MeshScene(mesh, nthreads=1), store, occ))
    for scene, store, _ in rays:  # build each BVH (Open3D builds it lazily, at the first cast)
        scene.cast_rays(store[0][:1])

    # -- the floor: bare cast_rays on exactly those rays, one thread, best of two passes ----------
    # (and, separately, the occlusion tests of the visible-area estimate, another Open3D ray query)
    bare = occl = (np.inf, np.inf)
    for _ in range(2):
        c = Clock()
        with c:
            for scene, store, _ in rays:
                for batch in store:
                    scene.cast_rays(batch)
        bare = min(bare, c.result())
        c = Clock()
        with c:
            for scene, _, occ in rays:
                for batch, t_far in occ:
                    scene.occluded(batch, t_far)
        occl = min(occl, c.result())
    n_rays = sum(len(b) for _, store, _ in rays for b in store)
    n_batches = sum(len(store) for _, store, _ in rays)
    n_occ = sum(len(b) for _, _, occ in rays for b, _ in occ)

    with tempfile.TemporaryDirectory() as tmp:
        # -- in-process end to end ----------------------------------------------------------
        c = Clock()
        with c:
            local = scan_population(params, settings, Path(tmp) / "local", workers=1).table
        local_t = c.result()

        # -- dask, warm cluster: CPU = this process + every worker ------------------------------
        with dask_client(workers) as client:
            client.run(_warm_worker)
            cpu0 = sum(client.run(time.process_time).values())
            c = Clock()
            with c:
                warm = scan_population(params, settings, Path(tmp) / "warm", scheduler=client.scheduler.address).table
            worker_cpu = sum(client.run(time.process_time).values()) - cpu0
            warm_t = (c.result()[0], c.result()[1] + worker_cpu)
        same = local.equals(warm)

        cold_t = (float("nan"), float("nan"))
        if not args.skip_cold:
            c = Clock()
            with c:
                scan_population(params, settings, Path(tmp) / "cold", workers=workers)
            cold_t = (c.result()[0], float("nan"))

    bare_w = (bare[0] / workers, bare[1] / workers)
    print(f"scan benchmark: {args.subjects} subjects x {len(views)} views = {n_views} views, camera {camera.name}, "
          f"{workers} workers, chunk {args.chunk_size}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}")
    print(f"rays cast: {n_rays / n_views:,.0f} per view in {n_batches / n_views:.1f} batches per view; "
          f"occlusion-test rays: {n_occ / n_views:,.0f} per view")
    print(f"body model build (cached, once per process): {model_s:.2f} s")
    print("stage breakdown, one process (wall / CPU):")
    for label, (w, cpu), per in (("anny bodies (batched)", bodies, args.subjects),
                                 ("MeshScene per body", scene_t.result(), args.subjects),
                                 ("measure_view", measure_t.result(), n_views),
                                 ("bare cast_rays (floor)", bare, n_views),
                                 ("bare test_occlusions", occl, n_views)):
        unit = "body" if per == args.subjects else "view"
        print(f"  {label:24s} {w / per * 1e3:8.2f} / {cpu / per * 1e3:8.2f} ms/{unit}   "
              f"= {w / n_views * 1e3:6.3f} / {cpu / n_views * 1e3:6.3f} ms/view")
    print(f"  measure_view overhead over the floor: {(measure_t.result()[1] - bare[1]) / n_views * 1e3:.2f} ms CPU/view "
          f"({(measure_t.result()[1] - bare[1] - occl[1]) / n_views * 1e3:.2f} ms without the occlusion tests)")
    print(f"{'path':38s} {'wall s':>8s} {'views/s':>8s} {'x floor':>8s} {'CPU s':>8s} {'x floor':>8s}")
    # Wall time against the floor of the same number of cores; CPU time against the bare casts' CPU time.
    rows = [
        ("bare cast_rays, 1 thread", bare, bare[0]),
        (f"bare cast_rays / {workers} ({workers}-core floor)", bare_w, bare_w[0]),
        ("scan, in-process (--workers 1)", local_t, bare[0]),
        (f"scan, dask {workers} workers, warm", warm_t, bare_w[0]),
        (f"scan, dask {workers} workers, cold", cold_t, bare_w[0]),
    ]
    for label, (w, cpu), wall_floor in rows:
        print(f"{label:38s} {w:8.2f} {n_views / w:8.0f} {w / wall_floor:8.2f} {cpu:8.2f} {cpu / bare[1]:8.2f}")
    rate = n_views / warm_t[0]
    ratio = warm_t[0] / bare_w[0]
    print(f"end to end (warm, {workers} workers): {rate:.0f} views/s (target >= {TARGET_VIEWS_PER_S:.0f}: "
          f"{'met' if rate >= TARGET_VIEWS_PER_S else 'NOT met'}); ratio to bare ray casting {ratio:.2f} "
          f"(target <= {TARGET_RATIO}: {'met' if ratio <= TARGET_RATIO else 'NOT met'}); "
          f"CPU ratio {warm_t[1] / bare[1]:.2f} (to cast_rays + test_occlusions: {warm_t[1] / (bare[1] + occl[1]):.2f})")
    print(f"in-process and dask tables identical: {same}")


class Clock:
    """Wall-clock and CPU seconds of a ``with`` block (accumulates over several blocks)."""

    def __init__(self) -> None:
        self.wall = self.cpu = 0.0

    def __enter__(self) -> "Clock":
        self._w, self._c = time.perf_counter(), time.process_time()
        return self

    def __exit__(self, *exc) -> None:
        self.wall += time.perf_counter() - self._w
        self.cpu += time.process_time() - self._c

    def result(self) -> tuple[float, float]:
        return self.wall, self.cpu


def _warm_worker() -> None:
    """Build the body model and import Open3D in a worker before the timed run."""
    from wbsa.camera import MeshScene
    from wbsa.population.mesh import TriangleMesh
    from wbsa.scan.worker import body_model

    body_model()
    import numpy as np

    MeshScene(TriangleMesh(np.eye(3), np.array([[0, 1, 2]], dtype=np.int32)))


if __name__ == "__main__":
    main()
