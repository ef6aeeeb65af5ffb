"""``wbsa estimate``: WBSA of a real person from one depth image and a fitted model."""

from __future__ import annotations

import argparse
import json


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``estimate`` subcommand."""
    p = sub.add_parser("estimate", help="estimate WBSA from one depth image with a fitted model",
                       description="Segment the subject in a 16-bit depth PNG, reconstruct the visible surface, "
                                   "measure VBSA and predict WBSA with a prediction interval.")
    p.add_argument("depth", help="depth image: 16-bit PNG (millimetres unless --depth-scale), 0 = no return")
    p.add_argument("--model", required=True, help="model.json from wbsa fit (or a wbsa run study)")
    p.add_argument("--camera", default="kinect-v1", help="preset name or Open3D intrinsics JSON (default kinect-v1)")
    p.add_argument("--azimuth", type=float, default=0.0, help="view azimuth in degrees (default 0 = front)")
    p.add_argument("--elevation", type=float, default=0.0, help="view elevation in degrees (default 0)")
    p.add_argument("--distance", type=float, default=None, help="model distance in metres, if it holds several")
    p.add_argument("--stature-m", type=float, default=None, help="stature in metres (uses the stature model)")
    p.add_argument("--group", default="all", help="model group (default all)")
    p.add_argument("--kind", default="linear", help="model kind: linear, loglog, wls, quadratic (default linear)")
    p.add_argument("--vbsa", default=None, help="VBSA column of the model, if it holds several")
    p.add_argument("--level", type=float, default=0.95, help="prediction interval coverage (default 0.95)")
    p.add_argument("--depth-scale", type=float, default=1000.0, help="PNG units per metre (default 1000)")
    p.add_argument("--min-depth", type=float, default=0.4, help="nearest return kept, metres (default 0.4)")
    p.add_argument("--max-depth", type=float, default=8.0, help="farthest return kept, metres (default 8)")
    p.add_argument("--no-segment", action="store_true", help="keep every return (the image holds only the subject)")
    p.add_argument("--out-mesh", default=None, help="write the reconstructed surface here (.ply/.obj)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=run_estimate)


def run_estimate(args: argparse.Namespace) -> int:
    """Handler of ``wbsa estimate``."""
    from wbsa.analysis.model_file import WbsaModel
    from wbsa.camera import resolve_camera
    from wbsa.errors import WbsaError
    from wbsa.estimation.segment import SegmentSettings
    from wbsa.estimation.single_view import estimate_wbsa
    from wbsa.core.depth_image import read_depth_png

    if args.stature_m is not None and not 0.3 <= args.stature_m <= 2.75:
        raise WbsaError(f"--stature-m {args.stature_m} is not a human stature in metres (0.3–2.75)")
    intrinsics = resolve_camera(args.camera)
    depth = read_depth_png(args.depth, depth_scale=args.depth_scale)
    model = WbsaModel.load(args.model)
    segment = None if args.no_segment else SegmentSettings(min_depth_m=args.min_depth, max_depth_m=args.max_depth)
    est, surface = estimate_wbsa(depth, intrinsics, model, args.azimuth, args.elevation, stature_m=args.stature_m,
                                 group=args.group, kind=args.kind, level=args.level, segment=segment,
                                 vbsa_column=args.vbsa, distance_m=args.distance)
    if args.out_mesh:
        from wbsa.core.mesh_io import write_mesh

        write_mesh(surface, args.out_mesh)
    if args.json:
        print(json.dumps(est.to_dict(), indent=2))
    else:
        print(f"visible area (VBSA, {est.method}): {est.vbsa_m2:.4f} m²  from {est.n_pixels} pixels")
        print(f"WBSA estimate: {est.wbsa_m2:.3f} m²  ({100 * est.level:.0f} % prediction interval "
              f"{est.wbsa_lo_m2:.3f}–{est.wbsa_hi_m2:.3f} m²)  [{est.group}/{est.model}, {est.vbsa_column}]")
    return 0
