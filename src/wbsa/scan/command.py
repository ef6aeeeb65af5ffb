"""``wbsa scan``: scan every subject of a population at every view, in parallel, resumable."""

from __future__ import annotations

import argparse
import sys

from wbsa.camera.presets import presets_help
from wbsa.parallel import RunSettings
from wbsa.scan.settings import ScanSettings


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
    d, run = ScanSettings(), RunSettings()
    p.add_argument("population", metavar="POPULATION", help="population table (.parquet) from wbsa population")
    p.add_argument("--views", default=d.views, metavar="SPEC",
                   help=f"view set: paper (65 views), front, sphere:N or grid:STEP (default {d.views})")
    p.add_argument("--azimuths", default=None, metavar="DEG",
                   help="azimuths instead of --views, e.g. '0,30,90' or '0:180:30' (crossed with --elevations)")
    p.add_argument("--elevations", default=None, metavar="DEG", help="elevations instead of --views, e.g. '0,30'")
    p.add_argument("--camera", default=d.camera, metavar="NAME|JSON",
                   help=presets_help(d.camera))
    p.add_argument("--distance", type=float, default=d.distances_m[0], metavar="M",
                   help=f"camera distance from the body's centre in metres (default {d.distances_m[0]:g}, the paper's)")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="scan folder (parts/, scan.parquet, settings.json, intrinsics.json)")
    p.add_argument("--seed", type=int, default=d.seed, help=f"root seed of the per-subject sensor noise (default {d.seed})")
    p.add_argument("--chunk-size", type=int, default=run.chunk_size, metavar="N",
                   help="subjects per chunk, the unit of parallel work and of resuming; a folder keeps the chunk "
                        f"size it was started with (default {run.chunk_size})")
    p.add_argument("--workers", type=int, default=run.workers, metavar="N",
                   help="local worker processes (default 0: all cores); 1 scans in this process without dask")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="use an existing dask scheduler, e.g. tcp://10.0.0.5:8786 (default: $DASK_SCHEDULER_ADDRESS)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bar on stderr (default: when stderr is a terminal)")
    from wbsa.simulate.command import add_backend_argument

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
    """The :class:`~wbsa.scan.settings.ScanJob` that the command line asks for.

    The camera and view flags set the fields of :class:`~wbsa.scan.settings.ScanSettings` (``--azimuths``
    and ``--elevations`` replace ``--views``), the sensor flags :class:`~wbsa.sensor.SensorSettings`, the
    reconstruction flags :class:`~wbsa.surface.ReconstructionSettings`.

    Raises
    ------
    WbsaError
        Unknown camera or view set, bad numbers.
    """
    from wbsa.camera.views import parse_angles

    scan = ScanSettings(camera=args.camera, views=args.views,
                        azimuths_deg=tuple(parse_angles(args.azimuths, "azimuths")) if args.azimuths is not None else (),
                        elevations_deg=tuple(parse_angles(args.elevations, "elevations"))
                        if args.elevations is not None else (),
                        distances_m=(args.distance,), seed=args.seed, backend=args.backend)
    sensor = reconstruction = None
    if hasattr(args, "noise"):
        from wbsa.sensor.cli import sensor_settings_from_args

        sensor = sensor_settings_from_args(args)
    if hasattr(args, "reconstruct"):
        from wbsa.surface.cli import reconstruction_settings_from_args

        reconstruction = reconstruction_settings_from_args(args)
    return scan.job(args.distance, sensor=sensor, reconstruction=reconstruction)


def run_settings_from_args(args: argparse.Namespace) -> RunSettings:
    """The :class:`~wbsa.parallel.RunSettings` of ``--workers``, ``--scheduler``, ``--chunk-size``, ``--progress``."""
    return RunSettings(workers=args.workers, scheduler=args.scheduler, chunk_size=args.chunk_size,
                       progress=args.progress)


def handle(args: argparse.Namespace) -> int:
    """Run the scan; errors in the input or the settings raise :class:`~wbsa.errors.WbsaError`."""
    from wbsa.scan.engine import scan_population

    settings = settings_from_args(args)
    run = run_settings_from_args(args)
    result = scan_population(args.population, settings, args.out, workers=run.n_workers, scheduler=run.scheduler,
                             chunk_size=run.chunk_size, show_progress=run.progress)
    n_subjects = result.table["subject_id"].nunique()
    views_per_s = result.n_views_scanned / result.seconds if result.seconds > 0 else float("nan")
    resumed = f", {result.n_resumed} of {result.n_chunks} chunks resumed" if result.n_resumed else ""
    sys.stdout.write(f"scanned {n_subjects} subjects x {len(settings.views)} views = {len(result.table)} rows "
                     f"in {result.seconds:.1f} s ({views_per_s:.3g} views/s{resumed}) -> {result.path}\n")
    if result.n_views_invalid:
        sys.stderr.write(f"warning: {result.n_views_invalid} of {len(result.table)} views put the camera inside the "
                         "body (camera_inside = true): not measured, left out of fits; use a larger distance\n")
    return 0
