"""How much skin a scanned mesh with fused fingers and smoothed toes leaves out: anny's whole skin against the
surface a scanner's reconstruction makes of the same body.

A body scanner's mesh often has "mitten" hands (the fingers fused into one surface) and smoothed feet, and so
measures less skin than anny's, which has every finger and toe (the body fit and the population measure anny's).
Here the scanner's surface is a screened Poisson reconstruction (Open3D; Kazhdan & Hoppe 2013) of points sampled
densely on the body at rest, at an octree depth whose cells (about 7 mm at depth 8, 14 mm at depth 7 over a
body's 1.8 m) are as wide as the gaps between fingers and toes, so that they fuse. Each reconstructed triangle
belongs to the body part of the skin vertex nearest its centre; per part, its area is set against the skin's
own (the triangles of that part's vertices). The forearms are the control: a smooth part whose area the
reconstruction should keep.

    python benchmarks/bench_mitten_hands.py [--subjects 4 --seed 1000 --depths 8,7]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

#: Body parts (bone-name prefixes of anny's vertices) compared.
PARTS = {"hands": ("wrist", "metacarpal", "finger"), "feet": ("foot", "toe"), "forearms": ("lowerarm",)}


def part_areas_m2(vertices: np.ndarray, faces: np.ndarray, part_of_vertex: np.ndarray, points: np.ndarray,
                  tri: np.ndarray, skin_vertices: np.ndarray) -> tuple[dict, dict]:
    """Areas (m²) per part of the skin ``(vertices, faces)`` and of a reconstruction ``(points, tri)``.

    ``part_of_vertex (n,)`` names each skin vertex's part ('' for none); a skin triangle belongs to its first
    vertex's part, a reconstructed one to the part of the skin vertex (of ``skin_vertices``) nearest its centre.
    """
    from scipy.spatial import cKDTree

    from wbsa.core.mesh import triangle_areas_m2

    skin = triangle_areas_m2(vertices, faces)
    rec = triangle_areas_m2(points, tri)
    _, nearest = cKDTree(vertices[skin_vertices]).query(points[tri].mean(1), workers=1)
    rec_part = part_of_vertex[skin_vertices][nearest]
    skin_part = part_of_vertex[faces[:, 0]]
    return ({p: float(skin[skin_part == p].sum()) for p in PARTS} | {"all": float(skin.sum())},
            {p: float(rec[rec_part == p].sum()) for p in PARTS} | {"all": float(rec.sum())})


def reconstruct(vertices: np.ndarray, faces: np.ndarray, depth: int, n_points: int = 400_000, seed: int = 0):
    """A screened Poisson surface (points (k, 3), triangles (t, 3)) of ``n_points`` seeded samples of the skin."""
    import open3d as o3d

    mesh = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(vertices), o3d.utility.Vector3iVector(faces))
    mesh.compute_triangle_normals()
    o3d.utility.random.seed(seed)
    cloud = mesh.sample_points_uniformly(n_points, use_triangle_normal=True)
    rec, _ = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(cloud, depth=depth, n_threads=1)
    return np.asarray(rec.vertices), np.asarray(rec.triangles)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=4, help="bodies (bench_estimate's population; default 4)")
    ap.add_argument("--seed", type=int, default=1000)
    ap.add_argument("--depths", default="8,7", help="Poisson octree depths (default 8,7)")
    args = ap.parse_args()

    from bench_estimate import population

    from wbsa.bodies.body_model import BodyModel

    model = BodyModel()
    pop = population(args.subjects, 0.4, args.seed)
    rest = model.rest_bodies(pop)
    bone = np.asarray(model.bone_labels)[model.vertex_bone]
    part = np.full(len(bone), "", dtype=object)
    for name, prefixes in PARTS.items():
        part[np.array([b.startswith(prefixes) for b in bone])] = name
    faces = np.asarray(model.skin_faces)
    used = np.unique(faces)
    changes = {d: [] for d in args.depths.split(",")}
    for b in range(len(pop)):
        v = rest.vertices[b]
        for d in changes:
            pts, tri = reconstruct(v, faces, int(d))
            skin, rec = part_areas_m2(v, faces, part, pts, tri, used)
            row = {p: 100 * (rec[p] - skin[p]) / skin["all"] for p in (*PARTS, "all")}
            changes[d].append(row)
            print(f"body {b} ({pop['age_years'].iloc[b]:.0f} y, WBSA {skin['all']:.3f} m², hands "
                  f"{100 * skin['hands'] / skin['all']:.1f} %, feet {100 * skin['feet'] / skin['all']:.1f} %), depth {d}: reconstructed "
                  "minus skin, % of WBSA: " + ", ".join(f"{p} {x:+.2f}" for p, x in row.items()), flush=True)
    for d, rows in changes.items():
        mean = {p: np.mean([r[p] for r in rows]) for p in rows[0]}
        print(f"depth {d}, {len(rows)} bodies (seed {args.seed}), reconstructed minus skin, mean % of WBSA: "
              + ", ".join(f"{p} {x:+.2f}" for p, x in mean.items()))


if __name__ == "__main__":
    main()
