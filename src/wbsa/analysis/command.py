"""``wbsa fit``: per-view regression of WBSA on VBSA, cross-validation, groups, diagnostics, formulae comparison."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from wbsa.errors import WbsaError
from wbsa.typing import GROUP_NAMES, MODEL_KINDS


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``fit`` subcommand to the ``wbsa`` parser."""
    parser = subparsers.add_parser(
        "fit",
        help="fit WBSA = c1*VBSA + c0 per view and group, with k-fold cross-validation",
        description=(
            "For every view of the scan table and every group of subjects, fit WBSA from VBSA (and optional "
            "extra predictors such as stature) by linear and alternative models, cross-validate them, test "
            "homoscedasticity, compare with the classical BSA formulae, and write tables (Parquet, CSV, XLSX), "
            "a Spearman correlation matrix and a model file (model.json) that predicts WBSA with an interval."
        ),
    )
    parser.add_argument("population", metavar="POPULATION", help="population table (.parquet) from wbsa population")
    parser.add_argument("scan", metavar="SCAN", help="scan table (.parquet) from wbsa scan")
    parser.add_argument("--out", required=True, metavar="DIR", help="output folder")
    from types import SimpleNamespace

    from wbsa.analysis.settings import FitSettings
    from wbsa.settings_io import field_defaults

    d = SimpleNamespace(**field_defaults(FitSettings))  # FitSettings() would import pandas to check itself
    g = d.group_spec
    parser.add_argument("--vbsa", default=None, metavar="COLS",
                        help="VBSA column(s), comma-separated: vbsa_hit_m2, vbsa_visible_m2, vbsa_recon_m2:<method> "
                             f"(default {','.join(d.vbsa_columns)})")
    parser.add_argument("--predictors", action="append", default=None, metavar="COLS",
                        help="extra predictors besides VBSA as one comma-separated set, e.g. stature or "
                             "stature,waist_circ_m; repeat for several sets; the VBSA-only model is always fitted "
                             "(default: one set, stature)")
    parser.add_argument("--models", default=None, metavar="LIST",
                        help=f"model kinds: {', '.join(MODEL_KINDS)} (default {','.join(d.models)})")
    parser.add_argument("--groups", default=None, metavar="LIST",
                        help=f"groups fitted on their own: {', '.join(GROUP_NAMES)} (default: the paper's eight)")
    parser.add_argument("--k", type=int, default=None, help=f"cross-validation folds (default {d.k})")
    parser.add_argument("--seed", type=int, default=None, help=f"seed of the fold assignment (default {d.seed})")
    parser.add_argument("--kid-max-age", type=float, default=None, metavar="YEARS",
                        help=f"kids are at most this old (default {g.kid_max_age_years:g})")
    parser.add_argument("--stature-cuts", default=None, metavar="SMALL,BIG",
                        help="small stature <= SMALL m < normal <= BIG m < big "
                             f"(default {g.small_max_stature_m:.2f},{g.big_min_stature_m:.2f})")
    parser.add_argument("--obese-bmi", type=float, default=None, metavar="BMI",
                        help=f"obese group: BMI >= this (default {g.obese_min_bmi:g})")
    parser.add_argument("--include-out-of-frame", action="store_true",
                        help="keep views where the body is cut by the image border (default: leave them out)")
    parser.add_argument("--correlation-view", default=None, metavar="AZ,EL",
                        help="view of the Spearman correlation matrix, degrees "
                             f"(default {','.join(f'{a:g}' for a in d.correlation_view_deg)})")
    parser.add_argument("--residual-groups", default=None, metavar="LIST",
                        help=f"groups whose per-subject residuals are written (default {','.join(d.residual_groups)})")
    parser.add_argument("--residual-models", default=None, metavar="LIST",
                        help=f"model kinds whose per-subject residuals are written (default {','.join(d.residual_models)})")
    parser.add_argument("--population-kind", default=None, metavar="NAME",
                        help="label of the population in the model file (default: the population file name)")
    parser.set_defaults(func=handle)


def _list(text: str, what: str) -> tuple[str, ...]:
    items = tuple(s.strip() for s in text.split(",") if s.strip())
    if not items:
        raise WbsaError(f"--{what} is empty; give a comma-separated list")
    return items


