"""``wbsa scan``: scan every subject of a population at every view, in parallel, resumable."""

from __future__ import annotations

import argparse
import sys

from wbsa.scan.settings import DEFAULT_CHUNK_SIZE


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``scan`` subcommand to the ``wbsa`` parser."""
    p = subparsers.add_parser(
        "scan",
        help="scan a population with a virtual depth camera at many views (parallel, resumable)",
        description=(
            "Ray-cast every subject of a population table at every view and write one row per subject x view "
            "(visible areas, pixels, fits-in-frame, optional sensor and reconstruction columns) to OUT/scan.parquet. "
            "Chunks of subjects run in parallel on a local dask cluster (or an existing one) and are written as "
            "they finish, so running the same command again after a crash resumes where it stopped."
        ),
    )
    p.add_argument("population", metavar="POPULATION", help="population table (.parquet) from wbsa population")
    p.add_argument("--views", default=None, metavar="SPEC",
                   help="view set: paper (65 views, default), front, sphere:N or grid:STEP")
    p.add_argument("--azimuths", default=None, metavar="DEG",
                   help="azimuths instead of --views, e.g. '0,30,90' or '0:180:30' (crossed with --elevations)")
    p.add_argument("--elevations", default=None, metavar="DEG", help="elevations instead of --views, e.g. '0,30'")
    p.add_argument("--camera", default="kinect-v1", metavar="NAME|JSON",
                   help="camera preset (kinect-v1, kinect-v2, tum) or Open3D intrinsics JSON (default kinect-v1)")
    p.add_argument("--distance", type=float, default=4.3, metavar="M",
                   help="camera distance from the body's centre in metres (default 4.3, the paper's)")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="scan folder (parts/, scan.parquet, settings.json, intrinsics.json)")
    p.add_argument("--seed", type=int, default=0, help="root seed of the per-subject sensor noise (default 0)")
    p.add_argument("--chunk-size", type=int, default=DEFAULT_CHUNK_SIZE, metavar="N",
                   help=f"subjects per chunk, the unit of parallel work and of resuming (default {DEFAULT_CHUNK_SIZE})")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="local worker processes (default: all cores); 1 scans in this process without dask")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="use an existing dask scheduler, e.g. tcp://10.0.0.5:8786 (default: $DASK_SCHEDULER_ADDRESS)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bar on stderr (default: when stderr is a terminal)")
    from wbsa.camera.command import add_backend_argument

    add_backend_argument(p)
    _add_optional_stage_arguments(p)
    p.set_defaults(func=handle)


def _add_optional_stage_arguments(p: argparse.ArgumentParser) -> None:
    """The sensor flags (``--noise``, ``--holes``, ...) and ``--reconstruct`` of the sensor and surface stages."""
    from wbsa.sensor.cli import add_sensor_arguments
    from wbsa.surface.cli import add_reconstruct_arguments

    add_sensor_arguments(p)
    add_reconstruct_arguments(p)


def settings_from_args(args: argparse.Namespace):
    """The :class:`~wbsa.scan.settings.ScanSettings` that the command line asks for.

    Raises
    ------
    WbsaError
        Unknown camera or view set, bad numbers.
    """
    from wbsa.camera.intrinsics import resolve_camera
    from wbsa.camera.views import parse_views
    from wbsa.scan.settings import ScanSettings

    camera = resolve_camera(args.camera)
    spec = args.views if (args.views is not None or args.azimuths is not None or args.elevations is not None) else "paper"
    views = parse_views(spec, azimuths=args.azimuths, elevations=args.elevations, distance_m=args.distance)
    sensor = None
    if hasattr(args, "noise"):
        from wbsa.sensor.cli import sensor_model_from_args

        sensor = sensor_model_from_args(args, camera)
        if sensor.is_ideal:
            sensor = None
    methods, reconstruction = (), None
    if getattr(args, "reconstruct", None):
        from wbsa.surface.cli import reconstruct_methods_from_args, reconstruction_settings_from_args

        methods = reconstruct_methods_from_args(args)
        reconstruction = reconstruction_settings_from_args(args)
    return ScanSettings(camera=camera, views=tuple(views), sensor=sensor, reconstruct=methods,
                        reconstruction=reconstruction, seed=args.seed,
                        chunk_size=args.chunk_size, backend=args.backend)


def handle(args: argparse.Namespace) -> int:
    """Run the scan; errors in the input or the settings raise :class:`~wbsa.errors.WbsaError`."""
    from wbsa.scan.engine import scan_population

    settings = settings_from_args(args)
    result = scan_population(args.population, settings, args.out, workers=args.workers, scheduler=args.scheduler,
                             show_progress=args.progress)
    n_subjects = result.table["subject_id"].nunique()
    views_per_s = result.n_views_scanned / result.seconds if result.seconds > 0 else float("nan")
    resumed = f", {result.n_resumed} of {result.n_chunks} chunks resumed" if result.n_resumed else ""
    sys.stdout.write(f"scanned {n_subjects} subjects x {len(settings.views)} views = {len(result.table)} rows "
                     f"in {result.seconds:.1f} s ({views_per_s:.3g} views/s{resumed}) -> {result.path}\n")
    return 0
