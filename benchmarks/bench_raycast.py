"""Ray-casting speed: full frame vs ROIs vs the bare Open3D cast on the same rays, 65 paper views.

Usage::

    python benchmarks/bench_raycast.py [--camera kinect-v1] [--repeat 5] [--threads 1] [--anny] [--accuracy]

For every path the 65 paper views are timed ``--repeat`` times and the fastest pass is reported
(the build machine is shared; the minimum is the least disturbed estimate), as wall time and as CPU
time of this process (all threads). Ratios are against the bare ``RaycastingScene.cast_rays`` call on
exactly the rays the default (silhouette) ROI casts, the floor for one closest-hit ray per pixel, and
against that floor plus the bare ``test_occlusions`` call on the visibility rays ``measure_view`` casts
for the grazing triangles (recorded from a ``measure_view`` pass).
``measure_views`` is timed with every back end (``--backends``, default open3d and warp; the Warp back
end runs on the CPU here, all 65 views in one call).
``--anny`` adds a real body from ``wbsa.bodies.body_model`` when that module exists.
``--accuracy`` also prints the visible-area checks quoted in docs/camera.md: sphere caps against
2πr²(1 − r/d), both VBSA estimates of the bodies at 1×, 2×, 4× and 8× the camera's resolution, and the
coarse scenes of ``tests/helpers/reference.py`` (boxes and thin walls of two triangles per face, occluders)
against a Monte Carlo answer from a million surface points, for both back ends and for the former
centroid rule.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # helpers.shapes: test meshes

from wbsa.camera import (MeshScene, measure_view, paper_views, pose_from_view,  # noqa: E402
                         render, resolve_camera)
from wbsa.camera.raycast import cast, grid_rays, rect_rays  # noqa: E402
from wbsa.camera.roi import projected_roi, silhouette_pixels  # noqa: E402
from helpers.shapes import body_like  # noqa: E402


def best_pass(fn, views, repeat: int) -> tuple[float, float]:
    """Fastest of ``repeat`` passes over ``views``: (wall seconds, CPU seconds) per view."""
    wall = cpu = np.inf
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        for v in views:
            fn(v)
        wall = min(wall, time.perf_counter() - t0)
        cpu = min(cpu, time.process_time() - c0)
    return wall / len(views), cpu / len(views)


def bench(name: str, mesh, intrinsics, repeat: int, threads: int, backends: tuple[str, ...] = ("open3d", "warp")) -> None:
    import open3d  # noqa: F401  (imported before timing the scene build)

    t0 = time.perf_counter()
    scene = MeshScene(mesh, nthreads=threads)
    build_s = time.perf_counter() - t0
    views = paper_views()
    k = intrinsics
    poses = {v: pose_from_view(v, scene.center) for v in views}
    sil_rays, bbox_rays, full_rays = {}, {}, {}
    for v in views:
        grid = silhouette_pixels(scene, k, poses[v])
        bbox_rays[v] = rect_rays(k, poses[v], projected_roi(scene, k, poses[v]))
        sil_rays[v] = bbox_rays[v] if grid is None else grid_rays(k, poses[v], grid)[0]
        full_rays[v] = rect_rays(k, poses[v], (0, k.height, 0, k.width))
    # The visibility rays of the grazing triangles, as measure_view casts them.
    vis_rays = {v: [] for v in views}
    bare_occluded = scene.occluded
    for v in views:
        def recording(rays, t_far, batches=vis_rays[v]):
            batches.append((rays.copy(), t_far))
            return bare_occluded(rays, t_far)

        scene.occluded = recording
        measure_view(scene, k, v, return_frame=False)
    del scene.occluded  # back to the class's method

    # Same result first: every ROI must hit the same triangles at every pixel as the full frame.
    for v in views:
        full = render(scene, k, poses[v], roi="full").triangle_id
        for mode in ("silhouette", "bbox"):
            assert np.array_equal(render(scene, k, poses[v], roi=mode).triangle_id, full), f"{mode} ROI differs at {v}"

    timings = {
        "bare cast_rays, silhouette rays (floor)": best_pass(lambda v: scene.cast_rays(sil_rays[v]), views, repeat),
        "bare cast_rays, bbox rays": best_pass(lambda v: scene.cast_rays(bbox_rays[v]), views, repeat),
        "bare cast_rays, full-frame rays": best_pass(lambda v: scene.cast_rays(full_rays[v]), views, repeat),
        "bare test_occlusions, visibility rays": best_pass(
            lambda v: [scene.occluded(r, t) for r, t in vis_rays[v]], views, repeat),
        "cast(roi='silhouette')": best_pass(lambda v: cast(scene, k, poses[v], roi="silhouette"), views, repeat),
        "cast(roi='bbox')": best_pass(lambda v: cast(scene, k, poses[v], roi="bbox"), views, repeat),
        "measure_view(return_frame=False)": best_pass(
            lambda v: measure_view(scene, k, v, return_frame=False), views, repeat),
        "measure_view(return_frame=True)": best_pass(lambda v: measure_view(scene, k, v), views, repeat),
        "render(roi=True) -> DepthFrame": best_pass(lambda v: render(scene, k, poses[v]), views, repeat),
        "render(roi=False) -> DepthFrame": best_pass(lambda v: render(scene, k, poses[v], roi=False), views, repeat),
    }
    from wbsa.camera.backends import measure_views

    for backend in backends:  # all views in one call (the scan's unit: one body)
        measure_views(scene, k, views[:2], return_frames=False, backend=backend)  # compile / load kernels
        wall, cpu = best_pass(lambda _: measure_views(scene, k, views, return_frames=False, backend=backend),
                              [None], repeat)
        timings[f"measure_views(backend={backend!r})"] = (wall / len(views), cpu / len(views))
    n = {key: np.mean([len(r) for r in rays.values()]) for key, rays in
         (("silhouette", sil_rays), ("bbox", bbox_rays))}
    n_vis = np.mean([sum(len(r) for r, _ in b) for b in vis_rays.values()])
    floor_wall, floor_cpu = timings["bare cast_rays, silhouette rays (floor)"]
    vis_cpu = timings["bare test_occlusions, visibility rays"][1]
    print(f"\n{name}: {len(mesh.faces):,} triangles, camera {k.name} {k.width}x{k.height}, "
          f"{threads or 'all'} Open3D thread(s), scene build {build_s * 1e3:.1f} ms")
    print(f"mean rays per view: silhouette {n['silhouette']:,.0f}, bbox {n['bbox']:,.0f}, "
          f"full {k.width * k.height:,}; visibility rays {n_vis:,.0f}")
    print(f"{'path':42s} {'wall ms':>8s} {'cpu ms':>8s} {'views/cpu-s':>11s} {'x floor (cpu)':>13s} "
          f"{'x floor+vis':>11s}")
    for label, (wall, cpu) in timings.items():
        print(f"{label:42s} {wall * 1e3:8.2f} {cpu * 1e3:8.2f} {1 / cpu:11.0f} {cpu / floor_cpu:13.2f} "
              f"{cpu / (floor_cpu + vis_cpu):11.2f}")
    full = timings["render(roi=False) -> DepthFrame"]
    roi_render = timings["render(roi=True) -> DepthFrame"]
    print(f"render speed-up of the ROI over the full frame: {full[0] / roi_render[0]:.2f}x wall, "
          f"{full[1] / roi_render[1]:.2f}x cpu; "
          f"measure_view(return_frame=False) overhead over the floor: "
          f"{(timings['measure_view(return_frame=False)'][0] - floor_wall) * 1e3:.2f} ms wall, "
          f"{(timings['measure_view(return_frame=False)'][1] - floor_cpu) * 1e3:.2f} ms cpu per view")


def accuracy(name: str, mesh, intrinsics) -> None:
    """Visible-area accuracy: the paper's hit area vs the visible-area estimate across resolutions."""
    from wbsa.camera import View, sphere_cap_area_m2, vbsa_visible_m2
    from helpers.shapes import icosphere

    if name == "body-like ellipsoid assembly":
        sphere = MeshScene(icosphere(0.3, 5))
        print(f"\nsphere r = 0.3 m (20,480 triangles), camera {intrinsics.name}: error against 2πr²(1 − r/d)")
        print(f"{'d (m)':>6s} {'px radius':>9s} {'visible':>8s} {'pixels only':>11s} {'hit':>8s}")
        for d in (1.0, 2.0, 3.0, 4.3, 6.0):
            cap = sphere_cap_area_m2(0.3, d)
            errs = {"visible": [], "pixels": [], "hit": []}
            for az, el in ((0, 0), (37, 21), (100, -50), (200, 70)):
                row, frame = measure_view(sphere, intrinsics, View(az, el, d), target=np.zeros(3))
                errs["visible"].append(row["vbsa_visible_m2"] / cap - 1)
                errs["pixels"].append(vbsa_visible_m2(frame) / cap - 1)
                errs["hit"].append(row["vbsa_hit_m2"] / cap - 1)
            worst = {key: max(v, key=abs) for key, v in errs.items()}
            print(f"{d:6.1f} {intrinsics.fx * 0.3 / d:9.0f} {worst['visible']:+8.2%} {worst['pixels']:+11.2%} "
                  f"{worst['hit']:+8.2%}")
    scene = MeshScene(mesh)
    print(f"\n{name}: VBSA (m²) against resolution, camera {intrinsics.name} at 4.3 m")
    print(f"{'view':>12s} {'scale':>5s} {'pixels':>8s} {'hit':>8s} {'visible':>8s} {'pixels only':>11s}")
    for az, el in ((0, 0), (60, 30), (90, 0), (0, 90)):
        for scale in (1, 2, 4, 8):
            k = intrinsics.scaled(scale)
            row, frame = measure_view(scene, k, View(az, el, 4.3))
            print(f"{f'{az}/{el}':>12s} {scale:5d} {row['n_pixels']:8d} {row['vbsa_hit_m2']:8.4f} "
                  f"{row['vbsa_visible_m2']:8.4f} {vbsa_visible_m2(frame):11.4f}")


