"""``wbsa train``: an estimator model for your own camera, distance range or population."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``train`` subcommand."""
    from wbsa.camera.presets import TRAINED_CAMERAS, presets_help
    from wbsa.cli_types import number_in, range_of
    from wbsa.training.capture import DISTANCE_LIMITS_M, CaptureSettings
    from wbsa.training.settings import RenderSettings
    from wbsa.training.settings import TrainSettings
    from wbsa.typing import SURVEY_MEASURES

    d, r, c = TrainSettings(), RenderSettings(), CaptureSettings()
    p = sub.add_parser("train", help="train an estimator model for your own camera, distances or population",
                       description="Render virtual people with the cameras, distances and population given, measure "
                                   "them with the estimator's own code, fit the model and calibrate its interval on "
                                   "held-out subjects. The renders are kept as they finish: run the same command "
                                   "again after a kill and it resumes. The default settings take about 70 minutes "
                                   "on 2 cores; the model (model.npz in the run's folder) goes to wbsa estimate "
                                   "--model. Needs scikit-learn: pip install 'wbsa[train]'.")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="the run's folder (default ~/.cache/wbsa/train-<settings hash>, or $WBSA_CACHE_DIR)")
    p.add_argument("--camera", action="append", default=None, metavar="NAME|JSON",
                   help=presets_help() + f"; repeat for several (default: {', '.join(TRAINED_CAMERAS)})")
    p.add_argument("--disparity", default=None, metavar="BASELINE_M,STEP_PX",
                   help="with a JSON camera: its disparity (stereo: its quantisation and Intel's depth RMS noise), "
                        "e.g. 0.05,0.0833; default none (time of flight)")
    p.add_argument("--distance", type=range_of(*DISTANCE_LIMITS_M, unit="m"), default=c.distance_m,
                   metavar="LOW,HIGH", help=f"camera-to-subject distances in metres (default "
                                            f"{c.distance_m[0]:g},{c.distance_m[1]:g})")
    p.add_argument("--noise-scale", type=range_of(0.0, 10.0, unit="times the noise model's sigma"),
                   default=c.noise_scale, metavar="LOW,HIGH",
                   help=f"depth noise as a factor on the sigma of each camera's technology model (default {c.noise_scale[0]:g},"
                        f"{c.noise_scale[1]:g})")
    p.add_argument("--subjects", type=int, default=d.n_random, metavar="N",
                   help=f"random virtual people (default {d.n_random})")
    p.add_argument("--survey-subjects", type=int, default=d.n_survey, metavar="N",
                   help=f"people matched to NHANES (default {d.n_survey})")
    p.add_argument("--survey-measures", choices=SURVEY_MEASURES, default=d.survey_measures,
                   help=f"NHANES measures the survey subjects are fitted to: all seven (stature, mass, waist, hip, arm "
                        f"circumference, arm and leg length) or the first four (default {d.survey_measures})")
    p.add_argument("--ages", type=range_of(0.0, 90.0, unit="years"), default=d.age_years, metavar="LOW,HIGH",
                   help=f"ages of the random people in years (default {d.age_years[0]:g},{d.age_years[1]:g})")
    p.add_argument("--views", type=int, default=r.views_per_subject, metavar="N",
                   help=f"captures per person (default {r.views_per_subject})")
    p.add_argument("--seed", type=int, default=d.seed, help=f"seed of everything drawn (default {d.seed})")
    p.add_argument("--workers", type=number_in(1, what="a number of processes"), default=None,
                   help="worker processes for the renders (default: the cores); the model does not depend on it")
    p.add_argument("--default", action="store_true",
                   help="rebuild the model shipped with wbsa (the recipe; no other option) into the package's data "
                        "folder, with its model card")
    p.set_defaults(func=run_train)
    from wbsa.training.start.command import register as register_start

    register_start(sub)  # wbsa train-start: the body fit's learned start


def _camera(spec: str, disparity: tuple[float, float] | None):
    """A preset name as it is; an Open3D intrinsics JSON as a camera record."""
    from wbsa.camera.presets import resolve_camera
    from wbsa.camera.presets import CAMERAS, CameraRecord

    if spec in CAMERAS:
        if disparity is not None:
            from wbsa.errors import WbsaError

            raise WbsaError(f"--disparity goes with --camera FILE.json; the preset {spec} has its own")
        return spec
    intrinsics = resolve_camera(spec)
    return CameraRecord(intrinsics, "active-stereo" if disparity else "time-of-flight", disparity, False,
                        f"user camera {intrinsics.name}")


def settings_from_args(args: argparse.Namespace):
    """The :class:`TrainSettings` the options describe."""
    from wbsa.cli_types import range_of
    from wbsa.errors import WbsaError
    from wbsa.training.capture import CaptureSettings
    from wbsa.training.settings import RenderSettings
    from wbsa.training.settings import TrainSettings

    disparity = None
    if args.disparity is not None:
        try:
            disparity = range_of(1e-4, 10.0, unit="(metres, pixels)")(args.disparity)
        except argparse.ArgumentTypeError as exc:
            raise WbsaError(f"--disparity: {exc}") from None
        if not args.camera:
            raise WbsaError("--disparity goes with --camera FILE.json")
    capture = CaptureSettings(distance_m=tuple(args.distance), noise_scale=tuple(args.noise_scale))
    if args.camera:
        from dataclasses import replace

        capture = replace(capture, cameras=tuple(_camera(s, disparity) for s in args.camera))
    render = RenderSettings(views_per_subject=args.views, capture=capture)
    return TrainSettings(n_random=args.subjects, n_survey=args.survey_subjects,
                         survey_measures=args.survey_measures, age_years=tuple(args.ages), render=render, seed=args.seed)


def run_train(args: argparse.Namespace) -> int:
    """Handler of ``wbsa train``."""
    from wbsa.errors import WbsaError
    from wbsa.training.run import check_training_dependencies, train

    from wbsa.training.settings import TrainSettings

    check_training_dependencies()
    settings = settings_from_args(args)
    workers = int(args.workers) if args.workers else None
    if args.default:
        if settings != TrainSettings() or args.disparity is not None:
            raise WbsaError("--default rebuilds the shipped model from its recipe; give no camera, distance, noise, "
                            "population, views or seed option with it")
        from wbsa.training.run import rebuild_default_model

        model_path, card_path = rebuild_default_model(args.out, workers=workers)
        print(f"wrote {model_path} and {card_path}")
        return 0
    result = train(settings, args.out, workers=workers)
    print(result.summary())
    return 0
