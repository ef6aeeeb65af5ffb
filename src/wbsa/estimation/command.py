"""``wbsa estimate``: WBSA of a real person from one depth image."""

from __future__ import annotations

import argparse
import sys


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``estimate`` subcommand.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``wbsa`` parser's subcommands.
    """
    from wbsa.camera.presets import presets_help
    from wbsa.cli_types import number_in, pick
    from wbsa.estimation.clothes import CLOTHES, clothes_help
    from wbsa.estimation.limits import LIMITS
    from wbsa.typing import METHODS

    stature_cm, clothing_cm, depth = LIMITS["stature"].scaled(100), LIMITS["clothing"].scaled(100), LIMITS["depth"]

    p = sub.add_parser("estimate", help="estimate WBSA from one depth image of a standing person",
                       description="Find the person in a depth image of a room, measure the visible surface and "
                                   "stature, estimate the view, and predict WBSA with a calibrated interval. Every "
                                   "warning is printed; exit 2 on input that cannot be measured. The camera sees "
                                   "the outside of the clothes: state them with --clothes (a 1 cm layer "
                                   "not stated reads about 9 % high; docs/estimate.md, Clothes).")
    p.add_argument("depth", help="depth image: 16-bit PNG (mm), .npy (float metres), 32-bit float .tiff, .exr; or a "
                                 "point cloud in the camera's frame (metres): an organised .pcd brings its own camera "
                                 "(recovered from its points), a .ply or unorganised .pcd needs --camera")
    p.add_argument("--camera", default="auto",
                   help=presets_help() + "; auto (default): the preset of the image's size, flagged")
    p.add_argument("--method", default="regression", choices=METHODS,
                   help="estimation route: regression (default; the estimator model on the image's measures and "
                        "view, under a second), body-fit (the whole anny body fitted to the view and measured at "
                        "rest, several seconds; docs/body_fit.md), or both side by side (flagged when they "
                        "disagree)")
    p.add_argument("--model", default=None, help="estimator model (.npz, e.g. from wbsa train) or wbsa fit model "
                                                 "(.json); default: the model shipped with wbsa")
    p.add_argument("--azimuth", type=number_in(-360, 360), default=None,
                   help="stated azimuth in degrees (optional: it is estimated, and checked when given)")
    p.add_argument("--elevation", type=number_in(-90, 90), default=None,
                   help="stated elevation in degrees (optional: it is estimated, and checked when given)")
    p.add_argument("--clothes", default=None, choices=tuple(CLOTHES), metavar="NAME",
                   help="the clothes worn, a layer with its own uncertainty (widens the interval): "
                        + clothes_help() + "; not given (nor --clothing-cm): taken as none, flagged clothes_unstated")
    p.add_argument("--clothing-cm", type=number_in(*clothing_cm), default=None,
                   help="or the clothes as an explicit thickness over the trunk, upper arms, legs and feet in cm, "
                        f"{clothing_cm[0]:g}-{clothing_cm[1]:g}, how far their outside stands off the skin on average "
                        "(0: none or tight-fitting; the default model is trained on 0-1.5)")
    p.add_argument("--stature-cm", type=number_in(*stature_cm), default=None,
                   help=f"the subject's stature in cm, {stature_cm[0]:g}-{stature_cm[1]:g}; needed when the feet are "
                        "not in the frame (cut off or hidden), where it takes the measured stature's place")
    p.add_argument("--level", type=number_in(0, 1, low_open=True, high_open=True), default=0.95,
                   help="prediction interval coverage (default 0.95)")
    p.add_argument("--depth-scale", type=number_in(0, low_open=True), default=None,
                   help="depth units per metre (default 1000 for integer files, 1 for float files)")
    p.add_argument("--min-depth", type=number_in(0), default=depth.low,
                   help=f"nearest return kept, metres (default {depth.low:g})")
    p.add_argument("--max-depth", type=number_in(0, low_open=True), default=depth.high,
                   help=f"farthest return kept, metres (default {depth.high:g})")
    p.add_argument("--body-fit-steps", type=int, default=None,
                   help="with --method body-fit or both: most optimiser steps of the fit (default 200)")
    p.add_argument("--body-fit-restarts", type=int, default=None,
                   help="with --method body-fit or both: starting points fitted together (default 6)")
    p.add_argument("--pick", type=pick, default=None,
                   help="with several people: nearest, largest, center or x,y (a pixel of the subject)")
    p.add_argument("--no-segment", action="store_true",
                   help="every return is the subject (skip the segmentation; a body alone in the image is found "
                        "without it too)")
    p.add_argument("--mask-out", default=None, help="write the subject's mask here (8-bit PNG, 255 = subject)")
    p.add_argument("--out-mesh", default=None, help="write the reconstructed visible surface here (.ply/.obj)")
    p.add_argument("--out-body", default=None,
                   help="with --method body-fit or both: write the fitted body at rest here (.ply/.obj, metres, "
                        "+Z up) and as the camera saw it beside it (NAME-observed.ply, camera frame)")
    p.add_argument("--json", action="store_true", help="print the estimate, view and flags as JSON")
    p.add_argument("--fhir", action="store_true", help="print a FHIR R4 Observation (LOINC 8277-6) instead")
    p.add_argument("--patient", default=None, help="FHIR subject reference, e.g. Patient/123 (with --fhir)")
    p.set_defaults(func=run_estimate)


def run_estimate(args: argparse.Namespace) -> int:
    """Handler of ``wbsa estimate``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options of ``wbsa estimate``.
    """
    from wbsa.estimation.request import EstimateRequest
    from wbsa.estimation.single_view import estimate_request
    from wbsa.estimation.subject.segment import SegmentSettings

    _check_outputs(args)
    segment = None if args.no_segment else SegmentSettings(min_depth_m=args.min_depth, max_depth_m=args.max_depth,
                                                           pick=args.pick)
    request = EstimateRequest.build(
        args.camera, args.method, azimuth_deg=args.azimuth, elevation_deg=args.elevation, clothes=args.clothes,
        clothing_m=None if args.clothing_cm is None else args.clothing_cm / 100.0,
        stature_m=None if args.stature_cm is None else args.stature_cm / 100.0, level=args.level, segment=segment,
        body_fit=_body_fit_settings(args))
    est = estimate_request(request, args.depth, args.model, depth_scale=args.depth_scale)
    _write_outputs(args, est)
    from wbsa.estimation.flags import terminal_text

    for name, text in est.flags.items():
        sys.stderr.write(f"warning: {name}: {terminal_text(name, text)}\n")
    from wbsa.strict_json import json_text

    if args.fhir:
        from wbsa.estimation.fhir import fhir_observation

        print(json_text(fhir_observation(est, patient=args.patient)))
    elif args.json:
        print(json_text(est.to_dict()))
    else:
        print(f"WBSA {est.wbsa_m2:.3f} m²  ({100 * est.level:.0f} % interval {est.wbsa_lo_m2:.3f}–{est.wbsa_hi_m2:.3f} m²)"
              f"{'  [' + str(len(est.flags)) + ' warning(s)]' if est.flags else ''}")
        print(f"view: {est.view_text()}; subject {est.distance_m:.2f} m away, "
              f"{est.stature_m:.2f} m tall, VBSA {est.vbsa_m2:.3f} m² from {est.n_pixels} pixels [{est.model}]")
        for name, p in est.routes.items():
            print(f"  {name}: WBSA {p.wbsa_m2:.3f} m² ({p.wbsa_lo_m2:.3f}–{p.wbsa_hi_m2:.3f} m²) [{p.model_name}]")
        if est.body is not None:
            b = est.body
            print(f"fitted body: stature {b.stature_m:.3f} m, mass {b.mass_kg:.1f} kg (BMI {b.bmi:.1f}, from its "
                  f"volume {1000 * b.volume_m3:.1f} L), {b.sex}, residual {1000 * b.residual_m:.1f} mm, "
                  f"fitted in {b.seconds:.1f} s")
    return 0


def _body_fit_settings(args: argparse.Namespace):
    """The body fit's settings of ``--body-fit-*`` (None when none is given)."""
    changes = {name: value for name, value in (("steps", args.body_fit_steps), ("restarts", args.body_fit_restarts))
               if value is not None}
    if not changes:
        return None
    from wbsa.errors import SettingsError, WbsaError
    from wbsa.estimation.methods.body_fit.settings import BodyFitSettings

    try:
        return BodyFitSettings(**changes)
    except SettingsError as exc:
        raise WbsaError(f"--body-fit-{exc.field} {exc.problem}") from None


