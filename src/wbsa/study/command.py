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
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="worker processes of the population and scan stages (default: [run] workers, 0 = all cores)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bars on stderr (default: when stderr is a terminal)")
    p.add_argument("--print-config", action="store_true",
                   help="print the resolved settings as TOML and exit (a template for your own study file)")
    p.set_defaults(func=handle)


def handle(args: argparse.Namespace) -> int:
    """Load and check the settings, run the study, print the report's path."""
    from wbsa.study.settings import load_settings

    settings = load_settings(args.config)
    if args.print_config:
        sys.stdout.write(settings.to_toml())
        return 0
    from wbsa.study.pipeline import run_study

    result = run_study(settings, args.out, workers=args.workers, show_progress=args.progress)
    sys.stdout.write(f"{result.report_path}\n")
    return 0
