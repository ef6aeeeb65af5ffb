"""``wbsa view``: look at a mesh with the virtual depth camera and measure the visible skin.

The argument helpers (:func:`add_camera_arguments`, :func:`add_view_arguments`, :func:`intrinsics_from_args`,
:func:`views_from_args`) are shared with other commands that need a camera and a set of views.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from wbsa.errors import WbsaError
from wbsa.typing import MESH_UNITS, MESH_UPS

_INTRINSIC_FLAGS = ("width", "height", "fx", "fy", "cx", "cy", "skew")


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``view`` subcommand."""
    p = sub.add_parser(
        "view", help="render a mesh with the virtual depth camera and measure the visible skin area",
        description="Ray-cast a mesh (metres, +Z up, subject facing -Y; centre = bounding-box centre) with a "
                    "pinhole depth camera and print the visible areas: vbsa_hit_m2 (the paper's unique hit "
                    "triangles) and vbsa_visible_m2 (resolution-independent visible area).")
    p.add_argument("mesh", metavar="MESH", nargs="?",
                   help="triangle mesh file (.ply, .obj, .stl, .off, .gltf, .glb); see --units and --up")
    p.add_argument("--units", choices=MESH_UNITS, default="m", help="units of MESH (default m)")
    p.add_argument("--up", choices=MESH_UPS, default="z",
                   help="up axis of MESH (default z, facing -y); y: glTF and many scanners (facing +z)")
    p.add_argument("--population", metavar="FILE", help="look at a subject of this population table instead of MESH")
    p.add_argument("--subject", type=int, default=0, help="subject_id in --population (default 0)")
    add_camera_arguments(p)
    add_view_arguments(p)
    add_backend_argument(p)
    from wbsa.sensor.cli import add_sensor_arguments
    from wbsa.surface.cli import add_reconstruct_arguments

    add_sensor_arguments(p, seed=True)
    add_reconstruct_arguments(p)
    p.add_argument("--out", metavar="DIR", help="write depth PNG (mm), point cloud PLY, visible triangle ids, "
                                                "intrinsics/extrinsics JSON and a preview PNG here")
    p.add_argument("--coordinates", choices=("camera", "world"), default="camera",
                   help="frame of the written point cloud (default camera: x right, y down, z forward)")
    p.add_argument("--json", action="store_true", help="print the results as JSON")
    p.set_defaults(func=run_view)


def add_camera_arguments(p: argparse.ArgumentParser) -> None:
    """``--camera`` (preset or Open3D JSON) plus per-parameter overrides and ``--scale``."""
    from wbsa.camera.presets import presets_help

    g = p.add_argument_group("camera")
    g.add_argument("--camera", default="kinect-v1", metavar="NAME|JSON", help=presets_help("kinect-v1"))
    g.add_argument("--width", type=int, help="image width in pixels (overrides --camera)")
    g.add_argument("--height", type=int, help="image height in pixels (overrides --camera)")
    for name, what in (("fx", "focal length x"), ("fy", "focal length y"), ("cx", "principal point x"),
                       ("cy", "principal point y"), ("skew", "skew K[0,1]")):
        g.add_argument(f"--{name}", type=float, help=f"{what} in pixels (overrides --camera)")
    g.add_argument("--scale", type=float, default=1.0,
                   help="multiply the resolution (and focal lengths) by this factor, same field of view (default 1)")


def add_backend_argument(p: argparse.ArgumentParser) -> None:
    """``--backend open3d|warp|auto``: the ray-casting back end (:mod:`wbsa.camera.backends`)."""
    from wbsa.camera.backends import BACKENDS, DEFAULT_BACKEND

    p.add_argument("--backend", choices=BACKENDS, default=DEFAULT_BACKEND,
                   help="ray-casting back end: open3d (the reference, default), warp (NVIDIA Warp kernels on a CUDA "
                        "GPU if present, else the CPU; same numbers within float32 rounding) or auto (warp on a GPU, "
                        "else open3d)")


def add_view_arguments(p: argparse.ArgumentParser) -> None:
    """Azimuth/elevation lists or a named view set, and the distance."""
    g = p.add_argument_group("views (paper Fig 1: azimuth 0 = front, 90 = subject's left; elevation +90 = above)")
    g.add_argument("--azimuth", "--azimuths", dest="azimuths", metavar="DEG",
                   help="azimuth(s) in degrees: 30, 0,30,90 or 0:180:30 (default 0)")
    g.add_argument("--elevation", "--elevations", dest="elevations", metavar="DEG",
                   help="elevation(s) in degrees, same forms (default 0)")
    g.add_argument("--views", metavar="SET",
                   help="named view set instead: paper (65 views), front, sphere:N (Fibonacci), grid:STEP")
    g.add_argument("--distance", default="4.3", metavar="M|fit",
                   help="camera distance from the subject's centre in metres, or 'fit' for the smallest distance "
                        "that fits the mesh's height in the vertical field of view (eq. 9) (default 4.3)")
    g.add_argument("--margin", type=float, default=0.05,
                   help="with --distance fit: extra fraction of the height kept free (default 0.05)")


def intrinsics_from_args(args: argparse.Namespace):
    """The :class:`~wbsa.camera.intrinsics.Intrinsics` of ``--camera`` with the per-parameter overrides applied.

    When ``--width``/``--height`` change and ``--cx``/``--cy`` are not given, the principal point moves to
    the new image centre.
    """
    from dataclasses import replace

    from wbsa.camera.presets import resolve_camera

    base = resolve_camera(args.camera)
    changes = {name: getattr(args, name) for name in _INTRINSIC_FLAGS if getattr(args, name, None) is not None}
    if changes:
        if "width" in changes and "cx" not in changes:
            changes["cx"] = (changes["width"] - 1) / 2.0
        if "height" in changes and "cy" not in changes:
            changes["cy"] = (changes["height"] - 1) / 2.0
        base = replace(base, name="custom", **changes)
    scale = getattr(args, "scale", 1.0)
    return base if scale == 1.0 else base.scaled(scale)


