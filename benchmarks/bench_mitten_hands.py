"""How much skin area a scanned mesh with fused fingers and smoothed toes leaves out: anny whole against the same
body with each hand replaced by a mitten and each foot's toes fused.

A body scanner's mesh often has "mitten" hands (the fingers fused into one surface) and smoothed feet, and so
measures less skin than anny's, which has every finger and toe (the body fit and the population measure anny's).
For each body at rest: the mitten of a hand is the convex hull of the hand's vertices (those moved mainly by the
wrist, metacarpal and finger bones of that side) less its cap over the wrist's opening, and it replaces the hand's
own skin triangles; the toes are fused likewise (the convex hull of the toe vertices of each foot, less its cap).
A cap's area is that of the opening's boundary loop, a polygon projected on its best-fitting plane.

    python benchmarks/bench_mitten_hands.py [--subjects 12 --seed 1000]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))


def loop_area_m2(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Area (m²) of the openings of a patch of triangles ``faces (m, 3)``: each boundary loop as a polygon on its
    best-fitting plane (the vector area of a closed loop, fan-triangulated from its centroid)."""
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    _, inverse, counts = np.unique(edges, axis=0, return_inverse=True, return_counts=True)
    boundary = directed[counts[inverse.ravel()] == 1]
    total = 0.0
    nxt = {int(a): int(b) for a, b in boundary}
    seen: set[int] = set()
    for start in list(nxt):
        if start in seen:
            continue
        loop = [start]
        seen.add(start)
        while nxt.get(loop[-1]) is not None and nxt[loop[-1]] != start and nxt[loop[-1]] not in seen:
            loop.append(nxt[loop[-1]])
            seen.add(loop[-1])
        p = vertices[loop]
        c = p.mean(0)
        total += 0.5 * float(np.linalg.norm(np.cross(p - c, np.roll(p, -1, axis=0) - c).sum(0)))
    return total


def fused_area_change_m2(vertices: np.ndarray, faces: np.ndarray, part: np.ndarray) -> float:
    """Area change (m²) when the skin triangles of a part (vertices ``part (n,)`` bool) become their convex hull
    less the hull's cap over the part's opening."""
    from scipy.spatial import ConvexHull

    from wbsa.core.mesh import triangle_areas_m2

    inside = part[faces].all(axis=1)
    own = float(triangle_areas_m2(vertices, faces[inside]).sum())
    hull = ConvexHull(vertices[part]).area
    return hull - loop_area_m2(vertices, faces[inside]) - own


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=12, help="bodies (default 12, as bench_estimate's population)")
    ap.add_argument("--seed", type=int, default=1000)
    args = ap.parse_args()

    from bench_estimate import population

    from wbsa.bodies.body_model import BodyModel
    from wbsa.core.mesh import triangle_areas_m2

    model = BodyModel()
    pop = population(args.subjects, 0.4, args.seed)
    rest = model.rest_bodies(pop)
    labels = np.asarray(model.bone_labels)
    bone = labels[model.vertex_bone]
    rows = []
    for b in range(len(pop)):
        v = rest.vertices[b]
        whole = float(triangle_areas_m2(v, model.skin_faces).sum())
        change = {"hands": 0.0, "toes": 0.0}
        for side in ("L", "R"):
            hand = np.array([s.startswith(("wrist", "metacarpal", "finger")) and s.endswith(side) for s in bone])
            toes = np.array([s.startswith("toe") and s.endswith(side) for s in bone])
            change["hands"] += fused_area_change_m2(v, model.skin_faces, hand)
            change["toes"] += fused_area_change_m2(v, model.skin_faces, toes)
        rows.append((float(pop["age_years"].iloc[b]), whole, 100 * change["hands"] / whole,
                     100 * (change["hands"] + change["toes"]) / whole))
        print(f"body {b} ({rows[-1][0]:.0f} y): whole {whole:.4f} m², mitten hands {rows[-1][2]:+.2f} %, "
              f"and fused toes {rows[-1][3]:+.2f} %", flush=True)
    r = np.array(rows)
    print(f"\n{len(r)} bodies (seed {args.seed}): mitten hands {r[:, 2].mean():+.2f} % "
          f"({r[:, 2].min():+.2f} … {r[:, 2].max():+.2f}), mitten hands and fused toes {r[:, 3].mean():+.2f} % "
          f"({r[:, 3].min():+.2f} … {r[:, 3].max():+.2f}) of the whole skin's WBSA")


if __name__ == "__main__":
    main()
