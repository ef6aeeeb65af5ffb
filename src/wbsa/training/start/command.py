"""``wbsa train-start``: the body fit's learned start, trained on crops of virtual captures.

A subcommand of its own beside ``wbsa train`` (registered by :mod:`wbsa.training.command`): it makes another
thing (a network and its card, not an estimator model for ``wbsa estimate --model``), from other data
(depth crops, not measures) with other defaults (about 2,000 bodies × 8 views) and options (epochs).
"""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``train-start`` subcommand."""
    from wbsa.cli_types import number_in
    from wbsa.training.start.settings import StartSettings

    d = StartSettings()
    p = sub.add_parser("train-start", help="train the body fit's learned start (a small CNN on depth crops)",
                       description="Render virtual people as wbsa train does (rooms, cameras, sensors, postures, "
                                   "clothes), crop each segmented view to a normalised picture of the body, and train "
                                   "a small network to read anny's parameters, age, mass, stature, sex and the view "
                                   "from it, each with a spread. The crops are kept as they finish: run the same "
                                   "command again after a kill and it resumes. Writes start.npz and start_card.json "
                                   "(the data, the seed and the figures on validation bodies) into the run's folder.")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="the run's folder (default ~/.cache/wbsa/start-<data hash>, or $WBSA_CACHE_DIR)")
    p.add_argument("--subjects", type=int, default=d.n_random, metavar="N",
                   help=f"random virtual people (default {d.n_random})")
    p.add_argument("--survey-subjects", type=int, default=d.n_survey, metavar="N",
                   help=f"people matched to NHANES on seven measures (default {d.n_survey}: with the default seed, "
                        "those the shipped model was trained on, whom the held-out benchmarks leave out)")
    p.add_argument("--views", type=int, default=d.render.views_per_subject, metavar="N",
                   help=f"captures per person (default {d.render.views_per_subject})")
    p.add_argument("--epochs", type=int, default=d.epochs, metavar="N",
                   help=f"passes over the training crops (default {d.epochs})")
    p.add_argument("--batch", type=int, default=d.batch, metavar="N",
                   help=f"crops per training step (default {d.batch}; fewer for a small trial run)")
    p.add_argument("--chunk-subjects", type=int, default=d.chunk_subjects, metavar="N",
                   help=f"people per stored chunk of crops (default {d.chunk_subjects})")
    p.add_argument("--seed", type=int, default=d.seed, help=f"seed of everything drawn (default {d.seed}; never "
                                                             "1000 or 2000, the held-out seeds)")
    p.add_argument("--workers", type=number_in(1, what="a number of processes"), default=None,
                   help="worker processes for the renders (default: the cores); the crops do not depend on it")
    p.set_defaults(func=run_train_start)


def settings_from_args(args: argparse.Namespace):
    """The :class:`~wbsa.training.start.settings.StartSettings` the options describe."""
    from dataclasses import replace

    from wbsa.errors import WbsaError
    from wbsa.training.start.settings import StartSettings

    d = StartSettings()
    if args.views < 1:
        raise WbsaError(f"--views {args.views} must be at least 1 capture per person, e.g. 8")
    for name, value in (("--subjects", args.subjects), ("--survey-subjects", args.survey_subjects)):
        if value < 0:
            raise WbsaError(f"{name} {value} must be 0 or more people")
    if args.subjects + args.survey_subjects < 8:
        raise WbsaError("--subjects and --survey-subjects must add up to at least 8 people, e.g. --subjects 300")
    if args.epochs < 1 or args.chunk_subjects < 1:
        raise WbsaError("--epochs and --chunk-subjects must be at least 1")
    if args.batch < 2:
        raise WbsaError(f"--batch {args.batch} must be at least 2 crops, e.g. 64")
    return StartSettings(n_random=args.subjects, n_survey=args.survey_subjects,
                         render=replace(d.render, views_per_subject=args.views), epochs=args.epochs,
                         batch=args.batch, chunk_subjects=args.chunk_subjects, seed=args.seed)


def run_train_start(args: argparse.Namespace) -> int:
    """Handler of ``wbsa train-start``."""
    import os
    import sys

    from wbsa.training.start.run import train_start

    settings = settings_from_args(args)
    workers = int(args.workers) if args.workers else (os.cpu_count() or 1)
    model_path, card_path = train_start(settings, args.out, workers=workers,
                                        log=lambda line: print(line, file=sys.stderr, flush=True))
    print(f"wrote {model_path} and {card_path}")
    return 0
