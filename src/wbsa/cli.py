"""The ``wbsa`` command: a thin argparse layer over the API.

Each pipeline stage registers its own subcommands from a small ``command`` module
(``wbsa.<stage>.command.register(subparsers)``) that imports heavy libraries only
inside its handler, so ``wbsa bsa`` starts fast. Every :class:`~wbsa.errors.WbsaError`, and any
operating-system error (disk full, permissions) or ``MemoryError`` that reaches it, becomes one line
on stderr and exit status 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import warnings

from wbsa.core.versions import WBSA_VERSION as __version__
from wbsa.errors import WbsaError

#: Modules that contribute subcommands, in the order of the pipeline.
COMMAND_MODULES = (
    "wbsa.bodies.command",
    "wbsa.formulae.command",
    "wbsa.simulate.command",
    "wbsa.scan.command",
    "wbsa.analysis.command",
    "wbsa.report.command",
    "wbsa.study.command",
    "wbsa.training.command",
    "wbsa.estimation.command",
    "wbsa.server.command",
)


class _Parser(argparse.ArgumentParser):
    """argparse that reports usage errors as one line with exit status 2."""

    def parse_known_args(self, args=None, namespace=None):  # noqa: D102
        self._given = list(sys.argv[1:] if args is None else args)
        return super().parse_known_args(args, namespace)

    def error(self, message: str) -> None:  # noqa: D102
        words = self.prog.split()
        if len(words) == 1:  # the top parser also reports a command's unrecognised arguments: point to it
            commands = {c for a in self._actions if isinstance(a, argparse._SubParsersAction) for c in a.choices}
            words += [str(a) for a in getattr(self, "_given", [])[:1] if a in commands]
        sys.stderr.write(f"error: {message} (see {' '.join(words)} --help)\n")
        sys.exit(2)


def build_parser() -> argparse.ArgumentParser:
    """The full ``wbsa`` parser with every registered subcommand."""
    parser = _Parser(prog="wbsa", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"wbsa {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser, metavar="COMMAND")
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name == name:
                continue  # stage not present in this build
            raise
        module.register(sub)
    return parser


def _one_line_warning(message, category, filename, lineno, line=None) -> str:
    """Warnings as ``warning: <message>``, without the file, line and source that Python adds."""
    return f"warning: {message}\n"


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``wbsa`` console script; returns the exit status."""
    warnings.formatwarning = _one_line_warning
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # usage errors (one line, status 2), --help and --version
        return exc.code if isinstance(exc.code, int) else int(exc.code is not None)
    try:
        result = args.func(args)
    except WbsaError as exc:
        sys.stderr.write(f"error: {exc}\n")
        return 2
    except KeyboardInterrupt:
        sys.stderr.write("interrupted: finished parts are kept; run the same command again to resume\n")
        return 130
    except OSError as exc:  # a disk or permission error a writer did not name itself
        from wbsa.io import os_error_message

        sys.stderr.write(f"error: {os_error_message(exc, action=_os_action(exc))}\n")
        return 2
    except MemoryError:
        sys.stderr.write("error: out of memory; use smaller inputs (fewer subjects, smaller images or camera "
                         "resolution) or a machine with more memory\n")
        return 2
    return int(result or 0)


def _os_action(exc: OSError) -> str:
    import errno

    return "write" if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS) else "access"


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
