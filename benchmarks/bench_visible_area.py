"""Which renderer effects move the visible-area measures and the stature, on the held-out captures.

For each held-out capture of ``bench_estimate.py`` (same ``--seed``), on the subject's true pixels: the grid
reconstruction's area (the paper's VBSA) and the seen area (:mod:`wbsa.estimation.subject.seen_surface`)
of the project's render, of the plain renderer's (:mod:`wbsa.testing.plain_render`) and of each sensor effect
of the project's alone, relative to the noise-free render; and the top of the subject (the former 99.8th
percentile of the returns' heights, the seen surface's top with the unseen crown) against the posed body's
height. No estimator model is used.

    python benchmarks/bench_visible_area.py --subjects 24 [--effects] [--seed 1000]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))

#: The project's sensor effects switched off one at a time (``--effects``).
EFFECTS = {"holes and dropout": dict(holes_fraction=0.0, pixel_dropout=0.0), "grazing dropout": dict(grazing_dropout_deg=0.0),
           "lateral noise": dict(lateral_noise=False), "quantisation": dict(quantise=False)}


def heights_m(depth: np.ndarray, mask: np.ndarray, camera, pose) -> np.ndarray:
    """(k,) float64 world heights of the pixels ``mask`` of a z-depth image seen from ``pose``."""
    from wbsa.core.backproject import ray_directions

    r, c = np.nonzero(mask)
    points = ray_directions(camera, r, c) * depth[r, c][:, None]
    return ((points - pose.T) @ pose.R)[:, 2]


def top_m(depth: np.ndarray, mask: np.ndarray, camera, pose) -> tuple[float, float]:
    """(former, seen-surface) estimates of the subject's top, metres over the true floor: the 99.8th percentile
    of the returns' heights, and the estimator's (:func:`wbsa.estimation.subject.measure.seen_top_m`)."""
    import math

    from wbsa.core.backproject import ray_directions
    from wbsa.estimation.subject.measure import seen_top_m
    from wbsa.estimation.subject.seen_surface import seen_surface

    former = float(np.quantile(heights_m(depth, mask, camera, pose), 0.998))
    seen = seen_surface(depth, mask, camera)
    r, c = np.nonzero(seen.mask)
    points = ray_directions(camera, r, c) * seen.depth_m[r, c][:, None]
    world = (points - pose.T) @ pose.R
    q = np.column_stack([world @ pose.R[0], world[:, 2], np.zeros(len(world))])  # across the image, up
    return former, seen_top_m(points, q, pose.R[:, 2], math.sqrt(float(camera.fx) * float(camera.fy)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=24)
    ap.add_argument("--seed", type=int, default=1000)
    ap.add_argument("--effects", action="store_true", help="also each project sensor effect switched off alone")
    ap.add_argument("--out", default=None, help="per-capture rows (.csv)")
    args = ap.parse_args()

    from bench_estimate import population

    from wbsa.bodies.body_model import BodyModel
    from wbsa.camera.extrinsics import pose_from_view
    from wbsa.core.backproject import frame_from_depth_image
    from wbsa.estimation.subject.seen_surface import seen_surface
    from wbsa.surface import reconstruct
    from wbsa.testing.plain_render import plain_depth
    from wbsa.testing.testset import RoomTestSettings, plain_capture, room_test_captures
    from wbsa.training.room import capture_room

    pop = population(args.subjects, 0.4, args.seed)
    others = pop.iloc[np.roll(np.arange(len(pop)), 1)].reset_index(drop=True)
    settings = RoomTestSettings(seed=args.seed)
    body_model = BodyModel()
    rows = []
    for tc in room_test_captures(pop, others, 0, settings, body_model):
        cam, pose = tc.capture.camera, pose_from_view(tc.capture.view, tc.room.subject_center)
        ideal, itri = plain_depth(tc.room.mesh.vertices, tc.room.mesh.faces, width=cam.width, height=cam.height,
                                  fx=cam.fx, fy=cam.fy, cx=cam.cx, cy=cam.cy, rotation=pose.R,
                                  center_m=pose.camera_center, rng=None)
        plain, ptri = plain_capture(tc, args.seed)
        frames = {"ideal": (ideal, tc.room.is_subject(itri) & (ideal > 0)), "project": (tc.depth_m, tc.truth),
                  "plain": (plain, tc.room.is_subject(ptri) & (plain > 0))}
        if args.effects:
            for name, change in EFFECTS.items():
                sensor = dataclasses.replace(tc.capture.sensor, **change)
                frame, depth = capture_room(tc.room, dataclasses.replace(tc.capture, sensor=sensor), seed=args.seed,
                                            subject_id=tc.index)
                frames[f"project without {name}"] = (depth, tc.room.is_subject(frame.triangle_id) & (depth > 0))
        row = {"image": tc.index, "camera": cam.name, "posture": tc.posture, "distance_m": tc.capture.view.distance_m,
               "posed_height_m": float(tc.vertices[:, 2].max())}
        for name, (depth, mask) in frames.items():
            row[f"grid {name}"] = reconstruct(frame_from_depth_image(np.where(mask, depth, 0.0), cam,
                                                                     normals=False), "grid").area_m2
            row[f"seen {name}"] = seen_surface(depth, mask, cam).area_m2
            if name in ("project", "plain"):
                former, seen_top = top_m(depth, mask, cam, pose)
                row[f"top former {name} cm"] = 100 * (former - row["posed_height_m"])
                row[f"top seen {name} cm"] = 100 * (seen_top - row["posed_height_m"])
        rows.append(row)
        print(f"image {tc.index} {cam.name}: grid {100 * (row['grid project'] / row['grid ideal'] - 1):+.1f} / "
              f"{100 * (row['grid plain'] / row['grid ideal'] - 1):+.1f} %, seen "
              f"{100 * (row['seen project'] / row['seen ideal'] - 1):+.1f} / "
              f"{100 * (row['seen plain'] / row['seen ideal'] - 1):+.1f} % (project / plain vs noise-free)",
              flush=True)
    res = pd.DataFrame(rows)
    if args.out:
        res.to_csv(args.out, index=False)
    names = [c[len("grid "):] for c in res.columns if c.startswith("grid ") and c != "grid ideal"]
    table = pd.DataFrame({m: {n: 100 * (res[f"{m} {n}"] / res[f"{m} ideal"] - 1) for n in names}
                          for m in ("grid", "seen")}).stack()
    summary = pd.DataFrame({(m, n): {"mean_pct": v.mean(), "min_pct": v.min(), "max_pct": v.max()}
                            for (n, m), v in table.items()}).T
    print(f"\n{len(res)} held-out captures (seed {args.seed}), area against the noise-free render, %:")
    print(summary.round(2).to_string())
    tops = {c: res[c] for c in res.columns if c.startswith("top ")}
    print("\ntop of the subject against the posed body's height, cm: median / 90th percentile of |error|")
    for c, v in tops.items():
        print(f"  {c[:-3]:28s} {v.median():+.2f} / {v.abs().quantile(0.9):.2f}")


if __name__ == "__main__":
    main()
