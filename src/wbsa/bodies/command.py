"""``wbsa population`` and ``wbsa body``: build virtual populations and export single bodies."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from wbsa.errors import WbsaError


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``population`` and ``body`` subcommands."""
    from types import SimpleNamespace

    from wbsa.bodies.settings import PopulationSettings
    from wbsa.settings_io import field_defaults
    from wbsa.typing import DENSITY_MODELS, POPULATION_KINDS, SAMPLINGS, SURVEY_MEASURES

    d = SimpleNamespace(**field_defaults(PopulationSettings))
    p = sub.add_parser("population", help="build a virtual population and its anthropometric table",
                       description="Build a virtual population (one row per subject: phenotypes, stature, mass, "
                                   "BMI, WBSA, tape measures; SI units).")
    p.add_argument("--kind", required=True, choices=POPULATION_KINDS,
                   help="random: uniform macro parameters (paper's Virtual Random); survey: matched to NHANES "
                        "people; table: phenotypes from --params")
    p.add_argument("--n", type=int, help="number of subjects (random) or survey people (survey)")
    p.add_argument("--seed", type=int, default=d.seed, help=f"random seed (default {d.seed})")
    p.add_argument("--out", required=True, help="output table (.parquet, .csv or .xlsx)")
    p.add_argument("--format", choices=("parquet", "csv", "xlsx"), help="table format (default: from --out's suffix)")
    p.add_argument("--density", type=float, default=d.density_kg_m3, metavar="KG_M3",
                   help=f"body density for mass = volume × density (default {d.density_kg_m3:g} kg/m³, as anny)")
    p.add_argument("--density-model", choices=DENSITY_MODELS, default=d.density_model,
                   help="constant: every body --density (the paper's tables); deurenberg-siri/-brozek: each body's "
                        "fat fraction from its BMI, age and sex (Deurenberg 1991, with its scatter) and its density "
                        "by Siri's/Brozek's equation; adds fat_fraction and density_kg_m3 columns")
    p.add_argument("--sampling", choices=SAMPLINGS, default=d.sampling,
                   help="(--kind random) paper: uniform macro parameters, no local change (the paper's Virtual "
                        "Random); varied: local changes, anny's whole range, an obese half of the adults, ages 7-80 "
                        "(docs/population.md)")
    p.add_argument("--params", help="(--kind table) Parquet/CSV with p_gender, p_age, ... columns in [0, 1]")
    p.add_argument("--variations", type=int, default=d.variations,
                   help="(--kind survey) weight/muscle variations per person")
    p.add_argument("--posture", default=d.posture, metavar="NAME",
                   help="a-pose (default: every body in the paper's rest A-pose), mixed (a random posture per "
                        "subject) or one of arms-down, arms-wide, hands-on-hips, elbows-bent, feet-together, "
                        "feet-apart; each with random joint jitter, recorded as posture columns")
    p.add_argument("--survey-weights", action="store_true", help="(--kind survey) select people by exam weights")
    p.add_argument("--survey-measures", choices=SURVEY_MEASURES, default=d.survey_measures,
                   help="(--kind survey) seven (default): match stature, mass, waist, hip, arm circumference, upper "
                        "arm and upper leg length (NHANES); four: the first four only")
    p.add_argument("--workers", type=int, default=0,
                   help="worker processes (default 0: all cores; 1 = in this process)")
    p.add_argument("--scheduler", default=None,
                   help="address of an existing dask scheduler (default: $DASK_SCHEDULER_ADDRESS)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="show a progress bar (default: when stderr is a terminal)")
    p.set_defaults(func=run_population)

    b = sub.add_parser("body", help="export one body as PLY/OBJ (skin only, metres, standing on z = 0)")
    b.add_argument("--population", help="population table to take the subject from")
    b.add_argument("--subject", type=int, default=0, help="subject_id in --population (default 0)")
    for name in ("gender", "age", "muscle", "weight", "height", "proportions"):
        b.add_argument(f"--{name}", type=float, default=None, help=f"anny {name} in [0, 1] (without --population)")
    b.add_argument("--out", required=True, help="mesh file, .ply or .obj")
    b.set_defaults(func=run_body)


def settings_from_args(args: argparse.Namespace):
    """The :class:`~wbsa.bodies.settings.PopulationSettings` of parsed ``wbsa population`` arguments."""
    from wbsa.bodies.settings import PopulationSettings

    return PopulationSettings(kind=args.kind, n=args.n, seed=args.seed, density_kg_m3=args.density,
                              variations=args.variations, survey_weights=args.survey_weights,
                              survey_measures=args.survey_measures, params_path=args.params,
                              posture=args.posture, density_model=args.density_model, sampling=args.sampling)


def run_population(args: argparse.Namespace) -> int:
    """Handler of ``wbsa population``."""
    import dataclasses

    from wbsa.io import RUN_LOG_ATTR, write_run_log

    from wbsa.bodies.build import build_population
    from wbsa.io import write_table
    from wbsa.parallel import RunSettings

    settings = settings_from_args(args)
    run = RunSettings(workers=args.workers, scheduler=args.scheduler, progress=args.progress)
    out = Path(args.out)
    fmt = args.format or _format_of(out)
    df = build_population(**dataclasses.asdict(settings), show_progress=run.progress, workers=run.n_workers,
                          scheduler=run.scheduler)
    write_table(df, out, fmt)
    if df.attrs.get(RUN_LOG_ATTR):
        write_run_log(df.attrs[RUN_LOG_ATTR], out)
    print(f"wrote {len(df)} subjects to {out}")
    return 0


def run_body(args: argparse.Namespace) -> int:
    """Handler of ``wbsa body``."""
    import pandas as pd

    from wbsa.bodies.body_model import BodyModel
    from wbsa.bodies.subject import subject_mesh
    from wbsa.core.mesh_io import write_mesh
    from wbsa.bodies.table import read_population

    if args.population:
        mesh = subject_mesh(read_population(args.population), args.subject)
    else:
        row = {f"p_{k}": (0.5 if getattr(args, k) is None else getattr(args, k))
               for k in ("gender", "age", "muscle", "weight", "height", "proportions")}
        row.update(p_african=1 / 3, p_asian=1 / 3, p_caucasian=1 / 3)
        mesh = BodyModel().skin_meshes(pd.DataFrame([row]))[0]
    write_mesh(mesh, args.out)
    print(f"wrote {args.out}: {len(mesh.vertices)} vertices, {len(mesh.faces)} skin triangles, "
          f"area {mesh.area_m2:.4f} m²", file=sys.stdout)
    return 0


def _format_of(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix in (".parquet", ".pq"):
        return "parquet"
    if suffix in (".csv", ".xlsx"):
        return suffix[1:]
    raise WbsaError(f"cannot tell the format of {path}; use --format or a .parquet/.csv/.xlsx name")