def _check_outputs(args: argparse.Namespace) -> None:
    """The output options, checked before any work: names, suffixes, folders, and options that contradict."""
    from wbsa.atomic import check_output_file
    from wbsa.core.mesh_io import WRITE_SUFFIXES
    from wbsa.errors import WbsaError

    if args.json and args.fhir:
        raise WbsaError("--json and --fhir both print the result; give one of them")
    if args.patient is not None and not args.fhir:
        raise WbsaError("--patient goes with --fhir")
    if args.patient is not None and not args.patient.strip():
        raise WbsaError("--patient needs a FHIR reference such as Patient/123, got an empty one")
    files = []
    if args.mask_out is not None:
        files.append(check_output_file(args.mask_out, (".png",), "--mask-out").resolve())
    if args.out_mesh is not None:
        files.append(check_output_file(args.out_mesh, WRITE_SUFFIXES, "--out-mesh").resolve())
    if args.out_body is not None:
        if args.method == "regression":
            raise WbsaError("--out-body writes the fitted body of --method body-fit or both")
        body = check_output_file(args.out_body, WRITE_SUFFIXES, "--out-body")
        files += [body.resolve(), _observed_path(body).resolve()]
    if len(set(files)) < len(files):
        raise WbsaError("--mask-out, --out-mesh and --out-body name the same file; give different names")


def _observed_path(path):
    """``NAME-observed.SUFFIX`` beside ``path``: the fitted body in the camera frame."""
    from pathlib import Path

    path = Path(path)
    return path.with_name(f"{path.stem}-observed{path.suffix}")


def _write_outputs(args: argparse.Namespace, est) -> None:
    """The mask, the mesh and the fitted body as a set: all are written to temporaries and checked, then renamed;
    if one fails, none is put in place (an older file of any of the names is kept)."""
    import contextlib

    from wbsa.atomic import atomic_path
    from wbsa.core.depth_image import mask_image
    from wbsa.core.mesh_io import write_mesh

    with contextlib.ExitStack() as stack:  # left in reverse: the mask is checked and renamed first
        if args.out_body and est.body is not None:
            for pose, name in (("rest", args.out_body), ("observed", _observed_path(args.out_body))):
                tmp = stack.enter_context(atomic_path(name, keep_suffix=True, verify=lambda _: None))
                write_mesh(est.body.mesh(pose), tmp)
        if args.out_mesh:
            tmp = stack.enter_context(atomic_path(args.out_mesh, keep_suffix=True, verify=lambda _: None))
            write_mesh(est.surface, tmp)  # written and checked on a temporary of its own, then onto tmp
        if args.mask_out:
            tmp = stack.enter_context(atomic_path(args.mask_out))
            mask_image(est.mask).save(tmp, format="PNG")