def coarse_accuracy(intrinsics, n_samples: int = 1_000_000) -> None:
    """Coarse scenes (two triangles per box face) against the Monte Carlo answer, every check view."""
    from wbsa.camera import View
    from wbsa.camera.backends import measure_views
    from helpers.reference import (AXIS_VIEWS, EDGE_ON_VIEWS, OBLIQUE_VIEWS, coarse_scenes,
                                       monte_carlo_visible_area_m2, scene_mesh)

    print(f"\ncoarse scenes, camera {intrinsics.name} at 4.3 m: vbsa_visible_m2 against a Monte Carlo answer "
          f"({n_samples:,} area-weighted surface points)")
    print(f"{'scene':>10s} {'view':>9s} {'reference m²':>14s} {'open3d':>8s} {'warp':>8s} {'no split':>13s}")
    worst = {"open3d": 0.0, "warp": 0.0, "centroid": 0.0}
    for name, solids in coarse_scenes().items():
        scene = MeshScene(scene_mesh(solids))
        views = AXIS_VIEWS + OBLIQUE_VIEWS + (EDGE_ON_VIEWS if name == "thin wall" else ())
        views = [View(az, el, 4.3) for az, el in views]
        rows = {b: [r for r, _ in measure_views(scene, intrinsics, views, return_frames=False, backend=b)]
                for b in ("open3d", "warp")}
        rows["centroid"] = [r for r, _ in measure_views(scene, intrinsics, views, return_frames=False,
                                                        grazing_split_px=None)]
        for i, view in enumerate(views):
            ref, se = monte_carlo_visible_area_m2(solids, intrinsics, pose_from_view(view, scene.center), n_samples)
            err = {b: rows[b][i]["vbsa_visible_m2"] / ref - 1 for b in rows}
            for b in err:
                worst[b] = max(worst[b], abs(err[b]))
            print(f"{name:>10s} {f'{view.azimuth_deg:g}/{view.elevation_deg:g}':>9s} {ref:9.4f}±{se:.4f} "
                  f"{err['open3d']:+8.2%} {err['warp']:+8.2%} {err['centroid']:+13.2%}")
    print(f"worst |error|: open3d {worst['open3d']:.2%}, warp {worst['warp']:.2%}, no split {worst['centroid']:.2%}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--camera", default="kinect-v1")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--threads", type=int, default=1,
                        help="Open3D threads per cast (0 = all cores; default 1, as in a scan with one worker "
                             "per core)")
    parser.add_argument("--anny", action="store_true", help="also time a real anny body (slow first build)")
    parser.add_argument("--accuracy", action="store_true", help="also print the visible-area accuracy tables")
    parser.add_argument("--backends", default="open3d,warp", help="back ends of the measure_views rows")
    args = parser.parse_args()
    intrinsics = resolve_camera(args.camera)
    bodies = [("body-like ellipsoid assembly", body_like())]
    if args.anny:
        try:
            import pandas as pd

            from wbsa.bodies.body_model import BodyModel
        except ImportError as exc:
            print(f"anny body skipped: {exc}")
        else:
            params = pd.DataFrame([{"p_gender": 0.0, "p_age": 0.8, "p_muscle": 0.5, "p_weight": 0.5, "p_height": 0.5,
                                    "p_proportions": 0.5, "p_african": 1 / 3, "p_asian": 1 / 3,
                                    "p_caucasian": 1 / 3}])
            bodies.append(("anny body (male, age 0.8, other phenotypes 0.5)", BodyModel().skin_meshes(params)[0]))
    backends = tuple(b.strip() for b in args.backends.split(",") if b.strip())
    for name, mesh in bodies:
        bench(name, mesh, intrinsics, args.repeat, args.threads, backends)
    if args.accuracy:
        for name, mesh in bodies:
            accuracy(name, mesh, intrinsics)
        coarse_accuracy(intrinsics)


if __name__ == "__main__":
    main()