def _floats(text: str, n: int, what: str) -> tuple[float, ...]:
    try:
        values = tuple(float(s) for s in text.split(","))
    except ValueError:
        values = ()
    if len(values) != n:
        raise WbsaError(f"--{what} {text!r} needs {n} comma-separated numbers")
    return values


def settings_from_args(args: argparse.Namespace):
    """The :class:`~wbsa.analysis.settings.FitSettings` of parsed ``wbsa fit`` arguments.

    Each flag sets the field of the same meaning; a flag left out keeps the field's default.
    """
    from wbsa.analysis.groups import GroupSpec
    from wbsa.analysis.settings import FitSettings, with_vbsa_only

    fields: dict = {"population_kind": args.population_kind or Path(args.population).stem,
                    "require_in_frame": not args.include_out_of_frame}
    for flag, name in (("vbsa", "vbsa_columns"), ("models", "models"), ("groups", "groups"),
                       ("residual_groups", "residual_groups"), ("residual_models", "residual_models")):
        if getattr(args, flag) is not None:
            fields[name] = _list(getattr(args, flag), flag.replace("_", "-"))
    if args.predictors is not None:
        fields["predictor_sets"] = with_vbsa_only(
            tuple(s.strip() for s in p.split(",") if s.strip() and s.strip().lower() != "none") for p in args.predictors)
    for flag in ("k", "seed"):
        if getattr(args, flag) is not None:
            fields[flag] = getattr(args, flag)
    if args.correlation_view is not None:
        fields["correlation_view_deg"] = _floats(args.correlation_view, 2, "correlation-view")
    spec: dict = {}
    if args.stature_cuts is not None:
        spec["small_max_stature_m"], spec["big_min_stature_m"] = _floats(args.stature_cuts, 2, "stature-cuts")
    if args.kid_max_age is not None:
        spec["kid_max_age_years"] = args.kid_max_age
    if args.obese_bmi is not None:
        spec["obese_min_bmi"] = args.obese_bmi
    if spec:
        fields["group_spec"] = GroupSpec(**spec)
    return FitSettings(**fields)


def handle(args: argparse.Namespace) -> int:
    """Fit, write the outputs and print a short summary."""
    from wbsa.analysis.outputs import run_fit

    settings = settings_from_args(args)
    out, paths = run_fit(args.population, args.scan, args.out, settings)
    info = out.info
    w = sys.stdout.write
    w(f"fitted {info['n_fits']} models: {info['n_subjects']} subjects x {info['n_views']} views, "
      f"groups {', '.join(settings.groups)}, models {', '.join(settings.models)}, k = {settings.k} "
      f"({info['seconds']:.1f} s)\n")
    if info["n_out_of_frame"] and settings.require_in_frame:
        w(f"left out {info['n_out_of_frame']} scan rows whose body does not fit in the frame\n")
    if info["n_skipped"]:
        reasons = out.skipped.groupby("group", observed=True, sort=False)["reason"].first().head(3)
        w(f"skipped {info['n_skipped']} group/view/model combinations (see skipped.csv), e.g. "
          + "; ".join(f"{g}: {r}" for g, r in reasons.items()) + "\n")
    fits = out.fits
    sel = fits[(fits["group"] == "all") & (fits["model"] == settings.models[0])]
    for (vcol, label), part in sel.groupby(["vbsa_column", "predictors"], sort=True):
        best = part.loc[part["cv_rmse_m2"].idxmin()]
        worst = part.loc[part["cv_rmse_m2"].idxmax()]
        w(f"all subjects, {settings.models[0]} {label} ({vcol}): CV RMSE {best['cv_rmse_m2']:.4f} m2 at "
          f"({best['azimuth_deg']:g}, {best['elevation_deg']:g}) to {worst['cv_rmse_m2']:.4f} m2 at "
          f"({worst['azimuth_deg']:g}, {worst['elevation_deg']:g})\n")
    w(f"wrote {len(paths)} files to {Path(args.out)} (fits.parquet/.csv/.xlsx, model.json, ...)\n")
    return 0
