"""Ray-casting speed: full frame vs ROI vs the bare Open3D cast on the same rays, 65 paper views.

Usage::

    python benchmarks/bench_raycast.py [--camera kinect-v1] [--repeat 5] [--threads 0] [--anny]

For every path the 65 paper views are timed ``--repeat`` times and the fastest pass is reported
(the build machine is shared; the minimum is the least disturbed estimate). Ratios are against the
bare ``RaycastingScene.cast_rays`` call on exactly the ROI rays, which no wrapper can beat.
``--anny`` adds a real body from ``wbsa.population.body_model`` when that module exists.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from wbsa.camera import (MeshScene, measure_view, paper_views, pose_from_view,  # noqa: E402
                         render, resolve_camera)
from wbsa.camera.raycast import cast, projected_roi, roi_rays  # noqa: E402
from wbsa.camera.shapes import body_like  # noqa: E402


def best_pass(fn, views, repeat: int) -> float:
    """Fastest of ``repeat`` passes over ``views``, seconds per view."""
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        for v in views:
            fn(v)
        best = min(best, time.perf_counter() - t0)
    return best / len(views)


def bench(name: str, mesh, intrinsics, repeat: int, threads: int) -> None:
    t0 = time.perf_counter()
    scene = MeshScene(mesh, nthreads=threads)
    build_s = time.perf_counter() - t0
    views = paper_views()
    poses = {v: pose_from_view(v, scene.center) for v in views}
    roi_ray_sets = {v: roi_rays(intrinsics, poses[v], projected_roi(scene, intrinsics, poses[v])) for v in views}
    full_rect = (0, intrinsics.height, 0, intrinsics.width)
    full_ray_sets = {v: roi_rays(intrinsics, poses[v], full_rect) for v in views}

    # Same result first: ROI and full frame must hit the same triangles at every pixel.
    for v in views:
        a = render(scene, intrinsics, poses[v], roi=True)
        b = render(scene, intrinsics, poses[v], roi=False)
        assert np.array_equal(a.triangle_id, b.triangle_id), f"ROI differs from full frame at {v}"

    timings = {
        "bare cast_rays, ROI rays (floor)": best_pass(lambda v: scene.cast_rays(roi_ray_sets[v]), views, repeat),
        "bare cast_rays, full-frame rays": best_pass(lambda v: scene.cast_rays(full_ray_sets[v]), views, repeat),
        "cast(roi=True) (compact)": best_pass(lambda v: cast(scene, intrinsics, poses[v]), views, repeat),
        "measure_view(return_frame=False)": best_pass(
            lambda v: measure_view(scene, intrinsics, v, return_frame=False), views, repeat),
        "render(roi=True) -> DepthFrame": best_pass(lambda v: render(scene, intrinsics, poses[v]), views, repeat),
        "render(roi=False) -> DepthFrame": best_pass(
            lambda v: render(scene, intrinsics, poses[v], roi=False), views, repeat),
        "measure_view(return_frame=True)": best_pass(lambda v: measure_view(scene, intrinsics, v), views, repeat),
    }
    n_roi = np.mean([len(r) for r in roi_ray_sets.values()])
    floor = timings["bare cast_rays, ROI rays (floor)"]
    print(f"\n{name}: {len(mesh.faces):,} triangles, camera {intrinsics.name} "
          f"{intrinsics.width}x{intrinsics.height}, scene build {build_s * 1e3:.1f} ms, "
          f"mean ROI {n_roi:,.0f} rays ({n_roi / (intrinsics.width * intrinsics.height):.1%} of the frame)")
    print(f"{'path':40s} {'ms/view':>8s} {'views/s':>8s} {'x floor':>8s}")
    for label, sec in timings.items():
        print(f"{label:40s} {sec * 1e3:8.2f} {1 / sec:8.0f} {sec / floor:8.2f}")
    full = timings["render(roi=False) -> DepthFrame"]
    print(f"ROI speed-up of render: {full / timings['render(roi=True) -> DepthFrame']:.2f}x; "
          f"measure_view overhead over the floor: {(timings['measure_view(return_frame=False)'] - floor) * 1e3:.2f} ms/view")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--camera", default="kinect-v1")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--threads", type=int, default=0, help="Open3D threads per cast (0 = all cores)")
    parser.add_argument("--anny", action="store_true", help="also time a real anny body (slow first build)")
    args = parser.parse_args()
    intrinsics = resolve_camera(args.camera)
    bench("body-like ellipsoid assembly", body_like(), intrinsics, args.repeat, args.threads)
    if args.anny:
        try:
            import pandas as pd

            from wbsa.population.body_model import BodyModel
        except ImportError as exc:
            print(f"\nanny body skipped: {exc}")
            return
        params = pd.DataFrame([{"p_gender": 0.0, "p_age": 0.8, "p_muscle": 0.5, "p_weight": 0.5, "p_height": 0.5,
                                "p_proportions": 0.5, "p_african": 1 / 3, "p_asian": 1 / 3, "p_caucasian": 1 / 3}])
        mesh = BodyModel().skin_meshes(params)[0]
        bench("anny body (adult male, all phenotypes 0.5)", mesh, intrinsics, args.repeat, args.threads)


if __name__ == "__main__":
    main()
