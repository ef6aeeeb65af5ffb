"""``wbsa report``: every figure and table of a study or a fit folder in one self-contained HTML file."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``report`` subcommand to the ``wbsa`` parser."""
    p = subparsers.add_parser(
        "report",
        help="build the HTML report (figures and tables) of a study or a fit folder",
        description=(
            "Draw the paper's figures from a study folder (wbsa run --out) or a fit folder (wbsa fit --out): WBSA "
            "distribution, VBSA-WBSA scatter, c1 and CV RMSE against the view per group, errors by group, the "
            "non-linear view, residual diagnostics, point-cloud snapshots, reconstruction and camera-distance "
            "effects when the study has them, and the formulae comparison; write them with the tables, settings, "
            "versions and run times into one HTML file that opens in any browser."
        ),
    )
    p.add_argument("path", metavar="STUDY_DIR_OR_FIT_DIR", help="output folder of wbsa run or of wbsa fit")
    p.add_argument("--out", default=None, metavar="FILE",
                   help="HTML file to write (default: report.html inside STUDY_DIR_OR_FIT_DIR)")
    p.add_argument("--population", default=None, metavar="FILE",
                   help="population table of a fit folder (default: found from the study or the fit's record)")
    p.add_argument("--scan", action="append", default=None, metavar="FILE",
                   help="scan table of a fit folder; repeat for several distances (default: found like --population)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bar on stderr (default: when stderr is a terminal)")
    p.set_defaults(func=handle)


def handle(args: argparse.Namespace) -> int:
    """Build the report and print its path."""
    from wbsa.report.build import build_report
    from wbsa.report.sources import resolve_sources

    sources = resolve_sources(args.path, args.population, tuple(args.scan or ()))
    out = Path(args.out) if args.out else Path(args.path) / "report.html"
    result = build_report(sources, out, show_progress=args.progress)
    missing = f"; not drawn (no data): {', '.join(result.unavailable)}" if result.unavailable else ""
    sys.stderr.write(f"report: {len(result.figures)} figures, {len(result.tables)} tables in {result.seconds:.1f} s"
                     f"{missing}\n")
    sys.stdout.write(f"{result.path}\n")
    return 0
