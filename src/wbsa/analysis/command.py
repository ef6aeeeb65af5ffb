"""``wbsa fit``: per-view regression of WBSA on VBSA, cross-validation, groups, diagnostics, formulae comparison."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from wbsa.errors import WbsaError


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
    parser.add_argument("--vbsa", default="vbsa_visible_m2", metavar="COLS",
                        help="VBSA column(s), comma-separated: vbsa_hit_m2, vbsa_visible_m2, vbsa_recon_m2:<method> "
                             "(default vbsa_visible_m2)")
    parser.add_argument("--predictors", action="append", default=None, metavar="COLS",
                        help="extra predictors besides VBSA as one comma-separated set, e.g. stature or "
                             "stature,waist_circ_m; repeat for several sets; the VBSA-only model is always fitted "
                             "(default: one set, stature)")
    parser.add_argument("--models", default="linear,loglog,wls", metavar="LIST",
                        help="model kinds: linear, quadratic, loglog, wls (default linear,loglog,wls)")
    parser.add_argument("--groups", default="all,males,females,kids,adults,small,normal,big", metavar="LIST",
                        help="groups fitted on their own: all, males, females, kids, adults, small, normal, big, "
                             "obese (default: the paper's eight)")
    parser.add_argument("--k", type=int, default=10, help="cross-validation folds (default 10)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the fold assignment (default 0)")
    parser.add_argument("--kid-max-age", type=float, default=15.0, metavar="YEARS",
                        help="kids are at most this old (default 15)")
    parser.add_argument("--stature-cuts", default="1.40,2.00", metavar="SMALL,BIG",
                        help="small stature <= SMALL m < normal <= BIG m < big (default 1.40,2.00)")
    parser.add_argument("--obese-bmi", type=float, default=30.0, metavar="BMI",
                        help="obese group: BMI >= this (default 30)")
    parser.add_argument("--include-out-of-frame", action="store_true",
                        help="keep views where the body is cut by the image border (default: leave them out)")
    parser.add_argument("--correlation-view", default="0,0", metavar="AZ,EL",
                        help="view of the Spearman correlation matrix, degrees (default 0,0)")
    parser.add_argument("--residual-groups", default="all", metavar="LIST",
                        help="groups whose per-subject residuals are written (default all)")
    parser.add_argument("--residual-models", default="linear", metavar="LIST",
                        help="model kinds whose per-subject residuals are written (default linear)")
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
    """The :class:`~wbsa.analysis.fit_views.FitSettings` of parsed ``wbsa fit`` arguments."""
    from wbsa.analysis.fit_views import FitSettings
    from wbsa.analysis.groups import GroupSpec

    small, big = _floats(args.stature_cuts, 2, "stature-cuts")
    if args.predictors is None:
        sets = ((), ("stature_m",))
    else:
        given = [tuple(s.strip() for s in p.split(",") if s.strip() and s.strip().lower() != "none")
                 for p in args.predictors]
        sets = tuple(dict.fromkeys([(), *given]))
    return FitSettings(
        vbsa_columns=_list(args.vbsa, "vbsa"),
        predictor_sets=sets,
        models=_list(args.models, "models"),
        groups=_list(args.groups, "groups"),
        group_spec=GroupSpec(kid_max_age_years=args.kid_max_age, small_max_stature_m=small, big_min_stature_m=big,
                             obese_min_bmi=args.obese_bmi),
        k=args.k,
        seed=args.seed,
        require_in_frame=not args.include_out_of_frame,
        residual_groups=_list(args.residual_groups, "residual-groups"),
        residual_models=_list(args.residual_models, "residual-models"),
        population_kind=args.population_kind or Path(args.population).stem,
    )


def handle(args: argparse.Namespace) -> int:
    """Fit, write the outputs and print a short summary."""
    from wbsa.analysis.outputs import run_fit

    settings = settings_from_args(args)
    view = _floats(args.correlation_view, 2, "correlation-view")
    out, paths = run_fit(args.population, args.scan, args.out, settings, correlation_view=view)
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