def views_from_args(args: argparse.Namespace, intrinsics, stature_m: float | None = None) -> list:
    """The views of ``--views`` or ``--azimuths`` × ``--elevations`` at ``--distance``.

    ``--distance fit`` needs ``stature_m`` (the subject's height).
    """
    from wbsa.camera.fit import distance_to_fit
    from wbsa.camera.views import parse_views

    text = str(args.distance).strip().lower()
    if text == "fit":
        if stature_m is None:
            raise WbsaError("--distance fit needs a subject height; give a number of metres")
        distance = distance_to_fit(stature_m, intrinsics, margin=args.margin)
    else:
        try:
            distance = float(text)
        except ValueError:
            raise WbsaError(f"--distance must be metres or 'fit', got {args.distance!r}") from None
    return parse_views(args.views, azimuths=args.azimuths, elevations=args.elevations, distance_m=distance)


def run_view(args: argparse.Namespace) -> int:
    """Handler of ``wbsa view``."""
    from wbsa.simulate.export import write_view_outputs
    from wbsa.core.mesh_io import write_mesh
    from wbsa.camera.intrinsics import Intrinsics
    from wbsa.camera.scene import MeshScene
    from wbsa.simulate.target import load_target
    from wbsa.io import write_json, write_table

    from wbsa.sensor.cli import sensor_settings_from_args
    from wbsa.simulate.view import simulate_view
    from wbsa.surface.cli import reconstruction_settings_from_args

    intrinsics: Intrinsics = intrinsics_from_args(args)
    mesh = load_target(args)
    source = args.mesh or f"{args.population}#subject={args.subject}"
    sensor = sensor_settings_from_args(args, intrinsics)
    recon_settings = reconstruction_settings_from_args(args)
    scene = MeshScene(mesh)
    stature = float(scene.bbox_max[2] - scene.bbox_min[2])
    views = views_from_args(args, intrinsics, stature)
    out = Path(args.out) if args.out else None
    rows = []
    subject = args.subject if args.population else 0
    for view in views:
        sim = simulate_view(scene, intrinsics, view, backend=args.backend, sensor=None if sensor.is_ideal else sensor,
                            seed=args.sensor_seed, subject_id=subject, reconstruct=recon_settings.methods,
                            reconstruction=recon_settings, keep_frame=out is not None, keep_surfaces=out is not None)
        row = {"mesh": source, "mesh_area_m2": float(scene.triangle_areas_m2.sum()), **sim.row}
        frame, recon = sim.frame, sim.surfaces
        rows.append(row)
        if out is not None:
            target_dir = out if len(views) == 1 else out / view.label
            title = (f"{Path(source).name}  az {view.azimuth_deg:g}°  el {view.elevation_deg:g}°  "
                     f"D {view.distance_m:.3g} m  {intrinsics.name}  hit {row['vbsa_hit_m2']:.4f} m²  "
                     f"visible {row['vbsa_visible_m2']:.4f} m²")
            write_view_outputs(frame, target_dir, row, coordinates=args.coordinates, title=title)
            for method, surface in recon.items():
                write_mesh(surface, target_dir / f"recon_{method.replace('-', '_')}.ply")
    if out is not None and len(views) > 1:
        import pandas as pd

        write_table(pd.DataFrame(rows), out / "views.csv")
        write_json(intrinsics.to_open3d_json(), out / "intrinsics.json")
    blind = [r for r in rows if r["n_pixels"] == 0]
    if blind:
        sys.stderr.write(f"warning: no pixel sees the body in {len(blind)} of {len(rows)} view(s) (e.g. azimuth "
                         f"{blind[0]['azimuth_deg']:g}, elevation {blind[0]['elevation_deg']:g}, "
                         f"{blind[0]['distance_m']:g} m): visible area 0; move the camera closer\n")
    if args.json:
        from wbsa.strict_json import json_text

        sys.stdout.write(json_text(rows[0] if len(rows) == 1 else rows) + "\n")
    else:
        _print_rows(rows, intrinsics, out)
    return 0


def _print_rows(rows: list[dict], intrinsics, out: Path | None) -> None:
    k = intrinsics
    print(f"camera {k.name}: {k.width}x{k.height}, fx {k.fx:g}, fy {k.fy:g}, cx {k.cx:g}, cy {k.cy:g}"
          + (f", skew {k.skew:g}" if k.skew else ""))
    print(f"mesh {rows[0]['mesh']}: total area {rows[0]['mesh_area_m2']:.4f} m²")
    recon = [c for c in rows[0] if c.startswith("vbsa_recon_")]
    names = "".join(f" {c[len('vbsa_recon_'):-3] + ' m²':>14s}" for c in recon)
    print(f"{'azimuth':>8s} {'elev.':>6s} {'dist m':>7s} {'pixels':>8s} {'hit m²':>8s} {'visible m²':>10s}{names}  fits")
    for r in rows:
        print(f"{r['azimuth_deg']:8.4g} {r['elevation_deg']:6.4g} {r['distance_m']:7.3f} {r['n_pixels']:8d} "
              f"{r['vbsa_hit_m2']:8.4f} {r['vbsa_visible_m2']:10.4f}" + "".join(f" {r[c]:14.4f}" for c in recon)
              + f"  {'yes' if r['fits_in_frame'] else 'CUT'}")
    if out is not None:
        print(f"wrote {out}")
