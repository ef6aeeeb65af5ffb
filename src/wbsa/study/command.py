"""``wbsa run``: the whole study (population → scan → fit → report) from one TOML file."""

from __future__ import annotations

import argparse
import sys


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``run`` subcommand to the ``wbsa`` parser."""
    p = subparsers.add_parser(
        "run",
        help="run a whole study: population, scan, fit and report (resumable, reuses finished stages)",
        description=(
            "Build a virtual population, scan it at every view (and camera distance), fit WBSA from VBSA per view "
            "and group, and write the report, all under --out. Settings come from a TOML file (--config); keys it "
            "leaves out take the embedded default (a few hundred random subjects at the paper's 65 views). Every "
            "stage's folder is named by a hash of its settings and inputs, so running the same study again reuses "
            "what is finished, and a killed run resumes. Prints the report's path."
        ),
    )
    p.add_argument("--config", default=None, metavar="TOML",
                   help="study settings: a .toml file or a shipped one (default, paper, distance-sweep, "
                        "reconstruction); default: the embedded default")
    p.add_argument("--out", default="runs/study", metavar="DIR", help="study folder (default runs/study)")
    g = p.add_argument_group("overrides of the settings (written into the resolved study.toml)")
    g.add_argument("--n", type=int, default=None, metavar="N", help="subjects in the population ([population] n)")
    g.add_argument("--views", default=None, metavar="SET",
                   help="view set ([scan] views): paper, front, sphere:N, grid:STEP; replaces angle lists")
    g.add_argument("--k", type=int, default=None, metavar="K", help="cross-validation folds ([fit] k)")
    g.add_argument("--camera", default=None, metavar="NAME|JSON", help="camera preset or intrinsics JSON ([scan] camera)")
    g.add_argument("--distance", default=None, metavar="M[,M...]",
                   help="camera distance(s) in metres ([scan] distances_m), e.g. 2.5 or 3.5,4.3")
    g.add_argument("--title", default=None, metavar="TEXT", help="the study's name in the report ([study] name)")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="worker processes of the population and scan stages (default: [run] workers, 0 = all cores)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bars on stderr (default: when stderr is a terminal)")
    p.add_argument("--print-config", action="store_true",
                   help="print the resolved settings as TOML and exit (a template for your own study file)")
    p.set_defaults(func=handle)


def overrides_from_args(args: argparse.Namespace) -> dict:
    """``{table: {key: value}}`` of the override flags given (``--views`` also clears the angle lists).

    Raises
    ------
    WbsaError
        For a ``--distance`` that is not a list of numbers.
    """
    from wbsa.errors import WbsaError

    out: dict[str, dict] = {}

    def put(table: str, **keys) -> None:
        out.setdefault(table, {}).update(keys)

    if args.n is not None:
        put("population", n=args.n)
    if args.views is not None:
        put("scan", views=args.views, azimuths_deg=[], elevations_deg=[])
    if args.camera is not None:
        put("scan", camera=args.camera)
    if args.distance is not None:
        try:
            put("scan", distances_m=[float(d) for d in args.distance.split(",") if d.strip()])
        except ValueError:
            raise WbsaError(f"--distance must be metres, e.g. 2.5 or 3.5,4.3, got {args.distance!r}") from None
    if args.k is not None:
        put("fit", k=args.k)
    if args.title is not None:
        put("study", name=args.title)
    return out


def handle(args: argparse.Namespace) -> int:
    """Load and check the settings, run the study, print the report's path."""
    from wbsa.study.settings import load_settings

    settings = load_settings(args.config, overrides_from_args(args))
    if args.print_config:
        sys.stdout.write(settings.to_toml())
        return 0
    from wbsa.study.pipeline import run_study

    result = run_study(settings, args.out, workers=args.workers, show_progress=args.progress)
    sys.stdout.write(f"{result.report_path}\n")
    return 0
