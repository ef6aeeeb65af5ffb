"""Command-line flags of the simulated sensor, shared by ``wbsa view`` and ``wbsa scan``."""

from __future__ import annotations

import argparse

from wbsa.cli_types import number_in
from wbsa.sensor.settings import SensorSettings
from wbsa.typing import NOISE_MODELS


_fraction = number_in(0.0, 1.0, what="a fraction")
_grazing_deg = number_in(0.0, 90.0, high_open=True, what="degrees")
_noise_scale = number_in(0.0, 10.0, what="a factor")


def add_sensor_arguments(parser: argparse.ArgumentParser, *, seed: bool = False) -> None:
    """Add the sensor flags (an argument group "sensor") to ``parser``.

    ``--noise {none,nguyen2012,camera}``, ``--holes FRACTION``, ``--pixel-dropout FRACTION``,
    ``--grazing-dropout DEG``, ``--quantise``, ``--noise-scale FACTOR``, ``--no-lateral-noise``, ``--range-limits`` and, with
    ``seed=True``, ``--sensor-seed N`` (commands that have their own ``--seed`` pass that instead).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's parser; changed in place.
    seed : bool
        Also add ``--sensor-seed``.
    """
    g = parser.add_argument_group("sensor (simulated depth camera; all off by default)")
    g.add_argument("--noise", choices=NOISE_MODELS, default="none",
                   help="depth noise model: nguyen2012 = Kinect v1 axial and lateral noise (the paper's, whatever the "
                        "camera); camera = the camera preset's own technology (structured light, time of flight, "
                        "active stereo, LiDAR; docs/sensor_and_surface.md) (default: none)")
    g.add_argument("--holes", type=_fraction, default=0.0, metavar="FRACTION",
                   help="drop this fraction of the visible triangles and their pixels, as in the paper (default: 0)")
    g.add_argument("--pixel-dropout", type=_fraction, default=0.0, metavar="FRACTION",
                   help="lose each returned pixel with this probability (default: 0)")
    g.add_argument("--grazing-dropout", type=_grazing_deg, default=None, metavar="DEG",
                   help="drop returns within DEG of grazing incidence (default: the noise model's, 8; 0 without)")
    g.add_argument("--quantise", action="store_true",
                   help="quantise disparity: 1/8 pixel with a 0.075 m baseline (Kinect v1); with --noise camera, the "
                        "preset's own disparity (none for time of flight and LiDAR)")
    g.add_argument("--noise-scale", type=_noise_scale, default=1.0, metavar="FACTOR",
                   help="with a noise model: multiply its sigma by this (default 1 = the model's level)")
    g.add_argument("--no-lateral-noise", dest="lateral_noise", action="store_false",
                   help="with a noise model: axial noise only")
    g.add_argument("--range-limits", action="store_true",
                   help="drop returns outside the camera preset's depth range (Kinect v1: 0.8-4.0 m)")
    if seed:
        g.add_argument("--sensor-seed", type=int, default=0, metavar="N",
                       help="seed of the sensor's random effects (default: 0)")


def sensor_settings_from_args(args: argparse.Namespace, camera=None) -> SensorSettings:
    """The :class:`SensorSettings` described by the flags of :func:`add_sensor_arguments`.

    Parameters
    ----------
    args : argparse.Namespace
    camera : wbsa.camera.Intrinsics, optional
        The command's camera; with ``--range-limits`` it must have a finite working range.

    Raises
    ------
    SettingsError
        If ``--range-limits`` is asked for a camera without a working range.
    """
    settings = SensorSettings(
        noise=getattr(args, "noise", "none"),
        lateral_noise=getattr(args, "lateral_noise", True),
        noise_scale=getattr(args, "noise_scale", 1.0),
        quantise=getattr(args, "quantise", False),
        holes_fraction=getattr(args, "holes", 0.0),
        pixel_dropout=getattr(args, "pixel_dropout", 0.0),
        grazing_dropout_deg=getattr(args, "grazing_dropout", None),
        range_limits=getattr(args, "range_limits", False),
    )
    if camera is not None:
        settings.check_camera(camera)
    return settings
