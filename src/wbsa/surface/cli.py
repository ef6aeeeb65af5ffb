"""Command-line flags of surface reconstruction, shared by ``wbsa view`` and ``wbsa scan``."""

from __future__ import annotations

import argparse

from wbsa.cli_types import number_in
from wbsa.surface.settings import ReconstructionSettings
from wbsa.typing import BOUNDARY_MODELS, DENOISE_METHODS, RECONSTRUCTION_METHODS


def _methods(text: str) -> tuple[str, ...]:
    if text.strip().lower() in ("", "none"):
        return ()
    names = tuple(dict.fromkeys(t.strip() for t in text.split(",") if t.strip()))
    bad = [n for n in names if n not in RECONSTRUCTION_METHODS]
    if bad:
        raise argparse.ArgumentTypeError(f"unknown reconstruction method(s) {', '.join(bad)}; "
                                         f"use a comma-separated list of {', '.join(RECONSTRUCTION_METHODS)} or none")
    return names


_positive = number_in(0.0, low_open=True, what="a number")
_non_negative = number_in(0.0, what="a number")


def add_reconstruct_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the reconstruction flags (an argument group "reconstruction") to ``parser``.

    ``--reconstruct METHODS`` (comma-separated: grid, ball-pivoting, poisson; default none),
    ``--denoise``, ``--denoise-sigma PX``, ``--boundary``, ``--voxel-size M``, ``--smooth``,
    ``--poisson-depth N``.
    """
    g = parser.add_argument_group("reconstruction (surface from the depth image)")
    g.add_argument("--reconstruct", type=_methods, default=(), metavar="METHODS",
                   help=f"comma-separated methods among {', '.join(RECONSTRUCTION_METHODS)} (default: none); "
                        "adds vbsa_recon_<method>_m2")
    g.add_argument("--denoise", choices=DENOISE_METHODS, default=ReconstructionSettings.denoise,
                   help="depth filter before reconstruction (default: %(default)s, robust local quadrics)")
    g.add_argument("--denoise-sigma", type=_positive, default=ReconstructionSettings.denoise_sigma_px,
                   metavar="PX", help="spatial scale of the depth filter in pixels (default: %(default)s)")
    g.add_argument("--boundary", choices=BOUNDARY_MODELS, default=ReconstructionSettings.boundary,
                   help="grid: skirt along the mesh boundary (default: %(default)s)")
    g.add_argument("--voxel-size", type=_non_negative, default=0.0, metavar="M",
                   help="ball-pivoting/poisson: voxel down-sampling size in metres (default: off)")
    g.add_argument("--smooth", action="store_true",
                   help="ball-pivoting/poisson: moving-least-squares smoothing of the points")
    g.add_argument("--poisson-depth", type=int, default=ReconstructionSettings.poisson_depth, metavar="N",
                   help="poisson: octree depth (default: %(default)s)")


def reconstruction_settings_from_args(args: argparse.Namespace) -> ReconstructionSettings:
    """The :class:`ReconstructionSettings` described by the flags of :func:`add_reconstruct_arguments`.

    ``--reconstruct`` gives ``methods`` (empty when none), the other flags the fields of the same names.
    """
    d = ReconstructionSettings()
    return ReconstructionSettings(
        methods=tuple(getattr(args, "reconstruct", ()) or ()),
        denoise=getattr(args, "denoise", d.denoise),
        denoise_sigma_px=getattr(args, "denoise_sigma", d.denoise_sigma_px),
        boundary=getattr(args, "boundary", d.boundary),
        voxel_size_m=getattr(args, "voxel_size", d.voxel_size_m),
        smoothing="mls" if getattr(args, "smooth", False) else "none",
        poisson_depth=getattr(args, "poisson_depth", d.poisson_depth),
    )
