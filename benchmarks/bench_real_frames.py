"""The real-frame cases of `wbsa estimate`: what the estimator does now on each, as a Markdown table.

Each case is reproduced on a render (two people side by side in a room, Kinect v2 at 3 m:
``wbsa.testing.frames.side_by_side``; the frame's bottom blanked from the knees, or its top down to the
hips; the man alone, the room blanked, whole and cut) and on PCL's real frame ``tests/fixtures/pcl/five_people.pcd`` (five people in a corridor, 2.0–2.8 m
away, the nearest cut by the frame at the knees; read as a point cloud, its camera recovered from its points).
Every estimate uses the shipped model; each row prints
the answer (WBSA, interval, stature, flags) or the one-line refusal. Deterministic: the same table each run.

    python benchmarks/bench_real_frames.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

FIVE_PEOPLE = Path(__file__).resolve().parent.parent / "tests" / "fixtures" / "pcl" / "five_people.pcd"


def outcome(depth, camera: str, **kw) -> str:
    """What ``wbsa.estimate`` does: ``WBSA 1.234 m² [lo–hi], stature 1.80 m; flags a, b`` or ``refused: ...``."""
    import wbsa
    from wbsa.errors import WbsaError
    from wbsa.estimation import SegmentSettings

    pick = kw.pop("pick", None)
    try:
        est = wbsa.estimate(depth, camera, segment=SegmentSettings(pick=pick), **kw)
    except WbsaError as exc:
        return f"refused: {exc}"
    flags = ", ".join(f"`{f}`" for f in est.flags) or "none"
    return (f"WBSA {est.wbsa_m2:.3f} m² [{est.wbsa_lo_m2:.3f}–{est.wbsa_hi_m2:.3f}], stature {est.stature_m:.2f} m; "
            f"flags {flags}")


def _middle(mask: np.ndarray) -> tuple[int, int]:
    ys, xs = np.nonzero(mask)
    return int(np.median(xs)), int(np.median(ys))


def main() -> None:
    from wbsa.bodies.body_model import BodyModel
    from wbsa.testing.frames import read_pcd_depth, side_by_side

    depth, man, people = side_by_side(BodyModel())
    rows = np.flatnonzero(man.any(axis=1))
    knees = depth.copy()
    knees[int(rows[-1] - 0.27 * (rows[-1] - rows[0])):] = 0.0
    legs = depth.copy()
    legs[:int(rows[-1] - 0.45 * (rows[-1] - rows[0]))] = 0.0
    man_px, woman_px = _middle(man), _middle(people & ~man)
    whole = outcome(depth, "kinect-v2", pick=man_px)
    stature_m = float(whole.split("stature ")[1].split(" m")[0])
    five = str(FIVE_PEOPLE)  # read as the point cloud it is: its camera recovered from its points
    cases = [
        ("render: two people side by side, the man picked, clothes not stated", depth, "kinect-v2",
         dict(pick=man_px)),
        ("render: the same, the woman picked", depth, "kinect-v2", dict(pick=woman_px)),
        ("render: the same, no pick", depth, "kinect-v2", {}),
        ("render: the man, clothes stated `light` (0.8 ± 0.4 cm)", depth, "kinect-v2",
         dict(pick=man_px, clothes="light")),
        ("render: the man, clothes stated as 0.8 cm exactly", depth, "kinect-v2", dict(pick=man_px, clothing_m=0.008)),
        ("render: the frame's bottom blanked from the man's knees", knees, "kinect-v2", dict(pick=man_px)),
        (f"render: the same, stature stated ({stature_m:.2f} m)", knees, "kinect-v2",
         dict(pick=man_px, stature_m=stature_m)),
        ("render: the man alone (the room blanked: no floor), whole", np.where(man, depth, 0.0), "kinect-v2", {}),
        ("render: the man alone, cut at the knees (the legs end over nothing)", np.where(man, knees, 0.0),
         "kinect-v2", {}),
        (f"render: the same, stature stated ({stature_m:.2f} m)", np.where(man, knees, 0.0), "kinect-v2",
         dict(stature_m=stature_m)),
        ("render: the frame's top blanked down to the hips (only legs)", legs, "kinect-v2", dict(pick="nearest")),
        ("render: nobody (both people's pixels blanked)", np.where(people, 0.0, depth), "kinect-v2", {}),
        ("render: pick on the wall, 40 px from anyone", depth, "kinect-v2", dict(pick=(40, 100))),
        ("five_people.pcd: no pick", five, "auto", {}),
        ("five_people.pcd's depth as a 640 × 480 array, no camera given", read_pcd_depth(FIVE_PEOPLE), "auto",
         dict(pick=(86, 250))),
    ]
    for k, x in enumerate((86, 190, 320, 420)):
        cases.append((f"five_people.pcd: person {k + 1}, pick ({x}, 250)", five, "auto", dict(pick=(x, 250))))
    cases += [
        ("five_people.pcd: person 5 (cut at the knees), pick (530, 250)", five, "auto", dict(pick=(530, 250))),
        ("five_people.pcd: person 5, stature stated 1.80 m", five, "auto", dict(pick=(530, 250), stature_m=1.80)),
        ("five_people.pcd: person 1, clothes stated `street`", five, "auto", dict(pick=(86, 250), clothes="street")),
        ("five_people.pcd: pick on the corridor's far end (260, 150)", five, "auto", dict(pick=(260, 150))),
        ("five_people.pcd: pick on the cabinet by the right wall (590, 400)", five, "auto", dict(pick=(590, 400))),
        ("five_people.pcd: pick on the floor between people (262, 420)", five, "auto", dict(pick=(262, 420))),
    ]
    print("| case | what the estimator does now |")
    print("|---|---|")
    for name, d, camera, kw in cases:
        text = whole if name.startswith("render: two people side by side, the man picked") else outcome(d, camera, **kw)
        print(f"| {name} | {text.replace('|', '/')} |")


if __name__ == "__main__":
    main()
